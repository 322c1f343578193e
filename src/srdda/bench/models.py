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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from ..geometry.jointsets import JointSet, joint_traces
from ..io.ddainput import BlockMaterialSpec, DDAInput
from ..model import JointMaterial, Material, Model
from ..settings import RunSettings

__all__ = ["SLOPES", "BRICK", "BrickWallSpec", "brick_wall", "jointed_slope", "slope_input"]


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
        block_materials=[BlockMaterialSpec(unit_mass=2700.0, unit_weight=26487.0, young=5e9, poisson=0.25)],
        joint_materials=[(40.0, 0.0, 0.0), (15.0, 0.0, 0.0)],
    )


def jointed_slope(name: str) -> tuple[Model, RunSettings]:
    """The slope ``name`` ("a", "b", "c": about 73, 270, 1,014 blocks) and its run settings.

    Settings as the converter reads them from the analysis file: dda0 (linear
    rotation), Δt = 2 ms, 200 steps, g2 = 0.002, contact stiffness 10 × E.
    """
    data = slope_input(name)
    return data.to_model(data.cut()), RunSettings(**data.run_parameters())


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
    base_overhang: float = 1.0  # m, the base reaches this far beyond each end of the wall
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
    half_height = 0.5 * (ny * spec.height + spec.base_depth)  # w0 of simulation.model_half_height
    settings = RunSettings(dt=spec.dt, n_steps=10, method="dda0", penalty=spec.contact_stiffness,
                           contact_penalty=spec.contact_stiffness,
                           max_displacement_ratio=spec.step_displacement / half_height)
    return model, settings

