"""A semicircular masonry arch of 15 voussoirs on two fixed abutments.

The arch ring (intrados radius 4 m, thickness 0.6 m) and the abutments are
one boundary; radial joints cut the ring into voussoirs (mortar-free joints,
friction 35°) and two vertical joints separate the abutments.
Run: python examples/cutting/masonry_arch.py  (writes masonry_arch.toml here)
"""
from pathlib import Path

import numpy as np
import shapely

import srdda
from srdda.io import save_model
from srdda.model import JointMaterial

r_in, r_out, n_stones = 4.0, 4.6, 15
angles = np.linspace(0.0, np.pi, 64)
cos, sin = np.cos(angles), np.sin(angles)
sin[[0, -1]] = 0.0  # the springings lie exactly on the abutments' top y = 0
outer = np.column_stack([r_out * cos, r_out * sin])
inner = np.column_stack([r_in * cos[::-1], r_in * sin[::-1]])
ring = shapely.Polygon(np.vstack([outer, inner]))
abutments = shapely.box(-r_out - 1.0, -2.0, -r_in, 0.0).union(shapely.box(r_in, -2.0, r_out + 1.0, 0.0))
boundary = shapely.unary_union([ring, abutments])
cuts = np.linspace(0.0, np.pi, n_stones + 1)
c, s = np.cos(cuts), np.sin(cuts)
s[[0, -1]] = 0.0
radial = np.column_stack([(r_in - 0.1) * c, (r_in - 0.1) * s, (r_out + 0.1) * c, (r_out + 0.1) * s])
cut = srdda.cut_blocks(radial, np.ones(len(radial), dtype=int), edge_node_distance=1e-3,
                       boundary=boundary, boundary_type=0)

model = srdda.Model(gravity=(0.0, -9.81))
model.add_material("stone", srdda.Material(density=2300.0, young=10e9, poisson=0.2, plane="strain"))
model.add_joint_material("dry joint", JointMaterial(friction_angle=35.0))
fixed = shapely.bounds(cut.polygons)[:, 1] < -1.0  # the abutments
srdda.add_cut_blocks(model, cut, materials={0: "stone"}, joints={1: "dry joint"}, fixed=fixed)
model.add_measured_point([0.0, r_out - 0.05])  # the key stone's extrados
settings = srdda.RunSettings(dt=2e-4, n_steps=2000, method="srdda", penalty=50 * 10e9)
out = Path(__file__).with_name("masonry_arch.toml")
save_model(model, settings, out, title="semicircular masonry arch, 15 voussoirs")
print(f"{cut.n_blocks} blocks ({int(fixed.sum())} abutments) -> {out}")
