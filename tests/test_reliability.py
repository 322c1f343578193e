"""Output safety and bad input (issue 15, docs/reliability.md): each test names the promise it checks."""
from __future__ import annotations

import dataclasses
import errno
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner, Result as CliResult

import srdda
from srdda.apps.cli import main
from srdda.io import outputlock, results_store
from srdda.io.modelfile import load_model
from srdda.io.results_store import ResultsStore, ResultsWriteError, load_checkpoint, read_results, resume
from srdda.ledger import ENERGY_NAMES
from srdda.apps.paper import examples_dir
from srdda.state import initial_state

ROD = examples_dir() / "paper" / "rod.toml"
STATE_FIELDS = ("vertices", "points", "velocity", "acceleration", "stress", "rotation")


def _one_message(result: CliResult, code: int) -> str:
    """The CLI ended with ``code`` and a message, not a traceback; returns its output."""
    assert result.exit_code == code, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert "Traceback" not in result.output
    return result.output


def _rod(n_steps: int) -> tuple[srdda.Model, srdda.RunSettings]:
    model, settings = load_model(ROD)
    return model, dataclasses.replace(settings, n_steps=n_steps)


def _assert_same_state(path: Path, reference: srdda.Result) -> None:
    final = load_checkpoint(path, _rod(0)[0].arrays())
    ref = reference.final_state
    assert final.step == ref.step
    for name in STATE_FIELDS:
        # the resumed run is the uninterrupted one: exact up to 1e-12 relative (acceptance of the results store)
        a, b = getattr(final, name), getattr(ref, name)
        assert np.max(np.abs(a - b)) <= 1e-12 * max(float(np.max(np.abs(b))), 1e-300), name


