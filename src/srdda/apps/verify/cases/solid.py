"""3D verification problems: models and their independent references (closed forms, scipy ODEs).

Each ``*_case`` function runs srdda and returns the measured quantities beside
their references, so that ``srdda verify`` and the tests share one definition.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import solve_ivp

from srdda.geometry.polyhedron import box, prism
from srdda.integrators.methods import MethodName
from srdda.io.modelfile import load_model
from srdda.kinematics.shape3d import rotation_matrix_3d, skew
from srdda.model import Material, Model
from ...paper.registry import examples_dir
from srdda.settings import RunSettings
from srdda.simulation import run

__all__ = ["Measured", "spin_case", "intermediate_axis_case", "extruded_case", "conical_pendulum_case",
           "uniaxial_case", "T_SECTION"]


@dataclass(frozen=True)
class Measured:
    """One measured quantity beside its reference."""

    quantity: str
    method: str
    ours: float
    reference: float


def _inertia(model: Model) -> tuple[np.ndarray, np.ndarray, float]:
    """Rotational inertia J about the centroid (3, 3), the centroid and the mass of a one-block model."""
    arrays = model.arrays()
    mom = arrays.moments(arrays.vertex_position)
    second = mom.second[0]
    inertia = arrays.block_density[0] * (np.trace(second) * np.eye(3) - second)
    return inertia, mom.centroid[0], float(arrays.block_mass[0])


def spin_case(method: MethodName, steps: int = 10_000, dt: float = 1e-3, omega: float = 3.0) -> list[Measured]:
    """A box spinning about its principal z axis in free flight: ω and volume kept; dda0's volume grows.

    dda0's linear update maps the block by I + Δθ·[e_z]× each step, whose
    determinant is 1 + (ωΔt)²: the volume grows by (1 + (ωΔt)²)^N while ω stays.
    """
    model = Model(gravity=(0.0, 0.0, 0.0))
    model.add_material("rock", Material(2600.0, 1e16, 0.25))
    model.add_polyhedron(*box((0, 0, 0), (1.0, 0.5, 0.2)), "rock", angular_velocity=(0.0, 0.0, omega))
    result = run(model, RunSettings(dt=dt, n_steps=steps, method=method), keep_history=False)
    state = result.final_state
    assert state is not None  # run() leaves its final state
    volume0 = model.arrays().moments(model.arrays().vertex_position).volume[0]
    growth = (1.0 + (omega * dt) ** 2) ** steps if method == "dda0" else 1.0
    return [Measured("omega_z", method, float(state.velocity[0, 5]), omega),
            Measured("volume / initial", method, float(state.moments.volume[0] / volume0), growth)]


# a T-shaped section (m): flange 0.6 × 0.1, web 0.1 × 0.4; concave, three distinct principal moments
T_SECTION = [[-0.3, 0.0], [0.3, 0.0], [0.3, 0.1], [0.05, 0.1], [0.05, 0.5], [-0.05, 0.5], [-0.05, 0.1],
             [-0.3, 0.1]]


def _zero_crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    i = np.flatnonzero(np.sign(x[1:]) != np.sign(x[:-1]))
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def intermediate_axis_case(method: MethodName, flips: int = 10, dt: float = 1e-3, spin: float = 20.0,
                           wobble: float = 1.0) -> list[Measured]:
    """The tennis-racket flip of a concave T prism spun near its intermediate axis, against Euler's equations.

    Reference: the rigid body's orientation R and angular momentum L (constant)
    integrated with scipy's DOP853 (rtol 1e-12); the flip half-period is the
    mean time between sign changes of ω along the body's intermediate axis.
    Also: kinetic energy and |angular momentum| of the run, relative drift.
    """
    model = Model(gravity=(0.0, 0.0, 0.0))
    model.add_material("steel", Material(7800.0, 2e11, 0.3))
    model.add_polyhedron(*prism(T_SECTION, -0.1, 0.1), "steel")
    inertia, _, _ = _inertia(model)
    _, axes = np.linalg.eigh(inertia)
    middle = axes[:, 1]
    omega0 = spin * middle + wobble * axes[:, 0]
    model.blocks[0].velocity = (0.0, 0.0, 0.0, *omega0)
    reference_half = _euler_half_period(inertia, omega0, middle, dt, flips)
    steps = int(np.ceil((flips + 0.5) * reference_half / dt))
    result = run(model, RunSettings(dt=dt, n_steps=steps, method=method))
    t = np.asarray(result.time)
    omega = result.array("velocity")[:, 0, 3:6]
    rotation = result.array("rotation")[:, 0]
    along = np.einsum("nji,nj->ni", rotation, omega) @ middle  # ω in the body frame, on the middle axis
    crossings = _zero_crossings(t, along)
    half = float(np.mean(np.diff(crossings))) if len(crossings) > 1 else float("inf")
    turned = rotation @ inertia @ np.swapaxes(rotation, 1, 2)
    momentum = np.einsum("nij,nj->ni", turned, omega)
    energy = 0.5 * np.einsum("ni,ni->n", omega, momentum)
    size = np.linalg.norm(momentum, axis=1)
    return [Measured("flip half-period (s)", method, half, reference_half),
            Measured("kinetic energy / initial", method, float(energy[np.argmax(np.abs(energy - energy[0]))]
                                                               / energy[0]), 1.0),
            Measured("|angular momentum| / initial", method, float(size[np.argmax(np.abs(size - size[0]))]
                                                                   / size[0]), 1.0)]


def _euler_half_period(inertia: np.ndarray, omega0: np.ndarray, middle: np.ndarray, dt: float,
                       flips: int) -> float:
    """Mean flip half-period of the free rigid body (orientation R, constant L), scipy DOP853."""
    momentum = inertia @ omega0

    def rates(_: float, y: np.ndarray) -> np.ndarray:
        R = y.reshape(3, 3)
        w = R @ np.linalg.solve(inertia, R.T @ momentum)
        return (skew(w[None])[0] @ R).ravel()

    def body_component(y: np.ndarray) -> float:
        R = y.reshape(3, 3)
        return float(np.linalg.solve(inertia, R.T @ momentum) @ middle)

    horizon = 1.0
    while True:
        sol = solve_ivp(rates, (0.0, horizon), np.eye(3).ravel(), method="DOP853", rtol=1e-12, atol=1e-14,
                        dense_output=True)
        t = np.arange(0.0, horizon, 0.1 * dt)
        crossings = _zero_crossings(t, np.array([body_component(y) for y in sol.sol(t).T]))
        if len(crossings) > flips:
            return float(np.mean(np.diff(crossings[: flips + 1])))
        horizon *= 2.0


def extruded_case(example: str, method: MethodName, steps: int = 2000, young: float | None = None,
                  penalty: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ω histories of a paper example (``rod`` or ``pendulum``) in 2D and as 1 m prisms in 3D.

    Returns (ω 2D, ω 3D, ω 2D with another solver): the last one measures how
    much the 2D model's own rounding moves ω (a stiff penalty amplifies it).
    ``young``/``penalty`` soften the model when given.
    """
    model, settings = load_model(examples_dir() / "paper" / f"{example}.toml")
    if young is not None:
        model.materials = {k: replace(m, young=young) for k, m in model.materials.items()}
    settings = replace(settings, method=method, n_steps=steps, solver="dense",
                       penalty=settings.penalty if penalty is None else penalty)
    flat = run(model, settings).array("velocity")[:, :, 2]
    solid = run(model.extruded(), settings).array("velocity")[:, :, 5]
    other = run(model, replace(settings, solver="superlu")).array("velocity")[:, :, 2]
    return flat, solid, other


