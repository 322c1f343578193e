"""The ``srdda`` command line: run model files and the paper's examples.

Errors in the input are reported as one message naming the field (exit 2),
and so is an output that already holds a finished run's results (exit 2: pass
--overwrite or choose another --out); an output that cannot be written (held
by another run, a folder not writable, a full disk) as one message saying what
is kept (exit 1); a run that diverges stops, keeps what it recorded and exits with 3.
"""
from __future__ import annotations

import json
import os
import sys
import warnings
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal

import click
import numpy as np
from pydantic import ValidationError
from tqdm import tqdm

from .._version import __version__
from ..backends.arrays import DEVICES, GpuUnavailable, cupy_backend, gpu_problem
from ..integrators.methods import METHODS, MethodName
from .cli_results import (animate_command, history_command, plot_command, prepare_resume_run, report_paper,
                          vtk_command)
from ..io.convert import convert
from ..io.modelfile import ModelFileError, format_validation, load_model, read_model_text
from ..io.results_store import OutputExistsError, ResultsStore, ResultsWriteError, read_results
from .paper import EXAMPLES, relative_error, run_example
from ..model import Model, ModelArrays, ModelError
from ..results import Result
from ..settings import RunSettings
from ..simulation import run
from ..solvers import available_solvers, get_solver
from ..step import Stepper
from .summary import format_summary, run_summary

__all__ = ["main", "BadInput"]


class BadInput(click.ClickException):
    """Bad input or usage reported as one message without the usage text: exit 2 (docs/cli.md)."""

    exit_code = 2


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="srdda")
def main() -> None:
    """Discontinuous Deformation Analysis: DDA0, DDA1 and SRDDA (Fan, Zheng & Zhao 2017). SI units."""
    warnings.showwarning = _show_warning


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int, file=None,
                  line=None) -> None:
    """A warning as one line on stderr, "warning: ...", without the source line it was raised at."""
    click.echo(f"warning: {message}", err=True)


def _load(path: str):
    try:
        return load_model(path)
    except ModelFileError as exc:
        raise click.UsageError(str(exc)) from None


def _compile(model: Model, settings: RunSettings, source: str) -> ModelArrays:
    """The model's arrays, checked with its run settings as the run will check them (one message, exit 2)."""
    try:
        arrays = model.arrays()
        Stepper(arrays, settings, get_solver(settings.solver, settings.solver_tolerance))
        settings.resolved_device(arrays.n_unknowns)  # a GPU asked for where there is none
    except (ModelError, GpuUnavailable) as exc:
        raise click.UsageError(f"{source}: {exc}") from None
    return arrays


def _override(settings: RunSettings, option: str, **changes: Any) -> RunSettings:
    """``settings`` with ``changes`` from a command-line option, validated like a model file."""
    try:
        return replace(settings, **changes)
    except ValidationError as exc:
        raise click.UsageError(format_validation(exc, option, "invalid with the model's run settings")) from None


HISTORIES = ("step", "time", "centroid", "area", "rotation", "velocity", "stress", "measured_position",
             "measured_velocity", "energy", "iterations")


def save_histories(results_file: Path, result: Result, out: Path) -> tuple[Path, dict]:
    """Write a run's block histories as ``histories.npz`` and a ``summary.json`` in ``out``.

    They are read from the results file the run streamed to (every recorded
    step, not the vertices), so the run itself keeps no history in memory;
    the summary adds :func:`srdda.apps.summary.run_summary` of them and the final
    state. Returns the file written and the summary.
    """
    out.mkdir(parents=True, exist_ok=True)
    stored = read_results(results_file, names=HISTORIES)
    arrays = {name: stored.array(name) for name in HISTORIES}
    # numpy's stub matches the ** names against allow_pickle too (HISTORIES holds no such name)
    np.savez_compressed(out / "histories.npz", **arrays,  # type: ignore[arg-type]
                        energy_keys=np.array(stored.energy_names))
    steps = arrays["step"]
    summary: dict[str, object] = {"method": result.method, "status": result.status, "blocks": list(result.block_names)}
    if len(steps) and result.final_state is not None:
        summary.update(run_summary(stored, result.final_state))
    else:
        summary.update(recorded_steps=0, last_step=None, last_time=None)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return out / "histories.npz", summary


