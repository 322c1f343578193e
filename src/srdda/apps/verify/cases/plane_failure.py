"""Plane failure with water (Hoek & Bray): the closed forms and a model that reproduces them.

A block of weight W rests on a plane dipping ψ (friction φ, cohesion c over
the sliding area A); water pushes it off the plane with the uplift U (the
resultant of the pressure on the sliding plane) and down the slope with V
(the resultant of the water in the tension crack behind it, a vertical crack:
horizontal). Limit equilibrium along the plane (E. Hoek & J. W. Bray, *Rock
Slope Engineering*, 3rd ed., IMM, London, 1981, ch. 7; D. C. Wyllie & C. W.
Mah, *Rock Slope Engineering*, 4th ed., 2004, ch. 6):

    FS = [c·A + (W cos ψ − U − V sin ψ) tan φ] / (W sin ψ + V cos ψ)

and, where FS < 1, the block slides down the plane with

    a = [W sin ψ + V cos ψ − (W cos ψ − U − V sin ψ) tan φ − c·A] / m.

Both hold for any U and V: Hoek & Bray's crack filled to z_w with the water
draining at the toe (U = ½γ_w z_w A, V = ½γ_w z_w²) is one case, a phreatic
surface parallel to the plane (a uniform head h on it: U = γ_w h A) another.

:func:`wet_plane_model` builds the 2D block (per metre of thickness): a
parallelogram whose base of length L lies on a fixed incline through the
origin (its toe at the origin), with vertical faces of height H at the toe and
at the back (the crack's face), so that its weight acts over the middle of its
base and the release does not rock it; the phreatic surface is parallel to the incline, the
uniform ``head`` above it (vertical), so U and V stay the same as it slides.
:func:`set_hoek_bray_water` gives it Hoek & Bray's water instead (docs/water.md).
"""
from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from scipy.optimize import brentq

from srdda.constraints.water import UNIT_WEIGHT
from srdda.geometry.polygon import BlockMoments, block_moments
from srdda.model import JointMaterial, Material, Model

__all__ = ["plane_failure_factor", "plane_failure_acceleration", "wet_plane_model", "wet_plane_forces",
           "set_hoek_bray_water", "PlaneFailure", "PLANE_FAILURE", "plane_failure_water_forces", "plane_failure_model",
           "PLANE_DIP", "PLANE_G", "BASE_LENGTH", "CRACK_HEIGHT", "DENSITY"]

G = 9.81  # m/s², Hoek & Bray's slope (PlaneFailure)
PLANE_DIP, PLANE_G = 30.0, 10.0  # ψ (°), g (m/s²)
BASE_LENGTH, CRACK_HEIGHT, DENSITY = 2.0, 1.0, 2500.0  # L, H (m), ρ (kg/m³)


def plane_failure_factor(weight: float, dip: float, friction: float, uplift: float = 0.0, crack: float = 0.0,
                         cohesion: float = 0.0, area: float = 0.0) -> float:
    """Hoek & Bray's FS of plane failure (module doc); ``dip``, ``friction`` in degrees, forces in N (per m in
    2D), ``cohesion`` Pa over the sliding ``area`` (m², m in 2D)."""
    psi, tan_phi = np.radians(dip), np.tan(np.radians(friction))
    normal = weight * np.cos(psi) - uplift - crack * np.sin(psi)
    return float((cohesion * area + normal * tan_phi) / (weight * np.sin(psi) + crack * np.cos(psi)))


def plane_failure_acceleration(mass: float, weight: float, dip: float, friction: float, uplift: float = 0.0,
                               crack: float = 0.0, cohesion: float = 0.0, area: float = 0.0) -> float:
    """The sliding block's acceleration down the plane (m/s², module doc); meaningful where FS < 1."""
    psi, tan_phi = np.radians(dip), np.tan(np.radians(friction))
    normal = weight * np.cos(psi) - uplift - crack * np.sin(psi)
    driving = weight * np.sin(psi) + crack * np.cos(psi)
    return float((driving - normal * tan_phi - cohesion * area) / mass)


def _corners() -> np.ndarray:
    """The block's corners: toe, crack bottom, crack top, top of the toe's face."""
    c, s = np.cos(np.radians(PLANE_DIP)), np.sin(np.radians(PLANE_DIP))
    bottom = BASE_LENGTH * np.array([c, s])
    top = bottom + [0.0, CRACK_HEIGHT]
    return np.array([[0.0, 0.0], bottom, top, [0.0, CRACK_HEIGHT]])


