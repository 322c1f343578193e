"""The content of an existing DDA input (geometry + analysis files) and its srdda model.

:mod:`srdda.io.legacy` (Shi's text files) and :mod:`srdda.io.ddaml` (DDA for
Windows XML) both fill a :class:`DDAInput`; :meth:`DDAInput.to_model` cuts the
blocks (:func:`srdda.geometry.cutting.cut_blocks`) and maps the parameters onto
srdda's (the table is in ``docs/cutting.md``). Everything srdda does not
support is reported with ``warnings.warn`` naming it.
"""
from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from ..geometry.cutting import NO_JOINT, BlockCut, CuttingError, cut_blocks
from ..model import JointMaterial, Material, Model, ModelError
from ..settings import RunSettings

__all__ = ["DDAInput", "DDAInputError", "domain_scale"]

MERGE_FACTOR = 1.25  # DC merges intersections closer than 1.25 e00 w0 (ntdda geometry code)


class DDAInputError(ValueError):
    """An existing DDA input file is unreadable (the message names the file and the item)."""


def read_input_text(path: Path) -> str:
    """The text of an input file; an unreadable file is a :class:`DDAInputError` naming it."""
    try:
        return path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise DDAInputError(f"{path}: cannot read ({exc.strerror})") from None


def domain_scale(segments: np.ndarray) -> float:
    """Shi's drawing scale w0 of the joint lines (ntdda ``computeDomainscale``).

    Half the height of the bounding box, or half the width / 1.3 when the
    box is wider than 1.3 times its height, times 1.02. The edge-node
    distance of DDA files is a ratio to w0.
    """
    pts = np.asarray(segments, dtype=float).reshape(-1, 2)
    half_w, half_h = np.ptp(pts, axis=0) / 2.0
    w0 = half_w / 1.3 if half_w > 1.3 * half_h else half_h
    return float(w0 * 1.02)


@dataclass
class BlockMaterialSpec:
    """A DDA block material as written in the files (units as the author used)."""

    unit_mass: float
    unit_weight: float
    young: float
    poisson: float
    stress: tuple[float, float, float] = (0.0, 0.0, 0.0)
    strain: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    damping: float = 0.0


