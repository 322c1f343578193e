"""Schema of the srdda model file (TOML), validated with pydantic.

Every table forbids unknown keys, so a misspelt field is an error that names
it. Quantities marked with a unit kind accept a number (SI) or "value unit".
See docs/model-file.md for the format with an example.
"""
from __future__ import annotations

from typing import Annotated, Literal

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, ValidationInfo, field_validator

from ..settings import RunSettings
from ..units import reject_boolean, to_si

__all__ = ["ModelFile", "MaterialSection", "BlockSection", "PointRef", "FixedPointSection",
           "PointLoadSection", "PointSpringSection", "MeasuredPointSection", "JointMaterialSection",
           "HingeSection", "PinSection", "SpringSection", "HistorySection", "PrescribedMotionSection",
           "BaseAccelerationSection", "BoltSection", "WaterSection", "CrackSection",
           "CuttingSection", "CutDomainSection", "JointSetSection", "JointSection", "StageSection"]


def _unit(kind: str) -> BeforeValidator:
    return BeforeValidator(lambda v: to_si(v, kind))


Pressure = Annotated[float, _unit("pressure")]
Stiffness = Annotated[float, _unit("stiffness")]
JointStiffness = Annotated[float, _unit("joint stiffness")]
Density = Annotated[float, _unit("density")]
Time = Annotated[float, _unit("time")]
Angle = Annotated[float, _unit("angle")]
Length = Annotated[float, _unit("length")]
Point = tuple[float, float] | tuple[float, float, float]  # [x, y] in 2D, [x, y, z] in 3D


def _strictly_increasing(rows: list[tuple[float, float, float]]) -> list[tuple[float, float, float]]:
    if any(b[0] <= a[0] for a, b in zip(rows, rows[1:])):
        raise ValueError("table times must increase strictly")
    return rows


Table = Annotated[list[tuple[Time, float, float]], AfterValidator(_strictly_increasing)]  # rows [t, x, y]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    @field_validator("*", mode="before")
    @classmethod
    def _no_boolean(cls, value: object, info: ValidationInfo) -> object:
        assert info.field_name is not None  # a field validator's info names its field
        return reject_boolean(value, cls.model_fields[info.field_name].annotation)


class MaterialSection(_Strict):
    density: Density = Field(ge=0)
    young: Pressure = Field(gt=0)
    poisson: float = Field(gt=-1, lt=0.5)
    plane: Literal["stress", "strain"] = "stress"


class JointMaterialSection(_Strict):
    friction_angle: Angle = Field(0.0, ge=0, lt=90)
    cohesion: Pressure = Field(0.0, ge=0)
    tensile_strength: Pressure = Field(0.0, ge=0)
    normal_stiffness: JointStiffness | None = Field(None, gt=0)  # Pa/m; None: the run's contact penalty
    shear_stiffness: JointStiffness | None = Field(None, gt=0)  # Pa/m; None: shear_ratio × the normal one
    restitution: float | None = Field(None, gt=0, le=1)  # e_n; None: Shi's spring (docs/contacts.md)
    between: list[tuple[str, str]] = []


class BlockSection(_Strict):
    """A polygon (``vertices``), or a polyhedron (``vertices`` with ``faces``, or ``box``)."""

    name: str | None = None
    material: str
    vertices: list[Point] | None = Field(None, min_length=3)
    faces: list[list[int]] | None = None  # 3D: vertex indices of each face (any orientation)
    box: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None  # 3D: [lo, hi] corners
    velocity: Point | None = None  # default zero
    angular_velocity: float | tuple[float, float, float] = 0.0  # rad/s: ω in 2D, [ωx, ωy, ωz] in 3D
    stress: tuple[Pressure, Pressure, Pressure] | tuple[Pressure, Pressure, Pressure, Pressure, Pressure, Pressure] \
        = (0.0, 0.0, 0.0)  # (σx, σy, τxy) in 2D, (σx, σy, σz, τyz, τzx, τxy) in 3D
    fixed: bool = False
    edge_joints: list[str] | None = None  # joint material per edge; "" = chosen by block materials


class PointRef(_Strict):
    at: Point
    block: str | int | None = None


