"""Small models for the results tests (no /work/shared needed)."""
from __future__ import annotations

import srdda

ROD_SOURCE = '''
import srdda

def rod_model(length=10.0, thickness=0.1):
    """The paper's slender rod (4.2): a 10 x 0.1 m block pinned at one end, released horizontal."""
    m = srdda.Model(gravity=(0.0, -10.0))
    m.add_material("rock", srdda.Material(density=2500.0, young=2e16, poisson=0.25))
    m.add_block([[0, 0], [length, 0], [length, thickness], [0, thickness]], "rock", name="rod")
    m.add_fixed_point([0.0, thickness / 2], stiffness=2e16)
    m.add_measured_point([length, thickness / 2])
    m.add_point_load([length / 2, thickness / 2], [[0.0, 0.0, 0.0], [1.0, 0.0, -100.0]])
    return m
'''
namespace: dict = {}
exec(ROD_SOURCE, namespace)
rod_model = namespace["rod_model"]


def rod_settings(method: str = "srdda", n_steps: int = 200) -> srdda.RunSettings:
    return srdda.RunSettings(dt=1e-3, n_steps=n_steps, method=method, penalty=2e16)


def two_block_model() -> srdda.Model:
    """Two blocks of different materials and vertex counts, spinning and drifting."""
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("a", srdda.Material(density=2000.0, young=1e9, poisson=0.2))
    m.add_material("b", srdda.Material(density=2600.0, young=5e9, poisson=0.3))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "a", velocity=(1.0, 0.0), angular_velocity=0.5)
    m.add_block([[3, 0], [4, 0], [4.5, 0.8], [3.5, 1.5], [2.8, 0.9]], "b", velocity=(-0.5, 1.0))
    m.add_measured_point([0.5, 0.5])
    m.add_measured_point([3.5, 0.5])
    return m
