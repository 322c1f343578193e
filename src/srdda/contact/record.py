"""The contact record: what a detector gives for the contacts of one configuration, in either dimension.

A contact joins a point x_a of block a and a point x_b of block b along the
unit normal n (outward from b) and has a shear frame of k = dim - 1 unit
vectors in its plane (2D: the edge's tangent; 3D: e1, e2). The shear spring
joins two material points r_a, r_b, each an anchor plus a combination of axes
with the k reference coordinates of the spring:

    r = anchor + Σ_j reference_j · axis_j

(2D: r_a the vertex, r_b a point of the edge at edge parameter reference_0;
3D vertex-face: r_b a point of the face in its frame; 3D edge-edge: r_a, r_b
points of the two edges at edge parameters reference_0, reference_1). With the
method's shape functions T the end-of-step normal gap and shear are, to
first order in the step's unknowns Δd (Shi 1988, ch. 4; Shi 2001),

    g_n = g_0 + n·(T_a(x_a) Δd_a − T_b(x_b) Δd_b)
    s_j = s_j0 + e_j·(T_a(r_a) Δd_a − T_b(r_b) Δd_b),     j < k.

Everything downstream (:mod:`.pipeline`: the contact set, step and term; the
contact law; the springs) reads the record's arrays and never asks which
detector made it: the frame width k is data, not a branch.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ContactRecord", "match_previous"]


@dataclass(frozen=True)
class ContactRecord:
    """n contacts in the configuration at the start of a step (module doc)."""

    features: np.ndarray  # (n, f) int64: the detector's own description (which vertex, edge, face)
    key: np.ndarray  # (n,) int64: one number per contact, the same while the same features touch
    block_a: np.ndarray  # (n,)
    block_b: np.ndarray  # (n,)
    point_a: np.ndarray  # (n, dim) x_a
    point_b: np.ndarray  # (n, dim) x_b, the foot of x_a on b
    normal: np.ndarray  # (n, dim) unit, outward from b
    frame: np.ndarray  # (n, k, dim) unit shear directions
    gap: np.ndarray  # (n,) n·(x_a − x_b); negative: penetration
    start_reference: np.ndarray  # (n, k) the reference of a shear spring that starts unstretched now
    anchor_a: np.ndarray  # (n, dim)
    axes_a: np.ndarray  # (n, k, dim)
    anchor_b: np.ndarray  # (n, dim)
    axes_b: np.ndarray  # (n, k, dim)
    joint: np.ndarray  # (n,) int64 row of the model's joint table
    bond: np.ndarray  # (n,) length (2D) or area (3D) over which cohesion and tensile strength act
    tributary: np.ndarray  # (n,) length (2D) or area (3D) of joint a contact stands for (stiffness per area)
    draggable: np.ndarray  # (n,) bool: a sliding contact's spring may be carried at its strength (3D vertex-face)
    # the faces of a that make up each bond: (contact (m,), face (m,): 2D the edge's start vertex, 3D the mesh
    # face, share (m,): 1 / the face's vertex count), so bond = Σ share × face size (the water, docs/water.md)
    bond_faces: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.key)

    @property
    def frame_width(self) -> int:
        """k: shear components of a contact (1 in 2D, 2 in 3D)."""
        return self.frame.shape[1]

    def reference_points(self, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The shear spring's material points (r_a, r_b), each (n, dim), for references (n, k)."""
        r_a = self.anchor_a + np.einsum("nk,nki->ni", reference, self.axes_a)
        r_b = self.anchor_b + np.einsum("nk,nki->ni", reference, self.axes_b)
        return r_a, r_b

    def reference_shift(self, shear_change: np.ndarray, rows: np.ndarray | slice = slice(None)) -> np.ndarray:
        """The change of the references that changes the springs' shears by ``shear_change`` (one row per
        contact of ``rows``, all by default): M·Δρ = Δs with M_ji = e_j·(axes_a_i − axes_b_i) (2D: −|edge|;
        vertex-face: minus the face's two edges; edge-edge: the two edges seen in the frame), in the
        configuration of the record."""
        m = np.einsum("nji,nki->njk", self.frame[rows], self.axes_a[rows] - self.axes_b[rows])
        return np.linalg.solve(m, shear_change[..., None])[..., 0]

    def shear(self, reference: np.ndarray) -> np.ndarray:
        """Shear (n, k) of springs at ``reference``: r_a − r_b in the frame."""
        r_a, r_b = self.reference_points(reference)
        return np.einsum("nki,ni->nk", self.frame, r_a - r_b)


def match_previous(new_keys: np.ndarray, old_keys: np.ndarray) -> np.ndarray:
    """For each new key the index of the same key among ``old_keys`` (-1 if new): one ``searchsorted``.

    A contact found again at the next step keeps its state, reference point,
    normal force and bond (Shi 1988: contact transfer).
    """
    if len(old_keys) == 0:
        return np.full(len(new_keys), -1, dtype=np.int64)
    order = np.argsort(old_keys, kind="stable")
    sorted_keys = old_keys[order]
    pos = np.minimum(np.searchsorted(sorted_keys, new_keys), len(sorted_keys) - 1)
    found = sorted_keys[pos] == new_keys
    return np.where(found, order[pos], -1)
