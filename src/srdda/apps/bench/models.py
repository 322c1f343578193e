"""The standard benchmark models of ``srdda bench`` (issue 14), generated here.

* ``jointed_slope("a" | "b" | "c")``: the jointed rock slope of the DDAML
  benchmark files (DDA for Windows format) that other DDA programs are timed
  on: a 60 × 5 m base under a 20 m high slope face at 45°, cut by two
  persistent joint sets (dip 25° and 100°) whose traces run over the box
  x ∈ [-1, 61] m, y ∈ [0, 21] m. The joint lines, materials and analysis
  parameters are written into a :class:`~srdda.io.ddainput.DDAInput`, so the
  blocks are cut and the model is built by exactly the code that converts the
  files (``srdda convert``): every closed loop is a block, as in Shi's DC,
  including the loops the traces close in the air above the face.
* ``brick_wall(nx, ny)``: a running-bond wall of 1 × 0.5 m bricks resting on
  a fixed base block.
* ``jointed_slope_3d()``: the 3D counterpart of slope b: its profile (inside
  the type-1 outline) extruded 12 m along the strike, cut by the same two
  sets (dip 25° and 80°, striking along the slope) and a vertical cross set
  every 2 m, on a fixed base slab; same materials and analysis parameters.
* ``english_bond_wall(nx, courses)``: a wall one brick (1 m) thick of
  1 × 0.5 × 0.5 m bricks in English bond (stretcher and header courses
  alternating) on a fixed base block.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from ...cutmodel import add_cut_polyhedra
from ...geometry.cutting3d import PolyhedralCut, convex_hull_polyhedron, cut_polyhedra
from ...geometry.jointsets2d import JointSet, joint_traces
from ...geometry.jointsets3d import JointSet3D, joint_planes
from ...geometry.polyhedron import box
from ...io.ddainput import BlockMaterialSpec, DDAInput
from ...model import JointMaterial, Material, Model
from ...settings import RunSettings

__all__ = ["SLOPES", "BRICK", "SLOPE_3D", "BrickWallSpec", "Slope3DSpec", "brick_wall", "english_bond_wall",
           "english_bond_outlines", "jointed_slope", "jointed_slope_3d", "slope_3d_cut", "slope_input"]


@dataclass(frozen=True)
class SlopeSpacing:
    """Perpendicular spacings (m) of the two joint sets of one slope model."""

    gentle: float  # the set dipping 25°
    steep: float  # the set dipping 100°


SLOPES = {"a": SlopeSpacing(4.0, 5.0), "b": SlopeSpacing(2.0, 2.5), "c": SlopeSpacing(1.0, 1.25)}

# The slope's outline and the base's top as type-1 joint lines (x1, y1, x2, y2), m.
_SLOPE_LINES = np.array([[0, -5, 60, -5], [60, -5, 60, 20], [60, 20, 35, 20], [35, 20, 15, 0], [15, 0, 0, 0],
                         [0, 0, 0, -5], [0, 0, 15, 0], [15, 0, 60, 0]], dtype=float)
_TRACE_BOX = [(-1.0, 0.0), (61.0, 0.0), (61.0, 21.0), (-1.0, 21.0)]  # where the set traces run
# Each set's traces lie at these perpendicular offsets (m, modulo the spacing) from the origin,
# as in the benchmark files.
_SET_OFFSETS = {25.0: 0.3137, 100.0: 0.5711}
_FIXED_POINTS = np.array([[2, -4], [58, -4], [30, -4], [2, -1], [58, -1]], dtype=float)  # in the base block
_MEASURED_POINT = np.array([[20.1234, 4.0321]])
_SLOPE_ROCK = BlockMaterialSpec(unit_mass=2700.0, unit_weight=26487.0, young=5e9, poisson=0.25)
_SLOPE_JOINTS = [(40.0, 0.0, 0.0), (15.0, 0.0, 0.0)]  # (φ°, c, T) of joint types 1 (outline) and 2 (sets)


def _set_origin(dip: float) -> tuple[float, float]:
    """A point of one trace line of the set dipping ``dip`` degrees."""
    theta = np.radians(dip)
    normal = np.array([-np.sin(theta), np.cos(theta)])
    x, y = _SET_OFFSETS[dip] * normal
    return float(x), float(y)


def slope_input(name: str) -> DDAInput:
    """The slope ``name`` as the content of its DDAML files (geometry and analysis)."""
    if name not in SLOPES:
        raise ValueError(f"unknown slope {name!r}; choose one of {sorted(SLOPES)}")
    spacing = SLOPES[name]
    sets = [JointSet(dip=dip, spacing=s, joint_type=2, origin=_set_origin(dip))
            for dip, s in ((25.0, spacing.gentle), (100.0, spacing.steep))]
    traces, types = joint_traces(shapely.Polygon(_TRACE_BOX), sets, seed=None)
    return DDAInput(
        source=f"jointed slope {name}", edge_node_ratio=0.01,
        joints=np.vstack([_SLOPE_LINES, traces]),
        joint_types=np.concatenate([np.ones(len(_SLOPE_LINES), dtype=np.int64), types]),
        fixed_lines=np.hstack([_FIXED_POINTS, _FIXED_POINTS]), measured_points=_MEASURED_POINT.copy(),
        dynamic=True, n_steps=200, max_displacement_ratio=0.002, max_time_step=0.002, penalty_factor=10.0,
        plane_strain=True, save_interval=10, rotation="linear",
        block_materials=[_SLOPE_ROCK], joint_materials=list(_SLOPE_JOINTS),
    )


def jointed_slope(name: str) -> tuple[Model, RunSettings]:
    """The slope ``name`` ("a", "b", "c": about 73, 270, 1,014 blocks) and its run settings.

    Settings as the converter reads them from the analysis file: dda0 (linear
    rotation), Δt = 2 ms, 200 steps, g2 = 0.002, contact stiffness 10 × E.
    """
    data = slope_input(name)
    return data.to_model(data.cut()), RunSettings(**data.run_parameters())


@dataclass(frozen=True)
class Slope3DSpec:
    """The 3D jointed slope: which 2D slope's profile and sets, how wide, how often cut across the strike (m)."""

    slope: str = "b"  # the 2D slope whose profile, joint sets and spacings are extruded
    width: float = 12.0  # along the strike (y)
    cross_spacing: float = 2.0  # the vertical cross set, planes y = 0, 2, 4, ... m


