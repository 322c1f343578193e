"""No energy from contacts (issue 29), property-based (hypothesis): 2D and 3D, srdda, dda1 and Chung-Hulbert.

Random convex polygons and polyhedra dropped on a fixed base at random
heights, angles, speeds and spins, with and without friction and cohesion; a
small stack; a small wall struck by a block; under srdda and dda1 with their
own schemes and with ``scheme = "chung-hulbert"``. In every run the
mechanical energy (kinetic + gravitational + strain + springs + contacts)
never rises above its start plus the work of loads by more than 1e-6 of the
energy in play, and the ledger's ``dissipated_contact`` and
``dissipated_friction`` never fall from one step to the next by more than the
rounding (``DISSIPATION_ROUNDING``, 1e-9 of the energy in play):
:func:`energy_models.contact_energy_excess`.

The guarantee holds under ``contact_solver = "newton"``. Under the open-close
solver Shi's bands let contacts put energy in (docs/reliability.md, *No energy
from contacts*): its variants are strict xfails, each pinned on a drop that
fails (``@example``), with the measured figure. Derandomized
(tests/conftest.py), no shrinking: every run tests the same draws, quickly.
"""
from __future__ import annotations

import numpy as np
import pytest
from energy_models import PENALTY, contact_energy_excess, two_blocks_impact
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st
from test_property_runs import convex_block
from test_property_runs_3d import convex_polyhedron

import srdda
from srdda.geometry.polyhedron import box
from srdda.history import TimeHistory
from srdda.kinematics.shape3d import rotation_matrix_3d
from srdda.ledger import DISSIPATION_ROUNDING

G = -9.81
RISE = 1e-6  # of the energy in play: the guarantee (docs/reliability.md)
RUNS = [("srdda", None), ("dda1", None), ("srdda", "chung-hulbert"), ("dda1", "chung-hulbert")]
joints = st.fixed_dictionaries({"friction_angle": st.sampled_from([0.0, 30.0]),
                                "cohesion": st.sampled_from([0.0, 1e4]),
                                "tensile_strength": st.sampled_from([0.0, 1e4])})
runs = st.sampled_from(RUNS)
few = settings(max_examples=8, deadline=None, phases=[Phase.explicit, Phase.generate],
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
# the open-close's bands (docs/contacts.md, "The band's pull" and "Cycling contacts"): a contact held closed
# in tension while its gap shrank pulls the blocks together; measured on the pinned drop (srdda, φ = 30°):
# dissipated_contact fell by 4.89 J in step 207, 5.7e-3 of the energy in play
OPEN_CLOSE = pytest.param("open-close", marks=pytest.mark.xfail(strict=True, reason=(
    "open-close: two contacts held closed by the freezing rules while their gaps shrank from 30 and 155 µm to "
    "1 and 3 µm pulled the pinned drop's block down: dissipated_contact fell by 5.7e-3 of the energy in play")))
SOLVERS = ["newton", OPEN_CLOSE]
# Shi's reverse-slip band: a sliding contact whose slip turned back by less than f0·w0 keeps its friction, which
# then pushes the block the way it moves (docs/contacts.md); measured on the stack's pinned draw (dda1, φ = 30°)
BAND_SLIP = pytest.param("open-close", marks=pytest.mark.xfail(strict=True, reason=(
    "open-close: a sliding contact's slip turned back within Shi's band f0·w0 (0.04 µm) under its friction: "
    "dissipated_friction fell by 3.3e-7 of the energy in play")))
# both bands on the wall's pinned blow (srdda, φ = 0, c = 10 kPa): measured 3.6e-2 of the energy in play
BAND_WALL = pytest.param("open-close", marks=pytest.mark.xfail(strict=True, reason=(
    "open-close: contacts held closed by Shi's band and the freezing rules while their gaps shrank pulled the "
    "blocks together: dissipated_contact fell by 3.6e-2 of the energy in play on the pinned blow")))


def _model(dim: int, joint: dict[str, float]) -> srdda.Model:
    m = srdda.Model(gravity=(0.0, G) if dim == 2 else (0.0, 0.0, G))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(**joint), between=[("rock", "rock")])
    return m


def _check(m: srdda.Model, run: tuple[str, str | None], solver: str, steps: int, dt: float = 1e-3) -> None:
    method, scheme = run
    result = srdda.run(m, srdda.RunSettings(dt=dt, n_steps=steps, method=method, scheme=scheme, penalty=PENALTY,
                                            contact_solver=solver))
    assert result.completed, result.status
    assert max(result.closed_contacts) > 0
    rise, fall = contact_energy_excess(result)
    assert rise <= RISE and fall <= DISSIPATION_ROUNDING, (rise, fall)


