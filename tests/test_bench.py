"""The standard benchmark models and ``srdda bench`` (issue 14, item 2).

No timing is asserted: the figures depend on the machine and its load.
"""
from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import shapely
from click.testing import CliRunner

from srdda.apps.bench.models import (BRICK, SLOPE_3D, SLOPES, Slope3DSpec, brick_wall, english_bond_outlines,
                                english_bond_wall, jointed_slope, jointed_slope_3d, slope_3d_cut, slope_input)
from srdda.apps.bench.runner import CASES, QUICK, REQUIRED_KEYS, BenchCase, beyond_free_fall, format_table, measure
from srdda import Material
from srdda.apps.cli import main
from srdda.contact.pipeline import ContactModel, ContactStep
from srdda.geometry.jointsets3d import plane_normal
from srdda.model import Model
from srdda.settings import RunSettings
from srdda.simulation import run
from srdda.step import Stepper, contact_parameters, model_half_height
from srdda.term import CUT_CAUSES

# Block counts of the three slopes: every closed loop of the joint lines (Shi's DC), as the DDAML
# converter cuts the benchmark files slope_{a,b,c}.geo (measured once, docs/performance.md).
SLOPE_BLOCKS = {"a": 74, "b": 273, "c": 1029}
# The rock mass (inside the type-1 outline): 60 × 5 m base + the trapezoid under the 45° face,
# (45 + 25) / 2 × 20 m.
ROCK_AREA = 60.0 * 5.0 + 0.5 * (45.0 + 25.0) * 20.0


@pytest.mark.parametrize("name", sorted(SLOPES))
def test_slope_blocks_and_rock_area(name: str) -> None:
    model, settings = jointed_slope(name)
    arrays = model.arrays()
    assert arrays.n_blocks == SLOPE_BLOCKS[name]
    inside = slope_input(name).cut([1])
    # the blocks inside the outline tile it exactly; 1e-9 relative: rounding of the cut's coordinates
    assert inside.areas().sum() == pytest.approx(ROCK_AREA, rel=1e-9)
    assert (settings.method, settings.dt, settings.n_steps) == ("dda0", 0.002, 200)
    assert settings.contact_penalty == pytest.approx(10 * 5e9)
    # gravity from unit weight / unit mass of the file's material
    assert arrays.gravity[1] == pytest.approx(-26487.0 / 2700.0)


def test_slope_sets_have_their_spacing() -> None:
    data = slope_input("b")
    traces = data.joints[data.joint_types == 2]
    d = traces[:, 2:] - traces[:, :2]
    dip = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 180.0
    for angle, spacing in ((25.0, SLOPES["b"].gentle), (100.0, SLOPES["b"].steep)):
        chosen = np.abs(dip - angle) < 1e-9
        theta = np.radians(angle)
        offsets = np.unique(np.round(traces[chosen, :2] @ np.array([-np.sin(theta), np.cos(theta)]), 9))
        np.testing.assert_allclose(np.diff(offsets), spacing, rtol=1e-9)  # rounding to 1e-9 m above


