"""A jointed slope of about 1000 blocks with contacts everywhere: steps per second,
open-close iterations per step and the profile's top entries.

The slope (20 m high, 35° face over a 5 m deep base) is cut by two joint sets
(dip 30° and 110°, spacing 0.765 m) with shapely; slivers are left out;
blocks reaching below y = 1 m are fixed. Joints: φ = 25°, no cohesion, so the blocks near the
face start to move under gravity.

    PYTHONPATH=src python benchmarks/bench_contact_slope.py [steps] [--profile]
"""
from __future__ import annotations

import cProfile
import io
import platform
import pstats
import sys
import time

import numpy as np
import shapely

import srdda
from srdda.model import JointMaterial


def jointed_slope(spacing: float = 0.765, sets: tuple[float, float] = (30.0, 110.0)) -> srdda.Model:
    """A slope cut by two joint sets into blocks (about 1000 for the default spacing)."""
    height, toe, width = 20.0, 8.0, 40.0
    run = height / np.tan(np.radians(35.0))
    slope = shapely.Polygon([(0, 0), (width, 0), (width, height + 5), (toe + run, height + 5), (toe, 5), (0, 5)])
    u = np.array([np.cos(np.radians(sets[0])), np.sin(np.radians(sets[0]))])
    v = np.array([np.cos(np.radians(sets[1])), np.sin(np.radians(sets[1]))])
    n = int(2 * max(width, height + 5) / spacing) + 2
    origin = np.array([width / 2, (height + 5) / 2])
    cells = []
    for i in range(-n, n):
        for j in range(-n, n):
            p = origin + spacing * (i * u + j * v)
            cells.append(shapely.Polygon([p, p + spacing * u, p + spacing * (u + v), p + spacing * v]))
    pieces = shapely.intersection(np.array(cells), slope)
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("rock", srdda.Material(density=2600.0, young=5e9, poisson=0.25))
    m.add_joint_material("joint", JointMaterial(friction_angle=25.0), between=[("rock", "rock")])
    for piece in pieces:
        # slivers (less than a fifth of a full block) are left out as voids: a sliver squeezed
        # between sliding neighbours is far softer than the contact springs around it
        if piece.is_empty or piece.geom_type != "Polygon" or piece.area < 0.2 * spacing**2 * np.sin(np.radians(80)):
            continue
        coords = np.asarray(shapely.simplify(piece, 1e-9).exterior.coords)[:-1]
        fixed = coords[:, 1].min() < 1.0
        m.add_block(coords, "rock", fixed=bool(fixed))
    return m


def main(steps: int, profile: bool) -> None:
    model = jointed_slope()
    arrays = model.arrays()
    settings = srdda.RunSettings(dt=2e-4, n_steps=steps, method="srdda", penalty=5e10, record_every=steps)
    n_free = int(np.count_nonzero(~arrays.block_fixed))
    print(f"# {platform.machine()}, Python {platform.python_version()}, numpy {np.__version__}")
    print(f"blocks {arrays.n_blocks} ({n_free} free), vertices {len(arrays.vertex_position)}")
    srdda.run(model, srdda.RunSettings(dt=2e-4, n_steps=2, method="srdda", penalty=5e10))  # compile numba
    solves: list[int] = []

    class Count:
        def record(self, arrays, state, n, energy):  # noqa: ANN001
            solves.append(n)

        def finish(self, status, state):  # noqa: ANN001
            pass

    settings = srdda.RunSettings(dt=2e-4, n_steps=steps, method="srdda", penalty=5e10)
    prof = cProfile.Profile() if profile else None
    t0 = time.perf_counter()
    if prof:
        prof.enable()
    res = srdda.run(model, settings, recorders=[Count()])
    if prof:
        prof.disable()
    wall = time.perf_counter() - t0
    contacts = res.final_state.contacts
    print(f"status {res.status}; {steps} steps in {wall:.1f} s: {steps / wall:.2f} steps/s; "
          f"simulated {res.time[-1]:.4f} s")
    print(f"solves per step: mean {np.mean(solves[1:]):.2f}, max {max(solves[1:])}")
    print(f"contacts at the end: {len(contacts.vertex)} ({int(np.count_nonzero(contacts.closed))} closed), "
          f"max penetration {max(res.max_penetration):.2e} m")
    moved = np.linalg.norm(res.array("centroid")[-1] - res.array("centroid")[0], axis=1).max()
    print(f"largest block displacement {moved:.2e} m")
    if prof:
        out = io.StringIO()
        pstats.Stats(prof, stream=out).sort_stats("cumulative").print_stats(18)
        print(out.getvalue())


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(int(args[0]) if args else 200, "--profile" in sys.argv)
