"""The water cases: plane failure with water against Hoek & Bray's closed form, and the uplift on a submerged
contact (docs/verification.md, docs/water.md)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .cases.plane_failure import (BASE_LENGTH, PLANE_DIP, plane_failure_acceleration, plane_failure_factor,
                                   set_hoek_bray_water, wet_plane_forces, wet_plane_model)
from ...constraints.water import UNIT_WEIGHT, WaterCrackTerm
from ...contact.pipeline import ContactModel
from ...contact.record import ContactRecord
from ...contact.water import contact_water
from ...geometry.facets import boundary_simplices
from ...integrators.methods import MethodName
from ...model import JointMaterial, Material, Model, ModelArrays
from ...results import Result
from ...settings import RunSettings
from ...simulation import run
from ...step import contact_parameters, model_half_height
from .registry import Row, case, row

__all__: list[str] = []

# ---------------------------------------------------------------------------------------------
# water-plane-2d / -3d: the block of srdda.apps.verify.cases.plane_failure (L = 2 m base on a 30° incline, 1 m high
# vertical faces, the back one the crack's, 2500 kg/m³, g = 10) with joint friction 40°: dry FS = 1.45; wet
# (a phreatic surface 0.6 m above the incline, the crack full: U = 11,772 N/m, V = 4905 N/m) FS = 0.754,
# sliding; a little water (0.05 m, the crack 0.2 m deep) FS = 1.40, at rest. (With 0.1 m of water the 3D
# block's vertex-face contacts slip for a few steps at the release and relock with their springs dragged at
# their strength: dissipated_contact falls by 0.055 J and the energy watch says so, as it does for a dry
# block that rocks at its release; docs/water.md.) Δt = 1 ms, 1000 steps, contact penalty 1e10 N/m
# (per m in 2D; 5e9 per contact in 3D, four contacts for two). 3D: the model extruded 1 m, rigid (E = 1e14 Pa:
# a prism's extra strain unknowns settle into the contacts differently, contacts3d.py's extruded-incline-3d).
FRICTION = 40.0
SLIDING = (0.6, 1.0)  # head above the incline, crack depth (m)
RESTING = (0.05, 0.2)
PLANE_STEPS, PLANE_DT, PLANE_PENALTY = 1000, 1e-3, 1e10
# The sliding acceleration is the change of the block's speed from 0.5 s to 1 s over 0.5 s: the release
# (water and weight put on contacts with no force yet) rocks the block on its two contact lines for the
# first tenths of a second (the crack's resultant acts a third of the way up its face), which the travel
# 2d/t² would carry (measured 1.6e-2 off at 1 s), the speed's slope not. Then the block's speed follows the
# closed form to the contact springs' settling (measured 3.1e-6 in 2D, 3.5e-6 in 3D); a model that left out
# the crack's force or the uplift would be off by 11 % or 23 %.
PLANE_ACCELERATION = 1e-4
# At rest (FS 1.45 dry, 1.40 with a little water): the travel in 1 s is the contact springs' deflection and the rocking
# of the release (~1e-5 m: W = 4.3e4 N/m on k_n = 1e10 N/m, k_s = 0.4 k_n; measured 1.5e-5 m in 2D,
# 3.3e-6 m in 3D); a block that slipped travels decimetres (the wet one 0.7 m).
PLANE_AT_REST = 1e-4  # m


# Hoek & Bray's water on the same block (srdda.apps.verify.cases.plane_failure.set_hoek_bray_water: the crack 1 m deep, the
# phreatic line from its water surface to the toe): at the start the uplift is ½γ_w·z_w·L and the crack's force
# ½γ_w·z_w², an identity of the contacts' shares of the wetted faces' exact integrals (the base's and the crack's):
# round-off (measured 0 in 2D, 1.9e-16 in 3D).
HOEK_BRAY_DEPTH = 1.0
HOEK_BRAY_IDENTITY = 1e-12


def _completed(result: Result, what: str) -> Result:
    if not result.completed:
        raise RuntimeError(f"{what}: the run did not complete ({result.status})")
    return result


def _plane_run(model: Model, method: MethodName, dim: int, what: str) -> Result:
    penalty = PLANE_PENALTY if dim == 2 else PLANE_PENALTY / 2
    settings = RunSettings(dt=PLANE_DT, n_steps=PLANE_STEPS, method=method, penalty=penalty)
    return _completed(run(model if dim == 2 else model.extruded(1.0), settings), what)


def _plane_model(dim: int, water: tuple[float, float] | None) -> Model:
    young = 1e9 if dim == 2 else 1e14
    if water is None:
        return wet_plane_model(FRICTION, young=young)
    return wet_plane_model(FRICTION, water[0], water[1], young=young)


def contact_water_forces(arrays: ModelArrays, settings: RunSettings) -> tuple[ContactRecord, np.ndarray]:
    """The contacts of ``arrays`` as built (with ``settings``' contact parameters) and their water forces, N (per m
    in 2D)."""
    contacts = ContactModel(arrays, contact_parameters(arrays, settings, model_half_height(arrays.vertex_position)))
    step = contacts.prepare(arrays.vertex_position, None, True)
    assert step is not None and arrays.water is not None
    return step.record, contact_water(arrays.water, step.record, contacts.params.distance, arrays.vertex_position,
                                      boundary_simplices(arrays))


def _contact_water(arrays: ModelArrays, penalty: float) -> float:
    """Σ of the water forces of the contacts of ``arrays`` as built, N (per m in 2D)."""
    return float(np.sum(contact_water_forces(arrays, RunSettings(dt=PLANE_DT, n_steps=1, penalty=penalty))[1]))


def crack_water_force(arrays: ModelArrays) -> float:
    """|Σ| of the tension cracks' water forces on the blocks of ``arrays`` as built, N (per m in 2D)."""
    _, _, forces = WaterCrackTerm(arrays).resultants(arrays, arrays.vertex_position)
    return float(np.linalg.norm(np.sum(forces, axis=0)))


