"""The HDF5 results store: content, crash safety (SIGKILL) and resume."""
from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest

import srdda
from srdda.io.results_store import (ResultsFileError, ResultsStore, load_checkpoint, model_arrays_from_file,
                                    read_results, resume)
from srdda.io.results_reader import MODEL_DATASETS
from srdda.model import RENAMED_FIELDS, AttachedPoints, ModelArrays
from results_models import ROD_SOURCE, rod_model, rod_settings, two_block_model

STATE_FIELDS = ("vertices", "points", "velocity", "acceleration", "stress", "rotation")


def _max_relative(a: np.ndarray, b: np.ndarray) -> float:
    scale = max(float(np.max(np.abs(b))), 1e-300)
    return float(np.max(np.abs(a - b))) / scale


def test_store_holds_the_same_histories_as_the_in_memory_result(tmp_path: Path) -> None:
    settings = srdda.RunSettings(dt=1e-3, n_steps=57, record_every=2)
    path = tmp_path / "run.h5"
    res = srdda.run(two_block_model(), settings, recorders=[ResultsStore(path, settings, flush_every=7)])
    stored = read_results(path)
    # the file holds exact copies of the recorded arrays: equality, no tolerance
    for name in ("step", "time", "centroid", "area", "rotation", "velocity", "stress", "measured_position",
                 "measured_velocity", "iterations"):
        np.testing.assert_array_equal(stored.array(name), res.array(name), err_msg=name)
    np.testing.assert_array_equal(stored.array("energy"), res.array("energy"))
    assert stored.energy_names == tuple(res.energy[0])
    assert stored.status == "completed" and stored.settings == settings
    assert stored.block_names == res.block_names
    assert stored.array("vertices")[-1].tolist() == res.final_state.vertices.tolist()


def test_a_model_without_points_is_stored(tmp_path: Path) -> None:
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    settings = srdda.RunSettings(dt=1e-3, n_steps=5)
    srdda.run(m, settings, recorders=[ResultsStore(tmp_path / "p.h5", settings, flush_every=2)])
    stored = read_results(tmp_path / "p.h5")
    assert stored.measured_position.shape == (6, 0, 2) and stored.completed
    resume(tmp_path / "p.h5")  # nothing left to run: the file stays complete
    assert read_results(tmp_path / "p.h5").step.tolist() == list(range(6))


def test_stored_model_rebuilds_the_model_arrays(tmp_path: Path) -> None:
    model = rod_model()
    settings = rod_settings(n_steps=3)
    path = tmp_path / "rod.h5"
    srdda.run(model, settings, recorders=[ResultsStore(path, settings, model_text="# the model file")])
    original, rebuilt = model.arrays(), model_arrays_from_file(path)
    for record, again in ((original, rebuilt), (original.attached, rebuilt.attached)):
        for name, value in vars(record).items():
            if isinstance(value, np.ndarray):
                np.testing.assert_array_equal(getattr(again, name), value, err_msg=name)
    assert rebuilt.block_names == original.block_names
    for t in (0.0, 0.3, 2.0):  # the table load survives the round trip
        np.testing.assert_array_equal(rebuilt.attached.load_force[0](t), original.attached.load_force[0](t))
    assert read_results(path).model_text == "# the model file"
    with h5py.File(path) as f:
        assert {"numpy", "h5py", "hdf5", "srdda", "python"} <= set(f["versions"].attrs)


def test_the_stored_model_keeps_the_dataset_names_of_srdda_0_1() -> None:
    # every array of ModelArrays and of its attached points has a dataset (else a file would silently lose it),
    # named as srdda 0.1 named the field (so that files of either version read in the other)
    def arrays_of(record: type, prefix: str = "") -> set[str]:
        return {prefix + f.name for f in dataclasses.fields(record) if str(f.type).startswith("np.ndarray")}

    assert set(MODEL_DATASETS.values()) == arrays_of(ModelArrays) | arrays_of(AttachedPoints, "attached.")
    for old, new in RENAMED_FIELDS.items():
        assert MODEL_DATASETS.get(old, new) == new, old  # "loads" (a tuple of histories) is an attribute
    unchanged = set(MODEL_DATASETS) - set(RENAMED_FIELDS)
    assert all(MODEL_DATASETS[name] == name for name in unchanged)


def test_a_callable_load_needs_the_model_to_resume(tmp_path: Path) -> None:
    model = rod_model()
    model.add_point_load([5.0, 0.05], lambda t: (0.0, -t))
    settings = rod_settings(n_steps=4)
    path = tmp_path / "f.h5"
    srdda.run(model, settings, recorders=[ResultsStore(path, settings)])
    with pytest.raises(ResultsFileError, match="Python function"):
        resume(path)


def test_not_a_results_file_is_a_clear_error(tmp_path: Path) -> None:
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = 1
    with pytest.raises(ResultsFileError, match="not an srdda results file"):
        read_results(tmp_path / "other.h5")
    (tmp_path / "text.h5").write_text("hello")
    with pytest.raises(ResultsFileError, match="cannot open"):
        read_results(tmp_path / "text.h5")


