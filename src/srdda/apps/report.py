"""The paper report: run the paper's examples, write Markdown and HTML with every table and figure.

Everything in the report comes from runs made by :func:`make_report` itself
(never from stored numbers): each example of :mod:`srdda.apps.paper` is built and
run under each method, each run is written to ``DIR/runs/<example>_<method>.h5``
(a results file: ``srdda plot``/``animate``/``vtk`` work on it), the example's
``tables(results)`` rows are laid out ours beside the paper's, and its figures
are drawn by the maker registered for it in :data:`FIGURES`.

Output: ``DIR/report.md`` (figures as ``DIR/figures/*.png``) and
``DIR/report.html`` (self-contained: figures embedded as base64 PNG).
"""
from __future__ import annotations

import base64
import datetime
import html
import io
import os
import platform
import shlex
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from .._version import __version__  # noqa: E402
from . import plotting  # noqa: E402
from ..integrators.methods import METHODS, MethodName  # noqa: E402
from ..io.results_store import ResultsStore  # noqa: E402
from ..model import Model  # noqa: E402
from ..results import Result  # noqa: E402
from ..settings import RunSettings  # noqa: E402
from ..simulation import run  # noqa: E402
from .markup import CSS, html_table, md_table  # noqa: E402
from .ensemble.report import paper_report_section  # noqa: E402

__all__ = ["ExampleRun", "FIGURES", "register_figures", "run_examples", "write_report", "make_report",
           "pivot_table"]

FigureList = list[tuple[str, Figure]]  # (caption, figure)
FigureMaker = Callable[[dict[str, Result], Model], FigureList]
FIGURES: dict[str, FigureMaker] = {}
CONFIG_FIGURES = {"pendulum": "3", "rod": "5", "sine-wave": "7", "nunchaku": "11", "rockfall": "14"}
MAX_OMEGA_BLOCKS = 4  # the ω-against-time figure is drawn for models of at most this many moving blocks


def register_figures(name: str) -> Callable[[FigureMaker], FigureMaker]:
    """Register the figure maker of paper example ``name`` (results per method, the example's model)."""
    def deco(maker: FigureMaker) -> FigureMaker:
        FIGURES[name] = maker
        return maker
    return deco


@dataclass
class ExampleRun:
    """One example run under several methods: results, table rows, figures, timings, files."""

    name: str
    title: str
    results: dict[str, Result]
    rows: list[dict]
    figures: FigureList
    wall_seconds: dict[str, float]
    files: dict[str, Path] = field(default_factory=dict)
    errors: list[str] = field(default_factory=list)
    notes: str = ""  # the example's choices where the paper is silent
    inputs: tuple[list[str], list[list[str]]] | None = None  # the inputs table (header, rows): materials, run


# -- figure makers -------------------------------------------------------------------
def _pivot(model: Model) -> np.ndarray:
    attached = model.arrays().attached
    return attached.point_position[attached.fixed_rows[0]] if len(attached.fixed_rows) else np.zeros(2)


def _balance_summary(results: dict[str, Result]) -> str:
    """The largest balance error of each run, in J/m and relative to its initial and peak kinetic energy."""
    parts = []
    for method, res in results.items():
        ledger = plotting.ledger_series(res)
        unit = plotting.quantity_unit(res, "energy")
        initial = sum(float(ledger[k][0]) for k in ("kinetic", "elastic", "spring", "contact"))
        error = float(np.max(np.abs(ledger["error"])))
        shares = [f"{100 * error / v:.2g}% of {what}" for v, what in
                  ((initial, "E₀"), (float(np.max(ledger["kinetic"])), "the peak kinetic energy")) if v > 0]
        parts.append(f"{plotting.method_label(method)} {error:.3g} {unit}"
                     + (f" ({', '.join(shares)})" if shares else ""))
    return "; ".join(parts)


