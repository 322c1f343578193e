"""The model: blocks, materials, loads, supports and measured points.

A :class:`Model` is built with ``add_*`` methods (or read from a model file by
:mod:`srdda.io`) and compiled by :meth:`Model.arrays` into flat numpy arrays
that the time loop uses. Units are SI: m, kg, s, N, Pa.

The records it builds from and compiles into (:class:`ModelArrays`, :class:`Material`, :class:`JointMaterial`,
:class:`JointTable`, :class:`ModelError`, ...) are defined in :mod:`srdda.modeldata`, below the terms that name
them, and re-exported here.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import shapely

from .constraints.checks import redundant_constraints, unheld_massless_blocks
from .constraints.water import crack_facets
from .history import HistoryError, MotionHistory
from .geometry.polygon import next_vertex_index, normalize_polygon, overlapping_pairs
from .geometry.polyhedron import (PolyhedronMesh, normalize_polyhedra, normalize_polyhedron,
                                  PolyhedronError, box, polyhedron_covers, prism)
from .kinematics.blocktype import PLANE, SOLID, BlockType, block_type_of_dimension
from .kinematics.shape3d import elasticity_matrix_3d
from .kinematics.update2d import rotate_symmetric_components
from .kinematics.update3d import rotate_symmetric_components_3d
# the records (srdda.modeldata) keep this path; RENAMED_FIELDS and ConstraintArrays are only re-exported here
from .modeldata.arrays import RENAMED_FIELDS, AttachedPoints, Load, ModelArrays
from .modeldata.constraints import BoltSpec, ConstraintArrays, HingeSpec, PrescribedSpec, SpringSpec, compile_links
from .modeldata.materials import JointMaterial, JointTable, Material, ModelError, PlaneKind, elasticity_matrix
from .modeldata.water import UNIT_WEIGHT, WaterTable, water_table
from .stages import Stage, resolve_stages

__all__ = ["AttachedPoints", "JointMaterial", "JointTable", "Material", "Model", "ModelArrays", "ModelError", "Load",
           "PlaneKind", "elasticity_matrix"]


def _finite(values: Sequence[float] | float, what: str) -> tuple[float, ...]:
    """``values`` as floats, or a ModelError naming ``what`` if one is not a finite number."""
    numbers = tuple(float(v) for v in np.atleast_1d(np.asarray(values, dtype=float)))
    if not all(np.isfinite(numbers)):
        raise ModelError(f"{what} must be finite numbers, got {list(numbers)}")
    return numbers


@dataclass
class _Block:
    vertices: np.ndarray
    material: int
    velocity: tuple[float, ...]  # translation then rotation rates
    stress: tuple[float, ...]
    name: str
    fixed: bool = False
    edge_joints: tuple[str | None, ...] | None = None  # joint material of edge i (vertex i to i+1)
    faces: list[np.ndarray] | None = None  # a polyhedron's outward faces (3D); None for a polygon
    face_joints: tuple[str | None, ...] | None = None  # joint material of face i (3D)


@dataclass
class Model:
    """A block system: polygons (2D, :meth:`add_block`) or polyhedra (3D, :meth:`add_polyhedron`).

    Build it with the ``add_*`` methods; SI units throughout. The dimension is
    the blocks': a model holds polygons or polyhedra, not both; gravity and
    every point have as many components.
    """

    gravity: tuple[float, ...] = (0.0, 0.0)
    materials: dict[str, Material] = field(default_factory=dict)
    blocks: list[_Block] = field(default_factory=list)
    fixed_points: list[tuple[int, np.ndarray, float]] = field(default_factory=list)
    point_loads: list[tuple[int, np.ndarray, Load]] = field(default_factory=list)
    point_springs: list[tuple[int, np.ndarray, int, np.ndarray, float]] = field(default_factory=list)
    measured_points: list[tuple[int, np.ndarray]] = field(default_factory=list)
    joint_materials: dict[str, JointMaterial] = field(default_factory=dict)
    joint_map: dict[tuple[str, str], str] = field(default_factory=dict)
    default_joint: JointMaterial = JointMaterial()
    hinges: list[HingeSpec] = field(default_factory=list)
    springs: list[SpringSpec] = field(default_factory=list)
    prescribed: list[PrescribedSpec] = field(default_factory=list)
    base_acceleration: MotionHistory | None = None
    bolts: list[BoltSpec] = field(default_factory=list)
    allow_overlap: bool = False  # True: blocks that overlap at the start are accepted (their contacts push them apart)
    water: WaterTable | None = None  # the water in the joints (set_water, docs/water.md)
    stages: list[Stage] = field(default_factory=list)  # the staged analysis (srdda.stages); [] runs as today

    # -- building ---------------------------------------------------------
    def add_material(self, name: str, material: Material) -> str:
        self.materials[name] = material
        return name

    def add_joint_material(self, name: str, joint: JointMaterial, between: Sequence[tuple[str, str]] = ()) -> str:
        """Add a joint material; ``between`` lists block-material pairs whose contacts use it."""
        self.joint_materials[name] = joint
        for a, b in between:
            for m in (a, b):
                if m not in self.materials:
                    raise ModelError(f"joint material {name!r}: unknown block material {m!r}")
            held = self.joint_map.get((a, b), self.joint_map.get((b, a), name))
            if held != name:
                raise ModelError(f"joint material {name!r}: the block materials ({a!r}, {b!r}) already have joint "
                                 f"material {held!r}; give each pair of materials one joint material")
            self.joint_map[(a, b)] = name
        return name

    def add_block(
        self,
        vertices: Sequence[Sequence[float]] | np.ndarray,
        material: str,
        velocity: Sequence[float] = (0.0, 0.0),
        angular_velocity: float = 0.0,
        stress: Sequence[float] = (0.0, 0.0, 0.0),
        name: str | None = None,
        fixed: bool = False,
        edge_joints: Sequence[str | None] | None = None,
    ) -> int:
        """Add a simple polygon (any orientation; stored counter-clockwise); returns its index.

        ``fixed`` blocks never move. ``edge_joints`` names the joint material of
        each edge (edge i runs from vertex i to vertex i+1 as given); None or a
        missing list means the joint is chosen by the block materials.
        """
        index = len(self.blocks)
        label = name or f"block {index}"
        if material not in self.materials:
            raise ModelError(f"{label}: unknown material {material!r}")
        self._same_dimension(PLANE.dim, label)
        raw = np.asarray(vertices, dtype=float)
        verts = normalize_polygon(vertices, label)
        joints: tuple[str | None, ...] | None = None
        if edge_joints is not None:
            joints = tuple(edge_joints)
            if len(joints) != len(verts):
                raise ModelError(f"{label}: edge_joints needs one entry per edge ({len(verts)}), got {len(joints)}")
            for j in joints:
                if j is not None and j not in self.joint_materials:
                    raise ModelError(f"{label}: unknown joint material {j!r}")
            if len(raw) > len(verts):
                raw = raw[:-1]
            if not np.array_equal(raw, verts):  # reversed to counter-clockwise: edge i -> edge n-2-i
                joints = tuple(joints[(len(joints) - 2 - i) % len(joints)] for i in range(len(joints)))
        v = _finite(velocity, f"{label}: velocity")
        if len(v) != 2:
            raise ModelError(f"{label}: velocity must be [vx, vy]")
        s = _finite(stress, f"{label}: stress")
        if len(s) != 3:
            raise ModelError(f"{label}: stress must be [sx, sy, txy]")
        angular_velocity = _finite(angular_velocity, f"{label}: angular_velocity")[0]
        mat_index = list(self.materials).index(material)
        self.blocks.append(_Block(verts, mat_index, (v[0], v[1], float(angular_velocity)), s, label, bool(fixed),
                                  joints))
        return index

    def add_polyhedron(
        self,
        vertices: Sequence[Sequence[float]] | np.ndarray,
        faces: Sequence[Sequence[int] | np.ndarray],
        material: str,
        velocity: Sequence[float] = (0.0, 0.0, 0.0),
        angular_velocity: Sequence[float] = (0.0, 0.0, 0.0),
        stress: Sequence[float] = (0.0,) * 6,
        name: str | None = None,
        fixed: bool = False,
        face_joints: Sequence[str | None] | None = None,
    ) -> int:
        """Add a polyhedral block (3D): vertices (n, 3) and faces as lists of vertex indices; returns its index.

        The surface must be closed and manifold with planar faces; their
        orientation is made consistent and outward (see
        :func:`srdda.geometry.polyhedron.normalize_polyhedron`). ``stress`` is
        (σx, σy, σz, τyz, τzx, τxy) in Pa; ``angular_velocity`` (ωx, ωy, ωz) in rad/s.
        ``srdda.geometry.polyhedron.box`` and ``prism`` make (vertices, faces).
        ``face_joints`` names the joint material of each face (None: the one
        chosen by the block materials); a contact on a face takes the face's.
        """
        index = len(self.blocks)
        label = name or f"block {index}"
        if material not in self.materials:
            raise ModelError(f"{label}: unknown material {material!r}")
        self._same_dimension(SOLID.dim, label)
        verts, outward = normalize_polyhedron(vertices, faces, label)
        v, w, s = (_finite(x, f"{label}: {name}") for x, name in ((velocity, "velocity"),
                                                                   (angular_velocity, "angular_velocity"),
                                                                   (stress, "stress")))
        if len(v) != SOLID.dim or len(w) != SOLID.dim:
            raise ModelError(f"{label}: velocity and angular_velocity are [x, y, z] vectors")
        if len(s) != SOLID.n_strain:
            raise ModelError(f"{label}: stress must be [sx, sy, sz, tyz, tzx, txy]")
        mat_index = list(self.materials).index(material)
        self.blocks.append(_Block(verts, mat_index, (*v, *w), s, label, bool(fixed), None, outward,
                                  self._face_joints(face_joints, len(outward), label)))
        return index

    def _face_joints(self, face_joints: Sequence[str | None] | None, n_faces: int, label: str
                     ) -> tuple[str | None, ...] | None:
        """Checked joint-material names of a polyhedron's faces (None when none is named)."""
        if face_joints is None:
            return None
        joints = tuple(face_joints)
        if len(joints) != n_faces:
            raise ModelError(f"{label}: face_joints needs one entry per face ({n_faces}), got {len(joints)}")
        for j in joints:
            if j is not None and j not in self.joint_materials:
                raise ModelError(f"{label}: unknown joint material {j!r}")
        return joints if any(j is not None for j in joints) else None

    def add_polyhedra(self, blocks: Sequence[tuple[object, object]], materials: Sequence[str],
                      names: Sequence[str], fixed: Sequence[bool],
                      face_joints: Sequence[Sequence[str | None] | None] | None = None) -> list[int]:
        """Add many polyhedral blocks at rest, validated together (fast for thousands); returns their indices.

        ``blocks`` are (vertices, faces) pairs, with one material, name and
        fixed flag each (and optionally the faces' joint materials); otherwise
        as :meth:`add_polyhedron`.
        """
        if not len(blocks) == len(materials) == len(names) == len(fixed):
            raise ModelError("add_polyhedra: give one material, name and fixed flag per block")
        unknown = sorted(set(materials) - set(self.materials))
        if unknown:
            raise ModelError(f"{names[list(materials).index(unknown[0])]}: unknown material {unknown[0]!r}")
        if not blocks:
            return []
        self._same_dimension(SOLID.dim, names[0])
        mat_index = {name: k for k, name in enumerate(self.materials)}
        first = len(self.blocks)
        rest = (0.0,) * (2 * SOLID.dim)
        joints = [None] * len(blocks) if face_joints is None else list(face_joints)
        if len(joints) != len(blocks):
            raise ModelError("add_polyhedra: give face_joints for every block (or None)")
        for (verts, outward), mat, name, fix, fj in zip(normalize_polyhedra(blocks, names), materials, names, fixed,
                                                         joints):
            self.blocks.append(_Block(verts, mat_index[mat], rest, (0.0,) * SOLID.n_strain, name, bool(fix), None,
                                      outward, self._face_joints(fj, len(outward), name)))
        return list(range(first, len(self.blocks)))

    @property
    def dim(self) -> int:
        """2 for polygons, 3 for polyhedra (2 while the model has no block)."""
        return SOLID.dim if self.blocks and self.blocks[0].faces is not None else PLANE.dim

    def _same_dimension(self, dim: int, label: str) -> None:
        if self.blocks and self.dim != dim:
            raise ModelError(f"{label}: a model holds polygons (2D) or polyhedra (3D), not both")

    def block_at(self, point: Sequence[float] | np.ndarray, what: str = "point") -> int:
        """Index of the block containing ``point`` (on its boundary counts)."""
        found = self.blocks_at(point)
        if not found:
            raise ModelError(f"{what} at {tuple(float(c) for c in point)} lies in no block")
        return found[0]

    def _resolve(self, point: Sequence[float] | np.ndarray, block: int | None, what: str) -> tuple[int, np.ndarray]:
        p = np.asarray(point, dtype=float)
        if p.shape != (self.dim,) or not np.all(np.isfinite(p)):
            raise ModelError(f"{what}: a point has {self.dim} finite coordinates in this {self.dim}D model")
        if block is None:
            block = self.block_at(p, what)
        elif not 0 <= block < len(self.blocks):
            raise ModelError(f"{what}: block {block} does not exist")
        elif not self._covers(block, p):
            raise ModelError(f"{what}: point {tuple(float(c) for c in p)} lies outside block "
                             f"{self.blocks[block].name!r}")
        return block, p

    def add_fixed_point(self, point: Sequence[float], block: int | None = None, stiffness: float | None = None) -> None:
        """Pin ``point`` of a block to where it is now by a penalty spring (N/m; default: the run's penalty)."""
        b, p = self._resolve(point, block, "fixed point")
        if stiffness is not None and not 0 < stiffness < np.inf:
            raise ModelError(f"fixed point stiffness must be finite and > 0, got {stiffness}")
        self.fixed_points.append((b, p, np.nan if stiffness is None else float(stiffness)))

    def add_point_load(self, point: Sequence[float], force: object, block: int | None = None) -> None:
        """Apply a force (constant [fx, fy], table of [t, fx, fy], or callable of t) at a block point."""
        b, p = self._resolve(point, block, "point load")
        try:
            self.point_loads.append((b, p, Load.of(force)))
        except HistoryError as exc:
            raise ModelError(f"point load at {tuple(p)}: {exc}") from None

    def add_point_spring(self, point_a: Sequence[float], point_b: Sequence[float], stiffness: float,
                         block_a: int | None = None, block_b: int | None = None) -> None:
        """Tie a point of one block to a point of another by a zero-length spring (N/m)."""
        a, pa = self._resolve(point_a, block_a, "point spring end a")
        b, pb = self._resolve(point_b, block_b, "point spring end b")
        if not 0 < stiffness < np.inf:
            raise ModelError(f"point spring stiffness must be finite and > 0, got {stiffness}")
        self.point_springs.append((a, pa, b, pb, float(stiffness)))

    def add_measured_point(self, point: Sequence[float], block: int | None = None) -> int:
        """Record position and velocity of a block point every step; returns its index."""
        b, p = self._resolve(point, block, "measured point")
        self.measured_points.append((b, p))
        return len(self.measured_points) - 1

    # -- constraints, springs, driven points (srdda.constraints) -------------
    def blocks_at(self, point: Sequence[float] | np.ndarray) -> list[int]:
        """Indices of every block containing ``point`` (on a boundary counts)."""
        p = np.asarray(point, dtype=float)
        return [i for i in range(len(self.blocks)) if self._covers(i, p)]

    def _covers(self, block: int, point: np.ndarray) -> bool:
        """True if ``point`` lies in the block or on its boundary (to 1e-9 of its size)."""
        b = self.blocks[block]
        if b.faces is not None:
            return polyhedron_covers(b.vertices, b.faces, point)
        return shapely.Polygon(b.vertices).buffer(1e-9 * _scale(b.vertices)).covers(shapely.Point(point))

    def add_hinge(self, point: Sequence[float], block_a: int | None = None, block_b: int | None = None,
                  point_b: Sequence[float] | None = None, correct_drift: bool = True, name: str = "") -> int:
        """Keep ``point`` of block a on ``point_b`` (default: the same point) of block b, exactly.

        Without block indices the two blocks that contain the point are used;
        each point must lie in (or on) its block. ``correct_drift=False`` is the
        paper's Eq. 72 (right-hand side 0). Returns the hinge's index: the force on
        its first point is ``srdda.hinge_forces(arrays.links, result.multipliers[k])[i]``.
        """
        what = name or f"hinge {len(self.hinges)}"
        pa = np.asarray(point, dtype=float)
        pb = pa if point_b is None else np.asarray(point_b, dtype=float)
        if point_b is None and (block_a is None or block_b is None):
            found = [i for i in self.blocks_at(pa) if i not in (block_a, block_b)]
            missing = int(block_a is None) + int(block_b is None)
            if len(found) != missing:
                raise ModelError(f"{what}: cannot tell which blocks point {tuple(pa)} joins; give block_a and block_b")
            block_a = found.pop(0) if block_a is None else block_a
            block_b = found.pop(0) if block_b is None else block_b
        a, pa = self._resolve(pa, block_a, what)
        b, pb = self._resolve(pb, block_b, what)
        if a == b:
            raise ModelError(f"{what}: block_a and block_b must differ")
        if self.blocks[a].fixed and self.blocks[b].fixed:
            raise ModelError(f"{what}: both blocks are fixed")
        self.hinges.append(HingeSpec(a, pa, b, pb, bool(correct_drift), what))
        return len(self.hinges) - 1

    def add_pin(self, point: Sequence[float], block: int | None = None, correct_drift: bool = True,
                name: str = "") -> int:
        """Pin ``point`` of a block to the ground exactly (Lagrange multipliers); returns its hinge index."""
        what = name or f"pin {len(self.hinges)}"
        b, p = self._resolve(point, block, what)
        if self.blocks[b].fixed:
            raise ModelError(f"{what}: block {self.blocks[b].name!r} is fixed already")
        self.hinges.append(HingeSpec(b, p, -1, p, bool(correct_drift), what))
        return len(self.hinges) - 1

    def add_spring(self, point_a: Sequence[float], point_b: Sequence[float], stiffness: float,
                   rest_length: float | None = None, damping: float = 0.0, kind: str = "axial",
                   block_a: int | None = None, block_b: int | None = None) -> None:
        """A linear spring (N/m) with optional dashpot (N·s/m) between two block points (see SpringSpec)."""
        a, pa = self._resolve(point_a, block_a, "spring end a")
        b, pb = self._resolve(point_b, block_b, "spring end b")
        if not 0 < stiffness < np.inf:
            raise ModelError(f"spring stiffness must be finite and > 0, got {stiffness}")
        if not 0 <= damping < np.inf:
            raise ModelError(f"spring damping must be finite and >= 0, got {damping}")
        if kind not in ("axial", "offset"):
            raise ModelError(f"spring kind must be 'axial' or 'offset', got {kind!r}")
        if kind == "axial" and np.allclose(pa, pb):
            raise ModelError("spring: an axial spring needs two distinct points (use kind='offset')")
        if rest_length is not None and not rest_length >= 0:
            raise ModelError(f"spring rest_length must be >= 0, got {rest_length}")
        self.springs.append(SpringSpec(a, pa, b, pb, float(stiffness), rest_length, float(damping), kind))

    def add_prescribed_motion(self, point: Sequence[float], history: object, quantity: str = "displacement",
                              components: str | None = None, by: str = "multiplier", stiffness: float | None = None,
                              block: int | None = None) -> None:
        """Drive a block point: ``history`` of displacement (m, from its start), velocity (m/s) or
        acceleration (m/s², starting from rest: a shaking table or an earthquake record at a support).

        ``history``: [x, y(, z)] constant, [[t, x, y(, z)], ...] table, ``MotionHistory.sine(...)`` or a
        callable of t; ``components`` the axes driven, e.g. "x", "xy" (default: every axis: "xy" in 2D,
        "xyz" in 3D); ``by`` "multiplier" (exact) or "penalty" (``stiffness`` N/m, default the run's penalty).
        """
        b, p = self._resolve(point, block, "prescribed point")
        if self.blocks[b].fixed:
            raise ModelError(f"prescribed point: block {self.blocks[b].name!r} is fixed")
        if quantity not in ("displacement", "velocity", "acceleration"):
            raise ModelError(f"prescribed quantity must be 'displacement', 'velocity' or 'acceleration', got {quantity!r}")
        axes = "xyz"[: self.dim]
        components = axes if components is None else components
        if not components or any(c not in axes for c in components) or len(set(components)) != len(components):
            raise ModelError(f"prescribed components are some of {axes!r} in this {self.dim}D model, got "
                             f"{components!r}")
        if by not in ("multiplier", "penalty"):
            raise ModelError(f"prescribed 'by' must be 'multiplier' or 'penalty', got {by!r}")
        if stiffness is not None and not 0 < stiffness < np.inf:
            raise ModelError(f"prescribed stiffness must be finite and > 0, got {stiffness}")
        try:
            hist = MotionHistory.of(history)
        except HistoryError as exc:
            raise ModelError(f"prescribed point history: {exc}") from exc
        self.prescribed.append(PrescribedSpec(b, p, hist, quantity, tuple(c in components for c in axes), by,
                                              None if stiffness is None else float(stiffness)))

    def add_bolt(self, point_a: Sequence[float], point_b: Sequence[float], stiffness: float, pretension: float = 0.0,
                 strength: float | None = None, shear_stiffness: float = 0.0, block_a: int | None = None,
                 block_b: int | None = None, name: str = "") -> int:
        """A rock bolt from ``point_a`` of a block to ``point_b`` of another block (``block_b=-1``: the ground).

        ``stiffness`` axial (N/m), ``pretension`` (N), ``strength`` tensile (N;
        None: never breaks), ``shear_stiffness`` (N/m) across the bolt; see
        :mod:`srdda.constraints.bolts`. Returns the bolt's index.
        """
        what = name or f"bolt {len(self.bolts)}"
        a, pa = self._resolve(point_a, block_a, f"{what} end a")
        if block_b == -1:
            pb = np.asarray(point_b, dtype=float)
            if pb.shape != (self.dim,) or not np.all(np.isfinite(pb)):
                raise ModelError(f"{what} end b: a point has {self.dim} finite coordinates in this {self.dim}D model")
            b = -1
        else:
            b, pb = self._resolve(point_b, block_b, f"{what} end b")
            if a == b:
                raise ModelError(f"{what}: both ends lie in block {self.blocks[a].name!r}; a bolt joins two blocks "
                                 "(or a block and the ground: block_b = -1, \"ground\" in a model file)")
        for label, value, low in (("stiffness", stiffness, "> 0"), ("pretension", pretension, ">= 0"),
                                  ("shear_stiffness", shear_stiffness, ">= 0")):
            if not (np.isfinite(value) and (value > 0 if low == "> 0" else value >= 0)):
                raise ModelError(f"{what}: {label} must be finite and {low}, got {value}")
        if strength is not None and not 0 < strength:
            raise ModelError(f"{what}: strength must be > 0 (N), got {strength}")
        if np.allclose(pa, pb):
            raise ModelError(f"{what}: its two ends coincide; a bolt needs a length")
        if strength is not None and pretension > strength:
            raise ModelError(f"{what}: the pretension {pretension} N exceeds the strength {strength} N")
        self.bolts.append(BoltSpec(a, pa, b, pb, float(stiffness), float(pretension),
                                   np.inf if strength is None else float(strength), float(shear_stiffness), what))
        return len(self.bolts) - 1

    def set_base_acceleration(self, history: object) -> None:
        """Ground acceleration a_g(t) (m/s²), applied as the body force -ρ·a_g on every block."""
        try:
            self.base_acceleration = MotionHistory.of(history)
        except HistoryError as exc:
            raise ModelError(f"base acceleration: {exc}") from exc

    def set_water(self, level: float | None = None, point: Sequence[float] | None = None,
                  normal: Sequence[float] | None = None, unit_weight: float = UNIT_WEIGHT,
                  cracks: Sequence[tuple[Sequence[float], Sequence[float], float]] = ()) -> WaterTable:
        """Water in the joints (docs/water.md): the phreatic surface at the horizontal ``level`` (m, elevation
        against gravity: y in 2D, z in 3D) or the plane through ``point`` with the upward ``normal``;
        ``unit_weight`` γ_w (N/m³); ``cracks``: tension cracks as (point, normal, depth), the plane of the crack
        and the depth (m) of the water standing in it above its bottom. Set the gravity first.
        """
        try:
            self.water = water_table(self.gravity, level, point, normal, unit_weight, cracks)
        except ValueError as exc:
            raise ModelError(f"water.{exc}") from None
        return self.water

    def add_stage(self, stage: Stage) -> int:
        """Append a stage of a staged analysis (:class:`srdda.stages.Stage`); returns its index.

        Its names (blocks, bolts, materials) are checked when the model is compiled (:meth:`arrays`).
        """
        self.stages.append(stage)
        return len(self.stages) - 1

    def _check_overlaps(self, vertices: np.ndarray, block_ptr: np.ndarray) -> None:
        """ModelError naming the blocks that overlap at the start (more than 1e-6 of the smaller area)."""
        pairs, areas = overlapping_pairs(vertices, block_ptr)
        if len(pairs):
            shown = ", ".join(f"{self.blocks[a].name!r} and {self.blocks[b].name!r} ({area:.3g} m²)"
                              for (a, b), area in zip(pairs[:5], areas[:5]))
            more = f" and {len(pairs) - 5} more pairs" if len(pairs) > 5 else ""
            raise ModelError(f"blocks overlap at the start: {shown}{more}; move them apart, or set "
                             "allow_overlap (Model.allow_overlap = True, or allow_overlap = true in the model "
                             "file) to let their contacts push them apart")

    def extruded(self, thickness: float = 1.0) -> Model:
        """This 2D model as 3D prisms from z = -thickness/2 to thickness/2, every point at z = 0.

        A 2D model is per metre of thickness: with ``thickness`` 1 m masses,
        stiffnesses and forces carry over unchanged, and the 3D model moving in
        its plane is the 2D one (gravity, velocities, loads get a zero z
        component; stresses (σx, σy, τxy) become (σx, σy, 0, 0, 0, τxy)).
        """
        if self.dim != PLANE.dim:
            raise ModelError("only a 2D model can be extruded")
        if not thickness > 0:
            raise ModelError(f"extrusion thickness must be > 0, got {thickness}")
        out = Model(gravity=(*self.gravity, 0.0), materials=dict(self.materials),
                    joint_materials=dict(self.joint_materials), joint_map=dict(self.joint_map),
                    default_joint=self.default_joint)
        mats = list(self.materials)
        half = 0.5 * thickness
        for b in self.blocks:
            sx, sy, txy = b.stress
            out.add_polyhedron(*prism(b.vertices, -half, half, b.name), mats[b.material],
                               velocity=(*b.velocity[:2], 0.0), angular_velocity=(0.0, 0.0, b.velocity[2]),
                               stress=(sx, sy, 0.0, 0.0, 0.0, txy), name=b.name, fixed=b.fixed)

        def at(p: np.ndarray) -> np.ndarray:
            return np.append(p, 0.0)

        out.fixed_points = [(i, at(p), k) for i, p, k in self.fixed_points]
        out.point_loads = [(i, at(p), load.padded(SOLID.dim)) for i, p, load in self.point_loads]
        out.point_springs = [(a, at(pa), b, at(pb), k) for a, pa, b, pb, k in self.point_springs]
        out.measured_points = [(i, at(p)) for i, p in self.measured_points]
        out.hinges = [replace(h, point_a=at(h.point_a), point_b=at(h.point_b)) for h in self.hinges]
        out.springs = [replace(s, point_a=at(s.point_a), point_b=at(s.point_b)) for s in self.springs]
        out.prescribed = [replace(p, point=at(p.point), history=p.history.padded(SOLID.dim),
                                  components=(*p.components, False)) for p in self.prescribed]
        if self.base_acceleration is not None:
            out.base_acceleration = self.base_acceleration.padded(SOLID.dim)
        out.bolts = [replace(b, point_a=at(b.point_a), point_b=at(b.point_b)) for b in self.bolts]
        out.water = None if self.water is None else self.water.padded()
        out.stages = [replace(s, base_acceleration=None if s.base_acceleration is None
                              else s.base_acceleration.padded(SOLID.dim)) for s in self.stages]
        return out

    def add_box(self, lo: Sequence[float], hi: Sequence[float], material: str, **options: Any) -> int:
        """Add the axis-aligned box [lo, hi] (3D, m) as a polyhedral block; returns its index.

        ``options`` are those of :meth:`add_polyhedron` (velocity, angular_velocity,
        stress, name, fixed, face_joints; faces in the order of
        :func:`srdda.geometry.polyhedron.box`). Turn it with :meth:`rotate`.
        """
        try:
            vertices, faces = box(lo, hi, str(options.get("name") or f"block {len(self.blocks)}"))
        except PolyhedronError as exc:
            raise ModelError(str(exc)) from None
        return self.add_polyhedron(vertices, faces, material, **options)

    # -- placing blocks ----------------------------------------------------
    def block_masses(self) -> np.ndarray:
        """Mass (nb,) of every block, kg (per m of thickness in 2D): density × volume as built."""
        return self.arrays().block_mass

    def translate(self, offset: Sequence[float], blocks: Sequence[int | str] | None = None) -> None:
        """Move blocks (all, or ``blocks``: indices or names) by ``offset`` (m), with the points on them."""
        self._move(np.eye(self.dim), np.zeros(self.dim), np.asarray(_finite(offset, "offset")), blocks)

    def rotate(self, angle: float, about: Sequence[float] | None = None, axis: Sequence[float] | None = None,
               blocks: Sequence[int | str] | None = None) -> None:
        """Turn blocks (all, or ``blocks``: indices or names) by ``angle`` degrees about the point ``about``.

        2D: counter-clockwise about ``about`` (default the origin). 3D: right-handed
        about the line through ``about`` along ``axis`` (default z). The blocks'
        velocities, angular velocities and initial stresses turn with them; the
        fixed points, point loads, point springs and measured points on them move
        with them (a load's force keeps its direction). Hinges, springs, driven
        points and bolts are placed in the turned model: add them after turning.
        """
        theta = np.radians(_finite(angle, "angle")[0])
        if self.dim == PLANE.dim:
            c, s = np.cos(theta), np.sin(theta)
            rotation = np.array([[c, -s], [s, c]])
        else:
            k = np.asarray(_finite(axis if axis is not None else (0.0, 0.0, 1.0), "axis"))
            if k.shape != (SOLID.dim,) or not np.linalg.norm(k) > 0:
                raise ModelError(f"axis must be a non-zero [x, y, z] vector, got {k.tolist()}")
            k = k / np.linalg.norm(k)
            cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
            rotation = np.eye(SOLID.dim) + np.sin(theta) * cross + (1 - np.cos(theta)) * cross @ cross  # Rodrigues
        centre = np.zeros(self.dim) if about is None else np.asarray(_finite(about, "about"))
        if centre.shape != (self.dim,):
            raise ModelError(f"about must be a point with {self.dim} coordinates, got {centre.tolist()}")
        self._move(rotation, centre, np.zeros(self.dim), blocks)

    def _move(self, rotation: np.ndarray, centre: np.ndarray, offset: np.ndarray,
              blocks: Sequence[int | str] | None) -> None:
        """x -> R (x - centre) + centre + offset for the chosen blocks and the points on them."""
        if not self.blocks:
            raise ModelError("the model has no blocks to move")
        if offset.shape != (self.dim,):
            raise ModelError(f"offset must have {self.dim} components, got {offset.tolist()}")
        names = [b.name for b in self.blocks]
        chosen = set(range(len(self.blocks))) if blocks is None else set()
        for b in blocks or ():
            if isinstance(b, str):
                if b not in names:
                    raise ModelError(f"no block named {b!r}")
                chosen.add(names.index(b))
            elif not 0 <= int(b) < len(self.blocks):
                raise ModelError(f"no block {b} (the model has {len(self.blocks)})")
            else:
                chosen.add(int(b))
        specs: tuple[HingeSpec | SpringSpec | BoltSpec, ...] = (*self.hinges, *self.springs, *self.bolts)
        linked = [s.block_a for s in specs] + [s.block_b for s in specs] + [p.block for p in self.prescribed]
        if chosen & {b for b in linked if b is not None}:
            raise ModelError("move or turn blocks before adding hinges, springs, driven points or bolts to them")

        def at(p: np.ndarray) -> np.ndarray:
            return (np.asarray(p, dtype=float) - centre) @ rotation.T + centre + offset

        bt = block_type_of_dimension(self.dim)
        for k in chosen:
            block = self.blocks[k]
            velocity = np.asarray(block.velocity, dtype=float)
            velocity[bt.translation] = rotation @ velocity[bt.translation]
            if self.dim == SOLID.dim:
                velocity[bt.rotation] = rotation @ velocity[bt.rotation]
                stress = rotate_symmetric_components_3d(np.asarray([block.stress]), rotation[None], 1.0)[0]
            else:
                stress = rotate_symmetric_components(np.asarray([block.stress]), np.arctan2(rotation[1, 0],
                                                                                            rotation[0, 0]), 1.0)[0]
            self.blocks[k] = replace(block, vertices=at(block.vertices), velocity=tuple(velocity.tolist()),
                                     stress=tuple(stress.tolist()))
        self.fixed_points = [(b, at(p) if b in chosen else p, k) for b, p, k in self.fixed_points]
        self.point_loads = [(b, at(p) if b in chosen else p, f) for b, p, f in self.point_loads]
        self.measured_points = [(b, at(p) if b in chosen else p) for b, p in self.measured_points]
        self.point_springs = [(a, at(pa) if a in chosen else pa, b, at(pb) if b in chosen else pb, k)
                              for a, pa, b, pb, k in self.point_springs]

    # -- compiling ---------------------------------------------------------
    def arrays(self) -> ModelArrays:
        """Flat arrays of the whole model for the time loop: its block, joint and point parts."""
        if not self.blocks:
            raise ModelError("the model has no blocks")
        bt = block_type_of_dimension(self.dim)
        _finite(self.gravity, "gravity")
        if len(self.gravity) != bt.dim:
            raise ModelError(f"gravity must have {bt.dim} components in a {bt.dim}D model, got {len(self.gravity)}")
        arrays = ModelArrays(
            **self._block_arrays(bt),
            gravity=np.asarray(self.gravity, dtype=float),
            **self._joint_arrays(),
            **self._point_arrays(bt),
            water=self.water,
            stages=resolve_stages(self, self.stages) if self.stages else (),
        )
        self._check_held(arrays)
        self._check_water(arrays)
        return arrays

    def _block_arrays(self, bt: BlockType) -> dict[str, Any]:
        """The blocks' and vertices' fields of :class:`ModelArrays` (and the 3D mesh); checks 2D overlaps."""
        mats = list(self.materials.values())
        counts = [len(b.vertices) for b in self.blocks]
        block_ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        if bt is SOLID:
            elasticity = np.array([elasticity_matrix_3d(mats[b.material].young, mats[b.material].poisson)
                                   for b in self.blocks])
            mesh = PolyhedronMesh.from_blocks([(b.vertices, b.faces) for b in self.blocks],
                                              [b.name for b in self.blocks])
        else:
            elasticity = np.array([elasticity_matrix(mats[b.material]) for b in self.blocks])
            mesh = None
        velocity = np.zeros((len(self.blocks), bt.ndof))
        velocity[:, : bt.rotation.stop] = [b.velocity for b in self.blocks]
        vertices = np.concatenate([b.vertices for b in self.blocks])
        if bt is PLANE and not self.allow_overlap:
            self._check_overlaps(vertices, block_ptr)
        return dict(
            vertex_position=vertices,
            block_ptr=block_ptr,
            vertex_block=np.repeat(np.arange(len(counts)), counts),
            vertex_next=next_vertex_index(block_ptr),
            block_density=np.array([mats[b.material].density for b in self.blocks]),
            block_elasticity=elasticity,
            block_compliance=np.linalg.inv(elasticity),
            block_velocity=velocity,
            block_stress=np.array([b.stress for b in self.blocks], dtype=float),
            block_fixed=np.array([b.fixed for b in self.blocks], dtype=bool),
            block_material=np.array([b.material for b in self.blocks], dtype=np.int64),
            block_names=tuple(b.name for b in self.blocks),
            mesh=mesh,
        )

    def _joint_arrays(self) -> dict[str, Any]:
        """The joints' fields of :class:`ModelArrays`: the joint table and which row each contact takes."""
        joint_names = list(self.joint_materials)
        mat_names = list(self.materials)
        by_mats = np.zeros((len(mat_names), len(mat_names)), dtype=np.int64)
        for (a, b), name in self.joint_map.items():
            ia, ib = mat_names.index(a), mat_names.index(b)
            by_mats[ia, ib] = by_mats[ib, ia] = joint_names.index(name) + 1

        def joint_rows(named: tuple[str | None, ...] | None, n: int) -> np.ndarray:
            """Rows of the joint table named per edge or face, -1 where the block materials choose."""
            return np.full(n, -1) if named is None else np.array([-1 if j is None else joint_names.index(j) + 1
                                                                   for j in named])

        edge_joint = np.concatenate([joint_rows(b.edge_joints, len(b.vertices)) for b in self.blocks]
                                    ).astype(np.int64)
        face_joint = None if self.dim != SOLID.dim else np.concatenate(
            [joint_rows(b.face_joints, len(b.faces or ())) for b in self.blocks]).astype(np.int64)
        return dict(
            joints=JointTable.of([self.default_joint, *self.joint_materials.values()]),
            material_joint=by_mats,
            edge_joint=edge_joint,
            face_joint=face_joint,
        )

    def _point_arrays(self, bt: BlockType) -> dict[str, Any]:
        """The points' fields of :class:`ModelArrays`: the attached points and the links that use them."""
        groups: list[list[np.ndarray]] = [[], [], [], [], []]
        owners: list[list[int]] = [[], [], [], [], []]
        for b, p, _ in self.fixed_points:
            groups[0].append(p)
            owners[0].append(b)
        for b, p, _ in self.point_loads:
            groups[1].append(p)
            owners[1].append(b)
        for a, pa, b, pb, _ in self.point_springs:
            groups[2].append(pa)
            owners[2].append(a)
            groups[3].append(pb)
            owners[3].append(b)
        for b, p in self.measured_points:
            groups[4].append(p)
            owners[4].append(b)
        sizes = [len(g) for g in groups]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        rows = [np.arange(offsets[i], offsets[i + 1]) for i in range(5)]
        pts = np.array([p for g in groups for p in g], dtype=float).reshape(-1, bt.dim)
        link_pts, link_owners, links = compile_links(self.hinges, self.springs, self.prescribed,
                                                     self.base_acceleration, len(pts), bt.dim, self.bolts)
        attached = AttachedPoints(
            point_position=np.concatenate([pts, link_pts]),
            point_block=np.concatenate([np.array([o for g in owners for o in g], dtype=np.int64), link_owners]),
            fixed_rows=rows[0],
            fixed_stiffness=np.array([k for _, _, k in self.fixed_points], dtype=float),
            load_rows=rows[1],
            load_force=tuple(ld for _, _, ld in self.point_loads),
            point_spring_rows_a=rows[2],
            point_spring_rows_b=rows[3],
            point_spring_stiffness=np.array([k for *_, k in self.point_springs], dtype=float),
            measured_rows=rows[4],
        )
        return dict(attached=attached, links=links)

    def _check_water(self, arrays: ModelArrays) -> None:
        """ModelError naming a water table of another dimension or a crack on which no moving block's face lies."""
        if self.water is None:
            return
        if len(self.water.point) != arrays.vertex_position.shape[1]:
            raise ModelError(f"water: the table is {len(self.water.point)}D, the model "
                             f"{arrays.vertex_position.shape[1]}D (set the gravity before the water)")
        for i, crack in enumerate(self.water.cracks):
            try:
                crack_facets(arrays, crack)
            except ValueError as exc:
                raise ModelError(f"water.cracks[{i}]: {exc}") from None

    def _check_held(self, arrays: ModelArrays) -> None:
        """ModelError naming redundant constraints and moving blocks without mass that nothing holds."""
        redundant = redundant_constraints(arrays)
        if redundant:
            raise ModelError(f"redundant constraints: {'; '.join(redundant)} (their forces would be undetermined: "
                             "the run stops with a singular system or gives arbitrary constraint forces); remove "
                             "the repeated ones")
        free = unheld_massless_blocks(arrays)
        if free:
            mats = list(self.materials)
            names = ", ".join(f"{self.blocks[b].name!r} (material {mats[self.blocks[b].material]!r})"
                              for b in free[:5]) + (f" and {len(free) - 5} more" if len(free) > 5 else "")
            raise ModelError(f"moving blocks without mass (density 0) that nothing holds: {names}; their "
                             "equations are singular. Give the material a density, fix the block, or hold it by "
                             "fixed points, springs, hinges or pins at enough points (two in 2D, three in 3D)")


def _scale(v: np.ndarray) -> float:
    return float(np.ptp(v, axis=0).max())
