"""Checks of a compiled model that the run would otherwise fail on at its first steps (``srdda check`` runs them).

Both work on the rows of the shape function T at the points where constraints
and springs act, at the start of the run:

* :func:`redundant_constraints`: constraints by Lagrange multipliers (hinges,
  pins, points driven by multipliers) that repeat what earlier ones impose
  (the same hinge twice, a pin given twice, four pins on one block, three on a
  line). Their multipliers are not determined: the saddle-point system is
  singular (exactly so for a repeated one: the run stops with "singular
  system") or its constraint forces are arbitrary. A constraint is compared
  with the earlier ones acting on one of its blocks, so a redundancy that only
  closes around a loop of several blocks is not found.
* :func:`unheld_massless_blocks`: moving blocks without mass (density 0) whose
  rigid motion (translation, rotation) nothing resists at the start: no mass,
  no spring, fixed point or constraint at enough points. Their equations are
  singular. Contacts do not count: the check runs before any contact exists.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..modeldata.arrays import ModelArrays

__all__ = ["redundant_constraints", "unheld_massless_blocks"]

# Rows are scaled to unit length; a constraint whose rows keep less than this of their length once projected off
# the earlier constraints' rows adds nothing (exact repetitions and collinear pins leave ~1e-15).
DEPENDENT = 1e-8


def _shape_rows(arrays: ModelArrays, rows: np.ndarray) -> np.ndarray:
    """Shi's T (n, dim, ndof) at the attached points ``rows``, at the start of the run."""
    centroid = arrays.moments(arrays.vertex_position).centroid
    blocks = arrays.attached.point_block[rows]
    return arrays.block_type.shape(arrays.attached.point_position[rows] - centroid[blocks])


def _multiplier_constraints(arrays: ModelArrays) -> list[tuple[str, dict[int, np.ndarray]]]:
    """Each multiplier constraint as (its name, {moving block: its rows (k, ndof) on that block's unknowns})."""
    links, fixed = arrays.links, arrays.block_fixed
    out: list[tuple[str, dict[int, np.ndarray]]] = []
    if links.n_hinges:
        ta, tb = _shape_rows(arrays, links.hinge_rows_a), _shape_rows(arrays, links.hinge_rows_b)
        for i, (a, b) in enumerate(zip(links.hinge_block_a, links.hinge_block_b)):
            on: dict[int, np.ndarray] = {}
            if not fixed[a]:
                on[int(a)] = ta[i]
            if b >= 0 and not fixed[b]:
                on[int(b)] = -tb[i]
            out.append((links.hinge_names[i] or f"hinge {i}", on))
    driven = np.flatnonzero(links.prescribed_multiplier)
    if len(driven):
        rows = links.prescribed_rows[driven]
        t = _shape_rows(arrays, rows)
        for k, j in enumerate(driven):
            point = tuple(float(c) for c in arrays.attached.point_position[rows[k]])
            block = int(arrays.attached.point_block[rows[k]])
            out.append((f"the point driven at {point}", {block: t[k][links.prescribed_mask[j]]}))
    return out


def _stack(constraints: list[dict[int, np.ndarray]], ndof: int) -> np.ndarray:
    """The rows of ``constraints`` over the unknowns of all their blocks, each row scaled to unit length."""
    blocks = sorted({b for c in constraints for b in c})
    column = {b: k * ndof for k, b in enumerate(blocks)}
    out = []
    for c in constraints:
        rows = np.zeros((len(next(iter(c.values()))), len(blocks) * ndof))
        for b, t in c.items():
            rows[:, column[b]:column[b] + ndof] = t
        out.append(rows)
    m = np.concatenate(out)
    return m / np.maximum(np.linalg.norm(m, axis=1), 1e-300)[:, None]


def _independent(earlier: list[dict[int, np.ndarray]], new: dict[int, np.ndarray], ndof: int) -> bool:
    """True if every row of the constraint ``new`` is independent of the ``earlier`` ones' and of its other rows."""
    rows = _stack([*earlier, new], ndof)
    n_new = len(next(iter(new.values())))
    _, singular, basis = np.linalg.svd(rows[:-n_new], full_matrices=False)
    added = rows[-n_new:] - (rows[-n_new:] @ basis[singular > DEPENDENT].T) @ basis[singular > DEPENDENT]
    return bool(np.linalg.svd(added, compute_uv=False).min() > DEPENDENT)


