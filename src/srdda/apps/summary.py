"""What a run did, in a few numbers: the summary ``srdda run`` prints and writes in ``summary.json``.

It is computed after the run, with whole arrays, from the recorded histories
(an in-memory :class:`~srdda.results.Result` or a results file's
:class:`~srdda.io.results_reader.StoredResult`) and the run's final state:
the step cuts by cause (``State.cuts``), the largest centroid displacement and
speed with the block and the time they were reached, the final kinetic
energy, the energy balance error, the contacts' final states and, for a staged
run, each stage's end (steps, times, the unbalanced-force ratio reached). Extremes are
taken over the recorded steps only (``record_every``); the step cuts over every
step attempt.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..contact.openclose import LOCKED, OPEN, SLIDING
from ..kinematics.blocktype import block_type_of_dimension
from ..ledger import energy_in_play
from ..results import reference_rows
from ..state import State

__all__ = ["run_summary", "format_summary"]

Results = Any  # Result or StoredResult: both have .array(name), .block_names, .energy_names


def run_summary(res: Results, final: State) -> dict[str, Any]:
    """The summary of a run: recorded histories ``res`` and the state the run ended in, ``final``.

    Keys (SI units; energies in J per metre of thickness in 2D, J in 3D):
    ``recorded_steps``, ``last_step`` and ``last_time``; ``cuts`` (step attempts cut, by cause) and
    ``cut_attempts`` (their sum);
    ``largest_displacement`` and ``largest_speed`` of a block's centroid over
    the recorded steps (``value`` in m or m/s, ``block``, ``time``, ``step``);
    ``final_kinetic_energy`` (in ``energy_unit``); ``energy_balance`` (``error``: the ledger's
    balance at the end minus its start, ``scale``: the largest energy in play
    over the recorded steps (:func:`srdda.ledger.energy_in_play`),
    ``relative_error``: their ratio, None when nothing moved); ``contacts``:
    how many of the final contacts are open, sliding and locked; ``stages`` (a staged run only): each stage's
    name, kind, first and last step, steps, start and end time, status, and the unbalanced-force ratio of its
    last step (an equilibrium stage: its tolerance and whether it was reached). A stage that resets
    displacements measures the largest displacement from its start.
    """
    time, step = res.array("time"), res.array("step")
    stages = list(getattr(res, "stages", ()))
    centroid = res.array("centroid")
    block_type = block_type_of_dimension(centroid.shape[-1])
    translation = block_type.translation
    # from the start, or from the start of the last stage that reset displacements (a staged run)
    displacement = np.linalg.norm(centroid - centroid[reference_rows(step, stages)], axis=-1)  # (rows, blocks)
    speed = np.linalg.norm(res.array("velocity")[..., translation], axis=-1)
    energy = dict(zip(res.energy_names, res.array("energy").T))
    start = {name: float(values[0]) for name, values in energy.items()}
    error = float(energy["balance"][-1] - energy["balance"][0])
    scale = float(np.max(energy_in_play(energy, start)))
    states = final.contacts.state if final.contacts is not None else np.zeros(0, dtype=int)

    def largest(values: np.ndarray) -> dict[str, Any]:
        row, block = np.unravel_index(int(np.argmax(values)), values.shape)
        return {"value": float(values[row, block]), "block": str(res.block_names[block]),
                "time": float(time[row]), "step": int(step[row])}

    return {"recorded_steps": len(step), "last_step": int(step[-1]), "last_time": float(time[-1]),
            "cuts": final.cuts_by_cause, "cut_attempts": int(np.sum(final.cuts)),
            "largest_displacement": largest(displacement), "largest_speed": largest(speed),
            "final_kinetic_energy": float(energy["kinetic"][-1]), "energy_unit": "J/m" if block_type.dim == 2 else "J",
            "energy_balance": {"error": error, "scale": scale, "relative_error": error / scale if scale > 0 else None},
            "contacts": {name: int(np.count_nonzero(states == code))
                         for name, code in (("open", OPEN), ("sliding", SLIDING), ("locked", LOCKED))},
            **({"stages": [_stage_end(row) for row in stages]} if stages else {})}


def _stage_end(row: dict[str, Any]) -> dict[str, Any]:
    """What the summary keeps of a stage's row: its name, kind, steps, times, status and the ratio it reached."""
    keys = ("name", "kind", "first_step", "last_step", "steps", "start_time", "end_time", "status", "ratio",
            "tolerance", "reached")
    return {k: row[k] for k in keys if k in row}


def format_summary(summary: dict[str, Any]) -> list[str]:
    """The summary as a few lines of text for the end of ``srdda run``."""
    cuts = ", ".join(f"{n} {cause}" for cause, n in summary["cuts"].items())
    lines = [f"steps: {summary['last_step']} ({summary['recorded_steps']} recorded), to t = "
             f"{summary['last_time']:.6g} s; step attempts cut: {summary['cut_attempts']} ({cuts})"]
    for key, words, unit in (("largest_displacement", "largest displacement", "m"),
                             ("largest_speed", "largest speed", "m/s")):
        x = summary[key]
        lines.append(f"{words}: {x['value']:.6g} {unit}, block {x['block']} at t = {x['time']:.6g} s")
    balance, unit = summary["energy_balance"], summary["energy_unit"]
    relative = "-" if balance["relative_error"] is None else f"{balance['relative_error']:.3g}"
    lines.append(f"final kinetic energy: {summary['final_kinetic_energy']:.6g} {unit}; energy balance error: "
                 f"{balance['error']:.3g} {unit} ({relative} of the largest energy in play, "
                 f"{balance['scale']:.6g} {unit})")
    c = summary["contacts"]
    lines.append(f"contacts at the end: {c['open']} open, {c['sliding']} sliding, {c['locked']} locked")
    for stage in summary.get("stages", ()):
        lines.append(format_stage(stage))
    return lines


def format_stage(stage: dict[str, Any]) -> str:
    """One line of a stage's end: its steps and times, and the unbalanced-force ratio it reached."""
    if "last_step" not in stage:
        return f"stage {stage['name']} ({stage['kind']}): began at step {stage['first_step']}, not ended"
    ratio = "-" if stage.get("ratio") is None else f"{stage['ratio']:.3g}"
    if stage["kind"] == "equilibrium":
        verdict = "reached" if stage.get("reached") else "not reached"
        ratio += f" ({verdict}: tolerance {stage['tolerance']:.3g})"
    status = "" if stage["status"] == "completed" else f"; {stage['status']}"
    return (f"stage {stage['name']} ({stage['kind']}): steps {stage['first_step']}-{stage['last_step']} "
            f"({stage['steps']}), t = {stage['start_time']:.6g}-{stage['end_time']:.6g} s; unbalanced-force ratio "
            f"{ratio}{status}")
