"""The energy ledger: stored energies and the work that enters or leaves.

Balance (J per metre of thickness in 2D):

    E(t) = kinetic + gravitational + elastic strain + springs and penalties + contacts
    E(t) - E(0) = W_loads + W_prescribed + W_constraints + W_water + W_stages - D_dashpots - D_friction
                  - D_contact - D_springs - D_impact - D_damping - D_numerical

Every term reports its stored energy (:attr:`srdda.term.Term.energy_kind`)
and its work per step (:meth:`srdda.term.Term.work`):
W_loads: point loads and the base-acceleration body force, Σ F(t_load)·Δx with
Δx the exact displacement; W_prescribed: the drivers of prescribed points,
-μ·Δx for multiplier rows and -p·g_mid·Δx_target for penalty drivers;
W_constraints: hinge and pin forces, -μ·(Δx_a - Δx_b), zero for an exactly
kept constraint (srdda, dda0), not for dda1's post-adjustment; D_dashpots
(``dissipated``): c|Δx_rel|²/Δt per step; D_friction (``dissipated_friction``):
the work the sliding contacts' Coulomb forces took out, -Σ F·Δs with F the
friction force of the step's last solve and Δs the slip of the contact vertex
along the edge over the step (:meth:`srdda.contact.pipeline.ContactStep.work`);
D_contact (``dissipated_contact``) and D_springs (``dissipated_springs``): the
work the contact penalty springs and the springs (fixed points, point springs,
springs) did on the blocks with their step force -k(g + c_p·Δg), minus the
change of their stored energy: ½k|Δg|² per step with c_p = 1 (DDA's impact
loss at contacts), plus what state changes or a point update other than T·Δd
(dda1) put in or took out (:meth:`srdda.constraints.springs.SpringTerm.work`);
the contacts' change of stored energy counts from what the step's springs hold
at the gaps detected at t (:meth:`srdda.contact.pipeline.ContactStep.start_energy`).
D_impact (``dissipated_impact``): the same for the normal springs of joints
with a restitution e_n (:mod:`srdda.contact.impact`), whose step loses no
energy to the spring: their dashpot's loss, the impacts' (1 − e_n²).
D_damping (``dissipated_damping``): the kinetic energy the velocities' scaling
by ``velocity_ratio`` < 1 takes out after each step, (1 − r²)·½v*ᵀMv* of the
scheme's velocity v* (the damped steps of an equilibrium stage and of
:func:`srdda.simulation.settle`; all of it in Shi's static mode, r = 0).
W_stages (``work_stages``): what a stage's start changes in the stored energy
(:func:`srdda.staging.run_stages`: blocks removed with their kinetic,
gravitational, strain and contact energy, a material changed under its stress,
bolts installed with their pretension, the velocities reset), booked as put in.
Neither ``dissipated_contact`` nor ``dissipated_friction`` ever falls over a
step (:class:`EnergyWatch` warns when one does).
D_numerical is what is left: the time scheme's and the linearisation's own
dissipation or drift (among it the change from the contact energy a step
committed, at gaps moved by the linearised increments, to that at the next
step's detected gaps), so ``balance`` = E - W_loads - W_prescribed -
W_constraints - W_water - W_stages + D_dashpots + D_friction + D_contact + D_springs + D_impact + D_damping
stays at E(0) when it is zero.

The gravitational energy is -Σ m g·c over every block, fixed ones included
(their share is a constant): only its changes have a meaning. The report
(:func:`srdda.apps.plotting.fig_energy_ledger`) draws it from the initial centroid
heights of the moving blocks.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .energy_names import ENERGY_KINDS, ENERGY_NAMES, LEDGER

if TYPE_CHECKING:
    from .modeldata.arrays import ModelArrays
    from .state import State
    from .term import Term

__all__ = ["ENERGY_NAMES", "energies", "energy_in_play", "EnergyWatch", "CREATION_TOLERANCE",
           "DISSIPATION_ROUNDING", "CONTACT_LOSSES"]


def energies(terms: Sequence[Term], arrays: ModelArrays, state: State) -> dict[str, float]:
    """Every stored energy, their total, the cumulative work of the ledger and the balance."""
    out = dict.fromkeys(ENERGY_KINDS, 0.0)
    for term in terms:
        if term.energy_kind is not None:
            out[term.energy_kind] += term.energy(arrays, state)
    out["total"] = sum(out[k] for k in ENERGY_KINDS)
    out.update(zip(LEDGER, map(float, state.ledger)))
    out["balance"] = out["total"] - out["work_loads"] - out["work_prescribed"] - out["work_constraints"] \
        - out["work_water"] - out["work_stages"] \
        + out["dissipated"] + out["dissipated_friction"] + out["dissipated_contact"] \
        + out["dissipated_springs"] + out["dissipated_impact"] + out["dissipated_damping"]
    return out


def energy_in_play(energy: Mapping[str, Any], start: Mapping[str, float]) -> Any:
    """The energy in play, the scale a balance error is measured against (J per m in 2D, J in 3D).

    Kinetic, elastic, spring and contact energy, the change of gravitational
    energy since ``start`` and every work of the ledger done since then; the
    entries of ``energy`` are numbers (one state) or arrays (recorded steps).
    """
    return energy["kinetic"] + energy["elastic"] + energy["spring"] + energy["contact"] \
        + abs(energy["gravity"] - start["gravity"]) + sum(abs(energy[k] - start[k]) for k in LEDGER)


# Energy created beyond this fraction of the energy in play is reported (docs/reliability.md):
# far above the methods' own drift (srdda and dda1 ~1e-14, dda0 3e-4 of a rockfall's energy),
# far below a contact that creates energy (1.5x to 4x measured before issue 15).
CREATION_TOLERANCE = 0.01
# What contacts take out never decreases over a step (docs/reliability.md): a fall of more than this fraction of
# the energy in play is energy a contact put in. The contact sums round at about 1e-13 of it (a gap is a
# difference of coordinates 1e4 times larger; measured 2e-13 on two blocks' impact), a contact that creates
# energy gives 1e-2 and more (½k_n g² of one impact: 0.5 of it under Chung-Hulbert before issue 29).
DISSIPATION_ROUNDING = 1e-9
# the ledger's entries that never decrease: what contacts take out
CONTACT_LOSSES = ("dissipated_contact", "dissipated_friction", "dissipated_impact")
NAMED_BLOCKS = 3  # blocks a warning names
CONTACT_ADVICE = "Check the contact penalty and the time step (docs/contacts.md)"
# dda1 moves the points after the solve by the exact rotation (Shi's T, post-adjusted): a contact's vertex leaves
# the gap its springs were solved for, and the springs found at the next step hold energy from nothing (the
# paper's rockfall under dda1: 297 J, 1.8 % of the energy in play, at its first impact)
POINT_UPDATE_ADVICE = ("Under dda1 the points are moved after the solve by the exact rotation, off the gaps the "
                       "contact springs were solved for (docs/reliability.md); srdda's secant solve keeps them")


class EnergyWatch:
    """Spots energy created in a run: the ledger's balance rising above its start, or what the contacts took
    out (:data:`CONTACT_LOSSES`) falling over a step.

    The scale is the largest energy in play so far: kinetic, elastic, spring and
    contact energy, the change of gravitational energy and the work done on the
    model. :meth:`check` gives each warning once: the balance's naming the step
    and the blocks whose kinetic energy rose most in it, the fall's naming the
    step and the ledger entry.
    """

    def __init__(self, start: Mapping[str, float], tolerance: float = CREATION_TOLERANCE,
                 advice: str = CONTACT_ADVICE) -> None:
        """``advice``: what the balance's warning tells the user to look at (the method's own cause, if any)."""
        self.start = dict(start)
        self.advice = advice
        self.last = {k: start[k] for k in CONTACT_LOSSES}  # the contacts' losses after the last step
        self.tolerance = tolerance
        self.scale = 0.0
        self.warned = False
        self.warned_fall = False

    def check(self, energy: Mapping[str, float], arrays: ModelArrays, before: State, after: State) -> list[str]:
        """The warnings for the step from ``before`` to ``after`` (energies ``energy`` at ``after``)."""
        self.scale = max(self.scale, energy_in_play(energy, self.start))
        out = [w for w in (self._fall(energy, after), self._created(energy, arrays, before, after)) if w is not None]
        self.last = {k: energy[k] for k in CONTACT_LOSSES}
        return out

    def _fall(self, energy: Mapping[str, float], after: State) -> str | None:
        """The warning for a contact loss that fell over the step by more than the rounding, or None."""
        fall = {k: self.last[k] - energy[k] for k in CONTACT_LOSSES}
        name = max(fall, key=lambda k: fall[k])
        if self.warned_fall or fall[name] <= DISSIPATION_ROUNDING * self.scale:
            return None
        self.warned_fall = True
        return (f"energy created by contacts: at step {after.step} (t = {after.time:.6g} s) the ledger's {name} "
                f"fell by {fall[name]:.3g} J, {fall[name] / self.scale:.3g} of the energy in play (contacts only "
                "take energy out; docs/reliability.md)")

    def _created(self, energy: Mapping[str, float], arrays: ModelArrays, before: State, after: State) -> str | None:
        """The warning for the balance risen above its start by more than the tolerance, or None."""
        created = energy["balance"] - self.start["balance"]
        if self.warned or self.scale <= 0.0 or created <= self.tolerance * self.scale:
            return None
        self.warned = True
        gained = _translational_energy(arrays, after) - _translational_energy(arrays, before)
        top = np.argsort(gained)[::-1][:NAMED_BLOCKS]
        names = ", ".join(str(arrays.block_names[i]) for i in top if gained[i] > 0) or "none"
        return (f"energy created: at step {after.step} (t = {after.time:.6g} s) the energy balance is "
                f"{created:.3g} J above its start, {created / self.scale:.1%} of the energy in play; "
                f"blocks that gained most kinetic energy in that step: {names}. {self.advice}")


def _translational_energy(arrays: ModelArrays, state: State) -> np.ndarray:
    """½ m |v|² of every block (rotation and strain rates left out: enough to name the culprits)."""
    v = state.velocity[:, arrays.block_type.translation]
    return 0.5 * arrays.block_mass * np.einsum("ni,ni->n", v, v)