# -- two runs never share an output; nothing written is damaged -----------------------------------------------
def test_a_second_run_into_a_held_folder_fails_before_touching_the_file(tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = CliRunner().invoke(main, ["run", str(ROD), "--steps", "20", "--out", str(out), "--quiet"])
    assert first.exit_code == 0, first.output
    path = out / "results.h5"
    before = path.read_bytes()
    holder = ResultsStore(path, _rod(20)[1])  # a run holding the folder, as `srdda run` holds it while it runs
    holder.acquire()
    try:
        second = CliRunner().invoke(main, ["run", str(ROD), "--steps", "20", "--out", str(out), "--overwrite"])
        message = _one_message(second, 1)
        assert "being written by another run" in message and f"pid {os.getpid()} on " in message
        assert "started 20" in message  # the holder's start time (ISO date)
        assert path.read_bytes() == before  # not truncated, not touched
        with pytest.raises(results_store.OutputInUseError, match=f"pid {os.getpid()}"):
            resume(path)  # resuming a held file is refused too
        assert path.read_bytes() == before
    finally:
        holder.release()
    again = CliRunner().invoke(main, ["run", str(ROD), "--steps", "20", "--out", str(out), "--overwrite", "--quiet"])
    assert again.exit_code == 0, again.output  # released: the folder can be used again


def test_finished_results_are_replaced_only_with_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "out"
    runner = CliRunner()
    assert runner.invoke(main, ["run", str(ROD), "--steps", "10", "--out", str(out), "--quiet"]).exit_code == 0
    before = (out / "results.h5").read_bytes()
    second = runner.invoke(main, ["run", str(ROD), "--steps", "12", "--out", str(out), "--quiet"])
    message = _one_message(second, 2)  # bad input (docs/cli.md), not a failed run
    assert "results of a run (status 'completed'" in message and "--overwrite" in message
    assert (out / "results.h5").read_bytes() == before
    third = runner.invoke(main, ["run", str(ROD), "--steps", "12", "--out", str(out), "--quiet", "--overwrite"])
    assert third.exit_code == 0, third.output
    assert read_results(out / "results.h5").step[-1] == 12
    assert sorted(p.name for p in out.iterdir()) == ["histories.npz", "results.h5", "summary.json"]  # no lock left


def test_default_output_is_a_new_folder_named_after_the_model_in_the_current_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    models, work = tmp_path / "models", tmp_path / "work"
    models.mkdir()
    work.mkdir()
    model = models / "rod.toml"
    model.write_text(ROD.read_text())
    monkeypatch.chdir(work)
    runner = CliRunner()
    first = runner.invoke(main, ["run", str(model), "--steps", "5", "--quiet"])
    assert first.exit_code == 0, first.output
    assert f"writing {Path('rod') / 'results.h5'}" in first.output
    second = runner.invoke(main, ["run", str(model), "--steps", "5", "--quiet"])
    assert second.exit_code == 0, second.output
    assert f"writing {Path('rod-2') / 'results.h5'}" in second.output
    assert read_results(work / "rod" / "results.h5").completed and read_results(work / "rod-2" / "results.h5").completed
    assert sorted(p.name for p in models.iterdir()) == ["rod.toml"]  # nothing beside the model file


def test_an_unwritable_output_folder_is_one_message(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("a file where a folder should be")
    out = _one_message(CliRunner().invoke(main, ["run", str(ROD), "--steps", "5", "--out", str(blocker / "x")]), 1)
    assert "cannot create the output folder" in out
    # a folder the user may not write in (root may write anywhere, so the OS's refusal is simulated)
    read_only = tmp_path / "read-only"
    read_only.mkdir()
    real_open = open

    def refusing_open(file, *args, **kwargs):
        if Path(file).parent == read_only:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(file))
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(outputlock, "open", refusing_open, raising=False)
    out = _one_message(CliRunner().invoke(main, ["run", str(ROD), "--steps", "5", "--out", str(read_only)]), 1)
    assert f"cannot write in {read_only} (Permission denied)" in out


# -- no lost flushed step -------------------------------------------------------------------------------------------
def test_resume_of_a_run_stopped_before_its_first_flush_restarts_it(tmp_path: Path) -> None:
    model, settings = _rod(30)
    path = tmp_path / "results.h5"
    store = ResultsStore(path, settings, flush_every=1000, model_text=ROD.read_text())
    arrays = model.arrays()
    store.record(arrays, initial_state(arrays, settings.resolved_method()), 0, dict.fromkeys(ENERGY_NAMES, 0.0))
    store._file.close()  # what a kill before the first flush leaves: the header, no step, no checkpoint
    store.release()
    assert "step" not in read_results(path).histories
    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet"])
    out = _one_message(result, 0)
    assert "stopped before its first flush; restarting it" in out
    reference = srdda.run(model, settings)
    stored = read_results(path)
    assert stored.completed
    np.testing.assert_array_equal(stored.step, np.arange(31))
    # the restarted run is the uninterrupted run: same code path from the same initial state, so exact
    np.testing.assert_array_equal(stored.velocity, reference.array("velocity"))
    _assert_same_state(path, reference)


def test_a_results_file_cut_short_in_its_header_is_one_message(tmp_path: Path) -> None:
    import h5py

    path = tmp_path / "results.h5"
    with h5py.File(path, "w") as f:  # what a kill while the store writes the header can leave
        f.attrs["format"] = results_store.FORMAT
        f.create_group("settings")
    for args in (["run", "--resume", str(path)], ["plot", str(path)]):
        out = _one_message(CliRunner().invoke(main, args), 2)
        assert "an incomplete results file (no model, history, checkpoint, contacts" in out


def _failing_after(calls: int, where: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Make the ``calls``-th call of ``results_store.<where>`` fail as a full disk does.

    For ``_append`` only its appends of the velocity history count (one per flush).
    """
    real = getattr(results_store, where)
    count = {"n": 0}

    def failing(*args, **kwargs):
        if where != "_append" or (args[0].name == "/history" and args[1] == "velocity"):
            count["n"] += 1
            if count["n"] == calls:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(*args, **kwargs)

    monkeypatch.setattr(results_store, where, failing)


@pytest.mark.parametrize("where,calls", [
    ("_append", 3),      # a write inside the third flush fails: the flush is cut short
    ("_make_room", 4),   # the disk-space check before the third flush fails (the 1st is at the file's creation)
])
def test_a_full_disk_stops_the_run_with_the_flushed_steps_intact_and_resumable(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, where: str, calls: int) -> None:
    model, settings = _rod(100)
    path = tmp_path / "results.h5"
    flush = 10
    _failing_after(calls, where, monkeypatch)
    with pytest.raises(ResultsWriteError, match="No space left on device") as caught:
        srdda.run(model, settings, recorders=[ResultsStore(path, settings, flush_every=flush)])
    message = str(caught.value)
    assert "the file keeps every step up to step 19" in message and f"srdda run --resume {path}" in message
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.h5"]  # lock and reserve gone
    reference = srdda.run(model, settings)
    kept = read_results(path)
    np.testing.assert_array_equal(kept.step, np.arange(20))  # steps 0..19: the two flushes before the failure
    for name in ("velocity", "centroid", "stress", "energy"):
        np.testing.assert_array_equal(kept.array(name), reference.array(name)[:20], err_msg=name)  # bit for bit
    assert load_checkpoint(path, model.arrays()).step == 19
    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    resumed = read_results(path)
    assert resumed.completed
    np.testing.assert_array_equal(resumed.step, np.arange(101))
    _assert_same_state(path, reference)


def test_a_full_disk_in_the_cli_is_one_message(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _failing_after(3, "_make_room", monkeypatch)  # the 3rd check: before the second flush
    result = CliRunner().invoke(main, ["run", str(ROD), "--steps", "30", "--out", str(tmp_path / "o"), "--quiet",
                                       "--flush-every", "10"])
    out = _one_message(result, 1)
    assert "cannot write the results (No space left on device); the file keeps every step up to step 9;" in out
    assert out.count("\n") == 2  # "writing ..." and the error


# -- no traceback on bad input ----------------------------------------------------------------------------------------
BAD_FILES = {
    "latin1.toml": ('title = "Pente d\'\xe9boulement"\n'.encode("latin-1"),
                    "not a UTF-8 text file (byte 0xe9 on line 1"),
    "binary.toml": (bytes(range(256)) * 4, "not a UTF-8 text file"),
    "nul.toml": (b"title = 'x'\n\x00\x00\x00\x00", "not a text file (it holds NUL bytes"),
    "truncated.toml": (ROD.read_bytes()[:ROD.read_bytes().index(b"vertices = [[") + 20], "not valid TOML"),
    "deep.toml": (b"a = " + b"[" * 5000 + b"]" * 5000, "nested too deeply"),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
@pytest.mark.parametrize("command", ["check", "run"])
def test_an_unreadable_model_file_is_one_message(tmp_path: Path, name: str, command: str) -> None:
    content, expected = BAD_FILES[name]
    path = tmp_path / name
    path.write_bytes(content)
    out = _one_message(CliRunner().invoke(main, [command, str(path)]), 2)
    assert str(path) in out and expected in out, out


def test_a_utf8_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + ROD.read_bytes())  # Windows editors write one
    assert _one_message(CliRunner().invoke(main, ["check", str(path)]), 0).startswith("ok:")


def test_a_hinge_point_in_no_block_is_one_message(tmp_path: Path) -> None:
    text = (Path(__file__).resolve().parents[1] / "examples" / "constraints" / "hinged-wall.toml").read_text()
    path = tmp_path / "hinge.toml"
    # the hinge without its blocks, at a point outside both: srdda cannot tell which blocks it joins
    path.write_text(text.replace('at = [0.4, 0.0]\nblock_a = "wall"\nblock_b = "foundation"\n', "at = [5.0, 5.0]\n"))
    out = _one_message(CliRunner().invoke(main, ["check", str(path)]), 2)
    assert "hinge.toml: toe: cannot tell which blocks point" in out and "give block_a and block_b" in out


# -- figures, animations, ParaView files: the output folder ------------------------------------------------------------
@pytest.fixture(scope="module")
def small_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("small") / "rod"
    result = CliRunner().invoke(main, ["run", str(ROD), "--steps", "6", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    return out / "results.h5"


@pytest.mark.parametrize("command,target", [("plot", "figs/sub/rod.png"), ("animate", "anim/sub/rod.gif"),
                                            ("vtk", "vtk/sub")])
def test_output_folders_of_plot_animate_vtk(small_run: Path, tmp_path: Path, command: str, target: str) -> None:
    extra = ["--frames", "2"] if command == "animate" else []
    made = CliRunner().invoke(main, [command, str(small_run), "-o", str(tmp_path / target), *extra])
    assert made.exit_code == 0, made.output  # a missing folder is created (as srdda run --out does)
    assert (tmp_path / target).exists()
    blocker = tmp_path / "file"
    blocker.write_text("a file where a folder should be")
    bad = CliRunner().invoke(main, [command, str(small_run), "-o", str(blocker / target), *extra])
    out = _one_message(bad, 1)
    assert "cannot write" in out and str(blocker) in out


def test_a_hinge_point_outside_its_named_blocks_is_an_error():
    m = srdda.Model()
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    a = m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    b = m.add_block([[1, 0], [2, 0], [2, 1], [1, 1]], "rock")
    with pytest.raises(srdda.ModelError, match=r"hinge 0: point \(5.0, 0.5\) lies outside block 'block 0'"):
        m.add_hinge((5.0, 0.5), block_a=a, block_b=b)
    assert m.add_hinge((1.0, 0.5), block_a=a, block_b=b) == 0  # on the shared edge: in both blocks


def test_blocks_overlapping_at_the_start_are_an_error_naming_them():
    m = srdda.Model()
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", name="lower")
    m.add_block([[0.5, 0.9], [1.5, 0.9], [1.5, 2], [0.5, 2]], "rock", name="upper")
    m.add_block([[1, 0], [2, 0], [2, 0.9], [1, 0.9]], "rock", name="beside")  # touches both: no overlap
    with pytest.raises(srdda.ModelError, match=r"blocks overlap at the start: 'lower' and 'upper' \(0.05 m²\)"):
        m.arrays()
    m.allow_overlap = True  # deliberately: their contacts push them apart
    assert m.arrays().n_blocks == 3


@pytest.mark.parametrize("bad", [
    lambda m: m.add_block([[0, 0], [1, 0], [1, 1]], "rock", velocity=(float("nan"), 0.0)),
    lambda m: m.add_block([[0, 0], [1, 0], [1, 1]], "rock", angular_velocity=float("inf")),
    lambda m: m.add_material("x", srdda.Material(2500.0, float("inf"), 0.25)),
    lambda m: m.add_point_load((0.5, 0.5), (float("nan"), 0.0), block=0),
    lambda m: m.add_point_spring((0.1, 0.1), (0.2, 0.1), float("inf"), block_a=0, block_b=0),
])
def test_non_finite_inputs_are_named_errors(bad):
    m = srdda.Model()
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    with pytest.raises(srdda.ModelError, match="finite"):
        bad(m)


def test_non_finite_gravity_is_a_named_error():
    m = srdda.Model(gravity=(0.0, float("nan")))
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    with pytest.raises(srdda.ModelError, match="gravity must be finite"):
        m.arrays()


def test_warnings_of_a_run_are_summarised_once():
    # a load function that warns at every call (two calls per step here) gives one warning with its count
    import warnings

    def load(t):
        warnings.warn("load table extrapolated", RuntimeWarning)
        return (0.0, -1.0)

    m = srdda.Model()
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    m.add_point_load((0.5, 0.5), load, block=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=50, method="dda0"))
    messages = [str(w.message) for w in caught if w.category is RuntimeWarning]
    assert messages == ["load table extrapolated (100 times in the run, first at step 1)"]


@pytest.mark.parametrize("blocks, problem", [
    ('''[[blocks]]
material = "r"
vertices = [[0, 0], [1, 0], [1, 1], [0, 1]]
[[blocks]]
material = "r"
vertices = [[0.5, 0.5], [1.5, 0.5], [1.5, 1.5], [0.5, 1.5]]
''', "blocks overlap at the start"),
])
def test_a_model_the_run_cannot_take_is_one_message_before_any_output(tmp_path, blocks, problem):
    gravity = "[0.0, 0.0, -9.81]" if "box" in blocks else "[0.0, -9.81]"
    path = tmp_path / "m.toml"
    path.write_text(f"gravity = {gravity}\n[run]\ndt = 1e-3\nsteps = 5\n[materials.r]\ndensity = 2500.0\n"
                    f"young = 1e9\npoisson = 0.2\n{blocks}", encoding="utf-8")
    for command in (["check", str(path)], ["run", str(path), "--out", str(tmp_path / "out")]):
        out = CliRunner().invoke(main, command)
        assert out.exit_code == 2 and problem in out.output and "Traceback" not in out.output
    assert not (tmp_path / "out").exists()
