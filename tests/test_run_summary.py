"""The run's summary (srdda.apps.summary, summary.json) and the time histories of srdda history (issue 30, items 5-6)."""
from __future__ import annotations

import json
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import srdda
from srdda.apps.cli import main
from srdda.io.modelfile import load_model
from srdda.io.results_store import ResultsStore, load_checkpoint
from srdda.step import Stepper
from srdda.apps.summary import run_summary
from srdda.apps.verify.cases2d import INCLINE_G, INCLINE_PENALTY, INCLINE_PSI, incline_model_2d

DATA = Path(__file__).parent / "data"
PHI = 20.0  # the joint's friction angle (°): the block slides
# Δt = 0.05 s on the incline: the first steps move a vertex more than g2·w0 (0.01 × 3.43 m) and are cut
INCLINE = srdda.RunSettings(dt=0.05, n_steps=40, penalty=INCLINE_PENALTY, max_displacement_ratio=0.01)
MASS = 2500.0 * 0.5  # kg per m: the 1 m × 0.5 m sliding block


@pytest.fixture(scope="module")
def incline(tmp_path_factory: pytest.TempPathFactory):
    """The sliding block's run (to a results file, checkpoints every 5 recorded steps) and the causes of
    the cuts that Stepper.step returned, counted as they happened."""
    seen: Counter[str] = Counter()
    step = Stepper.step

    def spy(self: Stepper, state: srdda.State, dt: float):
        outcome = step(self, state, dt)
        if outcome.status == "cut":
            seen[outcome.cause] += 1
        return outcome

    path = tmp_path_factory.mktemp("summary") / "incline.h5"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Stepper, "step", spy)
        result = srdda.run(incline_model_2d(PHI), INCLINE, recorders=[ResultsStore(path, INCLINE, flush_every=5)])
    assert result.completed, result.status
    return result, seen, path


def test_summary_of_a_block_sliding_on_an_incline(incline) -> None:
    result, seen, _ = incline
    s = run_summary(result, result.final_state)
    a = INCLINE_G * (np.sin(INCLINE_PSI) - np.cos(INCLINE_PSI) * np.tan(np.radians(PHI)))  # m/s²
    for key in ("largest_speed", "largest_displacement"):
        assert s[key]["block"] == "block 1" and s[key]["step"] == 40  # the sliding block, still accelerating
    t = s["largest_speed"]["time"]
    assert t == pytest.approx(result.time[-1]) and t < 40 * INCLINE.dt  # the cut steps shortened Δt
    assert s["largest_speed"]["value"] == pytest.approx(a * t, rel=2e-4)  # measured 7e-5
    assert s["largest_displacement"]["value"] == pytest.approx(0.5 * a * t**2, rel=2e-4)
    assert s["final_kinetic_energy"] == pytest.approx(0.5 * MASS * (a * t) ** 2, rel=4e-4)
    # the energy in play: the gravitational energy released, once as kinetic energy and friction, once as its change
    released = MASS * INCLINE_G * np.sin(INCLINE_PSI) * 0.5 * a * t**2
    assert s["energy_balance"]["scale"] == pytest.approx(2 * released, rel=1e-3)
    assert abs(s["energy_balance"]["relative_error"]) < 1e-3
    assert s["energy_balance"]["error"] == pytest.approx(s["energy_balance"]["relative_error"] * 2 * released, rel=1e-3)
    # both vertices of the block's base slide; none is open or locked
    assert s["contacts"] == {"open": 0, "sliding": 2, "locked": 0}
    assert seen["displacement"] > 0  # the test forces cuts
    assert s["cuts"] == {cause: seen[cause] for cause in srdda.term.CUT_CAUSES} == result.cuts
    assert s["cut_attempts"] == sum(seen.values())


