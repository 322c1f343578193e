"""Collinear frictionless impacts, 2D and 3D: the rebound speed ratio and where the energy went.

Two blocks of equal mass meet head on at 1 m/s each (or one block hits a fixed
base at 1 m/s), without gravity or friction, the joint with or without a
normal restitution e_n. A block is 1 m wide (a 1 m square, a 1 m cube); the
other is twice as tall (and, in 3D, as deep) and as much less dense: the same
mass, its face wider than the hitting one, so that each block's contacts are
its own corners on the other's face (two equal aligned squares in 2D meet
corner to corner, where a vertex-vertex contact is born already deep in the
other block and creates energy whatever the joint law: docs/contacts.md,
"Impacts and restitution"). The rebound ratio is the relative normal speed
after over before, e_n for an ideal impact law, whatever Δt.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from srdda.integrators.methods import MethodName
from srdda.model import JointMaterial, Material, Model
from srdda.settings import RunSettings, ContactSolverName
from srdda.simulation import run

__all__ = ["impact_model", "ImpactRun", "impact_case", "IMPACT_PENALTY"]

DENSITY, APPROACH, GAP = 2500.0, 1.0, 0.002  # kg/m³; m/s per block; m between the faces at the start
IMPACT_PENALTY = 1e8  # N/m per contact: ωΔt ≤ 0.57 at Δt = 1 ms (2 contacts in 2D, 4 in 3D, m* = 1250 kg)
DURATION = 0.02  # s: the faces meet after 1 ms (2 ms on a base), the contact lasts π/ω ≤ 11 ms


def impact_model(dim: int, on_base: bool, restitution: float | None = None) -> Model:
    """Block ``hit`` (moving −x, 1 m wide) and the taller ``other`` (moving +x, or fixed: the base)."""
    m = Model(gravity=(0.0,) * dim)
    m.add_material("rock", Material(DENSITY, 1e12, 0.25))  # stiff: the impact's energy stays out of the strain
    m.add_material("light", Material(DENSITY / 2 ** (dim - 1), 1e12, 0.25))  # twice as tall (and deep)
    m.add_joint_material("joint", JointMaterial(restitution=restitution), between=[("rock", "rock"),
                                                                                  ("rock", "light")])
    other = 0.0 if on_base else APPROACH
    if dim == 2:
        m.add_block([[-1.0, -0.5], [0.0, -0.5], [0.0, 1.5], [-1.0, 1.5]], "light", velocity=(other, 0.0),
                    fixed=on_base, name="other")
        m.add_block([[GAP, 0.0], [GAP + 1.0, 0.0], [GAP + 1.0, 1.0], [GAP, 1.0]], "rock",
                    velocity=(-APPROACH, 0.0), name="hit")
    else:
        m.add_box([-1.0, -0.5, -0.5], [0.0, 1.5, 1.5], "light", velocity=(other, 0.0, 0.0), fixed=on_base,
                  name="other")
        m.add_box([GAP, 0.0, 0.0], [GAP + 1.0, 1.0, 1.0], "rock", velocity=(-APPROACH, 0.0, 0.0), name="hit")
    return m


@dataclass(frozen=True)
class ImpactRun:
    """What one impact measured; energies as fractions of the kinetic energy before it."""

    ratio: float  # relative normal speed after / before
    kinetic_lost: float  # 1 − the kinetic energy after
    dissipated_impact: float  # the ledger's dissipated_impact (joints with a restitution)
    dissipated_contact: float  # the ledger's dissipated_contact (Shi's springs)
    balance: float  # the change of the ledger's balance (0: every loss booked)


def impact_case(dim: int, on_base: bool, dt: float, restitution: float | None = None,
                penalty: float = IMPACT_PENALTY, method: MethodName = "srdda",
                contact_solver: ContactSolverName = "open-close") -> ImpactRun:
    """Run the impact for :data:`DURATION` at ``dt`` and measure it (the blocks have parted by then)."""
    settings = RunSettings(dt=dt, n_steps=int(round(DURATION / dt)), method=method, contact_penalty=penalty,
                           contact_solver=contact_solver)
    result = run(impact_model(dim, on_base, restitution), settings)
    if not result.completed:
        raise RuntimeError(f"impact run did not complete ({result.status})")
    if result.closed_contacts[-1] != 0:
        raise RuntimeError(f"the blocks are still in contact after {DURATION} s")
    v = result.array("velocity")[:, :, 0]  # x velocity of each block (other, hit)
    first, last = result.energy[0], result.energy[-1]
    before = first["kinetic"]

    def share(key: str) -> float:
        return float((last[key] - first[key]) / before)

    return ImpactRun(float((v[-1, 1] - v[-1, 0]) / (v[0, 0] - v[0, 1])), -share("kinetic"),
                     share("dissipated_impact"), share("dissipated_contact"), share("balance"))
