"""The paper's generalized-α against Shi's scheme and Chung-Hulbert."""
import numpy as np
import pytest

import srdda
from srdda.integrators import TimeScheme, alpha_parameters


def test_alpha_parameters_at_rho_one():
    am, af, beta, gamma = alpha_parameters(1.0)
    assert (am, af, beta, gamma) == (0.5, 0.5, 0.25, 0.5)


@pytest.mark.parametrize("dt", [1e-3, 0.37])
def test_paper_scheme_at_rho_one_is_shi(dt):
    shi = TimeScheme("shi").coefficients(dt)
    paper = TimeScheme("paper", 1.0).coefficients(dt)
    for name in ("c_k", "c_p", "c_m", "m_v", "m_a", "k_v", "k_a", "v_d", "v_v", "v_a"):
        assert getattr(paper, name) == pytest.approx(getattr(shi, name), rel=1e-15, abs=1e-15 / dt**2), name


def test_paper_scheme_differs_below_rho_one():
    c = TimeScheme("paper", 0.5).coefficients(1e-3)
    # αm = 0, αf = 1/3, β = 4/9, γ = 5/6: elastic weight Δt(1-αf)γ/(βΔt) = 1.25
    assert c.c_k == pytest.approx(1.25, rel=1e-15)
    assert c.c_m == pytest.approx(1 / (4 / 9 * 1e-6), rel=1e-15)


def test_chung_hulbert_at_rho_one_is_trapezoidal():
    c = TimeScheme("chung-hulbert", 1.0).coefficients(1e-2)
    assert c.c_k == 0.5 and c.c_p == 0.5 and c.load_time_fraction == 0.5


def _oscillator(scheme, rho, n_steps, dt):
    """A 1 kg block on a fixed-point spring, x'' = -(k/m) x, x(t) = 0.01 sin(2πt); returns (x, v, t)."""
    m = srdda.Model()
    m.add_material("m", srdda.Material(density=1.0, young=1e12, poisson=0.2))
    m.add_block([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]], "m", velocity=(0.02 * np.pi, 0.0))
    m.add_fixed_point([0.0, 0.0], stiffness=4 * np.pi**2)  # ω = 2π rad/s, T = 1 s
    s = srdda.RunSettings(dt=dt, n_steps=n_steps, method="srdda", scheme=scheme, rho_inf=rho, linearization="start")
    r = srdda.run(m, s)
    return r.array("centroid")[:, 0, 0], r.array("velocity")[:, 0, 0], r.array("time")


def _amplification(scheme, rho, omega, dt):
    """The one-step map of (x, V, A) for m ẍ + k x = 0, k = ω² m, a penalty spring (module doc of schemes).

    (c_p k + c_m m) Δd = -k x + m (m_v V + m_a A); V, A at t + Δt from the Newmark updates.
    """
    c = TimeScheme(scheme, rho).coefficients(dt)
    k = omega**2
    dd = np.array([-k, c.m_v, c.m_a]) / (c.c_p * k + c.c_m)
    return np.array([[1.0, 0.0, 0.0], [0.0, c.v_v, c.v_a], [0.0, c.a_v, c.a_a]]) + np.outer([1.0, c.v_d, c.a_d], dd)


def _physical_root(scheme, rho, omega, dt):
    """The eigenvalue of the oscillation: of the complex pair, or (unresolved) the largest real root."""
    roots = np.linalg.eigvals(_amplification(scheme, rho, omega, dt))
    if scheme == "paper" and rho == 1.0:  # Shi's scheme: A never feeds back; its root -1 moves nothing
        roots = roots[np.abs(roots + 1.0) > 1e-9]
    return roots[np.argmax(np.abs(roots))]


