"""How to run a model: the one definition of the run settings.

:class:`RunSettings` is a pydantic dataclass: the Python API builds it with
keywords, the model file's ``[run]`` table is validated into it (the file
writes ``steps`` for ``n_steps``), and the CLI replaces fields of it with
:func:`dataclasses.replace`, which validates again. Every value the run uses
is checked here, once, with a message naming the field: a time step that is
not finite or out of range, a solver that is not installed, a step-cut factor
that would never shrink the step, ``rho_inf`` with a scheme that ignores it,
both ``contact_penalty`` and ``auto_penalty``, ``min_dt`` not below ``dt``,
``device = "gpu"`` with a solver that has no GPU backend (errors; a GPU asked
for where CuPy or a CUDA device is missing is an error when the run starts,
:meth:`RunSettings.resolved_device`); contact settings with ``contacts = false``
and ``secant_max_iterations`` without the secant linearisation (warnings: they
have no effect).
Times in s, stiffnesses in N/m; a model file may write ``"2 ms"``.
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from typing import Annotated, ClassVar, Literal

from pydantic import (AfterValidator, AliasChoices, BeforeValidator, ConfigDict, Field, ValidationInfo,
                      field_validator, model_validator)
from pydantic.dataclasses import dataclass
from pydantic.fields import FieldInfo

from .integrators.methods import Method, MethodName, method_preset
from .integrators.schemes import SchemeName
from .backends.arrays import DeviceName, GPU_SOLVERS, resolve_device
from .units import reject_boolean, to_si
from .solvers import DEFAULT_TOLERANCE, available_solvers

__all__ = ["RunSettings", "ContactSolverName", "MIN_DT", "MAX_DT", "MAX_STEPS", "MAX_STEP_CUT_FACTOR"]

ContactSolverName = Literal["open-close", "newton"]  # Shi's open-close iteration, or Newton's method

# Δt bounds: Shi's coefficients use 4/Δt², finite only for Δt above ~1e-154; a step below a
# picosecond or above a million seconds is a unit mistake in every rock-mechanics model.
MIN_DT = 1e-12
MAX_DT = 1e6
MAX_STEPS = 10**12  # steps are int64 in the results file; 1e12 steps take longer than any run
# A cut must shrink Δt enough that a handful of cuts reach a stable step (0.9**22 = 0.1).
MAX_STEP_CUT_FACTOR = 0.9


def _unit(kind: str) -> BeforeValidator:
    return BeforeValidator(lambda v: v if v is None else to_si(v, kind))


def _finite(value: float | None) -> float | None:
    if value is not None and not math.isfinite(value):
        raise ValueError("must be a finite number")
    return value


def _installed(name: str) -> str:
    if name not in available_solvers():
        raise ValueError(f"solver {name!r} is not installed here (pip install srdda[{name}]); "
                         f"installed: {', '.join(available_solvers())}")
    return name


Finite = AfterValidator(_finite)
Seconds = Annotated[float, _unit("time"), Finite]
NewtonsPerMetre = Annotated[float, _unit("stiffness"), Finite]
Degrees = Annotated[float, _unit("angle"), Finite]
Metres = Annotated[float, _unit("length"), Finite]
Ratio = Annotated[float, Finite]


# the settings only the contacts use: changed with contacts = false, they have no effect
CONTACT_FIELDS = ("contact_solver", "contact_penalty", "auto_penalty", "shear_ratio", "contact_distance_factor",
                  "contact_angle_tolerance", "penetration_fraction", "open_close_max_iterations",
                  "friction_tolerance", "open_close_freeze_after", "open_close_settle_after")


@dataclass(frozen=True, config=ConfigDict(extra="forbid", populate_by_name=True))
class RunSettings:
    """How to run a model (SI). Give ``n_steps``, ``end_time`` or both (the run stops at the first)."""

    __pydantic_fields__: ClassVar[dict[str, FieldInfo]]  # set by pydantic's dataclass
    dt: Annotated[Seconds, Field(ge=MIN_DT, le=MAX_DT)]
    n_steps: Annotated[int | None, Field(ge=0, le=MAX_STEPS,
                                         validation_alias=AliasChoices("n_steps", "steps"))] = None
    end_time: Annotated[Seconds | None, Field(gt=0)] = None
    method: MethodName = "srdda"
    rho_inf: Annotated[Ratio, Field(ge=0, le=1)] = 1.0
    scheme: SchemeName | None = None  # override the method's time scheme
    linearization: Literal["start", "secant"] | None = None  # override the method's linearisation
    penalty: Annotated[NewtonsPerMetre, Field(gt=0)] = 1e9  # default stiffness of fixed points (N/m)
    solver: Annotated[str, AfterValidator(_installed)] = "auto"  # a name of available_solvers()
    # the iterative backends (cg-amg, cg-jacobi; auto above ITERATIVE_LIMIT blocks) stop when every unknown
    # of the increment is estimated within this of the exact solution (m): docs/performance.md
    solver_tolerance: Annotated[Metres, Field(gt=0, le=1.0)] = DEFAULT_TOLERANCE
    # where the conjugate gradient runs: "cpu", "gpu" (CuPy and a CUDA GPU, srdda[gpu]) or "auto" (the GPU for
    # models of GPU_MIN_UNKNOWNS unknowns or more when one is present; docs/gpu.md)
    device: DeviceName = "auto"
    # The secant pass stops when |Δθ|·|δθ| (δθ: change of the rotation increment between two solves)
    # is below this: the mismatch between the linearised and the exact rotation displacement of a
    # point, per metre of lever arm, is about half of it.
    secant_tolerance: Annotated[Ratio, Field(gt=0)] = 1e-13
    secant_max_iterations: Annotated[int, Field(ge=1)] = 8
    # Shi's dynamic ratio k01: velocities and accelerations are multiplied by it after every
    # step. 1 = dynamic; 0 = Shi's static analysis (each step starts at rest).
    velocity_ratio: Annotated[Ratio, Field(ge=0, le=1)] = 1.0
    record_every: Annotated[int, Field(ge=1)] = 1
    # contacts and step control (docs/contacts.md); lengths relative to w0 = half the model height
    contacts: bool = True  # detect and resolve block contacts
    # how a step's contact problem is solved: Shi's open-close iteration, or Newton's method with a line search on
    # the step's incremental potential (docs/contacts.md, "The contact solve")
    contact_solver: ContactSolverName = "open-close"
    contact_penalty: Annotated[NewtonsPerMetre | None, Field(gt=0)] = None  # k_n (N/m); None: ``penalty``
    auto_penalty: Annotated[Ratio | None, Field(gt=0)] = None  # k_n = this × the largest Young's modulus × 1 m
    shear_ratio: Annotated[Ratio, Field(gt=0)] = 0.4  # k_s / k_n
    max_displacement_ratio: Annotated[Ratio, Field(gt=0)] = 0.01  # g2: largest vertex displacement / w0
    contact_distance_factor: Annotated[Ratio, Field(gt=0)] = 2.5  # d0 = factor × g2 × w0
    contact_angle_tolerance: Annotated[Degrees, Field(ge=0, lt=45)] = 3.0  # Shi's angle criterion
    penetration_fraction: Annotated[Ratio, Field(gt=0)] = 0.4  # a step deeper than this × d0 is cut
    open_close_max_iterations: Annotated[int, Field(ge=1)] = 40  # state-changing solves before a cut (docs/contacts.md)
    # Newton's solves of a step before it is cut: a safeguard only (its iteration converges; docs/contacts.md)
    newton_max_iterations: Annotated[int, Field(ge=1)] = 100
    friction_tolerance: Annotated[Ratio, Field(gt=0)] = 1e-3  # relative settling of a sliding normal force
    open_close_tolerance: Annotated[Ratio, Field(ge=0, le=1e-3)] = 2e-7  # Shi's f0: open-close lengths / w0
    open_close_force_tolerance: Annotated[Ratio, Field(ge=0, le=1e-2)] = 1e-4  # negligible state change / block force
    open_close_freeze_after: Annotated[int, Field(ge=1)] = 2  # state changes of one contact before it is held
    open_close_settle_after: Annotated[int, Field(ge=1)] = 4  # solves after which contacts may only settle
    step_cut_factor: Annotated[Ratio, Field(gt=0, le=MAX_STEP_CUT_FACTOR)] = 1.0 / 3.0  # Δt ← factor·Δt
    min_dt: Annotated[Seconds | None, Field(gt=0)] = None  # the run stops below this; None: 1e-6 × dt

    @field_validator("*", mode="before")
    @classmethod
    def _no_boolean(cls, value: object, info: ValidationInfo) -> object:
        assert info.field_name is not None  # a field validator's info names its field
        return reject_boolean(value, cls.__pydantic_fields__[info.field_name].annotation)

    @model_validator(mode="after")
    def _consistent(self) -> RunSettings:
        if self.n_steps is None and self.end_time is None:
            raise ValueError("give n_steps (steps in a model file) or end_time")
        method = self.resolved_method()
        if method.scheme.name == "shi" and self.rho_inf != 1.0:
            raise ValueError(f"rho_inf = {self.rho_inf} has no effect with the 'shi' time scheme (method "
                             f"{self.method!r}, scheme {method.scheme.name!r}); set rho_inf = 1, or use scheme "
                             "'paper' or 'chung-hulbert'")
        if self.device == "gpu" and self.solver not in GPU_SOLVERS:
            raise ValueError(f"device = 'gpu' runs the block-Jacobi conjugate gradient on the GPU, and solver "
                             f"{self.solver!r} has none: choose solver {' or '.join(map(repr, GPU_SOLVERS))}, "
                             "or device 'cpu'")
        if self.contact_penalty is not None and self.auto_penalty is not None:
            raise ValueError(f"give contact_penalty ({self.contact_penalty:g} N/m) or auto_penalty "
                             f"({self.auto_penalty:g} × the largest Young's modulus), not both")
        if self.min_dt is not None and self.min_dt >= self.dt:
            raise ValueError(f"min_dt = {self.min_dt:g} s must be below dt = {self.dt:g} s (the run stops "
                             "when a cut step falls below min_dt)")
        defaults = {f.name: f.default for f in dataclasses.fields(RunSettings)}
        if not self.contacts:
            unused = [n for n in CONTACT_FIELDS if getattr(self, n) != defaults[n]]
            if unused:
                warnings.warn(f"contacts = false: {', '.join(unused)} {'has' if len(unused) == 1 else 'have'} "
                              "no effect", UserWarning, stacklevel=2)
        if method.linearization != "secant" and self.secant_max_iterations != defaults["secant_max_iterations"]:
            warnings.warn(f"secant_max_iterations has no effect with method {self.method!r} (linearisation "
                          f"{method.linearization!r}; srdda's secant pass uses it)", UserWarning, stacklevel=2)
        return self

    def resolved_method(self) -> Method:
        """The method preset with this run's scheme and linearisation overrides."""
        return method_preset(self.method, self.rho_inf, self.scheme, self.linearization)

    def resolved_device(self, unknowns: int) -> str:
        """Where the linear solves of a model of ``unknowns`` unknowns (blocks × ndof) run: "cpu" or "gpu"
        (``device`` resolved).

        Raises :class:`~srdda.backends.arrays.GpuUnavailable` (a ValueError naming the field) for
        ``device = "gpu"`` where CuPy or a CUDA device is missing: checked when a run starts, not here,
        so that the settings stored with a GPU run's results still read on a machine without one.
        """
        return resolve_device(self.device, self.solver, unknowns)

    @property
    def last_step_limit(self) -> float:
        """The step count at which the run stops (infinite when only ``end_time`` is given)."""
        return math.inf if self.n_steps is None else float(self.n_steps)