SLOPE_3D = Slope3DSpec()
_BASE_SLAB = ((0.0, -5.0), (60.0, 0.0))  # (x, z) corners of the 2D slope's base block
_SLOPE_PROFILE = np.array([[15.0, 0.0], [60.0, 0.0], [60.0, 20.0], [35.0, 20.0]])  # (x, z): the rock above it


def slope_3d_cut(spec: Slope3DSpec = SLOPE_3D) -> PolyhedralCut:
    """The rock above the base of :func:`jointed_slope_3d`, cut by its three joint sets (all of joint type 2).

    x east, z up, y along the strike; the 2D sets' traces (line at θ° in the
    x-z plane through the same point) become planes containing the y axis:
    dip θ towards the west for θ ≤ 90°, dip 180° - θ towards the east above.
    No piece is dropped or merged (no minimum thickness or volume), as the
    2D slopes keep every loop.
    """
    if spec.slope not in SLOPES:
        raise ValueError(f"unknown slope {spec.slope!r}; choose one of {sorted(SLOPES)}")
    if not (spec.width > 0 and spec.cross_spacing > 0):
        raise ValueError(f"a 3D slope needs width > 0 and cross_spacing > 0, got {spec.width}, {spec.cross_spacing}")
    spacing = SLOPES[spec.slope]
    corners = np.array([[x, y, z] for y in (0.0, spec.width) for x, z in _SLOPE_PROFILE])  # the profile's prism
    domain = convex_hull_polyhedron(corners, "slope")
    sets = []
    for theta, s in ((25.0, spacing.gentle), (100.0, spacing.steep)):
        x0, z0 = _set_origin(theta)
        sets.append(JointSet3D(dip=min(theta, 180.0 - theta), dip_direction=270.0 if theta <= 90.0 else 90.0,
                               spacing=s, joint_type=2, origin=(x0, 0.0, z0)))
    sets.append(JointSet3D(dip=90.0, dip_direction=0.0, spacing=spec.cross_spacing, joint_type=2))
    return cut_polyhedra(domain, joint_planes(corners, sets, seed=None), boundary_type=1)


