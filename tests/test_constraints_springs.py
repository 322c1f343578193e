"""Springs with dashpots: exact agreement with the scheme's own recurrence, and closed forms."""
import numpy as np
import pytest

from srdda import Material, Model, RunSettings, run

RHO, SIDE = 1000.0, 1.0
MASS = RHO * SIDE * SIDE


def _oscillator(k, c, v0, kind="offset"):
    """A free unit square tied at its centroid to a fixed block by a spring (and dashpot) along x."""
    m = Model()
    m.add_material("rock", Material(density=RHO, young=1e10, poisson=0.25))
    m.add_block([[-3, -0.5], [-2, -0.5], [-2, 0.5], [-3, 0.5]], "rock", fixed=True, name="ground")
    m.add_block([[0, -0.5], [1, -0.5], [1, 0.5], [0, 0.5]], "rock", velocity=(v0, 0.0), name="mass")
    m.add_spring((-2.5, 0.0), (0.5, 0.0), k, damping=c, kind=kind, block_a=0, block_b=1)
    return m


def _recurrence(k, c, v0, dt, n):
    """Shi's scheme for m·ẍ + c·ẋ + k·x = 0 with the spring force at the end of the step and the
    dashpot on the mean velocity Δx/Δt: m(V1 - V0)/Δt = -k x1 - c Δx/Δt, Δx = Δt (V0 + V1)/2."""
    x, v, out = 0.0, v0, [0.0]
    for _ in range(n):
        # unknown Δx: (2m/Δt² + k + c/Δt) Δx = 2m V0/Δt - k x
        dx = (2 * MASS / dt * v - k * x) / (2 * MASS / dt**2 + k + c / dt)
        v = 2 * dx / dt - v
        x += dx
        out.append(x)
    return np.array(out)


@pytest.mark.parametrize("kind", ["offset", "axial"])
@pytest.mark.parametrize("method", ["dda0", "srdda"])
def test_spring_dashpot_follow_the_scheme_recurrence(kind, method):
    k, c, v0, dt, n = 4e4, 2e3, 0.01, 1e-3, 400
    res = run(_oscillator(k, c, v0, kind), RunSettings(dt=dt, n_steps=n, method=method))
    x = res.array("centroid")[:, 1, 0] - 0.5
    # the same discrete equations solved two ways: agreement to round-off of the block's
    # elasticity (E = 1e10 couples strain unknowns at ~1e-9 relative)
    assert np.max(np.abs(x - _recurrence(k, c, v0, dt, n))) <= 1e-8 * v0 / np.sqrt(k / MASS)


def test_damped_oscillator_closed_form():
    k, c, v0, dt, n = 4e4, 2e3, 0.01, 2e-4, 2500
    res = run(_oscillator(k, c, v0), RunSettings(dt=dt, n_steps=n, method="srdda"))
    t = np.array(res.time)
    x = res.array("centroid")[:, 1, 0] - 0.5
    w = np.sqrt(k / MASS)
    zeta = c / (2 * np.sqrt(k * MASS))
    wd = w * np.sqrt(1 - zeta**2)
    exact = v0 / wd * np.exp(-zeta * w * t) * np.sin(wd * t)
    # tolerance: the end-of-step spring force damps by about exp(-ω²Δt·t/2) = 1 - 1e-3 here,
    # plus the O((ωΔt)²) phase error; 1% of the amplitude v0/ω covers both with margin
    assert np.max(np.abs(x - exact)) <= 0.01 * v0 / w


def test_dashpot_dissipation_is_in_the_ledger():
    k, c, v0, dt, n = 4e4, 2e3, 0.01, 2e-4, 5000
    res = run(_oscillator(k, c, v0), RunSettings(dt=dt, n_steps=n, method="srdda"))
    e0, e1 = res.energy[0], res.energy[-1]
    assert e1["dissipated"] > 0.5 * e0["total"]  # most of the energy went through the dashpot
    # balance = E + dissipated stays at E(0) up to the scheme's own dissipation ½k|Δx|² per step
    # (end-of-step spring force): Σ ½kΔx² ≈ ω²Δt·∫(KE/E0)dt·E0 ≈ 0.2% of E0 here
    assert e1["balance"] == pytest.approx(e0["total"], rel=5e-3)


def test_axial_spring_has_no_transverse_stiffness_at_rest_length():
    # moving the mass across the spring (y) meets no linear resistance: it keeps its velocity
    m = Model()
    m.add_material("rock", Material(density=RHO, young=1e10, poisson=0.25))
    m.add_block([[-3, -0.5], [-2, -0.5], [-2, 0.5], [-3, 0.5]], "rock", fixed=True)
    m.add_block([[0, -0.5], [1, -0.5], [1, 0.5], [0, 0.5]], "rock", velocity=(0.0, 1e-3))
    m.add_spring((-2.5, 0.0), (0.5, 0.0), 4e4, block_a=0, block_b=1)
    res = run(m, RunSettings(dt=1e-3, n_steps=100, method="srdda"))
    vy = res.array("velocity")[-1, 1, 1]
    # second order in the transverse displacement: stretch (y²/2ℓ) force ~ k y³/ℓ², negligible
    assert vy == pytest.approx(1e-3, rel=1e-6)