def test_cut_counts_survive_checkpoints_and_continued_runs(incline) -> None:
    result, _, path = incline
    assert sum(result.cuts.values()) > 0  # cut in the first steps, none after step 20: a count restarted misses them
    arrays = incline_model_2d(PHI).arrays()
    np.testing.assert_array_equal(load_checkpoint(path, arrays).cuts, result.final_state.cuts)
    half = srdda.run(arrays, replace(INCLINE, n_steps=20), keep_history=False)
    rest = srdda.run(arrays, replace(INCLINE, n_steps=20), state=half.final_state, keep_history=False)
    assert rest.final_state.step == 40 and rest.cuts == result.cuts


def test_srdda_run_prints_the_summary_and_writes_it(tmp_path: Path) -> None:
    out = tmp_path / "run"
    res = CliRunner().invoke(main, ["run", str(DATA / "two_blocks.toml"), "--out", str(out), "--quiet"])
    assert res.exit_code == 0, res.output
    written = json.loads((out / "summary.json").read_text())
    model, settings = load_model(DATA / "two_blocks.toml")
    direct = srdda.run(model, settings)
    expected = run_summary(direct, direct.final_state)
    assert {k: written[k] for k in expected} == expected  # the same run: every number to its last digit
    assert written["method"] == "dda1" and written["last_step"] == 20
    assert written["cut_attempts"] > 0  # Δt = 2 ms is cut for the spring-tied block
    speed = written["largest_speed"]
    assert (f"largest speed: {speed['value']:.6g} m/s, block {speed['block']} at t = {speed['time']:.6g} s"
            in res.output)
    assert f"step attempts cut: {written['cut_attempts']}" in res.output


# -- srdda history ----------------------------------------------------------------------------------
G = 9.81