@dataclass
class DDAInput:
    """Geometry and analysis data of a DDA input, in the files' own terms."""

    source: str
    edge_node_ratio: float  # e00 (g1): edge-node distance / w0
    joints: np.ndarray  # (n, 4)
    joint_types: np.ndarray  # (n,)
    material_lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    material_line_types: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    fixed_lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))  # points: x1 = x2, y1 = y2
    load_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    measured_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    hole_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    # analysis
    dynamic: bool = True
    n_steps: int = 0
    max_displacement_ratio: float = 0.01  # g2
    max_time_step: float = 0.01
    penalty_factor: float = 50.0
    auto_time_step: bool = False
    auto_penalty: bool = False
    plane_strain: bool = False
    save_interval: int = 1
    rotation: str = "linear"
    gravity_acceleration: float | None = None  # None: unit weight / unit mass
    open_close_limit: int | None = None
    block_materials: list[BlockMaterialSpec] = field(default_factory=list)
    joint_materials: list[tuple[float, float, float]] = field(default_factory=list)  # (phi deg, c, t)
    load_histories: list[np.ndarray] = field(default_factory=list)  # (k, 3) rows (t, fx, fy)

    # -- geometry ------------------------------------------------------------
    @property
    def edge_node_distance(self) -> float:
        """Absolute merge distance of the cutting: 1.25 e00 w0, as Shi's DC."""
        return MERGE_FACTOR * self.edge_node_ratio * domain_scale(self.joints)

    def cut(self, domain_types: Sequence[int] | None = None) -> BlockCut:
        """Blocks cut from the joint lines.

        By default every closed loop is a block, as in Shi's DC (joint traces
        running past the boundary can close loops outside the rock mass).
        With ``domain_types``, the domain is the region enclosed by the joints
        of those types (e.g. ``[1]`` when type 1 draws the boundary) and only
        blocks inside it are kept.
        """
        boundary = None
        if domain_types is not None:
            chosen = np.isin(self.joint_types, np.asarray(domain_types))
            lines = shapely.linestrings(self.joints[chosen].reshape(-1, 2, 2))
            faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(shapely.unary_union(lines))))
            boundary = shapely.unary_union(faces)
            if not isinstance(boundary, shapely.Polygon) or boundary.is_empty:
                raise DDAInputError(f"{self.source}: joints of type(s) {list(domain_types)} do not enclose "
                                    "one connected region")
            boundary = shapely.Polygon(boundary.exterior)
        try:
            return cut_blocks(self.joints, self.joint_types, edge_node_distance=self.edge_node_distance,
                              boundary=boundary, boundary_type=int(domain_types[0]) if domain_types else 0,
                              hole_points=self.hole_points, material_lines=self.material_lines,
                              material_line_types=self.material_line_types, default_material=1)
        except CuttingError as exc:
            raise DDAInputError(f"{self.source}: {exc}") from None

    # -- parameters ------------------------------------------------------------
    def gravity(self) -> float:
        """Gravitational acceleration: the file's value, else unit weight / unit mass of material 1."""
        if self.gravity_acceleration is not None:
            return self.gravity_acceleration
        ratios = [m.unit_weight / m.unit_mass for m in self.block_materials if m.unit_mass > 0]
        if not ratios:
            return 0.0
        if not np.allclose(ratios, ratios[0], rtol=1e-3):
            warnings.warn(f"{self.source}: unit weight / unit mass differs between block materials "
                          f"({', '.join(f'{r:g}' for r in ratios)}); gravity taken from material 1", stacklevel=3)
        return float(ratios[0])

    def run_parameters(self) -> dict[str, Any]:
        """The file's run parameters under srdda's RunSettings names (a plain dict).

        The contact entries (``contact_penalty``, ``max_displacement_ratio``,
        ``open_close_max_iterations``) carry the names of the contact settings
        of srdda's RunSettings; a RunSettings without them is told by a warning.
        """
        young = max((m.young for m in self.block_materials), default=0.0)
        params: dict[str, Any] = {
            "method": "dda0" if self.rotation == "linear" else "dda1",
            "dt": self.max_time_step,
            "n_steps": self.n_steps,
            "penalty": self.penalty_factor * young,
            "contact_penalty": self.penalty_factor * young,
            "max_displacement_ratio": self.max_displacement_ratio,
            "record_every": max(1, self.save_interval),
            "velocity_ratio": 1.0 if self.dynamic else 0.0,  # Shi's static analysis: k01 = 0
        }
        if self.open_close_limit is not None:
            params["open_close_max_iterations"] = self.open_close_limit
        return params

    def run_settings(self) -> RunSettings:
        """RunSettings from :meth:`run_parameters`; whatever srdda cannot honour is warned about."""
        if self.auto_time_step:
            warnings.warn(f"{self.source}: automatic time step is not supported; the file's maximum time step "
                          f"{self.max_time_step:g} is the time step", stacklevel=2)
        if self.auto_penalty:
            warnings.warn(f"{self.source}: automatic penalty is not supported; the penalty is fixed at "
                          f"{self.penalty_factor:g} x the largest Young's modulus", stacklevel=2)
        params = self.run_parameters()
        known = {f.name for f in dataclasses.fields(RunSettings)}
        unused = {k: v for k, v in params.items() if k not in known}
        if unused:
            warnings.warn(f"{self.source}: contact settings not in this srdda's RunSettings (ignored): "
                          + ", ".join(f"{k}={v:g}" for k, v in unused.items()), stacklevel=2)
        try:
            return RunSettings(**{k: v for k, v in params.items() if k in known})
        except ValueError as exc:
            raise DDAInputError(f"{self.source}: run settings: {exc}") from None

    # -- model ------------------------------------------------------------------
    def to_model(self, cut: BlockCut | None = None) -> Model:
        """The srdda Model: blocks, materials, joint materials, fixed/load/measured points, gravity."""
        cut = self.cut() if cut is None else cut
        model = Model(gravity=(0.0, -self.gravity()))
        plane = "strain" if self.plane_strain else "stress"
        used = np.unique(cut.block_material)
        for k in used:
            if not 1 <= k <= len(self.block_materials):
                raise DDAInputError(f"{self.source}: blocks use material {k} but "
                                    f"{len(self.block_materials)} block material(s) are defined")
        for k, m in enumerate(self.block_materials, start=1):
            if any(m.strain):
                warnings.warn(f"{self.source}: initial strain of block material {k} is not supported "
                              "(ignored)", stacklevel=2)
            if m.damping:
                warnings.warn(f"{self.source}: damping {m.damping:g} of block material {k} is not supported "
                              "(ignored)", stacklevel=2)
            try:
                model.add_material(f"material {k}", Material(density=m.unit_mass, young=m.young,
                                                             poisson=m.poisson, plane=plane))
            except ModelError as exc:
                raise DDAInputError(f"{self.source}: block material {k}: {exc}") from None
        for k, (phi, c, t) in enumerate(self.joint_materials, start=1):
            try:
                model.add_joint_material(f"joint {k}", JointMaterial(phi, c, t))
            except ModelError as exc:
                raise DDAInputError(f"{self.source}: joint material {k}: {exc}") from None
        types = np.unique(cut.edge_joint[cut.edge_joint != NO_JOINT])
        missing = [int(t) for t in types if not 1 <= t <= len(self.joint_materials)]
        if missing:
            raise DDAInputError(f"{self.source}: joint type(s) {missing} have no joint properties "
                                f"({len(self.joint_materials)} defined)")
        names = np.array([None] + [f"joint {k}" for k in range(1, len(self.joint_materials) + 1)], dtype=object)
        for b in range(cut.n_blocks):
            verts, joints = cut.block(b)
            spec = self.block_materials[cut.block_material[b] - 1]
            model.add_block(verts, f"material {cut.block_material[b]}", velocity=spec.velocity[:2],
                            angular_velocity=spec.velocity[2], stress=spec.stress,
                            edge_joints=list(names[np.where(joints == NO_JOINT, 0, joints)]))
        self._add_points(model, cut)
        return model

    def _add_points(self, model: Model, cut: BlockCut) -> None:
        try:
            pts, blocks = cut.line_points(self.fixed_lines, "fixed point/line")
            for p, b in zip(pts, blocks):
                model.add_fixed_point(p, block=int(b))
            load_blocks = cut.locate(self.load_points, "load point")
            measured_blocks = cut.locate(self.measured_points, "measured point")
        except CuttingError as exc:
            raise DDAInputError(f"{self.source}: {exc}") from None
        if len(self.load_points) and len(self.load_histories) != len(self.load_points):
            raise DDAInputError(f"{self.source}: {len(self.load_points)} load point(s) but "
                                f"{len(self.load_histories)} load time histories")
        for p, b, table in zip(self.load_points, load_blocks, self.load_histories):
            force: object = table[0, 1:] if len(table) == 1 else table
            try:
                model.add_point_load(p, force, block=int(b))
            except ModelError as exc:
                raise DDAInputError(f"{self.source}: load point at {tuple(p)}: {exc}") from None
        for p, b in zip(self.measured_points, measured_blocks):
            model.add_measured_point(p, block=int(b))
