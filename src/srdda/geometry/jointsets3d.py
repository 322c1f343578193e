"""Joint planes and discs in 3D: orientations, Fisher scatter, statistical joint sets.

Orientation convention (geological, right-handed): x east, y north, z up.
A plane dipping ``dip`` degrees (0-90, from the horizontal) towards the
azimuth ``dip_direction`` (degrees clockwise from north) has the upward unit
normal

    n = (sin δ sin α, sin δ cos α, cos δ),   δ = dip, α = dip direction,

and its line of steepest descent (the dip vector) is
(cos δ sin α, cos δ cos α, -sin δ). The pole (downward normal) plunges
90° - δ towards α + 180°.

Fisher scatter: the normals of the planes of a set follow Fisher's
distribution on the sphere (density ∝ exp(κ cos θ) about the mean normal),
sampled exactly by inverting its distribution function (N. I. Fisher,
T. Lewis & B. J. J. Embleton, *Statistical Analysis of Spherical Data*,
Cambridge University Press, 1987, p. 59):

    θ = 2 arcsin √(-ln(U (1 - λ) + λ) / (2κ)),  λ = exp(-2κ),  φ = 2π V,

with U, V independent uniforms on (0, 1] from numpy's ``Generator``.

A joint set is a family of parallel planes ``spacing`` apart (a plane passes
through ``origin``). ``persistence`` below 1 makes the joints finite discs of
radius ``radius``: the disc centres on each plane of the set are a Poisson
process (a Boolean model of discs) whose intensity λ = -ln(1 - p) / (π r²)
makes the expected jointed fraction of the plane equal to the areal
persistence p. Each disc then cuts only the blocks it crosses completely
(:mod:`srdda.geometry.cutting3d`).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .cutting2d import CuttingError

__all__ = ["JointPlanes", "JointSet3D", "dip_and_direction", "fisher_directions", "joint_planes", "plane_normal"]


def plane_normal(dip: float | np.ndarray, dip_direction: float | np.ndarray) -> np.ndarray:
    """Upward unit normal(s) (..., 3) of planes of dip / dip direction in degrees (x east, y north, z up)."""
    d, a = np.radians(dip), np.radians(dip_direction)
    return np.stack(np.broadcast_arrays(np.sin(d) * np.sin(a), np.sin(d) * np.cos(a), np.cos(d)), axis=-1)


def dip_and_direction(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Dip and dip direction (degrees) of planes with normal(s) (..., 3), either sense of the normal."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where(n[..., 2:3] < 0, -n, n)  # the upward normal
    dip = np.degrees(np.arccos(np.clip(n[..., 2], -1.0, 1.0)))
    direction = np.degrees(np.arctan2(n[..., 0], n[..., 1])) % 360.0
    return dip, direction


def _orthonormal_frame(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the unit ``axis`` to a right-handed frame (e1, e2, axis)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(axis, e1)


def fisher_directions(mean: ArrayLike, kappa: float, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` unit vectors (n, 3) from Fisher's distribution about ``mean`` with concentration ``kappa`` > 0.

    Exact inversion of the distribution of the angle θ to the mean (Fisher,
    Lewis & Embleton 1987, p. 59; see the module docstring); the azimuth
    about the mean is uniform.
    """
    if not kappa > 0:
        raise CuttingError(f"Fisher concentration kappa must be > 0, got {kappa}")
    mu = np.asarray(mean, dtype=float)
    mu = mu / np.linalg.norm(mu)
    u = 1.0 - rng.random(n)  # (0, 1]
    v = rng.random(n)
    lam = np.exp(-2.0 * kappa)
    theta = 2.0 * np.arcsin(np.sqrt(np.clip(-np.log(u * (1.0 - lam) + lam) / (2.0 * kappa), 0.0, 1.0)))
    phi = 2.0 * np.pi * v
    e1, e2 = _orthonormal_frame(mu)
    s = np.sin(theta)
    return (s * np.cos(phi))[:, None] * e1 + (s * np.sin(phi))[:, None] * e2 + np.cos(theta)[:, None] * mu


@dataclass(frozen=True)
class JointPlanes:
    """Joint planes and discs: unit ``normal`` (k, 3), a ``point`` (k, 3) of each (a disc's centre),
    ``radius`` (k,) (``inf``: an infinite plane) and integer ``joint_type`` (k,) labelling the faces it makes."""

    normal: np.ndarray
    point: np.ndarray
    radius: np.ndarray
    joint_type: np.ndarray

    @classmethod
    def of(cls, normal: ArrayLike, point: ArrayLike, radius: ArrayLike = np.inf,
           joint_type: ArrayLike = 1) -> JointPlanes:
        """Validated joints; ``radius`` and ``joint_type`` may be one value for all."""
        n = np.asarray(normal, dtype=float).reshape(-1, 3) if np.size(normal) else np.zeros((0, 3))
        p = np.asarray(point, dtype=float).reshape(-1, 3) if np.size(point) else np.zeros((0, 3))
        if len(n) != len(p):
            raise CuttingError(f"joints: {len(n)} normals but {len(p)} points")
        if not (np.all(np.isfinite(n)) and np.all(np.isfinite(p))):
            raise CuttingError("joints: normals and points must be finite numbers")
        length = np.linalg.norm(n, axis=1)
        if np.any(length == 0):
            raise CuttingError(f"joints: joint {int(np.flatnonzero(length == 0)[0])} has a zero normal")
        r = np.broadcast_to(np.asarray(radius, dtype=float), (len(n),)).copy()
        if np.any(~(r > 0)):
            raise CuttingError(f"joints: a disc radius must be > 0, got {r[~(r > 0)][0]}")
        t = np.broadcast_to(np.asarray(joint_type), (len(n),))
        if len(t) and not np.issubdtype(t.dtype, np.integer):
            raise CuttingError("joints: joint_type must be integers")
        return cls(n / length[:, None], p, r, t.astype(np.int64))

    @classmethod
    def concatenate(cls, parts: Sequence[JointPlanes]) -> JointPlanes:
        if not parts:
            return cls.of(np.zeros((0, 3)), np.zeros((0, 3)))
        return cls(*(np.concatenate([getattr(j, f) for j in parts]) for f in ("normal", "point", "radius",
                                                                             "joint_type")))

    def __len__(self) -> int:
        return len(self.normal)


