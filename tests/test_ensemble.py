"""Ensembles (issue 16 items 1-3): sampling, spec errors, collectors, resume, workers, failures, Dask.

The model is a tiny rockfall (a stone leaving a ledge onto a 34° face, 0.6 s of
5 ms steps): each run takes a fraction of a second.
"""
from __future__ import annotations

import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from srdda.apps.cli import main
from srdda.apps.ensemble import SpecError, apply_values, load_spec, run_ensemble, run_one, sample
from srdda.apps.ensemble.collect import SettleRule
from srdda.geometry.ground import Ground
from srdda.apps.ensemble.spec import StopRule
from srdda.io.modelfile import load_model
from srdda.simulation import run

MODEL = """
title = "test slope"
gravity = [0.0, -9.81]
[run]
dt = "5 ms"
end_time = 0.6
contact_penalty = "2 GN/m"
max_displacement_ratio = 0.02
[materials.rock]
density = 2700.0
young = "20 GPa"
poisson = 0.25
[joint_materials.slope]
friction_angle = 35.0
between = [["rock", "rock"]]
[[blocks]]
name = "ledge"
material = "rock"
fixed = true
vertices = [[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]]
[[blocks]]
name = "face"
material = "rock"
fixed = true
vertices = [[2.0, 0.0], [5.0, 0.0], [5.0, 1.0], [2.0, 3.0]]
[[blocks]]
name = "stone"
material = "rock"
vertices = [[1.8, 3.1], [2.2, 3.1], [2.2, 3.4], [1.8, 3.4]]
velocity = [2.0, 0.0]
[[measured_points]]
at = [2.0, 3.25]
block = "stone"
"""

SPEC = """
model = "slope.toml"
runs = 6
seed = 7
stations = [2.5, 3.0, 3.5]
[stop]
domain = [[-1.0, -1.0], [6.0, 10.0]]
[[parameters]]
name = "v0"
shortcut = "velocity_x"
distribution = "normal"
mean = 2.0
std = 0.5
[[parameters]]
name = "friction"
shortcut = "friction"
joint = "slope"
distribution = "uniform"
low = 25.0
high = 40.0
"""

TABLES = ("runs", "collectors", "trajectories")


def write_spec(folder: Path, spec: str = SPEC, model: str = MODEL) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "slope.toml").write_text(model)
    (folder / "spec.toml").write_text(spec)
    return folder / "spec.toml"


def tables(out: Path) -> dict[str, dict]:
    return {name: pq.read_table(out / f"{name}.parquet").to_pydict() for name in TABLES}


