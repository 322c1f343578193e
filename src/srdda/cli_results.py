"""Command-line tools for results files: ``srdda plot``, ``srdda animate``, ``srdda vtk``, resuming a run."""
from __future__ import annotations

import warnings
from pathlib import Path

import click
from tqdm import tqdm

from .io.results_store import (ResultsDamageWarning, ResultsFileError, ResultsInUseError, ResultsWriteError,
                               Resumption, StoredResult, prepare_resume, read_results)

__all__ = ["plot_command", "animate_command", "vtk_command", "prepare_resume_run", "report_paper"]

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


@click.command("plot")
@click.argument("run", type=RUN)
@click.option("--what", type=click.Choice(["model", "trajectories", "centroids", "series"]), default="model",
              show_default=True, help="The blocks at a step, measured-point or centroid paths, or a time series.")
@click.option("--step", type=int, default=None, help="Recorded step to draw the model at (default: the last).")
@click.option("--quantity", "quantities", multiple=True,
              help="For --what series: e.g. energy.total, velocity.omega, area, stress.sxx (repeatable).")
@click.option("--color", default="speed", show_default=True,
              help="Block colour for --what model: speed, area_change, velocity.omega, stress.sxx, ... or none.")
@click.option("-o", "--out", type=click.Path(dir_okay=False), default=None,
              help="Image file (png, pdf, svg; default: RUN's name + _WHAT.png).")
def plot_command(run: str, what: str, step: int | None, quantities: tuple[str, ...], color: str,
                 out: str | None) -> None:
    """Draw a results file RUN (or srdda run's output folder): the model at a step, trajectories or time series."""
    from . import plotting

    res = _read(run)
    try:
        if what == "model":
            index = -1 if step is None else plotting.step_index(res, step)
            figs = {"model": plotting.fig_model(res, index, None if color == "none" else color)}
        elif what in ("trajectories", "centroids"):
            figs = {what: plotting.fig_trajectories(res, "measured" if what == "trajectories" else "centroid")}
        else:
            if not quantities:
                raise click.UsageError("--what series needs --quantity; one of: "
                                       + ", ".join(plotting.quantity_names(res)))
            figs = {q: plotting.fig_time_series(res, q) for q in quantities}
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


@click.command("animate")
@click.argument("run", type=RUN)
@click.option("-o", "--out", type=click.Path(dir_okay=False), required=True, help="Output .gif or .mp4.")
@click.option("--fps", type=click.IntRange(min=1), default=20, show_default=True)
@click.option("--frames", type=click.IntRange(min=1), default=200, show_default=True,
              help="At most this many recorded steps, evenly spread.")
@click.option("--color", default="speed", show_default=True, help="Block colour (as for plot) or none.")
def animate_command(run: str, out: str, fps: int, frames: int, color: str) -> None:
    """Animate a results file RUN into a GIF or MP4 (MP4 needs ffmpeg: srdda[mp4]; else GIF)."""
    from .animation import animate

    if Path(out).suffix.lower() not in (".gif", ".mp4"):
        raise click.UsageError(f"-o/--out must end in .gif or .mp4, got {out!r}")
    res = _read(run)
    _writable(Path(out))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            path = animate(res, out, fps=fps, max_frames=frames, color=None if color == "none" else color)
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
@click.option("--every", type=click.IntRange(min=1), default=1, show_default=True,
              help="Write every N-th recorded step (and the last).")
def vtk_command(run: str, out: str, every: int) -> None:
    """Write ParaView files (VTU per step, PVD series) of a results file RUN."""
    from .io.vtk import write_vtu_series

    res = _read(run)
    _writable(Path(out), folder=True)
    try:
        pvds = write_vtu_series(res, out, every=every)
    except OSError as exc:
        raise click.ClickException(f"cannot write in {out} ({exc.strerror})") from None
    for path in pvds.values():
        click.echo(f"wrote {path}")
