"""srdda plot / animate / vtk and srdda run --resume, through click's test runner."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import srdda
from srdda.apps import animation
from srdda.apps.cli import main
from srdda.io.modelfile import load_model
from srdda.io.results_store import load_checkpoint, read_results
from srdda.apps.paper import examples_dir

ROD = examples_dir() / "paper" / "rod.toml"


@pytest.fixture(scope="module")
def rod_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("cli") / "rod"
    result = CliRunner().invoke(main, ["run", str(ROD), "--steps", "80", "--out", str(out), "--quiet",
                                       "--flush-every", "16"])
    assert result.exit_code == 0, result.output
    return out / "results.h5"


def test_run_writes_a_results_file_with_the_model_text(rod_run: Path) -> None:
    stored = read_results(rod_run)
    assert stored.completed and len(stored.step) == 81
    assert stored.model_text == ROD.read_text()


def test_plot_commands_write_images(rod_run: Path, tmp_path: Path) -> None:
    runner = CliRunner()
    for args in (["--what", "model", "--step", "40"], ["--what", "trajectories"],
                 ["--what", "series", "--quantity", "energy.total"]):
        out = tmp_path / f"{args[1]}.png"
        result = runner.invoke(main, ["plot", str(rod_run), *args, "-o", str(out)])
        assert result.exit_code == 0, result.output
        assert Image.open(out).size[0] > 100
    folder = runner.invoke(main, ["plot", str(rod_run.parent), "--what", "centroids"])  # srdda run's folder
    assert folder.exit_code == 0 and (rod_run.parent / "results_centroids.png").exists(), folder.output
    bad = runner.invoke(main, ["plot", str(rod_run), "--what", "series", "--quantity", "velocity.spin"])
    assert bad.exit_code == 2 and "unknown quantity 'velocity.spin'" in bad.output
    (tmp_path / "x.h5").write_text("not hdf5")
    bad = runner.invoke(main, ["plot", str(tmp_path / "x.h5")])
    assert bad.exit_code == 2 and "cannot open as an HDF5 results file" in bad.output


def test_animate_writes_a_gif_with_moving_frames(rod_run: Path, tmp_path: Path) -> None:
    out = tmp_path / "rod.gif"
    result = CliRunner().invoke(main, ["animate", str(rod_run), "-o", str(out), "--frames", "6"])
    assert result.exit_code == 0, result.output
    gif = Image.open(out)
    assert gif.n_frames == 6
    first = np.asarray(gif.convert("RGB"))
    gif.seek(5)
    assert np.any(np.asarray(gif.convert("RGB")) != first)  # the rod moved between frames


def test_mp4_without_ffmpeg_falls_back_to_gif(rod_run: Path, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(animation, "ffmpeg_path", lambda: None)
    with pytest.warns(UserWarning, match="no ffmpeg"):
        written = animation.animate(rod_run, tmp_path / "rod.mp4", max_frames=3)
    assert written == tmp_path / "rod.gif" and Image.open(written).n_frames == 3


def test_vtk_command_writes_a_series(rod_run: Path, tmp_path: Path) -> None:
    result = CliRunner().invoke(main, ["vtk", str(rod_run), "-o", str(tmp_path), "--every", "40"])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.glob("*.vtu")) == [f"blocks_{s:07d}.vtu" for s in (0, 40, 80)]
    mesh = meshio.read(tmp_path / "blocks_0000080.vtu")
    assert len(mesh.cells) == 1 and mesh.cells[0].data.shape == (1, 4)


CHILD = textwrap.dedent('''
    import os, signal, sys
    from dataclasses import replace
    import srdda
    from srdda.io.modelfile import load_model
    from srdda.io.results_store import ResultsStore

    class KilledStore(ResultsStore):
        """SIGKILLs its own process right after its 10th flush: a deterministic kill, no timing involved."""
        flushes = 0

        def flush(self):
            super().flush()
            self.flushes += 1
            if self.flushes == 10:
                os.kill(os.getpid(), signal.SIGKILL)

    model, settings = load_model(sys.argv[2])
    settings = replace(settings, n_steps=1500)
    store = KilledStore(sys.argv[1], settings, flush_every=50, model_text=open(sys.argv[2]).read())
    srdda.run(model, settings, recorders=[store])
''')


def test_run_resume_after_sigkill_reaches_the_uninterrupted_state(tmp_path: Path) -> None:
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    path = tmp_path / "results.h5"
    env = {**os.environ, "PYTHONPATH": str(Path(srdda.__file__).parents[1])}
    child = subprocess.run([sys.executable, str(script), str(path), str(ROD)], env=env, capture_output=True, text=True)
    assert child.returncode == -signal.SIGKILL, child.stderr
    killed = read_results(path)
    assert killed.status == "running" and killed.step[-1] == 499  # 10 flushes of 50 recorded steps

    result = CliRunner().invoke(main, ["run", "--resume", str(path), "--quiet"])
    assert result.exit_code == 0, result.output
    model, settings = load_model(ROD)
    reference = srdda.run(model, replace(settings, n_steps=1500)).final_state
    final = load_checkpoint(path, model.arrays())
    assert final.step == 1500 and read_results(path).completed
    for name in ("vertices", "velocity", "acceleration", "stress", "rotation", "points"):
        ref = getattr(reference, name)
        # acceptance: same final state as the uninterrupted run to 1e-12 relative
        assert np.max(np.abs(getattr(final, name) - ref)) <= 1e-12 * max(np.max(np.abs(ref)), 1e-300), name
    both = CliRunner().invoke(main, ["run", str(ROD), "--resume", str(path)])
    assert both.exit_code == 2 and "not both" in both.output


FAKE_FFMPEG = '''#!{python}
"""Stands in for ffmpeg: reads the raw frames matplotlib pipes in and reports what it got."""
import json, sys
args = sys.argv[1:]
data = sys.stdin.buffer.read()
with open(args[-1], "w") as fh:
    json.dump({{"size": args[args.index("-s") + 1], "pix_fmt": args[args.index("-pix_fmt") + 1],
               "bytes": len(data)}}, fh)
'''


def test_mp4_pipes_every_frame_to_ffmpeg(rod_run: Path, tmp_path: Path, monkeypatch) -> None:
    import json

    fake = tmp_path / "ffmpeg"
    fake.write_text(FAKE_FFMPEG.format(python=sys.executable))
    fake.chmod(0o755)
    monkeypatch.setattr(animation, "ffmpeg_path", lambda: str(fake))
    written = animation.animate(rod_run, tmp_path / "rod.mp4", max_frames=5, dpi=50)
    assert written == tmp_path / "rod.mp4"
    got = json.loads(written.read_text())
    width, height = (int(v) for v in got["size"].split("x"))
    assert got["pix_fmt"] == "rgba" and (width, height) == (320, 240)  # 6.4 x 4.8 in at 50 dpi
    assert got["bytes"] == 5 * width * height * 4  # five RGBA frames
