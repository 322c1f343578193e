"""A parameter study farmed out to worker processes: ``srdda.run`` is a pure function.

Each run builds its own model from its parameters, so nothing is shared between
workers; the same function can be submitted to a Dask or Ray cluster unchanged
(e.g. ``client.map(sliding_distance, angles)``). Here: how far a block slides down
a 30° incline in 0.5 s for several joint friction angles, against the closed form
½·g·(sin α − cos α·tan φ)·t².  Run: python examples/ensemble.py
"""
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import srdda

ALPHA = np.radians(30.0)
G = 9.81
T = 0.5


def sliding_distance(friction_angle: float) -> float:
    """Distance slid in T seconds by a block on a 30° incline with joint friction ``friction_angle``."""
    m = srdda.Model(gravity=(G * np.sin(ALPHA), -G * np.cos(ALPHA)))  # incline along x, gravity rotated
    m.add_material("rock", srdda.Material(2600.0, 10e9, 0.25))
    m.add_joint_material("joint", srdda.JointMaterial(friction_angle=friction_angle), between=[("rock", "rock")])
    m.add_block([[-5, -1], [5, -1], [5, 0], [-5, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], "rock")
    res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=int(T / 1e-3), method="srdda", penalty=1e10))
    c = res.array("centroid")[:, 1]
    return float(c[-1, 0] - c[0, 0])


if __name__ == "__main__":
    angles = [0.0, 10.0, 20.0, 25.0]
    with ProcessPoolExecutor(max_workers=2) as pool:
        distances = list(pool.map(sliding_distance, angles))
    for phi, d in zip(angles, distances):
        exact = max(0.0, 0.5 * G * (np.sin(ALPHA) - np.cos(ALPHA) * np.tan(np.radians(phi))) * T**2)
        print(f"φ = {phi:4.1f}°: slid {d:.5f} m, closed form {exact:.5f} m")