def redundant_constraints(arrays: ModelArrays) -> list[str]:
    """Messages naming each multiplier constraint that repeats the earlier ones on its blocks (see the module)."""
    constraints = _multiplier_constraints(arrays)
    ndof = arrays.block_type.ndof
    seen_on: dict[int, list[int]] = {}  # block -> earlier constraints acting on it
    problems = []
    for k, (name, on) in enumerate(constraints):
        earlier = sorted({j for b in on for j in seen_on.get(b, [])})
        if on and earlier and not _independent([constraints[j][1] for j in earlier], on, ndof):
            alone = [j for j in earlier if not _independent([constraints[j][1]], on, ndof)]  # a repetition
            named = alone[:1] or earlier
            others = " and ".join(repr(constraints[j][0]) for j in named[:4]) + (" ..." if len(named) > 4 else "")
            problems.append(f"{name!r} repeats what {others} already impose{'s' if len(named) == 1 else ''}")
        for b in on:
            seen_on.setdefault(b, []).append(k)
    return problems


def unheld_massless_blocks(arrays: ModelArrays) -> list[int]:
    """Moving blocks of density 0 whose translation and rotation nothing resists at the start (see the module)."""
    massless = np.flatnonzero((arrays.block_density == 0) & ~arrays.block_fixed)
    if not len(massless):
        return []
    bt, links, attached = arrays.block_type, arrays.links, arrays.attached
    rigid = np.r_[bt.translation, bt.rotation]
    # every point that holds its block: fixed points, spring ends, hinge and pin points, driven points, bolt ends
    full = [attached.fixed_rows, attached.point_spring_rows_a, attached.point_spring_rows_b, links.hinge_rows_a,
            links.hinge_rows_b[links.hinge_block_b >= 0], links.bolt_rows_a[links.bolt_shear_stiffness > 0],
            links.bolt_rows_b[(links.bolt_rows_b >= 0) & (links.bolt_shear_stiffness > 0)],
            links.spring_rows_a[~links.spring_axial], links.spring_rows_b[~links.spring_axial]]
    rows = np.concatenate([r.astype(np.int64) for r in full])
    t = _shape_rows(arrays, rows)[:, :, rigid].reshape(-1, len(rigid))
    owner = np.repeat(attached.point_block[rows], bt.dim)
    # axial springs and bolts hold along their line only, at both ends (a bolt's ground end holds nothing)
    axial_a = np.r_[links.spring_rows_a[links.spring_axial], links.bolt_rows_a]
    axial_b = np.r_[links.spring_rows_b[links.spring_axial], links.bolt_rows_b]
    if len(axial_a):
        ground = np.r_[np.zeros((int(links.spring_axial.sum()), bt.dim)), links.bolt_ground]
        line = attached.point_position[axial_a] - np.where((axial_b >= 0)[:, None],
                                                           attached.point_position[np.maximum(axial_b, 0)], ground)
        line /= np.maximum(np.linalg.norm(line, axis=1), 1e-300)[:, None]
        on_block = axial_b >= 0
        for ends, direction in ((axial_a, line), (axial_b[on_block], line[on_block])):
            t = np.concatenate([t, np.einsum("nd,ndk->nk", direction, _shape_rows(arrays, ends)[:, :, rigid])])
            owner = np.concatenate([owner, attached.point_block[ends]])
    driven = links.prescribed_rows
    if len(driven):
        td = _shape_rows(arrays, driven)[:, :, rigid]
        t = np.concatenate([t, td[links.prescribed_mask]])
        owner = np.concatenate([owner, np.repeat(attached.point_block[driven], links.prescribed_mask.sum(axis=1))])
    out = []
    for b in massless:
        held = t[owner == b]
        if len(held) < len(rigid) or np.linalg.matrix_rank(held, tol=DEPENDENT * max(1.0, np.abs(held).max())) \
                < len(rigid):
            out.append(int(b))
    return out
