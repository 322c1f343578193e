"""3D contact detection on 10,000 and 100,000 boxes, and the per-step cost of a 1,000-block 3D stack.

* detection: a cubic grid of 0.998 m cubes at 1 m spacing, each turned by a random angle below 0.01 rad
  (so faces are not exactly parallel), contact distance d0 = 0.01 m: every cube touches its 26
  neighbours' boxes and 6 neighbours' faces (the narrow phase's worst case). Times the broad phase
  (hash grid), the narrow phase (vertex-face and edge-edge) and the whole ``SolidContactModel.detect``
  (with the face planes), best of three after a warm-up;
* a step: 10 x 10 x 10 unit cubes stacked on a fixed base under gravity (a wall of blocks settling
  into its contacts), 20 steps of 1 ms per method: ms per step and solves per step;
* a step of the 1,303-block 3D jointed slope (examples/solid/jointed-slope-3d.toml), 20 steps per method.

Usage: PYTHONPATH=src python benchmarks/bench_contacts3d.py [--blocks 10000 100000] [--stack 10] [--slope FILE]
       [--json out.json]
"""
from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

import srdda
from bench_core import report
from srdda.contact.polyhedra_broadphase import block_boxes_3d, candidate_pairs_3d
from srdda.contact.polyhedra_narrowphase import detect_polyhedra_contacts
from srdda.contact.solid_term import SolidContactModel, surface_geometry
from srdda.contact.term import ContactParameters
from srdda.geometry.polyhedron import box
from srdda.kinematics.shape3d import rotation_matrix_3d


def cube_grid(n_blocks: int, seed: int = 0) -> srdda.Model:
    """About ``n_blocks`` slightly turned 0.998 m cubes on a 1 m grid (a cube of cubes)."""
    side = int(np.ceil(n_blocks ** (1 / 3)))
    ijk = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n_blocks]
    turn = rotation_matrix_3d(np.random.default_rng(seed).uniform(-0.01, 0.01, (n_blocks, 3)))
    vertices, faces = box((-0.499, -0.499, -0.499), (0.499, 0.499, 0.499))
    m = srdda.Model(gravity=(0.0, 0.0, -9.81))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    for k in range(n_blocks):
        m.add_polyhedron(vertices @ turn[k].T + ijk[k], faces, "rock")
    return m


def time_detection(n_blocks: int, d0: float = 0.01, repeats: int = 3) -> dict:
    t0 = time.perf_counter()
    arrays = cube_grid(n_blocks).arrays()
    build = time.perf_counter() - t0
    cm = SolidContactModel(arrays, ContactParameters(1e10, 4e9, d0, np.radians(3.0), 0.4 * d0))
    v = arrays.vertex_position
    cm.detect(v)  # compile
    best = {"broad": np.inf, "narrow": np.inf, "detect": np.inf}
    for _ in range(repeats):
        t0 = time.perf_counter()
        boxes = block_boxes_3d(v, arrays.block_ptr)
        pairs = candidate_pairs_3d(boxes, d0, cm.movable)
        t1 = time.perf_counter()
        s = surface_geometry(v, cm.mesh, cm.topology, cm.sin_tol)
        t2 = time.perf_counter()
        topo = cm.topology
        found = detect_polyhedra_contacts(v, pairs, boxes, arrays.block_ptr, topo.block_face_ptr, cm.mesh.face_ptr,
                                          cm.mesh.face_vertex, s.face_normal, s.face_point, topo.neighbour_ptr,
                                          topo.neighbour, s.vertex_convex, topo.block_edge_ptr, topo.edge_v0,
                                          topo.edge_v1, topo.edge_faces, s.edge_convex, d0, cm.sin_tol, 0.4 * d0)
        t3 = time.perf_counter()
        cm.detect(v)
        t4 = time.perf_counter()
        best = {"broad": min(best["broad"], t1 - t0), "narrow": min(best["narrow"], t3 - t2),
                "detect": min(best["detect"], t4 - t3)}
    return {"model": f"{n_blocks} cubes: detection", "method": "-", "blocks": n_blocks, "pairs": len(pairs), "contacts": len(found),
            "build_s": build, "broad_ms": 1e3 * best["broad"], "narrow_ms": 1e3 * best["narrow"],
            "ms_per_step": 1e3 * best["detect"]}


def stack(side: int) -> srdda.Model:
    """``side``³ unit cubes stacked on a fixed base, touching (they settle into their contacts), 1 mm apart sideways."""
    m = srdda.Model(gravity=(0.0, 0.0, -9.81))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=35.0), between=[("rock", "rock")])
    m.add_polyhedron(*box((-1, -1, -1), (side + 1, side + 1, 0)), "rock", fixed=True)
    for i in range(side):
        for j in range(side):
            for k in range(side):
                m.add_polyhedron(*box((i, j, k), (i + 0.999, j + 0.999, k + 1.0)), "rock")
    return m


def time_stack(side: int, method: str, steps: int = 20) -> dict:
    arrays = stack(side).arrays()
    settings = srdda.RunSettings(dt=1e-3, n_steps=steps, method=method, penalty=1e11, record_every=steps)
    srdda.run(arrays, srdda.RunSettings(dt=1e-3, n_steps=1, method=method, penalty=1e11))  # compile
    t0 = time.perf_counter()
    res = srdda.run(arrays, settings)
    wall = time.perf_counter() - t0
    assert res.completed, res.status
    return {"model": f"{side ** 3}-cube stack", "method": method, "blocks": arrays.n_blocks,
            "ms_per_step": 1e3 * wall / steps, "solves_per_step": float(np.mean(res.iterations[1:])),
            "contacts": int(res.closed_contacts[-1])}


def time_model_file(path: str, method: str, steps: int = 20) -> dict:
    """ms per step of a model file (its settings, ``steps`` steps of its Δt) after one compiling step."""
    from srdda.io.modelfile import load_model

    model, settings = load_model(path)
    arrays = model.arrays()
    settings = dataclasses.replace(settings, method=method, n_steps=steps, record_every=steps)
    srdda.run(arrays, dataclasses.replace(settings, n_steps=1))
    t0 = time.perf_counter()
    res = srdda.run(arrays, settings)
    wall = time.perf_counter() - t0
    return {"model": f"{arrays.n_blocks}-block jointed slope", "method": method, "blocks": arrays.n_blocks,
            "ms_per_step": 1e3 * wall / max(res.final_state.step, 1), "status": res.status,
            "solves_per_step": float(np.mean(res.iterations[1:])), "contacts": int(res.closed_contacts[-1])}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--blocks", type=int, nargs="*", default=[10_000, 100_000])
    ap.add_argument("--stack", type=int, default=10)
    ap.add_argument("--slope", default=str(Path(__file__).parents[1] / "examples" / "solid" / "jointed-slope-3d.toml"))
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    rows = [time_detection(n) for n in args.blocks]
    for r in rows:
        print(f"{r['blocks']:7d} cubes: {r['pairs']} pairs, {r['contacts']} contacts; broad {r['broad_ms']:.1f} ms, "
              f"narrow {r['narrow_ms']:.1f} ms, detect {r['ms_per_step']:.1f} ms (model built in {r['build_s']:.1f} s)")
    rows += [time_stack(args.stack, m) for m in srdda.METHODS]
    if args.slope:
        rows += [time_model_file(args.slope, m) for m in srdda.METHODS]
    for r in rows[len(args.blocks):]:
        print(f"{r['model']} {r['method']}: {r['solves_per_step']:.1f} solves per step, {r['contacts']} contacts")
    report(rows, args.json)


if __name__ == "__main__":
    main()
