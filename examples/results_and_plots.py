"""Write a run to a results file, resume it, and look at it: figures, a GIF, ParaView files.

Run: python examples/results_and_plots.py [OUT_DIR]   (default: out/results_demo)
"""
import sys
from pathlib import Path

import srdda
from srdda.apps import plotting
from srdda.apps.animation import animate
from srdda.io.vtk import write_vtu_series

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/results_demo")
out.mkdir(parents=True, exist_ok=True)

model = srdda.Model(gravity=(0.0, -9.81))
model.add_material("granite", srdda.Material(density=2700.0, young=50e9, poisson=0.25))
slab = model.add_block([[0, 0], [2, 0], [2, 0.5], [0, 0.5]], "granite", name="slab")
model.add_fixed_point([0.0, 0.5], block=slab, stiffness=1e12)
model.add_measured_point([2.0, 0.0], block=slab)

results = {}
for method in srdda.METHODS:
    settings = srdda.RunSettings(dt=1e-3, n_steps=1500, method=method, penalty=1e12)
    path = out / f"slab_{method}.h5"
    # flush every 100 recorded steps: a killed run keeps them, and srdda.resume(path) continues it
    srdda.run(model, settings, recorders=[srdda.ResultsStore(path, settings, flush_every=100)])
    results[method] = srdda.read_results(path)

plotting.fig_swing_trajectories(results, pivot=(0.0, 0.5)).savefig(out / "trajectories.png", dpi=100)
plotting.fig_time_series(results, "energy.total").savefig(out / "energy.png", dpi=100)
plotting.fig_model(results["dda0"], -1, color="area_change").savefig(out / "dda0_last_step.png", dpi=100)
print("wrote", animate(results["srdda"], out / "slab.gif", max_frames=60))
print("wrote", write_vtu_series(results["srdda"], out / "vtk", every=50))
