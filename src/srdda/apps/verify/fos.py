"""The factor-of-safety cases: ``srdda fos`` against Hoek & Bray's closed forms (docs/verification.md)."""
from __future__ import annotations

import numpy as np

from .cases.plane_failure import PLANE_FAILURE, plane_failure_model
from .cases.slope3d import (WEDGE_PLANES, hoek_bray_wedge_angles, hoek_bray_wedge_factor_of_safety, wedge_friction_for,
                             wedge_model, wedge_solution, wedge_water_forces, wet_wedge_factor_of_safety)
from ..fos import FactorOfSafety, factor_of_safety, try_factor
from ...integrators.methods import MethodName
from ...model import JointMaterial, Model
from ...settings import RunSettings
from .registry import Row, case, row
from .water import contact_water_forces, crack_water_force

__all__: list[str] = []

# The bound on FS against the closed form: 2 %. The bracket's tolerance (0.5 % of F) puts its
# middle within 0.25 % of where the model fails; the rest is the model's own error (measured below).
FOS_BOUND = 0.02
MARGIN_FACTORS = (0.98, 1.02)  # the runs that show how far from the decision the criterion is


def _margin_rows(name: str, model: Model, settings: RunSettings, fos: FactorOfSafety) -> list[Row]:
    """The runs at 0.98 and 1.02 × the measured FS: the verdict (a checked row) and the measure (information)."""
    arrays = model.arrays()
    every_joint = np.arange(len(model.joint_materials) + 1)
    rows: list[Row] = []
    for k in MARGIN_FACTORS:
        trial = try_factor(arrays, settings, every_joint, k * fos.factor_of_safety, fos.criterion)
        # the verdict is exact: stable (0) below FS, failed (1) above
        rows.append(row(name, f"failed at {k:g} FS (1 = yes)", "srdda", float(trial.failed), float(k > 1), 0.0))
        rows.append(row(name, f"growth over the last window / rest threshold ({trial.threshold:.2g} m) at {k:g} FS",
                        "srdda", trial.growth / trial.threshold, 1.0, None))
        if trial.failed:  # a settled run has no rate: it gained nothing over either window
            rows.append(row(name, f"rate ratio growth / previous window at {k:g} FS (decision at "
                                  f"{fos.criterion.decay:g})", "srdda", trial.rate_ratio, fos.criterion.decay, None))
    return rows


def _fos_rows(name: str, label: str, model: Model, settings: RunSettings, exact: float) -> list[Row]:
    """``srdda fos`` of ``model`` against the closed form ``exact`` (checked to FOS_BOUND), its bracket and its
    margin runs."""
    fos = factor_of_safety(model, settings)
    return [row(name, label, "srdda", fos.factor_of_safety, exact, FOS_BOUND),
            row(name, "bracket width / F", "srdda", (fos.failed - fos.stable) / fos.stable, fos.tolerance, None),
            *_margin_rows(name, model, settings, fos)]


# ---------------------------------------------------------------------------------------------
# fos-plane-2d: Hoek & Bray's plane failure (srdda.apps.verify.cases.plane_failure: a 12 m slope, face 60°, sliding plane
# 30° daylighting at the toe, a dry tension crack where the weight's line of action meets the middle of
# the plane, c = 20 kPa, φ = 25°: FS = 1.2092). The block is 100 × stiffer than the contacts (E = 1e12 Pa,
# k_n = 1e10 N/m): the bond is lost where a contact slides, so an elastic block whose strain loads one end
# of the plane more than the other loses its cohesion end by end, before the closed form's whole-plane
# failure (information row at E = 10 GPa: 1.7 % low).
PLANE_SETTINGS = RunSettings(dt=1e-3, n_steps=1, contact_penalty=1e10)
PLANE_YOUNG, PLANE_SOFT_YOUNG = 1e12, 10e9


@case("fos-plane-2d", dim=2, methods=("srdda",),
      description="srdda fos of Hoek & Bray's plane failure (c, φ, dry tension crack) against the closed form")