@dataclass(frozen=True)
class JointSet3D:
    """One joint set in 3D; angles in degrees (dip 0-90, dip direction clockwise from north), lengths in m.

    ``kappa``: Fisher concentration of the normals (None: no scatter).
    ``persistence``: areal persistence p in (0, 1]; below 1 the joints are
    discs of ``radius`` (required then) placed as a Boolean model.
    ``spacing_sd``: standard deviation of the normal spacing (normal
    scatter of each plane's offset).
    """

    dip: float
    dip_direction: float
    spacing: float
    kappa: float | None = None
    persistence: float = 1.0
    radius: float | None = None
    joint_type: int = 1
    origin: tuple[float, float, float] = field(default=(0.0, 0.0, 0.0))
    spacing_sd: float = 0.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.dip <= 90.0:
            raise CuttingError(f"joint set dip must be within 0-90 degrees, got {self.dip}")
        if not np.isfinite(self.dip_direction):
            raise CuttingError(f"joint set dip_direction must be a finite angle, got {self.dip_direction}")
        if not self.spacing > 0:
            raise CuttingError(f"joint set spacing must be > 0, got {self.spacing}")
        if self.kappa is not None and not self.kappa > 0:
            raise CuttingError(f"joint set kappa must be > 0 (or None: no scatter), got {self.kappa}")
        if not 0.0 < self.persistence <= 1.0:
            raise CuttingError(f"joint set persistence must be in (0, 1], got {self.persistence}")
        if self.persistence < 1.0 and self.radius is None:
            raise CuttingError("joint set with persistence < 1 needs the disc radius")
        if self.radius is not None and not (self.radius > 0 and self.persistence < 1.0):
            raise CuttingError(f"joint set radius must be > 0 and goes with persistence < 1 (persistence 1: "
                               f"infinite planes), got radius {self.radius}, persistence {self.persistence}")
        if not self.spacing_sd >= 0:
            raise CuttingError(f"joint set spacing_sd must be >= 0, got {self.spacing_sd}")

    @property
    def normal(self) -> np.ndarray:
        return plane_normal(self.dip, self.dip_direction)


def _set_joints(points: np.ndarray, js: JointSet3D, rng: np.random.Generator) -> JointPlanes:
    """The planes (or discs) of one set whose nominal plane lies within the points' extent along the normal."""
    n = js.normal
    o = np.asarray(js.origin, dtype=float)
    h = (points - o) @ n
    first, last = np.floor(h.min() / js.spacing) - 1, np.ceil(h.max() / js.spacing) + 1
    offsets = np.arange(first, last + 1) * js.spacing
    if js.spacing_sd > 0:
        offsets = offsets + rng.normal(0.0, js.spacing_sd, len(offsets))
    offsets = offsets[(offsets >= h.min()) & (offsets <= h.max())]  # nominal planes meeting the points' extent
    base = o + offsets[:, None] * n  # a point of each nominal plane
    if js.persistence == 1.0:
        normals = np.tile(n, (len(base), 1)) if js.kappa is None else fisher_directions(n, js.kappa, len(base), rng)
        return JointPlanes.of(normals, base, np.inf, js.joint_type)
    assert js.radius is not None  # JointSet3D's check: persistence < 1 comes with a radius
    r = float(js.radius)
    e1, e2 = _orthonormal_frame(n)
    uv = np.column_stack([(points - o) @ e1, (points - o) @ e2])
    lo, hi = uv.min(axis=0) - r, uv.max(axis=0) + r
    intensity = -np.log1p(-js.persistence) / (np.pi * r * r)  # Boolean model: covered fraction = p
    counts = rng.poisson(intensity * np.prod(hi - lo), len(base))
    k = int(counts.sum())
    uv_c = lo + rng.random((k, 2)) * (hi - lo)
    centres = np.repeat(base, counts, axis=0) + uv_c[:, :1] * e1 + uv_c[:, 1:] * e2
    normals = np.tile(n, (k, 1)) if js.kappa is None else fisher_directions(n, js.kappa, k, rng)
    return JointPlanes.of(normals, centres, r, js.joint_type)


def joint_planes(points: object, sets: Sequence[JointSet3D], seed: int | None = 0) -> JointPlanes:
    """Planes / discs of every set covering ``points`` (m, 3) (e.g. the domain's vertices).

    The same ``seed`` gives the same joints; sets draw from one generator in order.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(pts) == 0 or not np.all(np.isfinite(pts)):
        raise CuttingError("joint_planes: points must be finite [x, y, z] triples (the domain's vertices)")
    rng = np.random.default_rng(seed)
    return JointPlanes.concatenate([_set_joints(pts, js, rng) for js in sets])
