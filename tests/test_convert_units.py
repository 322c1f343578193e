"""``srdda convert``: DDA inputs in non-SI units converted to SI, and a geometry without its analysis file.

``tests/data/block_ft.*`` is a legacy pair written in feet, slugs and pounds-force: a free 2 ft x 1 ft
block, unit mass 5 slug/ft³, unit weight 161 lbf/ft³ (g = 32.2 ft/s²), E = 1e6 lbf/ft², an initial
stress of 100 lbf/ft², an initial velocity of 2 ft/s, a joint with cohesion 10 lbf/ft². The expected
SI values are computed from the exact definitions of the units: ft = 0.3048 m, lb = 0.45359237 kg,
lbf = lb x 9.80665 m/s² (so slug = lbf s²/ft).
"""
from __future__ import annotations

import dataclasses
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from srdda import run
from srdda.apps.cli import main
from srdda.io import load_model
from srdda.io.convert import read_dda
from srdda.io.ddainput import DEFAULT_ANALYSIS, DDAInputError
from srdda.units import UNIT_SYSTEMS, detect_unit_system

DATA = Path(__file__).parent / "data"
DOCS = Path(__file__).resolve().parents[1] / "docs"
FT, LBF = 0.3048, 0.45359237 * 9.80665
SLUG = LBF / FT
PSF = LBF / FT**2
EXACT = 1e-12  # the conversions are one or two multiplications: only rounding is left


