"""Water in the joints (docs/water.md): the pressure, its resultants, the model file, the ledger, and the
closed forms of plane failure with water (srdda verify's water cases)."""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
import shapely

import srdda
from srdda.apps.verify.cases.plane_failure import (PLANE_DIP, plane_failure_acceleration, plane_failure_factor, wet_plane_forces,
                                       wet_plane_model)
from srdda.constraints.water import UNIT_WEIGHT, submerged_integrals, water_table
from srdda.io import ModelFileError, model_from_dict, model_to_dict
from srdda.model import ModelError
from srdda.settings import RunSettings
from srdda.simulation import EnergyWarning
from srdda.apps.verify import run_case


# -- the pressure and its integrals ---------------------------------------------------------------------
def test_head_is_the_height_of_the_surface_above_the_point():
    flat = water_table((0.0, -9.81), level=2.0)
    assert flat.head(np.array([[5.0, -1.0], [0.0, 3.0]])).tolist() == [3.0, -1.0]
    assert flat.pressure(np.array([[5.0, -1.0], [0.0, 3.0]])).tolist() == [3.0 * UNIT_WEIGHT, 0.0]
    # a surface rising 1 in 2 through (0, 1): above x = 4 it stands at 3
    sloped = water_table((0.0, -9.81), point=(0.0, 1.0), normal=(-1.0, 2.0))
    assert sloped.head(np.array([[4.0, 0.0]]))[0] == pytest.approx(3.0, rel=1e-15)
    assert sloped.raised(-0.5).head(np.array([[4.0, 0.0]]))[0] == pytest.approx(2.5, rel=1e-15)
    assert flat.at_level(-0.5).head(np.array([[5.0, -1.0]]))[0] == pytest.approx(0.5, rel=1e-15)
    assert flat.at_level(-0.5).level() == pytest.approx(-0.5, rel=1e-15)
    # 3D, gravity along -z: the level is a height in z
    assert water_table((0.0, 0.0, -10.0), level=1.0).head(np.array([[7.0, -3.0, 0.25]]))[0] == 0.75
    # a 3D plane z = 1 + y/2: above (5, 4, 0) it stands at 3
    tilted = water_table((0.0, 0.0, -10.0), point=(0.0, 0.0, 1.0), normal=(0.0, -1.0, 2.0))
    assert tilted.head(np.array([[5.0, 4.0, 0.0]]))[0] == pytest.approx(3.0, rel=1e-15)


def test_submerged_segments_integrate_exactly():
    # a segment from height 0 to 2 under a level at 1.5: the wet part is 3/4 of it, h from 1.5 to 0
    points = np.array([[[0.0, 0.0], [0.0, 2.0]]])
    integral, first = submerged_integrals(points, 1.5 - points[..., 1])
    assert integral[0] == pytest.approx(0.75 * 0.5 * 1.5, rel=1e-15)  # unit measure: ∫ over s in [0, 0.75]
    assert first[0, 1] / integral[0] == pytest.approx(0.5, rel=1e-15)  # a third of the wet 1.5 m


def _area(tri: np.ndarray) -> float:
    (ax, ay), (bx, by) = tri[1] - tri[0], tri[2] - tri[0]
    return abs(0.5 * (ax * by - ay * bx))


def _clipped_reference(triangle: np.ndarray, head: np.ndarray) -> tuple[float, np.ndarray]:
    """∫max(h, 0) and ∫max(h, 0)·x over a 2D triangle of unit measure, by shapely's clipping to h >= 0 and a
    fan of the wet polygon, on which h is linear and non-negative (an independent computation)."""
    coeff = np.linalg.solve(np.column_stack([triangle, np.ones(3)]), head)  # h = c0 x + c1 y + c2
    big = 1e3
    # the half-plane h >= 0 as a large polygon
    normal = coeff[:2] / np.linalg.norm(coeff[:2])
    origin = -coeff[2] * coeff[:2] / np.dot(coeff[:2], coeff[:2])
    along = np.array([-normal[1], normal[0]])
    half = shapely.Polygon([origin - big * along, origin + big * along, origin + big * along + big * normal,
                            origin - big * along + big * normal])
    wet = shapely.Polygon(triangle).intersection(half)
    area = _area(triangle)
    if wet.is_empty:
        return 0.0, np.zeros(2)
    ring = np.asarray(wet.exterior.coords)[:-1]
    total, first = 0.0, np.zeros(2)
    for i in range(1, len(ring) - 1):
        tri = ring[[0, i, i + 1]]
        t_area = _area(tri)
        h = tri @ coeff[:2] + coeff[2]
        total += t_area * h.mean()
        first += t_area / 12 * (h @ tri + h.sum() * tri.sum(axis=0))
    return total / area, first / area