def fos_plane_2d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    exact = PLANE_FAILURE.factor_of_safety()
    model = plane_failure_model(PLANE_FAILURE, young=PLANE_YOUNG)
    soft = factor_of_safety(plane_failure_model(PLANE_FAILURE, young=PLANE_SOFT_YOUNG), PLANE_SETTINGS)
    return [*_fos_rows("fos-plane-2d", "FS, dry (E = 1e12 Pa)", model, PLANE_SETTINGS, exact),
            row("fos-plane-2d", "FS, dry, elastic block E = 10 GPa", "srdda", soft.factor_of_safety, exact, None)]


# ---------------------------------------------------------------------------------------------
# fos-wedge-3d: the wedge of wedge-3d (srdda.apps.verify.cases.slope3d.wedge_model: planes 40/130 and 60/220, face 70/160)
# with the friction of FS 1.2 by Hoek & Bray's wedge solution, dry, no cohesion; k_n = 1e11 N/m.
# Information row: the same wedge with c = 5 kPa, φ = 25° on both planes against Hoek & Bray's short solution
# (FS 1.036): a 3D joint's cohesion acts at the corner contacts of the wedge's faces and is lost contact by
# contact as each slides, and a vertex of the rock under a plane that touches the wedge's face adds its own
# faces' area to the bond (docs/factor-of-safety.md, *Cohesion*): measured 7 % low.
WEDGE_FACTOR = 1.2
WEDGE_SETTINGS = RunSettings(dt=1e-3, n_steps=1, penalty=1e11)
WEDGE_COHESION, WEDGE_COHESIVE_FRICTION = 5e3, 25.0
WEDGE_HEIGHT = 6.0  # m, wedge_model's default


@case("fos-wedge-3d", dim=3, methods=("srdda",),
      description="srdda fos of the tetrahedral wedge (friction of FS 1.2) against Hoek & Bray's wedge solution")
def fos_wedge_3d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    phi = wedge_friction_for(WEDGE_FACTOR)
    exact = wedge_solution(*WEDGE_PLANES, phi).factor_of_safety
    cohesive = wedge_model(WEDGE_COHESIVE_FRICTION)
    cohesive.add_joint_material("joint", JointMaterial(WEDGE_COHESIVE_FRICTION, WEDGE_COHESION))  # replaces its joint
    short_solution = hoek_bray_wedge_factor_of_safety(hoek_bray_wedge_angles(), WEDGE_HEIGHT, WEDGE_COHESIVE_FRICTION,
                                                      WEDGE_COHESIVE_FRICTION, WEDGE_COHESION, WEDGE_COHESION)
    return [*_fos_rows("fos-wedge-3d", "FS, dry", wedge_model(phi), WEDGE_SETTINGS, exact),
            row("fos-wedge-3d", f"FS, dry, c = {WEDGE_COHESION / 1e3:g} kPa, φ = {WEDGE_COHESIVE_FRICTION:g}°",
                "srdda", factor_of_safety(cohesive, WEDGE_SETTINGS).factor_of_safety, short_solution, None)]


# ---------------------------------------------------------------------------------------------
# fos-plane-wet-2d: fos-plane-2d's slope with Hoek & Bray's water (srdda.apps.verify.cases.plane_failure.set_hoek_bray_water):
# the tension crack filled to its top, z_w = 1.663 m (the most water their model puts in this slope), the
# phreatic line from the crack's water surface to the toe: U = ½γ_w·z_w·A = 168.6 kN/m, V = ½γ_w·z_w² =
# 13.6 kN/m, FS 1.2092 dry → 1.1170 wet (−7.6 %). The model's water forces at the start equal U and V: the
# contacts' shares of the base's exact wetted integral and the crack face's (round-off, measured 8.6e-16 and 0).
# srdda fos measured 0.5 % low: V acts a third of the way up the crack's water, off the plane, and its moment
# about the plane's middle (78 kN·m/m) leaves the heel's contact 7.5 kN/m less compressed than the toe's, so
# the heel loses its cohesion first (0.3 % of the resisting force; with c = 0, φ = 35° the same water gives
# −0.1 %, inside the bracket).
PLANE_WATER_IDENTITY = 1e-12


