"""Readers of existing DDA inputs (legacy text, DDAML) and ``srdda convert``."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from srdda.apps.cli import main
from srdda.io import load_model
from srdda.io.convert import read_dda
from srdda.io.ddainput import DDAInputError, domain_scale
from srdda.io.ddaml import read_ddaml
from srdda.io.legacy import read_legacy

DATA = Path(__file__).parent / "data"


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


def _ddaml_geometry(joints, fixed_lines=(), fixed_points=(), load_points=(), hidden_points=()) -> str:
    """A DDAML geometry as DDA for Windows writes it (joints "x1 y1 x2 y2" with a type, fixed lines or points,
    load points, and a measured-point section commented out, as in its samples)."""
    rows = "\n".join(f'      <Joint type="{t}"> {x1} {y1} {x2} {y2} </Joint>' for x1, y1, x2, y2, t in joints)
    fixed = "".join(f"      <Line> {a} {b} {c} {d} </Line>\n" for a, b, c, d in fixed_lines)
    fixed += "".join(f"      <Point> {x} {y} </Point>\n" for x, y in fixed_points)
    loads = "".join(f"   <Point> {x} {y} </Point>\n" for x, y in load_points)
    hidden = "".join(f"    <Point> {x} {y} </Point>\n" for x, y in hidden_points)
    return ('<?xml version="1.0" standalone="no"?>\n<!DOCTYPE DDA SYSTEM "geometry.dtd">\n'
            '<Berkeley:DDA xmlns:Berkeley="http://www.tsoft.com/~bdoolin/dda">\n<Berkeley:Geometry>\n'
            f'   <Berkeley:Edgenodedist distance="0.01"/>\n   <Jointlist>\n{rows}\n   </Jointlist>\n'
            f"   <Fixedpointlist>\n{fixed}   </Fixedpointlist>\n"
            + (f"   <Loadpointlist>\n{loads}   </Loadpointlist>\n" if load_points else "")
            + f"<!--\n   <Measuredpointlist>\n{hidden}   </Measuredpointlist>\n-->\n"
            "</Berkeley:Geometry>\n</Berkeley:DDA>\n")


def _box(x0, y0, x1, y1, t=1, over=0.0):
    """A rectangle's four joints, each running ``over`` past its corners (as hand-drawn inputs do)."""
    return [(x0, y0 - over, x0, y1 + over, t), (x0 - over, y1, x1 + over, y1, t),
            (x1, y1 + over, x1, y0 - over, t), (x1 + over, y0, x0 - over, y0, t)]


def _slope_joints():
    """A 45° slope 0-60 x 0-20 m on a 5 m base, cut by two joint sets whose traces run past the boundary."""
    outline = [(0, -5, 60, -5, 1), (60, -5, 60, 20, 1), (60, 20, 35, 20, 1), (35, 20, 15, 0, 1), (15, 0, 0, 0, 1),
               (0, 0, 0, -5, 1), (15, 0, 60, 0, 1)]
    dip25 = [(c, 0, c + 45, 45 * np.tan(np.radians(25)), 2) for c in (-10.0, 2.0, 14.0, 26.0, 38.0, 50.0)]
    steep = [(c, -0.5, c - 4.0, 21.0, 2) for c in (24.0, 33.0, 42.0, 51.0)]
    return outline + dip25 + steep


SLOPE_AREA = 60 * 5 + 45 * 20 - 0.5 * 20 * 20  # base + slope profile (trapezoid 15-60 x 0-20 minus the cut)


def _legacy_circular_slope(path: Path) -> None:
    """Legacy text files (Shi's format) of a 2 x 1 m slope with a circular slip surface and 3 slices."""
    arc = [(1.0 + 0.8 * np.cos(a), 1.0 + 0.8 * np.sin(a)) for a in np.linspace(np.pi, 2 * np.pi, 19)]
    joints = [(*arc[i], *arc[i + 1], 1) for i in range(18)]  # the slip surface, (0.2, 1) down and up to (1.8, 1)
    joints += [(0, 0, 2, 0, 2), (2, 0, 2, 1, 2), (2, 1, 0, 1, 2), (0, 1, 0, 0, 2)]  # the domain
    joints += [(x, 1.05, x, 0.15, 3) for x in (0.6, 1.0, 1.4)]  # slices, running past the top edge and the arc
    counts = [len(joints), 0, 0, 0, 2, 0, 1, 0]  # joints, boundary, material, bolts, fixed, loads, measured, holes
    lines = ["0.01", f"{counts[0]} {counts[1]}", *map(str, counts[2:])]
    lines += [" ".join(f"{v:.6f}" for v in j[:4]) + f" {j[4]}" for j in joints]
    lines += ["1.9 0.1 1.9 0.1", "0.1 0.1 0.1 0.1", "0.5 0.9"]  # two fixed points (degenerate lines), a measured one
    path.with_suffix(".geo").write_text("\n".join(lines) + "\n")
    # static, 20 steps, one block material, three joint materials, g2 = 0.006, Δt = 0.01 s
    path.with_suffix(".ana").write_text("0\n20\n1\n3\n0.006\n0.01\n2.0 19.6 1000000.0 0.3\n0 0 0\n0 0 0\n0 0 0\n"
                                        "30 0 0\n30 0 0\n30 0 0\n")