class FixedPointSection(PointRef):
    stiffness: Stiffness | None = Field(None, gt=0)


class PointLoadSection(PointRef):
    force: Point | None = None
    table: Table | None = None


class PointSpringSection(_Strict):
    a: Point
    b: Point
    block_a: str | int | None = None
    block_b: str | int | None = None
    stiffness: Stiffness = Field(gt=0)


class MeasuredPointSection(PointRef):
    pass


class HingeSection(_Strict):
    """Point ``at`` of block_a kept exactly on point ``at_b`` (default ``at``) of block_b."""

    at: Point
    at_b: Point | None = None
    block_a: str | int | None = None
    block_b: str | int | None = None
    correct_drift: bool = True
    name: str = ""


class PinSection(PointRef):
    """A block point pinned exactly to the ground (Lagrange multipliers)."""

    correct_drift: bool = True
    name: str = ""


class SpringSection(PointSpringSection):
    """A linear spring with optional dashpot between two block points (srdda.constraints.springs)."""

    rest_length: float | None = Field(None, ge=0)
    damping: float = Field(0.0, ge=0)  # N·s/m
    kind: Literal["axial", "offset"] = "axial"


class HistorySection(_Strict):
    """A time history: exactly one of constant [x, y], table [[t, x, y], ...], or sine (amplitude, period)."""

    constant: Point | None = None
    table: Table | None = None
    amplitude: Point | None = None
    period: Time | None = Field(None, gt=0)
    phase: float = 0.0  # rad


class PrescribedMotionSection(PointRef):
    """A driven block point: displacement (m, from its start) or velocity (m/s) history."""

    history: HistorySection
    quantity: Literal["displacement", "velocity", "acceleration"] = "displacement"
    components: Literal["x", "y", "z", "xy", "xz", "yz", "xyz"] | None = None  # default: every axis
    by: Literal["multiplier", "penalty"] = "multiplier"
    stiffness: Stiffness | None = Field(None, gt=0)


class BaseAccelerationSection(HistorySection):
    """Ground acceleration (m/s²): a history, or an earthquake record file (srdda.io.records)."""

    record: str | None = None  # an .AT2 or .csv file, relative to the model file's folder
    format: Literal["at2", "csv"] | None = None  # default: by the file's extension
    units: Literal["g", "m/s2", "cm/s2"] | None = None  # default: .AT2 header's (g), m/s2 for CSV
    scale: float = 1.0
    baseline: Literal["none", "mean", "linear", "quadratic"] = "none"
    components: Literal["x", "y", "z", "xy", "xz", "yz", "xyz"] | None = None  # axes of the record's columns


class BoltSection(_Strict):
    """A rock bolt from point ``a`` of block_a to point ``b`` of block_b or the ground (srdda.constraints.bolts)."""

    a: Point
    b: Point
    block_a: str | int | None = None
    block_b: str | int | None = None  # "ground": b is fixed in space
    stiffness: Stiffness = Field(gt=0)  # axial, N/m
    pretension: float = Field(0.0, ge=0)  # N
    strength: float | None = Field(None, gt=0)  # tensile strength, N; None: never breaks
    shear_stiffness: Stiffness = Field(0.0, ge=0)  # N/m across the bolt
    name: str = ""


class CrackSection(_Strict):
    """A tension crack: the plane (2D: line) through ``point`` with ``normal``, water ``depth`` m deep above its
    bottom (srdda.constraints.water)."""

    point: Point
    normal: Point
    depth: Length = Field(ge=0)


class WaterSection(_Strict):
    """The water in the joints (docs/water.md): a horizontal ``level``, or a plane through ``point`` with the
    upward ``normal``; the unit weight γ_w (N/m³) and the tension cracks."""

    level: Length | None = None  # m, elevation against gravity (y in 2D, z in 3D)
    point: Point | None = None
    normal: Point | None = None
    unit_weight: float = Field(9810.0, gt=0)  # N/m³
    cracks: list[CrackSection] = []


Point3 = tuple[float, float, float]