@case("fos-plane-wet-2d", dim=2, methods=("srdda",),
      description="srdda fos of Hoek & Bray's plane failure, tension crack full (U, V), against the closed form")
def fos_plane_wet_2d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    name, depth = "fos-plane-wet-2d", PLANE_FAILURE.crack_depth
    uplift, crack = PLANE_FAILURE.water_forces(depth)
    model = plane_failure_model(PLANE_FAILURE, young=PLANE_YOUNG, water_depth=depth)
    arrays = model.arrays()
    _, water = contact_water_forces(arrays, PLANE_SETTINGS)
    return [row(name, "uplift on the plane U (N/m) = ½γ_w·z_w·A", "-", float(np.sum(water)), uplift,
                PLANE_WATER_IDENTITY),
            row(name, "crack force V (N/m) = ½γ_w·z_w²", "-", crack_water_force(arrays), crack,
                PLANE_WATER_IDENTITY),
            row(name, "FS wet / FS dry, Hoek & Bray", "-", PLANE_FAILURE.factor_of_safety(uplift, crack)
                / PLANE_FAILURE.factor_of_safety(), 1.0, None),
            *_fos_rows(name, f"FS, crack full (z_w = {depth:.3f} m), E = 1e12 Pa", model, PLANE_SETTINGS,
                       PLANE_FAILURE.factor_of_safety(uplift, crack))]


# ---------------------------------------------------------------------------------------------
# fos-wedge-wet-3d: fos-wedge-3d's wedge (friction of FS 1.2 dry) with water in its two sliding planes up to a
# horizontal level 3 m above the toe (half the wedge's height): the wet part of each face is the triangle at the
# toe cut by the level (srdda.apps.verify.cases.slope3d.wedge_water_forces: U_A = 131.4 kN, U_B = 56.3 kN), normal to its
# plane, so the driving force W sin ψ_i stays and each plane carries N_i − U_i: FS 1.2 → 1.0732
# (wet_wedge_factor_of_safety). Hoek & Bray's own distribution (zero on the outcropping edges, ½γ_w·H on the line of
# intersection) is no plane surface. The water acts only on the joints (contacts), none on the free faces: the
# level stands 3 m up the slope face, where the water would run out unless the face were sealed (or frozen,
# as Hoek & Bray discuss for a blocked drainage); a pool standing against the face would push on its wet part
# too, which the model leaves out (docs/water.md). The contacts' water on each plane equals U_A, U_B at the start
# (the exact wetted integrals shared among the wedge's corners: round-off, measured 0 and 7.8e-16).
WEDGE_LEVEL = 3.0  # m
WEDGE_WATER_IDENTITY = 1e-12


@case("fos-wedge-wet-3d", dim=3, methods=("srdda",),
      description="srdda fos of the wedge, water to 3 m in its planes, against (N_i − U_i) tan φ / (W sin ψ_i)")
def fos_wedge_wet_3d(methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    name, phi = "fos-wedge-wet-3d", wedge_friction_for(WEDGE_FACTOR)
    model = wedge_model(phi)
    model.set_water(level=WEDGE_LEVEL)
    uplift = wedge_water_forces(WEDGE_LEVEL, WEDGE_HEIGHT)
    record, water = contact_water_forces(model.arrays(), WEDGE_SETTINGS)
    rows = []
    for block, plane, u in ((1, "A", uplift[0]), (2, "B", uplift[1])):  # the blocks under planes A and B
        on = (record.block_a == block) | (record.block_b == block)
        rows.append(row(name, f"water on plane {plane}, U_{plane} (N)", "-", float(np.sum(water[on])), u,
                        WEDGE_WATER_IDENTITY))
    exact = wet_wedge_factor_of_safety(phi, phi, *uplift, WEDGE_HEIGHT)
    return [*rows, row(name, "FS wet / FS dry, closed form", "-", exact / WEDGE_FACTOR, 1.0, None),
            *_fos_rows(name, f"FS, water level {WEDGE_LEVEL:g} m", model, WEDGE_SETTINGS, exact)]