def new_output_folder(model: str) -> Path:
    """A new folder named after the model in the current directory: NAME, else NAME-2, NAME-3, ...

    Created here (atomically), so two runs started together never get the same one.
    """
    stem = Path(model).stem
    for n in range(1, 10_000):
        folder = Path(stem if n == 1 else f"{stem}-{n}")
        try:
            folder.mkdir()
        except FileExistsError:
            continue
        except OSError as exc:
            raise click.ClickException(f"cannot create the output folder {folder.resolve()} ({exc.strerror})") from None
        return folder
    raise click.ClickException(f"{stem}, {stem}-2, ... {stem}-9999 all exist here; give --out")


def output_folder(model: str, out: str | None) -> Path:
    """``--out`` (created if missing), or a new folder named after the model (:func:`new_output_folder`)."""
    if out is None:
        return new_output_folder(model)
    try:
        Path(out).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise click.ClickException(f"cannot create the output folder {out} ({exc.strerror})") from None
    return Path(out)


@main.command("run")
@click.argument("model", type=click.Path(exists=True, dir_okay=False), required=False)
@click.option("--method", type=click.Choice(METHODS), help="Override the model file's method.")
@click.option("--steps", type=click.IntRange(min=0), help="Override the number of steps.")
@click.option("--end-time", type=float, default=None,
              help="Run until this time (s) instead of the model's step count (with --steps: the first reached).")
