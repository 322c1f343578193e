"""Hoek & Bray's plane failure as a model file for `srdda fos` (srdda.cases.plane2d; docs/factor-of-safety.md).

Writes plane-failure.toml beside this script: a 12 m slope with a 60° face, a sliding plane dipping 30°
that daylights at the toe, a dry tension crack, c = 20 kPa and φ = 25° on the plane; the file opens with
Hoek & Bray's factor of safety. Then: srdda fos examples/fos/plane-failure.toml
Run: python examples/fos/plane_failure.py
"""
from pathlib import Path

import tomli_w

from srdda import RunSettings
from srdda.cases.plane2d import PLANE_FAILURE, plane_failure_model
from srdda.io.modelfile import model_to_dict

HERE = Path(__file__).parent
case = PLANE_FAILURE
title = "plane failure (Hoek & Bray), dry"
lines = [title,
         f"slope {case.height:g} m, face {case.face:g} deg, sliding plane {case.plane:g} deg daylighting at the toe, "
         f"tension crack {case.crack_depth:.3f} m deep",
         f"c = {case.cohesion / 1e3:g} kPa, phi = {case.friction:g} deg; W = {case.weight:.6g} N/m, "
         f"A = {case.length:.6g} m",
         f"predicted: FS = [cA + W cos psi tan phi] / (W sin psi) = {case.factor_of_safety():.4f}",
         "block E = 1e12 Pa, 100 x stiffer than the contacts (docs/factor-of-safety.md, Cohesion)",
         "Written by examples/fos/plane_failure.py."]
settings = RunSettings(dt=1e-3, n_steps=1000, contact_penalty=1e10)
text = "".join(f"# {line}\n" for line in lines) + tomli_w.dumps(
    model_to_dict(plane_failure_model(case, young=1e12), settings, title))
(HERE / "plane-failure.toml").write_text(text, encoding="utf-8")
print(f"plane-failure.toml: {title}, FS = {case.factor_of_safety():.4f}")
