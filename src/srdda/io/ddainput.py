"""The content of an existing DDA input (geometry + analysis files) and its srdda model.

:mod:`srdda.io.legacy` (Shi's text files) and :mod:`srdda.io.ddaml` (DDA for
Windows XML) both fill a :class:`DDAInput` in the file's own units;
:meth:`DDAInput.in_si` converts it to SI, :meth:`DDAInput.use_default_analysis`
fills what a missing analysis file would give, :meth:`DDAInput.to_model` cuts the
blocks (:func:`srdda.geometry.cutting2d.cut_blocks`) and maps the parameters onto
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

from ..geometry.cutting2d import NO_JOINT, BlockCut, CuttingError, cut_blocks
from ..model import JointMaterial, Material, Model, ModelError, PlaneKind
from ..settings import RunSettings
from ..units import UNIT_SYSTEMS, UnitSystem, detect_unit_system

__all__ = ["DDAInput", "DDAInputError", "domain_scale", "DEFAULT_ANALYSIS"]

MERGE_FACTOR = 1.25  # DC merges intersections closer than 1.25 e00 w0 (ntdda geometry code)


class DDAInputError(ValueError):
    """An existing DDA input file is unreadable (the message names the file and the item)."""


# The analysis of a geometry converted without its analysis file (SI; docs/cutting.md): a generic
# hard rock, joints with friction only, a dynamic run of 1 s under srdda; edit the written model file.
DEFAULT_ANALYSIS: dict[str, Any] = {
    "density": 2600.0,  # kg/m3, every block material
    "gravity": 9.81,  # m/s2 (unit weight = density x gravity)
    "young": 10e9,  # Pa
    "poisson": 0.25,  # plane stress, as DDA without <Planestrain>
    "friction_angle": 30.0,  # degrees, every joint type; no cohesion, no tensile strength
    "method": "srdda",
    "dt": 1e-3,  # s
    "steps": 1000,
    "max_displacement_ratio": 0.01,  # g2
    "penalty_factor": 50.0,  # penalty = 50 x E, as DDA for Windows
}


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
    """A DDA block material as written in the files (units as the author used, until :meth:`DDAInput.in_si`)."""

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
    method: str | None = None  # srdda's method; None: from ``rotation`` (the file's choice)
    notes: list[str] = field(default_factory=list)  # how the input was read (unit conversion, defaults)

    # -- units -----------------------------------------------------------------
    def in_si(self, units: str = "auto") -> DDAInput:
        """A copy in SI units, converted from ``units`` (a name of ``UNIT_SYSTEMS``, or "auto").

        "auto" takes the system whose standard gravity the file's gravity is
        (9.81 → SI, 32.2 → ft-lbf-slug, 386 → in-lbf); a file without gravity
        is taken as SI. A gravity that matches no system is an error asking
        for ``units``. The conversion is stated in :attr:`notes`.
        """
        g = self.gravity()
        if units == "auto":
            system, how = self._detect_units(g)
        elif units in UNIT_SYSTEMS:
            system, how = UNIT_SYSTEMS[units], f"{units} as given"
        else:
            raise DDAInputError(f"{self.source}: unknown units {units!r}; choose auto or one of "
                                + ", ".join(UNIT_SYSTEMS))
        out = self._scaled(system)
        if system.name == "SI":
            out.notes.append(f"units: {how} (m, kg, s, N, Pa): numbers kept as written")
        else:
            out.notes += [f"units: {how} ({system.units}); converted to SI:",
                          f"  length x {system.length:.6g} m, time x {system.time:.6g} s, "
                          f"force x {system.force:.6g} N, stress and moduli x {system.pressure:.6g} Pa,",
                          f"  unit mass x {system.density:.6g} kg/m3, unit weight x {system.unit_weight:.6g} N/m3"
                          + (f", gravity {g:.6g} -> {g * system.acceleration:.6g} m/s2" if g else "")]
        return out

    def _detect_units(self, g: float) -> tuple[UnitSystem, str]:
        if g == 0.0:
            return UNIT_SYSTEMS["SI"], "no gravity in the files to tell them, taken as SI"
        system = detect_unit_system(g)
        if system is None:
            raise DDAInputError(f"{self.source}: gravity {g:g} (unit weight / unit mass) is standard gravity in "
                                "none of the unit systems " + ", ".join(
                                    f"{s.name} ({s.gravity:.4g})" for s in UNIT_SYSTEMS.values())
                                + "; give the file's units (srdda convert --units)")
        if system.name == "SI" and any(0 < m.unit_mass < 100 for m in self.block_materials):
            warnings.warn(f"{self.source}: unit mass {min(m.unit_mass for m in self.block_materials):g} is small "
                          "for kg/m3; if the file is in kN, m and t, give --units kN-m-t", stacklevel=3)
        return system, f"gravity {g:g} is standard gravity in {system.name}"

    def _scaled(self, u: UnitSystem) -> DDAInput:
        """A copy with every dimensional number multiplied by its SI factor in ``u``."""
        def material(m: BlockMaterialSpec) -> BlockMaterialSpec:
            return dataclasses.replace(
                m, unit_mass=m.unit_mass * u.density, unit_weight=m.unit_weight * u.unit_weight,
                young=m.young * u.pressure,
                stress=(m.stress[0] * u.pressure, m.stress[1] * u.pressure, m.stress[2] * u.pressure),
                velocity=(m.velocity[0] * u.velocity, m.velocity[1] * u.velocity, m.velocity[2] / u.time))

        return dataclasses.replace(
            self, joints=self.joints * u.length, material_lines=self.material_lines * u.length,
            fixed_lines=self.fixed_lines * u.length, load_points=self.load_points * u.length,
            measured_points=self.measured_points * u.length, hole_points=self.hole_points * u.length,
            max_time_step=self.max_time_step * u.time,
            gravity_acceleration=None if self.gravity_acceleration is None
            else self.gravity_acceleration * u.acceleration,
            block_materials=[material(m) for m in self.block_materials],
            joint_materials=[(phi, c * u.pressure, t * u.pressure) for phi, c, t in self.joint_materials],
            load_histories=[h * np.array([u.time, u.force, u.force]) for h in self.load_histories],
            notes=list(self.notes))

    # -- analysis defaults ----------------------------------------------------------
    def use_default_analysis(self) -> None:
        """Fill the analysis of a geometry read without its analysis file with :data:`DEFAULT_ANALYSIS` (SI).

        Every block material number the material lines use and every joint
        type get the default material; the defaults are listed in :attr:`notes`.
        """
        d = DEFAULT_ANALYSIS
        n_block = int(max(self.material_line_types, default=1))
        n_joint = int(max(self.joint_types, default=1))
        self.block_materials = [BlockMaterialSpec(unit_mass=d["density"], unit_weight=d["density"] * d["gravity"],
                                                  young=d["young"], poisson=d["poisson"])
                                for _ in range(n_block)]
        self.joint_materials = [(d["friction_angle"], 0.0, 0.0)] * n_joint
        self.dynamic, self.method = True, d["method"]
        self.n_steps, self.max_time_step = d["steps"], d["dt"]
        self.max_displacement_ratio, self.penalty_factor = d["max_displacement_ratio"], d["penalty_factor"]
        self.auto_time_step = self.auto_penalty = False
        if len(self.load_points):
            warnings.warn(f"{self.source}: {len(self.load_points)} load point(s) without the analysis file's "
                          "force histories are ignored", stacklevel=2)
            self.load_points = np.zeros((0, 2))
        self.notes += [
            "no analysis file: the default analysis (docs/cutting.md):",
            f"  every block material: density {d['density']:g} kg/m3, E {d['young']:g} Pa, poisson "
            f"{d['poisson']:g}, plane stress; gravity {d['gravity']:g} m/s2; every joint type: friction "
            f"{d['friction_angle']:g} deg, no cohesion, no tension;",
            f"  method {d['method']}, dt {d['dt']:g} s, {d['steps']} steps, g2 {d['max_displacement_ratio']:g}, "
            f"penalty {d['penalty_factor']:g} x E"]

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
            "method": self.method or ("dda0" if self.rotation == "linear" else "dda1"),
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
        plane: PlaneKind = "strain" if self.plane_strain else "stress"
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
