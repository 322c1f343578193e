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
    """A 1 kg block on a fixed-point spring, x'' = -(k/m) x, x(t) = 0.01 sin(2πt)."""
    m = srdda.Model()
    m.add_material("m", srdda.Material(density=1.0, young=1e12, poisson=0.2))
    m.add_block([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]], "m", velocity=(0.02 * np.pi, 0.0))
    m.add_fixed_point([0.0, 0.0], stiffness=4 * np.pi**2)  # ω = 2π rad/s, T = 1 s
    s = srdda.RunSettings(dt=dt, n_steps=n_steps, method="srdda", scheme=scheme, rho_inf=rho, linearization="start")
    r = srdda.run(m, s)
    return r.array("centroid")[:, 0, 0], r.array("time")


def test_shi_and_paper_rho_one_runs_are_identical():
    x1, _ = _oscillator("shi", 1.0, 200, 0.01)
    x2, _ = _oscillator("paper", 1.0, 200, 0.01)
    # identical coefficients up to round-off in 2/Δt² (1e-15 relative)
    assert np.max(np.abs(x1 - x2)) < 1e-14


def test_rho_below_one_damps_high_frequencies_only():
    # With Δt = T/10 the response is resolved: ρ∞ = 0.5 must change amplitude
    # by well under 1% per period (second order), while a Δt = 10 T step
    # (unresolved) is damped towards ρ∞ per step.
    x_lo, _ = _oscillator("paper", 0.5, 100, 0.01)
    amp0, amp1 = np.max(np.abs(x_lo[:100])), np.max(np.abs(x_lo[-100:]))
    assert abs(amp1 / amp0 - 1) < 0.01
    x_hi, _ = _oscillator("paper", 0.5, 40, 10.0)
    x_one, _ = _oscillator("paper", 1.0, 40, 10.0)
    assert np.max(np.abs(x_hi[-5:])) < 1e-3 * np.max(np.abs(x_one[-5:]))


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