class CutDomainSection(_Strict):
    """One convex part of the domain cut into 3D blocks: a ``box``, or ``vertices`` (with ``faces``, or their hull)."""

    material: str
    box: tuple[Point3, Point3] | None = None
    vertices: list[Point3] | None = Field(None, min_length=4)
    faces: list[list[int]] | None = None
    fixed: bool = False


class JointSetSection(_Strict):
    """A joint set (srdda.geometry.jointsets3d.JointSet3D): dip / dip direction, spacing, scatter, persistence."""

    dip: Angle = Field(ge=0, le=90)
    dip_direction: Angle
    spacing: Length = Field(gt=0)
    kappa: float | None = Field(None, gt=0)
    persistence: float = Field(1.0, gt=0, le=1)
    radius: Length | None = Field(None, gt=0)
    origin: Point3 = (0.0, 0.0, 0.0)
    spacing_sd: Length = Field(0.0, ge=0)
    joint_type: int = 1
    joint_material: str | None = None  # a name of [joint_materials] for the faces this set makes


class JointSection(_Strict):
    """One joint plane through ``point``, or a disc centred there with ``radius``."""

    point: Point3
    dip: Angle = Field(ge=0, le=90)
    dip_direction: Angle
    radius: Length | None = Field(None, gt=0)
    joint_type: int = 1
    joint_material: str | None = None  # a name of [joint_materials] for the faces this joint makes


class CuttingSection(_Strict):
    """3D blocks cut from a convex domain (or convex parts) by joint sets and joints (srdda.geometry.cutting3d)."""

    domain: list[CutDomainSection] = Field(min_length=1)
    joint_sets: list[JointSetSection] = []
    joints: list[JointSection] = []
    seed: int = 0
    min_volume: float = Field(0.0, ge=0)  # m³
    min_thickness: Length = Field(0.0, ge=0)
    fixed_box: tuple[Point3, Point3] | None = None  # blocks whose centroid lies in this box are fixed


class StageSection(_Strict):
    """One stage of a staged analysis (srdda.stages.Stage): its kind and what changes at its start."""

    name: str = Field(min_length=1)
    kind: Literal["equilibrium", "dynamic"] = "dynamic"
    remove_blocks: list[str] = []  # names or shell patterns ("tunnel*")
    install_bolts: list[str] = []  # names of [[bolts]]: inactive until this stage
    fix_blocks: list[str] = []
    free_blocks: list[str] = []
    base_acceleration: BaseAccelerationSection | None = None  # its time 0 is the stage's start
    materials: dict[str, MaterialSection] = {}  # new properties of named materials
    joint_materials: dict[str, JointMaterialSection] = {}  # new properties of named joint materials
    run: dict[str, object] = {}  # [run] fields for this stage; steps and end_time count from its start
    tolerance: float = Field(1e-5, gt=0)  # an equilibrium stage: the unbalanced-force ratio to reach
    max_steps: int = Field(20000, ge=1)  # an equilibrium stage: the most steps it takes
    reset_displacements: bool = False
    water_level: Length | None = None  # the phreatic surface moved to this elevation (docs/water.md)


class ModelFile(_Strict):
    """The whole model file."""

    title: str = ""
    units: Literal["SI"] = "SI"
    gravity: Point = (0.0, 0.0)
    allow_overlap: bool = False  # accept blocks that overlap at the start (their contacts push them apart)
    run: RunSettings  # the run settings (srdda.settings), validated where they are defined
    materials: dict[str, MaterialSection] = Field(min_length=1)
    joint_materials: dict[str, JointMaterialSection] = {}
    blocks: list[BlockSection] = []  # at least one block here or from [cutting]
    cutting: CuttingSection | None = None
    fixed_points: list[FixedPointSection] = []
    point_loads: list[PointLoadSection] = []
    point_springs: list[PointSpringSection] = []
    measured_points: list[MeasuredPointSection] = []
    hinges: list[HingeSection] = []
    pins: list[PinSection] = []
    springs: list[SpringSection] = []
    prescribed_motion: list[PrescribedMotionSection] = []
    base_acceleration: BaseAccelerationSection | None = None
    bolts: list[BoltSection] = []
    water: WaterSection | None = None
    stages: list[StageSection] = []
