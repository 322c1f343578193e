"""The classical 3D rock-slope checks as model files (srdda.apps.verify.cases.slope3d; docs/slope-checks-3d.md).

Writes, beside this script:
- slide-topple-<region>.toml: a block on a 30° incline, one case in each region of the sliding /
  toppling chart (stable, slides, topples, slides and topples);
- wedge-fs1.2.toml, wedge-fs0.8.toml: the tetrahedral wedge on joint planes 40°/130° and 60°/220°
  (slope face 70°/160°, horizontal top) with the friction angle that gives a limit-equilibrium
  factor of safety of 1.2 (it stays) and 0.8 (it slides along the line of intersection).
Each file opens with the closed-form prediction. They need 3D contacts to run.
Run: python examples/solid/slope_checks.py
"""
import math
from dataclasses import replace
from pathlib import Path

import tomli_w

from srdda import RunSettings
from srdda.apps.verify.cases.slope3d import (SLIDE_TOPPLE_CASES, WEDGE_FACE, WEDGE_PLANES, incline_acceleration,
                                 slide_topple_model, toppling_angular_acceleration, wedge_friction_for, wedge_model,
                                 wedge_solution)
from srdda.io.modelfile import model_to_dict

HERE = Path(__file__).parent
SETTINGS = RunSettings(dt=1e-3, n_steps=1000, method="srdda")


def write(model, title: str, lines: list[str], name: str, penalty: float) -> None:
    """The model file ``name`` with the run settings of its verification case (k_n = ``penalty``)."""
    header = "".join(f"# {line}\n" for line in [title, *lines, "Written by examples/solid/slope_checks.py."])
    text = header + tomli_w.dumps(model_to_dict(model, replace(SETTINGS, penalty=penalty), title))
    (HERE / name).write_text(text, encoding="utf-8")
    print(f"{name}: {title}")


for case in SLIDE_TOPPLE_CASES:
    a = incline_acceleration(case.psi, case.phi)
    alpha = toppling_angular_acceleration(case.psi, case.base, case.height)
    write(slide_topple_model(case), f"block on a {case.psi:g} deg incline: {case.mode}",
          [f"friction {case.phi:g} deg, base {case.base:g} m along the dip, height {case.height:g} m "
           f"(b/h = {case.base / case.height:.3g}, tan psi = {math.tan(math.radians(case.psi)):.3g})",
           f"predicted: {case.mode}; sliding acceleration g(sin psi - cos psi tan phi) = {a:.4f} m/s2"
           + (f"; initial toppling angular acceleration about the down-dip edge {alpha:.4f} rad/s2"
              if alpha > 0 and a == 0 else "")],
          f"slide-topple-{case.name.replace(' ', '-')}.toml", penalty=1e10)  # as srdda verify slide-topple-3d

for fs in (1.2, 0.8):
    phi = wedge_friction_for(fs)
    s = wedge_solution(*WEDGE_PLANES, phi)
    write(wedge_model(phi), f"tetrahedral wedge, factor of safety {fs:g}",
          [f"joint planes A {WEDGE_PLANES[0][0]:g}/{WEDGE_PLANES[0][1]:g}, B {WEDGE_PLANES[1][0]:g}/"
           f"{WEDGE_PLANES[1][1]:g} (dip/dip direction), slope face {WEDGE_FACE[0]:g}/{WEDGE_FACE[1]:g}, top "
           f"horizontal at 6 m; friction {phi:.4f} deg on both planes",
           f"line of intersection: plunge {s.plunge:.4f} deg, trend {s.trend:.4f} deg; N_A/W = {s.normal_a:.5f}, "
           f"N_B/W = {s.normal_b:.5f}",
           f"predicted: FS = {s.factor_of_safety:.4f}; "
           + ("the wedge stays" if fs >= 1 else
              f"slides along the line of intersection at a = g sin(psi_i)(1 - FS) = {s.acceleration:.5f} m/s2")],
          f"wedge-fs{fs:g}.toml", penalty=1e11)  # as srdda verify wedge-3d
