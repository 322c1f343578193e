"""Specifications of hinges, pins, springs and prescribed motion, and their flat arrays.

The :class:`~srdda.model.Model` keeps lists of the specs below; ``Model.arrays``
puts every point into the model's attached points (``ModelArrays.attached``,
which the time loop moves with their blocks) and compiles :class:`ConstraintArrays`, which
indexes those rows. Units SI.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields

import numpy as np

from ..history import MotionHistory

__all__ = ["HingeSpec", "SpringSpec", "PrescribedSpec", "BoltSpec", "ConstraintArrays", "compile_links", "links_to_flat",
           "links_from_flat"]


@dataclass(frozen=True)
class HingeSpec:
    """Point ``point_a`` of block ``block_a`` stays on point ``point_b`` of ``block_b`` (-1: the ground).

    ``correct_drift``: the constraint rows ask T_a·Δd_a - T_b·Δd_b = -(x_a - x_b),
    closing any separation left from earlier steps; False gives the paper's
    Eq. 72 (right-hand side 0), which lets a linearisation error accumulate.
    """

    block_a: int
    point_a: np.ndarray
    block_b: int
    point_b: np.ndarray
    correct_drift: bool = True
    name: str = ""


@dataclass(frozen=True)
class SpringSpec:
    """A linear spring (N/m) between two block points, with an optional dashpot (N·s/m).

    ``kind="axial"``: the force acts along the line of the two points,
    k·(ℓ - rest_length) (rest_length None: the initial distance).
    ``kind="offset"``: the force is k·(x_a - x_b - r0) in both directions, r0
    the initial separation vector (a DDA point spring with a rest offset;
    r0 = 0 ties the points together).
    """

    block_a: int
    point_a: np.ndarray
    block_b: int
    point_b: np.ndarray
    stiffness: float
    rest_length: float | None = None
    damping: float = 0.0
    kind: str = "axial"


@dataclass(frozen=True)
class PrescribedSpec:
    """A block point driven along ``history``: displacement from its start (m), velocity (m/s) or
    acceleration (m/s², from rest: a shaking table or an earthquake record at a support).

    ``components`` (bool, bool) says which of x and y are prescribed; ``by`` is
    "multiplier" (exact, Lagrange rows) or "penalty" (a spring of
    ``stiffness`` N/m to the moving target; None: the run's penalty).
    """

    block: int
    point: np.ndarray
    history: MotionHistory
    quantity: str = "displacement"
    components: tuple[bool, ...] = (True, True)  # which axes are driven
    by: str = "multiplier"
    stiffness: float | None = None


@dataclass(frozen=True)
class BoltSpec:
    """A rock bolt from ``point_a`` of ``block_a`` to ``point_b`` of ``block_b`` (-1: the ground, fixed in space).

    ``stiffness`` axial (N/m), ``pretension`` (N, the axial force at
    installation), ``strength`` the tensile force (N) beyond which it breaks
    for good (inf: never), ``shear_stiffness`` (N/m) across its initial axis
    (dowel action). See :mod:`srdda.constraints.bolts`.
    """

    block_a: int
    point_a: np.ndarray
    block_b: int
    point_b: np.ndarray
    stiffness: float
    pretension: float = 0.0
    strength: float = np.inf
    shear_stiffness: float = 0.0
    name: str = ""


def _rows() -> np.ndarray:
    return np.zeros(0, dtype=np.int64)


def _no_points() -> np.ndarray:
    """Default of a per-point (n, dim) array: ``__post_init__`` puts (0, dim) zeros of its dtype in its place."""
    return np.zeros((0, 0))


@dataclass(frozen=True)
class ConstraintArrays:
    """Flat arrays of the hinges, springs with dashpots, driven points and bolts.

    Their ``*_rows*`` index the model's attached points (``ModelArrays.attached``); the
    zero-length point springs are not links but attached points' rows
    (``AttachedPoints.point_spring_rows_a``).

    ``dim`` is the number of coordinates of a point: every per-point array has
    ``dim`` columns and a hinge or pin has ``dim`` multiplier rows.
    """

    dim: int
    hinge_rows_a: np.ndarray = field(default_factory=_rows)
    hinge_rows_b: np.ndarray = field(default_factory=_rows)  # pins: the row of the pin's own point
    hinge_block_a: np.ndarray = field(default_factory=_rows)
    hinge_block_b: np.ndarray = field(default_factory=_rows)  # -1 = ground
    hinge_correct: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    hinge_names: tuple[str, ...] = ()
    spring_rows_a: np.ndarray = field(default_factory=_rows)
    spring_rows_b: np.ndarray = field(default_factory=_rows)
    spring_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    spring_damping: np.ndarray = field(default_factory=lambda: np.zeros(0))
    spring_rest: np.ndarray = field(default_factory=lambda: np.zeros(0))  # axial rest length
    spring_offset: np.ndarray = field(default_factory=_no_points)  # (n, dim) offset kind: r0
    spring_axial: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    prescribed_rows: np.ndarray = field(default_factory=_rows)
    prescribed_mask: np.ndarray = field(default_factory=_no_points)  # (n, dim) prescribed components
    prescribed_order: np.ndarray = field(default_factory=_rows)  # 0 displacement, 1 velocity, 2 acceleration
    prescribed_multiplier: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    prescribed_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))  # nan = run's penalty
    prescribed_histories: tuple[MotionHistory, ...] = ()
    prescribed_sources: tuple[tuple[MotionHistory, int], ...] = ()  # distinct (history, order) pairs
    prescribed_source: np.ndarray = field(default_factory=_rows)  # source of each prescribed point
    base_acceleration: MotionHistory | None = None
    bolt_rows_a: np.ndarray = field(default_factory=_rows)
    bolt_rows_b: np.ndarray = field(default_factory=_rows)  # -1: end b on the ground (at bolt_ground)
    bolt_ground: np.ndarray = field(default_factory=_no_points)  # (n, dim) where end b is when it is on the ground
    bolt_axis: np.ndarray = field(default_factory=_no_points)  # (n, dim) initial separation x_a - x_b
    bolt_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bolt_pretension: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bolt_strength: np.ndarray = field(default_factory=lambda: np.zeros(0))  # inf: never breaks
    bolt_shear_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bolt_names: tuple[str, ...] = ()
    bolt_active: np.ndarray | None = None  # (n,) bool: installed (a staged analysis installs bolts); None: all

    def __post_init__(self) -> None:
        for name, dtype in (("spring_offset", float), ("prescribed_mask", bool), ("bolt_ground", float),
                            ("bolt_axis", float)):
            if getattr(self, name) is None or getattr(self, name).shape == (0, 0):
                object.__setattr__(self, name, np.zeros((0, self.dim), dtype=dtype))

    @property
    def n_bolts(self) -> int:
        return len(self.bolt_rows_a)

    @property
    def n_hinges(self) -> int:
        return len(self.hinge_rows_a)

    @property
    def hinged_block_pairs(self) -> np.ndarray:
        """Block pairs (n, 2) joined by a hinge (contacts between them are left out)."""
        linked = self.hinge_block_b >= 0
        return np.column_stack([self.hinge_block_a[linked], self.hinge_block_b[linked]])

    @property
    def n_multipliers(self) -> int:
        """Constraint rows (multipliers) per step: ``dim`` per hinge or pin, then the driven components."""
        return self.dim * self.n_hinges + int(self.prescribed_mask[self.prescribed_multiplier].sum())

    def prescribed_displacement(self, t: float) -> np.ndarray:
        """Prescribed displacement (n, dim) of every prescribed point at time t (from its start).

        Each distinct (history, quantity) source is evaluated once (many support points
        usually share one record) and spread to its points by ``prescribed_source``.
        """
        if not len(self.prescribed_rows):
            return np.zeros((0, self.dim))
        values = np.array([h(t) if order == 0 else h.integral(t) if order == 1 else h.double_integral(t)
                           for h, order in self.prescribed_sources])
        return values[self.prescribed_source]


def compile_links(hinges: list[HingeSpec], springs: list[SpringSpec], prescribed: list[PrescribedSpec],
                  base_acceleration: MotionHistory | None, first_row: int, dim: int, bolts: Sequence[BoltSpec] = ()
                  ) -> tuple[np.ndarray, np.ndarray, ConstraintArrays]:
    """Points (n, dim), their blocks (n,) and the arrays of all links; point rows start at ``first_row``."""
    pts: list[np.ndarray] = []
    owners: list[int] = []

    def add(block: int, point: np.ndarray) -> int:
        pts.append(np.asarray(point, dtype=float))
        owners.append(block)
        return first_row + len(pts) - 1

    ha = np.array([add(h.block_a, h.point_a) for h in hinges], dtype=np.int64)
    hb = np.array([add(h.block_b, h.point_b) if h.block_b >= 0 else ha[i] for i, h in enumerate(hinges)],
                  dtype=np.int64)
    sa = np.array([add(s.block_a, s.point_a) for s in springs], dtype=np.int64)
    sb = np.array([add(s.block_b, s.point_b) for s in springs], dtype=np.int64)
    pr = np.array([add(p.block, p.point) for p in prescribed], dtype=np.int64)
    ba = np.array([add(b.block_a, b.point_a) for b in bolts], dtype=np.int64)
    bb = np.array([add(b.block_b, b.point_b) if b.block_b >= 0 else -1 for b in bolts], dtype=np.int64)
    head = np.array([b.point_a for b in bolts], dtype=float).reshape(-1, dim)
    anchor = np.array([b.point_b for b in bolts], dtype=float).reshape(-1, dim)
    sep = np.array([np.asarray(s.point_a, float) - np.asarray(s.point_b, float) for s in springs]).reshape(-1, dim)
    rest = np.array([np.linalg.norm(sep[i]) if s.rest_length is None else s.rest_length
                     for i, s in enumerate(springs)], dtype=float)
    orders = [("displacement", "velocity", "acceleration").index(p.quantity) for p in prescribed]
    keys: list[tuple[int, int]] = []
    sources: list[tuple[MotionHistory, int]] = []
    for p, order in zip(prescribed, orders):
        if (id(p.history), order) not in keys:
            keys.append((id(p.history), order))
            sources.append((p.history, order))
    links = ConstraintArrays(
        dim=dim,
        hinge_rows_a=ha, hinge_rows_b=hb,
        hinge_block_a=np.array([h.block_a for h in hinges], dtype=np.int64),
        hinge_block_b=np.array([h.block_b for h in hinges], dtype=np.int64),
        hinge_correct=np.array([h.correct_drift for h in hinges], dtype=bool),
        hinge_names=tuple(h.name for h in hinges),
        spring_rows_a=sa, spring_rows_b=sb,
        spring_stiffness=np.array([s.stiffness for s in springs], dtype=float),
        spring_damping=np.array([s.damping for s in springs], dtype=float),
        spring_rest=rest,
        spring_offset=np.where(np.array([s.kind == "offset" for s in springs], bool)[:, None], sep, 0.0),
        spring_axial=np.array([s.kind == "axial" for s in springs], dtype=bool),
        prescribed_rows=pr,
        prescribed_mask=np.array([p.components for p in prescribed], dtype=bool).reshape(-1, dim),
        prescribed_order=np.array(orders, dtype=np.int64),
        prescribed_multiplier=np.array([p.by == "multiplier" for p in prescribed], dtype=bool),
        prescribed_stiffness=np.array([np.nan if p.stiffness is None else p.stiffness for p in prescribed],
                                      dtype=float),
        prescribed_histories=tuple(p.history for p in prescribed),
        prescribed_sources=tuple(sources),
        prescribed_source=np.array([keys.index((id(p.history), order)) for p, order in zip(prescribed, orders)],
                                   dtype=np.int64),
        base_acceleration=base_acceleration,
        bolt_rows_a=ba, bolt_rows_b=bb,
        bolt_ground=np.where((bb < 0)[:, None], anchor, 0.0),
        bolt_axis=head - anchor,
        bolt_stiffness=np.array([b.stiffness for b in bolts], dtype=float),
        bolt_pretension=np.array([b.pretension for b in bolts], dtype=float),
        bolt_strength=np.array([b.strength for b in bolts], dtype=float),
        bolt_shear_stiffness=np.array([b.shear_stiffness for b in bolts], dtype=float),
        bolt_names=tuple(b.name for b in bolts),
    )
    return np.array(pts, dtype=float).reshape(-1, dim), np.array(owners, dtype=np.int64), links


def links_to_flat(links: ConstraintArrays) -> tuple[dict[str, np.ndarray], dict[str, object]]:
    """The links as (arrays by field name, JSON-able histories) for a results file.

    A history given as a Python callable becomes None (a file cannot hold it).
    """
    arrays = {f.name: getattr(links, f.name) for f in fields(links) if isinstance(getattr(links, f.name), np.ndarray)}
    meta = {"hinge_names": list(links.hinge_names), "bolt_names": list(links.bolt_names),
            "sources": [h.to_json() for h, _ in links.prescribed_sources],
            "base_acceleration": (None if links.base_acceleration is None else links.base_acceleration.to_json()),
            "has_base_acceleration": links.base_acceleration is not None}
    return arrays, meta


def links_from_flat(arrays: dict[str, np.ndarray], meta: dict) -> ConstraintArrays:
    """Inverse of :func:`links_to_flat`; raises ValueError if a history was a Python callable."""
    sources_json = meta["sources"]
    if any(s is None for s in sources_json) or (meta["has_base_acceleration"] and meta["base_acceleration"] is None):
        raise ValueError("a prescribed-motion or base-acceleration history is a Python function, "
                         "which a file cannot hold")
    order = np.asarray(arrays["prescribed_order"], dtype=np.int64)
    source = np.asarray(arrays["prescribed_source"], dtype=np.int64)
    hists = [MotionHistory.from_json(s) for s in sources_json]
    sources = tuple((hists[i], int(order[np.flatnonzero(source == i)[0]])) for i in range(len(hists)))
    base = meta["base_acceleration"]
    kwargs = {name: np.asarray(value) for name, value in arrays.items()}
    return ConstraintArrays(dim=kwargs["prescribed_mask"].shape[1], **kwargs, hinge_names=tuple(meta["hinge_names"]),
                            bolt_names=tuple(meta.get("bolt_names", ())),
                            prescribed_histories=tuple(hists[i] for i in source), prescribed_sources=sources,
                            base_acceleration=None if base is None else MotionHistory.from_json(base))