def _hoek_bray_rows(name: str, dim: int) -> list[Row]:
    model = wet_plane_model(FRICTION)
    set_hoek_bray_water(model, HOEK_BRAY_DEPTH)
    arrays = (model if dim == 2 else model.extruded(1.0)).arrays()
    uplift = _contact_water(arrays, PLANE_PENALTY)
    crack = crack_water_force(arrays)
    return [row(name, "Hoek & Bray's uplift U (N/m) = ½γ_w·z_w·L", "-", uplift,
                0.5 * UNIT_WEIGHT * HOEK_BRAY_DEPTH * BASE_LENGTH, HOEK_BRAY_IDENTITY),
            row(name, "Hoek & Bray's crack force V (N/m) = ½γ_w·z_w²", "-", crack,
                0.5 * UNIT_WEIGHT * HOEK_BRAY_DEPTH**2, HOEK_BRAY_IDENTITY)]


def _plane_rows(name: str, dim: int, methods: tuple[MethodName, ...]) -> list[Row]:
    rows = _hoek_bray_rows(name, dim)
    weight, mass, _, _ = wet_plane_forces(None, 0.0)
    dry_fs = plane_failure_factor(weight, PLANE_DIP, FRICTION)
    _, _, u, v = wet_plane_forces(*SLIDING)
    wet_fs = plane_failure_factor(weight, PLANE_DIP, FRICTION, u, v)
    exact = plane_failure_acceleration(mass, weight, PLANE_DIP, FRICTION, u, v)
    _, _, u_rest, v_rest = wet_plane_forces(*RESTING)
    rest_fs = plane_failure_factor(weight, PLANE_DIP, FRICTION, u_rest, v_rest)
    for method in methods:
        for label, water, fs in (("dry", None, dry_fs), ("little water", RESTING, rest_fs)):
            res = _plane_run(_plane_model(dim, water), method, dim, f"{name} {label} {method}")
            c = res.array("centroid")[:, 1]
            rows.append(row(name, f"travel in 1 s (m), {label}, FS = {fs:.3f}", method,
                            float(np.linalg.norm(c[-1] - c[0])), 0.0, PLANE_AT_REST))
        res = _plane_run(_plane_model(dim, SLIDING), method, dim, f"{name} wet {method}")
        speed = np.linalg.norm(res.array("velocity")[:, 1, :dim], axis=1)
        half = int(np.searchsorted(res.time, 0.5 * res.time[-1]))
        measured = (speed[-1] - speed[half]) / (res.time[-1] - res.time[half])
        rows.append(row(name, f"acceleration (m/s²), wet, FS = {wet_fs:.3f}", method, measured, exact,
                        PLANE_ACCELERATION))
    return rows