# One sentence per energy-ledger panel: what the curve is and why it moves (srdda.ledger)
LEDGER_SENTENCES = {
    "kinetic": "Kinetic energy: ½ḋᵀMḋ of every block, translation, rotation and straining.",
    "potential": "Gravity potential of the moving blocks from their initial centroid heights (negative as they "
                 "fall; fixed blocks excluded).",
    "elastic": "Strain energy stored in the deforming blocks.",
    "spring": "Energy stored in springs and penalty supports (fixed points, point springs, springs): the spring "
              "stretched by the support's penalty. A method that moves points after the solve (DDA1's "
              "post-adjusted rotation) stretches the support's spring by that move, which stores energy here "
              "that no force did work for; the ledger books the same amount as put in by the point update "
              "(the springs' step-force panel, negative), so the two cancel in the balance.",
    "contact": "Energy stored in the closed contacts' penalty springs.",
    "work_loads": "Cumulative work of point loads and of the base acceleration's body force.",
    "work_prescribed": "Cumulative work of the drivers of prescribed motion.",
    "work_constraints": "Cumulative work of the hinge and pin forces: zero for a hinge kept exactly (SRDDA, "
                        "DDA0), not for DDA1's post-adjustment.",
    "dissipated": "Cumulative energy the dashpots took out.",
    "dissipated_friction": "Cumulative energy friction took out at sliding contacts.",
    "dissipated_contact": "Cumulative energy the contact penalty took out: DDA's impact loss and springs "
                          "released while stretched.",
    "dissipated_springs": "Cumulative energy the springs' step force took out (negative: put in, e.g. by a "
                          "point update other than the solved displacement, which then shows in the springs' "
                          "stored energy).",
    "dissipated_impact": "Cumulative energy the impacts on joints with a restitution e_n took out: their dashpot, "
                         "(1 − e_n²) of each impact's energy.",
    "work_water": "Cumulative work of the water pressure in the joints and tension cracks (docs/water.md): "
                  "positive while the uplift pushes the blocks apart or down the slope.",
    "dissipated_damping": "Cumulative kinetic energy the velocity damping took out (velocity_ratio < 1: the "
                          "damped steps of an equilibrium stage or of settle).",
    "work_stages": "Cumulative change of the stored energy at the stages' starts: blocks removed with their "
                   "energy, materials changed under stress, bolts installed with their pretension, velocities "
                   "reset (negative: taken out).",
    "error": "Balance error E − E₀ − W_in + D: the time scheme's and the linearisation's own loss or gain; "
             "zero for an exact ledger.",
}


def _common(results: dict[str, Result], model: Model) -> FigureList:
    """Figures every example gets: the energy ledger and the moving blocks' angular velocities per method."""
    drawn = plotting.ledger_panels(plotting.ledger_series(r) for r in results.values())
    unit = "J per m of thickness" if model.dim == 2 else "J"
    figs = [(f"Energy ledger per method, one panel per entry on its own scale ({unit}); entries that stay zero "
             "are left out; methods that agree draw on top of each other (solid DDA0, dashed DDA1, dotted "
             "SRDDA). " + " ".join(LEDGER_SENTENCES[key] for key, _ in drawn)
             + f" Largest balance error: {_balance_summary(results)}.", plotting.fig_energy_ledger(results))]
    moving = np.flatnonzero(~model.arrays().block_fixed)
    if 0 < len(moving) <= MAX_OMEGA_BLOCKS:
        figs.append(("Angular velocity ω (rad/s) of every moving block against time: a colour per method, "
                     "a line style per block.",
                     plotting.fig_time_series({plotting.method_label(m): r for m, r in results.items()},
                                              "velocity.omega", blocks=moving)))
    return figs


@register_figures("pendulum")
def _pendulum(results: dict[str, Result], model: Model) -> FigureList:
    return [("Fig. 4: trajectories of point B (x, y in m) by (a) DDA0, (b) DDA1, (c) SRDDA; middle: the same "
             "enlarged at the lowest point; bottom: B's distance from the pivot A minus its "
             "initial value (m) against time.",
             plotting.fig_swing_trajectories(results, pivot=_pivot(model), names=("B",)))]


@register_figures("rod")
def _rod(results: dict[str, Result], model: Model) -> FigureList:
    return [("Fig. 6: trajectories of points B (centroid, blue) and C (tip, red) (x, y in m) by (a) DDA0, "
             "(b) DDA1, (c) SRDDA; middle: B's paths enlarged at its lowest point; bottom: "
             "each point's distance from the pivot A minus its initial value (m) against time.",
             plotting.fig_swing_trajectories(results, pivot=_pivot(model), names=("B", "C")))]


@register_figures("sine-wave")
def _wave(results: dict[str, Result], model: Model) -> FigureList:
    return [(f"Fig. {8 + i}: the bar chain's transverse displacement v (m) of each bar's centroid against its "
             f"position x (m) at CS {s} ({i + 1} period{'s' if i else ''} of the driving sine), per method.",
             plotting.fig_wave_shapes(results, steps=(s,))) for i, s in enumerate((300, 600, 900))]


