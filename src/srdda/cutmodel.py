"""Cut blocks added to a :class:`~srdda.model.Model`: 2D (:class:`~srdda.geometry.cutting2d.BlockCut`) and 3D
(:class:`~srdda.geometry.cutting3d.PolyhedralCut`)."""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .geometry.cutting2d import NO_JOINT, BlockCut
from .geometry.cutting3d import PolyhedralCut
from .model import Model, ModelError

__all__ = ["add_cut_blocks", "add_cut_polyhedra"]


def _fixed_flags(fixed: Sequence[bool] | np.ndarray | None, n_blocks: int) -> np.ndarray:
    """One checked fixed flag per cut block (none given: all free)."""
    flags = np.zeros(n_blocks, dtype=bool) if fixed is None else np.asarray(fixed, dtype=bool)
    if flags.shape != (n_blocks,):
        raise ModelError(f"fixed needs one flag per block ({n_blocks}), got {flags.shape}")
    return flags


def _joint_names(types: np.ndarray, joints: Mapping[int, str | None]) -> list[str | None]:
    """The joint material named for each edge's or face's joint type (None: by the block materials)."""
    return [None if t == NO_JOINT else joints.get(int(t)) for t in types]


def add_cut_blocks(model: Model, cut: BlockCut, materials: Mapping[int, str],
                   joints: Mapping[int, str | None] | None = None,
                   fixed: Sequence[bool] | np.ndarray | None = None, prefix: str = "block",
                   names: Sequence[str] | None = None) -> list[int]:
    """Add every block of ``cut`` to ``model``; returns their indices.

    ``materials`` maps the cut's material labels to the model's material
    names; ``joints`` maps joint types to joint-material names (a type not
    listed, and edges on no joint, take the joint chosen by the block
    materials). ``fixed`` marks blocks that never move. ``names``: each
    block's name (default ``"{prefix} {index}"``; a stage removes a group of
    them by a pattern, e.g. ``"tunnel*"``).
    """
    joints = {} if joints is None else dict(joints)
    missing = sorted(set(np.unique(cut.block_material).tolist()) - set(materials))
    if missing:
        raise ModelError(f"cut blocks use material label(s) {missing} with no entry in materials")
    fixed_arr = _fixed_flags(fixed, cut.n_blocks)
    if names is None:
        names = [f"{prefix} {b}" for b in range(cut.n_blocks)]
    elif len(names) != cut.n_blocks:
        raise ModelError(f"names: expected {cut.n_blocks} block names, got {len(names)}")
    out = []
    for b in range(cut.n_blocks):
        verts, types = cut.block(b)
        edge_joints = _joint_names(types, joints)
        out.append(model.add_block(verts, materials[int(cut.block_material[b])], name=names[b],
                                   fixed=bool(fixed_arr[b]),
                                   edge_joints=edge_joints if any(j is not None for j in edge_joints) else None))
    return out


def add_cut_polyhedra(model: Model, cut: PolyhedralCut, materials: str | Mapping[int, str],
                      fixed: Sequence[bool] | np.ndarray | None = None, prefix: str = "block",
                      joints: Mapping[int, str | None] | None = None) -> list[int]:
    """Add every block of a 3D cut to ``model``; returns their indices.

    ``materials``: one material name for all blocks, or a map from the
    domain part index (``cut.block_part``) to a material name. ``fixed``
    marks blocks that never move. ``joints`` maps joint types
    (``cut.face_joint``) to joint-material names, as :func:`add_cut_blocks`
    does in 2D: a face on a joint of a listed type takes that joint
    material; other faces take the one chosen by the block materials.
    """
    by_part = {int(p): materials for p in np.unique(cut.block_part)} if isinstance(materials, str) \
        else dict(materials)
    missing = sorted(set(np.unique(cut.block_part).tolist()) - set(by_part))
    if missing:
        raise ModelError(f"cut blocks come from domain part(s) {missing} with no entry in materials")
    fixed_arr = _fixed_flags(fixed, cut.n_blocks)
    joints = {} if joints is None else dict(joints)
    face_joints = None
    if joints:
        named = _joint_names(cut.face_joint, joints)
        face_joints = [named[cut.face_first[b]:cut.face_first[b + 1]] for b in range(cut.n_blocks)]
    return model.add_polyhedra(cut.blocks(), [by_part[int(p)] for p in cut.block_part],
                               [f"{prefix} {b}" for b in range(cut.n_blocks)], fixed_arr.tolist(), face_joints)
