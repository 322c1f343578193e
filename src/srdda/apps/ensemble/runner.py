"""Running an ensemble on Dask: one task per run, each finished run written at once, resumable.

:func:`run_one` is the task: it draws run ``i``'s sample, builds the model
from the sampled model-file dictionary, runs it with the spec's stop rule and
a :class:`~srdda.apps.ensemble.collect.RockfallRecorder`, and returns a plain
dictionary (any error of the sample is caught and returned as a failed run).
:func:`run_ensemble` submits the runs that have no file yet to a
``distributed.LocalCluster`` (one single-threaded worker process per core) or
to a running scheduler, and writes each result as it arrives to
``runs/run-<i>.json`` (written to a temporary name, then renamed: a file is
there whole or not at all). So a killed ensemble loses only the runs in
flight, and the tables are assembled from the files at the end.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from tqdm import tqdm

from ...io.modelfile import model_from_dict
from ...io.outputlock import release_lock, take_lock
from ...simulation import run
from .collect import RockfallRecorder, SettleRule
from .sampling import apply_values, load_spec, sample, tracked_block
from .spec import EnsembleSpec, SpecError

__all__ = ["run_one", "run_ensemble", "EnsembleRun", "read_run_files", "dask_client"]

RUNS_DIR = "runs"
FINGERPRINT_FILE = "ensemble.json"
LOCK_FILE = "ensemble.lock"  # held while an ensemble writes the folder (srdda.io.outputlock)


def run_one(spec: EnsembleSpec, base: dict[str, Any], index: int) -> dict[str, Any]:
    """Run ``index`` of the ensemble: its sample, its status and message, its measures (a JSON-able dict)."""
    values = sample(spec, index)
    record: dict[str, Any] = {"run": index, "values": values}
    start = time.perf_counter()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            data = apply_values(base, spec, values)
            model, settings = model_from_dict(data, f"run {index}")
            if spec.stop.end_time is not None:
                settings = replace(settings, end_time=spec.stop.end_time)
            arrays = model.arrays()
            dim = arrays.block_type.dim
            recorder = RockfallRecorder(arrays, tracked_block(data, spec), spec.all_collectors(dim),
                                        spec.trajectory_interval)
            rule = SettleRule(arrays, spec.stop)
            result = run(arrays, settings, recorders=[recorder], keep_history=False, stop=rule)
    except Exception as exc:  # noqa: BLE001 - any error of this sample is this run's failure, not the ensemble's
        return {**record, "status": "failed", "message": f"{type(exc).__name__}: {exc}",
                "seconds": time.perf_counter() - start}
    assert recorder.start is not None and recorder.end is not None and result.final_state is not None
    notes = sorted({str(w.message) for w in caught})
    status = "ok" if result.completed else "diverged"
    horizontal = recorder.end[:-1] - recorder.start[:-1]
    measures = {
        "stop_reason": rule.reason if result.completed else "diverged",
        "end_time": result.final_state.time, "steps": result.final_state.step,
        **{f"start_{a}": float(x) for a, x in zip("xyz", recorder.start)},
        **{f"end_{a}": float(x) for a, x in zip("xyz", recorder.end)},
        "runout": float((horizontal @ horizontal) ** 0.5), "drop": float(recorder.start[-1] - recorder.end[-1]),
        "max_kinetic_energy": recorder.max_kinetic, "max_speed": recorder.max_speed,
        "time_to_stop": rule.time_to_stop}
    message = "; ".join(notes) if result.completed else result.status  # warnings of a run that completed
    return {**record, "status": status, "message": message, "dim": dim, "measures": measures,
            "collectors": recorder.crossings, "trajectory": recorder.trajectory,
            "seconds": time.perf_counter() - start}


def _write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data), encoding="utf-8")
    os.replace(tmp, path)


def run_file(out: Path, index: int) -> Path:
    return out / RUNS_DIR / f"run-{index:07d}.json"


def read_run_files(out: Path, runs: int) -> dict[int, dict[str, Any]]:
    """The finished runs of ``out`` with an index below ``runs``, by index."""
    found: dict[int, dict[str, Any]] = {}
    for path in sorted((out / RUNS_DIR).glob("run-[0-9]*.json")):
        index = int(path.stem.removeprefix("run-"))
        if index < runs:
            try:
                found[index] = json.loads(path.read_text(encoding="utf-8"))
            except (ValueError, OSError) as exc:
                raise SpecError(f"{path}: not a readable run file ({exc}); delete it to run that run again") from None
    return found


def _fingerprint(spec: EnsembleSpec, base: dict[str, Any]) -> str:
    """What the runs depend on: the spec without its run count, and the base model."""
    text = json.dumps({"spec": spec.model_dump(mode="json", exclude={"runs"}), "model": base}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _claim(out: Path, spec: EnsembleSpec, base: dict[str, Any]) -> None:
    """Mark ``out`` as this spec's, or refuse it if it holds runs of another spec or model."""
    path = out / FINGERPRINT_FILE
    fingerprint = _fingerprint(spec, base)
    if path.exists():
        held = json.loads(path.read_text(encoding="utf-8")).get("fingerprint")
        if held != fingerprint:
            raise SpecError(f"{out} holds runs of another spec or base model (its parameters, seed, stop rule or "
                            "collectors differ); choose another --out, or delete it to start again")
        return
    (out / RUNS_DIR).mkdir(parents=True, exist_ok=True)
    _write_json_atomic(path, {"fingerprint": fingerprint, "spec": spec.model_dump(mode="json", exclude={"runs"})})


