"""The impact verification cases (issue 29, item 7): the rebound speed ratio of a collinear frictionless impact
on a joint with a normal restitution e_n against e_n itself, 2D and 3D (srdda.apps.verify.cases.impacts runs them).

Each tolerance is given beside its case with what it measures (docs/verification.md).
"""
from __future__ import annotations

from .cases.impacts import impact_case
from ...integrators.methods import MethodName
from .registry import Row, case, row

__all__: list[str] = []

# Two blocks of equal mass head on, and a block on a fixed base, at e_n = 0.2, 0.5, 0.8, 1 and Δt = 0.1 and 1 ms
# (the factor of 10; --quick: 1 ms only), k_n = 1e8 N/m per contact (ωΔt ≤ 0.57).
RESTITUTIONS = (0.2, 0.5, 0.8, 1.0)
STEPS = (1e-4, 1e-3)
# The bound: the rebound ratio within 2 % of e_n. Measured: within 0.38 % (3D pair, e_n = 0.2, 1 ms).
IMPACT_RATIO = 0.02
# Every loss in the ledger: its balance moves by at most this fraction of the kinetic energy before the impact
# (measured 1.4e-4, the same with e_n = 1: the method's own drift, not the impact law).
IMPACT_BALANCE = 5e-4


def _impact_rows(name: str, dim: int, methods: tuple[MethodName, ...], quick: bool) -> list[Row]:
    rows: list[Row] = []
    for method in methods:
        drift = 0.0
        for on_base, label in ((False, "pair"), (True, "base")):
            for e in RESTITUTIONS:
                for dt in STEPS[-1:] if quick else STEPS:
                    impact = impact_case(dim, on_base, dt, e, method=method)
                    drift = max(drift, abs(impact.balance))
                    rows.append(row(name, f"rebound ratio, {label}, e_n = {e}, dt = {dt * 1e3:g} ms", method,
                                    impact.ratio, e, IMPACT_RATIO))
        rows.append(row(name, "largest balance change / kinetic energy", method, drift, 0.0, IMPACT_BALANCE))
    return rows


for _dim in (2, 3):
    def _run(methods: tuple[MethodName, ...], quick: bool, dim: int = _dim) -> list[Row]:
        return _impact_rows(f"impact-restitution-{dim}d", dim, methods, quick)

    case(f"impact-restitution-{_dim}d", dim=_dim, methods=("srdda", "dda1", "dda0"), quick=True,
         description="collinear impacts on a joint with restitution e_n rebound at e_n for dt 0.1 to 1 ms")(_run)
