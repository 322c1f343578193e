"""The standard benchmark models and ``srdda bench`` (issue 14, item 2).

No timing is asserted: the figures depend on the machine and its load.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from click.testing import CliRunner

from srdda.bench.models import BRICK, SLOPES, brick_wall, jointed_slope, slope_input
from srdda.bench.runner import REQUIRED_KEYS
from srdda.cli import main
from srdda.step import model_half_height

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
    area = arrays.moments(arrays.vertices).area
    # exact: every coordinate is a multiple of 0.5 m, so the moment sums are exact in binary
    assert area.sum() == nx * ny * 0.5 + base_area
    assert area[0] == base_area and arrays.block_fixed.tolist() == [True] + [False] * (arrays.n_blocks - 1)
    assert np.count_nonzero(area == 0.25) == 2 * (ny // 2)  # half bricks at both ends of the odd rows
    polys = [shapely.Polygon(v) for v in np.split(arrays.vertices, arrays.block_ptr[1:-1])]
    tree = shapely.STRtree(polys)
    i, j = tree.query(polys, predicate="intersects")
    pairs = i < j
    overlap = shapely.area(shapely.intersection(np.take(polys, i[pairs]), np.take(polys, j[pairs])))
    assert overlap.max(initial=0.0) == 0.0  # neighbours share edges only
    assert settings.max_displacement_ratio * model_half_height(arrays.vertices) == pytest.approx(
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
        assert r["solves_total"] >= r["steps"] * r["solves_per_step"]
        assert 0.0 < r["sim_time"] <= 2 * 0.002 + 1e-15  # Δt is at most the set one
        shares = [r[f"share_{p}"] for p in ("detection", "assembly", "solve", "open_close", "other")]
        assert min(shares) >= 0.0 and sum(shares) == pytest.approx(1.0, abs=1e-9)  # rounding of the sum
        assert r["peak_mb"] > 0


def test_bench_time_limit_gives_a_row_not_a_hang() -> None:
    out = CliRunner().invoke(main, ["bench", "--json", "--model", "slope_a", "--steps", "5", "--timeout", "0.001"])
    assert out.exit_code == 0, out.output
    (row,) = json.loads(out.output)["rows"]
    assert row["steps"] == 0 and row["sim_time"] == 0.0 and "wall-time limit" in row["note"]


def test_bench_unknown_model_is_one_message() -> None:
    out = CliRunner().invoke(main, ["bench", "--model", "slope_z"])
    assert out.exit_code == 2 and "unknown model(s) slope_z" in out.output
