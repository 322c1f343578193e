"""The three DDA methods as presets of kinematics, time scheme and linearisation.

=========  ===============  ==================  ==============  ================
method     kinematics       time scheme         linearisation   stress update
=========  ===============  ==================  ==============  ================
dda0       linear           shi                 start           additive
dda1       exact-rotation   shi                 start           additive
srdda      exact-rotation   paper (ρ∞)          secant          objective
=========  ===============  ==================  ==============  ================

``start`` evaluates the shape function of loads, springs and constraints in
the configuration at t (Shi); ``secant`` iterates the step so that they use
T_sec at the converged rotation increment (see :mod:`srdda.kinematics.update2d`).
``objective`` rotates stresses (and strain rates) with the block: Eq. 50 in
the co-moving frame, written back in global components. In 3D srdda also
takes the rate of change of a block's rotational inertia (the gyroscopic
torque -ω × Jω, docs/theory-3d.md); dda0 and dda1 keep Shi's inertia.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal, get_args

from .schemes import TimeScheme

__all__ = ["Method", "METHODS", "MethodName", "method_preset"]

MethodName = Literal["dda0", "dda1", "srdda"]
METHODS: tuple[MethodName, ...] = get_args(MethodName)


@dataclass(frozen=True)
class Method:
    name: str
    kinematics: str  # "linear" | "exact-rotation"
    scheme: TimeScheme
    linearization: str  # "start" | "secant"
    objective_stress: bool
    gyroscopic: bool = False  # 3D: the torque -ω × Jω of a block's turning inertia (srdda.assembly.blocks)

    def __post_init__(self) -> None:
        if self.kinematics not in ("linear", "exact-rotation"):
            raise ValueError(f"kinematics must be 'linear' or 'exact-rotation', got {self.kinematics!r}")
        if self.linearization not in ("start", "secant"):
            raise ValueError(f"linearization must be 'start' or 'secant', got {self.linearization!r}")
        if self.linearization == "secant" and self.kinematics != "exact-rotation":
            raise ValueError("the secant linearization needs exact-rotation kinematics")


def method_preset(name: str, rho_inf: float = 1.0, scheme: str | None = None,
                  linearization: str | None = None) -> Method:
    """The preset ``name`` (dda0, dda1, srdda), optionally with another scheme or linearisation."""
    if name == "dda0":
        m = Method("dda0", "linear", TimeScheme("shi"), "start", False)
    elif name == "dda1":
        m = Method("dda1", "exact-rotation", TimeScheme("shi"), "start", False)
    elif name == "srdda":
        m = Method("srdda", "exact-rotation", TimeScheme("paper", rho_inf), "secant", True, gyroscopic=True)
    else:
        raise ValueError(f"method must be one of {METHODS}, got {name!r}")
    if scheme is not None:
        m = replace(m, scheme=TimeScheme(scheme, rho_inf))
    if linearization is not None:
        m = replace(m, linearization=linearization)
    return m
