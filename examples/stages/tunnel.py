"""A tunnel in jointed rock, staged: equilibrium, excavation, bolts, an earthquake record.

The rock of examples/cutting/tunnel.py (a 30 x 30 m section of jointed granite, the same two joint
sets and seed), but the tunnel (6 m diameter) is not cut out from the start: its core is two blocks,
"tunnel heading" above the springline and "tunnel bench" below, bounded by the excavation line (joint
material "excavation line"). Blocks touching the outer boundary are fixed. Stages:

1. gravity (equilibrium): the model settles under its weight until the unbalanced-force ratio < 1e-5;
2. excavation (dynamic): the tunnel's blocks removed (``remove_blocks = ["tunnel*"]``), displacements
   reset; the rock around the opening moves into it for 0.05 s;
3. support (equilibrium): rock bolts 4 m long, radial from the roof, installed (``install_bolts``) and
   the rock settles on them;
4. earthquake (dynamic): the synthetic record at half its amplitude (PGA 0.18 g, horizontal) starts at
   the base; it runs the model's [run] steps (1.5 s), so `srdda run --steps N` shortens it.

Every stage solves its contacts with ``contact_solver = "newton"``: it converges each step's contact
problem to its minimum, which holds a settled model at rest (docs/contacts.md, docs/examples-staged.md).
Run: python examples/stages/tunnel.py (writes tunnel.toml beside it), then srdda run examples/stages/tunnel.toml.
"""
from pathlib import Path

import numpy as np
import shapely
import tomli_w

import srdda
from srdda.io.modelfile import model_to_dict
from srdda.model import JointMaterial

HERE = Path(__file__).parent
RECORD = "../../src/srdda/data/records/synthetic.AT2"  # relative to this folder, as the model file reads it
SCALE = 0.5  # of the record: PGA 0.18 g
size, radius = 30.0, 3.0
centre = np.array([size / 2, size / 2])
domain = np.array([(0, 0), (size, 0), (size, size), (0, size)], dtype=float)
tunnel = srdda.circular_opening(tuple(centre), radius, n_sides=32)
sets = [srdda.JointSet(dip=35.0, spacing=2.5, trace_length=8.0, bridge=1.0, joint_type=1, dip_sd=3.0),
        srdda.JointSet(dip=125.0, spacing=2.5, trace_length=8.0, bridge=1.0, joint_type=2, dip_sd=3.0)]
traces, types = srdda.joint_traces(shapely.Polygon(domain, holes=[tunnel]), sets, seed=11)  # as cutting/tunnel.py
ring = np.asarray(tunnel, dtype=float)
line = np.hstack([ring, np.roll(ring, -1, axis=0)])  # the excavation line, type 3
springline = [[centre[0] - radius - 0.01, centre[1], centre[0] + radius + 0.01, centre[1]]]  # heading | bench
cut = srdda.cut_blocks(np.vstack([traces, line, springline]), np.concatenate([types, np.full(len(line), 3), [3]]),
                       edge_node_distance=0.02, boundary=domain, boundary_type=0)

centroids = shapely.get_coordinates(shapely.centroid(cut.polygons))
inside = shapely.contains_xy(shapely.Polygon(tunnel).buffer(1e-6), *centroids.T)
names = [("tunnel heading" if c[1] > centre[1] else "tunnel bench") if i else f"rock {b}"
         for b, (c, i) in enumerate(zip(centroids, inside))]
model = srdda.Model(gravity=(0.0, -9.81))
model.add_material("granite", srdda.Material(density=2650.0, young=30e9, poisson=0.22, plane="strain"))
model.add_joint_material("set 1", JointMaterial(friction_angle=30.0))
model.add_joint_material("set 2", JointMaterial(friction_angle=25.0))
model.add_joint_material("excavation line", JointMaterial(friction_angle=40.0))
fixed = shapely.distance(cut.polygons, shapely.LinearRing(domain)) < 1e-9
srdda.add_cut_blocks(model, cut, materials={0: "granite"}, joints={1: "set 1", 2: "set 2", 3: "excavation line"},
                     fixed=fixed, names=names)

# radial bolts through the roof, 4 m long, every 30° from 30° to 150°: from just inside the rock
# (r = 3.05 m) into the rock behind the key blocks; one whose ends lie in the same block holds nothing
bolts = []
for angle in np.radians(np.arange(30.0, 151.0, 30.0)):
    u = np.array([np.cos(angle), np.sin(angle)])
    a, b = centre + (radius + 0.05) * u, centre + (radius + 4.0) * u
    block_a, block_b = (int(i) for i in cut.locate([a, b]))
    if block_a != block_b and not fixed[block_a]:
        bolts.append(model.add_bolt(a, b, 2.5e7, pretension=2e4, strength=2.0e5, shear_stiffness=5e6,
                                    block_a=block_a, block_b=block_b, name=f"bolt {len(bolts) + 1}"))
crown = centre + [0.0, radius + 0.05]
model.add_measured_point(crown, block=int(cut.locate([crown])[0]))

model.add_stage(srdda.Stage("gravity", kind="equilibrium", max_steps=4000))
model.add_stage(srdda.Stage("excavation", remove_blocks=["tunnel*"], reset_displacements=True,
                            run={"n_steps": 250}))
model.add_stage(srdda.Stage("support", kind="equilibrium", install_bolts=[f"bolt {i + 1}" for i in range(len(bolts))],
                            max_steps=4000))
settings = srdda.RunSettings(dt=2e-4, n_steps=7500, method="srdda", penalty=50 * 30e9, contact_solver="newton",
                             record_every=10)
data = model_to_dict(model, settings, "circular tunnel in jointed granite, staged")
quake = {"record": RECORD, "scale": SCALE, "baseline": "linear", "components": "x"}
data["stages"].append({"name": "earthquake", "base_acceleration": quake})
header = "".join(f"# {line}\n" for line in [
    "A tunnel in jointed granite, staged: gravity (equilibrium), excavation (the tunnel's blocks removed),",
    f"support ({len(bolts)} rock bolts installed, equilibrium), earthquake (the synthetic record (PGA 0.35 g,",
    "horizontal) at half its amplitude: PGA 0.18 g; the earthquake runs [run] steps: 7500 steps of 0.2 ms = 1.5 s).",
    "docs/examples-staged.md.",
    "Written by examples/stages/tunnel.py."])
(HERE / "tunnel.toml").write_text(header + tomli_w.dumps(data), encoding="utf-8")
print(f"{cut.n_blocks} blocks, {int((~fixed).sum())} free, {len(bolts)} bolts -> {HERE / 'tunnel.toml'}")
