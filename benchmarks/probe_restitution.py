"""The rebound speed ratio of collinear frictionless impacts (``srdda.apps.verify.cases.impacts``), before and after e_n.

Prints the tables of docs/contacts.md, "Impacts and restitution": the ratio without a restitution (Shi's
spring) per Δt and contact solver; with e_n per Δt, 2D and 3D, pair and base, at the cases' penalty
(ωΔt ≤ 0.57) and at the run's default penalty 1e9 N/m (ωΔt up to 1.8); the same with the continuous
damping ratio ζ = −ln e/√(π² + ln² e) in place of the calibrated one (the approach tried first); and at
stiffer contacts, k_n = 1e10 to 1e12 N/m (ωΔt 2.8 to 57 at 1 ms), where an impact lasts one or two steps.

    python benchmarks/probe_restitution.py
"""
from __future__ import annotations

from unittest import mock

import numpy as np

from srdda.apps.verify.cases.impacts import IMPACT_PENALTY, impact_case

STEPS = (1e-4, 2.5e-4, 5e-4, 1e-3)
RESTITUTIONS = (0.2, 0.5, 0.8, 1.0)
CASES = ((2, False, "2D pair"), (2, True, "2D base"), (3, False, "3D pair"), (3, True, "3D base"))
HEAD = "| case | " + " | ".join(f"Δt = {dt * 1e3:g} ms" for dt in STEPS) + " |"
RULE = "|---" * (len(STEPS) + 1) + "|"


def continuous(restitution: np.ndarray, omega_dt: np.ndarray) -> np.ndarray:
    """The damping ratio of the continuous spring-dashpot (no calibration to the step)."""
    log = np.log(restitution)
    return -log / np.sqrt(np.pi**2 + log**2)


def without_restitution() -> None:
    for penalty in (IMPACT_PENALTY, 1e9):
        print(f"\nWithout restitution, k_n = {penalty:g} N/m: rebound ratio (open-close / newton)\n\n{HEAD}\n{RULE}")
        for dim, base, label in CASES:
            cells = [f"{impact_case(dim, base, dt, None, penalty).ratio:.3f} / "
                     f"{impact_case(dim, base, dt, None, penalty, contact_solver='newton').ratio:.3f}"
                     for dt in STEPS]
            print(f"| {label} | " + " | ".join(cells) + " |")


def with_restitution(penalty: float, title: str) -> None:
    print(f"\n{title}, k_n = {penalty:g} N/m: ratio / e_n, largest |balance change| / kinetic energy\n\n{HEAD}\n{RULE}")
    for dim, base, label in CASES:
        for e in RESTITUTIONS:
            runs = [impact_case(dim, base, dt, e, penalty) for dt in STEPS]
            print(f"| {label}, e_n = {e} | " + " | ".join(f"{r.ratio / e:.4f} ({abs(r.balance):.0e})" for r in runs)
                  + " |")


def stiff() -> None:
    print("\nStiff contacts: ratio (none) or ratio / e_n at Δt = 0.1 ms / 1 ms\n\n"
          "| k_n (N/m) | case | none | e_n = 0.2 | e_n = 0.5 | e_n = 1 |\n|---|---|---|---|---|---|")
    for penalty in (1e10, 1e11, 1e12):
        for dim, base, label in (CASES[1], CASES[2]):
            cells = []
            for e in (None, 0.2, 0.5, 1.0):
                ratios = [impact_case(dim, base, dt, e, penalty).ratio / (1.0 if e is None else e) for dt in STEPS[::3]]
                cells.append(" / ".join(f"{r:.3f}" for r in ratios))
            print(f"| {penalty:g} | {label} | " + " | ".join(cells) + " |")


def main() -> None:
    without_restitution()
    with_restitution(IMPACT_PENALTY, "With restitution")
    with_restitution(1e9, "With restitution")
    with mock.patch("srdda.contact.impact.impact_damping_ratio", continuous):
        with_restitution(IMPACT_PENALTY, "Continuous ζ (not kept)")
        with_restitution(1e9, "Continuous ζ (not kept)")
    stiff()


if __name__ == "__main__":
    main()
