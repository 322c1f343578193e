"""The model's materials: block materials, joint materials and the joint table, and the model's error.

They are data that the builder (:class:`srdda.model.Model`), the stages and the contact law name; they live
below the terms so that those can name them without importing the builder (docs/architecture.md).
:mod:`srdda.model` re-exports them.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

__all__ = ["ModelError", "PlaneKind", "Material", "JointMaterial", "JointTable", "elasticity_matrix"]


class ModelError(ValueError):
    """The model is inconsistent (the message names the item and the problem)."""


PlaneKind = Literal["stress", "strain"]  # a 2D model's plane stress or plane strain


@dataclass(frozen=True)
class Material:
    """Block material. ``density`` kg/m³, ``young`` Pa, ``poisson`` (-), 2D idealisation."""

    density: float
    young: float
    poisson: float
    plane: PlaneKind = "stress"

    def __post_init__(self) -> None:
        if not 0 <= self.density < np.inf:
            raise ModelError(f"material density must be finite and >= 0, got {self.density}")
        if not 0 < self.young < np.inf:
            raise ModelError(f"material young must be finite and > 0, got {self.young}")
        upper = 0.5 if self.plane == "stress" else 0.5
        if not -1.0 < self.poisson < upper:
            raise ModelError(f"material poisson must lie in (-1, 0.5), got {self.poisson}")
        if self.plane not in ("stress", "strain"):
            raise ModelError(f"material plane must be 'stress' or 'strain', got {self.plane!r}")


@dataclass(frozen=True)
class JointMaterial:
    """Mohr-Coulomb joint: friction angle (degrees), cohesion (Pa), tensile strength (Pa), and optionally
    its normal and shear stiffness per unit area (Pa/m, as UDEC's and 3DEC's joint kn and ks), and optionally
    its normal restitution e_n in (0, 1]: the ratio of rebound to approach speed of an impact on the joint.

    Without stiffnesses a contact on the joint takes the run's contact penalty
    (``contact_penalty``, N/m per contact: per metre of thickness in 2D), the
    shear stiffness ``shear_ratio`` × that; with them, a contact's springs are
    the joint's stiffness × the joint area it stands for (docs/contacts.md,
    "Contact stiffness"). A shear stiffness needs a normal one. Without a
    restitution an impact loses what the time step makes it lose (Shi's
    spring, docs/contacts.md, "Impacts and restitution").
    """

    friction_angle: float = 0.0
    cohesion: float = 0.0
    tensile_strength: float = 0.0
    normal_stiffness: float | None = None
    shear_stiffness: float | None = None
    restitution: float | None = None

    def __post_init__(self) -> None:
        if not 0.0 <= self.friction_angle < 90.0:
            raise ModelError(f"joint friction_angle must lie in [0, 90) degrees, got {self.friction_angle}")
        if not 0 <= self.cohesion < np.inf:
            raise ModelError(f"joint cohesion must be finite and >= 0, got {self.cohesion}")
        if not 0 <= self.tensile_strength < np.inf:
            raise ModelError(f"joint tensile_strength must be finite and >= 0, got {self.tensile_strength}")
        for name in ("normal_stiffness", "shear_stiffness"):
            value = getattr(self, name)
            if value is not None and not 0 < value < np.inf:
                raise ModelError(f"joint {name} must be finite and > 0 (Pa/m), got {value}")
        if self.shear_stiffness is not None and self.normal_stiffness is None:
            raise ModelError("joint shear_stiffness needs a normal_stiffness (Pa/m) too")
        if self.restitution is not None and not 0.0 < self.restitution <= 1.0:
            raise ModelError(f"joint restitution must lie in (0, 1], got {self.restitution}")


@dataclass(frozen=True)
class JointTable:
    """The model's joint materials as arrays, one row per joint (row 0: the default joint)."""

    friction_angle: np.ndarray  # (nj,) rad
    cohesion: np.ndarray  # (nj,) Pa
    tensile_strength: np.ndarray  # (nj,) Pa
    normal_stiffness: np.ndarray  # (nj,) Pa/m; nan: the run's contact penalty
    shear_stiffness: np.ndarray  # (nj,) Pa/m; nan: shear_ratio × the normal stiffness
    restitution: np.ndarray  # (nj,) normal restitution e_n; nan: none (Shi's spring)

    @classmethod
    def of(cls, joints: Sequence[JointMaterial]) -> JointTable:
        def column(name: str) -> np.ndarray:
            return np.array([np.nan if getattr(j, name) is None else getattr(j, name) for j in joints], dtype=float)

        return cls(np.radians([j.friction_angle for j in joints]), column("cohesion"), column("tensile_strength"),
                   column("normal_stiffness"), column("shear_stiffness"), column("restitution"))


def elasticity_matrix(mat: Material) -> np.ndarray:
    """D relating (σx, σy, τxy) to (εx, εy, γxy), plane stress or plane strain."""
    E, nu = mat.young, mat.poisson
    if mat.plane == "stress":
        c = E / (1 - nu * nu)
        return c * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    c = E / ((1 + nu) * (1 - 2 * nu))
    return c * np.array([[1 - nu, nu, 0], [nu, 1 - nu, 0], [0, 0, (1 - 2 * nu) / 2]])