def test_submerged_triangles_integrate_exactly():
    rng = np.random.default_rng(7)
    triangles = rng.uniform(-1.0, 1.0, (200, 3, 2))
    heads = rng.uniform(-1.0, 1.0, (200, 3))
    integral, first = submerged_integrals(triangles, heads)
    for k in range(len(triangles)):
        ref, ref_first = _clipped_reference(triangles[k], heads[k])
        # shapely's clipping rounds the cut points (1e-16 of the box of 1e3): 1e-11 absolute on values ~0.1
        assert integral[k] == pytest.approx(ref, abs=1e-11)
        assert first[k] == pytest.approx(ref_first, abs=1e-11)


# -- the model file and the API --------------------------------------------------------------------------
def _plane_dict() -> dict:
    model = wet_plane_model(40.0, 0.6, 1.0)
    return model_to_dict(model, RunSettings(dt=1e-3, n_steps=10))


def test_the_water_section_round_trips():
    data = _plane_dict()
    model, _ = model_from_dict(data)
    original = wet_plane_model(40.0, 0.6, 1.0)
    assert model.water == original.water
    data["water"] = {"level": 0.5, "unit_weight": 10000.0,
                     "cracks": [{"point": [1.7320508075688772, 1.0], "normal": [1, 0], "depth": "0.5 m"}]}
    model, _ = model_from_dict(data)
    assert model.water is not None and model.water.level() == pytest.approx(0.5, rel=1e-15)
    assert model.water.unit_weight == 10000.0 and model.water.cracks[0].depth == 0.5


@pytest.mark.parametrize("water, field, problem", [
    ({"unit_weight": 9810.0}, "water.level", "exactly one"),
    ({"level": 1.0, "point": [0, 0], "normal": [0, 1]}, "water.level", "exactly one"),
    ({"point": [0, 0]}, "water.normal", "upward normal"),
    ({"point": [0, 0], "normal": [0, -1]}, "water.normal", "must point up"),
    ({"point": [0, 0, 0], "normal": [0, 1, 0]}, "water.point", "needs 2 components"),
    ({"level": 1.0, "unit_weight": -1.0}, "water.unit_weight", "greater than 0"),
    ({"level": 1.0, "cracks": [{"point": [9, 9], "normal": [1, 0], "depth": 1.0}]}, "water.cracks[0]",
     "no face of a moving block"),
    ({"level": 1.0, "cracks": [{"point": [9, 9], "normal": [1, 0], "depth": -1.0}]}, "water.cracks[0].depth",
     "greater than or equal to 0"),
    ({"level": 1.0, "height": 2.0}, "water.height", "unknown field"),
])
def test_bad_water_names_the_field(water, field, problem):
    data = _plane_dict()
    data["water"] = water
    with pytest.raises((ModelFileError, ModelError)) as err:  # the crack's faces are found when compiled
        model_from_dict(data)[0].arrays()
    assert field in str(err.value) and problem in str(err.value)


def test_water_needs_gravity():
    model = srdda.Model()
    with pytest.raises(ModelError, match="water.gravity: water pressure needs gravity"):
        model.set_water(level=1.0)


def test_extruded_model_keeps_its_water():
    flat = wet_plane_model(40.0, 0.6, 1.0)
    solid = flat.extruded(1.0)
    assert solid.water is not None and flat.water is not None
    assert solid.water.up == (0.0, 1.0, 0.0) and solid.water.point == (*flat.water.point, 0.0)
    assert solid.arrays().water == solid.water


