"""A jointed rock slope: boundary + two joint sets -> blocks -> srdda model file.

A 45° slope 20 m high on a 5 m base, cut by a set dipping 25° out of the face
(friction 15°) and a steep set at 100° (friction 30°), persistent traces with
some scatter, as the benchmark slopes of docs/cutting.md. The base block and
every block touching the model's bottom or right side are fixed.
Run: python examples/cutting/jointed_slope.py  (writes jointed_slope.toml here)
"""
from pathlib import Path

import numpy as np
import shapely

import srdda
from srdda.io import save_model
from srdda.model import JointMaterial

boundary = np.array([(0, -5), (60, -5), (60, 20), (35, 20), (15, 0), (0, 0)], dtype=float)
rock_mass = shapely.Polygon([(15, 0), (35, 20), (60, 20), (60, 0)])  # jointed part above the base
sets = [srdda.JointSet(dip=25.0, spacing=4.0, joint_type=2, spacing_sd=0.3, dip_sd=1.0),
        srdda.JointSet(dip=100.0, spacing=5.0, trace_length=12.0, bridge=2.0, joint_type=3, dip_sd=2.0)]
traces, types = srdda.joint_traces(rock_mass, sets, seed=7)
base_line = np.array([[0.0, 0.0, 60.0, 0.0]])  # the base block is separated from the slope
cut = srdda.cut_blocks(np.vstack([base_line, traces]), np.concatenate([[1], types]),
                       edge_node_distance=0.05, boundary=boundary, boundary_type=1)

model = srdda.Model(gravity=(0.0, -9.81))
model.add_material("rock", srdda.Material(density=2700.0, young=5e9, poisson=0.25, plane="strain"))
model.add_joint_material("bedding", JointMaterial(friction_angle=40.0))
model.add_joint_material("set 1", JointMaterial(friction_angle=15.0))
model.add_joint_material("set 2", JointMaterial(friction_angle=30.0))
bounds = shapely.bounds(cut.polygons)
fixed = (bounds[:, 1] < -4.99) | (bounds[:, 2] > 59.99)  # base and blocks on the right side
srdda.add_cut_blocks(model, cut, materials={0: "rock"}, joints={1: "bedding", 2: "set 1", 3: "set 2"},
                     fixed=fixed)
model.add_measured_point([20.0, 4.0])
settings = srdda.RunSettings(dt=1e-3, n_steps=2000, method="srdda", penalty=50 * 5e9)
out = Path(__file__).with_name("jointed_slope.toml")
save_model(model, settings, out, title="jointed rock slope cut from two joint sets")
print(f"{cut.n_blocks} blocks ({int(fixed.sum())} fixed) -> {out}")
