"""The ensemble's tables (pyarrow), summary statistics, figures and report, from the per-run files.

Written by :func:`write_outputs` into the output folder, every time an
ensemble finishes or resumes, from ``runs/run-*.json`` alone (so they are the
same whichever workers made the runs and in which order): ``runs.parquet``,
``collectors.parquet``, ``trajectories.parquet``, ``summary.json``,
``summary.csv``, ``figures/*.png`` and ``report.md``/``report.html``.
Columns and units: docs/ensembles.md (each Parquet field also carries its
unit in its metadata).
"""
from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from .collect import COLLECTOR_FIELDS
from .spec import EnsembleSpec

__all__ = ["model_dimension", "runs_table", "collectors_table", "trajectories_table", "summary", "write_outputs",
           "UNITS", "SUMMARY_QUANTITIES"]

# Units of the columns (2D energies and masses are per metre of thickness).
UNITS = {"end_time": "s", "time_to_stop": "s", "runout": "m", "drop": "m", "max_kinetic_energy": "J",
         "max_speed": "m/s", "time": "s", "speed": "m/s", "angular_speed": "rad/s", "kinetic_translational": "J",
         "kinetic_rotational": "J", "kinetic": "J", "bounce_height": "m",
         **{f"{p}{a}": "m" for p in ("start_", "end_", "") for a in "xyz"},
         **{f"velocity_{a}": "m/s" for a in "xyz"}}
SUMMARY_QUANTITIES = ("speed", "kinetic_translational", "kinetic_rotational", "kinetic", "bounce_height")
PERCENTILES = (50, 95, 99)


def model_dimension(base: dict[str, Any]) -> int:
    """2 or 3: the dimension of a model-file dictionary's blocks."""
    block = base["blocks"][0]
    return 3 if block.get("box") is not None or block.get("faces") is not None else len(block["vertices"][0])


def _field(name: str, kind: pa.DataType, dim: int) -> pa.Field:
    unit = UNITS.get(name, "")
    if dim == 2 and unit == "J":
        unit = "J/m"
    return pa.field(name, kind, metadata={"unit": unit} if unit else None)


def _table(columns: dict[str, tuple[pa.DataType, list[Any]]], dim: int) -> pa.Table:
    schema = pa.schema([_field(name, kind, dim) for name, (kind, _) in columns.items()])
    return pa.table({name: values for name, (_, values) in columns.items()}, schema=schema)


def _float(value: Any) -> float:
    return math.nan if value is None else float(value)


def runs_table(spec: EnsembleSpec, records: list[dict[str, Any]], dim: int) -> pa.Table:
    """One row per run (by index): status, message, the sample's values, the run's measures."""
    axes = "xyz"[:dim]
    measures = ["end_time", *(f"start_{a}" for a in axes), *(f"end_{a}" for a in axes), "runout", "drop",
                "max_kinetic_energy", "max_speed", "time_to_stop"]
    columns: dict[str, tuple[pa.DataType, list[Any]]] = {
        "run": (pa.int64(), [r["run"] for r in records]),
        "status": (pa.string(), [r["status"] for r in records]),
        "message": (pa.string(), [r["message"] for r in records]),
        **{p.name: (pa.float64(), [r["values"][p.name] for r in records]) for p in spec.parameters},
        "stop_reason": (pa.string(), [r.get("measures", {}).get("stop_reason", "failed") for r in records]),
        "steps": (pa.int64(), [r.get("measures", {}).get("steps", 0) for r in records])}
    for name in measures:
        columns[name] = (pa.float64(), [_float(r.get("measures", {}).get(name)) for r in records])
    return _table(columns, dim)


def collectors_table(spec: EnsembleSpec, records: list[dict[str, Any]], dim: int) -> pa.Table:
    """One row per run that ran (not failed) × collector: crossed or not, and the values at the crossing."""
    axes = "xyz"[:dim]
    names = [c.name for c in spec.all_collectors(dim)]
    fields = [*axes, *(f"velocity_{a}" for a in axes), *COLLECTOR_FIELDS]
    rows = [(r["run"], name, r["collectors"].get(name)) for r in records if "collectors" in r for name in names]
    columns: dict[str, tuple[pa.DataType, list[Any]]] = {
        "run": (pa.int64(), [run for run, _, _ in rows]),
        "collector": (pa.string(), [name for _, name, _ in rows]),
        "crossed": (pa.bool_(), [c is not None for _, _, c in rows])}
    for f in fields:
        columns[f] = (pa.float64(), [math.nan if c is None else float(c[f]) for _, _, c in rows])
    return _table(columns, dim)


def trajectories_table(records: list[dict[str, Any]], dim: int) -> pa.Table:
    """The tracked block's centroid path of every run that ran, one row per stored point."""
    rows = [(r["run"], point) for r in records for point in r.get("trajectory", [])]
    columns: dict[str, tuple[pa.DataType, list[Any]]] = {
        "run": (pa.int64(), [run for run, _ in rows]), "time": (pa.float64(), [p[0] for _, p in rows])}
    for k, a in enumerate("xyz"[:dim]):
        columns[a] = (pa.float64(), [p[1 + k] for _, p in rows])
    return _table(columns, dim)


