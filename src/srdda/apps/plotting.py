"""Figures of runs (matplotlib, Agg backend): any run, and the paper's figures per method.

Every function takes recorded histories — an in-memory
:class:`~srdda.simulation.Result` or a :class:`~srdda.io.results_store.StoredResult`
— and returns a matplotlib ``Figure``; nothing is drawn on screen. The
paper's figures put the three methods side by side (one column each, in the
order of the ``results`` mapping):

=============================  ===========================================
:func:`fig_configuration`       Figs. 3, 5, 7, 11, 14: the model set-up
:func:`fig_swing_trajectories`  Figs. 4 and 6: pendulum / rod trajectories,
                                zoomed view of the offset, radial offset
:func:`fig_wave_shapes`         Figs. 8-10: bar-chain shape at given steps
:func:`fig_nunchaku`            Figs. 12, 13: hinge-point trajectories,
                                angular velocities, point C of all methods
:func:`fig_rockfall`            Fig. 15: trajectories of P1 and P2 over the
                                slope
:func:`fig_energy_ledger`       every run: the energy ledger, one panel per
                                entry (stored, work in, dissipated, error)
=============================  ===========================================

Every axis carries its SI unit (:func:`quantity_unit`); energies are J per
metre of thickness in 2D, J in 3D.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, overload

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from ..model import Model  # noqa: E402
from ..results import removed_blocks  # noqa: E402

__all__ = ["history", "quantity_names", "components", "block_values", "method_label", "plot_blocks", "fixed_blocks",
           "fig_configuration",
           "fig_model", "fig_solid_model", "step_title", "plot_solid_blocks", "solid_faces", "solid_limits",
           "fig_trajectories", "fig_time_series", "plot_bolts", "fig_bolt_forces",
           "fig_swing_trajectories", "fig_wave_shapes", "fig_nunchaku", "fig_rockfall", "step_index",
           "quantity_unit", "quantity_label", "quantity_words", "fig_energy_ledger", "ledger_series", "ledger_panels",
           "LEDGER_PANELS",
           "block_energies", "fig_block_energies", "ENERGY_WORDS"]

Results = Any  # Result or StoredResult: both have .array(name), .block_names, .method
Background = tuple[np.ndarray, np.ndarray]  # (vertices, block_ptr) of blocks drawn grey (slopes, ground)

ENERGY_NAMES = ("kinetic", "gravity", "elastic", "spring", "total")
VELOCITY_COMPONENTS = ("vx", "vy", "omega", "exx_rate", "eyy_rate", "gxy_rate")
VELOCITY_COMPONENTS_3D = ("vx", "vy", "vz", "omega_x", "omega_y", "omega_z", "exx_rate", "eyy_rate", "ezz_rate",
                          "gyz_rate", "gzx_rate", "gxy_rate")
STRESS_COMPONENTS = ("sxx", "syy", "sxy")
STRESS_COMPONENTS_3D = ("sxx", "syy", "szz", "syz", "szx", "sxy")
XY = ("x", "y")
XYZ = ("x", "y", "z")
MAX_LEGEND = 12  # more lines than this get no legend (it would cover the plot)


def _energy_names(res: Results) -> tuple[str, ...]:
    if hasattr(res, "energy_names"):
        return tuple(res.energy_names)
    return tuple(res.energy[0]) if res.energy else ENERGY_NAMES


def components(res: Results) -> dict[str, tuple[str, ...]]:
    """The component names of the vector histories of ``res`` (2D or 3D)."""
    solid = _dim(res) == 3
    coords = XYZ if solid else XY
    return {"velocity": VELOCITY_COMPONENTS_3D if solid else VELOCITY_COMPONENTS,
            "stress": STRESS_COMPONENTS_3D if solid else STRESS_COMPONENTS, "centroid": coords,
            "measured_position": coords, "measured_velocity": coords}


def history(res: Results, name: str) -> np.ndarray:
    """A recorded quantity as an array (first axis = recorded step).

    ``name`` is a history (``time``, ``centroid``, ``velocity``, ...), an energy
    (``energy.kinetic``), a velocity component (``velocity.omega``, ``vx`` ...
    see ``VELOCITY_COMPONENTS``, ``VELOCITY_COMPONENTS_3D``), a stress
    component (``stress.sxx``) or a coordinate of a vector history
    (``measured_position.y``, ``centroid.x``).
    """
    if "." not in name:
        return np.asarray(res.array(name))
    base, part = name.split(".", 1)
    if base == "energy":
        names = _energy_names(res)
        if part not in names:
            raise KeyError(f"no energy {part!r}; energies are {names}")
        return np.asarray(res.array("energy"))[:, names.index(part)]
    comps = components(res).get(base)
    if comps is None or part not in comps:
        raise KeyError(f"unknown quantity {name!r}; try one of {quantity_names(res)}")
    return np.asarray(res.array(base))[..., comps.index(part)]


def quantity_names(res: Results) -> list[str]:
    """Every name :func:`history` accepts for ``res``."""
    comps = components(res)
    return (["area", "rotation", "iterations", "bolt_force", "bolt_shear_force"]
            + [f"velocity.{c}" for c in comps["velocity"]]
            + [f"stress.{c}" for c in comps["stress"]] + [f"energy.{e}" for e in _energy_names(res)]
            + [f"{v}.{c}" for v in ("centroid", "measured_position", "measured_velocity") for c in comps[v]])


_UNITS = {"time": "s", "step": "step", "area": "m²", "rotation": "rad", "iterations": "solves",
          "velocity.vx": "m/s", "velocity.vy": "m/s", "velocity.vz": "m/s", "velocity.omega": "rad/s",
          "velocity.omega_x": "rad/s", "velocity.omega_y": "rad/s", "velocity.omega_z": "rad/s", "velocity": "1/s",
          "stress": "Pa", "centroid": "m", "measured_position": "m", "measured_velocity": "m/s",
          "closed_contacts": "contacts", "max_penetration": "m", "multipliers": "N/m", "speed": "m/s",
          "area_change": "1", "bolt_force": "N", "bolt_shear_force": "N", "bolt_broken": "1", "bolt_break_time": "s"}

# What each quantity is, in words, for axis labels (energies: the ledger's entries, srdda.ledger)
ENERGY_WORDS = {"kinetic": "kinetic energy", "gravity": "gravitational energy (every block, fixed ones included)",
                "elastic": "strain energy of the blocks", "spring": "energy in springs and penalty supports",
                "contact": "energy in the contact springs", "total": "total stored energy",
                "work_loads": "work of loads and base acceleration", "work_prescribed": "work of prescribed motion",
                "work_constraints": "work of hinge forces", "dissipated": "energy dissipated by dashpots",
                "dissipated_friction": "energy dissipated by friction",
                "dissipated_contact": "energy taken out by the contact penalty",
                "dissipated_springs": "energy taken out by the springs' step force",
                "dissipated_impact": "energy taken out by impacts with a restitution",
                "work_water": "work of the water pressure",
                "dissipated_damping": "energy taken out by velocity damping (velocity_ratio)",
                "work_stages": "energy put in by the stages' changes",
                "balance": "energy balance E − W_in + D"}
_COMPONENT_WORDS = {"vx": "velocity x", "vy": "velocity y", "vz": "velocity z", "omega": "angular velocity ω",
                    "omega_x": "angular velocity ωx", "omega_y": "angular velocity ωy",
                    "omega_z": "angular velocity ωz", "exx_rate": "strain rate ε̇x", "eyy_rate": "strain rate ε̇y",
                    "ezz_rate": "strain rate ε̇z", "gxy_rate": "shear strain rate γ̇xy",
                    "gyz_rate": "shear strain rate γ̇yz", "gzx_rate": "shear strain rate γ̇zx",
                    "sxx": "normal stress σx", "syy": "normal stress σy", "szz": "normal stress σz",
                    "sxy": "shear stress τxy", "syz": "shear stress τyz", "szx": "shear stress τzx"}
_WORDS = {"time": "time", "step": "step", "area": "area", "rotation": "rotation", "iterations": "linear solves",
          "centroid": "centroid", "measured_position": "measured point", "measured_velocity": "measured point velocity",
          "closed_contacts": "closed contacts", "max_penetration": "deepest penetration",
          "multipliers": "hinge multipliers", "speed": "speed", "area_change": "area change A/A₀ − 1",
          "bolt_force": "bolt axial force", "bolt_shear_force": "bolt shear force", "bolt_broken": "bolt broken",
          "bolt_break_time": "bolt break time"}


def _dim(res: Results) -> int:
    return int(np.asarray(res.array("centroid")).shape[-1])


def quantity_unit(res: Results, name: str) -> str:
    """SI unit of a :func:`history` name (or ``speed``, ``area_change``) of ``res``, for axis labels.

    Energies are J per metre of thickness in 2D and J in 3D; ``area`` is m² in
    2D and the volume (m³) in 3D; forces are N per metre in 2D, N in 3D.
    """
    base = name.split(".", 1)[0]
    if base == "energy":
        return "J/m" if _dim(res) == 2 else "J"
    if name == "area" and _dim(res) == 3:
        return "m³"
    if name in ("multipliers", "bolt_force", "bolt_shear_force"):
        return "N/m" if _dim(res) == 2 else "N"
    unit = _UNITS.get(name, _UNITS.get(base))
    if unit is None:
        raise KeyError(f"no unit known for {name!r}")
    return unit


def quantity_words(res: Results, name: str) -> str:
    """What a :func:`history` name is, in words: ``"normal stress σx"``, ``"kinetic energy"``, ``"centroid x"``."""
    base, _, part = name.partition(".")
    if base == "energy":
        return ENERGY_WORDS.get(part, f"energy {part}")
    if name == "area" and _dim(res) == 3:
        return "volume"
    if base in ("velocity", "stress"):
        return _COMPONENT_WORDS.get(part, name)
    words = _WORDS.get(base, base.replace("_", " "))
    return f"{words} {part}" if part else words


def quantity_label(res: Results, name: str) -> str:
    """An axis or colour-bar label: the quantity in words and its unit, ``"normal stress σx (Pa)"``."""
    return f"{quantity_words(res, name)} ({quantity_unit(res, name)})"


def step_index(res: Results, step: int) -> int:
    """Row of the recorded step ``step`` (the nearest recorded one at or before it)."""
    steps = np.asarray(res.array("step"))
    i = int(np.searchsorted(steps, step, side="right")) - 1
    if i < 0:
        raise ValueError(f"step {step} precedes the first recorded step {steps[0]}")
    return i


def method_label(name: str) -> str:
    """The paper's name of a method (DDA0, DDA1, SRDDA)."""
    return {"dda0": "DDA0", "dda1": "DDA1", "srdda": "SRDDA"}.get(name, name)


