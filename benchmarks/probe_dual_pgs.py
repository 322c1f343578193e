"""Formulation (b) of the contact solve, measured: the step's problem in the contact forces, by projected
Gauss-Seidel, against Newton (a) and Shi's open-close on the same steps of the bench models.

A probe, not the engine: it runs a bench model under open-close to a moving state, then takes its next step
three ways:

* open-close (the default solver): solves and time of the step;
* Newton on the Tresca problem, N* of the yield forces held at the contacts' normal forces at the step's
  start (``srdda.apps.bench.formulations.held_tresca_step``): solves, time, its increments x_N;
* the same Tresca problem in its dual: with A block-diagonal (inertia, elasticity and loads couple no two
  blocks; fixed blocks have A⁻¹ = 0) the increments are x = A⁻¹(F + Gᵀλ), G the contacts' rows [n·T; e·T],
  and the forces λ minimise ½λᵀ(W + C)λ + bᵀλ over λ_n ≥ −T, |λ_t| ≤ τ, with W = c_p G A⁻¹ Gᵀ, C = diag(1/k_n,
  1/k_s), b = [g_0; s_0] + c_p G A⁻¹F. Projected Gauss-Seidel takes the contacts one by one (normal force, then
  shear forces with the step 1/λ_max of their block of W + C, projected on the disk of radius τ), updating the
  two blocks' x as it goes, until a sweep changes no force by more than the negligible force (1e-4 of the
  blocks' weight, the runs' ``open_close_force_tolerance``). Cold: λ = 0; warm: λ = the forces the contacts
  ended the last step with.

Prints, per model: contacts, open-close solves and ms, Newton solves and ms, PGS sweeps and ms cold and warm,
and the distance between the PGS and Newton increments relative to Newton's.

    python benchmarks/probe_dual_pgs.py [model ...]     (slope_a slope_b slope_c wall_10k slope3d_1k)
"""
from __future__ import annotations

import sys
import time
from dataclasses import replace

import numpy as np
from numba import njit

from srdda import simulation
from srdda.apps.bench.formulations import held_tresca_step
from srdda.apps.bench.runner import CASES
from srdda.contact.newton import NewtonContactModel
from srdda.contact.openclose import negligible_force
from srdda.contact.record import match_previous
from srdda.solvers import get_solver
from srdda.step import Stepper

WARM_STEPS = {"slope_a": 40, "slope_b": 40, "slope_c": 20, "wall_10k": 3, "slope3d_1k": 2}


@njit(cache=True)
def _sweeps(block_a, block_b, rows_a, rows_b, minv, x, lam, start, stiffness, tau, tension, c_p, limit,
            max_sweeps):
    """Projected Gauss-Seidel over the contacts until a sweep changes no force by more than ``limit``;
    returns the sweeps made. rows_*: (n, 1 + k, ndof); lam, start, stiffness: (n, 1 + k)."""
    n, m, ndof = rows_a.shape
    # each contact's block of W + C and the step of its shear forces (1/λ_max of that block)
    diag = np.zeros((n, m, m))
    for c in range(n):
        a, b = block_a[c], block_b[c]
        for i in range(m):
            for j in range(m):
                sa = 0.0
                sb = 0.0
                for p in range(ndof):
                    for q in range(ndof):
                        sa += rows_a[c, i, p] * minv[a, p, q] * rows_a[c, j, q]
                        sb += rows_b[c, i, p] * minv[b, p, q] * rows_b[c, j, q]
                diag[c, i, j] = c_p * (sa + sb)
            diag[c, i, i] += 1.0 / stiffness[c, i]
    shear_step = np.zeros(n)
    for c in range(n):
        shear_step[c] = 1.0 / np.linalg.eigvalsh(diag[c, 1:, 1:]).max()
    w = np.zeros(m)
    for sweep in range(1, max_sweeps + 1):
        largest = 0.0
        for c in range(n):
            a, b = block_a[c], block_b[c]
            for part in range(2):  # the normal force, then the shear forces
                lo, hi = (0, 1) if part == 0 else (1, m)
                for i in range(lo, hi):
                    s = 0.0
                    for p in range(ndof):
                        s += rows_a[c, i, p] * x[a, p] - rows_b[c, i, p] * x[b, p]
                    w[i] = start[c, i] + c_p * s + lam[c, i] / stiffness[c, i]
                old = lam[c].copy()
                if part == 0:
                    lam[c, 0] = max(-tension[c], lam[c, 0] - w[0] / diag[c, 0, 0])
                else:
                    size = 0.0
                    for i in range(1, m):
                        lam[c, i] -= shear_step[c] * w[i]
                        size += lam[c, i] ** 2
                    size = np.sqrt(size)
                    if size > tau[c]:
                        for i in range(1, m):
                            lam[c, i] *= tau[c] / size
                for i in range(lo, hi):
                    d = lam[c, i] - old[i]
                    if d != 0.0:
                        largest = max(largest, abs(d) / limit[c])
                        for p in range(ndof):
                            ua = 0.0
                            ub = 0.0
                            for q in range(ndof):
                                ua += minv[a, p, q] * rows_a[c, i, q]
                                ub += minv[b, p, q] * rows_b[c, i, q]
                            x[a, p] += d * ua
                            x[b, p] -= d * ub
        if largest <= 1.0:
            return sweep
    return max_sweeps