GENERATED_INPUTS = {
    **{f"fixed-line-{blocks}-{name}": (_box(0, 0, blocks, 1) + ([(1, 0, 1, 1, 1)] if blocks == 2 else []),
                                       [line], blocks, blocks * 1.0)
       for blocks in (1, 2)
       for name, line in (("crossing", (-0.5, 0.5, blocks + 0.5, 0.5)), ("inside", (0.1, 0.5, blocks - 0.1, 0.5)),
                          ("just-past", (-0.1, 0.5, blocks + 0.1, 0.5)))},
    "pushed-block": (_box(10, 10, 50, 20, over=0.02) + [(15, 19.99, 15, 25.01, 1), (14.99, 25, 20.01, 25, 1),
                                                        (20, 25.01, 20, 19.99, 1)], [], 2, 400.0 + 25.0),
    "jointed-slope": (_slope_joints(), [], None, SLOPE_AREA),
}


def _write_generated(tmp_path: Path, name: str) -> tuple[Path, Path]:
    joints, fixed_lines, _, _ = GENERATED_INPUTS[name]
    geo = tmp_path / f"{name}.geo"
    fixed_points = [(12, 12), (12, 18), (48, 18), (48, 12)] if name == "pushed-block" else []
    load = {"pushed-block": (17.5, 22.5), "jointed-slope": (55.0, -2.5)}.get(name, (0.5, 0.8))
    geo.write_text(_ddaml_geometry(joints, fixed_lines, fixed_points, [load], [load]))
    return geo, DATA / "tiny_ddaml.ana"  # a dynamic analysis with one time-varying point load


@pytest.mark.parametrize("name", sorted(GENERATED_INPUTS))
def test_generated_ddaml_inputs_load_with_every_block(tmp_path, name):
    # DDAML inputs with the features of DDA for Windows' samples: joints running past their corners, fixed
    # lines crossing, inside or just past the blocks, fixed points, a commented-out section, joint sets
    # running past the boundary. Cutting must keep the domain: the block areas sum to its area (exact
    # polygons: 1e-9 relative for the round-off of the intersections).
    geo, ana = _write_generated(tmp_path, name)
    _, _, n_blocks, area = GENERATED_INPUTS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_dda(geo, ana)
        cut = data.cut()
        model = data.to_model(cut)
        data.run_settings()
    inside = data.cut(domain_types=[1])  # the blocks inside the type-1 outline (the slope's sets close loops
    if n_blocks is not None:              # in the air above its face too)
        assert cut.n_blocks == inside.n_blocks == n_blocks
    else:
        assert inside.n_blocks > 20  # the two sets cut the slope into many blocks
    assert abs(inside.areas().sum() - area) <= 1e-9 * area
    assert len(model.blocks) == cut.n_blocks
    model.arrays()


def test_generated_legacy_circular_slope_loads(tmp_path):
    _legacy_circular_slope(tmp_path / "circle")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_dda(tmp_path / "circle.geo")
        cut = data.cut()
    # the arc and the three slices (their ends past the top edge and the arc are trimmed as dangling) cut
    # the 2 x 1 m domain into 5 blocks: 4 slices of the sliding mass and the rest
    assert cut.n_blocks == 5
    assert abs(cut.areas().sum() - 2.0) <= 1e-9 * 2.0


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


def test_generated_pushed_block_and_circular_slope_run_under_the_three_methods(tmp_path):
    geo, ana = _write_generated(tmp_path, "pushed-block")
    _legacy_circular_slope(tmp_path / "circle")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _run_all_methods(read_dda(geo, ana))
        _run_all_methods(read_dda(tmp_path / "circle.geo"))
