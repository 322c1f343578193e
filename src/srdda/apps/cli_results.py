"""Command-line tools for results files: ``srdda plot``, ``srdda animate``, ``srdda vtk``, ``srdda history``,
resuming a run."""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import click
from tqdm import tqdm

from ..integrators.methods import MethodName
from ..io.results_store import (ResultsDamageWarning, ResultsFileError, ResultsInUseError, ResultsWriteError, 
                               Resumption, StoredResult, prepare_resume, read_results)

__all__ = ["plot_command", "animate_command", "vtk_command", "history_command", "prepare_resume_run", "report_paper"]

RUN = click.Path(exists=True)


def _read(path: str) -> StoredResult:
    """The results file RUN, or RUN/results.h5 when RUN is the output folder of ``srdda run``."""
    if Path(path).is_dir():
        path = str(Path(path) / "results.h5")
    try:
        with warnings.catch_warnings():  # the damage is told below, every time (a warning is shown once)
            warnings.simplefilter("ignore", ResultsDamageWarning)
            res = read_results(path)
    except ResultsInUseError as exc:
        raise click.ClickException(str(exc)) from None
    except ResultsFileError as exc:
        raise click.UsageError(str(exc)) from None
    if res.damage is not None:
        click.echo(f"warning: {res.damage}", err=True)
    if "step" not in res.histories or len(res.step) == 0:
        raise click.UsageError(f"{path}: no intact recorded step to read" if res.damage else
                               f"{path}: no recorded step was flushed yet")
    return res


def _writable(path: Path, folder: bool = False) -> Path:
    """``path`` with its folder (``folder``: itself) created; one clear message if that cannot be done."""
    try:
        (path if folder else path.parent).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise click.ClickException(f"cannot write {path} ({exc.strerror})") from None
    return path


def prepare_resume_run(path: str, flush_every: int | None = None) -> Resumption:
    """Hold a results file for ``srdda run --resume`` and say where it continues; one message on any error."""
    try:
        prepared = prepare_resume(path, flush_every=flush_every)
    except ResultsInUseError as exc:
        raise click.ClickException(str(exc)) from None
    except ResultsFileError as exc:
        raise click.UsageError(str(exc)) from None
    except ResultsWriteError as exc:
        raise click.ClickException(str(exc)) from None
    if prepared.damage is not None:
        click.echo(f"warning: {prepared.damage}", err=True)
    elif prepared.start < 0:
        click.echo(f"{path}: the run stopped before its first flush; restarting it from the beginning", err=True)
    return prepared


def report_paper(directory: str, names: list[str], methods: list[MethodName], quiet: bool = False,
                 ) -> tuple[list[dict], bool]:
    """Run paper examples and write the report (``srdda paper ... --report DIR``).

    Returns the table documents ``{"example", "rows"}`` and whether any run,
    table or figure failed (each failure is printed on stderr).
    """
    from .report import make_report

    bars: dict[tuple[str, str], tqdm] = {}

    def progress(example: str, method: str, step: int, total: int) -> None:
        key = (example, method)
        if key not in bars:
            bars[key] = tqdm(total=total, desc=f"{example} {method}", unit="step",
                                 disable=True if quiet else None, leave=False)
        bars[key].update(1)

    try:
        runs, (md, html) = make_report(directory, names, methods, progress)
    finally:
        for bar in bars.values():
            bar.close()
    for run_ in runs:
        for err in run_.errors:
            click.echo(f"error in {run_.name}: {err}", err=True)
    click.echo(f"report written to {md} and {html}", err=True)
    return [{"example": r.name, "rows": r.rows} for r in runs], any(r.errors for r in runs)


PLOTS = ("model", "trajectories", "centroids", "series", "energy", "block-energy")


@click.command("plot")
@click.argument("run", type=RUN)
@click.option("--what", type=click.Choice(PLOTS), default=None,
              help="The blocks at a step, measured-point or centroid paths, time series, the energy ledger (one "
                   "panel per entry) or each block's energies (default: series when --quantity is given, else "
                   "model).")
@click.option("--step", type=int, default=None, help="Recorded step to draw the model at (default: the last).")
@click.option("--quantity", "quantities", multiple=True,
              help="A time series: e.g. energy (the whole ledger), energy.kinetic, velocity.omega, stress.sxx, "
                   "area (repeatable: one figure each).")
