"""Joint traces from statistical joint sets, and openings (tunnels).

A joint set in a 2D section is a family of parallel traces: inclination
``dip`` (degrees, counter-clockwise from the +x axis, the convention of the
DDA slope files: 25° rises to the right, 100° leans left), perpendicular
``spacing``, ``trace_length`` (None: persistent, crossing the whole domain)
and ``bridge`` (intact rock between collinear traces). Seeded random
perturbations: normal scatter of spacing, dip and trace length, and a random
shift of each trace line along itself. Traces are clipped to the domain with
shapely (vectorised), so they can be fed to :func:`srdda.geometry.cutting2d.cut_blocks`.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from .cutting2d import CuttingError

__all__ = ["JointSet", "circular_opening", "joint_traces", "polygonal_opening"]


@dataclass(frozen=True)
class JointSet:
    """One joint set; lengths in m, angles in degrees; ``*_sd`` are standard deviations."""

    dip: float
    spacing: float
    trace_length: float | None = None
    bridge: float = 0.0
    joint_type: int = 1
    origin: tuple[float, float] = (0.0, 0.0)  # a point one trace line passes through (before scatter)
    spacing_sd: float = 0.0
    dip_sd: float = 0.0
    trace_length_sd: float = 0.0

    def __post_init__(self) -> None:
        if not self.spacing > 0:
            raise CuttingError(f"joint set spacing must be > 0, got {self.spacing}")
        if self.trace_length is not None and not self.trace_length > 0:
            raise CuttingError(f"joint set trace_length must be > 0 or None, got {self.trace_length}")
        if not self.bridge >= 0:
            raise CuttingError(f"joint set bridge must be >= 0, got {self.bridge}")
        for name in ("spacing_sd", "dip_sd", "trace_length_sd"):
            if not getattr(self, name) >= 0:
                raise CuttingError(f"joint set {name} must be >= 0, got {getattr(self, name)}")


def _set_segments(domain: shapely.Polygon, js: JointSet, rng: np.random.Generator) -> np.ndarray:
    """Unclipped traces (k, 4) of one set covering the domain's bounding circle."""
    theta = np.radians(js.dip)
    u = np.array([np.cos(theta), np.sin(theta)])  # along the traces
    n = np.array([-u[1], u[0]])  # normal: spacing direction
    c = np.asarray(domain.centroid.coords[0])
    x0, y0, x1, y1 = domain.bounds
    radius = 0.5 * np.hypot(x1 - x0, y1 - y0) + js.spacing
    o = np.asarray(js.origin, dtype=float)
    first = np.floor(((c - o) @ n - radius) / js.spacing)
    last = np.ceil(((c - o) @ n + radius) / js.spacing)
    offsets = (np.arange(first, last + 1) * js.spacing)
    offsets = offsets + rng.normal(0.0, js.spacing_sd, len(offsets)) if js.spacing_sd > 0 else offsets
    base = o + offsets[:, None] * n  # a point of each trace line
    along_c = (c - base) @ u  # the domain centre's position along each line
    span = 2.0 * radius
    if js.trace_length is None:
        starts = (along_c - radius)[:, None]
        lengths = np.full_like(starts, span)
    else:
        period = js.trace_length + js.bridge
        m = int(np.ceil(span / period)) + 1
        phase = rng.uniform(0.0, period, len(offsets))
        starts = (along_c - radius - phase)[:, None] + np.arange(m)[None, :] * period
        lengths = np.full_like(starts, js.trace_length)
        if js.trace_length_sd > 0:
            lengths = np.maximum(lengths + rng.normal(0.0, js.trace_length_sd, lengths.shape), 0.0)
    p0 = base[:, None, :] + starts[..., None] * u
    p1 = p0 + lengths[..., None] * u
    segs = np.concatenate([p0, p1], axis=-1).reshape(-1, 4)
    segs = segs[lengths.ravel() > 0]
    if js.dip_sd > 0:  # rotate each trace about its midpoint
        d = np.radians(rng.normal(0.0, js.dip_sd, len(segs)))
        mid = 0.5 * (segs[:, :2] + segs[:, 2:])
        half = 0.5 * (segs[:, 2:] - segs[:, :2])
        rot = np.stack([half[:, 0] * np.cos(d) - half[:, 1] * np.sin(d),
                        half[:, 0] * np.sin(d) + half[:, 1] * np.cos(d)], axis=1)
        segs = np.hstack([mid - rot, mid + rot])
    return segs


def joint_traces(domain: object, sets: Sequence[JointSet], seed: int | None = 0) -> tuple[np.ndarray, np.ndarray]:
    """Traces of all sets clipped to ``domain``: segments (k, 4) and their joint types (k,).

    ``domain`` is a polygon (vertices or a shapely Polygon, openings allowed
    as holes). The same ``seed`` gives the same traces.
    """
    poly = domain if isinstance(domain, shapely.Polygon) else shapely.Polygon(np.asarray(domain, dtype=float))
    if not poly.is_valid or poly.area <= 0:
        raise CuttingError("joint_traces: domain is not a simple polygon of positive area")
    rng = np.random.default_rng(seed)
    all_segs, all_types = [], []
    for js in sets:
        segs = _set_segments(poly, js, rng)
        clipped = shapely.intersection(shapely.linestrings(segs.reshape(-1, 2, 2)), poly)
        parts = shapely.get_parts(clipped)
        parts = parts[(shapely.get_type_id(parts) == 1) & (shapely.length(parts) > 0)]
        coords, idx = shapely.get_coordinates(parts, return_index=True)
        same = idx[1:] == idx[:-1]
        pieces = np.hstack([coords[:-1][same], coords[1:][same]])
        all_segs.append(pieces)
        all_types.append(np.full(len(pieces), js.joint_type, dtype=np.int64))
    if not all_segs:
        return np.zeros((0, 4)), np.zeros(0, dtype=np.int64)
    return np.vstack(all_segs), np.concatenate(all_types)


def circular_opening(center: Sequence[float], radius: float, n_sides: int = 48) -> np.ndarray:
    """Vertices (n_sides, 2) of a regular polygon inscribed in a circle: a circular tunnel."""
    if not radius > 0:
        raise CuttingError(f"circular opening radius must be > 0, got {radius}")
    if n_sides < 3:
        raise CuttingError(f"circular opening needs n_sides >= 3, got {n_sides}")
    a = np.linspace(0.0, 2.0 * np.pi, n_sides, endpoint=False)
    return np.asarray(center, dtype=float) + radius * np.column_stack([np.cos(a), np.sin(a)])


def polygonal_opening(vertices: object) -> np.ndarray:
    """Validated vertices of a polygonal opening (e.g. a horseshoe tunnel)."""
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3 or not np.all(np.isfinite(v)):
        raise CuttingError("polygonal opening: a list of at least three finite [x, y] vertices")
    poly = shapely.Polygon(v)
    if not poly.is_valid or poly.area <= 0:
        raise CuttingError(f"polygonal opening is not simple ({shapely.is_valid_reason(poly)})")
    return v
