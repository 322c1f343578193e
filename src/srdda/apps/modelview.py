"""A model drawn before it runs (``srdda show``): blocks by material, joints, supports, bolts, measured points.

2D models are drawn with matplotlib on :func:`srdda.apps.plotting.fig_configuration`'s
symbols; 3D models are rendered with pyvista off-screen
(:mod:`srdda.apps.render3d`), or with matplotlib's 3D axes where pyvista cannot
render. Every symbol has a legend entry.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from . import plotting  # noqa: E402
from ..model import Model, ModelArrays  # noqa: E402
from .render3d import pyvista_renders, render_blocks  # noqa: E402

__all__ = ["fig_model_setup", "material_colors"]

FIXED_ALPHA = 0.35  # fixed blocks (ground, slope) are drawn see-through in 3D, so the moving ones show
MOVING_ALPHA = 0.75  # moving blocks of a 3D model with points, so that points inside them show


def material_colors(n: int) -> list[tuple[float, float, float, float]]:
    """One light colour per block material (matplotlib's Pastel1, then Pastel2)."""
    # matplotlib's stubs type get_cmap as a Colormap; these two are ListedColormaps, which have colors
    palette = [*plt.get_cmap("Pastel1").colors, *plt.get_cmap("Pastel2").colors]  # type: ignore[attr-defined]
    return [palette[k % len(palette)] for k in range(n)]


def _joint_edges(arrays: ModelArrays) -> dict[int, np.ndarray]:
    """Segments (n, 2, dim) of the block edges (2D) or face edges (3D) with a named joint material, per joint row."""
    out: dict[int, list[np.ndarray]] = {}
    if arrays.mesh is None:
        for v in np.flatnonzero(arrays.edge_joint >= 0):
            out.setdefault(int(arrays.edge_joint[v]), []).append(arrays.vertex_position[[v, arrays.vertex_next[v]]])
    elif arrays.face_joint is not None:
        mesh = arrays.mesh
        for f in np.flatnonzero(arrays.face_joint >= 0):
            ring = mesh.face_vertex[mesh.face_ptr[f]:mesh.face_ptr[f + 1]]
            for a, b in zip(ring, np.roll(ring, -1)):
                out.setdefault(int(arrays.face_joint[f]), []).append(arrays.vertex_position[[a, b]])
    return {k: np.array(v) for k, v in out.items()}


def _legend(model: Model, arrays: ModelArrays, colors: list) -> list:
    """Legend handles: each material used, fixed blocks, and the symbols of the 3D picture."""
    used = np.unique(arrays.block_material)
    names = list(model.materials)
    handles: list = [Patch(facecolor=colors[m], edgecolor="k", label=f"material: {names[m]}") for m in used]
    if np.any(arrays.block_fixed):
        handles.append(Patch(facecolor="white", edgecolor="k", hatch="//", label="fixed block"))
    return handles


def fig_model_setup(model: Model, title: str = "") -> Figure:
    """The model as built, before it runs: blocks coloured by material (fixed ones hatched in 2D, see-through in
    3D), named joints, fixed points, springs, hinges, bolts, loads and measured points, each in the legend."""
    arrays = model.arrays()
    colors = material_colors(len(model.materials))
    joint_names = ["default", *model.joint_materials]
    joints = _joint_edges(arrays)
    joint_colors = {row: f"C{k % 10}" for k, row in enumerate(sorted(joints))}
    if arrays.mesh is None:
        fig = plotting.fig_configuration(arrays, title)
        ax = fig.axes[0]
        coll = ax.collections[0]
        coll.set_facecolor([colors[m] for m in arrays.block_material])
        coll.set_hatch(None)  # type: ignore[arg-type]  # matplotlib's stubs say str; None clears the hatch
        for b in np.flatnonzero(arrays.block_fixed):  # hatch the fixed blocks over their material colour
            ax.fill(*arrays.vertex_position[arrays.block_ptr[b]:arrays.block_ptr[b + 1]].T, facecolor="none",
                    edgecolor="0.3", hatch="//", lw=0)
        for row, segments in joints.items():
            for seg in segments:
                ax.plot(*seg.T, color=joint_colors[row], lw=2.5)
        for legend in fig.legends:
            legend.remove()
        handles = [h for h in ax.get_legend_handles_labels()[0] if h.get_label() not in ("fixed block", "moving block")]
        handles += [Line2D([], [], color=joint_colors[r], lw=2.5, label=f"joint: {joint_names[r]}") for r in joints]
        fig.legend(handles=_legend(model, arrays, colors) + handles, fontsize="small", loc="outside lower center",
                   ncols=3)
        return fig
    return _fig_solid_setup(model, arrays, colors, joints, joint_colors, joint_names, title)


def _fig_solid_setup(model: Model, arrays: ModelArrays, colors: list, joints: dict[int, np.ndarray],
                     joint_colors: dict[int, str], joint_names: list[str], title: str) -> Figure:
    """The 3D model: pyvista's picture in a matplotlib figure (title, legend), or matplotlib's 3D axes."""
    assert arrays.mesh is not None  # a 3D model's
    attached, links = arrays.attached, arrays.links
    pts = attached.point_position
    block_colors = [colors[m] for m in arrays.block_material]
    symbols = [(pts[attached.fixed_rows], "black", 12.0, "fixed point", "^"),
               (pts[links.hinge_rows_a], "dimgray", 14.0, "hinge (ball joint)", "o"),
               (pts[attached.load_rows], "tab:orange", 12.0, "point load", "v"),
               (pts[attached.measured_rows], "tab:red", 10.0, "measured point", "o")]
    bolt_ends = np.zeros((0, 2, 3))
    if links.n_bolts:
        rb = links.bolt_rows_b
        bolt_ends = np.stack([pts[links.bolt_rows_a], np.where((rb >= 0)[:, None], pts[np.maximum(rb, 0)],
                                                               links.bolt_ground)], axis=1)
    ends_a = np.concatenate([attached.point_spring_rows_a, links.spring_rows_a]).astype(np.int64)
    ends_b = np.concatenate([attached.point_spring_rows_b, links.spring_rows_b]).astype(np.int64)
    springs = np.stack([pts[ends_a], pts[ends_b]], axis=1)
    lines = [(bolt_ends, "tab:red", 4.0, "bolt"), (springs, "tab:green", 3.0, "spring"),
             *((segs, joint_colors[r], 4.0, f"joint: {joint_names[r]}") for r, segs in joints.items())]
    handles = [h for h in _legend(model, arrays, colors) if h.get_label() != "fixed block"]
    if np.any(arrays.block_fixed):
        handles.append(Patch(facecolor="0.9", edgecolor="0.6", label="fixed block (see-through)"))
    handles += [Line2D([], [], ls="none", marker=m, color=c, label=label) for p, c, _, label, m in symbols if len(p)]
    handles += [Line2D([], [], color=c, lw=2.5, label=label) for segs, c, _, label in lines if len(segs)]
    fig = plt.figure(figsize=(8, 7), layout="constrained")
    if pyvista_renders():
        # points often lie inside or on blocks (a centroid, a hinge between two faces): moving blocks are then
        # drawn slightly see-through so that they show
        solid = MOVING_ALPHA if any(len(p) for p, *_ in symbols) else 1.0
        image = render_blocks(arrays.vertex_position, arrays.mesh, colors=block_colors,
                              opacity=np.where(arrays.block_fixed, FIXED_ALPHA, solid),
                              points=[(p, c, s) for p, c, s, _, _ in symbols],
                              segments=[(s, c, w) for s, c, w, _ in lines])
        ax = fig.add_subplot()
        ax.imshow(image)
        ax.set_axis_off()
    else:
        ax = fig.add_subplot(projection="3d")
        coll = plotting.plot_solid_blocks(ax, arrays.vertex_position, arrays.mesh)
        alpha = np.where(arrays.block_fixed, FIXED_ALPHA, 1.0)
        coll.set_facecolor([(*block_colors[b][:3], alpha[b]) for b in arrays.mesh.face_block])
        for p, c, _, _, m in symbols:
            if len(p):
                ax.plot(*p.T, ls="none", marker=m, color=c)
        for segs, c, _, _ in lines:
            for seg in segs:
                ax.plot(*seg.T, color=c, lw=2.0)
        plotting.solid_limits(ax, arrays.vertex_position)
    ax.set_title(title)
    fig.legend(handles=handles, fontsize="small", loc="outside lower center", ncols=3)
    return fig