# -- any run --------------------------------------------------------------------
def plot_blocks(ax: plt.Axes, vertices: np.ndarray, block_ptr: np.ndarray, values: np.ndarray | None = None,
                cmap: str = "viridis", facecolor: str = "#c8d6e5", **kwargs: Any) -> PolyCollection:
    """Draw blocks as polygons, coloured by ``values`` (one per block) when given."""
    polys = [vertices[a:b] for a, b in zip(block_ptr[:-1], block_ptr[1:])]
    coll = PolyCollection(polys, edgecolor=kwargs.pop("edgecolor", "k"), linewidth=kwargs.pop("linewidth", 0.6),
                          facecolor=None if values is not None else facecolor, cmap=cmap, **kwargs)
    if values is not None:
        coll.set_array(np.asarray(values, dtype=float))
    ax.add_collection(coll)
    ax.autoscale_view()
    ax.set_aspect("equal")
    return coll


def fixed_blocks(model: Model) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and pointer of the fixed blocks (slope, ground) to draw behind paths."""
    a = model.arrays()
    keep = np.flatnonzero(a.block_fixed)
    if len(keep) == 0:
        return None
    counts = np.diff(a.block_ptr)[keep]
    verts = np.concatenate([a.vertex_position[a.block_ptr[b]:a.block_ptr[b + 1]] for b in keep])
    return verts, np.concatenate([[0], np.cumsum(counts)])


@overload
def block_values(res: Results, index: int, color: str) -> np.ndarray: ...
@overload
def block_values(res: Results, index: int, color: None) -> None: ...
def block_values(res: Results, index: int, color: str | None) -> np.ndarray | None:
    """One value per block at recorded row ``index``: ``speed``, ``area_change`` or a :func:`history` name."""
    if color is None:
        return None
    if color == "speed":
        v = history(res, "velocity")[index]
        return np.linalg.norm(v[:, : res.array("vertices").shape[-1]], axis=1)
    if color == "area_change":
        area = history(res, "area")
        return area[index] / area[0] - 1.0
    return history(res, color)[index]


def fig_configuration(arrays: Any, title: str = "", labels: Sequence[str] | None = None) -> Figure:
    """The model before the run (paper Figs. 3, 5, 7, 11, 14): blocks, supports, springs, hinges, points.

    ``arrays`` is a :class:`~srdda.model.ModelArrays`. Fixed blocks are grey,
    fixed points black triangles, springs green lines between open circles,
    hinges and pins black rings, driven (prescribed-motion) points purple
    diamonds, point loads orange triangles, measured points red dots labelled
    with ``labels`` (default P0, P1...; points at one place share one label).
    A slender model (20 times longer than high) with springs, hinges or driven
    points gets a second panel: a tenth of its length around the leftmost of
    them, enlarged, where they can be told apart.
    """
    lo, hi = arrays.vertex_position.min(axis=0), arrays.vertex_position.max(axis=0)
    width, height = hi - lo
    links = arrays.links
    details = np.concatenate([arrays.attached.point_position[rows] for rows in (
        links.prescribed_rows, arrays.attached.point_spring_rows_a, links.spring_rows_a, links.hinge_rows_a)])
    # a slender model with springs, hinges or driven points: those crowd at the full model's scale
    slender = width > 20 * max(height, 1e-12) and len(details) > 0
    fig, axes = plt.subplots(2 if slender else 1, 1, figsize=(7, 6.5 if slender else 4.5), layout="constrained",
                             squeeze=False)
    _draw_configuration(axes[0, 0], arrays, labels)
    axes[0, 0].set_title(title)
    pad = 0.05 * max(width, height)
    half = max(height, width / 6.0) / 2 + pad  # a 10 m rod 0.1 m thick gets a readable height
    mid = 0.5 * (lo[1] + hi[1])
    axes[0, 0].set(xlim=(lo[0] - pad, hi[0] + pad), ylim=(mid - half, mid + half))
    if slender:  # enlarged below: a tenth of the model around its first detail (from the left)
        zoom = axes[1, 0]
        _draw_configuration(zoom, arrays, labels)
        span = width / 10
        x0 = float(np.clip(details[:, 0].min() - span / 2, lo[0] - 0.02 * span, hi[0] + 0.02 * span - span))
        zoom.set(xlim=(x0, x0 + span), ylim=(mid - span / 6, mid + span / 6),
                 title=f"enlarged: x from {x0:.3g} to {x0 + span:.3g} m")
        axes[0, 0].indicate_inset((x0, mid - span / 6, span, span / 3), edgecolor="0.4")
    handles, names = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, names, fontsize="small", loc="outside lower center", ncols=4)
    return fig


def _draw_configuration(ax: plt.Axes, arrays: Any, labels: Sequence[str] | None) -> None:
    """Blocks, supports, springs, hinges, driven, loaded and measured points of ``arrays`` on ``ax``."""
    coll = plot_blocks(ax, arrays.vertex_position, arrays.block_ptr)
    coll.set_facecolor(list(np.where(arrays.block_fixed, "0.8", "#c8d6e5")))
    if np.any(arrays.block_fixed):  # legend entries for the two fills
        ax.fill([], [], facecolor="0.8", edgecolor="k", lw=0.5, label="fixed block")
        ax.fill([], [], facecolor="#c8d6e5", edgecolor="k", lw=0.5, label="moving block")
    pts = arrays.attached.point_position
    links = arrays.links
    if len(arrays.attached.fixed_rows):
        ax.plot(*pts[arrays.attached.fixed_rows].T, "k^", ms=8, label="fixed point")
    ends_a = np.concatenate([arrays.attached.point_spring_rows_a, links.spring_rows_a]).astype(np.int64)
    ends_b = np.concatenate([arrays.attached.point_spring_rows_b, links.spring_rows_b]).astype(np.int64)
    if len(ends_a):
        segments = np.full((3 * len(ends_a), 2), np.nan)  # a - b - gap, drawn as one line
        segments[0::3], segments[1::3] = pts[ends_a], pts[ends_b]
        ax.plot(*segments.T, "-", color="tab:green", lw=1.2, label="spring")
        ax.plot(*pts[np.concatenate([ends_a, ends_b])].T, "o", mfc="none", mec="tab:green", ms=6,
                label="spring end")
    if links.n_hinges:
        ax.plot(*pts[links.hinge_rows_a].T, "o", mfc="white", mec="k", mew=1.5, ms=9, label="hinge / pin")
    if len(links.prescribed_rows):
        ax.plot(*pts[links.prescribed_rows].T, "D", color="tab:purple", ms=6, label="driven point")
    if len(arrays.attached.load_rows):
        ax.plot(*pts[arrays.attached.load_rows].T, "v", color="tab:orange", ms=7, label="point load")
    links = arrays.links
    if links.n_bolts:
        rb = links.bolt_rows_b
        ends = np.stack([pts[links.bolt_rows_a], np.where((rb >= 0)[:, None], pts[np.maximum(rb, 0)],
                                                          links.bolt_ground)], axis=1)
        plot_bolts(ax, ends, np.zeros(links.n_bolts, dtype=bool), label="bolt")
    mr = arrays.attached.measured_rows
    if len(mr):
        ax.plot(*pts[mr].T, "o", color="tab:red", ms=4, label="measured point")
        names = list(labels) if labels else [f"P{k}" for k in range(len(mr))]
        places: dict[tuple[float, ...], list[int]] = {}
        scale = float(np.ptp(arrays.vertex_position, axis=0).max() or 1.0)
        for k, p in enumerate(pts[mr]):
            places.setdefault(tuple(np.round(p / (1e-6 * scale)).tolist()), []).append(k)
        # each label points away from its block's centroid (a corner's outwards, a centroid's up-right),
        # so that the labels of points of one block part
        away = pts[mr] - arrays.moments(arrays.vertex_position).centroid[arrays.attached.point_block[mr]]
        for group in places.values():
            d = away[group[0]]
            d = d / np.hypot(*d) if np.hypot(*d) > 1e-9 * scale else np.array([0.6, 0.8])
            ax.annotate(", ".join(names[k] for k in group), pts[mr][group[0]], xytext=tuple(9 * d),
                        textcoords="offset points", color="tab:red", fontsize=8,
                        ha="left" if d[0] >= 0 else "right", va="bottom" if d[1] >= 0 else "top")
    ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal")


def fig_model(res: Results, index: int = -1, color: str | None = "speed", trails: bool = True) -> Figure:
    """The blocks at recorded step ``index`` (needs the vertices history of a results file).

    ``color``: ``speed``, ``area_change`` or any per-block quantity of
    :func:`history` (e.g. ``velocity.omega``, ``stress.sxx``); ``trails`` draws
    the measured points' paths so far.
    """
    if "vertices" not in getattr(res, "histories", {}):
        raise ValueError("drawing the model needs the vertex history of a results file (srdda run -o FILE.h5)")
    if res.mesh is not None:
        return fig_solid_model(res, index, color, trails)
    fig, ax = plt.subplots(figsize=(7, 5), layout="constrained")
    verts = res.array("vertices")
    index = index % len(verts)
    values = block_values(res, index, color)
    ptr = res.block_ptr
    removed = removed_blocks(int(res.array("step")[index]), getattr(res, "stages", ()), len(ptr) - 1)
    kept = np.flatnonzero(~removed)  # a block excavated by a stage: an empty dashed outline, under the others
    sizes = np.diff(ptr)[kept]
    coll = plot_blocks(ax, np.concatenate([verts[index][ptr[b]:ptr[b + 1]] for b in kept]),
                       np.concatenate([[0], np.cumsum(sizes)]), None if values is None else values[kept])
    if np.any(removed):
        ax.add_collection(PolyCollection([verts[index][ptr[b]:ptr[b + 1]] for b in np.flatnonzero(removed)],
                                         facecolor="none", edgecolor="0.5", linestyle="--", linewidth=0.6))
    if values is not None:
        assert color is not None  # block_values gives values for a quantity only
        fig.colorbar(coll, ax=ax, label=quantity_label(res, color), shrink=0.7)
    if trails:
        _trails(ax, res, index)
    if "bolt_ends" in res.histories and res.bolt_ends.shape[1]:
        plot_bolts(ax, res.bolt_ends[index], res.bolt_broken[index], res.bolt_force[index])
    allv = verts.reshape(-1, 2)
    pad = 0.05 * float(np.ptp(allv, axis=0).max() or 1.0)
    ax.set_xlim(allv[:, 0].min() - pad, allv[:, 0].max() + pad)
    ax.set_ylim(allv[:, 1].min() - pad, allv[:, 1].max() + pad)
    ax.set(xlabel="x (m)", ylabel="y (m)", title=step_title(res, index))
    return fig


def plot_bolts(ax: plt.Axes, ends: np.ndarray, broken: np.ndarray, force: np.ndarray | None = None,
               label: str | None = None) -> None:
    """Rock bolts as lines from end a to end b (``ends`` (n, 2, 2)): intact solid red with the axial force
    written at their middle (kN per m when ``force`` is given), broken dashed grey."""
    broken = np.asarray(broken, dtype=bool)
    for k, (a, b) in enumerate(np.asarray(ends)[:, :, :2]):
        color, ls = ("0.5", "--") if broken[k] else ("tab:red", "-")
        ax.plot([a[0], b[0]], [a[1], b[1]], lw=2.0, marker="o", ms=3, label=label if k == 0 else None, color=color,
                ls=ls)
        if force is not None:
            ax.annotate("broken" if broken[k] else f"{force[k] / 1e3:.3g} kN", 0.5 * (a + b), xytext=(3, 3),
                        textcoords="offset points", fontsize=7, color=color)


def fig_bolt_forces(res: Results) -> Figure:
    """Axial force of every bolt against time (kN, per m in 2D), each break marked by a cross."""
    t = history(res, "time")
    force = history(res, "bolt_force")
    if force.ndim != 2 or not force.shape[1]:
        raise ValueError("the run has no rock bolts")
    broken = history(res, "bolt_broken").astype(bool)
    names = tuple(getattr(res, "bolt_names", ())) or tuple(f"bolt {k}" for k in range(force.shape[1]))
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    for k in range(force.shape[1]):
        line, = ax.plot(t, force[:, k] / 1e3, label=names[k])
        if broken[:, k].any():
            i = int(np.argmax(broken[:, k]))
            ax.plot(t[i], force[max(i - 1, 0), k] / 1e3, "x", color=line.get_color(), ms=9)
    ax.set(xlabel="time (s)", ylabel="axial force (kN)", title=f"{method_label(res.method)}: bolt forces")
    mark_stages(ax, res)
    if force.shape[1] <= MAX_LEGEND:
        ax.legend(fontsize="small")
    return fig


def step_title(res: Results, index: int) -> str:
    """"METHOD: step N, t = T s" of recorded row ``index`` (and ", stage NAME" in a staged run)."""
    step, time = int(res.array("step")[index]), float(res.array("time")[index])
    begun = [row["name"] for row in getattr(res, "stages", ()) if row["first_step"] <= step]
    return f"{method_label(res.method)}: step {step}, t = {time:.4g} s" + (f", stage {begun[-1]}" if begun else "")


def _trails(ax: Any, res: Results, index: int) -> None:
    """The measured points' paths up to recorded row ``index`` (2D or 3D axes)."""
    mp = history(res, "measured_position")
    for k in range(mp.shape[1]):
        ax.plot(*mp[: index + 1, k].T, lw=0.8, label=f"point {k}")