def jointed_slope_3d(spec: Slope3DSpec = SLOPE_3D) -> tuple[Model, RunSettings]:
    """The 3D jointed slope (about 1,020 blocks for the default spec) on its fixed base slab, and its run settings.

    The base slab (block 0, fixed) is the 2D slope's base block extruded over
    the width; the cut blocks rest on it. Materials and analysis are the 2D
    slopes' (:func:`slope_input`): ρ = 2700 kg/m³, g = 26,487 / 2700 m/s²,
    E = 5 GPa, ν = 0.25; φ = 15° between cut blocks (the joint sets), 40°
    between a cut block and the base (the outline's joint type 1); dda0,
    Δt = 2 ms, g2 = 0.002, k_n = 10 E.
    """
    cut = slope_3d_cut(spec)
    model = Model(gravity=(0.0, 0.0, -_SLOPE_ROCK.unit_weight / _SLOPE_ROCK.unit_mass))
    rock = Material(_SLOPE_ROCK.unit_mass, _SLOPE_ROCK.young, _SLOPE_ROCK.poisson)
    model.add_material("rock", rock)
    model.add_material("base", rock)
    (outline_phi, *_), (set_phi, *_) = _SLOPE_JOINTS
    model.add_joint_material("joint sets", JointMaterial(set_phi), between=[("rock", "rock")])
    model.add_joint_material("base", JointMaterial(outline_phi), between=[("rock", "base")])
    (x0, z0), (x1, z1) = _BASE_SLAB
    model.add_polyhedron(*box((x0, 0.0, z0), (x1, spec.width, z1), "base"), "base", name="base", fixed=True)
    add_cut_polyhedra(model, cut, "rock")
    return model, RunSettings(**slope_input(spec.slope).run_parameters())


@dataclass(frozen=True)
class BrickWallSpec:
    """Bricks, base and contacts of the benchmark walls (SI)."""

    length: float = 1.0  # m
    height: float = 0.5  # m
    density: float = 2500.0  # kg/m³
    young: float = 5e9  # Pa
    poisson: float = 0.2
    friction_angle: float = 30.0  # degrees, every contact
    contact_stiffness: float = 5e10  # N/m
    dt: float = 1e-3  # s
    base_depth: float = 1.0  # m, the fixed base block under the wall
    base_overhang: float = 1.0  # m, the base reaches this far beyond each end (and, in 3D, side) of the wall
    width: float = 0.5  # m, a brick's third side (3D walls); English bond needs length = 2 × width
    # g2·w0: the largest vertex displacement of a step (m), the same in every wall, so the contact
    # search distance d0 = 2.5 g2 w0 does not grow with the wall's height (as g2 = 0.01 of the
    # half height would: 0.6 m, more than a brick, at 100 rows)
    step_displacement: float = 0.01


BRICK = BrickWallSpec()


def _brick_outlines(nx: int, ny: int, spec: BrickWallSpec) -> np.ndarray:
    """Corners (n, 4, 2) of every brick, row by row, counter-clockwise.

    Even rows hold ``nx`` whole bricks; odd rows start and end with a half
    brick, so the vertical joints of neighbouring rows are offset by half a
    brick (running bond).
    """
    even = np.arange(nx + 1) * spec.length
    odd = np.concatenate([[0.0], (np.arange(nx) + 0.5) * spec.length, [nx * spec.length]])
    rows = []
    for r in range(ny):
        x = even if r % 2 == 0 else odd
        y0, y1 = r * spec.height, (r + 1) * spec.height
        x0, x1 = x[:-1], x[1:]
        rows.append(np.stack([np.column_stack([x0, np.full_like(x0, y0)]),
                              np.column_stack([x1, np.full_like(x0, y0)]),
                              np.column_stack([x1, np.full_like(x0, y1)]),
                              np.column_stack([x0, np.full_like(x0, y1)])], axis=1))
    return np.concatenate(rows)


def brick_wall(nx: int, ny: int, spec: BrickWallSpec = BRICK) -> tuple[Model, RunSettings]:
    """A running-bond wall ``nx`` bricks long and ``ny`` rows high on a fixed base, and its run settings.

    ``ny // 2`` rows hold ``nx + 1`` bricks (two of them halves), the others
    ``nx``; the base block (index 0) is fixed. Plane stress, gravity 9.81
    m/s² down; one joint material (φ = 30°, no cohesion) for every contact.
    Settings: dda0, Δt = 1 ms, k_n = 5e10 N/m, g2·w0 = ``spec.step_displacement``.
    """
    if nx < 1 or ny < 1:
        raise ValueError(f"a brick wall needs nx >= 1 and ny >= 1, got {nx} x {ny}")
    model = Model(gravity=(0.0, -9.81))
    model.add_material("brick", Material(spec.density, spec.young, spec.poisson))
    model.add_joint_material("mortarless joint", JointMaterial(spec.friction_angle), between=[("brick", "brick")])
    x0, x1 = -spec.base_overhang, nx * spec.length + spec.base_overhang
    model.add_block([[x0, -spec.base_depth], [x1, -spec.base_depth], [x1, 0.0], [x0, 0.0]], "brick",
                    name="base", fixed=True)
    for corners in _brick_outlines(nx, ny, spec):
        model.add_block(corners, "brick")
    return model, _wall_settings(ny, spec)