@pytest.mark.parametrize("solver", ["open-close", "newton"])
@pytest.mark.parametrize("run", RUNS)
def test_the_impact_of_issue_29_puts_no_energy_in(run, solver):
    # before the fix, under Chung-Hulbert: 1.27 (open-close) and 1.33 (Newton) times the initial energy, and
    # dissipated_contact fell by 169 and 383 J in one step; under Shi's scheme it fell by 20.5 J (measured 0 now)
    result = srdda.run(*two_blocks_impact(run[1], run[0], solver))
    assert result.completed and max(result.closed_contacts) > 0
    rise, fall = contact_energy_excess(result)
    assert rise <= RISE and fall <= DISSIPATION_ROUNDING, (rise, fall)


@pytest.mark.parametrize("solver", SOLVERS)
@few
@given(block=convex_block(), height=st.floats(0.0, 0.2), vx=st.floats(-2, 2), omega=st.floats(-3, 3),
       turn=st.floats(0, 2 * np.pi), joint=joints, run=runs)
@example(block=np.array([[-0.5306463259287053, 0.6049249135813521], [-0.9999254079873726, 0.008716998979434851],
                         [-0.75541794367009, -0.4676452163290931], [-0.3533682704185216, -0.6676524303608659],
                         [0.47820457187012055, -0.6268033932183854]]),
         height=0.04324467820380289, vx=-1.5971855919260927, omega=-2.768375220474187, turn=4.408242711704014,
         joint={"friction_angle": 30.0, "cohesion": 0.0, "tensile_strength": 0.0}, run=("srdda", None))
def test_a_dropped_polygon_puts_no_energy_in(solver, block, height, vx, omega, turn, joint, run):
    c, s = np.cos(turn), np.sin(turn)
    shape = 0.3 * block @ np.array([[c, s], [-s, c]])
    shape = shape - [0.0, shape[:, 1].min() - height]  # lowest vertex `height` above the base
    m = _model(2, joint)
    m.add_block([[-5, -1], [5, -1], [5, 0], [-5, 0]], "rock", fixed=True)
    m.add_block(shape, "rock", velocity=(vx, 0.0), angular_velocity=omega)
    _check(m, run, solver, 300)


@pytest.mark.parametrize("solver", ["newton", BAND_SLIP])
@few
@given(widths=st.lists(st.floats(0.2, 0.6), min_size=3, max_size=3), shifts=st.lists(st.floats(-0.1, 0.1),
       min_size=3, max_size=3), gap=st.sampled_from([0.0, 0.01]), joint=joints, run=runs)
@example(widths=[0.5576085932375427, 0.3333333333333333, 0.25322627096584216],
         shifts=[-0.08772604530527044, -0.07961670814896649, 0.05740509920248546], gap=0.01,
         joint={"friction_angle": 30.0, "cohesion": 0.0, "tensile_strength": 0.0}, run=("dda1", None))
def test_a_small_stack_puts_no_energy_in(solver, widths, shifts, gap, joint, run):
    # three boxes 0.2 m high on a base, each `gap` above the one below (0: touching, bonded at the start)
    m = _model(2, joint)
    m.add_block([[-3, -1], [3, -1], [3, 0], [-3, 0]], "rock", fixed=True)
    y = 0.0
    for w, x in zip(widths, shifts):
        y += gap
        m.add_block([[x - w / 2, y], [x + w / 2, y], [x + w / 2, y + 0.2], [x - w / 2, y + 0.2]], "rock")
        y += 0.2
    _check(m, run, solver, 200)


@pytest.mark.parametrize("solver", ["newton", BAND_WALL])
@few
@given(speed=st.floats(1.0, 4.0), height=st.floats(0.02, 0.35), omega=st.floats(-3, 3), joint=joints, run=runs)
@example(speed=3.9247775546771075, height=0.0763879310079866, omega=0.0,
         joint={"friction_angle": 0.0, "cohesion": 1e4, "tensile_strength": 0.0}, run=("srdda", None))
def test_a_small_wall_struck_by_a_block_puts_no_energy_in(solver, speed, height, omega, joint, run):
    # two courses of two 0.4 × 0.2 m bricks (the upper one laid half a brick over) struck by a 0.2 m block
    m = _model(2, joint)
    m.add_block([[-3, -1], [3, -1], [3, 0], [-3, 0]], "rock", fixed=True)
    for course, offset in ((0, 0.0), (1, 0.2)):
        for k in range(2):
            x, y = offset + 0.4 * k, 0.2 * course
            m.add_block([[x, y], [x + 0.4, y], [x + 0.4, y + 0.2], [x, y + 0.2]], "rock")
    m.add_block([[-0.25, height], [-0.05, height], [-0.05, height + 0.2], [-0.25, height + 0.2]], "rock",
                velocity=(speed, 0.0), angular_velocity=omega)
    _check(m, run, solver, 200)


