"""Robustness probe: does any contact create energy on randomly jointed slopes?

Not a benchmark (``make bench`` skips it) and not a test: a probe for developers.
Each seed cuts the 45° benchmark slope with two random joint sets (srdda's
generator), runs 600 steps under dda1 and srdda, and prints the largest rise of
the total energy above its initial value (relative to the potential energy of
the free blocks) and the largest block speed; a line is flagged when the rise
exceeds 1% or a block moves faster than sqrt(2·g·H) = 22 m/s.
Usage: python benchmarks/probe_contact_energy.py FIRST_SEED LAST_SEED
Findings on 2026-11-22 are in docs/contacts.md (limitations).
"""
import sys, numpy as np, shapely, srdda, warnings
from srdda.model import JointMaterial
boundary = np.array([(0, -5), (60, -5), (60, 20), (35, 20), (15, 0), (0, 0)], dtype=float)
rock_mass = shapely.Polygon([(15, 0), (35, 20), (60, 20), (60, 0)])
def trial(seed, method, steps=600):
    rng = np.random.default_rng(seed)
    sets = [srdda.JointSet(dip=float(rng.uniform(15, 40)), spacing=float(rng.uniform(2.5, 5)), joint_type=2, spacing_sd=0.3, dip_sd=1.0),
            srdda.JointSet(dip=float(rng.uniform(80, 120)), spacing=float(rng.uniform(3, 6)), trace_length=12.0, bridge=2.0, joint_type=3, dip_sd=2.0)]
    traces, types = srdda.joint_traces(rock_mass, sets, seed=seed)
    cut = srdda.cut_blocks(np.vstack([[[0.0, 0.0, 60.0, 0.0]], traces]), np.concatenate([[1], types]),
                           edge_node_distance=0.05, boundary=boundary, boundary_type=1)
    m = srdda.Model(gravity=(0.0, -9.81))
    m.add_material("rock", srdda.Material(2700.0, 5e9, 0.25, "strain"))
    m.add_joint_material("bedding", JointMaterial(40.0)); m.add_joint_material("s1", JointMaterial(float(rng.uniform(10, 30)))); m.add_joint_material("s2", JointMaterial(30.0))
    b = shapely.bounds(cut.polygons); fixed = (b[:, 1] < -4.99) | (b[:, 2] > 59.99)
    srdda.add_cut_blocks(m, cut, materials={0: "rock"}, joints={1: "bedding", 2: "s1", 3: "s2"}, fixed=fixed)
    r = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=steps, method=method, penalty=2.5e11))
    E = r.array("energy"); keys = list(r.energy[0]); tot = E[:, keys.index("total")]
    a = m.arrays(); free = ~a.block_fixed
    # energy scale: potential energy of free blocks above the model bottom
    mom = a.moments(a.vertex_position); scale = float(np.sum((2700 * mom.area * 9.81 * (mom.centroid[:, 1] + 5))[free]))
    v = r.array("velocity"); speed = np.hypot(v[:, :, 0], v[:, :, 1]).max()
    return cut.n_blocks, r.status[:40], (tot.max() - tot[0]) / scale, speed
for seed in range(int(sys.argv[1]), int(sys.argv[2])):
    for method in ["dda1", "srdda"]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            n, st, exc, sp = trial(seed, method)
        flag = "  <-- ENERGY" if exc > 0.01 or sp > 22 else ""
        print(f"seed {seed} {method}: {n} blocks, {st}, max energy excess {exc:.2e} of scale, max speed {sp:.2f} m/s{flag}", flush=True)
