"""3D contact verification problems: models and their closed forms (docs/verification.md).

* incline: a 1 × 1 × 0.5 m box on a fixed plane dipping ψ towards an
  azimuth that is not a coordinate axis, joint friction φ. φ < ψ: it slides
  with a = g (sin ψ − cos ψ tan φ) (:func:`srdda.apps.verify.cases.slope3d.incline_acceleration`);
  φ > ψ: it stays.
* drop: a 0.5 m cube dropped on a fixed base at an orientation, thrown
  sideways and spinning; the energy ledger's balance (stored energies plus
  friction dissipation) must never rise above its initial value.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from srdda.geometry.polyhedron import box
from srdda.integrators.methods import MethodName
from srdda.kinematics.shape3d import rotation_matrix_3d
from srdda.model import JointMaterial, Material, Model
from srdda.results import Result
from srdda.settings import RunSettings
from srdda.simulation import run
from .slope3d import G

__all__ = ["incline_model", "incline_case", "InclineRun", "drop_model", "drop_case"]

INCLINE_DENSITY, INCLINE_PENALTY = 2500.0, 1e10  # a 1250 kg box on four contacts of k_n = 1e10 N/m


def _completed(result: Result, what: str) -> Result:
    if not result.completed:
        raise RuntimeError(f"{what}: the run did not complete ({result.status})")
    return result


def incline_model(psi: float, phi: float, azimuth: float = 30.0) -> tuple[Model, np.ndarray]:
    """The box on a plane dipping ``psi`` (°) towards ``azimuth`` (° from x); returns the model and the dip vector."""
    turn = rotation_matrix_3d(np.array([[0.0, 0.0, np.radians(azimuth)]]))[0] \
        @ rotation_matrix_3d(np.array([[0.0, np.radians(psi), 0.0]]))[0]  # tilt about y: x goes down, then turn
    m = Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", Material(INCLINE_DENSITY, 1e9, 0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=phi), between=[("rock", "rock")])
    v, f = box((-6.0, -3.0, -1.0), (6.0, 3.0, 0.0))
    m.add_polyhedron(v @ turn.T, f, "rock", fixed=True, name="plane")
    v, f = box((0.0, 0.0, 0.0), (1.0, 1.0, 0.5))
    m.add_polyhedron(v @ turn.T, f, "rock", name="block")
    return m, turn[:, 0]


@dataclass(frozen=True)
class InclineRun:
    """What one incline run measured."""

    acceleration: float  # m/s², along the dip, from the velocity between ``settle`` and the end
    travel: float  # m: how far the centroid moved between ``settle`` and the end
    cross_slope: float  # m: the largest displacement across the dip (should be 0)
    solves_per_step: float


def incline_case(psi: float, phi: float, method: MethodName, settle: float = 0.5, duration: float = 1.0,
                 dt: float = 1e-3) -> InclineRun:
    """Run the incline for ``settle`` + ``duration`` s and measure after ``settle`` (the contacts' first bounce)."""
    model, dip = incline_model(psi, phi)
    steps = int(round((settle + duration) / dt))
    res = _completed(run(model, RunSettings(dt=dt, n_steps=steps, method=method, penalty=INCLINE_PENALTY)),
                     f"incline-3d ψ={psi} φ={phi} {method}")
    t = np.asarray(res.time)
    i = int(np.searchsorted(t, settle - 0.5 * dt))
    centroid = res.array("centroid")[:, 1]
    velocity = res.array("velocity")[:, 1, :3]
    along = velocity @ dip
    moved = centroid[i:] - centroid[i]
    across = moved - np.outer(moved @ dip, dip)
    return InclineRun(acceleration=float((along[-1] - along[i]) / (t[-1] - t[i])),
                      travel=float(np.max(np.linalg.norm(moved, axis=1))),
                      cross_slope=float(np.max(np.linalg.norm(across, axis=1))),
                      solves_per_step=float(np.mean(res.iterations[1:])))


def drop_model(rotation: tuple[float, float, float], height: float = 0.2, velocity=(1.0, 0.5, 0.0),
               spin=(0.0, 0.0, 2.0), phi: float = 30.0) -> Model:
    """A 0.5 m cube turned by the rotation vector ``rotation``, its lowest point ``height`` above a fixed base."""
    m = Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", Material(2600.0, 1e10, 0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=phi), between=[("rock", "rock")])
    m.add_polyhedron(*box((-3.0, -3.0, -1.0), (3.0, 3.0, 0.0)), "rock", fixed=True, name="base")
    v, f = box((-0.25, -0.25, -0.25), (0.25, 0.25, 0.25))
    v = v @ rotation_matrix_3d(np.array([rotation], dtype=float))[0].T
    v[:, 2] += height - v[:, 2].min()
    m.add_polyhedron(v, f, "rock", velocity=velocity, angular_velocity=spin, name="cube")
    return m


def drop_case(rotation: tuple[float, float, float], method: MethodName, steps: int = 600, dt: float = 1e-3,
              penalty: float = 1e11, **kw: Any) -> tuple[float, float]:
    """The largest rise of the energy balance over the run, relative to the cube's energy, and the dissipation.

    Balance = kinetic + gravitational + strain + contact springs + friction
    dissipated so far (no loads act). The scale is the cube's energy above
    the base's top: its initial kinetic energy plus m g (height of its
    centroid). Returns (largest rise / scale, friction dissipated / scale).
    """
    model = drop_model(rotation, **kw)
    res = _completed(run(model, RunSettings(dt=dt, n_steps=steps, method=method, penalty=penalty)),
                     f"drop-3d {rotation} {method}")
    names = list(res.energy[0])
    energy = res.array("energy")
    balance = energy[:, names.index("balance")]
    arrays = model.arrays()
    mass = float(arrays.block_mass[1])
    centroid = arrays.moments(arrays.vertex_position).centroid[1]
    kinetic0 = float(energy[0, names.index("kinetic")])
    scale = kinetic0 + mass * G * float(centroid[2])
    return float(np.max(balance - balance[0]) / scale), float(energy[-1, names.index("dissipated_friction")] / scale)


CORNER_PAIR_PENALTY = 1e9  # N/m: k_n of every contact of corner-pairs-3d
CORNER_PAIR_MASS = 2500.0  # kg: the top cube (1 m³ of 2500 kg/m³)


def corner_pair_settlement(method: MethodName, steps: int = 40) -> tuple[float, int]:
    """(settlement (m), contacts at the end) of a 1 m cube resting corner on corner on an equal fixed cube
    (cut blocks), after ``steps`` of Shi's static steps (velocity_ratio 0) of 1 ms; the blocks (E = 10¹⁴ Pa)
    10⁵ times stiffer axially than the springs."""
    m = Model(gravity=(0.0, 0.0, -G))
    m.add_material("rock", Material(CORNER_PAIR_MASS, 1e14, 0.25))
    m.add_polyhedron(*box((0, 0, -1), (1, 1, 0)), "rock", fixed=True, name="base")
    m.add_polyhedron(*box((0, 0, 0), (1, 1, 1)), "rock", name="cube")
    result = run(m, RunSettings(dt=1e-3, n_steps=steps, method=method, penalty=1e14,
                                contact_penalty=CORNER_PAIR_PENALTY, velocity_ratio=0.0))
    state = result.final_state
    assert state is not None and state.contacts is not None
    return 0.5 - float(result.array("centroid")[-1, 1, 2]), int(np.sum(state.contacts.closed))
