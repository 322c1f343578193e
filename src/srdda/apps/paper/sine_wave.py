"""Paper example 4.3: propagation of a sine wave along a bar-spring chain (Figs. 7-10).

The paper gives 40 bars of 0.25 × 0.10 m between A and B (10.00 m apart), 39
springs of k = 2×10⁸ N/m, A driven by v = 0.25·sin(2π n/300) (n the step,
u = 0), B fixed horizontally, Δt = 0.005 s, E = 2×10¹⁰ Pa, ν = 0.25, penalty
2×10⁸ N/m, no weight, ρ∞ = 1, 900 steps. It gives neither the layout nor the
density; the choices here (docs/constraints.md, "Sine wave"):

* the bars lie end to end along x from x = 0 to 10 m; spring i ties the
  centroids of bars i and i+1 (``kind="offset"``: force k·(relative displacement),
  both directions), so the chain is a shear chain whose transverse wave obeys
  m·v̈_i = k·(v_{i+1} - 2v_i + v_{i-1});
* A is the centroid of bar 1, driven exactly by Lagrange multipliers in both
  components (u = 0, v = 0.25 sin(2π t/1.5)); B is the centroid of bar 40, held
  horizontally by the penalty 2×10⁸ N/m (free vertically);
* ρ = 1.2×10⁸ kg/m³ (bar mass 3×10⁶ kg per metre of thickness), so that the
  wave travels about 3 m per period and three periods fit in the 10 m chain
  by step 900 (with a rock density the wave would cross the chain in 5 steps).

Reading a period off the wave (``profile_periods``): at step N (a multiple
of 300) the transverse displacement profile of the bar centroids is taken
along the chain; its zero crossings z_1 < z_2 < ... are found by linear
interpolation inside the wave (where |v| > 1% of the amplitude); z_0 is A (the
drive is at zero at N). A distance becomes a number of steps through the
phase velocity of the discrete chain at the drive frequency, c_p = ω/κ with
ω = 2·sqrt(k/m)·sin(κa/2) (a = 0.25 m the bar spacing). A period spans two
consecutive half-wavelengths counted from A, [z_0, z_2], [z_2, z_4], ...; the
earliest period (emitted from step 0) has no zero crossing at its front,
because in a dispersive chain the displacement ahead of the front decays
without crossing zero, so it is read as twice its trailing half-wave (the one
bounded by two crossings; docs/constraints.md compares other readings).
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from ...constraints import MotionHistory
from ...integrators.methods import MethodName
from ...model import Material, Model
from ...results import Result
from ...settings import RunSettings
from .registry import Example, Row, register

__all__ = ["SINE_WAVE", "build", "tables", "wave_periods", "profile_periods", "chain_reference",
           "phase_velocity", "PAPER_PERIODS"]

N_BARS, BAR_LENGTH, BAR_HEIGHT = 40, 0.25, 0.10
SPRING = 2e8  # N/m
DENSITY = 1.2e8  # kg/m³, chosen (see module doc)
DT, PERIOD_STEPS, AMPLITUDE = 0.005, 300, 0.25
PAPER_PERIODS: dict[int, dict[str, tuple[int, ...] | None]] = {  # step: {method: periods in CS, earliest first}
    300: {"dda0": (300,), "dda1": (300,), "srdda": (300,)},
    600: {"dda0": None, "dda1": None, "srdda": (299, 302)},  # DDA0/DDA1: two periods in about 573 CS
    900: {"dda0": (270, 281, 301), "dda1": (275, 281, 304), "srdda": (301, 302, 301)},
}
PAPER_TWO_PERIODS_600 = 573


def build(method: MethodName, n_steps: int = 900) -> tuple[Model, RunSettings]:
    """The bar-spring chain and its run settings for ``method``."""
    m = Model()
    m.add_material("bar", Material(density=DENSITY, young=2e10, poisson=0.25))
    a, h = BAR_LENGTH, BAR_HEIGHT / 2
    for i in range(N_BARS):
        m.add_block([[i * a, -h], [(i + 1) * a, -h], [(i + 1) * a, h], [i * a, h]], "bar", name=f"bar {i + 1}")
    for i in range(N_BARS - 1):
        m.add_spring(((i + 0.5) * a, 0.0), ((i + 1.5) * a, 0.0), SPRING, kind="offset", block_a=i, block_b=i + 1)
    m.add_prescribed_motion((0.5 * a, 0.0), MotionHistory.sine((0.0, AMPLITUDE), PERIOD_STEPS * DT), block=0)
    m.add_prescribed_motion(((N_BARS - 0.5) * a, 0.0), (0.0, 0.0), components="x", by="penalty",
                            stiffness=2e8, block=N_BARS - 1)
    return m, RunSettings(dt=DT, n_steps=n_steps, method=method, rho_inf=1.0, penalty=2e8, contacts=False)  # the bars touch only at their springs


def phase_velocity() -> float:
    """Phase velocity (m/s) of the discrete shear chain at the drive frequency."""
    mass = DENSITY * BAR_LENGTH * BAR_HEIGHT
    omega = 2 * np.pi / (PERIOD_STEPS * DT)
    kappa = 2.0 / BAR_LENGTH * np.arcsin(omega / (2.0 * np.sqrt(SPRING / mass)))
    return float(omega / kappa)


def _crossings(x: np.ndarray, v: np.ndarray) -> np.ndarray:
    s = np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)
    return x[s] - v[s] * (x[s + 1] - x[s]) / (v[s + 1] - v[s])


def profile_periods(x: np.ndarray, v: np.ndarray) -> list[float]:
    """Periods (CS) in the profile ``v`` at bar positions ``x`` (A = x[0]), earliest emitted first.

    Zero crossings and the front period's trailing half-wave as in the module doc.
    """
    x, v = np.asarray(x, float), np.asarray(v, float)
    in_wave = np.flatnonzero(np.abs(v) > 0.01 * AMPLITUDE)
    if len(in_wave) == 0:
        return []
    last = in_wave[-1] + 1
    marks = np.concatenate([[x[0]], _crossings(x[1:last + 1], v[1:last + 1])])
    metres_per_step = phase_velocity() * DT
    periods = [float((marks[i + 2] - marks[i]) / metres_per_step) for i in range(0, len(marks) - 2, 2)]
    if len(marks) % 2 == 0:  # a half-wave is left over: the trailing half of the front period
        periods.append(float(2.0 * (marks[-1] - marks[-2]) / metres_per_step))
    return periods[::-1]


def wave_periods(result: Result, step: int) -> list[float]:
    """Periods (CS) read off the wave profile of ``result`` at ``step``, earliest emitted first."""
    c = result.array("centroid")
    n = list(result.step).index(step)
    return profile_periods(c[0, :, 0], c[n, :, 1] - c[0, :, 1])


def chain_reference(steps: np.ndarray) -> np.ndarray:
    """Transverse centroid displacements (len(steps), N_BARS) of the chain's ODEs, by scipy.

    The independent reference for the layout above: m·v̈_i = k(v_{i+1} - 2v_i + v_{i-1}),
    bar 1 moved by the drive, bar 40 with one spring (B free vertically), no time step error
    (DOP853, rtol 1e-10).
    """
    mass = DENSITY * BAR_LENGTH * BAR_HEIGHT
    omega = 2 * np.pi / (PERIOD_STEPS * DT)

    def rates(t: float, y: np.ndarray) -> np.ndarray:
        v = np.concatenate([[AMPLITUDE * np.sin(omega * t)], y[:N_BARS - 1]])
        force = SPRING * (v[:-1] - v[1:])
        force[:-1] += SPRING * (v[2:] - v[1:-1])
        return np.concatenate([y[N_BARS - 1:], force / mass])

    t = np.asarray(steps, float) * DT
    sol = solve_ivp(rates, (0.0, float(t.max())), np.zeros(2 * (N_BARS - 1)), t_eval=t, method="DOP853",
                    rtol=1e-10, atol=1e-12)
    return np.column_stack([AMPLITUDE * np.sin(omega * t), sol.y[:N_BARS - 1].T])


def tables(results: dict[str, Result]) -> list[Row]:
    """Periods at CS 300, 600 and 900 per method, beside the paper's."""
    rows: list[Row] = []
    for step, per_method in PAPER_PERIODS.items():
        for method, res in results.items():
            if step not in list(res.step):
                continue
            paper = per_method.get(method)
            periods = wave_periods(res, step)
            for j, period in enumerate(periods):
                rows.append({"table": "Sine wave (4.3)", "quantity": f"period_{j + 1}", "step": step,
                             "method": method, "ours": period,
                             "paper": None if paper is None or j >= len(paper) else float(paper[j]),
                             "exact": float(PERIOD_STEPS), "unit": "step"})
            if step == 600 and len(periods) == 2:  # the paper: DDA0 and DDA1 fit two periods in ~573 CS
                rows.append({"table": "Sine wave (4.3)", "quantity": "two_periods", "step": step, "method": method,
                             "ours": periods[0] + periods[1],
                             "paper": float(sum(paper)) if paper is not None else float(PAPER_TWO_PERIODS_600),
                             "exact": 2.0 * PERIOD_STEPS, "unit": "step"})
    return rows


SINE_WAVE = register(Example(
    "sine-wave", "4.3 Propagation of a sine wave", tables, builder=build,
    notes="The paper gives neither the layout nor the density. Ours: springs tie neighbouring bar "
          "centroids (a shear chain), A is bar 1's centroid driven by multipliers, ρ = 1.2e8 kg/m³ so that "
          "three wavelengths fit by CS 900. No bar rotates, so the three methods give identical periods. "
          "Periods are read between zero crossings of the profile, the front period from its trailing "
          "half-wave, converted with the chain's phase velocity. docs/constraints.md, Sine wave."))
