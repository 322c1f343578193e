"""The ensemble spec (TOML): a base model, sampled parameters, the stop rule and the collectors.

Validated with pydantic like the model file: every table forbids unknown keys,
and :func:`load_spec` reports every problem in one :class:`SpecError` whose
lines name the field (``parameters[2].std: ...``). The format, field by field,
is in docs/ensembles.md.
"""
from __future__ import annotations

import math
from typing import Annotated, Any, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, model_validator


__all__ = ["SpecError", "EnsembleSpec", "Parameter", "Collector", "StopRule", "SHORTCUTS"]


class SpecError(ValueError):
    """An ensemble spec is unreadable or invalid; the message names the field."""


# Named shortcuts: what each one sets and which reference it needs (docs/ensembles.md).
BlockShortcut = Literal["release_dx", "release_dy", "release_dz", "velocity_x", "velocity_y", "velocity_z",
                        "angular_velocity", "angular_velocity_x", "angular_velocity_y", "angular_velocity_z",
                        "scale", "aspect"]
Shortcut = Literal[BlockShortcut, "density", "friction", "stiffness"]
BLOCK_SHORTCUTS: tuple[BlockShortcut, ...] = get_args(BlockShortcut)
SHORTCUTS: tuple[Shortcut, ...] = (*BLOCK_SHORTCUTS, "density", "friction", "stiffness")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class _Parameter(_Strict):
    """A sampled value: a column of runs.parquet, set in each run's model by ``path`` or ``shortcut``."""

    name: str = Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")
    path: str | None = None  # a model-file field, e.g. "blocks.stone.velocity[0]" or "run.contact_penalty"
    shortcut: Shortcut | None = None
    block: str | int | None = None  # block shortcuts: the block (default: the spec's tracked block)
    material: str | None = None  # "density": the material
    joint: str | None = None  # "friction": the joint material

    @model_validator(mode="after")
    def _target(self) -> _Parameter:
        if (self.path is None) == (self.shortcut is None):
            raise ValueError("give exactly one of 'path' (a model field) or 'shortcut'")
        if self.shortcut == "density" and self.material is None:
            raise ValueError("the 'density' shortcut needs 'material' (a material of the base model)")
        if self.shortcut == "friction" and self.joint is None:
            raise ValueError("the 'friction' shortcut needs 'joint' (a joint material of the base model)")
        return self


class Uniform(_Parameter):
    distribution: Literal["uniform"]
    low: float
    high: float

    @model_validator(mode="after")
    def _ordered(self) -> Uniform:
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low <= self.high):
            raise ValueError(f"need finite low <= high, got low = {self.low}, high = {self.high}")
        return self


class Normal(_Parameter):
    distribution: Literal["normal"]
    mean: float = Field(allow_inf_nan=False)
    std: float = Field(ge=0, allow_inf_nan=False)


class LogNormal(_Parameter):
    """Log-normal with the given mean and standard deviation of the value itself (not of its log)."""

    distribution: Literal["lognormal"]
    mean: float = Field(gt=0, allow_inf_nan=False)
    std: float = Field(ge=0, allow_inf_nan=False)


class Choice(_Parameter):
    distribution: Literal["choice"]
    values: list[float] = Field(min_length=1)
    weights: list[Annotated[float, Field(ge=0, allow_inf_nan=False)]] | None = None

    @model_validator(mode="after")
    def _weights(self) -> Choice:
        if self.weights is not None and (len(self.weights) != len(self.values) or sum(self.weights) <= 0):
            raise ValueError(f"weights need one non-negative number per value ({len(self.values)}) and a "
                             "positive sum")
        return self


Parameter = Annotated[Uniform | Normal | LogNormal | Choice, Field(discriminator="distribution")]


class Collector(_Strict):
    """A line (2D) or plane (3D) through ``at`` with unit ``normal``; crossed when a block moves along it."""

    name: str
    at: list[float] = Field(min_length=2, max_length=3)
    normal: list[float] = Field(min_length=2, max_length=3)

    @model_validator(mode="after")
    def _normal(self) -> Collector:
        if len(self.at) != len(self.normal):
            raise ValueError("'at' and 'normal' need the same dimension")
        if not math.isfinite(sum(x * x for x in self.normal)) or sum(x * x for x in self.normal) == 0:
            raise ValueError("'normal' must be a finite non-zero vector")
        return self


class StopRule(_Strict):
    """When a run ends: its end time, or every movable block at rest or out of the domain."""

    end_time: float | None = Field(None, gt=0, allow_inf_nan=False)  # s; default: the base model's
    rest_speed: float = Field(0.05, gt=0, allow_inf_nan=False)  # m/s: |v| + |ω|·r below this is at rest
    rest_duration: float = Field(0.25, ge=0, allow_inf_nan=False)  # s: rest held this long ends the run
    domain: tuple[list[float], list[float]] | None = None  # [[lo...], [hi...]]: a centroid outside is out

    @model_validator(mode="after")
    def _domain(self) -> StopRule:
        if self.domain is not None:
            lo, hi = self.domain
            if len(lo) != len(hi) or len(lo) not in (2, 3) or any(a >= b for a, b in zip(lo, hi)):
                raise ValueError("domain is [[x0, y0(, z0)], [x1, y1(, z1)]] with x0 < x1, y0 < y1 (z0 < z1)")
        return self


class EnsembleSpec(_Strict):
    """The whole spec file; ``model`` is resolved relative to the spec's folder."""

    title: str = ""
    model: str
    runs: int = Field(ge=1, le=10_000_000)
    seed: int = Field(ge=0)
    block: str | int | None = None  # the tracked block (runout, energy, collectors); default: the one movable
    parameters: list[Parameter] = []
    stop: StopRule = StopRule()
    stations: list[float] = []  # vertical collectors x = station, crossed in +x (downhill)
    collectors: list[Collector] = []
    trajectory_interval: float = Field(0.05, gt=0, allow_inf_nan=False)  # s between stored trajectory points

    @model_validator(mode="after")
    def _unique(self) -> EnsembleSpec:
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ValueError(f"parameter names must be unique, got {names}")
        collectors = [f"x={x:g}" for x in self.stations] + [c.name for c in self.collectors]
        if len(set(collectors)) != len(collectors):
            raise ValueError(f"collector names must be unique, got {collectors}")
        return self

    def all_collectors(self, dim: int) -> list[Collector]:
        """The stations as collectors (normal +x) in a ``dim``-D model, then the explicit collectors."""
        pad = [0.0] * (dim - 1)
        return [Collector(name=f"x={x:g}", at=[x, *pad], normal=[1.0, *pad]) for x in self.stations] \
            + list(self.collectors)
