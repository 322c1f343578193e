"""Models and checks shared by the contact-energy tests (issue 29): no contact puts energy in.

:func:`two_blocks_impact` is the impact of issue 29; :func:`contact_energy_excess`
measures a run against the guarantee of docs/reliability.md (*No energy from
contacts*).
"""
from __future__ import annotations

import numpy as np

import srdda
from srdda.ledger import CONTACT_LOSSES

PENALTY = 1e10  # N/m: k_n of the contact models (stiff against their blocks' weight, soft against E·1 m)


def two_blocks_impact(scheme: str | None = None, method: str = "srdda", solver: str = "open-close",
                      steps: int = 400, dt: float = 2.5e-4) -> tuple[srdda.Model, srdda.RunSettings]:
    """Two 1 m squares in a line, no gravity: one at 1 m/s strikes the other, 10.13 mm away, face on (their
    corners meet), at Δt = 0.25 ms (the first touch falls inside step 41)."""
    m = srdda.Model(gravity=(0.0, 0.0))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", velocity=(1.0, 0.0), name="striker")
    m.add_block([[1.01013, 0], [2.01013, 0], [2.01013, 1], [1.01013, 1]], "rock", name="struck")
    return m, srdda.RunSettings(dt=dt, n_steps=steps, method=method, scheme=scheme, contact_solver=solver,
                                penalty=PENALTY)


def series(result: srdda.Result, name: str) -> np.ndarray:
    """One energy (J, J per m in 2D) at every recorded step."""
    return result.array("energy")[:, list(result.energy[0]).index(name)]


def contact_energy_excess(result: srdda.Result) -> tuple[float, float]:
    """(rise, fall), both relative to the energy in play (the largest kinetic + elastic + spring + contact
    energy plus the largest change of gravitational energy): the mechanical energy's largest rise above its
    start plus the work of loads, prescribed points and constraints so far; the largest fall of
    ``dissipated_contact`` or ``dissipated_friction`` over one recorded step."""
    total = series(result, "total")
    work = series(result, "work_loads") + series(result, "work_prescribed") + series(result, "work_constraints")
    gravity = series(result, "gravity")
    stored = sum(series(result, k) for k in ("kinetic", "elastic", "spring", "contact"))
    scale = float(np.max(stored) + np.max(np.abs(gravity - gravity[0])))
    rise = float(np.max(total - work - total[0]))
    fall = max(float(np.max(-np.diff(series(result, k)), initial=0.0)) for k in CONTACT_LOSSES)
    return rise / scale, fall / scale