def solid_faces(vertices: np.ndarray, mesh: Any) -> tuple[list[np.ndarray], np.ndarray]:
    """Every face of every 3D block as a polygon (k, 3), and the block of each face."""
    rings = np.split(mesh.face_vertex, mesh.face_ptr[1:-1])
    return [vertices[r] for r in rings], mesh.face_block


def plot_solid_blocks(ax: Any, vertices: np.ndarray, mesh: Any, values: np.ndarray | None = None,
                      cmap: str = "viridis") -> Poly3DCollection:
    """Draw 3D blocks by their faces on 3D axes, coloured by ``values`` (one per block) when given."""
    faces, face_block = solid_faces(vertices, mesh)
    coll = Poly3DCollection(faces, edgecolor="k", linewidth=0.4, alpha=0.85, cmap=cmap,
                            facecolor=None if values is not None else "#c8d6e5")
    if values is not None:
        coll.set_array(np.asarray(values, dtype=float)[face_block])
    ax.add_collection3d(coll)
    return coll


def solid_limits(ax: Any, points: np.ndarray) -> None:
    """Equal scales on the three axes around ``points`` (n, 3)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.55 * float(np.max(hi - lo) or 1.0)
    ax.set(xlim=(centre[0] - half, centre[0] + half), ylim=(centre[1] - half, centre[1] + half),
           zlim=(centre[2] - half, centre[2] + half), xlabel="x (m)", ylabel="y (m)", zlabel="z (m)")
    ax.set_box_aspect((1, 1, 1))


def fig_solid_model(res: Results, index: int = -1, color: str | None = "speed", trails: bool = True) -> Figure:
    """3D blocks at recorded step ``index`` (their faces), with the measured points' paths so far.

    Rendered with pyvista off-screen (:mod:`srdda.apps.render3d`), else with matplotlib's 3D axes.
    """
    from matplotlib import cm, colors as mcolors

    from .render3d import pyvista_renders, render_blocks

    verts = res.array("vertices")
    index = index % len(verts)
    values = block_values(res, index, color)
    if not pyvista_renders():
        fig = plt.figure(figsize=(7, 6), layout="constrained")
        ax = fig.add_subplot(projection="3d")
        coll = plot_solid_blocks(ax, verts[index], res.mesh, values)
        if values is not None:
            assert color is not None  # block_values gives values for a quantity only
            fig.colorbar(coll, ax=ax, label=quantity_label(res, color), shrink=0.6)
        if trails:
            _trails(ax, res, index)
        solid_limits(ax, verts.reshape(-1, verts.shape[-1]))
        ax.set_title(step_title(res, index))
        return fig
    mp = history(res, "measured_position")[: index + 1]
    paths = [(np.stack([mp[:-1, k], mp[1:, k]], axis=1), f"C{k % 10}", 3.0) for k in range(mp.shape[1])] if trails \
        else []
    clim = None if values is None else (float(np.min(values)), float(np.max(values)) or 1.0)
    image = render_blocks(verts[index], res.mesh, values, clim=clim, segments=paths)
    fig, ax = plt.subplots(figsize=(7, 6), layout="constrained")
    ax.imshow(image)
    ax.set_axis_off()
    ax.set_title(step_title(res, index))
    if values is not None:
        assert clim is not None and color is not None  # both go with the values
        mappable = cm.ScalarMappable(mcolors.Normalize(*clim), "viridis")
        fig.colorbar(mappable, ax=ax, label=quantity_label(res, color), shrink=0.6)
    return fig


def fig_trajectories(res: Results, points: str = "measured", title: str | None = None) -> Figure:
    """Paths of the measured points (``points="measured"``) or the block centroids (``"centroid"``)."""
    key = {"measured": "measured_position", "centroid": "centroid"}[points]
    xy = history(res, key)
    fig, ax = plt.subplots(figsize=(6, 5), layout="constrained")
    labels = (res.block_names if points == "centroid" else [f"point {k}" for k in range(xy.shape[1])])
    for k in range(xy.shape[1]):
        ax.plot(xy[:, k, 0], xy[:, k, 1], lw=1.0, label=labels[k])
    ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal", title=title or f"{method_label(res.method)}: {points}")
    if 0 < xy.shape[1] <= MAX_LEGEND:
        fig.legend(fontsize="small", loc="outside right upper")
    return fig


def mark_stages(ax: plt.Axes, res: Results, names: bool = True) -> None:
    """The starts of a staged run's stages on a time axis: a dotted vertical line each, with the stage's name."""
    for row in getattr(res, "stages", ()):
        ax.axvline(row["start_time"], color="0.45", ls=":", lw=0.9)
        if names:
            ax.text(row["start_time"], 1.0, f" {row['name']}", transform=ax.get_xaxis_transform(), rotation=90,
                    va="top", ha="left", fontsize=7, color="0.3")


def fig_time_series(runs: Results | Mapping[str, Results], quantity: str,
                    blocks: Sequence[int] | np.ndarray | None = None) -> Figure:
    """A recorded quantity against time, one line per block (or measured point; ``blocks`` picks them)."""
    runs = runs if isinstance(runs, Mapping) else {method_label(runs.method): runs}
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    styles = ("-", "--", ":", "-.")
    for r, (label, res) in enumerate(runs.items()):
        t = history(res, "time")
        y = history(res, quantity)
        if y.ndim == 1:
            ax.plot(t, y, label=label)
            continue
        if y.ndim > 2:
            raise ValueError(f"{quantity} is a vector per block or point: plot {quantity}.x, {quantity}.y, ... "
                             "or use fig_trajectories")
        names = ([f"point {k}" for k in range(y.shape[1])] if quantity.startswith("measured_")
                 else (getattr(res, "bolt_names", ()) or [f"bolt {k}" for k in range(y.shape[1])])
                 if quantity.startswith("bolt_") else res.block_names)
        for j, b in enumerate(range(y.shape[1]) if blocks is None else blocks):
            # several runs: a colour per run, a line style per block; one run: a colour per block
            style, color = (styles[j % len(styles)], f"C{r % 10}") if len(runs) > 1 else ("-", f"C{j % 10}")
            ax.plot(t, y[:, b], style, color=color, label=f"{label}: {names[b]}" if len(runs) > 1 else names[b])
    ax.set(xlabel="time (s)", ylabel=quantity_label(next(iter(runs.values())), quantity))
    lines = len(ax.get_lines())
    mark_stages(ax, next(iter(runs.values())))
    if lines <= MAX_LEGEND:
        fig.legend(fontsize="small", loc="outside right upper")
    return fig


# -- the paper's figures -----------------------------------------------------------
def _columns(n: int, rows: int = 1, size: tuple[float, float] = (4.2, 4.0)) -> tuple[Figure, np.ndarray]:
    fig, axes = plt.subplots(rows, n, figsize=(size[0] * n, size[1] * rows), layout="constrained", squeeze=False)
    return fig, axes


def _zoom_box(xy: np.ndarray, width: float) -> tuple[float, float, float, float]:
    """A square window of side ``width`` around the lowest point of a path."""
    i = int(np.argmin(xy[:, 1]))
    x0, y0 = xy[i]
    return x0 - width / 2, x0 + width / 2, y0 - width / 4, y0 + 3 * width / 4


def _zoom(ax: plt.Axes, main: plt.Axes, paths: Sequence[np.ndarray], colors: Sequence[str],
          box: tuple[float, float, float, float], widths: Sequence[float] | None = None) -> None:
    """The paths inside ``box`` (x0, x1, y0, y1) drawn on ``ax``, the box marked on ``main``."""
    for k, (xy, c) in enumerate(zip(paths, colors)):
        ax.plot(xy[:, 0], xy[:, 1], color=c, lw=widths[k] if widths else 0.9)
    ax.set(xlim=box[:2], ylim=box[2:], xlabel="x (m)", ylabel="y (m)",
           title=f"zoom: {box[1] - box[0]:.3g} m wide at the lowest point")
    main.indicate_inset((box[0], box[2], box[1] - box[0], box[3] - box[2]), edgecolor="0.3")


def fig_swing_trajectories(results: Mapping[str, Results], pivot: Sequence[float] | np.ndarray = (0.0, 0.0),
                           points: Sequence[int] | None = None, zoom: float | None = None,
                           title: str = "", names: Sequence[str] | None = None) -> Figure:
    """Figs. 4 and 6: measured-point paths per method with a zoomed view, and their radial offset.

    Top row: the paths (a pendulum's B; a rod's B and C); middle row: the
    first point's paths enlarged around its lowest point, where DDA0's
    to-and-fro paths part. Bottom row: the distance of each point from the
    pivot minus its initial value (m) against time, which measures that offset
    (zero for an exact rigid swing). ``names``: the measured points' names
    (default "point 0", "point 1", ...).
    """
    colors = ["tab:blue", "tab:red", "tab:green", "tab:orange"]
    fig, axes = _columns(len(results), rows=3, size=(4.2, 3.3))
    pivot = np.asarray(pivot, dtype=float)
    for col, (method, res) in enumerate(results.items()):
        mp = history(res, "measured_position")
        idx = range(mp.shape[1]) if points is None else points
        paths = [mp[:, k] for k in idx]
        ax = axes[0, col]
        for k, xy, c in zip(idx, paths, colors):
            ax.plot(xy[:, 0], xy[:, 1], color=c, lw=0.9, label=names[k] if names else f"point {k}")
        ax.plot(*pivot, "k^")
        ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title=f"({'abc'[col % 3]}) {method_label(method)}")
        reach = float(np.max(np.linalg.norm(paths[0] - pivot, axis=1)))
        _zoom(axes[1, col], ax, paths, colors, _zoom_box(paths[0], zoom or 0.02 * reach))
        t = history(res, "time")
        for k, xy, c in zip(idx, paths, colors):
            r = np.linalg.norm(xy - pivot, axis=1)
            axes[2, col].plot(t, r - r[0], color=c, lw=0.9)
        axes[2, col].set(xlabel="time (s)", ylabel="radial offset (m)")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside upper center", ncols=4, fontsize="small")
    if title:
        fig.suptitle(title)
    return fig


def fig_wave_shapes(results: Mapping[str, Results], steps: Sequence[int] = (300, 600, 900),
                    blocks: Sequence[int] | None = None, title: str = "") -> Figure:
    """Figs. 8-10: the bar chain's transverse displacement along x at each step, per method.

    Rows are the steps, columns the methods; a bar's centroid gives one point.
    """
    fig, axes = _columns(len(results), rows=len(steps), size=(4.2, 2.4))
    for col, (method, res) in enumerate(results.items()):
        c = history(res, "centroid")
        sel = slice(None) if blocks is None else np.asarray(blocks)
        for row, step in enumerate(steps):
            i = step_index(res, step)
            ax = axes[row, col]
            ax.plot(c[i][sel, 0], c[i][sel, 1] - c[0][sel, 1], "-o", ms=2, lw=1.0)
            ax.axhline(0.0, color="0.7", lw=0.5)
            ax.set(xlabel="x (m)", ylabel="v (m)",
                   title=f"{method_label(method)}, CS {int(res.array('step')[i])}")
    if title:
        fig.suptitle(title)
    return fig


def fig_nunchaku(results: Mapping[str, Results], hinge_points: tuple[int, int] = (0, 1), tip_point: int = 2,
                 zoom: float | None = None, title: str = "") -> tuple[Figure, Figure]:
    """Figs. 12 and 13: hinge points B1, B2 per method with a zoom, the sticks' ω; point C of all methods.

    Returns (Fig. 12: top row paths of B1 (blue, wide) and B2 (red), middle
    row the same enlarged at B1's lowest point, bottom row the angular velocity
    of each stick against time; Fig. 13: paths of C).
    """
    fig12, axes = _columns(len(results), rows=3, size=(4.2, 3.3))
    for col, (method, res) in enumerate(results.items()):
        mp = history(res, "measured_position")
        paths = [mp[:, hinge_points[0]], mp[:, hinge_points[1]]]
        ax = axes[0, col]
        for xy, c, lab, lw in zip(paths, ("tab:blue", "tab:red"), ("B1", "B2"), (2.4, 0.9)):
            ax.plot(xy[:, 0], xy[:, 1], color=c, lw=lw, label=lab)  # B1 wide below B2: both show where they meet
        ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title=f"({'abc'[col % 3]}) {method_label(method)}")
        reach = float(np.ptp(paths[0], axis=0).max() or 1.0)
        _zoom(axes[1, col], ax, paths, ("tab:blue", "tab:red"), _zoom_box(paths[0], zoom or 0.05 * reach),
              widths=(2.4, 0.9))
        t = history(res, "time")
        omega = history(res, "velocity.omega")
        for b, (name, c) in enumerate(zip(res.block_names, ("tab:green", "tab:purple", "tab:brown", "tab:gray"))):
            axes[2, col].plot(t, omega[:, b], lw=0.9, color=c, label=f"ω of {name}")
        axes[2, col].set(xlabel="time (s)", ylabel="ω (rad/s)")
    (paths_h, paths_l), (omega_h, omega_l) = (axes[r, 0].get_legend_handles_labels() for r in (0, 2))
    fig12.legend(paths_h + omega_h, paths_l + omega_l, loc="outside upper center", ncols=4, fontsize="small")
    fig13, ax13 = plt.subplots(figsize=(6, 5), layout="constrained")
    for method, res in results.items():
        tip = history(res, "measured_position")[:, tip_point]
        ax13.plot(tip[:, 0], tip[:, 1], lw=0.9, label=method_label(method))
    ax13.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title="point C")
    ax13.legend(loc="upper center", fontsize="small")  # the swing leaves the middle above the lowest point empty
    if title:
        fig12.suptitle(title)
        fig13.suptitle(title)
    return fig12, fig13


def fig_rockfall(results: Mapping[str, Results], background: Background | None = None,
                 points: tuple[int, int] = (0, 1), title: str = "") -> Figure:
    """Fig. 15: paths of the stone's centroid P1 (blue) and vertex P2 (red) per method, over the slope."""
    fig, axes = _columns(len(results), size=(5.0, 4.0))
    for col, (method, res) in enumerate(results.items()):
        ax = axes[0, col]
        if background is not None:
            plot_blocks(ax, background[0], background[1], facecolor="0.85", edgecolor="0.4")
        mp = history(res, "measured_position")
        for k, c, lab in zip(points, ("tab:blue", "tab:red"), ("P1", "P2")):
            ax.plot(mp[:, k, 0], mp[:, k, 1], color=c, lw=0.8, label=lab)
        ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title=f"({'abc'[col % 3]}) {method_label(method)}")
        ax.autoscale_view()
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside upper center", ncols=2, fontsize="small")
    if title:
        fig.suptitle(title)
    return fig


