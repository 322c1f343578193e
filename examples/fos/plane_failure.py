"""Hoek & Bray's plane failure as model files for `srdda fos` (srdda.apps.verify.cases.plane_failure; docs/factor-of-safety.md).

Writes beside this script plane-failure.toml: a 12 m slope with a 60° face, a sliding plane dipping 30°
that daylights at the toe, a dry tension crack, c = 20 kPa and φ = 25° on the plane; and plane-failure-wet.toml:
the same slope with Hoek & Bray's water, the crack full and the phreatic line from its water surface to the toe.
Each file opens with Hoek & Bray's factor of safety. Then: srdda fos examples/fos/plane-failure.toml
Run: python examples/fos/plane_failure.py
"""
from pathlib import Path

import tomli_w

from srdda import RunSettings
from srdda.apps.verify.cases.plane_failure import PLANE_FAILURE, plane_failure_model
from srdda.io.modelfile import model_to_dict

HERE = Path(__file__).parent
case = PLANE_FAILURE
settings = RunSettings(dt=1e-3, n_steps=1000, contact_penalty=1e10)
depth = case.crack_depth
uplift, crack = case.water_forces(depth)
for name, water_depth, title, water, formula, fs in (
        ("plane-failure.toml", None, "plane failure (Hoek & Bray), dry", "dry tension crack",
         "[cA + W cos psi tan phi] / (W sin psi)", case.factor_of_safety()),
        ("plane-failure-wet.toml", depth, "plane failure (Hoek & Bray), tension crack full of water",
         f"tension crack full (z_w = {depth:.3f} m), phreatic line to the toe: U = 1/2 gamma_w z_w A = "
         f"{uplift:.6g} N/m, V = 1/2 gamma_w z_w^2 = {crack:.6g} N/m",
         "[cA + (W cos psi - U - V sin psi) tan phi] / (W sin psi + V cos psi)",
         case.factor_of_safety(uplift, crack))):
    lines = [title,
             f"slope {case.height:g} m, face {case.face:g} deg, sliding plane {case.plane:g} deg daylighting at the "
             f"toe, tension crack {depth:.3f} m deep",
             water,
             f"c = {case.cohesion / 1e3:g} kPa, phi = {case.friction:g} deg; W = {case.weight:.6g} N/m, "
             f"A = {case.length:.6g} m",
             f"predicted: FS = {formula} = {fs:.4f}",
             "block E = 1e12 Pa, 100 x stiffer than the contacts (docs/factor-of-safety.md, Cohesion)",
             "Written by examples/fos/plane_failure.py."]
    text = "".join(f"# {line}\n" for line in lines) + tomli_w.dumps(
        model_to_dict(plane_failure_model(case, young=1e12, water_depth=water_depth), settings, title))
    (HERE / name).write_text(text, encoding="utf-8")
    print(f"{name}: {title}, FS = {fs:.4f}")