@register_figures("nunchaku")
def _nunchaku(results: dict[str, Result], model: Model) -> FigureList:
    fig12, fig13 = plotting.fig_nunchaku(results)
    return [("Fig. 12: trajectories of the hinge points B1 (wide blue line) and B2 (thin red line on top) "
             "(x, y in m), per method; middle: the same enlarged at B1's lowest point: where "
             "the hinge holds, red runs inside blue; bottom: angular velocity ω (rad/s) of each stick against "
             "time.", fig12),
            ("Fig. 13: trajectories of point C (x, y in m) by DDA0, DDA1 and SRDDA.", fig13)]


@register_figures("rockfall")
def _rockfall(results: dict[str, Result], model: Model) -> FigureList:
    return [("Fig. 15: trajectories of P1 (centroid, blue) and P2 (vertex, red) (x, y in m) over the fixed slope "
             "(grey) by (a) DDA0, (b) DDA1, (c) SRDDA.",
             plotting.fig_rockfall(results, background=plotting.fixed_blocks(model)))]


def _generic(results: dict[str, Result], model: Model) -> FigureList:
    first = next(iter(results.values()))
    return [(f"Measured-point trajectories ({plotting.method_label(m)}).",
             plotting.fig_trajectories(r, "measured" if np.asarray(first.array("measured_position")).shape[1]
                                       else "centroid")) for m, r in results.items()]


# -- running -------------------------------------------------------------------------
def run_examples(names: Sequence[str] | None = None, methods: Sequence[MethodName] = METHODS,
                 runs_dir: str | Path | None = None,
                 progress: Callable[[str, str, int, int], None] | None = None) -> list[ExampleRun]:
    """Run paper examples (all registered ones by default) under ``methods``; tables and figures.

    A run that diverges or a table/figure that fails is reported in the
    example's ``errors`` instead of stopping the others. ``progress(example,
    method, step, n_steps)`` is called after every step.
    """
    from .paper import EXAMPLES, get_example
    from .paper.registry import examples_dir

    out = []
    for name in (list(EXAMPLES) if names is None else names):
        example = get_example(name)
        results: dict[str, Result] = {}
        wall: dict[str, float] = {}
        files: dict[str, Path] = {}
        errors: list[str] = []
        model = None
        settings_used: dict[str, RunSettings] = {}
        for method in methods:
            model, settings = example.build(method)
            settings_used[method] = settings
            recorders = []
            if runs_dir is not None:
                files[method] = Path(runs_dir) / f"{name}_{method}.h5"
                files[method].parent.mkdir(parents=True, exist_ok=True)
                text = ((examples_dir() / "paper" / example.model_file).read_text(encoding="utf-8")
                        if example.model_file else None)
                recorders.append(ResultsStore(files[method], settings, flush_every=500, model_text=text))
            callback = None if progress is None else (
                lambda step, m=method, n=settings.n_steps: progress(name, m, step, n))
            start = time.perf_counter()
            results[method] = run(model, settings, progress=callback, recorders=recorders)
            wall[method] = time.perf_counter() - start
            if not results[method].completed:
                errors.append(f"{method}: {results[method].status}")
        rows, figures = [], []
        try:
            rows = example.tables(results)
        except Exception as exc:  # a diverged run may lack the steps a table needs: say so in the report
            errors.append(f"tables: {type(exc).__name__}: {exc}")
        try:
            assert model is not None, "no method was run"
            paper_fig = f" (the paper's Fig. {CONFIG_FIGURES[name]})" if name in CONFIG_FIGURES else ""
            figures = [(f"The model as built for these runs{paper_fig}: fixed blocks grey, fixed points black "
                        "triangles, springs green lines between open circles, hinges black rings, driven points "
                        "purple diamonds, point loads orange triangles, measured points red dots with the paper's "
                        "names (else P0, P1, ... in the order the model lists them); a slender model with springs, "
                        "hinges or driven points has them enlarged below it.",
                        plotting.fig_configuration(model.arrays(), example.title, example.point_names or None))]
            figures += FIGURES.get(name, _generic)(results, model) + _common(results, model)
        except Exception as exc:
            errors.append(f"figures: {type(exc).__name__}: {exc}")
        out.append(ExampleRun(name, example.title, results, rows, figures, wall, files, errors, example.notes,
                              inputs_table(model, settings_used) if model is not None else None))
    return out