# -- the energy ledger --------------------------------------------------------------
# (key, panel title): stored energies, work that entered, energy taken out, what is left (srdda.ledger)
LEDGER_PANELS = (
    ("kinetic", "kinetic energy"),
    ("potential", "gravity potential of the moving blocks\n(datum: their initial centroid heights)"),
    ("elastic", "strain energy of the blocks"),
    ("spring", "springs and penalty supports"),
    ("contact", "contact springs (stored)"),
    ("work_loads", "work of loads and base acceleration (in)"),
    ("work_prescribed", "work of prescribed motion (in)"),
    ("work_constraints", "work of hinge forces (in)"),
    ("work_water", "work of the water pressure (in)"),
    ("dissipated", "dissipated by dashpots"),
    ("dissipated_friction", "dissipated by friction"),
    ("dissipated_contact", "taken out by the contact penalty\n(impacts, springs released stretched)"),
    ("dissipated_springs", "taken out by the springs' step force\n(negative: put in by the point update)"),
    ("dissipated_impact", "taken out by impacts with a restitution\n(their dashpot)"),
    ("dissipated_damping", "taken out by velocity damping\n(velocity_ratio < 1: equilibrium stages)"),
    ("work_stages", "put in by the stages' changes\n(removed blocks, bolts, velocities reset)"),
    ("error", "balance error: E − E₀ − W_in + D\n(time scheme, linearisation)"),
)