@click.option("--block", "blocks", multiple=True,
              help="For --what block-energy: a block name or index (repeatable; default: the moving blocks, at "
                   "most 6).")
@click.option("--color", default="speed", show_default=True,
              help="Block colour for --what model: speed, area_change, velocity.omega, stress.sxx, ... or none.")
@click.option("-o", "--out", type=click.Path(dir_okay=False), default=None,
              help="Image file (png, pdf, svg; default: RUN's name + _WHAT.png).")
def plot_command(run: str, what: str | None, step: int | None, quantities: tuple[str, ...], blocks: tuple[str, ...],
                 color: str, out: str | None) -> None:
    """Draw a results file RUN (or srdda run's output folder): the model at a step, paths, time series, energies."""
    from . import plotting

    res = _read(run)
    what = what or ("series" if quantities else "model")
    try:
        if what == "model":
            index = -1 if step is None else plotting.step_index(res, step)
            figs = {"model": plotting.fig_model(res, index, None if color == "none" else color)}
        elif what in ("trajectories", "centroids"):
            figs = {what: plotting.fig_trajectories(res, "measured" if what == "trajectories" else "centroid")}
        elif what == "energy":
            figs = {"energy": plotting.fig_energy_ledger(res)}
        elif what == "block-energy":
            figs = {"block_energy": plotting.fig_block_energies(res, _stored_arrays(res),
                                                                _block_indices(res, blocks) or None)}
        else:
            if not quantities:
                raise click.UsageError("--what series needs --quantity; one of: energy, "
                                       + ", ".join(plotting.quantity_names(res)))
            figs = {q: plotting.fig_energy_ledger(res) if q == "energy" else plotting.fig_time_series(res, q)
                    for q in quantities}
    except (KeyError, ValueError) as exc:
        raise click.UsageError(str(exc.args[0] if exc.args else exc)) from None
    base = _writable(Path(out) if out else Path(res.path).with_name(f"{Path(res.path).stem}_{what}.png"))
    for name, fig in figs.items():
        path = base if len(figs) == 1 else base.with_name(f"{base.stem}_{name.replace('.', '_')}{base.suffix}")
        try:
            fig.savefig(path, dpi=120)
        except OSError as exc:
            raise click.ClickException(f"cannot write {path} ({exc.strerror})") from None
        click.echo(f"wrote {path}")


def _block_indices(res: StoredResult, blocks: tuple[str, ...]) -> list[int]:
    """Block indices of ``--block`` values (names or indices); one message naming a block that is not there."""
    out = []
    for b in blocks:
        if b in res.block_names:
            out.append(res.block_names.index(b))
        elif b.isdigit() and int(b) < len(res.block_names):
            out.append(int(b))
        else:
            raise click.UsageError(f"--block {b!r}: no such block; the blocks are {', '.join(res.block_names)}")
    return out


def _stored_arrays(res: StoredResult):
    """The model arrays stored in a results file (masses, gravity, block type for per-block energies)."""
    from ..io.results_store import model_arrays_from_file

    try:
        return model_arrays_from_file(res.path)
    except ResultsFileError as exc:
        raise click.UsageError(str(exc)) from None


@click.command("animate")
@click.argument("run", type=RUN)
@click.option("-o", "--out", type=click.Path(dir_okay=False), required=True, help="Output .gif or .mp4.")
@click.option("--fps", type=click.IntRange(min=1), default=20, show_default=True)
@click.option("--frames", type=click.IntRange(min=1), default=200, show_default=True,
              help="At most this many recorded steps, evenly spread.")