NUMBA_THREADS = "NUMBA_NUM_THREADS"


def numba_threads_per_worker(workers: int) -> int:
    """numba threads for each of ``workers`` processes on this machine: its cores shared out, at least one."""
    return max(1, (os.cpu_count() or 1) // workers)


@contextmanager
def dask_client(workers: int | None, scheduler: str | None, processes: bool) -> Iterator[Any]:
    """A Dask client: of the running scheduler at ``scheduler``, or of a new LocalCluster closed on exit."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        with Client(scheduler) as client:
            yield client
        return
    n = workers or os.cpu_count() or 1
    # the cores shared among the worker processes: a run of more than 500 blocks runs its compiled loops on
    # numba's threads, one per core by default in every worker (docs/ensembles.md)
    env = {"env": {NUMBA_THREADS: str(numba_threads_per_worker(n))}} if processes else {}
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=processes, dashboard_address=":0",
                      silence_logs=logging.ERROR, **env) as cluster, Client(cluster) as client:
        yield client


@dataclass
class EnsembleRun:
    """What :func:`run_ensemble` did: the spec, the output folder, runs made now / before, failures, wall time."""

    spec: EnsembleSpec
    out: Path
    ran: int
    resumed: int
    failed: int
    seconds: float


def run_ensemble(spec_path: str | Path, out: str | Path, runs: int | None = None, workers: int | None = None,
                 scheduler: str | None = None, progress: bool = True, processes: bool = True) -> EnsembleRun:
    """Run the spec's ensemble into ``out`` (resuming the runs already there), then write tables and figures.

    ``workers``: processes of the local cluster (default one per core);
    ``scheduler``: address of a running Dask scheduler instead;
    ``processes=False``: a local cluster of threads in this process (tests). The folder is held (an OS
    lock on ``ensemble.lock``) while the ensemble writes it: a second one into it fails at once, naming this one.
    """
    start = time.perf_counter()
    spec, base = load_spec(spec_path, runs)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    lock = out / LOCK_FILE
    held = take_lock(lock, str(out))  # a second ensemble into the same folder fails here, naming this one
    try:
        return _run_held(spec, base, out, workers, scheduler, progress, processes, start)
    finally:
        release_lock(lock, held)


def _run_held(spec: EnsembleSpec, base: dict[str, Any], out: Path, workers: int | None, scheduler: str | None,
              progress: bool, processes: bool, start: float) -> EnsembleRun:
    """:func:`run_ensemble` once ``out`` is held."""
    from .tables import write_outputs  # pyarrow: imported when the tables are written

    _claim(out, spec, base)
    done = read_run_files(out, spec.runs)
    todo = [i for i in range(spec.runs) if i not in done]
    failed = sum(r["status"] != "ok" for r in done.values())
    if todo:
        with dask_client(workers, scheduler, processes) as client, \
                tqdm(total=spec.runs, initial=len(done), unit="run", desc="ensemble", disable=not progress) as bar:
            from distributed import as_completed

            index_of = {client.submit(run_one, spec, base, i, pure=False): i for i in todo}
            for future in as_completed(index_of):
                i = index_of[future]
                try:
                    record = future.result()
                except Exception as exc:  # noqa: BLE001 - a lost worker fails this run only
                    record = {"run": i, "values": sample(spec, i), "status": "failed",
                              "message": f"{type(exc).__name__}: {exc}"}
                _write_json_atomic(run_file(out, i), record)
                failed += record["status"] != "ok"
                bar.update(1)
                bar.set_postfix(failed=failed, remaining=spec.runs - bar.n)
    write_outputs(out, spec, base, [r for _, r in sorted(read_run_files(out, spec.runs).items())])
    return EnsembleRun(spec, out, len(todo), len(done), failed, time.perf_counter() - start)