def ledger_series(res: Results) -> dict[str, np.ndarray]:
    """The energy ledger of a run as the series of :data:`LEDGER_PANELS` (one value per recorded step).

    ``potential`` is the gravity energy minus its initial value: the fixed
    blocks' share is a constant and drops out, so it is the moving blocks'
    potential from their initial centroid heights. ``error`` is the balance
    minus its initial value (zero when the ledger closes; negative when energy
    is lost unaccounted). A results file written before a ledger entry existed
    gives zeros for it.
    """
    energy = np.asarray(res.array("energy"))
    names = _energy_names(res)

    def col(name: str) -> np.ndarray:
        return energy[:, names.index(name)] if name in names else np.zeros(len(energy))

    out = {key: col(key) for key, _ in LEDGER_PANELS if key not in ("potential", "error")}
    out["potential"] = col("gravity") - col("gravity")[0]
    out["error"] = col("balance") - col("balance")[0]
    return out


def ledger_panels(series: Sequence[Mapping[str, np.ndarray]] | Any) -> list[tuple[str, str]]:
    """The (key, title) of :data:`LEDGER_PANELS` that :func:`fig_energy_ledger` draws for these
    :func:`ledger_series`: the entries that are not zero in some run (relative to the largest), and the error."""
    series = list(series)
    largest = max(float(np.max(np.abs(v), initial=0.0)) for s in series for v in s.values())
    return [(k, t) for k, t in LEDGER_PANELS
            if k == "error" or any(np.max(np.abs(s[k]), initial=0.0) > 1e-9 * largest for s in series)]