@click.option("--color", default="speed", show_default=True, help="Block colour (as for plot) or none.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def animate_command(run: str, out: str, fps: int, frames: int, color: str, quiet: bool) -> None:
    """Animate a results file RUN into a GIF or MP4 (MP4 needs ffmpeg: srdda[mp4]; else GIF)."""
    from .animation import animate

    if Path(out).suffix.lower() not in (".gif", ".mp4"):
        raise click.UsageError(f"-o/--out must end in .gif or .mp4, got {out!r}")
    res = _read(run)
    _writable(Path(out))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with tqdm(total=min(frames, len(res.step)), unit="frame", desc="animate",
                      disable=True if quiet else None) as bar:
                def tick(frame: int, n_frames: int) -> None:
                    bar.total = n_frames
                    bar.update(1)

                path = animate(res, out, fps=fps, max_frames=frames, color=None if color == "none" else color,
                               progress=tick)
        except (KeyError, ValueError) as exc:
            raise click.UsageError(str(exc.args[0] if exc.args else exc)) from None
        except OSError as exc:
            raise click.ClickException(f"cannot write {out} ({exc.strerror})") from None
    for w in caught:
        click.echo(f"warning: {w.message}", err=True)
    click.echo(f"wrote {path}")


@click.command("vtk")
@click.argument("run", type=RUN)
@click.option("-o", "--out", type=click.Path(file_okay=False), required=True, help="Output folder.")
@click.option("--every", type=click.IntRange(min=1), default=None,
              help="Write every N-th recorded step (and the last); default: the smallest N that keeps each series "
                   "at or under 200 files.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def vtk_command(run: str, out: str, every: int | None, quiet: bool) -> None:
    """Write ParaView files (VTU per step, PVD series) of a results file RUN: blocks, contacts, bolts."""
    from ..io.vtk import default_every, series_rows, write_vtu_series

    res = _read(run)
    _writable(Path(out), folder=True)
    every = default_every(len(res.step)) if every is None else every
    try:
        with tqdm(total=len(series_rows(len(res.step), every)), unit="step", desc="vtk",
                  disable=True if quiet else None) as bar:
            pvds = write_vtu_series(res, out, every=every, progress=lambda: bar.update(1))
    except OSError as exc:
        raise click.ClickException(f"cannot write in {out} ({exc.strerror})") from None
    for path in pvds.values():
        click.echo(f"wrote {path}")


@click.command("history")
@click.argument("run", type=RUN)
@click.option("--block", "blocks", multiple=True, help="A block name or index (repeatable).")
@click.option("--point", "points", type=click.IntRange(min=0), multiple=True,
              help="A measured point: its index, in the order the model adds them from 0 (repeatable).")
@click.option("--quantity", "quantities", multiple=True,
              help="What to write (repeatable; default: all). Blocks: centroid, displacement (of the centroid "
                   "from its start), rotation, velocity, stress, area; measured points: position, displacement, "
                   "velocity; or one component, e.g. velocity.vx, stress.sxx, displacement.y.")
@click.option("--csv", "csv_file", type=click.Path(dir_okay=False), default=None,
              help="Write the CSV into this file (default: print it).")
@click.option("--overwrite", is_flag=True, help="Replace the --csv file if it exists (else that is an error).")
def history_command(run: str, blocks: tuple[str, ...], points: tuple[int, ...], quantities: tuple[str, ...],
                    csv_file: str | None, overwrite: bool) -> None:
    """Time histories of blocks and measured points of a results file RUN as CSV, one column per component."""
    from .timehistories import history_table, write_history_csv

    res = _read(run)
    if not blocks and not points:
        raise click.UsageError(f"give --block NAME or --point INDEX; the blocks are {', '.join(res.block_names)}")
    n_points = res.array("measured_position").shape[1]
    wrong = [p for p in points if p >= n_points]
    if wrong:
        raise click.UsageError(f"--point {wrong[0]}: no such measured point; the run has {n_points}"
                               + (f" (0 to {n_points - 1})" if n_points else ""))
    try:
        header, table = history_table(res, _block_indices(res, blocks), points, quantities)
    except ValueError as exc:
        raise click.UsageError(f"--quantity: {exc}") from None
    if csv_file is None:
        write_history_csv(header, table, sys.stdout)
        return
    path = Path(csv_file)
    if path.exists() and not overwrite:
        raise click.UsageError(f"{path} already exists; pass --overwrite to replace it, or choose another --csv")
    try:
        with _writable(path).open("w", encoding="utf-8", newline="") as out:
            write_history_csv(header, table, out)
    except OSError as exc:
        raise click.ClickException(f"cannot write {path} ({exc.strerror})") from None
    click.echo(f"wrote {path}: {len(table)} recorded steps, {len(header)} columns", err=True)