@pytest.mark.parametrize(("nx", "ny"), [(1, 1), (4, 3), (7, 6)])
def test_brick_wall_counts_area_and_bond(nx: int, ny: int) -> None:
    model, settings = brick_wall(nx, ny)
    arrays = model.arrays()
    assert arrays.n_blocks == 1 + nx * ny + ny // 2  # the base, nx per row, one more in odd rows
    base_area = (nx + 2 * BRICK.base_overhang) * BRICK.base_depth
    area = arrays.moments(arrays.vertex_position).area
    # exact: every coordinate is a multiple of 0.5 m, so the moment sums are exact in binary
    assert area.sum() == nx * ny * 0.5 + base_area
    assert area[0] == base_area and arrays.block_fixed.tolist() == [True] + [False] * (arrays.n_blocks - 1)
    assert np.count_nonzero(area == 0.25) == 2 * (ny // 2)  # half bricks at both ends of the odd rows
    polys = [shapely.Polygon(v) for v in np.split(arrays.vertex_position, arrays.block_ptr[1:-1])]
    tree = shapely.STRtree(polys)
    i, j = tree.query(polys, predicate="intersects")
    pairs = i < j
    overlap = shapely.area(shapely.intersection(np.take(polys, i[pairs]), np.take(polys, j[pairs])))
    assert overlap.max(initial=0.0) == 0.0  # neighbours share edges only
    assert settings.max_displacement_ratio * model_half_height(arrays.vertex_position) == pytest.approx(
        BRICK.step_displacement, rel=1e-12)
    assert (settings.dt, settings.contact_penalty, settings.method) == (1e-3, 5e10, "dda0")
    assert model.materials["brick"].young == 5e9 and model.materials["brick"].poisson == 0.2


def test_bad_model_parameters_are_named() -> None:
    with pytest.raises(ValueError, match="nx >= 1"):
        brick_wall(0, 3)
    with pytest.raises(ValueError, match="unknown slope 'z'"):
        jointed_slope("z")


def test_bench_quick_json_rows() -> None:
    out = CliRunner().invoke(main, ["bench", "--quick", "--json", "--steps", "2"])
    assert out.exit_code == 0, out.output
    rows = json.loads(out.output)["rows"]
    assert [r["model"] for r in rows] == ["slope_a", "slope_b"]
    for r in rows:
        assert set(REQUIRED_KEYS) <= set(r)
        assert r["blocks"] == SLOPE_BLOCKS[r["model"][-1]]
        assert (r["dim"], r["method"], r["dt"], r["steps"]) == (2, "dda0", 0.002, 2)
        # every attempt is either accepted or rejected
        assert r["attempts"] == r["steps"] + r["rejected_steps"]
        assert sum(r[f"cuts_{c}"] for c in CUT_CAUSES) == r["rejected_steps"]  # every cut has one cause
        assert r["solves_total"] >= r["steps"] * r["solves_per_step"]
        assert 0.0 < r["sim_time"] <= 2 * 0.002 + 1e-15  # Δt is at most the set one
        shares = [r[f"share_{p}"] for p in ("detection", "assembly", "solve", "open_close", "other")]
        assert min(shares) >= 0.0 and sum(shares) == pytest.approx(1.0, abs=1e-9)  # rounding of the sum
        assert r["peak_mb"] > 0
        assert (r["cg_iterations"], r["cg_iterations_per_solve"]) == (0, None)  # below 500 blocks: direct solves
        # the block Cholesky: a factor a solve at most (one is reused where the matrix did not change), an
        # ordering and analysis for each new block pattern, at most one a factorisation
        assert 0 < r["analyses"] <= r["factorizations"] <= r["solves_total"]
        # two steps from rest: some blocks fall freely (ratio 1); open-close's contacts pull a few of them up to
        # 0.5 % further (12 of slope_a's blocks beyond the 0.1 % margin), a blow-up would take them many times
        assert isinstance(r["beyond_free_fall"], int) and 0.99 <= r["free_fall_ratio"] < 1.01


def test_bench_counts_the_conjugate_gradients_iterations() -> None:
    # 589 blocks: above the 500 of ITERATIVE_LIMIT, so auto solves every system by the block-Jacobi CG
    case = BenchCase("wall_589", 2, lambda: brick_wall(24, 24), steps=2, quick_steps=1)
    row = measure(case, 2, "dda0", None, timeout=120.0)
    assert row["blocks"] == 589 and row["status"] == "completed", row["note"]
    # the CG iterates at the steps' first solves: the wall starts to load, far from its last increment
    assert row["cg_iterations"] > row["solves_total"]
    assert row["cg_iterations_per_solve"] * row["solves_total"] == pytest.approx(row["cg_iterations"], rel=1e-12)
    table = format_table([row])
    assert "CG it/solve" in table and f"{row['cg_iterations_per_solve']:.0f}" in table.splitlines()[1]


def test_bench_time_limit_gives_a_row_not_a_hang() -> None:
    out = CliRunner().invoke(main, ["bench", "--json", "--model", "slope_a", "--steps", "5", "--timeout", "0.001"])
    assert out.exit_code == 0, out.output
    (row,) = json.loads(out.output)["rows"]
    assert row["steps"] == 0 and row["sim_time"] == 0.0 and "wall-time limit" in row["note"]


def test_bench_unknown_model_is_one_message() -> None:
    out = CliRunner().invoke(main, ["bench", "--model", "slope_z"])
    assert out.exit_code == 2 and "unknown model(s) slope_z" in out.output


# -- 3D models -----------------------------------------------------------------------------------------

# Blocks of the 3D slope: 1,020 cut blocks (counted once, docs/performance.md) and the base slab.
SLOPE_3D_BLOCKS = 1021


def _initial_gaps(model: Model, settings: RunSettings) -> tuple[np.ndarray, float]:
    """Gaps (m) of every contact detected at t = 0 (the run's own detection) and the detection distance d0."""
    arrays = model.arrays()
    params = contact_parameters(arrays, settings, model_half_height(arrays.vertex_position))
    record = ContactModel(arrays, params).detector.detect(arrays.vertex_position)
    return (np.empty(0) if record is None else record.gap), params.distance


def test_slope_3d_blocks_volume_and_settings() -> None:
    model, settings = jointed_slope_3d()
    arrays = model.arrays()
    assert arrays.n_blocks == SLOPE_3D_BLOCKS
    assert arrays.block_fixed.tolist() == [True] + [False] * (SLOPE_3D_BLOCKS - 1)
    volume = arrays.moments(arrays.vertex_position).volume
    # the base slab 60 x 5 m and the rock above it, the 2D profile's trapezoid (45 + 25) / 2 x 20 m, over
    # the 12 m width; the cut blocks tile it: 1e-9 relative covers the rounding of the cut's coordinates
    assert volume[0] == pytest.approx(60.0 * 5.0 * SLOPE_3D.width, rel=1e-12)
    assert volume[1:].sum() == pytest.approx(0.5 * (45.0 + 25.0) * 20.0 * SLOPE_3D.width, rel=1e-9)
    assert volume.min() > 0.0
    np.testing.assert_allclose(arrays.block_mass, 2700.0 * volume, rtol=1e-12)  # ρ V, rounding only
    two_d = slope_input(SLOPE_3D.slope).run_parameters()
    assert (settings.method, settings.dt, settings.max_displacement_ratio, settings.contact_penalty) == (
        two_d["method"], two_d["dt"], two_d["max_displacement_ratio"], two_d["contact_penalty"])
    assert arrays.gravity[2] == pytest.approx(-26487.0 / 2700.0) and arrays.gravity[:2].tolist() == [0.0, 0.0]


def test_slope_3d_joint_faces_lie_on_the_three_sets() -> None:
    spec = Slope3DSpec(slope="a", width=4.0, cross_spacing=2.0)  # small: the same builder, fewer blocks
    cut = slope_3d_cut(spec)
    assert len(cut.skipped) == 0 and len(cut.rejected) == 0
    block_of_face = np.repeat(np.arange(cut.n_blocks), np.diff(cut.face_first))
    corners = cut.vertices[cut.block_ptr[block_of_face[np.repeat(np.arange(len(cut.face_joint)),
                                                                  np.diff(cut.face_ptr))]] + cut.face_vertex]
    following = np.roll(corners, -1, axis=0)
    following[cut.face_ptr[1:] - 1] = corners[cut.face_ptr[:-1]]
    newell = np.add.reduceat(np.cross(corners, following), cut.face_ptr[:-1], axis=0)
    normal = newell / np.linalg.norm(newell, axis=1)[:, None]
    sets = plane_normal(np.array([25.0, 80.0, 90.0]), np.array([270.0, 90.0, 0.0]))
    on_joint = cut.face_joint == 2
    # every joint face is parallel to one set's planes (1e-9: rounding of the cut points), each set is there
    parallel = np.abs(normal[on_joint] @ sets.T) > 1.0 - 1e-9
    assert np.all(parallel.sum(axis=1) == 1) and np.all(parallel.any(axis=0))
    # the cross set's planes are y = 2 m apart inside the 4 m width: one plane, y = 2 m
    cross = np.flatnonzero(on_joint)[parallel[:, 2]]
    np.testing.assert_allclose(corners[cut.face_ptr[cross], 1], 2.0, atol=1e-9)
    assert set(np.unique(cut.face_joint).tolist()) == {1, 2}  # domain faces carry the outline's type 1


@pytest.mark.parametrize(("nx", "courses"), [(1, 1), (2, 3), (3, 4)])
def test_english_bond_wall_counts_volume_and_bond(nx: int, courses: int) -> None:
    model, settings = english_bond_wall(nx, courses)
    arrays = model.arrays()
    headers = courses // 2
    assert arrays.n_blocks == 1 + 2 * nx * (courses - headers) + (2 * nx + 1) * headers
    volume = arrays.moments(arrays.vertex_position).volume
    # exact: every coordinate is a multiple of 0.25 m, so the moment sums are exact in binary
    assert volume[0] == (nx + 2.0) * 3.0 * 1.0  # base (nx + 2) x (1 + 2) x 1 m
    assert volume[1:].sum() == nx * 1.0 * 1.0 * 0.5 * courses  # the wall nx x 1 m x courses x 0.5 m, filled
    lo, hi = english_bond_outlines(nx, courses)
    overlap = np.prod(np.clip(np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None]), 0.0, None),
                      axis=2)
    np.fill_diagonal(overlap, 0.0)
    assert overlap.max() == 0.0  # bricks that fill the wall's volume without overlapping tile it
    assert lo[:, 2].min() == 0.0 and arrays.block_fixed.tolist() == [True] + [False] * (arrays.n_blocks - 1)
    # the bond: no vertical joint of a header course lies above or below one of a stretcher course
    course = np.round(lo[:, 2] / BRICK.height).astype(int)
    joints = [set(np.concatenate([lo[course % 2 == k, 0], hi[course % 2 == k, 0]]).tolist()) - {0.0, float(nx)}
              for k in (0, 1)]
    assert not joints[0] & joints[1]
    assert settings.max_displacement_ratio * model_half_height(arrays.vertex_position) == pytest.approx(
        BRICK.step_displacement, rel=1e-12)
    assert (settings.dt, settings.contact_penalty, settings.method) == (1e-3, 5e10, "dda0")