def _si_prefix(largest: float) -> tuple[float, str]:
    """The power of 1000 and its SI prefix that bring ``largest`` into [1, 1000) (n ... G)."""
    exponent = 0 if largest <= 0 else int(np.clip(3 * np.floor(np.log10(largest) / 3), -9, 9))
    return 10.0 ** exponent, {-9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}[exponent]


def fig_energy_ledger(results: Results | Mapping[str, Results], title: str = "") -> Figure:
    """The energy ledger: one panel per entry with its own scale, the methods overlaid.

    Each stored energy, each cumulative work and dissipation and the balance
    error gets its own axes, so that a large entry (a stiff spring) does not
    flatten a small one; entries that stay zero in every run are left out (the
    balance error never is). Panels in the order of :data:`LEDGER_PANELS`.
    """
    runs = results if isinstance(results, Mapping) else {results.method: results}
    series = {m: ledger_series(r) for m, r in runs.items()}
    keep = ledger_panels(series.values())
    ncols = min(3, len(keep))
    nrows = -(-len(keep) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.3 * ncols, 2.7 * nrows + 0.6), layout="constrained",
                             squeeze=False, sharex=True)
    first = next(iter(runs.values()))
    unit = quantity_unit(first, "energy")
    for ax, (key, panel) in zip(axes.flat, keep):
        factor, prefix = _si_prefix(max(float(np.max(np.abs(s[key]), initial=0.0)) for s in series.values()))
        for (method, res), style in zip(runs.items(), ("-", "--", ":", "-.") * len(runs)):
            ax.plot(history(res, "time"), series[method][key] / factor, style, lw=0.9, label=method_label(method))
        mark_stages(ax, first, names=ax is axes.flat[0])
        ax.set_title(panel, fontsize=9)
        ax.set_ylabel(f"energy ({prefix}{unit})", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)
    for ax in axes.flat[len(keep):]:
        ax.remove()
    for ax in axes.flat[: len(keep)]:  # every panel says its time axis: one glance, no counting rows
        ax.set_xlabel("time (s)", fontsize=8)
        ax.xaxis.set_tick_params(labelbottom=True)
    if len(runs) > 1:
        fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="outside upper center", ncols=len(runs),
                   fontsize="small")
    if title:
        fig.suptitle(title)
    return fig


