"""Every shipped model file, 2D and 3D (examples/ and the package's paper examples), through what a new user
does with it: `srdda show`, `run` (a few steps), `vtk`, `plot` (the model and the energies) and `animate`,
each ending with exit 0 and its files written, never a traceback."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

import srdda
from srdda.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_EXAMPLES = Path(srdda.__file__).parent / "data" / "examples"


def _model_files() -> list[Path]:
    """Every shipped .toml that is a model file (ensemble specs name a base model instead of holding blocks)."""
    files = sorted((ROOT / "examples").rglob("*.toml")) + sorted(PACKAGE_EXAMPLES.rglob("*.toml"))
    return [f for f in files if "model" not in tomllib.loads(f.read_text(encoding="utf-8"))]


MODELS = _model_files()


def test_the_list_covers_2d_and_3d_models_and_the_paper() -> None:
    names = {f.stem for f in MODELS}
    assert {"cube-drop", "rockfall-3d", "hinged-boxes", "jointed_slope", "rod", "rockfall-slope"} <= names
    assert len(MODELS) >= 20


def _ok(result, *written: Path) -> None:
    assert result.exit_code == 0, result.output
    assert "Traceback" not in result.output
    for path in written:
        assert path.exists() and path.stat().st_size > 0, path


@pytest.mark.slow
@pytest.mark.parametrize("model", MODELS, ids=[f"{f.parent.name}/{f.stem}" for f in MODELS])
def test_show_run_vtk_plot_animate(model: Path, tmp_path: Path) -> None:
    runner = CliRunner()
    _ok(runner.invoke(main, ["show", str(model), "-o", str(tmp_path / "model.png")]), tmp_path / "model.png")
    out = tmp_path / "run"
    # three steps keep 25 models affordable; every command below reads what any run writes
    _ok(runner.invoke(main, ["run", str(model), "--steps", "3", "--out", str(out), "--quiet"]), out / "results.h5")
    _ok(runner.invoke(main, ["vtk", str(out), "-o", str(tmp_path / "vtk"), "--quiet"]), tmp_path / "vtk" / "blocks.pvd")
    _ok(runner.invoke(main, ["plot", str(out), "-o", str(tmp_path / "last.png")]), tmp_path / "last.png")
    _ok(runner.invoke(main, ["plot", str(out), "--quantity", "energy", "-o", str(tmp_path / "energy.png")]),
        tmp_path / "energy.png")
    _ok(runner.invoke(main, ["animate", str(out), "-o", str(tmp_path / "run.gif"), "--frames", "3", "--quiet"]),
        tmp_path / "run.gif")