def test_standard_3d_wall_has_its_block_count() -> None:
    lo, _ = english_bond_outlines(50, 100)
    assert len(lo) + 1 == 10051  # 50 stretcher courses of 100 bricks, 50 header courses of 101, the base


@pytest.mark.parametrize("build", [lambda: english_bond_wall(3, 4),
                                   lambda: jointed_slope_3d(Slope3DSpec(slope="a", width=4.0))])
def test_3d_models_start_without_overlap(build: Callable[[], tuple[Model, RunSettings]]) -> None:
    model, settings = build()
    gap, distance = _initial_gaps(model, settings)
    assert len(gap) > 0
    # touching blocks: gaps 0 up to the rounding of the coordinates (1e-9 m), none beyond the search distance
    assert gap.min() >= -1e-9 and gap.max() <= distance


def test_bad_3d_model_parameters_are_named() -> None:
    with pytest.raises(ValueError, match="courses >= 1"):
        english_bond_wall(2, 0)
    with pytest.raises(ValueError, match="unknown slope 'z'"):
        jointed_slope_3d(Slope3DSpec(slope="z"))
    with pytest.raises(ValueError, match="width > 0"):
        jointed_slope_3d(Slope3DSpec(width=0.0))


def test_3d_models_are_listed_and_quick_stays_2d() -> None:
    assert {"slope3d_1k": 3, "wall3d_10k": 3}.items() <= {n: c.dim for n, c in CASES.items()}.items()
    assert all(CASES[name].dim == 2 for name in QUICK)
    help_text = CliRunner().invoke(main, ["bench", "--help"]).output
    doc = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text(encoding="utf-8")
    for name in CASES:
        assert name in " ".join(help_text.split()) and f"`{name}`" in doc


