"""Earthquake records: PEER NGA ``.AT2`` and CSV files as a base acceleration a_g(t) in m/s².

A record becomes a :class:`~srdda.history.TimeHistory` table (t, a_x, a_y[, a_z]):
a function of time, linearly interpolated at each step's load time whatever
the run's Δt (never indexed by step number). Processing, in this order:

1. read the samples (``.AT2``: values in g after the ``NPTS=..., DT=...`` line;
   CSV: rows ``time, ax, ay[, az]``, first time 0);
2. convert the units (``g`` = 9.80665 m/s², ``m/s2``, ``cm/s2``) and multiply by ``scale``;
3. end the record: one zero sample is appended one sample interval after the
   last one, so the ground stops accelerating when the record ends (a table
   otherwise holds its last value);
4. baseline correction (docs/earthquake-and-bolts.md): ``none``, or the
   subtraction from the acceleration of a polynomial of degree 0 (``mean``),
   1 (``linear``) or 2 (``quadratic``) in t whose time integral is the
   least-squares fit to the record's velocity under the constraint that the
   corrected velocity is zero at the record's end: the velocity-fitting
   baseline correction of Boore & Bommer (2005, "Processing of strong-motion
   accelerograms: needs, options and consequences", Soil Dynamics and
   Earthquake Engineering 25, 93-115, section 4), with the end condition as
   an exact constraint. The velocity is the trapezoidal integral of the
   samples, which is exactly the ground velocity a run sees (the integral of
   the interpolated table), so after the record the ground is at rest to round-off.

Every problem in a file is one :class:`RecordError` naming the file and the line.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..history import TimeHistory
from ..units import STANDARD_GRAVITY

__all__ = ["RecordError", "Record", "read_record", "baseline_correct", "record_history", "write_at2", "write_csv",
           "synthetic_record", "SYNTHETIC_RECORD", "RECORD_UNITS", "BASELINES"]

RECORD_UNITS = {"g": STANDARD_GRAVITY, "m/s2": 1.0, "m/s^2": 1.0, "m/s²": 1.0, "cm/s2": 0.01, "cm/s^2": 0.01,
                "gal": 0.01}
BASELINES = {"none": None, "mean": 0, "linear": 1, "quadratic": 2}  # degree of the polynomial removed
SYNTHETIC_RECORD = Path(__file__).resolve().parents[1] / "data" / "records" / "synthetic.AT2"

_NPTS_DT = re.compile(r"NPTS\s*=\s*(\d+)\s*,\s*DT\s*=\s*([-+0-9.eE]+)", re.IGNORECASE)
_OLD_NPTS_DT = re.compile(r"^\s*(\d+)\s+([-+0-9.eE]+)\s+NPTS\s*,\s*DT", re.IGNORECASE)  # NGA-West1 layout


class RecordError(ValueError):
    """An earthquake record that cannot be read; the message names the file, the line and the problem."""


@dataclass(frozen=True)
class Record:
    """Samples of a record as read: ``time`` (n,) s, ``values`` (n, m) in ``units``, ``axes`` one per column."""

    path: str
    time: np.ndarray
    values: np.ndarray
    axes: tuple[str, ...]
    units: str


def _read_text(path: Path) -> list[str]:
    try:
        return path.read_text(encoding="utf-8-sig", errors="strict").splitlines()
    except OSError as exc:
        raise RecordError(f"{path}: cannot read the record ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise RecordError(f"{path}: not a text file (an earthquake record is an .AT2 or .csv text file)") from None


def _read_at2(path: Path) -> Record:
    lines = _read_text(path)
    if len(lines) < 4:
        raise RecordError(f"{path}: an .AT2 record has 4 header lines, then the values; the file has {len(lines)} "
                          "lines")
    quantity = lines[2].upper()
    if "VELOCITY" in quantity or "DISPLACEMENT" in quantity:
        raise RecordError(f"{path}:3: the header says {lines[2].strip()!r}; an .AT2 record holds accelerations")
    found = _NPTS_DT.search(lines[3]) or _OLD_NPTS_DT.search(lines[3])
    if found is None:
        raise RecordError(f"{path}:4: expected 'NPTS= n, DT= dt SEC', got {lines[3].strip()!r}")
    npts, dt = int(found.group(1)), float(found.group(2))
    if npts < 1 or not 0 < dt < np.inf:
        raise RecordError(f"{path}:4: NPTS must be >= 1 and DT > 0, got NPTS={npts}, DT={dt}")
    values: list[float] = []
    for number, line in enumerate(lines[4:], start=5):
        for token in line.replace(",", " ").split():
            try:
                value = float(token)
            except ValueError:
                raise RecordError(f"{path}:{number}: {token!r} is not a number") from None
            if not np.isfinite(value):
                raise RecordError(f"{path}:{number}: {token!r} is not a finite number")
            values.append(value)
    if len(values) != npts:
        raise RecordError(f"{path}:4: the header says NPTS={npts} but the file holds {len(values)} values")
    units = "g" if "UNITS OF G" in quantity else "m/s2" if "M/S" in quantity else "cm/s2" if "CM/S" in quantity else "g"
    return Record(str(path), dt * np.arange(npts), np.asarray(values)[:, None], ("x",), units)


def _read_csv(path: Path) -> Record:
    rows: list[list[float]] = []
    axes: tuple[str, ...] | None = None
    first_line = 0
    for number, line in enumerate(_read_text(path), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        cells = [c.strip() for c in text.split(",")]
        if not rows and axes is None:
            try:
                [float(c) for c in cells]
            except ValueError:  # a header: time, ax, ay[, az]
                names = [c.lower() for c in cells]
                wanted = ["time", "ax", "ay", "az"][: len(names)]
                if names != wanted or len(names) < 2:
                    raise RecordError(f"{path}:{number}: the header must be 'time, ax[, ay[, az]]', got {text!r}"
                                      ) from None
                axes = tuple(n[1] for n in names[1:])
                continue
        if not 2 <= len(cells) <= 4:
            raise RecordError(f"{path}:{number}: a row is 'time, ax[, ay[, az]]' (2 to 4 numbers), got {len(cells)}")
        if rows and len(cells) != len(rows[0]):
            raise RecordError(f"{path}:{number}: {len(cells)} columns, but the first row has {len(rows[0])}")
        try:
            row = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not _is_number(c))
            raise RecordError(f"{path}:{number}: {bad!r} is not a number") from None
        if not np.all(np.isfinite(row)):
            raise RecordError(f"{path}:{number}: the row holds a value that is not finite")
        if rows and row[0] <= rows[-1][0]:
            raise RecordError(f"{path}:{number}: times must increase strictly ({row[0]} after {rows[-1][0]})")
        if not rows:
            first_line = number
            if row[0] != 0.0:
                raise RecordError(f"{path}:{number}: the record must start at time 0, got {row[0]} (shift its times)")
        rows.append(row)
    if len(rows) < 2:
        raise RecordError(f"{path}: a CSV record needs at least two rows 'time, ax[, ay[, az]]'")
    table = np.array(rows)
    columns = table.shape[1] - 1
    if axes is None:
        axes = tuple("xyz"[:columns])
    elif len(axes) != columns:
        raise RecordError(f"{path}:{first_line}: the header names {len(axes)} components, the rows have {columns}")
    return Record(str(path), table[:, 0], table[:, 1:], axes, "m/s2")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_record(path: str | Path, format: str | None = None) -> Record:
    """The samples of an ``.AT2`` or CSV record (``format`` "at2" or "csv"; default: by the file's extension)."""
    p = Path(path)
    kind = (format or p.suffix.lstrip(".")).lower()
    if kind == "at2":
        return _read_at2(p)
    if kind == "csv":
        return _read_csv(p)
    raise RecordError(f"{p}: unknown record format {kind!r}; give an .AT2 or .csv file, or format = 'at2' or 'csv'")


def _cumulative_trapezoid(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """∫₀ᵗ of piecewise-linear samples at every sample time (first row 0), column by column."""
    steps = 0.5 * (values[1:] + values[:-1]) * np.diff(time)[:, None]
    return np.vstack([np.zeros((1, values.shape[1])), np.cumsum(steps, axis=0)])


def baseline_correct(time: np.ndarray, values: np.ndarray, method: str, active: np.ndarray | None = None
                     ) -> np.ndarray:
    """Accelerations (n, m) minus the baseline polynomial of ``method`` (module doc), column by column.

    ``active`` (n,) marks the samples the polynomial is subtracted from (default all;
    :func:`record_history` leaves out the appended end sample, which stays 0).
    The corrected velocity (trapezoidal integral) is 0 at the last sample.
    """
    if method not in BASELINES:
        raise RecordError(f"unknown baseline correction {method!r}; use one of {', '.join(BASELINES)}")
    degree = BASELINES[method]
    values = np.asarray(values, dtype=float)
    if degree is None:
        return values.copy()
    mask = np.ones(len(time), dtype=bool) if active is None else np.asarray(active, dtype=bool)
    tau = np.asarray(time, dtype=float) / time[-1]  # scaled time: a well-conditioned basis
    basis = np.where(mask[:, None], tau[:, None] ** np.arange(degree + 1), 0.0)  # (n, p+1)
    fitted = _cumulative_trapezoid(time, basis)  # the velocity each basis term adds
    velocity = _cumulative_trapezoid(time, values)
    # minimise |v - G c|² subject to (v - G c)[-1] = 0: the KKT system [[GᵀG, gᵀ], [g, 0]]
    p = degree + 1
    kkt = np.zeros((p + 1, p + 1))
    kkt[:p, :p] = fitted.T @ fitted
    kkt[:p, p] = kkt[p, :p] = fitted[-1]
    rhs = np.vstack([fitted.T @ velocity, velocity[-1:]])
    coefficients = np.linalg.solve(kkt, rhs)[:p]  # (p, m)
    return values - basis @ coefficients


def record_history(path: str | Path, dim: int = 2, format: str | None = None, units: str | None = None,
                   scale: float = 1.0, baseline: str = "none", components: str | None = None) -> TimeHistory:
    """The base acceleration (m/s²) of a record file as a table history (module doc for the steps).

    ``units``: the file's units (default: what an .AT2 header says, else g for
    .AT2 and m/s2 for CSV). ``components``: the model axes the record's columns
    drive, one letter per column (default: "x" for an .AT2, the CSV header's axes).
    """
    rec = read_record(path, format)
    unit = rec.units if units is None else units
    if unit not in RECORD_UNITS:
        raise RecordError(f"{path}: unknown units {unit!r}; use one of {', '.join(RECORD_UNITS)}")
    if not np.isfinite(scale):
        raise RecordError(f"{path}: scale must be a finite number, got {scale}")
    axes = rec.axes if components is None else tuple(components)
    model_axes = "xyz"[:dim]
    if len(axes) != rec.values.shape[1] or len(set(axes)) != len(axes) or any(a not in model_axes for a in axes):
        raise RecordError(f"{path}: the record has {rec.values.shape[1]} component(s) ({', '.join(rec.axes)}); "
                          f"components must name as many distinct axes of this {dim}D model ({model_axes!r}), "
                          f"got {''.join(axes)!r}")
    end = rec.time[-1] + (rec.time[-1] - rec.time[-2] if len(rec.time) > 1 else 1.0)
    time = np.append(rec.time, end)
    values = np.vstack([rec.values * RECORD_UNITS[unit] * scale, np.zeros((1, rec.values.shape[1]))])
    corrected = baseline_correct(time, values, baseline, active=np.arange(len(time)) < len(rec.time))
    table = np.zeros((len(time), dim + 1))
    table[:, 0] = time
    for column, axis in enumerate(axes):
        table[:, 1 + model_axes.index(axis)] = corrected[:, column]
    return TimeHistory(table=table)


def write_at2(path: str | Path, dt: float, values_g: np.ndarray, title: str = "srdda record") -> None:
    """An .AT2 file (PEER NGA layout: 4 header lines, 5 values per line in g, E format with 7 digits)."""
    values = np.asarray(values_g, dtype=float).ravel()
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", title, "ACCELERATION TIME SERIES IN UNITS OF G",
             f"NPTS={len(values):7d}, DT= {dt:.6f} SEC"]
    lines += ["".join(f"{v:15.7E}" for v in values[i:i + 5]) for i in range(0, len(values), 5)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_csv(path: str | Path, time: np.ndarray, values: np.ndarray) -> None:
    """A CSV record: header ``time, ax, ay[, az]`` and one row per sample (values as given, full precision)."""
    values = np.asarray(values, dtype=float).reshape(len(time), -1)
    header = ", ".join(["time", *("ax", "ay", "az")[: values.shape[1]]])
    rows = [", ".join(repr(float(x)) for x in (t, *v)) for t, v in zip(time, values)]
    Path(path).write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")


def synthetic_record(duration: float = 6.0, dt: float = 0.01, pga: float = 0.35) -> tuple[float, np.ndarray]:
    """The repository's synthetic record (values in g at Δt = ``dt``): fixed sines under a trapezoidal envelope.

    a(t) = e(t)·Σ A_k sin(2π f_k t + φ_k), scaled to the peak ``pga`` (g); e rises
    linearly over 1 s, holds to 3 s and decays as exp(-(t - 3)/1.2 s). No
    random numbers: the same values on every machine (examples/records/make_synthetic.py).
    """
    t = dt * np.arange(int(round(duration / dt)) + 1)
    frequencies = (0.7, 1.3, 2.1, 3.4, 5.2)  # Hz
    amplitudes = (0.6, 1.0, 0.8, 0.5, 0.3)
    phases = (0.3, 1.9, 4.0, 2.6, 5.1)  # rad
    wave = sum(a * np.sin(2 * np.pi * f * t + p) for f, a, p in zip(frequencies, amplitudes, phases))
    envelope = np.clip(t / 1.0, 0.0, 1.0) * np.where(t > 3.0, np.exp(-(t - 3.0) / 1.2), 1.0)
    values = envelope * wave
    return dt, pga * values / np.max(np.abs(values))