# -- closed forms -----------------------------------------------------------------------------------------
def test_plane_failure_forms_agree():
    """m·a = (W sin ψ + V cos ψ)(1 − FS): the acceleration vanishes where FS = 1, whatever the water."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        w, u, v, c, area = rng.uniform(1e3, 1e5), rng.uniform(0, 1e4), rng.uniform(0, 1e4), rng.uniform(0, 1e4), 2.0
        dip, phi, mass = rng.uniform(10, 60), rng.uniform(5, 50), rng.uniform(1, 1e4)
        fs = plane_failure_factor(w, dip, phi, u, v, c, area)
        driving = w * np.sin(np.radians(dip)) + v * np.cos(np.radians(dip))
        a = plane_failure_acceleration(mass, w, dip, phi, u, v, c, area)
        assert mass * a == pytest.approx(driving * (1.0 - fs), rel=1e-12, abs=1e-9 * driving)


# -- runs -------------------------------------------------------------------------------------------------
def test_the_water_cases_pass():
    rows = [*run_case("water-uplift-2d", methods=("srdda",)), *run_case("water-uplift-3d", methods=("srdda",)),
            *run_case("water-plane-2d", methods=("srdda",)), *run_case("water-plane-3d", methods=("srdda",))]
    failed = [r for r in rows if r["passed"] is False]
    assert not failed, failed
    assert len(rows) == 14  # 2 + 2 uplift rows, 5 + 5 plane rows


@pytest.mark.parametrize("dim", [2, 3])
def test_the_ledger_books_the_water_and_closes(dim):
    """The sliding wet block (3D: extruded 1 m, rigid, as water-plane-3d): the crack's force V does work V cos ψ
    per metre of travel down the plane (the uplift none: the sliding plane's gap stays), and the balance closes
    with it, no energy warning."""
    model = wet_plane_model(40.0, 0.6, 1.0, young=1e9 if dim == 2 else 1e14)
    model = model if dim == 2 else model.extruded(1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", EnergyWarning)
        res = srdda.run(model, RunSettings(dt=1e-3, n_steps=500, penalty=1e10 if dim == 2 else 5e9))
    e = res.energies()
    c = res.array("centroid")[:, 1]
    travel = float(np.linalg.norm(c[-1] - c[0]))
    _, _, _, v = wet_plane_forces(0.6, 1.0)
    # the block's rocking at the release moves the crack's centre of pressure by ~1e-6 m besides the travel
    assert e["work_water"][-1] == pytest.approx(v * np.cos(np.radians(PLANE_DIP)) * travel, rel=1e-4)
    # Shi's step loses a little to the elastic 2D block's vibration (the dry block loses as much: 0.14 J); the
    # rigid 3D one 1.1e-6 J (measured over 1 s)
    loss = 0.2 if dim == 2 else 1e-4
    assert abs(e["balance"][-1] - e["balance"][0]) < loss


def test_a_lowered_table_changes_the_run():
    """The stages' way to change the water between runs: dataclasses.replace on the arrays' table."""
    arrays = wet_plane_model(40.0, 0.6, 1.0).arrays()
    assert arrays.water is not None
    settings = RunSettings(dt=1e-3, n_steps=300, penalty=1e10)
    dry = replace(arrays, water=replace(arrays.water.raised(-10.0), cracks=()))
    c = srdda.run(dry, settings).array("centroid")[:, 1]
    assert float(np.linalg.norm(c[-1] - c[0])) < 1e-4  # FS 1.45 dry: at rest (verify's bound)
    c = srdda.run(arrays, settings).array("centroid")[:, 1]
    assert float(np.linalg.norm(c[-1] - c[0])) > 0.05  # FS 0.75 wet: 0.5 a t² = 0.066 m


def test_contacts_on_a_crack_take_the_cracks_water_not_the_tables():
    """A closed crack (the block against a fixed block behind it): its contacts get no pressure of the phreatic
    surface, the crack's faces the crack's water; the sliding plane's contacts the surface's."""
    from srdda.constraints.water import crack_facets
    from srdda.contact.water import contact_water
    from srdda.contact.pipeline import ContactModel
    from srdda.geometry.facets import boundary_simplices
    from srdda.step import contact_parameters, model_half_height

    model = wet_plane_model(40.0)
    bottom, top = model.blocks[1].vertices[1], model.blocks[1].vertices[2]
    rise = np.tan(np.radians(PLANE_DIP))
    model.add_block([bottom.tolist(), (bottom + [1.0, rise]).tolist(), [bottom[0] + 1.0, top[1]], top.tolist()],
                    "rock", fixed=True, name="behind")
    model.set_water(level=5.0, cracks=[(bottom, (1.0, 0.0), 0.5)])
    arrays = model.arrays()
    settings = RunSettings(dt=1e-3, n_steps=1, penalty=1e10)
    contacts = ContactModel(arrays, contact_parameters(arrays, settings, model_half_height(arrays.vertex_position)))
    step = contacts.prepare(arrays.vertex_position, None, True)
    assert step is not None and arrays.water is not None
    force = contact_water(arrays.water, step.record, contacts.params.distance, arrays.vertex_position,
                          boundary_simplices(arrays))
    on_crack = np.abs(step.record.normal[:, 0]) > 0.999
    assert on_crack.any() and (~on_crack).any()
    assert np.all(force[on_crack] == 0.0)
    assert np.all(force[~on_crack] > 0.0)
    _, blocks = crack_facets(arrays, arrays.water.cracks[0])
    assert blocks.tolist() == [1]  # the moving block's face only: the fixed one's cannot move


def test_the_newton_contact_solve_carries_the_effective_force():
    """contact_solver = "newton" adds the same water forces: the joint carries W − p·A (water-uplift-2d)."""
    from srdda.apps.verify.water import UPLIFT_EFFECTIVE, UPLIFT_LEVEL, _uplift_model

    model = _uplift_model(2)
    res = srdda.run(model, RunSettings(dt=1e-3, n_steps=200, penalty=1e10, contact_solver="newton"))
    assert res.final_state is not None and res.final_state.contacts is not None
    weight = float(model.arrays().block_mass[1]) * 10.0
    expected = weight - UNIT_WEIGHT * UPLIFT_LEVEL * 2.0
    assert float(np.sum(res.final_state.contacts.normal_force)) == pytest.approx(expected, rel=UPLIFT_EFFECTIVE)


@pytest.mark.parametrize("level", [10.0, 3.0, 1.0])
def test_a_wedge_gets_the_water_on_each_plane(level):
    """The tetrahedral wedge (srdda.apps.verify.cases.slope3d, 6 m high) under a level above it, through it, near its toe:
    the water forces of each plane's contacts add up to γ_w ∫max(h, 0) dA over the wedge's face on it (the
    wetted integral, checked against shapely above), though a slab's corner also touches the wedge's face
    (its bond is left out: one side per joint)."""
    from srdda.apps.verify.cases.slope3d import wedge_model
    from srdda.contact.water import contact_water
    from srdda.contact.pipeline import ContactModel
    from srdda.geometry.facets import area_vectors, boundary_simplices
    from srdda.step import contact_parameters, model_half_height

    model = wedge_model(30.0)
    model.set_water(level=level)
    arrays = model.arrays()
    settings = RunSettings(dt=1e-3, n_steps=1, penalty=1e11)
    contacts = ContactModel(arrays, contact_parameters(arrays, settings, model_half_height(arrays.vertex_position)))
    step = contacts.prepare(arrays.vertex_position, None, True)
    assert step is not None and arrays.water is not None
    record = step.record
    force = contact_water(arrays.water, record, contacts.params.distance, arrays.vertex_position,
                          boundary_simplices(arrays))
    mesh = arrays.mesh
    x = arrays.vertex_position[mesh.tri[mesh.tri_block == 0]]
    areas = area_vectors(x)
    integral, _ = submerged_integrals(x, level - x[..., 2])
    for plane in (1, 2):
        on = (record.block_a == plane) | (record.block_b == plane)
        normal = record.normal[on][0]
        faces = np.abs(areas @ normal) > 0.999 * np.linalg.norm(areas, axis=1)
        exact = UNIT_WEIGHT * float(np.linalg.norm((integral[faces, None] * areas[faces]).sum(axis=0)))
        assert exact > 0.0
        assert float(np.sum(force[on])) == pytest.approx(exact, rel=1e-12)  # sums of the same terms: round-off


@pytest.mark.parametrize("levels", [(-5.0, 2.0), (-5.0, 2.0, -5.0)])
def test_a_stage_raises_and_lowers_the_water(levels):
    # the uplift case of srdda verify, dry at first (the surface 5 m under the joint), then each stage moves the
    # surface and settles (equilibrium stages): the joint carries W − p·A under water, W again once drained.
    # The ratio 1e-5 leaves each block's unbalanced force below 1e-5 of its weight: the springs carry the
    # closed form to that, and 1e-4 of W leaves 10 times that margin.
    from srdda.apps.verify.water import _uplift_model
    model = _uplift_model(2)
    model.water = model.water.at_level(levels[0])
    model.add_stage(srdda.Stage("dry", kind="equilibrium"))
    for k, level in enumerate(levels[1:]):
        model.add_stage(srdda.Stage(f"level {k}", kind="equilibrium", water_level=level))
    res = srdda.run(model, RunSettings(dt=1e-3, n_steps=1, penalty=1e10))
    assert all(stage["reached"] for stage in res.stages), res.stages
    weight = float(model.arrays().block_mass[1]) * 10.0
    pressure = UNIT_WEIGHT * max(levels[-1], 0.0)
    carried = float(np.sum(res.final_state.contacts.normal_force))
    assert carried == pytest.approx(weight - pressure * 2.0, rel=1e-4)


def test_a_stage_water_level_must_be_finite():
    from srdda.apps.verify.water import _uplift_model
    model = _uplift_model(2)
    model.add_stage(srdda.Stage("flood", water_level=float("nan")))
    with pytest.raises(ModelError, match="water_level"):
        model.arrays()
