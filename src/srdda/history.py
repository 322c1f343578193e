"""Time histories (point loads, prescribed motion, base acceleration): constant, table, sine or callable.

A :class:`TimeHistory` gives a vector (2 components in 2D, 3 in 3D) as a function of time t (s), its
time integral from 0 to t and its double integral ∫₀ᵗ∫₀ˢ = ∫₀ᵗ (t - r)·value(r) dr,
so a velocity or acceleration history becomes a displacement history without
any state (starting from rest): exact for constant, table (piecewise linear:
Simpson's rule is exact for the quadratic integrand of each segment) and sine;
adaptive quadrature (``scipy.integrate.quad``) for a callable.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["TimeHistory", "MotionHistory", "HistoryError"]


class HistoryError(ValueError):
    """A history is given in a form that cannot be read (the message says what is wrong)."""


@dataclass(frozen=True)
class TimeHistory:
    """A vector (x, y) or (x, y, z) as a function of time.

    Exactly one of: ``constant`` (x, y[, z]); ``table`` rows (t, x, y[, z]) with
    strictly increasing t, linear interpolation, held constant outside;
    ``sine``: amplitude (x, y[, z]), ``period`` (s) and ``phase`` (rad), value
    amplitude·sin(2π t / period + phase); ``function`` a callable of t
    returning the vector.
    """

    constant: tuple[float, ...] | None = None
    table: np.ndarray | None = None
    amplitude: tuple[float, ...] | None = None
    period: float | None = None
    phase: float = 0.0
    function: Callable[[float], ArrayLike] | None = None

    def __post_init__(self) -> None:
        given = [self.constant is not None, self.table is not None, self.amplitude is not None,
                 self.function is not None]
        if sum(given) != 1:
            raise HistoryError("a history is exactly one of: constant, table, sine (amplitude + period), function")
        if self.table is not None:
            tab = np.asarray(self.table, dtype=float)
            if tab.ndim != 2 or tab.shape[1] not in (3, 4) or len(tab) < 1:
                raise HistoryError("a history table has rows [t, x, y] (2D) or [t, x, y, z] (3D)")
            if np.any(np.diff(tab[:, 0]) <= 0):
                raise HistoryError("history table times must increase strictly")
            object.__setattr__(self, "table", tab)
        if self.amplitude is not None and not (self.period is not None and 0 < self.period < np.inf):
            raise HistoryError("a sine history needs a finite period > 0 (s)")
        for name in ("constant", "table", "amplitude"):
            value = getattr(self, name)
            if value is not None and not np.all(np.isfinite(np.asarray(value, dtype=float))):
                raise HistoryError(f"a history's {name} must hold finite numbers")

    @staticmethod
    def sine(amplitude: Sequence[float], period: float, phase: float = 0.0) -> TimeHistory:
        return TimeHistory(amplitude=tuple(float(a) for a in amplitude), period=float(period), phase=float(phase))

    @staticmethod
    def of(value: object) -> TimeHistory:
        """A history from a vector (constant), a table of [t, vector] rows, a callable, or a TimeHistory."""
        if isinstance(value, TimeHistory):
            return value
        if callable(value):
            return TimeHistory(function=value)
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 1 and len(arr) in (2, 3):
            return TimeHistory(constant=tuple(float(a) for a in arr))
        if arr.ndim == 2 and arr.shape[1] in (3, 4):
            return TimeHistory(table=arr)
        raise HistoryError("a history is [x, y] or [x, y, z], a table of [t, x, y(, z)] rows, a sine, "
                           "or a callable of t")

    def __call__(self, t: float) -> np.ndarray:
        if self.constant is not None:
            return np.asarray(self.constant, dtype=float)
        if self.table is not None:
            tab = self.table
            return np.array([np.interp(t, tab[:, 0], column) for column in tab[:, 1:].T])
        if self.amplitude is not None:
            assert self.period is not None  # __post_init__: a sine has a period
            return np.asarray(self.amplitude) * np.sin(2.0 * np.pi * t / self.period + self.phase)
        assert self.function is not None  # exactly one form is given
        return np.asarray(self.function(t), dtype=float).ravel()

    def integral(self, t: float) -> np.ndarray:
        """∫₀ᵗ value(s) ds."""
        if self.constant is not None:
            return np.asarray(self.constant, dtype=float) * t
        if self.table is not None:
            return self._table_integral(t)
        if self.amplitude is not None:
            assert self.period is not None  # __post_init__: a sine has a period
            w = 2.0 * np.pi / self.period
            return np.asarray(self.amplitude) * (np.cos(self.phase) - np.cos(w * t + self.phase)) / w
        from scipy.integrate import quad  # only callables need it: keeps start-up fast

        return np.array([quad(lambda s, i=i: self(s)[i], 0.0, t, limit=200)[0] for i in range(len(self(0.0)))])

    def double_integral(self, t: float) -> np.ndarray:
        """∫₀ᵗ ∫₀ˢ value(r) dr ds = ∫₀ᵗ (t - r)·value(r) dr (displacement from rest of an acceleration)."""
        if self.constant is not None:
            return np.asarray(self.constant, dtype=float) * 0.5 * t * t
        if self.table is not None:
            tab = self.table
            lo, hi = min(0.0, t), max(0.0, t)
            knots = np.concatenate([[lo], tab[:, 0][(tab[:, 0] > lo) & (tab[:, 0] < hi)], [hi]])
            mid = 0.5 * (knots[1:] + knots[:-1])
            pts = np.concatenate([knots, mid])
            vals = np.column_stack([np.interp(pts, tab[:, 0], column) for column in tab[:, 1:].T])
            f = (t - pts)[:, None] * vals
            n = len(knots)
            seg = np.diff(knots)[:, None] / 6.0 * (f[: n - 1] + 4.0 * f[n:] + f[1:n])
            return np.sum(seg, axis=0) * (1.0 if t >= 0 else -1.0)
        if self.amplitude is not None:
            assert self.period is not None  # __post_init__: a sine has a period
            w = 2.0 * np.pi / self.period
            p = self.phase
            return np.asarray(self.amplitude) * (t * np.cos(p) / w - (np.sin(w * t + p) - np.sin(p)) / w**2)
        from scipy.integrate import quad

        return np.array([quad(lambda r, i=i: (t - r) * self(r)[i], 0.0, t, limit=200)[0]
                         for i in range(len(self(0.0)))])

    def _table_integral(self, t: float) -> np.ndarray:
        """Exact integral of the piecewise-linear (held at the ends) table from 0 to t, vectorised."""
        tab = self.table
        assert tab is not None  # called for a table history
        lo, hi = min(0.0, t), max(0.0, t)
        inner = tab[:, 0][(tab[:, 0] > lo) & (tab[:, 0] < hi)]
        knots = np.concatenate([[lo], inner, [hi]])
        values = np.column_stack([np.interp(knots, tab[:, 0], column) for column in tab[:, 1:].T])
        area = np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(knots)[:, None], axis=0)
        return area if t >= 0 else -area


    def padded(self, size: int) -> TimeHistory:
        """The same history with zero components appended up to ``size`` (a 2D load in a 3D model)."""
        if self.constant is not None:
            return TimeHistory(constant=(*self.constant, *(0.0,) * (size - len(self.constant))))
        if self.table is not None:
            tab = self.table
            return TimeHistory(table=np.hstack([tab, np.zeros((len(tab), size + 1 - tab.shape[1]))]))
        if self.amplitude is not None:
            assert self.period is not None  # __post_init__: a sine has a period
            return TimeHistory.sine((*self.amplitude, *(0.0,) * (size - len(self.amplitude))), self.period,
                                    self.phase)
        function = self.function
        assert function is not None  # exactly one form is given
        return TimeHistory(function=lambda t: np.pad(np.asarray(function(t), dtype=float).ravel(),
                                                     (0, size - len(np.ravel(function(t))))))

    def to_json(self) -> dict | None:
        """A JSON-able form (None for a Python callable, which a file cannot hold)."""
        if self.function is not None:
            return None
        if self.table is not None:
            return {"table": np.asarray(self.table).tolist()}
        if self.amplitude is not None:
            return {"amplitude": list(self.amplitude), "period": self.period, "phase": self.phase}
        assert self.constant is not None  # exactly one form is given
        return {"constant": list(self.constant)}

    @staticmethod
    def from_json(data: dict) -> TimeHistory:
        """Inverse of :meth:`to_json`."""
        if "amplitude" in data:
            return TimeHistory.sine(data["amplitude"], data["period"], data["phase"])
        if "table" in data:
            return TimeHistory(table=np.asarray(data["table"], dtype=float))
        return TimeHistory(constant=tuple(float(c) for c in data["constant"]))


MotionHistory = TimeHistory  # a prescribed displacement, velocity or acceleration history
