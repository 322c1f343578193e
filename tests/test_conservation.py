"""Mass and linear momentum of a free block are conserved under every method.

A block spinning in free flight under gravity (no contacts), 10,000 steps.
Its mass is density × its volume as built; dda0's linear rotation update
stretches the block (area × (1 + (ωΔt)²) per step, Table 1's volume growth),
which must change its density, not its mass. Linear momentum is read from the
inertia term (M·V, translation rows), so a mass matrix built from the
stretched volume would show the created mass.
"""
from __future__ import annotations

import numpy as np
import pytest

import srdda
from srdda.assembly.blocks import mass_matrices

V0 = np.array([2.0, 5.0])  # m/s
OMEGA = 3.0  # rad/s
DT, STEPS = 1e-3, 10_000
G = np.array([0.0, -9.81])


def _spinning_block() -> srdda.Model:
    m = srdda.Model(gravity=tuple(G))
    m.add_material("rock", srdda.Material(density=2600.0, young=1e9, poisson=0.25))
    m.add_block([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], "rock", velocity=tuple(V0), angular_velocity=OMEGA)
    return m


@pytest.fixture(scope="module", params=["dda0", "dda1", "srdda"])
def flight(request):
    arrays = _spinning_block().arrays()
    result = srdda.run(arrays, srdda.RunSettings(dt=DT, n_steps=STEPS, method=request.param), keep_history=False)
    assert result.completed
    return request.param, arrays, result.final_state


def test_mass_is_conserved(flight):
    _, arrays, state = flight
    mass = mass_matrices(arrays, state)[:, 0, 0]  # ρ(t)·A(t), the translational mass of the inertia term
    # 1e-12: the density is m / A(t), so ρ·A returns m to within a rounding or two
    np.testing.assert_allclose(mass, arrays.block_mass, rtol=1e-12)


def test_linear_momentum_follows_gravity(flight):
    _, arrays, state = flight
    momentum = np.einsum("nij,nj->ni", mass_matrices(arrays, state), state.velocity)[:, :2]
    expected = arrays.block_mass[:, None] * (V0 + G * state.time)
    # 1e-12 relative: 10,000 exact constant-force updates, each with rounding ~1e-16 (2.3e-13 measured)
    np.testing.assert_allclose(momentum, expected, rtol=1e-12)


def test_dda0_area_grows_as_its_linear_update_predicts(flight):
    method, arrays, state = flight
    area0 = arrays.moments(arrays.vertex_position).area
    if method == "dda0":
        # a rigid rotation r0 = ωΔt per step maps the block by I + r0·J: area × det = 1 + r0² per step
        expected = (1.0 + (OMEGA * DT) ** 2) ** STEPS
        np.testing.assert_allclose(state.moments.area / area0, expected, rtol=1e-6)  # ω stays within 1e-14
    else:
        # exact rotations keep areas; 1e-11: rounding over 10,000 steps (1.9e-12 measured)
        np.testing.assert_allclose(state.moments.area / area0, 1.0, rtol=1e-11)
