"""Contact transfer between steps: a contact is the pair (vertex, edge).

A contact found again at the next step keeps its state, reference point,
normal force and bond (Shi 1988: contact transfer). Keys are
``vertex * n_vertices + edge``; matching is one ``searchsorted``.
"""
from __future__ import annotations

import numpy as np

__all__ = ["contact_keys", "match_previous"]


def contact_keys(vertex: np.ndarray, edge: np.ndarray, n_vertices: int) -> np.ndarray:
    return vertex.astype(np.int64) * n_vertices + edge.astype(np.int64)


def match_previous(new_keys: np.ndarray, old_keys: np.ndarray) -> np.ndarray:
    """For each new key the index of the same key among ``old_keys`` (-1 if new)."""
    if len(old_keys) == 0:
        return np.full(len(new_keys), -1, dtype=np.int64)
    order = np.argsort(old_keys, kind="stable")
    sorted_keys = old_keys[order]
    pos = np.minimum(np.searchsorted(sorted_keys, new_keys), len(sorted_keys) - 1)
    found = sorted_keys[pos] == new_keys
    return np.where(found, order[pos], -1)