@case("water-plane-2d", dim=2, methods=("dda1", "srdda"),
      description="plane failure with water: Hoek & Bray's U and V; dry and a little water at rest, wet sliding at a")
def water_plane_2d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    return _plane_rows("water-plane-2d", 2, methods)


@case("water-plane-3d", dim=3, methods=("dda1", "srdda"),
      description="water-plane-2d's block extruded: at rest dry and with a little water, wet sliding at a")
def water_plane_3d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    return _plane_rows("water-plane-3d", 3, methods)


# ---------------------------------------------------------------------------------------------
# water-uplift-2d / -3d: a 2 m wide, 1 m high block (2D; 2 x 2 x 1 m in 3D), 2500 kg/m³, g = 10, rigid
# (E = 1e14 Pa), resting on a wider fixed base, the water 2 m above the contact: p = 19,620 Pa under a weight
# of 25,000 Pa, so the joint stays closed with N' = W − U.
UPLIFT_LEVEL = 2.0  # m above the contact
# The water forces of the contacts sum to p × the contact's length (area): their bonds share
# the face exactly; measured to round-off (1e-16).
UPLIFT_IDENTITY = 1e-12
# After 200 steps of 1 ms the contacts' normal forces hold the block's weight less the uplift: what the
# springs carry is N' = W − U, to the block's oscillation on them after its release, which Shi's step damps
# slowly (measured 9.8e-7 relative in 2D, 2.0e-6 in 3D); a joint that ignored the water would carry W,
# 2.3 times as much.
UPLIFT_EFFECTIVE = 1e-5
UPLIFT_STEPS = 200


def _uplift_model(dim: int) -> Model:
    """The block on its base, the water ``UPLIFT_LEVEL`` above the contact (y = 0 in 2D, z = 0 in 3D)."""
    if dim == 2:
        m = Model(gravity=(0.0, -10.0))
        m.add_material("rock", Material(density=2500.0, young=1e14, poisson=0.25))
        m.add_block([[-3.0, -1.0], [3.0, -1.0], [3.0, 0.0], [-3.0, 0.0]], "rock", fixed=True, name="base")
        m.add_block([[-1.0, 0.0], [1.0, 0.0], [1.0, 1.0], [-1.0, 1.0]], "rock", name="block")
    else:
        m = Model(gravity=(0.0, 0.0, -10.0))
        m.add_material("rock", Material(density=2500.0, young=1e14, poisson=0.25))
        m.add_box((-3.0, -3.0, -1.0), (3.0, 3.0, 0.0), "rock", fixed=True, name="base")
        m.add_box((-1.0, -1.0, 0.0), (1.0, 1.0, 1.0), "rock", name="block")
    m.add_joint_material("joint", JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.set_water(level=UPLIFT_LEVEL)
    return m


def _uplift_rows(name: str, dim: int, methods: tuple[MethodName, ...]) -> list[Row]:
    model = _uplift_model(dim)
    arrays = model.arrays()
    area = 2.0 if dim == 2 else 4.0
    pressure = UNIT_WEIGHT * UPLIFT_LEVEL
    penalty = 1e10 if dim == 2 else 5e9
    settings = RunSettings(dt=1e-3, n_steps=UPLIFT_STEPS, penalty=penalty)
    rows = [row(name, "Σ contact water forces / (p × area)", "-", _contact_water(arrays, penalty) / (pressure * area),
                1.0, UPLIFT_IDENTITY)]
    weight = float(arrays.block_mass[1]) * 10.0
    for method in methods:
        res = _completed(run(model, replace(settings, method=method)), f"{name} {method}")
        assert res.final_state is not None and res.final_state.contacts is not None
        carried = float(np.sum(res.final_state.contacts.normal_force))
        rows.append(row(name, "Σ normal force of the contacts (N), W − p·A", method, carried,
                        weight - pressure * area, UPLIFT_EFFECTIVE))
    return rows


@case("water-uplift-2d", dim=2, methods=("dda1", "srdda"),
      description="a block on a submerged joint: the water force is p × length; the joint carries W − U")
def water_uplift_2d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    return _uplift_rows("water-uplift-2d", 2, methods)


@case("water-uplift-3d", dim=3, methods=("dda1", "srdda"),
      description="a box on a submerged joint: the water force is p × area; the joint carries W − U")
def water_uplift_3d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    return _uplift_rows("water-uplift-3d", 3, methods)
