"""Time of 3D block cutting on the jointed slope of examples/solid/jointed-slope-3d.toml.

Cuts the example's domain (five convex parts) by its three joint sets with
every spacing multiplied by each --scale factor (smaller: more blocks), and
reports joints, blocks, skipped cuts, the best of --repeat times of
``cut_polyhedra`` (the numba kernel plus the final validation of every
fragment) and of adding the blocks to a Model (``add_cut_polyhedra``, one
batch validation), and the relative volume error against the domain.

Usage: python benchmarks/bench_cutting3d.py [--scale 1,0.6,0.4] [--repeat 3] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import platform
import time
import tomllib
import warnings
from pathlib import Path

import numpy as np

from srdda.cutmodel import add_cut_polyhedra
from srdda.geometry.cutting3d import convex_hull_polyhedron
from srdda.geometry.polyhedron import PolyhedronMesh, box, polyhedron_moments
from srdda.io.modelfile import cut_section
from srdda.io.schema import CutDomainSection, CuttingSection
from srdda.model import Material, Model

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "solid" / "jointed-slope-3d.toml"


def best_time(fn, repeat: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scale", default="1,0.6,0.4", help="factors on every joint set's spacing")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    section = tomllib.loads(EXAMPLE.read_text(encoding="utf-8"))["cutting"]
    warnings.simplefilter("ignore")
    rows = []
    cut_section(CuttingSection.model_validate(section))  # compile (or load) the numba kernels first
    for scale in (float(s) for s in args.scale.split(",")):
        data = dict(section, joint_sets=[dict(js, spacing=float(js["spacing"].split()[0]) * scale)
                                         for js in section["joint_sets"]])
        spec = CuttingSection.model_validate(data)
        t_cut, cut = best_time(lambda spec=spec: cut_section(spec), args.repeat)

        def build(cut=cut) -> Model:
            model = Model(gravity=(0.0, 0.0, -9.81))
            model.add_material("rock", Material(2600.0, 1e10, 0.25))
            add_cut_polyhedra(model, cut, "rock")
            return model

        t_model, _ = best_time(build, args.repeat)
        parts = PolyhedronMesh.from_blocks([_part(d) for d in spec.domain])
        exact = polyhedron_moments(parts.vertices, parts).volume.sum()
        row = {"scale": scale, "blocks": cut.n_blocks, "vertices": len(cut.vertices),
               "skipped": len(cut.skipped), "rejected": len(cut.rejected), "cut_s": round(t_cut, 3),
               "model_s": round(t_model, 3), "volume_rel_error": float(cut.volumes().sum() / exact - 1)}
        rows.append(row)
        print(row)
    if args.json:
        args.json.write_text(json.dumps({"machine": platform.processor() or platform.machine(), "rows": rows},
                                        indent=1))


def _part(d: CutDomainSection) -> tuple[np.ndarray, list]:
    """One domain part as (vertices, faces), as the [cutting] section reads it."""
    if d.box is not None:
        return box(*d.box)
    return (np.array(d.vertices), d.faces) if d.faces is not None else convex_hull_polyhedron(d.vertices)


if __name__ == "__main__":
    main()