def test_contact_hook_appends_ragged_rows_at_its_interval(tmp_path: Path) -> None:
    def provider(arrays, state):  # a synthetic contact list whose length changes with the step
        n = state.step % 3
        return {"normal_force": np.full(n, float(state.step)), "point": np.zeros((n, 2))}

    settings = srdda.RunSettings(dt=1e-3, n_steps=20)
    path = tmp_path / "c.h5"
    srdda.run(two_block_model(), settings,
              recorders=[ResultsStore(path, settings, flush_every=4, contact_provider=provider, contact_every=5)])
    stored = read_results(path)
    np.testing.assert_array_equal(stored.contacts["step"], [0, 5, 10, 15, 20])
    for i, step in enumerate(stored.contacts["step"]):
        c = stored.contacts_at(i)
        assert len(c["normal_force"]) == step % 3 and np.all(c["normal_force"] == step)


CHILD = textwrap.dedent('''
    import os, signal, sys
    {source}
    from srdda.io import results_store
    from srdda.io.results_store import ResultsStore

    def kill(*_):
        os.kill(os.getpid(), signal.SIGKILL)

    class KilledStore(ResultsStore):
        """SIGKILLs its own process at a fixed point of flush number {kill_flush} (0-based): deterministic."""
        flushes = 0

        def flush(self):
            if self.flushes == {kill_flush} and "{where}" != "after":
                real_append = results_store._append

                def append(group, name, rows, chunk_rows):
                    if "{where}" == "data" and group.name == "/history" and name == "stress":
                        kill()  # half-way through the data phase: some histories appended, not flushed
                    return real_append(group, name, rows, chunk_rows)

                results_store._append = append
                results_store.commit_checkpoint = kill  # "commit": data and steps flushed, checkpoint not
            super().flush()
            if self.flushes == {kill_flush}:
                kill()
            self.flushes += 1

    settings = srdda.RunSettings(dt=1e-3, n_steps={n_steps}, method="{method}", penalty=2e16)
    srdda.run(rod_model(), settings, recorders=[KilledStore(sys.argv[1], settings, flush_every={flush})])
''')


@pytest.mark.parametrize("method,where", [("dda1", "after"), ("srdda", "after"), ("srdda", "commit"),
                                          ("srdda", "data")])
def test_sigkill_leaves_every_flushed_step_and_resume_matches(tmp_path: Path, method: str, where: str) -> None:
    # The child kills itself at a fixed point of its 17th flush (no timing involved): right after it
    # ("after"), before the checkpoint's step row is written ("commit"), or half-way through appending the
    # histories ("data"). Every flush before it must be in the file, and resume must complete the run.
    n_steps, flush, kill_flush = 1500, 25, 16
    script = tmp_path / "child.py"
    script.write_text(CHILD.format(source=ROD_SOURCE, n_steps=n_steps, flush=flush, kill_flush=kill_flush,
                                   method=method, where=where))
    path = tmp_path / "killed.h5"
    env = {**os.environ, "PYTHONPATH": str(Path(srdda.__file__).parents[1])}
    child = subprocess.run([sys.executable, str(script), str(path)], env=env, capture_output=True, text=True)
    assert child.returncode == -signal.SIGKILL, child.stderr

    killed = read_results(path)
    # the rows the file shows: whole flushes only (the first record is step 0); "commit" shows the steps of the
    # flush it was killed in (they were flushed), and its checkpoint is still the previous flush's
    n = flush * (kill_flush + (where == "commit") + (where == "after"))
    assert killed.status == "running"  # it never finished
    np.testing.assert_array_equal(killed.step, np.arange(n))
    assert np.all(np.isfinite(killed.velocity)) and np.all(np.isfinite(killed.vertices))
    checkpoint_step = flush * (kill_flush + (where == "after")) - 1
    assert load_checkpoint(path, rod_model().arrays()).step == checkpoint_step

    settings = rod_settings(method, n_steps)
    reference = srdda.run(rod_model(), settings)
    # flushed rows are the uninterrupted run's rows, bit for bit
    np.testing.assert_array_equal(killed.velocity, reference.array("velocity")[:n])

    resume(path)
    resumed = read_results(path)
    assert resumed.status == "completed"
    np.testing.assert_array_equal(resumed.step, np.arange(n_steps + 1))
    final = load_checkpoint(path, rod_model().arrays())
    assert final.step == n_steps
    # acceptance: the resumed run reaches the uninterrupted run's final state to 1e-12 relative
    for name in STATE_FIELDS:
        assert _max_relative(getattr(final, name), getattr(reference.final_state, name)) <= 1e-12, name
    assert _max_relative(resumed.velocity, reference.array("velocity")) <= 1e-12
    assert _max_relative(resumed.measured_position, reference.array("measured_position")) <= 1e-12


