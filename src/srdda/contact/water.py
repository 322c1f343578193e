"""The water force on the joints' contacts (docs/water.md): a contact below the water table carries the water on
the joint area its bond stands for, along its normal (the phreatic surface and its pressure:
:mod:`srdda.constraints.water`).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..constraints.water import PARALLEL, WaterTable, face_pressures

if TYPE_CHECKING:
    from .record import ContactRecord

__all__ = ["one_side", "contact_water"]


def one_side(record: ContactRecord) -> np.ndarray:
    """(n,) bool: the contacts whose bonds make up each joint: those of one side of each block pair, the side
    whose bonds sum less (the lower-numbered block's where they are equal).

    Where two faces overlap in part, the corners of each that lie on the other both give shares of their own
    face (a wedge on a larger slab whose corner touches the wedge's face: 116.8 m² of bond for a 53.6 m²
    face); the smaller face's corners are those that lie on the larger one, and where two equal faces
    coincide either side's corners give the whole."""
    bond = record.bond
    if len(bond) == 0:
        return np.zeros(0, dtype=bool)
    n_blocks = int(max(record.block_a.max(), record.block_b.max())) + 1
    low, high = np.minimum(record.block_a, record.block_b), np.maximum(record.block_a, record.block_b)
    side = (record.block_a == high).astype(np.int64)  # 0: the corner is the lower-numbered block's
    groups, index = np.unique((low * n_blocks + high) * 2 + side, return_inverse=True)
    sums = np.bincount(index, weights=bond, minlength=len(groups))
    sums[sums <= 0.0] = np.inf  # a side without bonds does not count
    _, pair = np.unique(groups // 2, return_inverse=True)
    least = np.full(pair.max() + 1, np.inf)
    np.minimum.at(least, pair, sums)
    first = np.full(len(least), len(groups))  # the first group of each pair at its least sum
    np.minimum.at(first, pair, np.where(sums == least[pair], np.arange(len(groups)), len(groups)))
    return (np.arange(len(groups)) == first[pair])[index]


def contact_water(water: WaterTable, record: ContactRecord, distance: float, vertices: np.ndarray,
                  facets: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """The water force (n,) of every contact of ``record`` at ``vertices``, N (per m in 2D): the water on the
    faces of a that make up its bond (``record.bond_faces``), each face's exact ∫p dA shared among its corners
    as the bond shares its area, from one side of each joint (:func:`one_side`); zero on a crack's plane (a
    contact within ``distance`` of it, its normal along the crack's). ``facets``: ``boundary_simplices``.
    Without ``bond_faces``, p(x_a) × bond."""
    if record.bond_faces is None:
        force = water.pressure(record.point_a) * record.bond
    else:
        owner, face, share = record.bond_faces
        force = np.bincount(owner, weights=share * face_pressures(water, vertices, face, facets),
                            minlength=len(record))
    force = np.where(one_side(record), force, 0.0)
    for crack in water.cracks:  # a few planes, each a whole-array test
        n = np.asarray(crack.normal)
        on = (np.abs((record.point_a - np.asarray(crack.point)) @ n) <= distance) \
            & (np.abs(record.normal @ n) >= PARALLEL)
        force[on] = 0.0
    return force
