"""Build a model in Python, run it under the three methods, and compare.

A 2 x 0.5 m slab pinned at one corner swings down under gravity; DDA0's linear
update inflates it, DDA1 and SRDDA keep its area.  Run: python examples/python_api.py
"""
import srdda

model = srdda.Model(gravity=(0.0, -9.81))
model.add_material("sandstone", srdda.Material(density=2400.0, young=15e9, poisson=0.25, plane="strain"))
slab = model.add_block([[0, 0], [2, 0], [2, 0.5], [0, 0.5]], "sandstone", name="slab")
model.add_fixed_point([0.0, 0.5], block=slab, stiffness=1e12)  # a pin (penalty spring, N/m)
tip = model.add_measured_point([2.0, 0.0], block=slab)

for method in srdda.METHODS:
    result = srdda.run(model, srdda.RunSettings(dt=1e-3, n_steps=2000, method=method, penalty=1e12))
    area = result.array("area")[:, slab]
    omega = result.array("velocity")[:, slab, 2]
    x, y = result.array("measured_position")[-1, tip]
    print(f"{method:6s} area change {area[-1] / area[0] - 1:+.2e}  max |ω| {abs(omega).max():.4f} rad/s  "
          f"tip at ({x:.3f}, {y:.3f}) m")