@pytest.mark.parametrize("rho", [1.0, 0.5])
@pytest.mark.parametrize("steps_per_period", [100, 20])
def test_measured_damping_of_a_resolved_oscillation_is_the_schemes_closed_form(rho, steps_per_period):
    # The run's x(t) must be the scheme's own recurrence (assembly, solve and updates of a real model
    # against the 3x3 map above: agreement to 1e-12 relative, round-off), and its amplitude must decay per
    # step by the modulus of the oscillation's root (log-fit of the peaks of 6 periods; peak sampling
    # errs by about (ωΔt)²/8 = 5e-3 at 20 steps a period, hence the 1e-2 on the per-period loss).
    omega, dt = 2 * np.pi, 1.0 / steps_per_period
    n = 6 * steps_per_period
    x, v, _ = _oscillator("paper", rho, n, dt)
    a_map = _amplification("paper", rho, omega, dt)
    z, recurrence = np.array([0.0, 0.02 * np.pi, 0.0]), [0.0]  # A(0) = 0: no force at x = 0
    for _ in range(n):
        z = a_map @ z
        recurrence.append(z[0])
    assert np.max(np.abs(x - recurrence)) <= 1e-12 * np.max(np.abs(recurrence))
    periods = np.reshape(np.abs(x[1:]), (6, steps_per_period))
    peaks, at = periods.max(axis=1), periods.argmax(axis=1) + np.arange(6) * steps_per_period
    measured = np.exp(np.polyfit(at, np.log(peaks), 1)[0])  # amplitude factor per step
    root = abs(_physical_root("paper", rho, omega, dt))
    loss_per_period = 1 - root**steps_per_period
    assert abs((1 - measured**steps_per_period) - loss_per_period) <= 1e-2 * loss_per_period
    if rho == 1.0:
        # Shi's scheme with the spring force at the end of the step: |λ|² = 2/(2 + (ωΔt)²) (characteristic
        # polynomial (2 + Ω²)λ² + (Ω² - 4)λ + 2), a loss of about π ωΔt/2 per period: 9.39% at T/100,
        # 38.2% at T/20
        assert root == pytest.approx((1 + (omega * dt) ** 2 / 2) ** -0.5, rel=1e-14)
        assert loss_per_period == pytest.approx({100: 0.0939, 20: 0.3823}[steps_per_period], abs=1e-4)


def test_rho_below_one_damps_unresolved_modes_towards_rho_inf_per_step():
    # Δt = 10 T (ωΔt = 63): the oscillation is not resolved. Closed form (the map's roots): ρ∞ = 0.5 damps it
    # by |λ| = 0.5004 per step (tending to ρ∞ as ωΔt grows), ρ∞ = 1 by 0.9980 only. Measured: the roots of the
    # second-order recurrence x(n+2) = a x(n+1) + b x(n) fitted to the run's x over steps 2-22 (the map's third
    # root is below 1e-16 for ρ∞ = 0.5, and Shi's root -1 does not move x; later steps, 1e-7 of the start and
    # less, carry round-off of 1e-9 relative and more); agreement to 1e-9.
    omega, dt = 2 * np.pi, 10.0
    for rho, expected in ((0.5, 0.5004), (1.0, 0.9980)):
        x, _, _ = _oscillator("paper", rho, 22, dt)
        root = abs(_physical_root("paper", rho, omega, dt))
        assert root == pytest.approx(expected, abs=1e-4)
        x = x[2:] / np.max(np.abs(x[2:]))
        (a, b), *_ = np.linalg.lstsq(np.column_stack([x[1:-1], x[:-2]]), x[2:], rcond=None)
        measured = np.max(np.abs(np.roots([1.0, -a, -b])))
        assert measured == pytest.approx(root, rel=1e-9)


def test_shi_and_paper_rho_one_runs_are_identical():
    x1, _, _ = _oscillator("shi", 1.0, 200, 0.01)
    x2, _, _ = _oscillator("paper", 1.0, 200, 0.01)
    # identical coefficients up to round-off in 2/Δt² (1e-15 relative)
    assert np.max(np.abs(x1 - x2)) < 1e-14


def test_velocity_ratio_zero_is_shis_static_analysis():
    # k01 = 0: every step starts at rest, so a block under a constant force moves by
    # the quasi-static increment d = F Δt² / (2 m) each step (Shi's scheme with V = 0):
    # after n steps n·g·Δt²/2, not the dynamic g (nΔt)²/2.
    m = srdda.Model(gravity=(0.0, -10.0))
    m.add_material("m", srdda.Material(density=1000.0, young=1e9, poisson=0.2))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "m")
    for method in ("dda0", "srdda"):
        r = srdda.run(m, srdda.RunSettings(dt=0.01, n_steps=50, method=method, velocity_ratio=0.0))
        drop = r.array("centroid")[-1, 0, 1] - 0.5
        assert drop == pytest.approx(-50 * 10.0 * 0.01**2 / 2, rel=1e-12)
        assert np.all(r.array("velocity")[-1] == 0.0)
