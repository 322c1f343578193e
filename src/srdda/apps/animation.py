"""Animations of a results file: GIF (Pillow, always there) or MP4 (ffmpeg, optional).

2D runs are drawn with matplotlib; 3D runs are rendered frame by frame with
pyvista off-screen (:mod:`srdda.apps.render3d`), else with matplotlib's 3D axes.

MP4 needs an ffmpeg executable: the one on PATH, or the one the optional
extra ``pip install srdda[mp4]`` (imageio-ffmpeg) brings. Without it an
``.mp4`` request writes a GIF beside it (same name, ``.gif``) and warns.
"""
from __future__ import annotations

import shutil
import warnings
from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import animation, cm, colors as mcolors  # noqa: E402

from ..io.results_store import StoredResult, read_results  # noqa: E402
from .render3d import pyvista_renders, render_blocks  # noqa: E402
from .plotting import (block_values, history, plot_blocks, plot_solid_blocks, quantity_label,  # noqa: E402
                       solid_faces, solid_limits, step_title)

__all__ = ["animate", "ffmpeg_path"]


def ffmpeg_path() -> str | None:
    """An ffmpeg executable: on PATH, else imageio-ffmpeg's (the ``srdda[mp4]`` extra); None if neither."""
    found = shutil.which("ffmpeg")
    if found:
        return found
    try:
        import imageio_ffmpeg
    except ImportError:
        return None
    return imageio_ffmpeg.get_ffmpeg_exe()


def _frames(n_rows: int, max_frames: int) -> np.ndarray:
    """Evenly spread recorded rows, always the first and the last."""
    if n_rows <= max_frames:
        return np.arange(n_rows)
    return np.unique(np.linspace(0, n_rows - 1, max_frames).round().astype(int))


def animate(results: StoredResult | str | Path, out: str | Path, fps: int = 20, max_frames: int = 200,
            color: str | None = "speed", dpi: int = 80, progress: Callable[[int, int], None] | None = None) -> Path:
    """Write an animation of the blocks and the measured points' paths; returns the file written.

    The suffix of ``out`` picks the format (``.gif`` or ``.mp4``); at most
    ``max_frames`` recorded steps are shown, evenly spread over the run.
    ``progress(frame, n_frames)`` is called after each frame is drawn.
    """
    res = results if isinstance(results, StoredResult) else read_results(results)
    out = Path(out)
    if out.suffix.lower() not in (".gif", ".mp4"):
        raise ValueError(f"animation file must end in .gif or .mp4, got {out.name!r}")
    if fps < 1 or max_frames < 1:
        raise ValueError("fps and max_frames must be >= 1")
    exe = ffmpeg_path() if out.suffix.lower() == ".mp4" else None
    if out.suffix.lower() == ".mp4" and exe is None:
        out = out.with_suffix(".gif")
        warnings.warn(f"no ffmpeg found (install srdda[mp4] or put ffmpeg on PATH); writing {out.name} instead",
                      stacklevel=2)
    with matplotlib.rc_context({"animation.ffmpeg_path": exe} if exe else {}):
        _write_animation(res, out, fps, max_frames, color, dpi, progress)
    return out


def _write_animation(res: StoredResult, out: Path, fps: int, max_frames: int, color: str | None, dpi: int,
                     progress: Callable[[int, int], None] | None = None) -> None:
    """Draw and save the frames with the writer the suffix of ``out`` picks."""
    writer = animation.FFMpegWriter(fps=fps) if out.suffix.lower() == ".mp4" else animation.PillowWriter(fps=fps)

    verts = history(res, "vertices")
    mp = history(res, "measured_position")
    frames = _frames(len(history(res, "step")), max_frames)
    if res.mesh is not None:
        _write_solid_animation(res, out, writer, frames, color, dpi, progress)
        return
    fig, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    values = block_values(res, 0, color)
    coll = plot_blocks(ax, verts[0], res.block_ptr, values)
    if color is not None:  # then there are values
        all_values = np.concatenate([block_values(res, int(i), color) for i in frames])
        coll.set_clim(float(all_values.min()), float(all_values.max()) or 1.0)
        fig.colorbar(coll, ax=ax, label=quantity_label(res, color))
    trails = [ax.plot([], [], lw=0.8)[0] for _ in range(mp.shape[1])]
    allv = verts[frames].reshape(-1, 2)
    pad = 0.05 * float(np.ptp(allv, axis=0).max() or 1.0)
    ax.set_xlim(allv[:, 0].min() - pad, allv[:, 0].max() + pad)
    ax.set_ylim(allv[:, 1].min() - pad, allv[:, 1].max() + pad)
    ax.set(xlabel="x (m)", ylabel="y (m)")
    ptr = res.block_ptr

    def draw(i: int) -> list:
        coll.set_verts([verts[i][a:b] for a, b in zip(ptr[:-1], ptr[1:])])
        if color is not None:
            coll.set_array(block_values(res, i, color))
        for k, line in enumerate(trails):
            line.set_data(mp[: i + 1, k, 0], mp[: i + 1, k, 1])
        ax.set_title(step_title(res, i))
        return [coll, *trails]

    _save(fig, draw, frames, out, writer, dpi, progress)