def wet_plane_model(friction: float, head: float | None = None, crack_depth: float = 0.0,
                    young: float = 1e9) -> Model:
    """The 2D block on the incline (module doc) with joint friction ``friction`` (°); water: a phreatic surface
    ``head`` m (vertically) above the incline (None: dry) and the crack filled ``crack_depth`` m deep."""
    c, s = np.cos(np.radians(PLANE_DIP)), np.sin(np.radians(PLANE_DIP))
    m = Model(gravity=(0.0, -PLANE_G))
    m.add_material("rock", Material(density=DENSITY, young=young, poisson=0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=friction), between=[("rock", "rock")])
    turn = np.array([[c, -s], [s, c]])
    m.add_block((np.array([[-6.0, -1.0], [6.0, -1.0], [6.0, 0.0], [-6.0, 0.0]]) @ turn.T).tolist(), "rock",
                fixed=True, name="incline")
    corners = _corners()
    m.add_block(corners.tolist(), "rock", name="block")
    if head is not None:
        cracks = [(corners[1], (1.0, 0.0), crack_depth)] if crack_depth > 0.0 else []
        m.set_water(point=(0.0, head), normal=(-s, c), unit_weight=UNIT_WEIGHT, cracks=cracks)
    return m


def wet_plane_forces(head: float | None, crack_depth: float) -> tuple[float, float, float, float]:
    """(W, m, U, V) of :func:`wet_plane_model`, per metre of thickness: U = γ_w·h·L, V = ½γ_w·z_w²."""
    corners = _corners()
    x, y = corners[:, 0], corners[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    mass = DENSITY * area
    uplift = 0.0 if head is None else UNIT_WEIGHT * max(head, 0.0) * BASE_LENGTH
    crack = 0.0 if head is None else 0.5 * UNIT_WEIGHT * crack_depth**2
    return mass * PLANE_G, mass, uplift, crack


def set_hoek_bray_water(model: Model, crack_depth: float, block: np.ndarray | None = None) -> None:
    """Hoek & Bray's water on a plane-failure block: the crack filled ``crack_depth`` (z_w) deep and the phreatic
    line from its water surface to the toe, so the pressure on the sliding plane falls linearly from γ_w·z_w at
    the crack to 0 at the toe (U = ½γ_w·z_w·L, V = ½γ_w·z_w²). ``block``: the sliding block's corners, its toe
    first and the foot of its vertical crack second (:meth:`PlaneFailure.vertices`); None: the block of
    :func:`wet_plane_model`."""
    corners = _corners() if block is None else np.asarray(block, dtype=float)
    toe, bottom = corners[0], corners[1]
    rise = bottom[1] + crack_depth - toe[1]
    model.set_water(point=toe, normal=(-rise, bottom[0] - toe[0]), unit_weight=UNIT_WEIGHT,
                    cracks=[(bottom, (1.0, 0.0), crack_depth)])


# Hoek & Bray's slope with a dry tension crack (srdda fos: docs/factor-of-safety.md)
def plane_failure_water_forces(length: float, water_depth: float, gamma_water: float = UNIT_WEIGHT
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
            return float(_moments(v).centroid[0, 0]) - 0.5 * x

        return float(brentq(off, h / tf * (1 + 1e-9), h / tp * (1 - 1e-9), xtol=1e-12))

    @property
    def weight(self) -> float:
        """W (N per metre of slope)."""
        return float(self.density * G * _moments(self.vertices()).area[0])

    @property
    def length(self) -> float:
        """A, the length of the sliding plane (m)."""
        return float(np.hypot(*self.vertices()[1]))

    @property
    def crack_depth(self) -> float:
        """z, the depth of the tension crack (m)."""
        v = self.vertices()
        return float(v[2, 1] - v[1, 1])

    def water_forces(self, water_depth: float) -> tuple[float, float]:
        """(U, V) (N/m) of Hoek & Bray's water, the crack filled ``water_depth`` z_w deep
        (:func:`plane_failure_water_forces` over this block's sliding plane)."""
        return plane_failure_water_forces(self.length, water_depth)

    def factor_of_safety(self, uplift: float = 0.0, crack_force: float = 0.0) -> float:
        """Hoek & Bray's FS of this block (dry unless water forces are given)."""
        return plane_failure_factor(self.weight, self.plane, self.friction, uplift, crack_force, self.cohesion,
                                    self.length)


PLANE_FAILURE = PlaneFailure()


def _moments(v: np.ndarray) -> BlockMoments:
    return block_moments(v, np.array([0, len(v)]))


def plane_failure_model(case: PlaneFailure = PLANE_FAILURE, young: float = 10e9,
                        water_depth: float | None = None) -> Model:
    """The sliding block ("block") on the fixed rock under the plane ("rock"), joint "plane" between them.

    The rock is a slab 5 m deep whose top is the sliding plane, from 2 m before
    the toe to 3 m behind the crack; the crack face and the slope face touch
    nothing (a dry crack carries no force). ``water_depth`` z_w: Hoek & Bray's
    water (:func:`set_hoek_bray_water`), the crack filled z_w deep (at most its
    depth) and the phreatic line from there to the toe; None: dry.
    """
    v = case.vertices()
    if water_depth is not None and not 0.0 <= water_depth <= case.crack_depth:
        raise ValueError(f"water_depth: must lie in [0, {case.crack_depth:g}] m (the crack's depth), got {water_depth}")
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
    if water_depth is not None:
        set_hoek_bray_water(model, water_depth, v)
    return model
