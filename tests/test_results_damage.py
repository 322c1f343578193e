"""Damaged results files and resume (issue 32, items 1 and 2): found when read, one line, resumed exactly.

A damaged file gets one line naming what is damaged and the last intact step,
the same from read_results, `srdda plot`, `srdda vtk` and `srdda run --resume`;
the resume continues from the last intact checkpoint and ends bit-identical to
the uninterrupted run. `--resume` keeps every setting the file stores and
leaves the outputs of a fresh run; it names the run holding a file and says
what is kept when the folder cannot be written; nothing is left behind.
"""
from __future__ import annotations

import errno
import json
import os
import random
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import srdda
from srdda.apps.cli import main
from srdda.io import results_store
from srdda.io.results_store import ResultsDamageWarning, ResultsStore, read_results
from results_fuzz import KINDS, FLUSH, check, damage, sources


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """A block sliding with contacts (results_fuzz): its model file, the uninterrupted and a killed run's files."""
    return sources(tmp_path_factory.mktemp("sources"))


def _flip_in_chunk(path: Path, dataset: str, row: int) -> None:
    """Flip one bit of ``dataset``'s value at ``row`` in the file's bytes, as a bad disk sector would."""
    with h5py.File(path, "r") as f:
        ds = f[dataset]
        chunk = ds.chunks[0]
        info = ds.id.get_chunk_info_by_coord((row // chunk * chunk, *(0,) * (ds.ndim - 1)))
        where = info.byte_offset + (row % chunk) * ds.dtype.itemsize * int(np.prod(ds.shape[1:]))
    data = bytearray(path.read_bytes())
    data[where + 1] ^= 0x10  # the case: step 496 read as 4848
    path.write_bytes(bytes(data))


def _same_histories(path: Path, reference: Path) -> None:
    with h5py.File(path, "r") as a, h5py.File(reference, "r") as b:
        for group in ("history", "contacts"):
            assert set(a[group]) == set(b[group]), group
            for name in b[group]:  # the resumed run is the uninterrupted one: bit for bit
                np.testing.assert_array_equal(a[group][name][()], b[group][name][()], err_msg=f"{group}/{name}")


def _line(output: str) -> str:
    """The damage line of a command's output (after its "path: damaged: ")."""
    found = [line.split(": damaged: ", 1)[1] for line in output.splitlines() if ": damaged: " in line]
    assert len(found) == 1, output
    return found[0]


def test_a_flipped_step_is_found_and_the_resume_keeps_every_intact_row(runs, tmp_path: Path) -> None:
    # issue 32: one flipped byte in /history/step made --resume cut the intact rows, crash, and leave the status
    # "running", the lock and the reserve behind
    _, complete, killed = runs
    path = tmp_path / "results.h5"
    path.write_bytes(killed.read_bytes())
    _flip_in_chunk(path, "history/step", 20)  # the chunk of rows 16-23 (flushes of 8 steps)
    with pytest.warns(ResultsDamageWarning) as caught:
        stored = read_results(path)
    expected = "/history/step from row 16 (its checksum fails); it keeps every step up to step 15 intact"
    assert str(caught[0].message) == f"{path}: damaged: {expected}" == stored.damage
    assert stored.step.tolist() == list(range(16))  # the intact rows, none after the damage
    runner = CliRunner()
    lines = {name: _line(runner.invoke(main, args).output) for name, args in (
        ("plot", ["plot", str(path), "-o", str(tmp_path / "m.png")]),
        ("vtk", ["vtk", str(path), "-o", str(tmp_path / "vtk")]))}
    assert lines == {"plot": expected, "vtk": expected}  # every reader says the same
    result = runner.invoke(main, ["run", "--resume", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    assert _line(result.output) == f"{expected}; resuming from the checkpoint at step 15"
    assert read_results(path).completed and read_results(path).damage is None
    _same_histories(path, complete)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["histories.npz", "m.png", "results.h5", "summary.json",
                                                           "vtk"]  # no lock, no reserve


@pytest.mark.parametrize("dataset, row, then", [
    # rows 40-47 lost (a chunk holds one flush): the run goes back to the checkpoint at step 39
    ("history/velocity", 41, "resuming from the checkpoint at step 39"),
    # the checkpoints at steps 23 and 31 lost (a chunk of 16 vertex rows): the last one, at 60, is intact
    ("checkpoint/vertices", 25, "resuming from the checkpoint at step 60"),
    # contact rows: one chunk holds them all here, so no contact record is intact: the run starts again
    ("contacts/normal_force", 30, "restarting the run from its beginning"),
])
def test_damaged_data_resumes_from_the_last_intact_checkpoint(runs, tmp_path: Path, dataset: str, row: int,
                                                              then: str) -> None:
    _, complete, _ = runs
    path = tmp_path / "results.h5"
    path.write_bytes(complete.read_bytes())
    _flip_in_chunk(path, dataset, row)
    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    assert f"/{dataset} from row " in _line(result.output) and _line(result.output).endswith(then)
    _same_histories(path, complete)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the rewritten file is intact
        assert read_results(path).completed


def test_damaged_results_files_never_end_in_a_traceback_and_resume_exactly(runs, tmp_path: Path) -> None:
    """A sample of the fuzzing of tests/fuzz_full.py: 4 damaged files of each kind (fixed seed)."""
    _, complete, killed = runs
    rng = random.Random(32)
    failures = []
    for i in range(4 * len(KINDS)):
        kind = KINDS[i % len(KINDS)]
        folder = tmp_path / f"d{i}"
        folder.mkdir()
        what = damage(rng.choice([complete, killed]), folder / "results.h5", kind, rng)
        problems, _ = check(folder / "results.h5", complete, kind, folder)
        if problems:
            failures.append((what, problems))
    assert not failures, failures


# -- resume keeps every setting and leaves the outputs of a fresh run (item 2) ------------------------------------
def test_resume_keeps_the_stored_flush_interval_and_leaves_a_fresh_runs_outputs(runs, tmp_path: Path) -> None:
    model_file, complete, killed = runs
    fresh = tmp_path / "fresh"
    assert CliRunner().invoke(main, ["run", str(model_file), "--out", str(fresh), "--quiet", "--flush-every",
                                     str(FLUSH)]).exit_code == 0
    resumed = tmp_path / "resumed"
    resumed.mkdir()
    (resumed / "results.h5").write_bytes(killed.read_bytes())  # killed after its 4th flush: steps 0-31
    result = CliRunner().invoke(main, ["run", "--resume", str(resumed / "results.h5"), "--quiet"])
    assert result.exit_code == 0, result.output
    assert f"completed: 61 recorded steps written to {resumed / 'results.h5'} and" in result.output
    with h5py.File(resumed / "results.h5", "r") as f:
        # checkpoints every 8 recorded steps as the file says (the CLI's default 100 overrode it before), and the end
        assert f["checkpoint/step"][()].tolist() == [7, 15, 23, 31, 39, 47, 55, 60]
        assert int(f.attrs["flush_every"]) == FLUSH
    assert sorted(p.name for p in resumed.iterdir()) == sorted(p.name for p in fresh.iterdir())
    assert json.loads((resumed / "summary.json").read_text()) == json.loads((fresh / "summary.json").read_text())
    with np.load(resumed / "histories.npz") as a, np.load(fresh / "histories.npz") as b:
        assert sorted(a.files) == sorted(b.files)
        for name in b.files:
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_resume_with_a_flush_interval_given_on_purpose_uses_it(runs, tmp_path: Path) -> None:
    _, _, killed = runs
    path = tmp_path / "results.h5"
    path.write_bytes(killed.read_bytes())
    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet", "--flush-every", "10"])
    assert result.exit_code == 0, result.output
    with h5py.File(path, "r") as f:
        assert f["checkpoint/step"][()].tolist() == [7, 15, 23, 31, 41, 51, 60] and int(f.attrs["flush_every"]) == 10


@pytest.mark.parametrize("option", [["--steps", "5"], ["--method", "dda0"], ["--end-time", "1"], ["--overwrite"],
                                    ["--out", "x"]])
def test_resume_refuses_options_that_would_change_the_run(runs, tmp_path: Path, option: list[str]) -> None:
    _, _, killed = runs
    path = tmp_path / "results.h5"
    path.write_bytes(killed.read_bytes())
    result = CliRunner().invoke(main, ["run", "--resume", str(path), *option])
    assert result.exit_code == 2 and f"{option[0]} cannot change them" in result.output, result.output
    assert path.read_bytes() == killed.read_bytes()


HOLDER = textwrap.dedent('''
    import sys, h5py
    from srdda.io.results_store import ResultsStore, read_results
    store = ResultsStore(sys.argv[1], read_results(sys.argv[1]).settings, resume_from=None)
    store.acquire()
    f = h5py.File(sys.argv[1], "a")  # as a run writing it holds it
    print("holding", flush=True)
    sys.stdin.read()
    f.close()
    store.release()
''')


def test_a_file_held_by_a_running_process_is_refused_naming_it(runs, tmp_path: Path) -> None:
    _, _, killed = runs
    path = tmp_path / "results.h5"
    path.write_bytes(killed.read_bytes())
    env = {**os.environ, "PYTHONPATH": str(Path(srdda.__file__).parents[1])}
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(path)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              text=True, env=env)
    try:
        assert holder.stdout.readline().strip() == "holding"
        for args, code in ((["run", "--resume", str(path), "--quiet"], 1), (["plot", str(path)], 1)):
            result = CliRunner().invoke(main, args)
            assert result.exit_code == code and "Traceback" not in result.output, result.output
            # the holder, not HDF5's "unable to lock file"
            assert f"{path} is being written by another run (pid {holder.pid} on " in result.output, result.output
    finally:
        holder.stdin.close()
        holder.wait(timeout=30)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.h5"]  # the refused commands left nothing


def test_resuming_in_a_folder_that_cannot_be_written_says_so(runs, tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    # the tests may run as root, who may write anywhere: the OS's refusal is injected
    _, _, killed = runs
    path = tmp_path / "results.h5"
    path.write_bytes(killed.read_bytes())

    def refused(*args, **kwargs):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(results_store, "_reserve_file", refused)  # the lock file exists, no new file can be made
    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet"])
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    # before: "the file keeps no step (it failed before its first flush); free some space"
    assert (f"cannot write the results (Permission denied); the file keeps every step up to step 31; make "
            f"{tmp_path} writable, then continue with: srdda run --resume {path}") in result.output
    assert path.read_bytes() == killed.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.h5"]


def test_an_interrupted_run_keeps_its_steps_and_leaves_nothing_behind(runs, tmp_path: Path) -> None:
    # Ctrl-C (or any error) in the middle of a run: before, the lock and a 2 MB reserve file stayed
    model_file, complete, _ = runs
    model, settings = srdda.io.modelfile.load_model(model_file)
    path = tmp_path / "results.h5"
    seen = []

    def progress(step: int) -> None:
        seen.append(sorted(p.name for p in tmp_path.iterdir()))
        if step == 21:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        srdda.run(model, settings, progress=progress, recorders=[ResultsStore(path, settings, flush_every=FLUSH)])
    assert seen[-1] == ["results.h5", "results.h5.lock"]  # while it ran: the reserve has no name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.h5"]
    stopped = read_results(path)
    assert stopped.status == "stopped: interrupted (KeyboardInterrupt)" and stopped.step.tolist() == list(range(22))
    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    _same_histories(path, complete)


def test_an_intact_array_chunked_across_its_rows_is_not_taken_for_damage(tmp_path: Path) -> None:
    # h5py chunks a large model array across its other axes too (the 3D blocks' 6 x 6 compliance of a 1,020-block
    # slope: several chunks share each first row), which the chunk-index check once took for a damaged index
    from srdda.io.integrity import checksummed, read_intact
    value = np.random.default_rng(0).normal(size=(4000, 6, 6))
    with h5py.File(tmp_path / "f.h5", "w", libver=("v108", "v108")) as f:
        ds = f.create_dataset("compliance", data=value, **checksummed(value))
        assert ds.chunks[1:] != ds.shape[1:]  # the case: chunks that split a row
    with h5py.File(tmp_path / "f.h5", "r") as f:
        rows = read_intact(f, "compliance")
    assert rows.problem is None and np.array_equal(rows.data, value)
