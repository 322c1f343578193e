"""The ``srdda`` command line: run model files and the paper's examples.

Errors in the input are reported as one message naming the field (exit 2);
a run that diverges stops, keeps what it recorded and exits with 3.
"""
from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

import click
import numpy as np
from tqdm import tqdm

from . import __version__
from .integrators.methods import METHODS
from .cli_results import animate_command, plot_command, report_paper, resume_run, vtk_command
from .io.convert import convert
from .io.modelfile import ModelFileError, load_model
from .io.results_store import ResultsStore
from .paper import EXAMPLES, relative_error, run_example
from .simulation import Result, run
from .solvers import available_solvers

__all__ = ["main"]


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="srdda")
def main() -> None:
    """Discontinuous Deformation Analysis: DDA0, DDA1 and SRDDA (Fan, Zheng & Zhao 2017). SI units."""


def _load(path: str):
    try:
        return load_model(path)
    except ModelFileError as exc:
        raise click.UsageError(str(exc)) from None


def save_histories(result: Result, out: Path) -> Path:
    """Write a run's histories as ``histories.npz`` and a ``summary.json`` in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    energy_keys = list(result.energy[0]) if result.energy else []
    np.savez_compressed(
        out / "histories.npz", step=result.array("step"), time=result.array("time"),
        centroid=result.array("centroid"), area=result.array("area"), rotation=result.array("rotation"),
        velocity=result.array("velocity"), stress=result.array("stress"),
        measured_position=result.array("measured_position"), measured_velocity=result.array("measured_velocity"),
        energy=result.array("energy"), energy_keys=np.array(energy_keys), iterations=result.array("iterations"))
    summary = {"method": result.method, "status": result.status, "blocks": list(result.block_names),
               "recorded_steps": len(result.step), "last_step": result.step[-1] if result.step else None,
               "last_time": result.time[-1] if result.time else None}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return out / "histories.npz"


@main.command("run")
@click.argument("model", type=click.Path(exists=True, dir_okay=False), required=False)
@click.option("--method", type=click.Choice(METHODS), help="Override the model file's method.")
@click.option("--steps", type=click.IntRange(min=0), help="Override the number of steps.")
@click.option("--out", "out", type=click.Path(file_okay=False), default=None,
              help="Output folder (default: MODEL's name without suffix, beside it).")
@click.option("--quiet", is_flag=True, help="No progress bar.")
@click.option("--resume", "resume_file", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Continue the run of a results.h5 from its last flush (instead of MODEL).")
@click.option("--flush-every", type=click.IntRange(min=1), default=100, show_default=True,
              help="Recorded steps between flushes of results.h5 (what a killed run can lose).")
def run_command(model: str | None, method: str | None, steps: int | None, out: str | None, quiet: bool,
                resume_file: str | None, flush_every: int) -> None:
    """Run a model file; write results.h5 (see srdda plot/animate/vtk) and its time histories."""
    if resume_file is not None:
        if model is not None:
            raise click.UsageError("give either MODEL or --resume RESULTS, not both")
        if resume_run(resume_file, quiet, flush_every) != "completed":
            sys.exit(3)
        return
    if model is None:
        raise click.UsageError("missing MODEL (or --resume RESULTS)")
    mdl, settings = _load(model)
    if method:
        settings = replace(settings, method=method)
    if steps is not None:
        settings = replace(settings, n_steps=steps)
    out_dir = Path(out) if out else Path(model).with_suffix("")
    out_dir.mkdir(parents=True, exist_ok=True)
    store = ResultsStore(out_dir / "results.h5", settings, flush_every=flush_every,
                         model_text=Path(model).read_text(encoding="utf-8"))
    with tqdm(total=settings.n_steps, disable=True if quiet else None, unit="step", desc=settings.method) as bar:
        result = run(mdl, settings, progress=lambda _: bar.update(1), recorders=[store])
    path = save_histories(result, out_dir)
    click.echo(f"{result.status}: {len(result.step)} recorded steps written to {path}")
    if not result.completed:
        sys.exit(3)


@main.command("check")
@click.argument("model", type=click.Path(exists=True, dir_okay=False))
def check_command(model: str) -> None:
    """Validate a model file without running it."""
    mdl, settings = _load(model)
    arrays = mdl.arrays()
    click.echo(f"ok: {arrays.n_blocks} blocks, {len(arrays.vertices)} vertices, method {settings.method}, "
               f"{settings.n_steps} steps of {settings.dt} s")


@main.command("info")
def info_command() -> None:
    """Versions and the linear solvers available here."""
    click.echo(f"srdda {__version__}, Python {sys.version.split()[0]}, numpy {np.__version__}")
    click.echo(f"solvers: {', '.join(available_solvers())}")
    click.echo(f"paper examples: {', '.join(EXAMPLES)}")


def _fmt(x: float | None, digits: int = 6) -> str:
    return "-" if x is None else f"{x:.{digits}f}"


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:+.4f}%"


def print_rows(rows: list[dict]) -> None:
    """Print table rows as aligned text, ours beside the paper's, with relative errors."""
    header = ("table", "quantity", "step", "method", "ours", "paper", "exact", "RE ours", "RE paper")
    lines = [header]
    for r in rows:
        digits = 0 if isinstance(r["paper"], int) else 6  # counts (contact steps) print as counts
        lines.append((r["table"], r["quantity"], "-" if r["step"] is None else str(r["step"]), r["method"],
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
def paper_command(example: str, method: str, as_json: bool, report_dir: str | None, quiet: bool) -> None:
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


@main.command("bench")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document {\"rows\": [...]} instead of a table.")
@click.option("--quick", is_flag=True, help="The small models only (slope a, b), few steps: under a minute.")
@click.option("--model", "models", multiple=True, help="Run this standard model (repeatable; default: all).")
@click.option("--steps", type=click.IntRange(min=0), default=None, help="Steps per model (default: the model's).")
@click.option("--dt", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Time step (s) for every model (default: the model's).")
@click.option("--method", type=click.Choice(METHODS), default="dda0", show_default=True)
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), default=900.0, show_default=True,
              help="Wall-time limit per model (s); a model that reaches it is reported with the steps it made.")
def bench_command(as_json: bool, quick: bool, models: tuple[str, ...], steps: int | None, dt: float | None,
                  method: str, timeout: float) -> None:
    """Time the standard benchmark models (issue 14), each in a fresh process: steps/s, solves, memory."""
    from .bench.runner import CASES, QUICK, format_table, run_cases

    unknown = [m for m in models if m not in CASES]
    if unknown:
        raise click.UsageError(f"unknown model(s) {', '.join(unknown)}; choose from {', '.join(CASES)}")
    names = list(models) or list(QUICK if quick else CASES)
    rows = run_cases(names, steps, quick, method, dt, timeout,
                     progress=None if as_json else lambda name: click.echo(f"running {name} ...", err=True))
    click.echo(json.dumps({"rows": rows}, indent=1) if as_json else format_table(rows))


main.add_command(plot_command)
main.add_command(animate_command)
main.add_command(vtk_command)

main.add_command(convert)

if __name__ == "__main__":
    main()