@click.option("--dt", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Override the model's time step (s).")
@click.option("--out", "out", type=click.Path(file_okay=False), default=None,
              help="Output folder (default: a new folder named after MODEL in the current directory: "
                   "NAME, or NAME-2, NAME-3, ... if that exists).")
@click.option("--overwrite", is_flag=True, help="Replace the results already in --out (else that is an error).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
@click.option("--resume", "resume_file", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Continue the run of a results.h5 from its last intact checkpoint, with the settings it stores "
                   "(instead of MODEL).")
@click.option("--flush-every", type=click.IntRange(min=1), default=None,
              help="Recorded steps between flushes of results.h5 (what a killed run can lose) [default: 100; with "
                   "--resume: the run's own].")
@click.option("--device", type=click.Choice(DEVICES), default=None,
              help="Override the model's device: where the conjugate gradient runs (gpu: CuPy and a CUDA GPU).")
def run_command(model: str | None, method: str | None, steps: int | None, end_time: float | None, dt: float | None,
                out: str | None, overwrite: bool, quiet: bool, resume_file: str | None, flush_every: int | None,
                device: str | None) -> None:
    """Run a model file; write results.h5 (see srdda plot/animate/vtk) and its time histories."""
    if resume_file is not None:
        if model is not None:
            raise click.UsageError("give either MODEL or --resume RESULTS, not both")
        given = [name for name, value in (("--method", method), ("--steps", steps), ("--end-time", end_time),
                                          ("--dt", dt), ("--device", device), ("--out", out),
                                          ("--overwrite", overwrite)) if value not in (None, False)]
        if given:
            raise click.UsageError(f"--resume continues a run with the settings and the folder its file keeps; "
                                   f"{', '.join(given)} cannot change them (run the model again for that)")
        prepared = prepare_resume_run(resume_file, flush_every)
        total = None if prepared.arrays.stages else prepared.settings.n_steps  # a staged run: its stages say
        store_path, desc = prepared.path, f"resume {prepared.settings.method}"
        start = (f"continuing {store_path} from step {prepared.start}" if prepared.start >= 0 else
                 f"restarting {store_path} from its first step")
        go = prepared.run
    else:
        if model is None:
            raise click.UsageError("missing MODEL (or --resume RESULTS)")
        store, arrays, settings = _new_run(model, method, steps, end_time, dt, device, out, overwrite, flush_every)
        total = None if arrays.stages else settings.n_steps  # a staged run: its stages say how many
        store_path, desc, start = store.path, settings.method, f"writing {store.path}"

        def go(progress: Callable[[int], None] | None = None) -> Result:
            return run(arrays, settings, progress=progress, recorders=[store], keep_history=False)
    out_dir = store_path.parent
    click.echo(start)
    try:
        with tqdm(total=total, disable=True if quiet else None, unit="step", desc=desc) as bar:
            result = go(lambda _: bar.update(1))
        path, summary = save_histories(store_path, result, out_dir)
    except GpuUnavailable as exc:  # a GPU run resumed where there is none
        raise BadInput(f"{store_path}: {exc}") from None
    except ResultsWriteError as exc:
        if exc.cut_short:  # HDF5 may crash in its exit handler after a flush that failed half-way: skip it
            click.echo(f"Error: {exc}", err=True)
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(1)
        raise click.ClickException(str(exc)) from None
    except OSError as exc:
        raise click.ClickException(f"cannot write the histories in {out_dir} ({exc.strerror})") from None
    click.echo(f"{result.status}: {summary['recorded_steps']} recorded steps written to {store_path} and {path}")
    if "cuts" in summary:
        click.echo("\n".join(format_summary(summary)))
    if not result.completed:
        sys.exit(3)


def _new_run(model: str, method: str | None, steps: int | None, end_time: float | None, dt: float | None,
             device: str | None, out: str | None, overwrite: bool,
             flush_every: int | None) -> tuple[ResultsStore, ModelArrays, RunSettings]:
    """The store (its output held), arrays and settings of a run of a model file; one message on any error."""
    mdl, settings = _load(model)
    if method:
        settings = _override(settings, "--method", method=method)
    if dt is not None:
        settings = _override(settings, "--dt", dt=dt)
    if device is not None:
        settings = _override(settings, "--device", device=device)
    if steps is not None or end_time is not None:
        settings = _override(settings, "--steps/--end-time", n_steps=steps,
                             end_time=settings.end_time if end_time is None else end_time)
    arrays = _compile(mdl, settings, model)  # before any output is made
    out_dir = output_folder(model, out)
    store = ResultsStore(out_dir / "results.h5", settings, flush_every=flush_every or 100, overwrite=overwrite,
                         model_text=read_model_text(model))
    try:
        store.acquire()  # before the run starts: fail at once if the output is taken
    except OutputExistsError as exc:
        raise BadInput(f"{exc}; pass --overwrite to replace them, choose another --out, or (a run "
                       f"that did not finish) continue it with: srdda run --resume {store.path}") from None
    except ResultsWriteError as exc:
        raise click.ClickException(str(exc)) from None
    return store, arrays, settings


@main.command("check")
@click.argument("model", type=click.Path(exists=True, dir_okay=False))
def check_command(model: str) -> None:
    """Validate a model file without running it."""
    mdl, settings = _load(model)
    arrays = _compile(mdl, settings, model)
    length = f"{settings.n_steps} steps" if settings.n_steps is not None else f"until t = {settings.end_time} s"
    stages = f"; stages: {', '.join(f'{p.name} ({p.kind})' for p in arrays.stages)}" if arrays.stages else ""
    click.echo(f"ok: {arrays.n_blocks} blocks ({arrays.block_type.dim}D), {len(arrays.vertex_position)} vertices, "
               f"method {settings.method}, {length} of {settings.dt} s{stages}")


@main.command("show")
@click.argument("model", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", type=click.Path(dir_okay=False), default=None,
              help="Image file (png, pdf, svg; default: MODEL's name + .png in the current directory).")
def show_command(model: str, out: str | None) -> None:
    """Draw a model file before running it: blocks by material, joints, fixed points, bolts, measured points."""
    from .modelview import fig_model_setup

    mdl, settings = _load(model)
    _compile(mdl, settings, model)
    path = Path(out) if out else Path(f"{Path(model).stem}.png")
    fig = fig_model_setup(mdl, read_title(model))
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120)
    except OSError as exc:
        raise click.ClickException(f"cannot write {path} ({exc.strerror})") from None
    click.echo(f"wrote {path}")


def read_title(model: str) -> str:
    """The model file's ``title`` (else its file name) for a picture's title."""
    import tomllib

    try:
        return str(tomllib.loads(read_model_text(model)).get("title") or Path(model).name)
    except (tomllib.TOMLDecodeError, OSError):
        return Path(model).name


@main.command("info")
def info_command() -> None:
    """Versions, the linear solvers and the GPU available here."""
    click.echo(f"srdda {__version__}, Python {sys.version.split()[0]}, numpy {np.__version__}")
    click.echo(f"solvers: {', '.join(available_solvers())}")
    problem = gpu_problem()
    click.echo(f"gpu: {cupy_backend().device_name()}" if problem is None else f"gpu: none ({problem})")
    click.echo(f"paper examples: {', '.join(EXAMPLES)}")


def _fmt(x: float | None, digits: int = 6) -> str:
    return "-" if x is None else f"{x:.{digits}f}"


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:+.4f}%"