def _stats(values: np.ndarray) -> dict[str, float | int]:
    values = values[np.isfinite(values)]
    if len(values) == 0:
        return {"count": 0, "mean": math.nan, **{f"p{q}": math.nan for q in PERCENTILES}, "max": math.nan}
    return {"count": int(len(values)), "mean": float(values.mean()),
            **{f"p{q}": float(np.percentile(values, q)) for q in PERCENTILES}, "max": float(values.max())}


def summary(spec: EnsembleSpec, runs: pa.Table, collectors: pa.Table, dim: int) -> dict[str, Any]:
    """Counts, runout and peak-energy statistics, and per collector the statistics of each crossing value."""
    status = np.array(runs.column("status").to_pylist(), dtype=object)
    ok = status == "ok"
    out: dict[str, Any] = {
        "title": spec.title, "runs": len(status), "ok": int(ok.sum()), "failed": int((status == "failed").sum()),
        "diverged": int((status == "diverged").sum()),
        "left_domain": int(np.sum(np.array(runs.column("stop_reason").to_pylist(), dtype=object) == "out_of_domain")),
        "runout": _stats(runs.column("runout").to_numpy()[ok]),
        **{f"end_{a}": _stats(runs.column(f"end_{a}").to_numpy()[ok]) for a in "xyz"[:dim]},
        "max_kinetic_energy": _stats(runs.column("max_kinetic_energy").to_numpy()[ok]),
        "time_to_stop": _stats(runs.column("time_to_stop").to_numpy()[ok]), "collectors": []}
    ran = set(np.asarray(runs.column("run").to_numpy())[ok].tolist())
    names = np.array(collectors.column("collector").to_pylist(), dtype=object)
    keep = np.isin(collectors.column("run").to_numpy(), list(ran)) if ran else np.zeros(len(names), bool)
    crossed = collectors.column("crossed").to_numpy(zero_copy_only=False)
    for c in spec.all_collectors(dim):
        mine = keep & (names == c.name)
        entry: dict[str, Any] = {"collector": c.name, "at": c.at, "normal": c.normal, "runs": int(mine.sum()),
                                 "crossed": int((mine & crossed).sum())}
        for q in SUMMARY_QUANTITIES:
            entry[q] = _stats(collectors.column(q).to_numpy()[mine & crossed])
        out["collectors"].append(entry)
    return out


def _summary_rows(doc: dict[str, Any], dim: int) -> list[dict[str, Any]]:
    """The summary as CSV rows: one per collector × quantity, then the per-run quantities."""
    energy = "J/m" if dim == 2 else "J"
    rows = []
    for c in doc["collectors"]:
        for q in SUMMARY_QUANTITIES:
            unit = energy if UNITS[q] == "J" else UNITS[q]
            rows.append({"collector": c["collector"], "quantity": q, "unit": unit, "crossed": c["crossed"],
                         "runs": c["runs"], **{k: v for k, v in c[q].items() if k != "count"}})
    for q in ("runout", *(f"end_{a}" for a in "xyz"[:dim]), "max_kinetic_energy", "time_to_stop"):
        unit = energy if UNITS[q] == "J" else UNITS[q]
        rows.append({"collector": "", "quantity": q, "unit": unit, "crossed": "", "runs": doc[q]["count"],
                     **{k: v for k, v in doc[q].items() if k != "count"}})
    return rows


def _write_atomic(path: Path, write: Any) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    write(tmp)
    os.replace(tmp, path)


def write_outputs(out: Path, spec: EnsembleSpec, base: dict[str, Any],
                  records: list[dict[str, Any]]) -> dict[str, Any]:
    """Assemble the run files of ``out`` (``records``, by index) into its tables, summary, figures and report;
    returns the summary."""
    from .figures import ensemble_figures  # matplotlib: imported when the figures are drawn
    from .report import write_ensemble_report

    dim = model_dimension(base)
    runs, collectors = runs_table(spec, records, dim), collectors_table(spec, records, dim)
    trajectories = trajectories_table(records, dim)
    for name, table in (("runs", runs), ("collectors", collectors), ("trajectories", trajectories)):
        _write_atomic(out / f"{name}.parquet", lambda p, t=table: pq.write_table(t, p))
    doc = summary(spec, runs, collectors, dim)
    doc["complete"] = len(records) == spec.runs
    figures = ensemble_figures(spec, base, runs, collectors, trajectories, dim, out / "figures")
    doc["figures"] = [(caption, path.name) for caption, path in figures]
    _write_atomic(out / "summary.json", lambda p: p.write_text(json.dumps(doc, indent=1), encoding="utf-8"))
    rows = _summary_rows(doc, dim)

    def write_csv(p: Path) -> None:
        with p.open("w", newline="", encoding="utf-8") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    _write_atomic(out / "summary.csv", write_csv)
    write_ensemble_report(out, doc, figures, dim)
    return doc
