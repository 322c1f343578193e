"""A circular tunnel in jointed rock: the key blocks around the opening.

A 30 x 30 m section with a 6 m diameter tunnel at its centre, two joint sets
(dips 35° and 125°, 2.5 m spacing, 8 m traces with 1 m bridges). Blocks that
touch the outer boundary are fixed; the blocks around the tunnel are free, so
a run shows which key blocks fall into the opening.
Run: python examples/cutting/tunnel.py  (writes tunnel.toml here)
"""
from pathlib import Path

import numpy as np
import shapely

import srdda
from srdda.io import save_model
from srdda.model import JointMaterial

size = 30.0
domain = np.array([(0, 0), (size, 0), (size, size), (0, size)], dtype=float)
tunnel = srdda.circular_opening((size / 2, size / 2), 3.0, n_sides=32)
rock = shapely.Polygon(domain, holes=[tunnel])
sets = [srdda.JointSet(dip=35.0, spacing=2.5, trace_length=8.0, bridge=1.0, joint_type=1, dip_sd=3.0),
        srdda.JointSet(dip=125.0, spacing=2.5, trace_length=8.0, bridge=1.0, joint_type=2, dip_sd=3.0)]
traces, types = srdda.joint_traces(rock, sets, seed=11)
cut = srdda.cut_blocks(traces, types, edge_node_distance=0.02, boundary=domain, openings=[tunnel],
                       boundary_type=0)

model = srdda.Model(gravity=(0.0, -9.81))
model.add_material("granite", srdda.Material(density=2650.0, young=30e9, poisson=0.22, plane="strain"))
model.add_joint_material("set 1", JointMaterial(friction_angle=30.0))
model.add_joint_material("set 2", JointMaterial(friction_angle=25.0))
outer = shapely.LinearRing(domain)
fixed = shapely.distance(cut.polygons, outer) < 1e-9
srdda.add_cut_blocks(model, cut, materials={0: "granite"}, joints={1: "set 1", 2: "set 2"}, fixed=fixed)
crown = cut.locate([(size / 2, size / 2 + 3.2)])[0]
model.add_measured_point([size / 2, size / 2 + 3.2], block=int(crown))
settings = srdda.RunSettings(dt=5e-4, n_steps=2000, method="srdda", penalty=50 * 30e9)
out = Path(__file__).with_name("tunnel.toml")
save_model(model, settings, out, title="circular tunnel in jointed granite")
print(f"{cut.n_blocks} blocks, {int((~fixed).sum())} free -> {out}")