# -- per-block energies ----------------------------------------------------------------
BLOCK_ENERGY_WORDS = {"translational": "kinetic, translation ½m|v|²", "rotational": "kinetic, rotation ½ωᵀJω",
                      "potential": "gravitational, from the initial height −m g·(c − c₀)"}
MAX_BLOCK_PANELS = 6  # per-block energy figures draw at most this many blocks unless they are named


def block_energies(res: Results, arrays: Any) -> dict[str, np.ndarray]:
    """Each block's energies (n, nb) at every recorded step: the keys of :data:`BLOCK_ENERGY_WORDS`.

    ``arrays`` is the run's :class:`~srdda.model.ModelArrays` (masses, gravity,
    the block type); the rotational energy uses each block's mass matrix
    in the recorded configuration (its vertices history), as the ledger's
    kinetic energy does. Fixed blocks give zeros.
    """
    bt = arrays.block_type
    mass = arrays.block_mass
    velocity = np.asarray(res.array("velocity"))
    centroid = np.asarray(res.array("centroid"))
    vertices = np.asarray(res.array("vertices"))
    v, w = velocity[..., bt.translation], velocity[..., bt.rotation]
    translational = 0.5 * mass * np.einsum("nbi,nbi->nb", v, v)
    rotational = np.empty_like(translational)
    for i, verts in enumerate(vertices):  # one recorded step at a time (a figure, not the time step)
        mom = arrays.moments(verts)
        matrix = bt.mass_matrix(mom.volume, mom.second)[:, bt.rotation, bt.rotation] * (mass / mom.volume)[:, None,
                                                                                                         None]
        rotational[i] = 0.5 * np.einsum("bi,bij,bj->b", w[i], matrix, w[i])
    potential = -mass * np.einsum("nbi,i->nb", centroid - centroid[0], np.asarray(arrays.gravity, dtype=float))
    fixed = np.asarray(arrays.block_fixed, dtype=bool)
    out = {"translational": translational, "rotational": rotational, "potential": potential}
    for values in out.values():
        values[:, fixed] = 0.0
    return out


