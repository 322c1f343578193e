"""The model as flat arrays for the time loop: :class:`ModelArrays` and its attached points.

``Model.arrays`` (:mod:`srdda.model`, which re-exports these names) compiles them; every term, the state and
the step read them. They live below the terms so that those can name them without importing the builder
(docs/architecture.md).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property
from operator import attrgetter

import numpy as np

from ..geometry.polygon import BlockMoments, block_moments
from ..geometry.polyhedron import PolyhedronMesh, PolyhedronMoments, polyhedron_moments
from ..history import TimeHistory
from ..kinematics.blocktype import BlockType, block_type_of_dimension
from .constraints import ConstraintArrays
from .materials import JointTable
from .stages import StagePlan
from .water import WaterTable

__all__ = ["AttachedPoints", "ModelArrays", "Load", "RENAMED_FIELDS"]

Load = TimeHistory  # a force (N) as a function of time: constant, table, sine or callable of t


@dataclass(frozen=True)
class AttachedPoints:
    """The points attached to blocks, one row each, and which rows are which (see :meth:`Model.arrays`).

    Shapes for a 2D model; a 3D model's points have 3 coordinates. The rows
    are, in order: the fixed points, the point loads, the point springs'
    ends a, their ends b, the measured points, then the points of the links
    (hinges, springs with dashpots, driven points, bolts), whose rows
    :class:`~srdda.constraints.data.ConstraintArrays` holds. The time loop
    moves every row with its block (``State.points``).
    """

    point_position: np.ndarray  # (np, 2) 2D, (np, 3) 3D: m, where each point is in the model as built
    point_block: np.ndarray  # (np,) int: the block carrying each point
    fixed_rows: np.ndarray  # (nfix,) int: the fixed points (pinned by a penalty spring to where they start)
    fixed_stiffness: np.ndarray  # (nfix,) N/m; nan: the run's penalty
    load_rows: np.ndarray  # (nload,) int: the points a point load acts at
    load_force: tuple[Load, ...]  # (nload,): each load's force (N, 2 components in 2D, 3 in 3D) against time
    point_spring_rows_a: np.ndarray  # (nps,) int: end a of each point spring (zero length, Model.add_point_spring)
    point_spring_rows_b: np.ndarray  # (nps,) int: its end b
    point_spring_stiffness: np.ndarray  # (nps,) N/m
    measured_rows: np.ndarray  # (nmp,) int: the measured points (recorded every step)


@dataclass(frozen=True)
class ModelArrays:
    """The model as flat arrays for the time loop (see :meth:`Model.arrays`).

    Fields are named ``object_field`` (as MuJoCo's ``mjModel``): the prefix
    says what the rows are (``block_``: nb blocks, ``vertex_``: nv vertices,
    ``edge_``: the nv edges of 2D blocks, ``face_``: nf faces of 3D blocks,
    ``material_``: nm block materials); shapes are given for 2D, then 3D.
    The points attached to blocks (fixed, loaded, tied by point springs,
    measured, and the links' points) are the record ``attached``; hinges,
    springs with dashpots, driven points and bolts the record ``links``;
    the joint materials the record ``joints``.
    """

    # -- blocks and their vertices
    vertex_position: np.ndarray  # (nv, 2) 2D, (nv, 3) 3D: m, every block's vertices, block after block
    block_ptr: np.ndarray  # (nb + 1,) int: block i's vertices are rows block_ptr[i]:block_ptr[i + 1]
    vertex_block: np.ndarray  # (nv,) int: the block of each vertex
    vertex_next: np.ndarray  # (nv,) int: the next vertex of the same block, cyclically (2D: counter-clockwise)
    block_density: np.ndarray  # (nb,) kg/m³ as built (block_mass is conserved)
    block_elasticity: np.ndarray  # (nb, 3, 3) 2D (plane stress or strain), (nb, 6, 6) 3D: Pa, stress = D·strain
    block_compliance: np.ndarray  # (nb, 3, 3) 2D, (nb, 6, 6) 3D: 1/Pa, the inverse of block_elasticity
    block_velocity: np.ndarray  # (nb, 6) 2D (vx, vy, ω, 3 strain rates 0), (nb, 12) 3D (v, ω, 6 zeros): initial
    block_stress: np.ndarray  # (nb, 3) 2D (σx, σy, τxy), (nb, 6) 3D (σx, σy, σz, τyz, τzx, τxy): initial, Pa
    block_fixed: np.ndarray  # (nb,) bool: the block does not move (ground, slope)
    block_material: np.ndarray  # (nb,) int: index into the model's materials
    block_names: tuple[str, ...]  # (nb,)
    gravity: np.ndarray  # (2,) 2D, (3,) 3D: m/s²
    # -- joints
    joints: JointTable  # (nj rows): the joint materials, row 0 the default joint
    material_joint: np.ndarray  # (nm, nm) int: the joint row of a contact between two block materials
    edge_joint: np.ndarray  # (nv,) int: joint row of the edge vertex -> vertex_next, -1: by materials (3D: all -1)
    # -- points and links
    attached: AttachedPoints  # fixed points, point loads, point springs, measured points (rows of np points)
    links: ConstraintArrays  # hinges, springs with dashpots, driven points, bolts (rows of attached points)
    mesh: PolyhedronMesh | None = None  # the faces (nf) of 3D blocks; None in 2D
    face_joint: np.ndarray | None = None  # (nf,) int 3D: joint row of each mesh face, -1: by materials; None 2D
    water: WaterTable | None = None  # the water table (docs/water.md); change it with dataclasses.replace
    block_removed: np.ndarray | None = None  # (nb,) bool: excavated by a stage (held, touches nothing); None: none
    stages: tuple[StagePlan, ...] = ()  # the staged analysis (srdda.stages), resolved; () runs as one stage
    base: ModelArrays | None = None  # of a stage's arrays: the model as built (what a results file stores)

    @property
    def n_blocks(self) -> int:
        return len(self.block_ptr) - 1

    @property
    def n_unknowns(self) -> int:
        """The step system's unknowns: blocks × the block type's ndof."""
        return self.n_blocks * self.block_type.ndof

    @cached_property
    def block_mass(self) -> np.ndarray:
        """Mass (nb,) of every block: density × volume of the model as built (kg per m of thickness in 2D).

        Mass is conserved: when a method changes a block's volume (dda0's rotation
        stretch, elastic strain) its density changes, not its mass.
        """
        return self.block_density * self.moments(self.vertex_position).volume

    @property
    def block_type(self) -> BlockType:
        """The blocks' type, by the dimension of the vertices."""
        return block_type_of_dimension(self.vertex_position.shape[1])

    def moments(self, vertices: np.ndarray) -> BlockMoments | PolyhedronMoments:
        """Exact block integrals of a configuration of this model's blocks (polygons, or polyhedra in 3D)."""
        if self.mesh is not None:
            return polyhedron_moments(vertices, self.mesh)
        return block_moments(vertices, self.block_ptr, self.vertex_block, self.vertex_next)


# ModelArrays' field names of srdda 0.1 -> where the value is now: read-only, deprecated for one release
RENAMED_FIELDS = {
    "vertices": "vertex_position", "next_vertex": "vertex_next", "density": "block_density",
    "elasticity": "block_elasticity", "compliance": "block_compliance", "velocity": "block_velocity",
    "stress": "block_stress", "joint_by_materials": "material_joint", "points": "attached.point_position",
    "point_block": "attached.point_block", "fixed_rows": "attached.fixed_rows",
    "fixed_stiffness": "attached.fixed_stiffness", "load_rows": "attached.load_rows", "loads": "attached.load_force",
    "spring_rows_a": "attached.point_spring_rows_a", "spring_rows_b": "attached.point_spring_rows_b",
    "spring_stiffness": "attached.point_spring_stiffness", "measured_rows": "attached.measured_rows",
}


def _deprecated_field(old: str, new: str) -> property:
    """A read-only property ``old`` of ModelArrays giving ``new`` (a dotted path) with a DeprecationWarning."""
    get = attrgetter(new)

    def value(self: ModelArrays) -> object:
        warnings.warn(f"ModelArrays.{old} is deprecated (renamed in srdda 0.2, removed in 0.3): use "
                      f"ModelArrays.{new}", DeprecationWarning, stacklevel=2)
        return get(self)

    return property(value, doc=f"Deprecated: ModelArrays.{new}.")


for _old, _new in RENAMED_FIELDS.items():  # set after the class so that type checkers flag the old names
    setattr(ModelArrays, _old, _deprecated_field(_old, _new))
