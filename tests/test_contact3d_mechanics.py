"""3D contact mechanics: the incline's closed forms, friction dissipation in the ledger, cohesion and tension,
the open-close rules with a shear vector, and a resumed run with 3D contacts."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import srdda
from srdda.apps.verify.cases.contacts3d import (CORNER_PAIR_MASS, CORNER_PAIR_PENALTY, corner_pair_settlement,
                                                 incline_case)
from srdda.apps.verify.cases.slope3d import incline_acceleration
from srdda.contact.openclose import LOCKED, OPEN, SLIDING
from srdda.contact import ContactModel, ContactParameters, ContactSet
from srdda.contact.openclose import next_states
from srdda.geometry.polyhedron import box
from srdda.io.results_store import ResultsStore, read_results, resume

G = 9.81


def test_box_slides_down_an_oblique_incline_with_the_closed_form_acceleration():
    # ψ = 30°, φ = 20°, dip towards azimuth 30°: after 0.2 s in the springs, a = g(sin ψ − cos ψ tan φ).
    # Measured 3e-12 relative after 0.5 s of settling; 1e-6 leaves room for the shorter settling here.
    measured = incline_case(30.0, 20.0, "srdda", settle=0.2, duration=0.2)
    assert measured.acceleration == pytest.approx(incline_acceleration(30.0, 20.0), rel=1e-6)
    # nothing pushes it across the dip; the friction direction, carried from step to step, drifts by
    # rounding only (measured 1.7e-9 m sideways over 0.11 m of travel)
    assert measured.cross_slope < 1e-6 * measured.travel


def test_box_on_an_incline_steeper_than_nothing_but_flatter_than_its_friction_stays():
    # φ = 35° > ψ = 30°: after settling the locked contacts hold it; the bound is 1e-6 m over 1 s
    # (measured 2e-16 m over 0.3 s here)
    measured = incline_case(30.0, 35.0, "dda1", settle=0.3, duration=0.3)
    assert measured.travel < 1e-9


def _sliding_block(v0: float, phi: float, method: str) -> srdda.Result:
    m = srdda.Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=phi), between=[("rock", "rock")])
    m.add_polyhedron(*box((-1, -2, -1), (8, 2, 0)), "rock", fixed=True)
    m.add_polyhedron(*box((0, 0, 0), (1, 1, 0.5)), "rock", velocity=(v0, 0.0, 0.0))
    return srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=400, method=method, penalty=1e10))


@pytest.mark.parametrize("method", ["srdda", "dda1"])
def test_friction_stops_a_sliding_box_and_the_ledger_holds_its_dissipation(method):
    # v0 = 2 m/s, μ = tan 30°: it stops after v0 / (μ g) = 0.353 s and d = v0² / (2 μ g) = 0.353 m. The ledger's
    # "dissipated_friction" is the friction work; with it the balance stays at its initial value to the numerical
    # dissipation of the contact springs' settling (measured 3e-5 of the kinetic energy).
    result = _sliding_block(2.0, 30.0, method)
    mu = np.tan(np.radians(30.0))
    travel = result.array("centroid")[-1, 1, 0] - 0.5
    # the springs settle by m g / k_n ~ 3e-7 m in the first steps; the stop is resolved to one Δt: 1e-3 relative
    assert travel == pytest.approx(4.0 / (2 * mu * G), rel=1e-3)
    names = list(result.energy[0])
    energy = result.array("energy")
    kinetic0 = energy[0, names.index("kinetic")]
    dissipated = energy[-1, names.index("dissipated_friction")]
    assert dissipated == pytest.approx(kinetic0, rel=1e-3)  # all the kinetic energy went into friction
    balance = energy[:, names.index("balance")]
    assert np.max(balance - balance[0]) <= 1e-9 * kinetic0  # never created
    assert abs(balance[-1] - balance[0]) <= 1e-3 * kinetic0


def _hanging_block(tension: float, cohesion: float) -> srdda.Result:
    # a box glued under a fixed roof: its weight (2500 kg·g = 24.5 kN over 1 m²) pulls the joint open
    m = srdda.Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(2500.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0, cohesion=cohesion, tensile_strength=tension),
                         between=[("rock", "rock")])
    m.add_polyhedron(*box((-1, -1, 0), (2, 2, 1)), "rock", fixed=True)
    m.add_polyhedron(*box((0, 0, -1), (1, 1, 0)), "rock")
    return srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=100, method="srdda", penalty=1e10))


def test_tensile_strength_over_the_joint_area_holds_a_hanging_block_and_less_lets_it_fall():
    # tension strength × area against the weight 24.5 kN: 50 kPa holds it, 10 kPa does not. The joint has
    # cohesion too: without it a contact in tension has no shear strength, so the rounding of its shear
    # (1e-17 m) makes it slide, and a sliding contact loses its bond (as in 2D)
    held = _hanging_block(50e3, 50e3)
    fell = _hanging_block(10e3, 50e3)
    drop_held = 0.0 - held.array("centroid")[-1, 1, 2] - 0.5
    drop_fell = 0.0 - fell.array("centroid")[-1, 1, 2] - 0.5
    assert drop_held < 1e-5  # elastic stretch of the springs only (m g / (4 k_n) ~ 6e-7 m)
    assert drop_fell == pytest.approx(0.5 * G * 0.1**2, rel=0.05)  # free fall from the first step


def test_open_close_rules_with_a_shear_vector():
    kn, ks = 1e9, 4e8
    n = 6
    state = np.array([OPEN, LOCKED, LOCKED, SLIDING, SLIDING, LOCKED], dtype=np.int8)
    direction = np.array([[0, 0], [0, 0], [0, 0], [1, 0], [1, 0], [0, 0]], dtype=float)
    gap = np.array([-1e-6, -1e-6, -1e-6, -1e-6, -1e-6, 1e-6])  # N = 1000 N (last: open, in tension)
    shear = np.array([[0, 0], [1e-6, 0], [0, 3e-6], [2e-6, 1e-6], [-1e-7, 0], [0, 0]])
    slip = shear.copy()
    tan_phi = np.full(n, 0.5)  # strength 500 N: k_s|s| = 400 N holds, 1200 N does not
    zero = np.zeros(n)
    strength = np.maximum(-kn * gap, 0.0) * tan_phi
    dragged = np.ones(n, dtype=bool)  # vertex-face contacts: their sliding springs are dragged at their strength
    new, friction, trial, changed, _ = next_states(state, direction, gap, shear, slip, np.full(n, kn), np.full(n, ks),
                                                   strength, tan_phi, zero, np.zeros(n, bool), np.full(n, 1000.0),
                                                   dragged)
    assert new.tolist() == [LOCKED, LOCKED, SLIDING, SLIDING, LOCKED, OPEN]
    np.testing.assert_allclose(friction[2], [0, 1])  # starts to slide along its spring's load
    np.testing.assert_allclose(friction[3], [1, 0])  # keeps its direction for the step
    # the next step's direction: the trial force of a spring held at its strength (1.25 µm along ŝ) plus the slip
    np.testing.assert_allclose(trial[3], np.array([3.25e-6, 1e-6]) / np.hypot(3.25e-6, 1e-6))
    assert changed.tolist() == [True, False, True, False, True, True]  # the reversed slip locks


def test_the_empty_contact_set_has_the_shapes_of_a_full_one():
    m = srdda.Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_polyhedron(*box((-1, -1, -1), (1, 1, 0)), "rock", fixed=True)
    m.add_polyhedron(*box((0, 0, 0.001), (0.5, 0.5, 0.5)), "rock")
    arrays = m.arrays()
    record = ContactModel(arrays, ContactParameters(1e9, 4e8, 0.05, np.radians(3.0), 0.02)).detector.detect(
        arrays.vertex_position)
    empty = ContactSet.empty(record)
    assert empty.direction.shape == (0, 2) and empty.point.shape == (0, 3) and empty.max_penetration == 0.0
    assert empty.features.shape == (0, record.features.shape[1])


def test_resume_with_3d_contacts_equals_the_uninterrupted_run(tmp_path: Path):
    # a cube thrown onto a base: the contact set (states, references, slip directions) lives on the State
    # and is checkpointed field by field, so a resumed run is the uninterrupted one (to 1e-12)
    def model() -> srdda.Model:
        m = srdda.Model(gravity=(0.0, 0.0, -G))
        m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
        m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
        m.add_polyhedron(*box((-3, -3, -1), (3, 3, 0)), "rock", fixed=True)
        m.add_polyhedron(*box((-0.25, -0.25, 0.05), (0.25, 0.25, 0.55)), "rock", velocity=(1.0, 0.5, 0.0),
                         angular_velocity=(0.0, 0.0, 2.0))
        return m

    settings = srdda.RunSettings(dt=1e-3, n_steps=200, method="srdda", penalty=1e11)
    reference = srdda.run(model(), settings)
    assert reference.completed and np.max(reference.closed_contacts) > 0
    stop = next(k for k in range(100, 190) if reference.closed_contacts[k] > 0)  # stopped while touching
    path = tmp_path / "drop.h5"
    first = srdda.run(model(), dataclasses.replace(settings, n_steps=stop),
                      recorders=[ResultsStore(path, settings, flush_every=10)])
    assert isinstance(first.final_state.contacts, ContactSet)
    got = resume(path, model().arrays()).final_state
    ref = reference.final_state
    assert got.step == ref.step
    for name in ("vertices", "velocity", "rotation"):
        a, b = getattr(got, name), getattr(ref, name)
        assert np.max(np.abs(a - b)) <= 1e-12 * max(1.0, np.max(np.abs(b))), name
    # the file's contact records hold every per-contact array of the set, contact points and normals included
    records = read_results(path)
    last = records.contacts_at(len(records.contacts["step"]) - 1)
    assert last["point"].shape[1:] == (3,) and last["normal"].shape[1:] == (3,) and last["shear"].shape[1:] == (2,)


def test_a_cube_on_an_equal_cube_settles_on_four_springs():
    """Corner on corner (cut blocks): the joint carries the weight W on one spring per corner pair, so the
    top cube settles by W/(4 k_n) (srdda verify corner-pairs-3d, whose tolerance says why 1e-4); two springs
    a corner (each corner found from both blocks) would settle it by half that."""
    settlement, contacts = corner_pair_settlement("dda0")
    assert contacts == 4
    assert settlement == pytest.approx(CORNER_PAIR_MASS * G / (4 * CORNER_PAIR_PENALTY), rel=1e-4)
