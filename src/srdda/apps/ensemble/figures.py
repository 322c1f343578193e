"""The ensemble's figures (matplotlib, Agg): runout distribution, envelopes along the slope, trajectories.

Each is drawn from the assembled tables and saved as ``figures/<name>.png``;
:func:`ensemble_figures` returns ``(caption, path)`` pairs for the report.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow as pa  # noqa: E402

from .. import plotting  # noqa: E402
from ...io.modelfile import model_from_dict  # noqa: E402
from .spec import EnsembleSpec  # noqa: E402

__all__ = ["ensemble_figures"]

MAX_TRAJECTORIES = 500  # more paths than this are drawn as the first 500 runs (the figure would be one blot)


def _save(fig: plt.Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _runout(runs: pa.Table, axis: str) -> plt.Figure:
    """Histogram of where the runs stopped, and the fraction of all runs stopped before each position.

    Runs that left the stop domain have no stopping point: they are left out of
    the histogram and counted in the fraction's denominator only (the curve
    ends below 1 by their share).
    """
    ok = np.array(runs.column("status").to_pylist()) == "ok"
    left = np.array(runs.column("stop_reason").to_pylist()) == "out_of_domain"
    end = np.sort(runs.column(f"end_{axis}").to_numpy()[ok & ~left])
    total = int(ok.sum())
    fig, (hist, cdf) = plt.subplots(1, 2, figsize=(9.5, 3.6))
    hist.hist(end, bins=max(5, min(40, len(end) // 5)), color="#4a7ab5", edgecolor="white")
    hist.set_xlabel(f"end position {axis} (m)")
    hist.set_ylabel("runs")
    fraction = np.arange(1, len(end) + 1) / max(total, 1)
    cdf.step(end, fraction, where="post", color="k")
    for q, style in ((50, ":"), (95, "--"), (99, "-.")):
        k = int(np.ceil(q / 100 * total)) - 1  # the q-th percentile run, if it stopped in the domain
        if 0 <= k < len(end):
            cdf.axvline(end[k], color="0.4", linestyle=style, label=f"P{q}")
    cdf.set_ylim(0, 1.02)
    cdf.set_xlabel(f"end position {axis} (m)")
    cdf.set_ylabel("fraction of runs stopped before")
    cdf.legend(loc="lower right")
    out = f"; {int((ok & left).sum())} left the domain" if np.any(ok & left) else ""
    fig.suptitle(f"Runout of {total} runs{out}")
    fig.tight_layout()
    return fig


def _envelopes(spec: EnsembleSpec, collectors: pa.Table, dim: int) -> plt.Figure:
    placed = sorted(spec.all_collectors(dim), key=lambda c: c.at[0])
    x = np.array([c.at[0] for c in placed])
    names = np.array(collectors.column("collector").to_pylist(), dtype=object)
    crossed = collectors.column("crossed").to_numpy(zero_copy_only=False)
    energy_unit = "J/m" if dim == 2 else "J"
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for ax, quantity, label in ((axes[0], "kinetic", f"kinetic energy ({energy_unit})"),
                                (axes[1], "bounce_height", "bounce height (m)")):
        values = collectors.column(quantity).to_numpy()
        curves: dict[str, list[float]] = {"P50": [], "P95": [], "max": []}
        for c in placed:
            v = values[(names == c.name) & crossed]
            v = v[np.isfinite(v)]
            for key, stat in (("P50", 50), ("P95", 95), ("max", 100)):
                curves[key].append(np.percentile(v, stat) if len(v) else np.nan)
        for (key, ys), style in zip(curves.items(), ("-", "--", ":")):
            ax.plot(x, ys, style, marker="o", markersize=3, color="k", label=key)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend()
    axes[1].set_xlabel("collector position x (m)")
    fig.suptitle("Envelopes at the collectors (runs that crossed each)")
    fig.tight_layout()
    return fig


def _trajectories(base: dict[str, Any], runs: pa.Table, trajectories: pa.Table, dim: int) -> plt.Figure:
    fig, ax = plt.subplots(figsize=(9, 5))
    up = "z" if dim == 3 else "y"
    if dim == 2:
        model, _ = model_from_dict(base, "base model")
        background = plotting.fixed_blocks(model)
        if background is not None:
            plotting.plot_blocks(ax, background[0], background[1], facecolor="0.85", edgecolor="0.4")
    run_ids = trajectories.column("run").to_numpy()
    xs, ys = trajectories.column("x").to_numpy(), trajectories.column(up).to_numpy()
    starts = np.flatnonzero(np.r_[True, run_ids[1:] != run_ids[:-1]])
    bounds = list(zip(starts, [*starts[1:], len(run_ids)]))[:MAX_TRAJECTORIES]
    for a, b in bounds:
        ax.plot(xs[a:b], ys[a:b], color="#c0392b", alpha=0.25, linewidth=0.7)
    ok = np.array(runs.column("status").to_pylist()) == "ok"
    ax.plot(runs.column("end_x").to_numpy()[ok], runs.column(f"end_{up}").to_numpy()[ok], "k.", markersize=3,
            label="end positions")
    ax.set_xlabel("x (m)")
    ax.set_ylabel(f"{up} (m)")
    ax.set_aspect("equal")
    ax.legend(loc="upper right")
    ax.set_title(f"Centroid paths of {len(bounds)} runs")
    fig.tight_layout()
    return fig


def ensemble_figures(spec: EnsembleSpec, base: dict[str, Any], runs: pa.Table, collectors: pa.Table,
                     trajectories: pa.Table, dim: int, folder: Path) -> list[tuple[str, Path]]:
    """Draw and save the figures; ``(caption, path)`` of each."""
    figures = [("Runout: histogram of where the tracked block stopped (x of its centroid) and the fraction of all "
                "runs stopped before each x (runs that left the domain are in the fraction's denominator only).",
                _save(_runout(runs, "x"), folder / "runout.png"))]
    if spec.all_collectors(dim):
        figures.append(("Kinetic energy (translational + rotational) and bounce height at the collectors: "
                        "median (P50), 95th percentile and maximum of the runs that crossed each.",
                        _save(_envelopes(spec, collectors, dim), folder / "envelopes.png")))
    figures.append(("Trajectories of the tracked block's centroid, overlaid, with the end positions.",
                    _save(_trajectories(base, runs, trajectories, dim), folder / "trajectories.png")))
    return figures
