"""The staged examples (issue 30 item 8): examples/stages/tunnel.toml and wedge-cut.toml run from `srdda run`
without a warning, and resume after a kill in any stage to the same final state, bit for bit."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import srdda
from srdda.io import load_model
from srdda.io.results_store import ResultsStore, load_checkpoint, read_results, resume
from srdda.model import ModelError

STAGES = Path(__file__).parents[1] / "examples" / "stages"
EXAMPLES = {"tunnel.toml": ["gravity", "excavation", "support", "earthquake"],
            "wedge-cut.toml": ["gravity", "cut", "residual"]}  # the stages of each
SHORT = 12  # steps of each stage in the resume test (a test-only override: the shipped stages are longer)


def short(name: str) -> tuple[srdda.Model, srdda.RunSettings]:
    """The shipped example with every stage cut to SHORT steps (equilibrium stages: max_steps), record_every 1."""
    model, settings = load_model(STAGES / name)
    model.stages[:] = [replace(s, max_steps=SHORT, run={**s.run, "n_steps": SHORT} if s.kind == "dynamic" else s.run)
                       for s in model.stages]
    return model, replace(settings, record_every=1)


KILLED_CHILD = """
import os, signal, sys
import srdda
from srdda.io.results_store import ResultsStore
from test_staged_examples import short

model, settings = short(sys.argv[1])

def progress(step):
    if step == int(sys.argv[3]):
        os.kill(os.getpid(), signal.SIGKILL)

srdda.run(model, settings, progress=progress, recorders=[ResultsStore(sys.argv[2], settings, flush_every=5)])
"""


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_the_shipped_example_runs_from_srdda_run_without_a_warning(name: str, tmp_path: Path) -> None:
    # the file as shipped, through the CLI with every warning an error; --steps (the CLI's own override)
    # shortens the dynamic stages that run the model's [run] steps (the earthquake, the cut), so the test stays fast
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-W", "error", "-m", "srdda", "run", str(STAGES / name), "--steps", "20",
                           "--out", str(out), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 0 and "Warning" not in done.stderr, done.stderr
    stored = read_results(out / "results.h5")
    assert stored.completed and [row["name"] for row in stored.stages] == EXAMPLES[name]
    for row in stored.stages:  # every equilibrium stage reaches the default tolerance
        assert row["kind"] == "dynamic" or (row["reached"] and row["ratio"] < 1e-5), row


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_the_example_resumes_after_a_kill_in_any_stage_bit_for_bit(name: str, tmp_path: Path) -> None:
    # as tests/test_staging.py: SIGKILL from inside the time loop (no timing involved) in each stage, then resume;
    # the file's histories, its stage table and its last checkpoint are those of the uninterrupted run, bit for bit
    model, settings = short(name)
    reference_path = tmp_path / "reference.h5"
    srdda.run(model, settings, recorders=[ResultsStore(reference_path, settings, flush_every=5)])
    reference = read_results(reference_path)
    assert [row["name"] for row in reference.stages] == EXAMPLES[name]
    env = {**os.environ,
           "PYTHONPATH": os.pathsep.join([str(Path(srdda.__file__).parents[1]), str(Path(__file__).parent)])}
    arrays = model.arrays()
    for row in reference.stages:
        kill_step = row["first_step"] + SHORT // 2 + 1
        path = tmp_path / f"killed_at_{kill_step}.h5"
        child = subprocess.run([sys.executable, "-c", KILLED_CHILD, name, str(path), str(kill_step)], env=env,
                               capture_output=True, text=True)
        assert child.returncode == -signal.SIGKILL, child.stderr
        resume(path)
        stored = read_results(path)
        assert stored.completed and stored.stages == reference.stages, kill_step
        for quantity in ("step", "time", "centroid", "velocity", "stress", "rotation", "energy"):
            np.testing.assert_array_equal(stored.array(quantity), reference.array(quantity),
                                          err_msg=f"{quantity} {kill_step}")
        final, expected = load_checkpoint(path, arrays), load_checkpoint(reference_path, arrays)
        for quantity in ("vertices", "points", "velocity", "acceleration", "stress", "rotation"):
            np.testing.assert_array_equal(getattr(final, quantity), getattr(expected, quantity), err_msg=quantity)


def test_the_tunnel_blocks_are_a_group_and_the_bolts_cross_the_roof() -> None:
    model, _ = load_model(STAGES / "tunnel.toml")
    names = [b.name for b in model.blocks]
    assert sorted(n for n in names if n.startswith("tunnel")) == ["tunnel bench", "tunnel heading"]
    installed = model.stages[2].install_bolts
    assert model.stages[1].remove_blocks == ("tunnel*",) and len(installed) >= 3
    assert sorted(installed) == sorted(b.name for b in model.bolts)


def test_cut_blocks_take_the_names_given() -> None:
    square = np.array([(0, 0), (2, 0), (2, 1), (0, 1)], dtype=float)
    cut = srdda.cut_blocks([[1, 0, 1, 1]], edge_node_distance=0.01, boundary=square)
    m = srdda.Model()
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    srdda.add_cut_blocks(m, cut, {0: "rock"}, names=["left", "right"])
    assert sorted(b.name for b in m.blocks) == ["left", "right"]
    with pytest.raises(ModelError, match="names: expected 2 block names, got 1"):
        srdda.add_cut_blocks(srdda.Model(), cut, {0: "rock"}, names=["one"])


def test_the_wedge_cut_verification_case_passes() -> None:
    # the example's model (srdda.apps.verify.cases.slope3d.wedge_cut_model) against Hoek & Bray, as `srdda verify` runs it
    # (the rows' tolerances and their reasons are in src/srdda/apps/verify/cases_stages.py)
    from srdda.apps.verify import run_case

    rows = run_case("stage-wedge-cut-3d", methods=("srdda",))
    assert len(rows) == 2 and all(r["passed"] for r in rows), [(r["quantity"], r["ours"]) for r in rows]


def test_the_shipped_wedge_is_the_model_of_the_verification_case() -> None:
    # wedge-cut.toml is wedge_cut_model() written out (examples/stages/wedge_cut.py): the same blocks and stages
    from srdda.apps.verify.cases.slope3d import wedge_cut_model

    shipped, _ = load_model(STAGES / "wedge-cut.toml")
    built = wedge_cut_model()
    assert shipped.arrays().stages == built.arrays().stages
    for a, b in zip(shipped.blocks, built.blocks, strict=True):
        assert a.name == b.name and a.fixed == b.fixed
        np.testing.assert_array_equal(a.vertices, b.vertices)  # floats written as repr: read back exactly