@pytest.fixture(scope="module")
def falling(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results file of a block falling freely for 0.2 s, a measured point on it."""
    m = srdda.Model(gravity=(0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", name="stone")
    m.add_measured_point([0.25, 0.75])
    settings = srdda.RunSettings(dt=1e-2, n_steps=20, record_every=2)
    path = tmp_path_factory.mktemp("history") / "fall.h5"
    assert srdda.run(m, settings, recorders=[ResultsStore(path, settings)]).completed
    return path


def _csv(path: Path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text(encoding="utf-8").splitlines()
    return lines[0].split(","), np.loadtxt(lines[1:], delimiter=",", ndmin=2)


def test_history_csv_of_a_falling_block_is_half_g_t_squared(falling: Path, tmp_path: Path) -> None:
    out = tmp_path / "fall.csv"
    res = CliRunner().invoke(main, ["history", str(falling), "--block", "stone", "--point", "0",
                                    "--quantity", "displacement", "--quantity", "velocity.vy", "--csv", str(out)])
    assert res.exit_code == 0, res.output
    header, table = _csv(out)
    assert header == ["time (s)", "step", "stone: displacement.x (m)", "stone: displacement.y (m)",
                      "stone: velocity.vy (m/s)", "point 0: displacement.x (m)", "point 0: displacement.y (m)",
                      "point 0: velocity.vy (m/s)"]
    t = table[:, 0]
    np.testing.assert_allclose(t, np.arange(0, 21, 2) * 1e-2, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(table[:, 1], np.arange(0, 21, 2))
    for col in (3, 6):  # the block's and the point's fall
        np.testing.assert_allclose(table[:, col], -0.5 * G * t**2, rtol=0, atol=1e-12)
    for col in (4, 7):
        np.testing.assert_allclose(table[:, col], -G * t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(table[:, [2, 5]], 0.0, atol=1e-12)


def test_history_prints_every_quantity_by_default(falling: Path) -> None:
    res = CliRunner().invoke(main, ["history", str(falling), "--block", "0"])
    assert res.exit_code == 0, res.output
    header = res.output.splitlines()[0].split(",")
    assert header == ["time (s)", "step"] + [f"stone: {q}" for q in (
        "centroid.x (m)", "centroid.y (m)", "displacement.x (m)", "displacement.y (m)", "rotation (rad)",
        "velocity.vx (m/s)", "velocity.vy (m/s)", "velocity.omega (rad/s)", "velocity.exx_rate (1/s)",
        "velocity.eyy_rate (1/s)", "velocity.gxy_rate (1/s)", "stress.sxx (Pa)", "stress.syy (Pa)",
        "stress.sxy (Pa)", "area (m²)")]
    table = np.loadtxt(res.output.splitlines()[1:], delimiter=",", ndmin=2)
    np.testing.assert_allclose(table[:, 3], 0.5 - 0.5 * G * table[:, 0] ** 2, rtol=0, atol=1e-12)  # centroid.y


@pytest.mark.parametrize(("args", "message"), [
    (["--block", "boulder"], "--block 'boulder': no such block; the blocks are stone"),
    (["--block", "stone", "--quantity", "speed"],
     "no quantity 'speed' for blocks; they have centroid, displacement, rotation, velocity, stress, area"),
    (["--block", "stone", "--quantity", "velocity.vw"], "the components of velocity are velocity.vx, velocity.vy, "),
    (["--point", "0", "--quantity", "stress"],
     "no quantity 'stress' for measured points; they have position, displacement, velocity"),
    (["--point", "1"], "--point 1: no such measured point; the run has 1 (0 to 0)"),
    ([], "give --block NAME or --point INDEX; the blocks are stone"),
])
def test_history_bad_input_is_one_message(falling: Path, args: list[str], message: str) -> None:
    res = CliRunner().invoke(main, ["history", str(falling), *args])
    assert res.exit_code == 2 and message in res.output and "Traceback" not in res.output, res.output


def test_history_keeps_an_existing_csv_unless_told(falling: Path, tmp_path: Path) -> None:
    out = tmp_path / "mine.csv"
    out.write_text("a user's file\n")
    res = CliRunner().invoke(main, ["history", str(falling), "--block", "stone", "--csv", str(out)])
    assert res.exit_code == 2 and "already exists; pass --overwrite" in res.output
    assert out.read_text() == "a user's file\n"
    res = CliRunner().invoke(main, ["history", str(falling), "--block", "stone", "--csv", str(out), "--overwrite"])
    assert res.exit_code == 0 and out.read_text().startswith("time (s),step,stone: centroid.x (m)")


def test_history_of_a_damaged_file_says_what_plot_says(tmp_path: Path) -> None:
    bad = tmp_path / "results.h5"
    bad.write_bytes(b"not an HDF5 file at all" * 10)
    plot = CliRunner().invoke(main, ["plot", str(bad)])
    history = CliRunner().invoke(main, ["history", str(bad), "--block", "0"])
    assert plot.exit_code == history.exit_code == 2
    assert plot.output.splitlines()[-1] == history.output.splitlines()[-1]
    assert history.output.splitlines()[-1].startswith(f"Error: {bad}: cannot open as an HDF5 results file")


def test_history_of_a_falling_3d_box(tmp_path: Path) -> None:
    m = srdda.Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_box([0, 0, 0], [1, 1, 1], "rock")
    settings = srdda.RunSettings(dt=1e-2, n_steps=10)
    path = tmp_path / "box.h5"
    assert srdda.run(m, settings, recorders=[ResultsStore(path, settings)]).completed
    res = CliRunner().invoke(main, ["history", str(path), "--block", "0", "--quantity", "displacement.z",
                                    "--quantity", "rotation", "--quantity", "area"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    rotation = [f"block 0: rotation.R{i}{j} (1)" for i in (1, 2, 3) for j in (1, 2, 3)]
    assert lines[0].split(",") == ["time (s)", "step", "block 0: displacement.z (m)", *rotation, "block 0: area (m³)"]
    table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    np.testing.assert_allclose(table[:, 2], -0.5 * G * table[:, 0] ** 2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(table[:, 3:12], np.tile(np.eye(3).ravel(), (11, 1)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(table[:, 12], 1.0, rtol=1e-9)