def _wall_settings(rows: int, spec: BrickWallSpec) -> RunSettings:
    """dda0, Δt, k_n of ``spec`` and g2 such that g2·w0 = ``spec.step_displacement`` for a wall of ``rows`` rows."""
    half_height = 0.5 * (rows * spec.height + spec.base_depth)  # w0 of step.model_half_height
    return RunSettings(dt=spec.dt, n_steps=10, method="dda0", penalty=spec.contact_stiffness,
                       contact_penalty=spec.contact_stiffness,
                       max_displacement_ratio=spec.step_displacement / half_height)


def english_bond_outlines(nx: int, courses: int, spec: BrickWallSpec = BRICK) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners (n, 3) of every brick of an English-bond wall, course by course.

    The wall runs along x, ``nx`` brick lengths long and one brick length L
    thick (y from 0 to L), courses of height h from z = 0 up. Even courses are
    stretchers: two leaves (y in [0, w] and [w, L], w = L/2) of ``nx`` bricks
    along x. Odd courses are headers across the wall (w along x, L along y),
    starting and ending with a closer of w/2, so their vertical joints fall at
    the middle of the stretchers below and above, and the headers tie the two
    leaves together.
    """
    if nx < 1 or courses < 1:
        raise ValueError(f"an English-bond wall needs nx >= 1 and courses >= 1, got {nx} x {courses}")
    length, w, h = spec.length, spec.width, spec.height
    if length != 2.0 * w:
        raise ValueError(f"English bond needs bricks twice as long as wide, got {length} x {w} m")
    sx, sy = (a.ravel() for a in np.meshgrid(np.arange(nx) * length, [0.0, w]))  # leaf by leaf
    stretch_lo = np.column_stack([sx, sy, np.zeros_like(sx)])
    stretch_hi = stretch_lo + np.array([length, w, h])
    x = np.concatenate([[0.0], 0.5 * w + w * np.arange(2 * nx), [nx * length]])  # header joints
    header_lo = np.column_stack([x[:-1], np.zeros_like(x[:-1]), np.zeros_like(x[:-1])])
    header_hi = np.column_stack([x[1:], np.full_like(x[1:], length), np.full_like(x[1:], h)])
    rise = np.array([0.0, 0.0, h])
    lo = [(header_lo if k % 2 else stretch_lo) + k * rise for k in range(courses)]
    hi = [(header_hi if k % 2 else stretch_hi) + k * rise for k in range(courses)]
    return np.concatenate(lo), np.concatenate(hi)


def english_bond_wall(nx: int, courses: int, spec: BrickWallSpec = BRICK) -> tuple[Model, RunSettings]:
    """An English-bond wall (:func:`english_bond_outlines`) on a fixed base block, and its run settings.

    2·nx bricks in each stretcher course and 2·nx + 1 in each header course;
    the base (block 0, fixed) is ``spec.base_depth`` deep and reaches
    ``spec.base_overhang`` beyond the wall on every side. Gravity 9.81 m/s²
    down (-z); material, joint and settings as :func:`brick_wall`'s.
    """
    lo, hi = english_bond_outlines(nx, courses, spec)
    model = Model(gravity=(0.0, 0.0, -9.81))
    model.add_material("brick", Material(spec.density, spec.young, spec.poisson))
    model.add_joint_material("mortarless joint", JointMaterial(spec.friction_angle), between=[("brick", "brick")])
    reach = spec.base_overhang
    model.add_polyhedron(*box((-reach, -reach, -spec.base_depth), (nx * spec.length + reach, spec.length + reach, 0.0),
                              "base"), "brick", name="base", fixed=True)
    names = [f"brick {k}" for k in range(len(lo))]
    model.add_polyhedra([box(a, b, n) for a, b, n in zip(lo, hi, names)], ["brick"] * len(lo), names,
                        [False] * len(lo))
    return model, _wall_settings(courses, spec)

