"""Row buffers that compiled detection loops fill without knowing how many rows they will find."""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["room_for_row"]

GROWTH = 2  # a full buffer is replaced by one this many times as long


@njit(cache=True)
def room_for_row(buf: np.ndarray, n: int) -> np.ndarray:
    """``buf`` if row ``n`` fits in it, else a copy of its first n rows in a buffer twice as long."""
    if n < buf.shape[0]:
        return buf
    bigger = np.empty((GROWTH * buf.shape[0], buf.shape[1]), dtype=buf.dtype)
    bigger[:n] = buf[:n]
    return bigger