# -- tables ---------------------------------------------------------------------------
def _si(value: float | None, unit: str) -> str:
    return "-" if value is None else f"{value:.6g} {unit}".strip()


def inputs_table(model: Model, settings: dict[str, RunSettings]) -> tuple[list[str], list[list[str]]]:
    """The inputs of an example's runs as (header, rows): materials, joints, Δt, steps, penalties, method, solver.

    A setting that differs between the methods' runs lists each method's value.
    """
    rows = [[f"material {name}", f"density {_si(m.density, 'kg/m³')}, Young's modulus {_si(m.young, 'Pa')}, "
             f"Poisson's ratio {m.poisson:g}, plane {m.plane}"] for name, m in model.materials.items()]
    joints = {"default joint": model.default_joint, **{f"joint {k}": j for k, j in model.joint_materials.items()}}
    rows += [[name, f"friction angle {j.friction_angle:g}°, cohesion {_si(j.cohesion, 'Pa')}, tensile strength "
              f"{_si(j.tensile_strength, 'Pa')}"] for name, j in joints.items()]

    def setting(label: str, field: str, unit: str = "") -> None:
        values = {m: getattr(s, field) for m, s in settings.items()}
        shown = {m: _si(v, unit) if isinstance(v, float) else "-" if v is None else str(v) for m, v in values.items()}
        text = (next(iter(shown.values())) if len(set(shown.values())) == 1
                else ", ".join(f"{plotting.method_label(m)} {v}" for m, v in shown.items()))
        rows.append([label, text])

    setting("method", "method")
    setting("time step Δt", "dt", "s")
    setting("steps", "n_steps")
    setting("end time", "end_time", "s")
    setting("penalty (fixed points, constraints)", "penalty", "N/m")
    setting("contact penalty k_n", "contact_penalty", "N/m")
    setting("time integration ρ∞", "rho_inf")
    setting("linear solver", "solver")
    return ["input", "value (SI)"], rows



def _decimals(paper: float | None) -> int:
    if isinstance(paper, int):  # a count (e.g. a contact step): ours is a count too
        return -2
    if paper is None:
        return 6
    text = repr(float(paper))
    return max(6, len(text.split(".")[1])) if "." in text and "e" not in text else 6


def _re(value: float | None, exact: float | None) -> str:
    if value is None or exact is None or exact == 0:
        return ""
    return f" ({100 * (value - exact) / exact:+.4f}%)"


def pivot_table(rows: Sequence[dict], methods: Sequence[str]) -> tuple[list[str], list[list[str]]]:
    """Rows of one paper table laid out as quantity, unit, CS, exact, then ours | paper per method.

    Every value of a row is in the row's ``unit`` (SI; ``step`` for a step
    count). Values carry two more decimals than the paper prints; the relative
    error to the exact value follows in parentheses where there is one.
    """
    keys: dict[tuple[str, object], dict] = {}
    for given in rows:
        entry = keys.setdefault((given["quantity"], given["step"]), {"exact": given["exact"],
                                                                     "unit": given.get("unit", "")})
        entry[given["method"]] = given
    header = ["quantity", "unit", "CS (step)", "exact"]
    for m in methods:
        header += [f"{plotting.method_label(m)} ours", f"{plotting.method_label(m)} paper"]
    body = []
    for (quantity, step), entry in keys.items():
        exact = entry["exact"]
        line = [str(quantity), entry["unit"], "" if step is None else str(step),
                "" if exact is None else f"{exact:.6f}"]
        for m in methods:
            r = entry.get(m)
            if r is None:
                line += ["", ""]
                continue
            d = _decimals(r["paper"]) + 2
            line.append(f"{r['ours']:.{d}f}{_re(r['ours'], exact)}")
            paper = r["paper"]
            shown = str(paper) if isinstance(paper, int) else repr(float(paper)) if paper is not None else ""
            line.append("" if paper is None else f"{shown}{_re(paper, exact)}")
        body.append(line)
    return header, body


def _tables(run_: ExampleRun) -> dict[str, list[dict]]:
    grouped: dict[str, list[dict]] = {}
    for r in run_.rows:
        grouped.setdefault(r["table"], []).append(r)
    return grouped


# -- writing ---------------------------------------------------------------------------
def _png(fig: Figure, dpi: int = 100) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return buf.getvalue()


