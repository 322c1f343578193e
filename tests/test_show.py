"""`srdda show`: a model drawn before it runs, 2D and 3D (pyvista off-screen, matplotlib's 3D axes as the
fallback), with every symbol in the legend."""
from __future__ import annotations

from pathlib import Path

import matplotlib.figure
import numpy as np
import pytest
from click.testing import CliRunner
from matplotlib.image import AxesImage
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from srdda.apps import modelview
from srdda.apps.cli import main
from srdda.io.modelfile import load_model
from srdda.apps.render3d import pyvista_renders

ROOT = Path(__file__).resolve().parents[1]
SLOPE = ROOT / "examples" / "cutting" / "jointed_slope.toml"
CUBE = ROOT / "examples" / "solid" / "cube-drop.toml"
BOLTED = ROOT / "examples" / "records" / "quake-bolted-block.toml"


def _labels(fig: matplotlib.figure.Figure) -> list[str]:
    return [t.get_text() for legend in fig.legends for t in legend.get_texts()]


def test_show_draws_a_2d_model_by_material_with_its_joints(tmp_path: Path) -> None:
    # issue 31 item 3: nothing drew a model before it ran
    res = CliRunner().invoke(main, ["show", str(SLOPE), "-o", str(tmp_path / "slope.png")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "slope.png").stat().st_size > 10_000
    fig = modelview.fig_model_setup(load_model(SLOPE)[0], "slope")
    labels = _labels(fig)
    assert {"material: rock", "fixed block", "measured point", "joint: set 1", "joint: set 2"} <= set(labels)


def test_show_draws_bolts_and_fixed_points(tmp_path: Path) -> None:
    labels = _labels(modelview.fig_model_setup(load_model(BOLTED)[0]))
    assert "bolt" in labels


def test_show_renders_a_3d_model_with_pyvista(tmp_path: Path) -> None:
    if not pyvista_renders():
        pytest.skip("pyvista cannot render off-screen on this machine (the matplotlib fallback is tested below)")
    fig = modelview.fig_model_setup(load_model(CUBE)[0], "cube")
    (image,) = [a for ax in fig.axes for a in ax.get_images()]
    assert isinstance(image, AxesImage)
    pixels = np.asarray(image.get_array())
    assert pixels.shape[2] == 3 and np.mean(pixels.min(axis=2) < 250) > 0.05  # more than 5 % is drawn
    assert "material: rock" in _labels(fig)


def test_without_pyvista_3d_models_are_drawn_with_matplotlib(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(modelview, "pyvista_renders", lambda: False)
    fig = modelview.fig_model_setup(load_model(CUBE)[0], "cube")
    (ax,) = fig.axes
    faces = [c for c in ax.collections if isinstance(c, Poly3DCollection)]
    assert len(faces) == 1 and len(faces[0].get_facecolor()) == 12  # two boxes, six faces each, by material
    assert {"material: rock", "fixed block (see-through)"} <= set(_labels(fig))


def test_show_refuses_a_bad_model_with_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(SLOPE.read_text().replace("[run]", "[run]\nnope = 1", 1))
    res = CliRunner().invoke(main, ["show", str(bad), "-o", str(tmp_path / "x.png")])
    assert res.exit_code == 2 and "Traceback" not in res.output
