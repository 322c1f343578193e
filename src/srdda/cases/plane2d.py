"""Plane failure of a rock slope in 2D: Hoek & Bray's closed form and the model that reproduces it.

E. Hoek & J. W. Bray, *Rock Slope Engineering*, 3rd ed., IMM, London, 1981,
ch. 7 (also D. C. Wyllie & C. W. Mah, *Rock Slope Engineering*, 4th ed.,
Spon, 2004, ch. 6). A block of weight W (per metre of slope) rests on a plane
dipping ψ_p, of length A (per metre), cut at its back by a tension crack of
depth z. With cohesion c, friction φ on the plane, water force U on the plane
(uplift) and V in the crack (pushing horizontally), the factor of safety is

    FS = [c A + (W cos ψ_p − U − V sin ψ_p) tan φ] / (W sin ψ_p + V cos ψ_p).

With the crack filled to depth z_w and the water draining at the toe,
U = ½ γ_w z_w A (triangular pressure along the plane) and V = ½ γ_w z_w².
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..model import JointMaterial, Material, Model

__all__ = ["PlaneFailure", "plane_failure_factor_of_safety", "plane_failure_water_forces", "plane_failure_model",
           "PLANE_FAILURE"]

G = 9.81  # m/s²
GAMMA_WATER = 9810.0  # N/m³, unit weight of water


def plane_failure_factor_of_safety(weight: float, length: float, psi: float, phi: float, cohesion: float,
                                   uplift: float = 0.0, crack_force: float = 0.0) -> float:
    """Hoek & Bray's FS of a block on a plane dipping ``psi`` (°) with friction ``phi`` (°) and cohesion (Pa).

    ``weight`` W (N/m), ``length`` A of the sliding plane (m), ``uplift`` U
    (water force on the plane, N/m) and ``crack_force`` V (water force in the
    tension crack, N/m): FS = [cA + (W cos ψ − U − V sin ψ) tan φ] / (W sin ψ + V cos ψ).
    """
    p, f = np.radians(psi), np.radians(phi)
    resisting = cohesion * length + (weight * np.cos(p) - uplift - crack_force * np.sin(p)) * np.tan(f)
    return float(resisting / (weight * np.sin(p) + crack_force * np.cos(p)))


def plane_failure_water_forces(length: float, water_depth: float, gamma_water: float = GAMMA_WATER
                               ) -> tuple[float, float]:
    """(U, V) (N/m): a tension crack filled to ``water_depth`` z_w draining along the plane of ``length`` A.

    U = ½ γ_w z_w A (pressure falling linearly from γ_w z_w at the crack to 0 at
    the toe), V = ½ γ_w z_w² (hydrostatic in the crack).
    """
    return 0.5 * gamma_water * water_depth * length, 0.5 * gamma_water * water_depth**2


@dataclass(frozen=True)
class PlaneFailure:
    """A slope of height H and face angle ψ_f, a sliding plane ψ_p daylighting at the toe, a vertical crack.

    The top of the slope is horizontal; the crack stands at the horizontal
    distance ``crack_x`` from the toe (None: where the weight's line of action
    meets the middle of the sliding plane, :meth:`balanced_crack_x`).
    """

    height: float = 12.0  # m
    face: float = 60.0  # ψ_f, degrees
    plane: float = 30.0  # ψ_p, degrees
    friction: float = 25.0  # φ, degrees
    cohesion: float = 20e3  # Pa
    density: float = 2600.0  # kg/m³
    crack_x: float | None = None  # m

    def vertices(self, crack_x: float | None = None) -> np.ndarray:
        """The sliding block: toe, foot of the crack, top of the crack, crest (counter-clockwise)."""
        x = self.balanced_crack_x() if crack_x is None and self.crack_x is None else (
            crack_x if crack_x is not None else self.crack_x)
        assert x is not None
        h, tp, tf = self.height, np.tan(np.radians(self.plane)), np.tan(np.radians(self.face))
        if not h / tf < x < h / tp:
            raise ValueError(f"the crack at x = {x:g} m must stand behind the crest ({h / tf:g} m) and in front of "
                             f"where the plane meets the top ({h / tp:g} m)")
        return np.array([[0.0, 0.0], [x, x * tp], [x, h], [h / tf, h]])

    def balanced_crack_x(self) -> float:
        """The crack position whose block has its centroid above the middle of its base.

        There the weight's line of action passes through the middle of the
        sliding plane, so its two end contacts carry the same normal force and
        reach their strength together: the block slides as a whole, as the
        closed form assumes, not by one end losing its cohesion first.
        """
        h, tp, tf = self.height, np.tan(np.radians(self.plane)), np.tan(np.radians(self.face))

        def off(x: float) -> float:
            v = self.vertices(x)
            return _centroid(v)[0] - 0.5 * x

        return float(brentq(off, h / tf * (1 + 1e-9), h / tp * (1 - 1e-9), xtol=1e-12))

    @property
    def weight(self) -> float:
        """W (N per metre of slope)."""
        return self.density * G * _area(self.vertices())

    @property
    def length(self) -> float:
        """A, the length of the sliding plane (m)."""
        return float(np.hypot(*self.vertices()[1]))

    @property
    def crack_depth(self) -> float:
        """z, the depth of the tension crack (m)."""
        v = self.vertices()
        return float(v[2, 1] - v[1, 1])

    def factor_of_safety(self, uplift: float = 0.0, crack_force: float = 0.0) -> float:
        """Hoek & Bray's FS of this block (dry unless water forces are given)."""
        return plane_failure_factor_of_safety(self.weight, self.length, self.plane, self.friction, self.cohesion,
                                              uplift, crack_force)


PLANE_FAILURE = PlaneFailure()


def _area(v: np.ndarray) -> float:
    x, y = v[:, 0], v[:, 1]
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _centroid(v: np.ndarray) -> np.ndarray:
    x, y = v[:, 0], v[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    return np.array([np.sum((x + np.roll(x, -1)) * cross), np.sum((y + np.roll(y, -1)) * cross)]) / (6 * _area(v))


def plane_failure_model(case: PlaneFailure = PLANE_FAILURE, young: float = 10e9) -> Model:
    """The sliding block ("block") on the fixed rock under the plane ("rock"), joint "plane" between them.

    The rock is a slab 5 m deep whose top is the sliding plane, from 2 m before
    the toe to 3 m behind the crack; the crack face and the slope face touch
    nothing (a dry crack carries no force).
    """
    v = case.vertices()
    tp = np.tan(np.radians(case.plane))
    x0, x1 = -2.0, float(v[1, 0]) + 3.0
    model = Model(gravity=(0.0, -G))
    model.add_material("block", Material(density=case.density, young=young, poisson=0.25))
    model.add_material("rock", Material(density=case.density, young=young, poisson=0.25))
    model.add_joint_material("plane", JointMaterial(friction_angle=case.friction, cohesion=case.cohesion),
                             [("block", "rock")])
    model.add_block(v.tolist(), "block", name="block")
    model.add_block([[x0, x0 * tp - 5.0], [x1, x1 * tp - 5.0], [x1, x1 * tp], [x0, x0 * tp]], "rock", name="rock",
                    fixed=True)
    return model