def _read(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_dda(*args, **kwargs)


def _model(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return data.to_model(), data.run_settings()


def test_gravity_tells_the_unit_system():
    assert detect_unit_system(9.81).name == "SI"
    assert detect_unit_system(32.2).name == "ft-lbf-slug"
    assert detect_unit_system(386.1).name == "in-lbf"
    assert detect_unit_system(20.0) is None
    # the pound-force system is consistent: 1 slug accelerated at 1 ft/s² weighs 1 lbf
    assert UNIT_SYSTEMS["ft-lbf-slug"].force == pytest.approx(LBF, rel=EXACT)
    assert UNIT_SYSTEMS["ft-lbf-slug"].gravity == pytest.approx(9.80665 / FT, rel=EXACT)


def test_feet_and_pounds_are_detected_from_gravity_and_converted_to_si():
    data = _read(DATA / "block_ft.geo")
    model, settings = _model(data)
    (block,) = model.blocks
    corners = np.array(sorted(map(tuple, block.vertices)))  # the cut may start the polygon at any corner
    np.testing.assert_allclose(corners, np.array([[0, 0], [0, 1], [2, 0], [2, 1]]) * FT, rtol=EXACT)
    material = model.materials["material 1"]
    assert material.density == pytest.approx(5 * SLUG / FT**3, rel=EXACT)  # 2576.9 kg/m³
    assert material.young == pytest.approx(1e6 * PSF, rel=EXACT)
    assert model.gravity[1] == pytest.approx(-32.2 * FT, rel=EXACT)  # 161 / 5 ft/s², as the file implies
    assert block.stress[0] == pytest.approx(100 * PSF, rel=EXACT)
    assert block.velocity[0] == pytest.approx(2 * FT, rel=EXACT)
    assert model.joint_materials["joint 1"].cohesion == pytest.approx(10 * PSF, rel=EXACT)
    assert settings.penalty == pytest.approx(50 * 1e6 * PSF, rel=EXACT)
    assert settings.dt == 0.01  # seconds in both systems
    assert "ft-lbf-slug" in data.notes[0]


@pytest.mark.parametrize("method", ["dda0", "srdda"])
def test_converted_block_falls_as_a_free_body_in_metres(method):
    """1 s of free flight: x = 2 ft/s x t, y = -g t²/2 with g = 32.2 ft/s², i.e. (0.6096, -4.90728) m.
    The schemes integrate a constant acceleration exactly, so only rounding is left (1e-9)."""
    model, settings = _model(_read(DATA / "block_ft.geo"))
    result = run(model, dataclasses.replace(settings, method=method))
    assert result.completed
    t = result.array("time")[-1]
    assert t == pytest.approx(1.0, rel=1e-12)
    moved = result.array("measured_position")[-1, 0] - result.array("measured_position")[0, 0]
    np.testing.assert_allclose(moved, [2 * FT * t, -0.5 * 32.2 * FT * t * t], rtol=1e-9)


def test_convert_states_the_conversion_in_the_header(tmp_path):
    out = tmp_path / "block.toml"
    result = CliRunner().invoke(main, ["convert", str(DATA / "block_ft.geo"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    header = text[:text.index("\ntitle")]
    assert all(line.startswith("#") for line in header.strip().splitlines())
    assert "ft-lbf-slug" in header and "length x 0.3048 m" in header and "gravity 32.2 -> 9.81456 m/s2" in header
    model, _ = load_model(out)
    assert model.materials["material 1"].density == pytest.approx(5 * SLUG / FT**3, rel=1e-12)


def test_an_existing_output_is_kept_unless_overwrite(tmp_path):
    out = tmp_path / "mine.toml"
    out.write_text("# my edits\n")
    args = ["convert", str(DATA / "block_ft.geo"), "-o", str(out)]
    refused = CliRunner().invoke(main, args)
    assert refused.exit_code == 2 and "already exists" in refused.output and "--overwrite" in refused.output
    assert out.read_text() == "# my edits\n"
    replaced = CliRunner().invoke(main, [*args, "--overwrite"])
    assert replaced.exit_code == 0, replaced.output
    assert load_model(out)[0].materials["material 1"].density == pytest.approx(5 * SLUG / FT**3, rel=1e-12)


def test_units_option_overrides_the_detection(tmp_path):
    out = tmp_path / "as_si.toml"
    result = CliRunner().invoke(main, ["convert", str(DATA / "block_ft.geo"), "--units", "SI", "-o", str(out)])
    assert result.exit_code == 0, result.output
    model, _ = load_model(out)
    assert model.materials["material 1"].density == 5.0 and model.gravity[1] == pytest.approx(-32.2)
    assert "SI as given" in out.read_text().splitlines()[1]


def test_a_gravity_of_no_known_system_asks_for_units(tmp_path):
    geo = shutil.copy(DATA / "block_ft.geo", tmp_path / "odd.geo")
    (tmp_path / "odd.ana").write_text((DATA / "block_ft.ana").read_text().replace("5 161 ", "5 100 "))  # g = 20
    with pytest.raises(DDAInputError, match="gravity 20 .*--units"):
        read_dda(geo)
    result = CliRunner().invoke(main, ["convert", str(geo), "-o", str(tmp_path / "odd.toml")])
    assert result.exit_code == 2 and "--units" in result.output
    result = CliRunner().invoke(main, ["convert", str(geo), "--units", "ft-lbf-slug", "-o", str(tmp_path / "x.toml")])
    assert result.exit_code == 0, result.output


def test_ddaml_geometry_alone_converts_with_the_default_analysis(tmp_path):
    geo = shutil.copy(DATA / "tiny_ddaml.geo", tmp_path / "alone.geo")  # no alone.ana beside it
    out = tmp_path / "alone.toml"
    result = CliRunner().invoke(main, ["convert", str(geo), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "no analysis file" in result.output
    text = out.read_text()
    assert "# no analysis file: the default analysis" in text
    model, settings = load_model(out)
    d = DEFAULT_ANALYSIS
    material = model.materials["material 1"]
    assert (material.density, material.young, material.poisson, material.plane) == (
        d["density"], d["young"], d["poisson"], "stress")
    assert model.gravity == (0.0, -d["gravity"])
    assert set(model.joint_materials) == {"joint 1", "joint 2"}  # one per joint type of the geometry
    assert all(j.friction_angle == d["friction_angle"] and j.cohesion == 0 for j in model.joint_materials.values())
    assert (settings.method, settings.dt, settings.n_steps) == (d["method"], d["dt"], d["steps"])
    assert settings.penalty == d["penalty_factor"] * d["young"]
    assert len(model.blocks) == 2 and not model.point_loads  # the load point has no force without the .ana
    short = run(model, dataclasses.replace(settings, n_steps=20))
    assert short.completed and np.all(np.isfinite(short.array("centroid")))


def test_legacy_geometry_alone_converts_too(tmp_path):
    geo = shutil.copy(DATA / "tiny.geo", tmp_path / "alone.geo")
    data = _read(geo)
    model, settings = _model(data)
    assert len(model.blocks) == 3 and len(model.materials) == 2  # material lines name material 2
    assert settings.method == DEFAULT_ANALYSIS["method"]


def test_the_default_analysis_is_documented():
    """docs/cutting.md has a table `| key | value | ... |` of DEFAULT_ANALYSIS; each value as in the code."""
    text = (DOCS / "cutting.md").read_text()
    section = text[text.index("### Without the analysis file"):]
    rows = dict(re.findall(r"^\| `(\w+)` \| `([^`]+)` \|", section, flags=re.M))
    assert set(rows) == set(DEFAULT_ANALYSIS)
    for key, value in DEFAULT_ANALYSIS.items():
        documented = rows[key]
        assert (documented == value) if isinstance(value, str) else float(documented) == value, key


def test_the_unit_systems_are_documented():
    text = (DOCS / "cutting.md").read_text()
    section = text[text.index("### Units"):]
    for name in UNIT_SYSTEMS:
        assert f"`{name}`" in section, name