def conical_pendulum_case(method: MethodName, periods: float = 2.0, dt: float = 2.5e-4, tilt: float = 0.5
                          ) -> list[Measured]:
    """A 0.2 × 0.2 × 1 m box hung from the ground by a ball hinge (pin) at its top, on a steady conical orbit.

    The tilt α about x and the spin Ω about the vertical satisfy Ω²(e_z × J_p e_z)
    = r_c × m g (J_p about the pivot), so the orbit is steady. Reference: the
    same rigid body about the fixed pivot, orientation and angular momentum
    integrated by scipy (rtol 1e-12). Measured: the orbit period (mean azimuth
    rate of the centroid) and the centroid's height, time-averaged.
    """
    g = 9.81
    turn = rotation_matrix_3d(np.array([[tilt, 0.0, 0.0]]))[0]
    vertices, faces = box((-0.1, -0.1, -1.0), (0.1, 0.1, 0.0))
    model = Model(gravity=(0.0, 0.0, -g))
    model.add_material("rock", Material(2500.0, 1e10, 0.25))
    model.add_polyhedron(vertices @ turn.T, faces, "rock")
    model.add_pin((0.0, 0.0, 0.0), block=0)
    inertia, c, mass = _inertia(model)
    pivot_inertia = inertia + mass * (c @ c * np.eye(3) - np.outer(c, c))
    up = np.array([0.0, 0.0, 1.0])
    torque = np.cross(c, mass * np.array([0.0, 0.0, -g]))
    gyro = np.cross(up, pivot_inertia @ up)
    spin = float(np.sqrt(torque @ gyro / (gyro @ gyro)))
    omega0 = spin * up
    model.blocks[0].velocity = (*np.cross(omega0, c), *omega0)
    steps = int(round(periods * 2 * np.pi / spin / dt))
    result = run(model, RunSettings(dt=dt, n_steps=steps, method=method, contacts=False))
    t = np.asarray(result.time)
    centroid = result.array("centroid")[:, 0]
    momentum = pivot_inertia @ omega0

    def rates(_: float, y: np.ndarray) -> np.ndarray:
        R, L = y[:9].reshape(3, 3), y[9:]
        w = np.linalg.solve(R @ pivot_inertia @ R.T, L)
        return np.concatenate([(skew(w[None])[0] @ R).ravel(), np.cross(R @ c, mass * np.array([0, 0, -g]))])

    sol = solve_ivp(rates, (0.0, t[-1]), np.concatenate([np.eye(3).ravel(), momentum]), method="DOP853",
                    rtol=1e-12, atol=1e-14, dense_output=True)
    ref = np.array([y[:9].reshape(3, 3) @ c for y in sol.sol(t).T])

    def period(points: np.ndarray) -> float:
        azimuth = np.unwrap(np.arctan2(points[:, 1], points[:, 0]))
        return float(2 * np.pi * (t[-1] - t[0]) / (azimuth[-1] - azimuth[0]))

    return [Measured("orbit period (s)", method, period(centroid), period(ref)),
            Measured("centroid height (m)", method, float(np.mean(centroid[:, 2])), float(np.mean(ref[:, 2])))]