def assert_same_tables(a: Path, b: Path) -> None:
    ta, tb = tables(a), tables(b)
    for name in TABLES:
        np.testing.assert_equal(ta[name], tb[name], err_msg=name)  # exact, NaN equal to NaN


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The uninterrupted 6-run ensemble on one worker (a thread of this process)."""
    folder = tmp_path_factory.mktemp("reference")
    run_ensemble(write_spec(folder), folder / "out", workers=1, processes=False, progress=False)
    return folder / "out"


def test_outputs_written(reference: Path) -> None:
    for name in ("runs.parquet", "collectors.parquet", "trajectories.parquet", "summary.json", "summary.csv",
                 "report.md", "report.html", "figures/runout.png", "figures/envelopes.png",
                 "figures/trajectories.png"):
        assert (reference / name).is_file(), name
    runs = tables(reference)["runs"]
    assert runs["run"] == list(range(6)) and set(runs["status"]) == {"ok"}
    values = [sample(load_spec(reference.parent / "spec.toml")[0], i) for i in range(6)]
    assert runs["v0"] == [v["v0"] for v in values] and runs["friction"] == [v["friction"] for v in values]
    assert len(tables(reference)["collectors"]["run"]) == 6 * 3


def test_two_worker_processes_give_the_same_tables(reference: Path, tmp_path: Path) -> None:
    run_ensemble(write_spec(tmp_path), tmp_path / "out", workers=2, processes=True, progress=False)
    assert_same_tables(reference, tmp_path / "out")


def _numba_threads() -> int:
    import numba
    return numba.get_num_threads()


def test_worker_processes_share_the_cores_among_their_numba_threads() -> None:
    # numba starts one thread per core in every process: two workers on two cores would each run a large
    # model's compiled loops on two threads (four threads on two cores)
    from srdda.apps.ensemble.runner import dask_client
    with dask_client(2, None, processes=True) as client:
        threads = {client.submit(_numba_threads, pure=False).result() for _ in range(4)}
    assert threads == {max(1, (os.cpu_count() or 1) // 2)}


def test_resume_after_a_stop_gives_the_uninterrupted_tables(reference: Path, tmp_path: Path) -> None:
    spec = write_spec(tmp_path)
    first = run_ensemble(spec, tmp_path / "out", runs=3, workers=1, processes=False, progress=False)
    assert (first.ran, first.resumed) == (3, 0)
    # what a kill leaves: the runs written so far and a run file half written under its temporary name
    (tmp_path / "out" / "runs" / ".run-0000003.json.999.tmp").write_text('{"run": 3, "sta')
    again = run_ensemble(spec, tmp_path / "out", workers=1, processes=False, progress=False)
    assert (again.ran, again.resumed) == (3, 3)
    assert_same_tables(reference, tmp_path / "out")
    done = run_ensemble(spec, tmp_path / "out", workers=1, processes=False, progress=False)
    assert (done.ran, done.resumed) == (0, 6)


def test_resume_refuses_another_spec(reference: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    shutil.copytree(reference, out)
    spec = write_spec(tmp_path, SPEC.replace("seed = 7", "seed = 8"))
    with pytest.raises(SpecError, match="holds runs of another spec"):
        run_ensemble(spec, out, workers=1, processes=False, progress=False)


def test_a_second_ensemble_into_a_held_folder_fails_naming_the_first(reference: Path, tmp_path: Path) -> None:
    # issue 32: two `srdda ensemble` runs into one --out both ran; the folder is now held like a run's output
    from srdda.io.outputlock import release_lock, take_lock

    out = tmp_path / "out"
    shutil.copytree(reference, out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    lock = out / "ensemble.lock"
    held = take_lock(lock, str(out))  # what a running `srdda ensemble --out out` holds
    try:
        result = CliRunner().invoke(main, ["ensemble", str(write_spec(tmp_path)), "--out", str(out), "--workers", "1",
                                           "--quiet"])
        assert result.exit_code == 1 and "Traceback" not in result.output, result.output
        assert f"{out} is being written by another run (pid {os.getpid()} on " in result.output
        assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p != lock} == before  # untouched
    finally:
        release_lock(lock, held)
    done = run_ensemble(write_spec(tmp_path), out, workers=1, processes=False, progress=False)
    assert (done.ran, done.resumed) == (0, 6) and not lock.exists()  # released: usable again, no lock left


def test_zero_variance_reproduces_the_single_run(tmp_path: Path) -> None:
    spec_text = SPEC.replace("std = 0.5", "std = 0.0").replace("low = 25.0\nhigh = 40.0", "low = 35.0\nhigh = 35.0")
    spec_text += ('\n[[parameters]]\nname = "dx"\nshortcut = "release_dx"\ndistribution = "normal"\nmean = 0.0\n'
                  'std = 0.0\n[[parameters]]\nname = "size"\nshortcut = "scale"\ndistribution = "choice"\n'
                  'values = [1.0]\n')
    spec = write_spec(tmp_path, spec_text.replace("runs = 6", "runs = 2"))
    run_ensemble(spec, tmp_path / "out", workers=1, processes=False, progress=False)
    got = tables(tmp_path / "out")
    model, settings = load_model(tmp_path / "slope.toml")
    single = run(model, settings)
    centroid = single.array("centroid")[:, 2]
    velocity = single.array("velocity")[:, 2]
    for k in range(2):  # both runs are the base model itself: bit for bit the single run
        assert got["runs"]["end_x"][k] == centroid[-1, 0] and got["runs"]["end_y"][k] == centroid[-1, 1]
        assert got["runs"]["end_time"][k] == single.time[-1] and got["runs"]["stop_reason"][k] == "end_time"
    # the crossings, from the single run's histories: first recorded step at or past each station,
    # interpolated linearly in x from the step before
    rows = got["collectors"]
    mass = 2700.0 * 0.4 * 0.3
    inertia = mass * (0.4**2 + 0.3**2) / 12.0  # rigid rectangle; the stone's strain changes it by < 1e-5
    reached = [station for station in (2.5, 3.0, 3.5) if np.any(centroid[:, 0] >= station)]
    assert reached == [2.5, 3.0]  # the stone stops near x = 3: the third collector is not crossed
    assert rows["crossed"] == [True, True, False] * 2 and math.isnan(rows["speed"][2])
    for station in reached:
        k = int(np.argmax(centroid[:, 0] >= station))
        f = (station - centroid[k - 1, 0]) / (centroid[k, 0] - centroid[k - 1, 0])
        v = velocity[k - 1] + f * (velocity[k] - velocity[k - 1])
        c = centroid[k - 1] + f * (centroid[k] - centroid[k - 1])
        i = rows["collector"].index(f"x={station:g}")
        # same formula, other rounding order: a few ulps
        assert rows["time"][i] == pytest.approx(single.time[k - 1] + f * (single.time[k] - single.time[k - 1]),
                                                rel=1e-12)
        assert rows["speed"][i] == pytest.approx(math.hypot(v[0], v[1]), rel=1e-12)
        assert rows["kinetic_translational"][i] == pytest.approx(0.5 * mass * (v[0] ** 2 + v[1] ** 2), rel=1e-12)
        assert rows["kinetic_rotational"][i] == pytest.approx(0.5 * inertia * v[2] ** 2, rel=1e-4)
        ground = 3.0 - (station - 2.0) * 2.0 / 3.0  # the face: from (2, 3) to (5, 1)
        assert rows["bounce_height"][i] == pytest.approx(c[1] - ground, rel=1e-12)


def test_a_failing_sample_is_recorded_and_the_others_finish(tmp_path: Path) -> None:
    spec = write_spec(tmp_path, SPEC.replace("low = 25.0\nhigh = 40.0", "low = 80.0\nhigh = 100.0"))
    outcome = run_ensemble(spec, tmp_path / "out", workers=1, processes=False, progress=False)
    runs = tables(tmp_path / "out")["runs"]
    bad = [sample(outcome.spec, i)["friction"] >= 90.0 for i in range(6)]  # the schema needs φ < 90°
    assert 0 < sum(bad) < 6  # the seed gives both kinds
    assert outcome.failed == sum(bad)
    for k in range(6):
        if bad[k]:
            assert runs["status"][k] == "failed" and "joint_materials.slope.friction_angle" in runs["message"][k]
            assert math.isnan(runs["end_x"][k])
        else:
            assert runs["status"][k] == "ok" and np.isfinite(runs["end_x"][k])


@pytest.mark.parametrize("change, message", [
    (("std = 0.5", "std = -0.5"), "parameters[0].normal.std"),
    (("std = 0.5", "sd = 0.5"), "parameters[0].normal.sd: unknown field"),
    (('distribution = "normal"', 'distribution = "gauss"'), "parameters[0]"),
    (('shortcut = "velocity_x"', 'path = "blocks.stone.speed"'), "no field 'speed'"),
    (('joint = "slope"', 'joint = "bedding"'), "no field 'bedding'"),
    (('model = "slope.toml"', 'model = "missing.toml"'), "cannot read the model file"),
    (("runs = 6", "runs = 0"), "runs: Input should be greater than or equal to 1"),
    (("domain = [[-1.0, -1.0], [6.0, 10.0]]", "domain = [[1.0, -1.0], [0.0, 10.0]]"), "stop: domain is"),
    (("stations = [2.5, 3.0, 3.5]", "stations = [2.5, 2.5]"), "collector names must be unique"),
])
def test_a_bad_spec_is_one_clear_error(tmp_path: Path, change: tuple[str, str], message: str) -> None:
    assert change[0] in SPEC
    spec = write_spec(tmp_path, SPEC.replace(*change))
    with pytest.raises(SpecError) as info:
        load_spec(spec)
    assert message in str(info.value)
    result = CliRunner().invoke(main, ["ensemble", str(spec), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2 and message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()  # nothing made before the spec is checked


def test_samples_depend_on_seed_and_index_only(tmp_path: Path) -> None:
    spec, _ = load_spec(write_spec(tmp_path))
    assert sample(spec, 4) == sample(spec.model_copy(update={"runs": 1000}), 4)
    assert sample(spec, 4) != sample(spec, 5)


def test_distributions_have_their_moments(tmp_path: Path) -> None:
    text = SPEC.replace('distribution = "normal"\nmean = 2.0\nstd = 0.5',
                        'distribution = "lognormal"\nmean = 2.0\nstd = 0.5')
    text = text.replace('distribution = "uniform"\nlow = 25.0\nhigh = 40.0',
                        'distribution = "choice"\nvalues = [30.0, 35.0]\nweights = [3.0, 1.0]')
    spec, _ = load_spec(write_spec(tmp_path, text))
    n = 20000
    draws = [sample(spec, i) for i in range(n)]
    v0 = np.array([d["v0"] for d in draws])
    # standard errors: mean 0.5/√n = 0.0035, std about 0.5·√(2/n)·(kurtosis) < 0.01: 4 σ bounds
    assert v0.mean() == pytest.approx(2.0, abs=0.015)
    assert v0.std() == pytest.approx(0.5, abs=0.04)
    assert v0.min() > 0
    share = np.mean([d["friction"] == 30.0 for d in draws])
    assert share == pytest.approx(0.75, abs=4 * math.sqrt(0.75 * 0.25 / n))  # binomial, 4 σ


def shoelace(vertices: list[list[float]]) -> float:
    x, y = np.asarray(vertices).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


@pytest.mark.parametrize("shortcut, value, area_factor", [("scale", 1.3, 1.69), ("aspect", 2.0, 1.0),
                                                          ("release_dx", 0.25, 1.0)])
def test_block_shortcuts(tmp_path: Path, shortcut: str, value: float, area_factor: float) -> None:
    text = SPEC + f'[[parameters]]\nname = "p"\nshortcut = "{shortcut}"\ndistribution = "choice"\nvalues = [{value}]\n'
    spec, base = load_spec(write_spec(tmp_path, text))
    data = apply_values(base, spec, {**sample(spec, 0), "p": value})
    stone = data["blocks"][2]["vertices"]
    # area × s² for a scale s, kept by an aspect change and a shift (round-off only)
    assert shoelace(stone) == pytest.approx(area_factor * shoelace(base["blocks"][2]["vertices"]), rel=1e-12)
    width = max(v[0] for v in stone) - min(v[0] for v in stone)
    height = max(v[1] for v in stone) - min(v[1] for v in stone)
    expected_ratio = (0.4 / 0.3) * (value if shortcut == "aspect" else 1.0)
    assert width / height == pytest.approx(expected_ratio, rel=1e-12)
    centre = np.mean(stone, axis=0)
    shift = value if shortcut == "release_dx" else 0.0
    np.testing.assert_allclose(centre, [2.0 + shift, 3.25], rtol=1e-12)
    np.testing.assert_allclose(data["measured_points"][0]["at"], [2.0 + shift, 3.25], rtol=1e-12)  # moves along
    assert base["blocks"][2]["vertices"][0] == [1.8, 3.1]  # the base is not changed


def test_ground_height_below_a_point(tmp_path: Path) -> None:
    model, _ = load_model(write_spec(tmp_path).parent / "slope.toml")
    ground = Ground(model.arrays())
    assert ground.height_below(np.array([1.0, 5.0])) == pytest.approx(3.0, abs=1e-12)
    assert ground.height_below(np.array([3.5, 5.0])) == pytest.approx(3.0 - 1.5 * 2 / 3, abs=1e-12)
    assert math.isnan(ground.height_below(np.array([7.0, 5.0])))  # beyond the slope: no ground


def test_stop_predicate_ends_the_run_at_its_step(tmp_path: Path) -> None:
    model, settings = load_model(write_spec(tmp_path).parent / "slope.toml")
    stopped = run(model, settings, stop=lambda state: state.step >= 5)
    five = run(model, replace(settings, end_time=None, n_steps=5))
    assert stopped.completed and stopped.step[-1] == 5 and stopped.step == five.step
    np.testing.assert_array_equal(stopped.final_state.vertices, five.final_state.vertices)


def test_settle_rule_rest_and_domain(tmp_path: Path) -> None:
    model, settings = load_model(write_spec(tmp_path).parent / "slope.toml")
    arrays = model.arrays()
    # the stone starts 10 cm above the ledge's edge: its centroid is outside a domain below y = 3.2
    out = SettleRule(arrays, StopRule(domain=([-1.0, -1.0], [6.0, 3.2])))
    result = run(arrays, settings, stop=out)
    assert out.reason == "out_of_domain" and result.step[-1] == 1
    # dropped with no velocity onto the flat ledge: at rest within the run, the rest held for 0.1 s
    still = replace(model, blocks=[replace(b, velocity=(0.0,) * len(b.velocity)) for b in model.blocks])
    rule = SettleRule(still.arrays(), StopRule(rest_speed=0.05, rest_duration=0.1))
    result = run(still, replace(settings, end_time=2.0), stop=rule)
    assert rule.reason == "rest" and result.final_state.time == pytest.approx(rule.time_to_stop + 0.1, abs=6e-3)
    assert rule.time_to_stop < 1.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_a_separate_dask_cluster_gives_the_same_tables(reference: Path, tmp_path: Path) -> None:
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    procs = [subprocess.Popen([str(bin_dir / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--dashboard-address", ":0"], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)]
    try:
        procs.append(subprocess.Popen([str(bin_dir / "dask"), "worker", address, "--nworkers", "2", "--nthreads",
                                       "1", "--dashboard-address", ":0"], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, start_new_session=True))
        spec = write_spec(tmp_path)
        result = CliRunner().invoke(main, ["ensemble", str(spec), "--scheduler", address, "--out",
                                           str(tmp_path / "out"), "--quiet"])
        assert result.exit_code == 0, result.output
        assert_same_tables(reference, tmp_path / "out")
    finally:
        for p in reversed(procs):  # worker first, then the scheduler; each in its own process group
            os.killpg(p.pid, signal.SIGTERM)
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


@pytest.mark.slow
def test_a_killed_ensemble_resumes(reference: Path, tmp_path: Path) -> None:
    spec = write_spec(tmp_path)
    out = tmp_path / "out"
    # 30 runs, killed once 2 are written; the resume asks for the first 6 (the reference's)
    cmd = [str(Path(sys.executable).parent / "srdda"), "ensemble", str(spec), "--runs", "30", "--workers", "1",
           "--out", str(out), "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while len(list((out / "runs").glob("run-*.json"))) < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the command and its cluster's worker, at once
        proc.wait()
    written = {p: p.read_bytes() for p in (out / "runs").glob("run-*.json")}
    assert 2 <= len(written) < 30
    result = CliRunner().invoke(main, ["ensemble", str(spec), "--workers", "1", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    assert all(p.read_bytes() == text for p, text in written.items())  # finished runs were not run again
    assert_same_tables(reference, out)


def test_the_paper_report_gets_the_ensemble_section(reference: Path, tmp_path: Path) -> None:
    from srdda.apps.report import write_report

    shutil.copytree(reference, tmp_path / "ensemble")
    md, html_path = write_report(tmp_path, [], command="test")
    text = md.read_text()
    assert "## Probabilistic rockfall" in text and "ensemble/figures/envelopes.png" in text
    hits = tables(reference)["collectors"]
    crossed = sum(c and name == "x=2.5" for c, name in zip(hits["crossed"], hits["collector"]))
    assert f"| x=2.5 | {crossed} / 6 |" in text
    assert html_path.read_text().count("<figure>") == 3
    plain, _ = write_report(tmp_path / "without", [], command="test")
    assert "Probabilistic rockfall" not in plain.read_text()


SOLID = """
gravity = [0.0, 0.0, -9.81]
[run]
dt = "5 ms"
end_time = 0.3
contacts = false
[materials.rock]
density = 2700.0
young = "20 GPa"
poisson = 0.25
[[blocks]]
name = "ground"
material = "rock"
fixed = true
box = [[-5.0, -5.0, -1.0], [5.0, 5.0, 0.0]]
[[blocks]]
name = "stone"
material = "rock"
box = [[-0.2, -0.3, 1.0], [0.2, 0.3, 1.4]]
velocity = [2.0, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 1.5]
"""


def test_a_collector_plane_in_3d(tmp_path: Path) -> None:
    spec_text = ('model = "slope.toml"\nruns = 1\nseed = 0\nstations = [0.5]\n[[collectors]]\nname = "level"\n'
                 'at = [0.0, 0.0, 1.0]\nnormal = [0.0, 0.0, -1.0]\n')
    spec, base = load_spec(write_spec(tmp_path, spec_text, SOLID))
    got = run_one(spec, base, 0)
    assert got["status"] == "ok", got["message"]
    mass = 2700.0 * 0.4 * 0.6 * 0.4
    rotational = 0.5 * mass * (0.4**2 + 0.6**2) / 12.0 * 1.5**2  # ½·I_z·ω², box about its vertical axis
    # free flight under constant gravity: the time scheme is exact for a constant acceleration
    station, level = got["collectors"]["x=0.5"], got["collectors"]["level"]
    assert station["time"] == pytest.approx(0.25, rel=1e-12)
    assert station["z"] == pytest.approx(1.2 - 0.5 * 9.81 * 0.25**2, rel=1e-12)
    assert station["bounce_height"] == pytest.approx(station["z"], rel=1e-12)  # the ground's top is z = 0
    assert station["kinetic_rotational"] == pytest.approx(rotational, rel=1e-6)  # strain-free rigid box
    # the level z = 1 is crossed downwards between two steps: linear interpolation, one step's curvature
    t = math.sqrt(2 * 0.2 / 9.81)
    assert level["time"] == pytest.approx(t, abs=0.5 * 9.81 * 0.005**2 / (9.81 * t))
    assert level["bounce_height"] == pytest.approx(1.0, rel=1e-12)