@pytest.mark.parametrize("run", RUNS)
def test_a_block_shaken_in_a_notch_puts_no_energy_in(run):
    # a square sits in the notch of a fixed ell, gravity tilted into the corner, shaken horizontally (3 m/s²,
    # 20 Hz) at the tunnel example's Δt and penalty. Its corner touches both faces of the notch; when the
    # detection gave it a spring on one face only (its entrance line), it sank into the other unresisted and was
    # found there compressed, ½k_n g² from nothing: the energy rose 0.81 of the energy in play above its start (srdda)
    m = srdda.Model(gravity=(-3.0, -9.0))
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_block([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], "rock", fixed=True)
    m.add_block([[1, 1], [1.8, 1], [1.8, 1.8], [1, 1.8]], "rock")
    m.set_base_acceleration(TimeHistory.sine((3.0, 0.0), 0.05))
    method, scheme = run
    result = srdda.run(m, srdda.RunSettings(dt=2e-4, n_steps=300, method=method, scheme=scheme, penalty=1.5e12,
                                            contact_solver="newton"))
    assert result.completed and max(result.closed_contacts) > 0
    rise, fall = contact_energy_excess(result)
    assert rise <= RISE and fall <= DISSIPATION_ROUNDING, (rise, fall)


# Newton only: long enough to land, open-close's bands show in 3D too (a drop's dissipated_contact fell by
# 5.6e-6 of the energy in play), but not on every draw, so no strict xfail pins them here
@pytest.mark.parametrize("solver", ["newton"])
@settings(max_examples=4, deadline=None, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(block=convex_polyhedron(), height=st.floats(0.0, 0.05),
       v=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, -0.3)),
       omega=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
       turn=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)), joint=joints, run=runs)
def test_a_dropped_polyhedron_puts_no_energy_in(solver, block, height, v, omega, turn, joint, run):
    points, faces = block
    points = points @ rotation_matrix_3d(np.array([turn]))[0].T
    points = points - [0.0, 0.0, points[:, 2].min() - height]  # lowest vertex `height` above the base
    m = _model(3, joint)
    m.add_polyhedron(*box((-2, -2, -1), (2, 2, 0)), "rock", fixed=True)
    m.add_polyhedron(points, faces, "rock", velocity=v, angular_velocity=omega)
    # long enough to land whatever the spin: the centroid, at most the block's height D above its lowest vertex,
    # falls at least g t²/2 (v_z ≤ 0), and some vertex is below it, so a vertex reaches the base by √(2(h + D)/g)
    landed = np.sqrt(2.0 * (height + np.ptp(points[:, 2])) / -G)
    _check(m, run, solver, int(np.ceil(landed / 1e-3)) + 20)


# Shi's step only: the impact law's dashpot is calibrated to it (docs/contacts/impacts.md)
SHI_RUNS = [run for run in RUNS if run[1] is None]


@few
@given(block=convex_block(), height=st.floats(0.0, 0.2), vx=st.floats(-2, 2), omega=st.floats(-3, 3),
       turn=st.floats(0, 2 * np.pi), joint=joints, restitution=st.floats(0.2, 1.0), run=st.sampled_from(SHI_RUNS))
def test_a_polygon_dropped_on_a_joint_with_a_restitution_puts_no_energy_in(block, height, vx, omega, turn, joint,
                                                                           restitution, run):
    # the impact law as a term of Newton's potential (its force the derivative of a convex ψ of the end gap)
    c, s = np.cos(turn), np.sin(turn)
    shape = 0.3 * block @ np.array([[c, s], [-s, c]])
    shape = shape - [0.0, shape[:, 1].min() - height]
    m = _model(2, {**joint, "restitution": restitution})
    m.add_block([[-5, -1], [5, -1], [5, 0], [-5, 0]], "rock", fixed=True)
    m.add_block(shape, "rock", velocity=(vx, 0.0), angular_velocity=omega)
    _check(m, run, "newton", 300)


@settings(max_examples=3, deadline=None, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(block=convex_polyhedron(), height=st.floats(0.0, 0.05),
       v=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, -0.3)),
       omega=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
       turn=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)), joint=joints,
       restitution=st.floats(0.2, 1.0), run=st.sampled_from(SHI_RUNS))
def test_a_polyhedron_dropped_on_a_joint_with_a_restitution_puts_no_energy_in(block, height, v, omega, turn, joint,
                                                                              restitution, run):
    points, faces = block
    points = points @ rotation_matrix_3d(np.array([turn]))[0].T
    points = points - [0.0, 0.0, points[:, 2].min() - height]
    m = _model(3, {**joint, "restitution": restitution})
    m.add_polyhedron(*box((-2, -2, -1), (2, 2, 0)), "rock", fixed=True)
    m.add_polyhedron(points, faces, "rock", velocity=v, angular_velocity=omega)
    landed = np.sqrt(2.0 * (height + np.ptp(points[:, 2])) / -G)  # as in the drop above
    _check(m, run, "newton", int(np.ceil(landed / 1e-3)) + 20)
