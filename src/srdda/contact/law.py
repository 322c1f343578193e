"""Contact laws: how a joint between two blocks responds, whatever the dimension.

A law turns the joint of each contact (a row of the model's
:class:`~srdda.model.JointTable`) and the contact's geometry (its bond and
tributary sizes, :class:`~srdda.contact.record.ContactRecord`) into a
:class:`JointResponse`: the normal and shear spring stiffnesses, the shear
strength as a function of the compression, the tension a closed contact
carries before it opens, and which contacts keep their bond after a step.
The open-close rules (:mod:`.openclose`) and the contact step
(:mod:`.pipeline`) use nothing else of the joint, so a law is added without
touching them (docs/architecture.md shows one).

:class:`MohrCoulomb` is the law of srdda's joints (Shi 1988): strength
N·tan φ + c·A, tension T·A while the joint is bonded (A its bond length or
area), a bond lost for good once the contact opens or slides.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import JointTable
from .openclose import LOCKED
from .record import ContactRecord

__all__ = ["ContactStiffness", "JointResponse", "ContactLaw", "MohrCoulomb"]


@dataclass(frozen=True)
class ContactStiffness:
    """The run's contact springs k_n, k_s (N/m per contact; per metre of thickness in 2D)."""

    normal: float
    shear: float

    @property
    def shear_ratio(self) -> float:
        return self.shear / self.normal


@dataclass(frozen=True)
class JointResponse:
    """Per contact: springs, and the Mohr-Coulomb-like envelope of a law (n,) each (N/m, N)."""

    normal_stiffness: np.ndarray  # k_n
    shear_stiffness: np.ndarray  # k_s
    friction: np.ndarray  # shear strength gained per newton of compression (tan φ)
    cohesion: np.ndarray  # shear strength at zero compression (N)
    tension: np.ndarray  # tension a closed contact carries before it opens (N)

    def strength(self, compression: np.ndarray) -> np.ndarray:
        """Shear strength (n,) of contacts under ``compression`` (N, ≥ 0)."""
        return compression * self.friction + self.cohesion


class ContactLaw:
    """How joints respond (module doc); subclasses give :meth:`response`."""

    def response(self, joints: JointTable, record: ContactRecord, bonded: np.ndarray,
                 stiffness: ContactStiffness) -> JointResponse:
        """The response of every contact of ``record`` (``bonded``: contacts whose bond still holds)."""
        raise NotImplementedError

    def keeps_bond(self, bonded: np.ndarray, state: np.ndarray) -> np.ndarray:
        """Which contacts are still bonded after a step that ended in ``state``: those that stayed locked."""
        return bonded & (state == LOCKED)

    @staticmethod
    def springs(joints: JointTable, record: ContactRecord, stiffness: ContactStiffness
                ) -> tuple[np.ndarray, np.ndarray]:
        """(k_n, k_s) per contact: the joint's stiffness per area × the contact's tributary size where the
        joint gives one, else the run's contact stiffness (docs/contacts.md, "Contact stiffness")."""
        normal = joints.normal_stiffness[record.joint]
        shear = joints.shear_stiffness[record.joint]
        own = ~np.isnan(normal)
        kn = np.where(own, normal * record.tributary, stiffness.normal)
        ks = np.where(own, np.where(np.isnan(shear), stiffness.shear_ratio * normal, shear) * record.tributary,
                      stiffness.shear)
        return kn, ks


class MohrCoulomb(ContactLaw):
    """Friction angle φ, cohesion c and tensile strength T of the joint; c and T act over the bond while it
    holds (module doc)."""

    def response(self, joints: JointTable, record: ContactRecord, bonded: np.ndarray,
                 stiffness: ContactStiffness) -> JointResponse:
        row = record.joint
        kn, ks = self.springs(joints, record, stiffness)
        return JointResponse(kn, ks, np.tan(joints.friction_angle[row]),
                             np.where(bonded, joints.cohesion[row] * record.bond, 0.0),
                             np.where(bonded, joints.tensile_strength[row] * record.bond, 0.0))