def fig_block_energies(res: Results, arrays: Any, blocks: Sequence[int] | None = None) -> Figure:
    """Per-block energies against time: one panel per block, each on its own scale, a legend per panel.

    ``blocks``: block indices (default: the moving blocks, at most
    :data:`MAX_BLOCK_PANELS`), so that a large block's energy never flattens a
    small one's.
    """
    energies = block_energies(res, arrays)
    chosen = (list(np.flatnonzero(~np.asarray(arrays.block_fixed, dtype=bool))[:MAX_BLOCK_PANELS])
              if blocks is None else list(blocks))
    if not chosen:
        raise ValueError("the run has no moving block; name blocks with --block")
    ncols = min(2, len(chosen))
    nrows = -(-len(chosen) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(max(7.0, 5.2 * ncols), 3.0 * nrows + 1.2), layout="constrained",
                             squeeze=False)
    t = history(res, "time")
    unit = quantity_unit(res, "energy")
    for ax, b in zip(axes.flat, chosen):
        factor, prefix = _si_prefix(max(float(np.max(np.abs(e[:, b]), initial=0.0)) for e in energies.values()))
        for key, words in BLOCK_ENERGY_WORDS.items():
            ax.plot(t, energies[key][:, b] / factor, lw=1.0, label=words)
        ax.plot(t, sum(e[:, b] for e in energies.values()) / factor, "k--", lw=0.8, label="sum of the three")
        ax.set(title=res.block_names[b], xlabel="time (s)", ylabel=f"energy ({prefix}{unit})")
        mark_stages(ax, res, names=ax is axes.flat[0])
    for ax in axes.flat[len(chosen):]:
        ax.remove()
    fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="outside upper center", ncols=2, fontsize="small",
               title=f"{method_label(res.method)}: energy of each block", title_fontsize="medium")
    return fig
