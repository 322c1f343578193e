"""A 3D wedge above a cut slope, staged (srdda.apps.verify.cases.slope3d.wedge_cut_model): equilibrium with the toe in place,
the toe excavated, then the joints weakened to their residual friction.

The tetrahedral wedge of srdda.apps.verify.cases.slope3d (joint planes A 40°/130° and B 60°/220°, slope face
70°/160°, horizontal top 6 m above the point where the line of intersection daylights). Before the cut,
the rock in front of the face up to 2 m above that point, the "toe" (fixed, as intact rock), covers the
daylight point: the line of intersection does not daylight. Stages:

1. gravity (equilibrium): the wedge settles on planes A and B until the unbalanced-force ratio < 1e-5;
2. cut (dynamic): the toe removed (``remove_blocks = ["toe"]``), displacements reset: the wedge
   daylights; with the joints' peak friction (38.31°) its limit-equilibrium factor of safety (Hoek & Bray
   1981, ch. 8) is 1.2 and it stays;
3. residual (dynamic): the joints' friction falls to 27.77° (``joint_materials``): FS 0.8, and the wedge
   slides along the line of intersection at a = g sin ψ_i (1 − FS).

Every stage solves its contacts with ``contact_solver = "newton"``, which holds a settled model at rest
(docs/contacts.md, docs/examples-staged.md). Run: python examples/stages/wedge_cut.py (writes wedge-cut.toml
beside it), then srdda run examples/stages/wedge-cut.toml.
"""
from pathlib import Path

import tomli_w

import srdda
from srdda.apps.verify.cases.slope3d import WEDGE_FACE, WEDGE_PLANES, wedge_cut_model, wedge_friction_for, wedge_solution
from srdda.io.modelfile import model_to_dict

HERE = Path(__file__).parent
PEAK, RESIDUAL, HEIGHT, TOE = 1.2, 0.8, 6.0, 2.0  # factors of safety once daylighting; wedge, toe height (m)

phi, residual = wedge_friction_for(PEAK), wedge_friction_for(RESIDUAL)
peak_solution, solution = wedge_solution(*WEDGE_PLANES, phi), wedge_solution(*WEDGE_PLANES, residual)
model = wedge_cut_model(PEAK, RESIDUAL, HEIGHT, TOE)  # the stages: gravity, cut, residual
settings = srdda.RunSettings(dt=1e-3, n_steps=500, method="srdda", penalty=1e11, contact_solver="newton",
                             record_every=10)
header = "".join(f"# {line}\n" for line in [
    "A 3D wedge above a cut slope, staged: gravity (equilibrium, the toe in place), cut (the toe excavated),",
    "residual (the joints' friction falls to its residual value).",
    f"joint planes A {WEDGE_PLANES[0][0]:g}/{WEDGE_PLANES[0][1]:g}, B {WEDGE_PLANES[1][0]:g}/{WEDGE_PLANES[1][1]:g},"
    f" slope face {WEDGE_FACE[0]:g}/{WEDGE_FACE[1]:g}, top at {HEIGHT:g} m, toe {TOE:g} m high",
    f"line of intersection: plunge {solution.plunge:.4f} deg, trend {solution.trend:.4f} deg",
    f"predicted after the cut: friction {phi:.4f} deg on both planes, FS = {peak_solution.factor_of_safety:.4f}:"
    " the wedge stays;",
    f"residual friction {residual:.4f} deg: FS = {solution.factor_of_safety:.4f}, the wedge slides along the line of"
    f" intersection at a = g sin(psi_i)(1 - FS) = {solution.acceleration:.5f} m/s2",
    "cut and residual run [run] steps each: 500 steps of 1 ms. docs/examples-staged.md.",
    "Written by examples/stages/wedge_cut.py."])
(HERE / "wedge-cut.toml").write_text(header + tomli_w.dumps(model_to_dict(model, settings, "wedge above a cut slope")),
                                     encoding="utf-8")
print(f"friction {phi:.4f} then {residual:.4f} deg, FS {peak_solution.factor_of_safety:.4f} then"
      f" {solution.factor_of_safety:.4f}, a = {solution.acceleration:.5f} m/s2"
      f" -> {HERE / 'wedge-cut.toml'}")