def _machine() -> str:
    return (f"{platform.platform()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"numpy {np.__version__}, srdda {__version__}")


def _runs_table(run_: ExampleRun) -> tuple[list[str], list[list[str]]]:
    header = ["method", "status", "recorded steps (count)", "last step (step)", "wall time (s)", "results file"]
    body = []
    for m, res in run_.results.items():
        body.append([plotting.method_label(m), res.status, str(len(res.step)), str(res.step[-1] if res.step else ""),
                     f"{run_.wall_seconds.get(m, float('nan')):.2f}",
                     str(run_.files[m].name) if m in run_.files else ""])
    return header, body


def write_report(directory: str | Path, runs: Sequence[ExampleRun], command: str | None = None,
                 total_seconds: float | None = None) -> tuple[Path, Path]:
    """Write ``report.md`` (+ ``figures/``) and a self-contained ``report.html`` of ``runs``."""
    out = Path(directory)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    command = command or " ".join(shlex.quote(a) for a in ["srdda", *sys.argv[1:]])
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    intro = (f"Every number and figure below comes from runs made by `{command}` on {stamp} "
             f"(machine: {_machine()}). 'ours' is this run, 'paper' is Fan, Zheng & Zhao (2017); "
             "relative errors to the exact value are in parentheses. Every value of a table row is in the "
             "row's unit (SI); CS is the step number.")
    if total_seconds is not None:
        intro += f" Total wall time: {total_seconds:.1f} s."
    md = ["# srdda: the paper's examples reproduced", "", intro, ""]
    hb = [f"<h1>srdda: the paper's examples reproduced</h1><p>{html.escape(intro)}</p>"]
    for run_ in runs:
        methods = list(run_.results)
        md += [f"## {run_.title}", ""]
        hb.append(f"<h2>{html.escape(run_.title)}</h2>")
        if run_.notes:
            md += [run_.notes, ""]
            hb.append(f"<p>{html.escape(run_.notes)}</p>")
        if run_.inputs is not None:
            md += ["### Inputs", "", md_table(*run_.inputs), ""]
            hb.append(f"<h3>Inputs</h3>{html_table(*run_.inputs)}")
        header, body = _runs_table(run_)
        md += [md_table(header, body), ""]
        hb.append(html_table(header, body))
        for err in run_.errors:
            md += [f"**Error:** {err}", ""]
            hb.append(f"<p class='err'>Error: {html.escape(err)}</p>")
        for table, rows in _tables(run_).items():
            header, body = pivot_table(rows, methods)
            md += [f"### {table}", "", md_table(header, body), ""]
            hb.append(f"<h3>{html.escape(table)}</h3>{html_table(header, body)}")
        for i, (caption, fig) in enumerate(run_.figures):
            png = _png(fig)
            name = f"{run_.name}_{i + 1}.png"
            (out / "figures" / name).write_bytes(png)
            md += [f"![{run_.title}, figure {i + 1}](figures/{name})", "", f"*{caption}*", ""]
            data = base64.b64encode(png).decode("ascii")
            alt = html.escape(f"{run_.title}, figure {i + 1}")
            hb.append(f"<figure><img src='data:image/png;base64,{data}' alt='{alt}'>"
                      f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    paper_report_section(out, md, hb)  # the probabilistic rockfall of DIR/ensemble, when one was run there
    md_path, html_path = out / "report.md", out / "report.html"
    md_path.write_text("\n".join(md), encoding="utf-8")
    html_path.write_text("<!doctype html><html><head><meta charset='utf-8'><title>srdda report</title>"
                         f"<style>{CSS}</style></head><body>{''.join(hb)}</body></html>", encoding="utf-8")
    return md_path, html_path


def make_report(directory: str | Path, names: Sequence[str] | None = None, methods: Sequence[MethodName] = METHODS,
                progress: Callable[[str, str, int, int], None] | None = None,
                command: str | None = None) -> tuple[list[ExampleRun], tuple[Path, Path]]:
    """Run the examples (results files under ``DIR/runs``) and write the report into ``directory``."""
    start = time.perf_counter()
    # every example's figures stay open until the report is written (about 25): not a leak
    with plt.rc_context({"figure.max_open_warning": 0}):
        runs = run_examples(names, methods, Path(directory) / "runs", progress)
        paths = write_report(directory, runs, command, time.perf_counter() - start)
    return runs, paths
