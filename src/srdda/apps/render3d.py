"""3D pictures of polyhedral blocks: pyvista (VTK) rendering off-screen, matplotlib's 3D axes as the fallback.

:func:`render_blocks` renders blocks' faces (coloured per block by values or
by given colours), points and segments into an RGB image with pyvista,
without a display: VTK's EGL (or OSMesa) window when there is no X server
(docs/results.md, *3D pictures*). :func:`pyvista_renders` says whether this
machine can (checked once per process by rendering a tiny scene); where it
cannot (no pyvista, no OpenGL library), or where ``SRDDA_3D_RENDERER=matplotlib``
is set, the figure functions of :mod:`srdda.apps.plotting` draw with matplotlib's
3D axes instead: slower, and faces may overlap wrongly, but always there.
"""
from __future__ import annotations

import functools
import os
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["pyvista_renders", "render_blocks", "RENDERER_VARIABLE"]

RENDERER_VARIABLE = "SRDDA_3D_RENDERER"  # "matplotlib": never use pyvista


def _import_pyvista() -> Any:
    """pyvista, told to render off-screen; without a display on Linux, VTK's EGL window (no X attempt)."""
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista

    pyvista.OFF_SCREEN = True
    return pyvista


@functools.cache
def pyvista_renders() -> bool:
    """True when pyvista is installed and renders off-screen here (a tiny scene is rendered once to check)."""
    if os.environ.get(RENDERER_VARIABLE, "").lower() == "matplotlib":
        return False
    try:
        pv = _import_pyvista()
        plotter = pv.Plotter(off_screen=True, window_size=(16, 16))
        plotter.add_mesh(pv.Cube())
        image = plotter.screenshot(return_img=True)
        plotter.close()
    except Exception:  # noqa: BLE001 - any failure (no library, no OpenGL context) means: use matplotlib
        return False
    return image is not None and image.size > 0


def _faces_polydata(pv: Any, vertices: np.ndarray, face_ptr: np.ndarray, face_vertex: np.ndarray) -> Any:
    """The faces as one pyvista PolyData (VTK's flat cell array: count, indices, count, ...)."""
    counts = np.diff(face_ptr)
    cells = np.insert(face_vertex.astype(np.int64), face_ptr[:-1], counts)
    return pv.PolyData(np.asarray(vertices, dtype=float), cells)


def render_blocks(vertices: np.ndarray, mesh: Any, values: np.ndarray | None = None,
                  colors: Sequence[Any] | None = None, clim: tuple[float, float] | None = None,
                  cmap: str = "viridis", opacity: Sequence[float] | np.ndarray | None = None,
                  points: Sequence[tuple[np.ndarray, str, float]] = (),
                  segments: Sequence[tuple[np.ndarray, str, float]] = (),
                  size: tuple[int, int] = (900, 700), bounds: Sequence[float] | np.ndarray | None = None
                  ) -> np.ndarray:
    """An RGB image (h, w, 3) of 3D blocks rendered off-screen with pyvista.

    ``mesh`` is a :class:`~srdda.geometry.polyhedron.PolyhedronMesh`; each
    block is coloured by ``values`` (one per block, on ``cmap`` within
    ``clim``), else by ``colors`` (one matplotlib colour per block), else
    light blue; ``opacity`` per block (default opaque). ``points``: (xyz (n,
    3), colour, size in pixels) drawn as spheres; ``segments``: (ends (n, 2,
    3), colour, width in pixels). The camera looks from the (+x, −y, +z)
    side at the whole scene, or at ``bounds`` (xmin, xmax, ymin, ymax, zmin,
    zmax: the same view for every frame of an animation), with the bounding
    box's axes labelled in metres.
    """
    from matplotlib.colors import to_rgb

    pv = _import_pyvista()
    plotter = pv.Plotter(off_screen=True, window_size=size)
    plotter.set_background("white")
    face_block = np.asarray(mesh.face_block)
    nb = len(mesh.block_ptr) - 1
    alpha = np.ones(nb) if opacity is None else np.asarray(opacity, dtype=float)
    for level in np.unique(alpha):  # VTK takes one opacity per actor
        keep = np.flatnonzero(alpha[face_block] == level)
        if not len(keep):
            continue
        starts, ends = mesh.face_ptr[keep], mesh.face_ptr[keep + 1]
        face_vertex = np.concatenate([mesh.face_vertex[a:b] for a, b in zip(starts, ends)])
        face_ptr = np.concatenate([[0], np.cumsum(ends - starts)])
        poly = _faces_polydata(pv, vertices, face_ptr, face_vertex)
        style: dict[str, Any] = {"show_edges": True, "edge_color": "black", "line_width": 1.0,
                                 "opacity": float(level), "lighting": True}
        if values is not None:
            poly.cell_data["value"] = np.asarray(values, dtype=float)[face_block[keep]]
            plotter.add_mesh(poly, scalars="value", cmap=cmap, clim=clim, show_scalar_bar=False, **style)
        else:
            rgb = (np.array([to_rgb(c) for c in colors]) if colors is not None
                   else np.tile(to_rgb("#c8d6e5"), (nb, 1)))
            poly.cell_data["rgb"] = (255 * rgb[face_block[keep]]).astype(np.uint8)
            plotter.add_mesh(poly, scalars="rgb", rgb=True, **style)
    for xyz, color, px in points:
        xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
        if len(xyz):
            plotter.add_points(xyz, color=to_rgb(color), point_size=px, render_points_as_spheres=True)
    for ends, color, width in segments:
        ends = np.asarray(ends, dtype=float).reshape(-1, 2, 3)
        if len(ends):
            plotter.add_lines(ends.reshape(-1, 3), color=to_rgb(color), width=width)
    plotter.camera_position = "iso"
    plotter.camera.azimuth = -90.0  # iso looks from (+x, +y, +z); turn to the (+x, -y, +z) side
    plotter.reset_camera(bounds=None if bounds is None else [float(b) for b in bounds])
    plotter.show_grid(xtitle="x (m)", ytitle="y (m)", ztitle="z (m)", color="gray", font_size=10,
                      bounds=None if bounds is None else [float(b) for b in bounds])
    image = plotter.screenshot(return_img=True)
    plotter.close()
    return np.asarray(image)