def uniaxial_case(method: MethodName = "srdda", stress: float = 100.0, young: float = 1e9, poisson: float = 0.25,
                  steps: int = 200) -> list[Measured]:
    """A free box pulled by equal and opposite uniform tractions on its x faces, settled with ρ∞ = 0.

    Point loads σA/4 at the four corners of each face: for a block whose
    displacement is linear (DDA) they do the same virtual work as a uniform
    traction. σ/E = 1e-7 keeps the geometric nonlinearity (strain² ~ 1e-14)
    below the closed forms' accuracy: ε_x = σ/E, ε_y = ε_z = -νσ/E.
    """
    size = np.array([1.0, 0.5, 0.4])
    model = Model(gravity=(0.0, 0.0, 0.0))
    model.add_material("rock", Material(2500.0, young, poisson))
    model.add_polyhedron(*box((0, 0, 0), size), "rock")
    force = stress * size[1] * size[2] / 4
    for y in (0.0, size[1]):
        for z in (0.0, size[2]):
            model.add_point_load((size[0], y, z), (force, 0.0, 0.0), block=0)
            model.add_point_load((0.0, y, z), (-force, 0.0, 0.0), block=0)
    result = run(model, RunSettings(dt=1e-3, n_steps=steps, method=method, rho_inf=0.0), keep_history=False)
    state = result.final_state
    assert state is not None  # run() leaves its final state
    strain = np.ptp(state.vertices, axis=0) / size - 1.0
    drift = float(np.linalg.norm(state.moments.centroid[0] - size / 2))
    return [Measured("axial strain", method, float(strain[0]), stress / young),
            Measured("lateral strain y", method, float(strain[1]), -poisson * stress / young),
            Measured("lateral strain z", method, float(strain[2]), -poisson * stress / young),
            Measured("centroid drift (m)", method, drift, 0.0)]

