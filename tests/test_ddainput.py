"""Readers of existing DDA inputs (legacy text, DDAML) and ``srdda convert``."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from srdda.cli import main
from srdda.io import load_model
from srdda.io.convert import read_dda
from srdda.io.ddainput import DDAInputError, domain_scale
from srdda.io.ddaml import read_ddaml
from srdda.io.legacy import read_legacy

DATA = Path(__file__).parent / "data"
SHARED = Path("/work/shared")


def test_legacy_sample_maps_geometry_and_parameters():
    data = read_legacy(DATA / "tiny.geo", DATA / "tiny.ana")
    cut = data.cut()
    assert cut.n_blocks == 3  # four loops, the one holding the hole point removed
    assert abs(cut.areas().sum() - 1.25) < 1e-14  # 2 x 1 domain minus the 0.75 m² upper-left block
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = data.to_model(cut)
        settings = data.run_settings()
    assert model.gravity == (0.0, -24525 / 2500)  # unit weight / unit mass of material 1
    upper_right = model.block_at((1.5, 0.9))
    block = model.blocks[upper_right]
    assert list(model.materials)[block.material] == "material 2"  # set by the material line
    assert block.stress == (1.0, 2.0, 3.0) and block.velocity == (0.5, 0.0, 0.0)
    assert model.materials["material 2"].young == 5e8
    assert model.joint_materials["joint 2"].cohesion == 1000.0
    # edges on the diagonal and on x = 1 carry joint 2, the boundary joint 1
    assert set(block.edge_joints) == {"joint 1", "joint 2"}
    assert len(model.fixed_points) == 3  # a point + a line crossing one block (two ends)
    assert len(model.measured_points) == 1
    assert settings.dt == 0.001 and settings.n_steps == 10 and settings.method == "dda0"
    assert settings.penalty == 50 * 1e9  # DDA for Windows' factor 50 times the largest E


def test_ddaml_sample_warns_and_maps_load_history():
    with pytest.warns(UserWarning) as record:
        data = read_ddaml(DATA / "tiny_ddaml.geo", DATA / "tiny_ddaml.ana")
        model = data.to_model()
        settings = data.run_settings()
    messages = " ".join(str(w.message) for w in record)
    for name in ("<Boltlist>", "<OCLimit>", "damping"):
        assert name in messages
    # g2 goes to RunSettings.max_displacement_ratio where the contact settings exist, else it is warned about
    if hasattr(settings, "max_displacement_ratio"):
        assert settings.max_displacement_ratio == 0.005
    else:
        assert "max_displacement_ratio=0.005" in messages
    assert model.materials["material 1"].plane == "strain"
    assert len(model.blocks) == 2
    _, _, load = model.point_loads[0]
    np.testing.assert_allclose(load(0.5), [50.0, -25.0])  # linear between the rows (0, 0, 0) and (1, 100, -50)
    assert settings.penalty == 20 * 1e9 and settings.record_every == 5
    fixed_blocks = {b for b, _, _ in model.fixed_points}
    assert len(model.fixed_points) == 2 and len(fixed_blocks) == 1  # the line crosses the base block only


def test_domain_scale_follows_shi():
    # wide box 10 x 2: half width 5 > 1.3 x half height 1 -> w0 = 5 / 1.3 * 1.02
    assert domain_scale([[0, 0, 10, 2]]) == pytest.approx(5 / 1.3 * 1.02)
    assert domain_scale([[0, 0, 2, 10]]) == pytest.approx(5 * 1.02)


def test_convert_cli_writes_a_loadable_model(tmp_path):
    out = tmp_path / "tiny.toml"
    result = CliRunner().invoke(main, ["convert", str(DATA / "tiny_ddaml.geo"), str(DATA / "tiny_ddaml.ana"),
                                       "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "2 blocks" in result.output
    model, settings = load_model(out)
    assert len(model.blocks) == 2 and settings.n_steps == 30


def test_bad_files_give_clear_errors(tmp_path):
    bad = tmp_path / "bad.geo"
    bad.write_text("0.01\n3 0\n0\n0\n0\n0\n0\n0\n0 0 1 0 1\n")
    with pytest.raises(DDAInputError, match="file ends while reading joint lines"):
        read_legacy(bad, DATA / "tiny.ana")
    xml = tmp_path / "bad_ddaml.geo"
    xml.write_text('<DDA><Geometry><Jointlist><Joint type="1">0 0 1</Joint></Jointlist></Geometry></DDA>')
    with pytest.raises(DDAInputError, match="needs 4 numbers"):
        read_dda(xml, DATA / "tiny_ddaml.ana")
    result = CliRunner().invoke(main, ["convert", str(bad), str(DATA / "tiny.ana"), "-o", str(tmp_path / "x.toml")])
    assert result.exit_code == 2 and "joint lines" in result.output


SHARED_FILES = sorted((SHARED / "dda-inputs").rglob("*.geo")) + sorted((SHARED / "benchmarks").rglob("*.geo"))


@pytest.mark.skipif(not SHARED.exists(), reason="extra check on the project's shared samples (not in a user's clone)")
@pytest.mark.parametrize("geo", SHARED_FILES, ids=lambda p: p.name)
def test_every_shared_dda_input_loads(geo):
    ana = geo.with_suffix(".ana")
    if not ana.exists():  # fixedlines/case*.geo come without an analysis file
        ana = SHARED / "dda-inputs" / "ddaml" / "pushblock.ana"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_dda(geo, ana)
        model = data.to_model()
        data.run_settings()
    assert len(model.blocks) >= 1
    model.arrays()


def test_domain_types_keep_only_blocks_inside_the_type_boundary():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_ddaml(DATA / "tiny_ddaml.geo", DATA / "tiny_ddaml.ana")
    assert data.cut().n_blocks == 2
    inside = data.cut(domain_types=[1])
    assert inside.n_blocks == 1
    assert abs(inside.areas()[0] - 4.0) < 1e-14  # the 4 x 1 base enclosed by the type-1 joints


EXAMPLES = Path(__file__).parents[1] / "examples" / "cutting"


@pytest.mark.parametrize("name,blocks", [("jointed_slope", 38), ("tunnel", 71), ("masonry_arch", 17)])
def test_cutting_example_model_files_load(name, blocks):
    model, _ = load_model(EXAMPLES / f"{name}.toml")
    assert len(model.blocks) == blocks
    arrays = model.arrays()
    assert arrays.block_fixed.any() and not arrays.block_fixed.all()
    assert (arrays.edge_joint > 0).any()  # the joint sets' materials reached the block edges


@pytest.mark.parametrize("method", ["dda0", "dda1", "srdda"])
def test_converted_free_block_moves_as_a_free_body(method):
    """Reader -> model -> run: mass (unit mass x area), gravity (unit weight / unit mass) and the
    load table all enter. A force (360, 180) N at the centroid of a 2 x 1 block of unit mass 18
    (m = 36 kg) under g = 176.58 / 18 = 9.81: the centroid moves by a t²/2 with a = (10, 5 - 9.81).
    The schemes integrate a constant acceleration exactly, so only rounding is left (1e-9)."""
    import dataclasses

    from srdda import run

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_ddaml(DATA / "free_block.geo", DATA / "free_block.ana")
        model = data.to_model()
        settings = dataclasses.replace(data.run_settings(), method=method)
    result = run(model, settings)
    assert result.completed
    t = result.array("time")[-1]
    moved = result.array("measured_position")[-1, 0] - result.array("measured_position")[0, 0]
    np.testing.assert_allclose(moved, 0.5 * np.array([10.0, 5.0 - 9.81]) * t * t, rtol=1e-9)
    assert t == pytest.approx(1.0, rel=1e-12)


def test_ddaml_prefix_without_namespace_declaration_is_read(tmp_path):
    geo = tmp_path / "noxmlns.geo"
    text = (DATA / "tiny_ddaml.geo").read_text().replace(' xmlns:Berkeley="http://www.tsoft.com/~bdoolin/dda"', "")
    geo.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_ddaml(geo, DATA / "tiny_ddaml.ana")
    assert data.edge_node_ratio == 0.01 and len(data.joints) == 7


def _run_all_methods(data):
    import dataclasses

    from srdda import run

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = data.to_model()
        settings = data.run_settings()
    for method in ("dda0", "dda1", "srdda"):
        result = run(model, dataclasses.replace(settings, method=method))
        assert result.completed, (method, result.status)
        assert np.all(np.isfinite(result.array("centroid")))


def test_converted_samples_run_under_the_three_methods():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _run_all_methods(read_legacy(DATA / "tiny.geo", DATA / "tiny.ana"))
        _run_all_methods(read_ddaml(DATA / "tiny_ddaml.geo", DATA / "tiny_ddaml.ana"))


@pytest.mark.skipif(not SHARED.exists(), reason="extra check on the project's shared samples (not in a user's clone)")
@pytest.mark.parametrize("geo", ["legacy/circleslope.geo", "ddaml/pushblock.geo"])
def test_shared_circleslope_and_pushblock_run_under_the_three_methods(geo):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _run_all_methods(read_dda(SHARED / "dda-inputs" / geo))