def print_rows(rows: list[dict]) -> None:
    """Print table rows as aligned text, ours beside the paper's, with relative errors."""
    header = ("table", "quantity", "unit", "step", "method", "ours", "paper", "exact", "RE ours", "RE paper")
    lines = [header]
    for r in rows:
        digits = 0 if isinstance(r["paper"], int) else 6  # counts (contact steps) print as counts
        lines.append((r["table"], r["quantity"], r.get("unit", "-"), "-" if r["step"] is None else str(r["step"]),
                      r["method"],
                      _fmt(r["ours"], digits), _fmt(r["paper"], digits), _fmt(r["exact"], digits),
                      _pct(relative_error(r["ours"], r["exact"])),
                      _pct(None if r["paper"] is None else relative_error(r["paper"], r["exact"]))))
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    for line in lines:
        click.echo("  ".join(cell.ljust(w) for cell, w in zip(line, widths)))


@main.command("paper")
@click.argument("example", type=click.Choice([*EXAMPLES, "all"]))
@click.option("--method", type=click.Choice([*METHODS, "all"]), default="all", show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document instead of tables.")
@click.option("--report", "report_dir", type=click.Path(file_okay=False), default=None,
              help="Also write report.md/report.html with every table and figure (and the runs) into this folder.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def paper_command(example: str, method: MethodName | Literal["all"], as_json: bool, report_dir: str | None,
                  quiet: bool) -> None:
    """Run one of the paper's examples and print its tables beside the paper's."""
    methods = list(METHODS) if method == "all" else [method]
    names = list(EXAMPLES) if example == "all" else [example]
    if report_dir is not None:
        documents, failed = report_paper(report_dir, names, methods, quiet or as_json)
        for doc in documents:
            if not as_json:
                click.echo(f"== {EXAMPLES[doc['example']].title} ==")
                print_rows(doc["rows"])
        if as_json:
            click.echo(json.dumps(documents[0] if len(documents) == 1 else documents, indent=1))
        if failed:
            sys.exit(3)
        return
    documents = []
    for name in names:
        bars: dict[str, tqdm] = {}

        def progress(m: str, step: int, total: int) -> None:
            if m not in bars:
                bars[m] = tqdm(total=total, desc=f"{name} {m}", unit="step",
                               disable=True if quiet or as_json else None, leave=False)
            bars[m].update(1)

        try:
            _, rows = run_example(name, methods, progress)
        except RuntimeError as exc:
            raise click.ClickException(str(exc)) from None
        finally:
            for bar in bars.values():
                bar.close()
        documents.append({"example": name, "rows": rows})
        if not as_json:
            click.echo(f"== {EXAMPLES[name].title} ==")
            print_rows(rows)
    if as_json:
        click.echo(json.dumps(documents[0] if len(documents) == 1 else documents, indent=1))


@main.command("verify")
@click.argument("cases", nargs=-1)
@click.option("--json", "as_json", is_flag=True, help='Print {"rows": [...]} instead of the table.')
@click.option("--quick", is_flag=True, help="Shorter runs of the cases whose tolerances hold for them.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def verify_command(cases: tuple[str, ...], as_json: bool, quick: bool, quiet: bool) -> None:
    """Run the verification cases (all, or CASES) against their references (docs/verification.md).

    Exit code 1 if any row exceeds its tolerance.
    """
    import time

    from .verify import CASES, UnknownCaseError, expected_seconds, get_case, run_case

    try:
        names = [get_case(name).name for name in cases] or list(CASES)
    except UnknownCaseError as exc:
        raise click.UsageError(str(exc)) from None
    estimates = [expected_seconds(name, quick) for name in names]
    rows: list[dict] = []
    # the bar counts the cases' expected seconds on the reference machine: its remaining time is that
    # estimate scaled by how fast this machine has gone so far
    with tqdm(total=round(sum(estimates)), unit="s", desc="verify", disable=True if quiet else None,
              bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} s of the reference machine "
                         "[{elapsed}<{remaining}]") as bar:
        for name, estimate in zip(names, estimates):
            bar.set_description(f"verify {name}")
            start = time.perf_counter()
            try:
                rows += run_case(name, quick)
            except RuntimeError as exc:
                raise click.ClickException(f"verification case {name}: {exc}") from None
            bar.update(round(estimate))
            if not as_json:
                bar.write(f"{name}: {time.perf_counter() - start:.1f} s", file=sys.stderr)
    if as_json:
        click.echo(json.dumps({"rows": rows}, indent=1))
    else:
        header = ("case", "quantity", "method", "ours", "reference", "error", "tolerance", "result")
        lines = [header] + [
            (r["case"], r["quantity"], r["method"], f"{r['ours']:.10g}", f"{r['reference']:.10g}",
             f"{r['rel_error']:.2e} {'rel' if r['measure'] == 'relative' else 'abs'}",
             "-" if r["tolerance"] is None else f"{r['tolerance']:.0e}",
             {True: "PASS", False: "FAIL", None: "info"}[r["passed"]]) for r in rows]
        widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
        for line in lines:
            click.echo("  ".join(cell.ljust(w) for cell, w in zip(line, widths)).rstrip())
    if any(r["passed"] is False for r in rows):
        sys.exit(1)


@main.command("bench")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document {\"rows\": [...]} instead of a table.")
@click.option("--quick", is_flag=True, help="The small models only (slope a, b), few steps: under a minute.")
@click.option("--model", "models", multiple=True,
              help="Run this standard model (repeatable; default: all): slope_a, slope_b, slope_c, wall_10k, "
                   "wall_100k (2D), slope3d_1k, wall3d_10k (3D).")
@click.option("--steps", type=click.IntRange(min=0), default=None, help="Steps per model (default: the model's).")
@click.option("--dt", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Time step (s) for every model (default: the model's).")
@click.option("--method", type=click.Choice(METHODS), default="dda0", show_default=True)
@click.option("--contact-solver", type=click.Choice(["open-close", "newton"]), default=None,
              help="How the steps' contact problems are solved (default: each model's own setting).")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), default=900.0, show_default=True,
              help="Wall-time limit per model (s); a model that reaches it is reported with the steps it made.")
@click.option("--device", type=click.Choice(["cpu", "gpu"]), default="cpu", show_default=True,
              help="Where the conjugate gradient runs; gpu needs CuPy and a CUDA GPU and adds the device and its "
                   "memory to the rows.")
def bench_command(as_json: bool, quick: bool, models: tuple[str, ...], steps: int | None, dt: float | None,
                  method: str, contact_solver: str | None, timeout: float, device: str) -> None:
    """Time the standard benchmark models, each in a fresh process: steps/s, solves, memory (docs/performance.md)."""
    from .bench.runner import CASES, QUICK, format_table, run_cases

    unknown = [m for m in models if m not in CASES]
    if unknown:
        raise click.UsageError(f"unknown model(s) {', '.join(unknown)}; choose from {', '.join(CASES)}")
    if device == "gpu" and gpu_problem() is not None:
        raise BadInput(f"--device gpu: {gpu_problem()}")
    names = list(models) or list(QUICK if quick else CASES)
    rows = run_cases(names, steps, quick, method, dt, timeout,
                     progress=None if as_json else lambda name: click.echo(f"running {name} ...", err=True),
                     contact_solver=contact_solver, device=device)
    click.echo(json.dumps({"rows": rows}, indent=1) if as_json else format_table(rows))


@main.command("ensemble")
@click.argument("spec", type=click.Path(exists=True, dir_okay=False))
@click.option("--runs", type=click.IntRange(min=1), default=None, help="Number of runs (default: the spec's).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the local Dask cluster (default: one per core).")
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler to use instead (tcp://HOST:PORT).")
@click.option("--out", "out", type=click.Path(file_okay=False), default=None,
              help="Output folder; an existing one of the same spec is resumed (default: a new folder named after SPEC).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def ensemble_command(spec: str, runs: int | None, workers: int | None, scheduler: str | None, out: str | None,
                     quiet: bool) -> None:
    """Run an ensemble of sampled runs on Dask; tables, statistics and figures in --out (docs/ensembles.md)."""
    from .ensemble import SpecError, load_spec, run_ensemble

    if workers is not None and scheduler is not None:
        raise click.UsageError("give --workers (a local cluster) or --scheduler (a running one), not both")
    try:
        load_spec(spec, runs)  # every error in the spec or its model before an output folder is made
        done = run_ensemble(spec, output_folder(spec, out), runs, workers, scheduler, progress=not quiet)
    except SpecError as exc:
        raise click.UsageError(str(exc)) from None
    except OSError as exc:
        raise click.ClickException(f"{exc}") from None
    click.echo(f"{done.spec.runs} runs in {done.out} ({done.ran} run now, {done.resumed} already there, "
               f"{done.failed} failed or diverged) in {done.seconds:.1f} s: runs.parquet, collectors.parquet, "
               "summary.json, summary.csv, figures/, report.html")


def _grouped_notes(notes: list[str]) -> list[tuple[str, int]]:
    """Warnings that differ only in their numbers, once each (the first) with how many there were."""
    import re

    groups: dict[str, list[str]] = {}
    for note in notes:
        groups.setdefault(re.sub(r"[-+]?\d[\d.e+-]*", "#", note), []).append(note)
    return [(found[0], len(found)) for found in groups.values()]


@main.command("fos")
@click.argument("model", type=click.Path(exists=True, dir_okay=False))
@click.option("--joint", "joints", multiple=True,
              help="Reduce only this joint material (repeat for several; default: every joint).")
@click.option("--tolerance", type=click.FloatRange(min=0, max=1, min_open=True, max_open=True), default=0.005,
              show_default=True, help="Stop when the bracket [stable, failed] is narrower than this fraction of F.")
@click.option("--initial", type=click.FloatRange(min=0, min_open=True), default=1.0, show_default=True,
              help="The first factor tried; the bracket is searched from it by doubling or halving.")
@click.option("--points", type=click.IntRange(min=1), default=1, show_default=True,
              help="Factors tried per round (1: bisection); run in parallel with --workers.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of a local Dask cluster for each round's factors (default: none, run here).")
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler to use instead (tcp://HOST:PORT).")
@click.option("--steps", type=click.IntRange(min=6), default=None,
              help="Static steps of each equilibrium run (default 60).")
@click.option("--dt", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Time step of the equilibrium runs (s; default: Shi's bound sqrt(2 g2 w0/|g|)).")
@click.option("--contact-solver", type=click.Choice(["open-close", "newton"]), default="newton", show_default=True,
              help="The contact solve of the equilibrium runs.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document instead of the table.")
@click.option("--quiet", is_flag=True, help="No line per trial while it runs.")
def fos_command(model: str, joints: tuple[str, ...], tolerance: float, initial: float, points: int,
                workers: int | None, scheduler: str | None, steps: int | None, dt: float | None, contact_solver: str,
                as_json: bool, quiet: bool) -> None:
    """Factor of safety by shear strength reduction: c/F, arctan(tan φ/F) (docs/factor-of-safety.md)."""
    from .fos import FailureCriterion, FosError, Trial, factor_of_safety

    if workers is not None and scheduler is not None:
        raise BadInput("give --workers (a local cluster) or --scheduler (a running one), not both")
    mdl, settings = _load(model)
    _compile(mdl, settings, model)

    def show(trial: Trial) -> None:
        verdict = "failed" if trial.failed else "stable"
        click.echo(f"F = {trial.factor:.6g}: {verdict} (growth over the last window {trial.growth:.3g} m, "
                   f"previous {trial.previous:.3g} m, {trial.seconds:.1f} s)", err=True)

    try:
        criterion = FailureCriterion(steps=steps or FailureCriterion.steps, dt=dt,
                                     contact_solver="newton" if contact_solver == "newton" else "open-close")
        result = factor_of_safety(mdl, settings, list(joints) or None, tolerance, initial, points, criterion,
                                  workers, scheduler, progress=None if quiet or as_json else show)
    except FosError as exc:
        raise BadInput(f"{model}: {exc}") from None
    if as_json:
        click.echo(json.dumps(result.to_dict(), indent=2))
        return
    for note, count in _grouped_notes([n for t in result.trials for n in t.notes]):
        click.echo(f"warning: in {count} of {len(result.trials)} runs: {note}", err=True)
    click.echo(f"FS = {result.factor_of_safety:.4f}, bracket [{result.stable:.4f} stable, {result.failed:.4f} failed] "
               f"after {len(result.trials)} runs ({sum(t.seconds for t in result.trials):.1f} s); joints reduced: "
               f"{', '.join(result.joints)}")


main.add_command(plot_command)
main.add_command(animate_command)
main.add_command(vtk_command)
main.add_command(history_command)

main.add_command(convert)

if __name__ == "__main__":
    main()