def test_tiny_3d_wall_runs_through_the_runner() -> None:
    engine = (Stepper.step, ContactModel.prepare, ContactStep.converged)
    case = BenchCase("wall3d_tiny", 3, lambda: english_bond_wall(3, 2), steps=2, quick_steps=1)
    row = measure(case, 2, "dda0", None, timeout=120.0)
    assert set(REQUIRED_KEYS) <= set(row) and row["status"] == "completed", row["note"]
    assert (row["dim"], row["blocks"], row["steps"], row["dt"]) == (3, 1 + 6 + 7, 2, 1e-3)
    assert row["attempts"] == row["steps"] + row["rejected_steps"]
    assert sum(row[f"cuts_{c}"] for c in CUT_CAUSES) == row["rejected_steps"]  # every cut has one cause
    assert row["contacts_per_attempt"] > 0  # the 3D detection was counted
    # the 3D contact classes are timed: detection and open-close took some time
    assert row["share_detection"] > 0.0 and row["share_open_close"] > 0.0
    shares = [row[f"share_{p}"] for p in ("detection", "assembly", "solve", "open_close", "other")]
    assert min(shares) >= 0.0 and sum(shares) == pytest.approx(1.0, abs=1e-9)  # rounding of the sum
    # the engine is as it was: the probe restored what it wrapped
    assert (Stepper.step, ContactModel.prepare, ContactStep.converged) == engine


def test_beyond_free_fall_counts_the_blocks_pushed_further_than_gravity_could() -> None:
    # three free blocks without contacts, 0.1 s: one falls from rest (its bound, to rounding), one is
    # thrown sideways at 1 m/s (its path is shorter than |v₀|·t + ½g·t²), one is pushed by a 10 kN load as well
    m = Model(gravity=(0.0, -9.81))
    m.add_material("rock", Material(2600.0, 1e10, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    m.add_block([[3, 0], [4, 0], [4, 1], [3, 1]], "rock", velocity=(1.0, 0.0))
    m.add_block([[6, 0], [7, 0], [7, 1], [6, 1]], "rock")
    m.add_point_load((6.5, 0.5), (1e4, 0.0))
    arrays = m.arrays()
    result = run(arrays, RunSettings(dt=1e-3, n_steps=100, contacts=False))
    beyond, ratio = beyond_free_fall(arrays, result)
    assert beyond == 1
    t, g = 0.1, 9.81
    pushed = np.hypot(0.5 * 1e4 / 2600.0 * t**2, 0.5 * g * t**2)  # the load's ½(F/m)t² beside the fall
    assert ratio == pytest.approx(pushed / (0.5 * g * t**2), rel=1e-9)
