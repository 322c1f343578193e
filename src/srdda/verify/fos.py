"""The factor-of-safety cases: ``srdda fos`` against Hoek & Bray's closed forms (docs/verification.md)."""
from __future__ import annotations

import numpy as np

from ..cases.plane2d import PLANE_FAILURE, plane_failure_model
from ..cases.slope3d import (WEDGE_PLANES, hoek_bray_wedge_angles, hoek_bray_wedge_factor_of_safety, wedge_friction_for,
                             wedge_model, wedge_solution)
from ..fos import FactorOfSafety, factor_of_safety, try_factor
from ..model import JointMaterial, Model
from ..settings import RunSettings
from .registry import Row, case, row

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


# ---------------------------------------------------------------------------------------------
# fos-plane-2d: Hoek & Bray's plane failure (srdda.cases.plane2d: a 12 m slope, face 60°, sliding plane
# 30° daylighting at the toe, a dry tension crack where the weight's line of action meets the middle of
# the plane, c = 20 kPa, φ = 25°: FS = 1.2092). The block is 100 × stiffer than the contacts (E = 1e12 Pa,
# k_n = 1e10 N/m): the bond is lost where a contact slides, so an elastic block whose strain loads one end
# of the plane more than the other loses its cohesion end by end, before the closed form's whole-plane
# failure (information row at E = 10 GPa: 1.7 % low).
PLANE_SETTINGS = RunSettings(dt=1e-3, n_steps=1, contact_penalty=1e10)
PLANE_YOUNG, PLANE_SOFT_YOUNG = 1e12, 10e9


@case("fos-plane-2d", dim=2, methods=("srdda",),
      description="srdda fos of Hoek & Bray's plane failure (c, φ, dry tension crack) against the closed form")
def fos_plane_2d(methods: tuple[str, ...], quick: bool) -> list[Row]:
    exact = PLANE_FAILURE.factor_of_safety()
    model = plane_failure_model(PLANE_FAILURE, young=PLANE_YOUNG)
    fos = factor_of_safety(model, PLANE_SETTINGS)
    soft = factor_of_safety(plane_failure_model(PLANE_FAILURE, young=PLANE_SOFT_YOUNG), PLANE_SETTINGS)
    return [row("fos-plane-2d", "FS, dry (E = 1e12 Pa)", "srdda", fos.factor_of_safety, exact, FOS_BOUND),
            row("fos-plane-2d", "bracket width / F", "srdda", (fos.failed - fos.stable) / fos.stable,
                fos.tolerance, None),
            row("fos-plane-2d", "FS, dry, elastic block E = 10 GPa", "srdda", soft.factor_of_safety, exact, None),
            *_margin_rows("fos-plane-2d", model, PLANE_SETTINGS, fos)]


# ---------------------------------------------------------------------------------------------
# fos-wedge-3d: the wedge of wedge-3d (srdda.cases.slope3d.wedge_model: planes 40/130 and 60/220, face 70/160)
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
def fos_wedge_3d(methods: tuple[str, ...], quick: bool) -> list[Row]:
    phi = wedge_friction_for(WEDGE_FACTOR)
    exact = wedge_solution(*WEDGE_PLANES, phi).factor_of_safety
    model = wedge_model(phi)
    fos = factor_of_safety(model, WEDGE_SETTINGS)
    cohesive = wedge_model(WEDGE_COHESIVE_FRICTION)
    cohesive.add_joint_material("joint", JointMaterial(WEDGE_COHESIVE_FRICTION, WEDGE_COHESION))  # replaces its joint
    short_solution = hoek_bray_wedge_factor_of_safety(hoek_bray_wedge_angles(), WEDGE_HEIGHT, WEDGE_COHESIVE_FRICTION,
                                                      WEDGE_COHESIVE_FRICTION, WEDGE_COHESION, WEDGE_COHESION)
    return [row("fos-wedge-3d", "FS, dry", "srdda", fos.factor_of_safety, exact, FOS_BOUND),
            row("fos-wedge-3d", "bracket width / F", "srdda", (fos.failed - fos.stable) / fos.stable,
                fos.tolerance, None),
            *_margin_rows("fos-wedge-3d", model, WEDGE_SETTINGS, fos),
            row("fos-wedge-3d", f"FS, dry, c = {WEDGE_COHESION / 1e3:g} kPa, φ = {WEDGE_COHESIVE_FRICTION:g}°",
                "srdda", factor_of_safety(cohesive, WEDGE_SETTINGS).factor_of_safety, short_solution, None)]

