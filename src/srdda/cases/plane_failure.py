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

from ..constraints.water import UNIT_WEIGHT
from ..model import JointMaterial, Material, Model

__all__ = ["plane_failure_factor", "plane_failure_acceleration", "wet_plane_model", "wet_plane_forces",
           "set_hoek_bray_water",
           "PLANE_DIP", "PLANE_G", "BASE_LENGTH", "CRACK_HEIGHT", "DENSITY"]

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


def set_hoek_bray_water(model: Model, crack_depth: float) -> None:
    """Hoek & Bray's water on :func:`wet_plane_model`'s block: the crack filled ``crack_depth`` (z_w) deep and
    the phreatic line from its water surface to the toe, so the pressure on the sliding plane falls linearly
    from γ_w·z_w at the crack to 0 at the toe (U = ½γ_w·z_w·L, V = ½γ_w·z_w²)."""
    toe, bottom = _corners()[0], _corners()[1]
    rise = bottom[1] + crack_depth - toe[1]
    model.set_water(point=toe, normal=(-rise, bottom[0] - toe[0]), unit_weight=UNIT_WEIGHT,
                    cracks=[(bottom, (1.0, 0.0), crack_depth)])