def probe(name: str) -> dict[str, float]:
    case = CASES[name]
    model, settings = case.build()
    arrays = model.arrays()
    settings = replace(settings, n_steps=WARM_STEPS[name], contact_solver="open-close", open_close_max_iterations=200)
    state = simulation.run(arrays, settings, keep_vertices=False).final_state
    dt = settings.dt
    # open-close: the step as runs take it
    stepper = Stepper(arrays, settings, get_solver(settings.solver))
    start = time.perf_counter()
    outcome = stepper.step(state, dt)
    open_close = (outcome.solves, time.perf_counter() - start, outcome.status)
    # Newton on the Tresca problem, N* the contacts' normal forces at the step's start
    newton_run = replace(settings, contact_solver="newton")
    starts: dict[str, np.ndarray] = {}

    def normal_star(n: int) -> np.ndarray:
        return starts["normal"]

    original = NewtonContactModel.start

    def start_hook(self, record, previous, old, bonded, response, normal_force):  # N* held at the start's forces
        starts["normal"] = normal_force.copy()
        return original(self, record, previous, old, bonded, response, normal_force)

    NewtonContactModel.start = start_hook
    try:
        got = held_tresca_step(arrays, newton_run, normal_star, state, solver=settings.solver)
    finally:
        NewtonContactModel.start = original
    assert got is not None, "the Newton step was not accepted"
    step, others, c_p = got.step, got.others, got.c_p
    assert not others.pair_i and not others.con_rhs, "the other terms couple blocks: no block-diagonal A"
    fixed = arrays.block_fixed
    minv = np.zeros_like(others.diag)
    minv[~fixed] = np.linalg.inv(others.diag[~fixed])
    springs = step._springs
    assert springs is not None
    rows_a = np.concatenate([springs.normal_a[:, None, :], springs.shear_a], axis=1)
    rows_b = np.concatenate([springs.normal_b[:, None, :], springs.shear_b], axis=1)
    r = step.record
    start_values = np.concatenate([r.gap[:, None], step.shear0], axis=1)
    stiffness = np.concatenate([step.response.normal_stiffness[:, None],
                                np.repeat(step.response.shear_stiffness[:, None], r.frame_width, axis=1)], axis=1)
    tau = step.yield_force()
    limit = negligible_force(arrays.block_mass, arrays.gravity, r.block_a, r.block_b, starts["normal"],
                             settings.open_close_force_tolerance)
    free = minv @ others.rhs[..., None]
    previous = state.contacts
    warm = np.zeros_like(start_values)
    if previous is not None:
        old = match_previous(r.key, previous.key)
        kept = old >= 0
        warm[kept, 0] = previous.normal_force[old[kept]]
        warm[kept, 1:] = previous.shear_force[old[kept]]
    out = {"contacts": len(r.gap), "open_close_solves": open_close[0], "open_close_ms": 1e3 * open_close[1],
           "newton_solves": got.solves, "newton_ms": 1e3 * got.seconds}
    args = (r.block_a, r.block_b, rows_a, rows_b, minv)
    _sweeps(*args, free[..., 0].copy(), np.zeros_like(warm), start_values, stiffness, tau,
            step.response.tension, c_p, limit, 1)  # compile
    for label, lam0 in (("cold", np.zeros_like(warm)), ("warm", warm)):
        lam = lam0.copy()
        x = free[..., 0].copy()
        for c in range(len(lam)):  # x = A⁻¹(F + Gᵀλ)
            x[r.block_a[c]] += minv[r.block_a[c]] @ (rows_a[c].T @ lam[c])
            x[r.block_b[c]] -= minv[r.block_b[c]] @ (rows_b[c].T @ lam[c])
        t0 = time.perf_counter()
        sweeps = _sweeps(*args, x, lam, start_values, stiffness, tau, step.response.tension, c_p, limit, 20000)
        out[f"pgs_{label}_sweeps"] = sweeps
        out[f"pgs_{label}_ms"] = 1e3 * (time.perf_counter() - t0)
        out[f"pgs_{label}_error"] = float(np.linalg.norm(x.ravel() - got.increments)
                                          / np.linalg.norm(got.increments))
    return out


def main() -> None:
    names = sys.argv[1:] or list(WARM_STEPS)
    print("| model | contacts | open-close solves | open-close ms | Newton solves | Newton ms | PGS sweeps cold "
          "| cold ms | ‖x − x_N‖/‖x_N‖ cold | PGS sweeps warm | warm ms | ‖x − x_N‖/‖x_N‖ warm |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        o = probe(name)
        print(f"| {name} | {o['contacts']} | {o['open_close_solves']} | {o['open_close_ms']:.0f} "
              f"| {o['newton_solves']} | {o['newton_ms']:.0f} | {o['pgs_cold_sweeps']} | {o['pgs_cold_ms']:.0f} "
              f"| {o['pgs_cold_error']:.1e} | {o['pgs_warm_sweeps']} | {o['pgs_warm_ms']:.0f} "
              f"| {o['pgs_warm_error']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