def test_resume_with_contacts_and_cut_steps_is_exact(tmp_path: Path) -> None:
    # A block dropped onto a fixed base with a tight g2: the step-size control cuts
    # and regrows Δt, and the contact set persists between steps. Both live on the
    # State, so a resumed run must equal the uninterrupted one (to 1e-12 relative).
    def model() -> srdda.Model:
        m = srdda.Model(gravity=(0.0, -10.0))
        m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
        m.add_block([[-2, -1], [2, -1], [2, 0], [-2, 0]], "rock", fixed=True)
        m.add_block([[-0.5, 0.05], [0.5, 0.05], [0.5, 0.55], [-0.5, 0.55]], "rock", angular_velocity=0.3)
        return m

    settings = srdda.RunSettings(dt=2e-3, n_steps=160, method="srdda", penalty=1e10, max_displacement_ratio=0.002)
    reference = srdda.run(model(), settings)
    assert reference.completed
    steps_dt = np.diff(reference.array("time"))
    touching = np.asarray(reference.closed_contacts) > 0
    # step k ran with a cut Δt while the block was in contact
    cut = [k for k in range(20, 140) if steps_dt[k - 1] < 0.9 * settings.dt and touching[k]]
    assert cut, "the model must exercise the step-size control during contact"
    half = dataclasses.replace(settings, n_steps=cut[0])
    path = tmp_path / "contact.h5"
    # the file holds the whole run's settings; the first process stops half-way (as if killed)
    first = srdda.run(model(), half, recorders=[ResultsStore(path, settings, flush_every=10)])
    assert first.final_state.contacts is not None and first.final_state.dt_next < settings.dt
    resumed = resume(path, model().arrays())
    ref_state = reference.final_state
    got = resumed.final_state
    assert got.step == ref_state.step
    for name in ("vertices", "velocity", "stress", "rotation"):
        a, b = getattr(got, name), getattr(ref_state, name)
        assert np.max(np.abs(a - b)) <= 1e-12 * max(1.0, np.max(np.abs(b))), name


@pytest.mark.slow
def test_sigkill_at_20_random_steps_then_resume_equals_the_uninterrupted_run_bit_for_bit(tmp_path: Path) -> None:
    # Acceptance of issue 15: a run SIGKILLed at a random moment, then resumed, equals the uninterrupted run
    # bit for bit. The 20 kill steps are drawn with a fixed seed; each forked child kills itself at its step
    # (from inside the time loop, so no timing is involved), wherever that falls between two flushes.
    n_steps, flush = 400, 20
    settings = rod_settings("srdda", n_steps)
    reference = srdda.run(rod_model(), settings)
    kill_steps = np.random.default_rng(15).choice(np.arange(1, n_steps), size=20, replace=False)
    for kill_step in sorted(int(s) for s in kill_steps):
        path = tmp_path / f"killed_at_{kill_step}.h5"
        pid = os.fork()
        if pid == 0:  # the child
            def progress(step: int) -> None:
                if step == kill_step:
                    os.kill(os.getpid(), signal.SIGKILL)

            try:
                srdda.run(rod_model(), settings, progress=progress,
                          recorders=[ResultsStore(path, settings, flush_every=flush)])
            finally:
                os._exit(1)  # not reached: the child dies by its own SIGKILL
        _, status = os.waitpid(pid, 0)
        assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
        if kill_step < flush - 1:  # killed before its first flush: the file holds the header only
            assert "step" not in read_results(path).histories
        else:
            assert read_results(path).step[-1] == (kill_step + 1) // flush * flush - 1
        resume(path)
        stored = read_results(path)
        assert stored.completed, kill_step
        for name in ("step", "time", "velocity", "centroid", "rotation", "stress", "energy", "measured_position"):
            np.testing.assert_array_equal(stored.array(name), reference.array(name), err_msg=f"{name} {kill_step}")
        final = load_checkpoint(path, rod_model().arrays())
        for name in STATE_FIELDS:
            np.testing.assert_array_equal(getattr(final, name), getattr(reference.final_state, name), err_msg=name)


def test_a_streamed_run_keeps_two_rows_in_memory_and_every_row_in_the_file(tmp_path: Path) -> None:
    # run(..., keep_history=False): the Result holds the first and the latest recorded step only, the
    # results file every step; the final state is the same as with the history kept (bit for bit)
    model = rod_model()
    settings = rod_settings("srdda", 60)
    full = srdda.run(model, settings)
    streamed = srdda.run(model, settings, recorders=[ResultsStore(tmp_path / "s.h5", settings, flush_every=7)],
                         keep_history=False)
    assert streamed.step == [0, 60] and len(streamed.velocity) == 2
    np.testing.assert_array_equal(streamed.final_state.velocity, full.final_state.velocity)
    stored = read_results(tmp_path / "s.h5")
    np.testing.assert_array_equal(stored.array("velocity"), full.array("velocity"))