def _write_solid_animation(res: StoredResult, out: Path, writer: animation.AbstractMovieWriter, frames: np.ndarray,
                           color: str | None, dpi: int, progress: Callable[[int, int], None] | None = None) -> None:
    """The 3D blocks' faces and the measured points' paths, frame by frame (pyvista, else matplotlib's 3D axes)."""
    verts = history(res, "vertices")
    mp = history(res, "measured_position")
    mesh = res.mesh
    assert mesh is not None  # a 3D result's
    if pyvista_renders():
        _write_rendered_animation(res, out, writer, frames, color, dpi, progress)
        return
    fig = plt.figure(figsize=(6.4, 5.6), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    values = block_values(res, 0, color)
    coll = plot_solid_blocks(ax, verts[0], mesh, values)
    if color is not None:  # then there are values
        all_values = np.concatenate([block_values(res, int(i), color) for i in frames])
        coll.set_clim(float(all_values.min()), float(all_values.max()) or 1.0)
        fig.colorbar(coll, ax=ax, label=quantity_label(res, color), shrink=0.6)
    trails = [ax.plot([], [], [], lw=0.8)[0] for _ in range(mp.shape[1])]
    solid_limits(ax, verts[frames].reshape(-1, verts.shape[-1]))

    def draw(i: int) -> list:
        coll.set_verts(solid_faces(verts[i], mesh)[0])
        if color is not None:
            coll.set_array(block_values(res, i, color)[mesh.face_block])
        for k, line in enumerate(trails):
            line.set_data_3d(*mp[: i + 1, k].T)
        ax.set_title(step_title(res, i))
        return [coll, *trails]

    _save(fig, draw, frames, out, writer, dpi, progress)


def _write_rendered_animation(res: StoredResult, out: Path, writer: animation.AbstractMovieWriter,
                              frames: np.ndarray, color: str | None, dpi: int,
                              progress: Callable[[int, int], None] | None = None) -> None:
    """3D frames rendered by pyvista off-screen (one fixed view over the whole run) shown in a matplotlib figure."""
    verts = history(res, "vertices")
    mp = history(res, "measured_position")
    mesh = res.mesh
    points = verts[frames].reshape(-1, verts.shape[-1])
    lo, hi = points.min(axis=0), points.max(axis=0)
    bounds = np.column_stack([lo, hi]).ravel()
    values = [block_values(res, int(i), color) for i in frames] if color is not None else None
    clim = None if values is None else (float(np.min(values)), float(np.max(values)) or 1.0)
    size = (int(6.4 * dpi * 1.25), int(5.6 * dpi * 1.25))

    def image(k: int) -> np.ndarray:
        i = int(frames[k])
        paths = [(np.stack([mp[:i, p], mp[1:i + 1, p]], axis=1), f"C{p % 10}", 3.0) for p in range(mp.shape[1])]
        return render_blocks(verts[i], mesh, None if values is None else values[k], clim=clim, segments=paths,
                             size=size, bounds=bounds)

    fig, ax = plt.subplots(figsize=(6.4, 5.6), layout="constrained")
    ax.set_axis_off()
    shown = ax.imshow(image(0))
    if clim is not None:
        assert color is not None  # clim comes with a quantity
        fig.colorbar(cm.ScalarMappable(mcolors.Normalize(*clim), "viridis"), ax=ax, label=quantity_label(res, color),
                     shrink=0.6)
    where = {int(i): k for k, i in enumerate(frames)}

    def draw(i: int) -> list:
        shown.set_data(image(where[i]))
        ax.set_title(step_title(res, i))
        return [shown]

    _save(fig, draw, frames, out, writer, dpi, progress)


def _save(fig: plt.Figure, draw: Callable[[int], list], frames: np.ndarray, out: Path,
          writer: animation.AbstractMovieWriter, dpi: int, progress: Callable[[int, int], None] | None = None) -> None:
    """Draw every frame with ``draw`` and write the animation (``progress(frame, n_frames)`` after each)."""
    anim = animation.FuncAnimation(fig, draw, frames=[int(i) for i in frames], blit=False)
    out.parent.mkdir(parents=True, exist_ok=True)
    anim.save(out, writer=writer, dpi=dpi, progress_callback=progress)
    plt.close(fig)
