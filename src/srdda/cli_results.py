"""Command-line tools for results files: ``srdda plot``, ``srdda animate``, ``srdda vtk``, resuming a run."""
from __future__ import annotations

import warnings
from pathlib import Path

import click
from tqdm import tqdm

from .backends.arrays import GpuUnavailable
from .io.results_store import ResultsFileError, ResultsWriteError, StoredResult, read_results, resume

__all__ = ["plot_command", "animate_command", "vtk_command", "resume_run", "report_paper"]

RUN = click.Path(exists=True)


def _read(path: str) -> StoredResult:
    """The results file RUN, or RUN/results.h5 when RUN is the output folder of ``srdda run``."""
    if Path(path).is_dir():
        path = str(Path(path) / "results.h5")
    try:
        res = read_results(path)
    except ResultsFileError as exc:
        raise click.UsageError(str(exc)) from None
    if "step" not in res.histories or len(res.step) == 0:
        raise click.UsageError(f"{path}: no recorded step was flushed yet")
    return res


def _writable(path: Path, folder: bool = False) -> Path:
    """``path`` with its folder (``folder``: itself) created; one clear message if that cannot be done."""
    try:
        (path if folder else path.parent).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise click.ClickException(f"cannot write {path} ({exc.strerror})") from None
    return path


def resume_run(path: str, quiet: bool = False, flush_every: int | None = None) -> str:
    """Continue a results file's run to its last step (``srdda run --resume``); returns the final status."""
    try:
        stored = read_results(path)
        steps = stored.histories.get("step", [])
        if len(steps) == 0:
            click.echo(f"{path}: the run stopped before its first flush; restarting it from the beginning", err=True)
        done = int(steps[-1]) if len(steps) else 0
        with tqdm(total=max(0, int(stored.settings.n_steps) - done), disable=True if quiet else None, unit="step",
                  desc=f"resume {stored.method}") as bar:
            result = resume(path, flush_every=flush_every, progress=lambda _: bar.update(1))
    except (ResultsFileError, GpuUnavailable) as exc:  # a GPU run resumed where there is no GPU: one message
        raise click.UsageError(f"{path}: {exc}" if isinstance(exc, GpuUnavailable) else str(exc)) from None
    except ResultsWriteError as exc:
        raise click.ClickException(str(exc)) from None
    final = read_results(path)
    click.echo(f"{result.status}: {path} now holds steps {int(final.step[0])}..{int(final.step[-1])} "
               f"({len(final.step)} recorded)")
    return result.status


def report_paper(directory: str, names: list[str], methods: list[str], quiet: bool = False,
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
    from .io.results_store import model_arrays_from_file

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
    from .io.vtk import default_every, series_rows, write_vtu_series

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
