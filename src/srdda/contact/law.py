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

A joint with a normal restitution e_n gets, in place of Shi's normal spring,
the impact law of :func:`impact_force`: the spring's discrete gradient (no
energy lost by the step, also where the contact closes or opens inside it)
and a dashpot on the penetration whose damping ratio
(:func:`impact_damping_ratio`) makes the contact's half turn in Shi's step
rebound at e_n (docs/contacts.md, "Impacts and restitution").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..modeldata.materials import JointTable
from .openclose import LOCKED
from .record import ContactRecord

__all__ = ["ContactStiffness", "JointResponse", "ContactLaw", "MohrCoulomb", "impact_damping_ratio", "impact_force",
           "impact_potential"]


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
    restitution: np.ndarray | None = None  # normal restitution e_n (nan: none); None: no contact has one

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

    @staticmethod
    def restitution(joints: JointTable, record: ContactRecord) -> np.ndarray | None:
        """e_n per contact (nan where its joint has none), or None where no joint of the model has one."""
        if np.all(np.isnan(joints.restitution)):
            return None
        return joints.restitution[record.joint]


class MohrCoulomb(ContactLaw):
    """Friction angle φ, cohesion c and tensile strength T of the joint; c and T act over the bond while it
    holds (module doc)."""

    def response(self, joints: JointTable, record: ContactRecord, bonded: np.ndarray,
                 stiffness: ContactStiffness) -> JointResponse:
        row = record.joint
        kn, ks = self.springs(joints, record, stiffness)
        return JointResponse(kn, ks, np.tan(joints.friction_angle[row]),
                             np.where(bonded, joints.cohesion[row] * record.bond, 0.0),
                             np.where(bonded, joints.tensile_strength[row] * record.bond, 0.0),
                             self.restitution(joints, record))


BISECTIONS = 60  # halvings of ζ's interval [0, 1]: below the rounding of ζ


def impact_damping_ratio(restitution: np.ndarray, omega_dt: np.ndarray) -> np.ndarray:
    """ζ (n,) of the dashpot c = 2ζ·k/ω that makes an impact in Shi's step rebound at ``restitution`` (e_n).

    While a contact stays closed, its spring at mid-step and the dashpot on
    the mean velocity Δg/Δt make Shi's step the trapezoidal rule of the damped
    oscillator: eigenvalue λ = ω(−ζ + i√(1−ζ²)) maps to z = (1 + λΔt/2)/(1 − λΔt/2)
    per step, and the half turn (phase π) decays by exp(π·Re ln z / Im ln z).
    The ζ that makes that e_n, by bisection (the decay falls with ζ), not the
    continuous ζ = −ln e/√(π² + ln² e), which rebounds about 20 % too fast
    at e_n = 0.2, ωΔt = 0.9 (docs/contacts.md). ``omega_dt``: ωΔt of the contact.
    """
    lo, hi = np.zeros(len(restitution)), np.ones(len(restitution))
    half = 0.5 * omega_dt
    for _ in range(BISECTIONS):
        zeta = 0.5 * (lo + hi)
        a = half * (-zeta + 1j * np.sqrt(1.0 - zeta**2))
        log = np.log((1.0 + a) / (1.0 - a))
        turns = log.imag > 0.0  # a map that no longer turns gives no rebound
        decay = np.where(turns, np.exp(np.pi * log.real / np.where(turns, log.imag, 1.0)), 0.0)
        more = decay > restitution
        lo, hi = np.where(more, zeta, lo), np.where(more, hi, zeta)
    return np.where(restitution < 1.0, 0.5 * (lo + hi), 0.0)


def impact_potential(gap0: np.ndarray, gap1: np.ndarray, stiffness: np.ndarray, viscosity: np.ndarray
                     ) -> np.ndarray:
    """ψ (n,) with ∂ψ/∂g1 = −N of :func:`impact_force`, ψ = 0 at g1 = 0 (J, per m in 2D): the impact law as
    a convex potential of the end gap, for a solve that minimises the step's potential (the Newton solver).

    N's spring part is the discrete gradient −(E(g1) − E(g0))/(g1 − g0) of the
    convex E = ½k·p², which increases with g1 (secants of a convex function),
    so its integral is convex: ¼k·g1² + ½k·g0·g1 while closed at both ends,
    −½k·g0²·ln((g1 − g0)/(−g0)) opening (g0 < 0 ≤ g1), and with u = g1 − g0,
    ½k(½(u² − g0²) + 2g0(u + g0) + g0²·ln(|u|/g0)) closing (g1 < 0 ≤ g0). The
    dashpot's part is (c/Δt)(½p1² − p0·g1).
    """
    p0, p1 = np.minimum(gap0, 0.0), np.minimum(gap1, 0.0)
    closed0, closed1 = gap0 < 0.0, gap1 < 0.0
    half = 0.5 * stiffness
    both = half * (0.5 * gap1**2 + gap0 * gap1)
    u = gap1 - gap0
    opening_arg = np.where(closed0 & ~closed1, u / np.where(closed0, -gap0, 1.0), 1.0)
    opening = -half * gap0**2 * np.log(np.maximum(opening_arg, 1.0))
    g0 = np.where(closed1 & ~closed0 & (gap0 > 0.0), gap0, 1.0)
    closing_log = np.where(gap0 > 0.0, gap0**2 * np.log(np.where(closed1 & ~closed0, -u, 1.0) / g0), 0.0)
    closing = half * (0.5 * (u**2 - gap0**2) + 2.0 * gap0 * (u + gap0) + closing_log)
    spring = np.where(closed0 & closed1, both, np.where(closed0, opening, np.where(closed1, closing, 0.0)))
    return spring + viscosity * (0.5 * p1**2 - p0 * gap1)


def impact_force(gap0: np.ndarray, gap1: np.ndarray, stiffness: np.ndarray, viscosity: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The normal force N (n,) of contacts with a restitution over a step from gap g0 to g1 (N, compression
    positive) and its stiffness −∂N/∂g1 (N/m).

    With the penetration p = min(g, 0): N = −½k(p0 + p1)·Δp/Δg − (c/Δt)·Δp,
    ``viscosity`` = c/Δt. The first part is the discrete
    gradient of the spring energy ½k·p², so the spring's work over the step
    is exactly −Δ(½k·p²), closing or opening inside the step included (Shi's
    spring at the step's end loses ½k·Δg² per step); the second is the
    dashpot on the penetration, whose work −(c/Δt)·Δp·Δg is the step's loss.
    """
    p0, p1 = np.minimum(gap0, 0.0), np.minimum(gap1, 0.0)
    dg = gap1 - gap0
    closed0, closed1 = gap0 < 0.0, gap1 < 0.0
    # Δp/Δg: 1 closed at both ends, 0 open at both, between where the contact closes or opens in the step
    moving = closed0 != closed1
    share = np.where(moving, (p1 - p0) / np.where(moving, dg, 1.0), np.where(closed0, 1.0, 0.0))
    force = -0.5 * stiffness * (p0 + p1) * share - viscosity * (p1 - p0)
    safe = np.where(moving, dg, 1.0)
    spring = np.where(closed0 & closed1, 0.5 * stiffness,
                      np.where(closed1, 0.5 * stiffness * gap1 * (2.0 * dg - gap1) / safe**2,  # closing
                               np.where(closed0, 0.5 * stiffness * gap0**2 / safe**2, 0.0)))  # opening
    return force, spring + np.where(closed1, viscosity, 0.0)
