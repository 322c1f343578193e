"""Read and write srdda model files (TOML, schema in :mod:`srdda.io.schema`).

``load_model(path)`` returns ``(Model, RunSettings)``; every problem in the
file is reported as one :class:`ModelFileError` whose message names the file,
the field (e.g. ``blocks[2].vertices``) and the problem.
"""
from __future__ import annotations

import dataclasses
import math
import tomllib
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
from pydantic import ValidationError

from ..cutmodel import add_cut_polyhedra
from ..history import HistoryError, MotionHistory
from ..geometry.cutting2d import CuttingError
from ..geometry.cutting3d import PolyhedralCut, convex_hull_polyhedron, cut_polyhedra
from ..geometry.jointsets3d import JointPlanes, JointSet3D, joint_planes, plane_normal
from ..geometry.polygon import PolygonError
from ..geometry.polyhedron import PolyhedronError, box
from ..model import JointMaterial, Load, Material, Model, ModelError
from ..settings import RunSettings
from .records import RecordError, record_history
from ..stages import Stage, resolve_stages
from .schema import (BaseAccelerationSection, BlockSection, CuttingSection, HistorySection, JointMaterialSection,
                     ModelFile, StageSection)

__all__ = ["ModelFileError", "load_model", "read_model_text", "model_from_dict", "save_model", "model_to_dict",
           "format_validation", "cut_section"]


class ModelFileError(ValueError):
    """A model file is unreadable or invalid; the message names the field."""


def _field_path(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in ("function-after[_increasing()]",) or str(part).startswith("function-"):
            continue
        else:
            out += ("." if out else "") + str(part)
    return out or "(top level)"


def format_validation(exc: ValidationError, source: str, what: str = "invalid model file") -> str:
    """One message for every problem of a validation error, each line naming its field."""
    lines = [f"{source}: {what}"]
    for err in exc.errors():
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] in ("extra_forbidden", "unexpected_keyword_argument"):
            msg = "unknown field (check the spelling)"
        elif err["type"] == "missing":
            msg = "required field is missing"
        lines.append(f"  {_field_path(err['loc'])}: {msg}")
    return "\n".join(lines)


def _block_index(ref: str | int | None, names: dict[str, int], n: int, where: str) -> int | None:
    if ref is None:
        return None
    if isinstance(ref, int):
        if not 0 <= ref < n:
            raise ModelFileError(f"{where}: block index {ref} out of range (0..{n - 1})")
        return ref
    if ref not in names:
        raise ModelFileError(f"{where}: no block named {ref!r}")
    return names[ref]


def model_from_dict(data: dict[str, Any], source: str = "model", base_dir: str | Path | None = None
                    ) -> tuple[Model, RunSettings]:
    """Validate a model-file dictionary and build the model and its run settings.

    ``base_dir``: the folder that relative file names (earthquake records) are
    relative to (default: the current directory).
    """
    if isinstance(data, dict) and "runs" in data and "model" in data and "blocks" not in data:
        raise ModelFileError(f"{source}: this is an ensemble file (it names a base model and a number of runs), "
                             "not a model file: run it with `srdda ensemble` (docs/ensembles.md)")
    try:
        spec = ModelFile.model_validate(data)
    except ValidationError as exc:
        raise ModelFileError(format_validation(exc, source)) from None
    try:
        return _build(spec, source, Path(base_dir) if base_dir is not None else Path())
    except (ModelError, PolygonError, ValueError) as exc:
        if isinstance(exc, ModelFileError):
            raise
        raise ModelFileError(f"{source}: {exc}") from None


def _build(spec: ModelFile, source: str, base_dir: Path) -> tuple[Model, RunSettings]:
    model = Model(gravity=spec.gravity, allow_overlap=spec.allow_overlap)
    for name, m in spec.materials.items():
        model.add_material(name, Material(m.density, m.young, m.poisson, m.plane))
    for name, j in spec.joint_materials.items():
        model.add_joint_material(name, _joint_material(j), j.between)
    names: dict[str, int] = {}
    for i, b in enumerate(spec.blocks):
        label = b.name or f"block {i}"
        if b.material not in spec.materials:
            raise ModelFileError(f"{source}: blocks[{i}].material: unknown material {b.material!r}")
        try:
            _add_block(model, b, label)
        except (ModelError, PolygonError, PolyhedronError) as exc:
            raise ModelFileError(f"{source}: blocks[{i}]: {exc}") from None
        if b.name is not None:
            if b.name in names:
                raise ModelFileError(f"{source}: blocks[{i}].name: duplicate block name {b.name!r}")
            names[b.name] = i
    if spec.cutting is not None:
        try:
            _add_cutting(model, spec.cutting)
        except (ModelError, CuttingError, PolyhedronError) as exc:
            raise ModelFileError(f"{source}: cutting: {exc}") from None
        names.update({b.name: i for i, b in enumerate(model.blocks) if i >= len(spec.blocks)})
    if not model.blocks:
        raise ModelFileError(f"{source}: the model has no blocks; give [[blocks]] or a [cutting] section")
    n = len(model.blocks)

    def where(section: str, i: int) -> str:
        return f"{source}: {section}[{i}]"

    try:
        for i, f in enumerate(spec.fixed_points):
            model.add_fixed_point(f.at, _block_index(f.block, names, n, where("fixed_points", i)), f.stiffness)
        for i, p in enumerate(spec.point_loads):
            if (p.force is None) == (p.table is None):
                raise ModelFileError(f"{where('point_loads', i)}: give exactly one of 'force' or 'table'")
            load = Load.of(p.force if p.force is not None else np.array(p.table))
            model.add_point_load(p.at, load, _block_index(p.block, names, n, where("point_loads", i)))
        for i, s in enumerate(spec.point_springs):
            model.add_point_spring(s.a, s.b, s.stiffness, _block_index(s.block_a, names, n, where("point_springs", i)),
                                   _block_index(s.block_b, names, n, where("point_springs", i)))
        for i, mp in enumerate(spec.measured_points):
            model.add_measured_point(mp.at, _block_index(mp.block, names, n, where("measured_points", i)))
        _add_links(model, spec, names, n, where)
        if spec.base_acceleration is not None:
            model.set_base_acceleration(_base_acceleration(spec.base_acceleration, model.dim, base_dir, source))
        if spec.water is not None:
            w = spec.water
            model.set_water(w.level, w.point, w.normal, w.unit_weight, [(c.point, c.normal, c.depth) for c in w.cracks])
        for k, stage in enumerate(spec.stages):
            model.add_stage(_stage(stage, model.dim, base_dir, f"{source}: stages[{k}]"))
        resolve_stages(model, model.stages)  # the names they give, checked now
    except ModelError as exc:
        raise ModelFileError(f"{source}: {exc}") from None
    return model, spec.run


def _joint_material(j: JointMaterialSection) -> JointMaterial:
    return JointMaterial(j.friction_angle, j.cohesion, j.tensile_strength, j.normal_stiffness, j.shear_stiffness,
                         j.restitution)


def _stage(section: StageSection, dim: int, base_dir: Path, where: str) -> Stage:
    """A ``[[stages]]`` table as a :class:`Stage` (its names are checked against the model by the caller)."""
    for name, j in section.joint_materials.items():
        if j.between:
            raise ModelFileError(f"{where}.joint_materials.{name}.between: a stage changes a joint material's "
                                 "properties, not the materials it joins")
    base = None if section.base_acceleration is None else _base_acceleration(section.base_acceleration, dim,
                                                                               base_dir, where)
    return Stage(section.name, section.kind, section.remove_blocks, section.install_bolts, section.fix_blocks,
                 section.free_blocks, base,
                 {n: Material(m.density, m.young, m.poisson, m.plane) for n, m in section.materials.items()},
                 {n: _joint_material(j) for n, j in section.joint_materials.items()}, section.run,
                 section.tolerance, section.max_steps, section.reset_displacements, section.water_level)


def _add_block(model: Model, b: BlockSection, label: str) -> None:
    """A polygon (``vertices``) or a polyhedron (``vertices`` + ``faces``, or ``box``)."""
    solid = b.faces is not None or b.box is not None
    if (b.vertices is None) == (b.box is None) or (b.box is not None and b.faces is not None):
        raise ModelError("give 'vertices' (with 'faces' for a polyhedron) or 'box', exactly one")
    if not solid:
        assert b.vertices is not None  # no box: vertices (checked above)
        if b.edge_joints is not None and len(b.edge_joints) == 0:
            raise ModelError("edge_joints is empty")
        joints = None if b.edge_joints is None else [j or None for j in b.edge_joints]
        stress = b.stress
        if isinstance(b.angular_velocity, tuple) or len(stress) != 3:
            raise ModelError("a polygon has a scalar angular_velocity and stress [sx, sy, txy]")
        model.add_block(b.vertices, b.material, b.velocity or (0.0, 0.0), b.angular_velocity, stress, label,
                        b.fixed, joints)
        return
    if b.edge_joints is not None:
        raise ModelError("edge_joints are for polygons (2D)")
    vertices: Sequence[Sequence[float]] | np.ndarray
    faces: Sequence[Sequence[int] | np.ndarray]
    if b.box is not None:
        vertices, faces = box(*b.box, label)
    else:
        assert b.vertices is not None and b.faces is not None  # a polyhedron without a box (checked above)
        vertices, faces = b.vertices, b.faces
    omega = b.angular_velocity if isinstance(b.angular_velocity, tuple) else (0.0, 0.0, b.angular_velocity)
    stress = b.stress if len(b.stress) == 6 else (b.stress[0], b.stress[1], 0.0, 0.0, 0.0, b.stress[2])
    model.add_polyhedron(vertices, faces, b.material, b.velocity or (0.0, 0.0, 0.0), omega, stress, label, b.fixed)


def cut_section(c: CuttingSection) -> PolyhedralCut:
    """The 3D cut a ``[cutting]`` section describes: its convex domain parts cut by its joint sets and joints."""
    parts: list[tuple[object, object]] = []
    for k, d in enumerate(c.domain):
        where = f"domain[{k}]"
        if (d.box is None) == (d.vertices is None) or (d.faces is not None and d.vertices is None):
            raise ModelError(f"{where}: give 'box', or 'vertices' (with 'faces', or without: their convex hull)")
        if d.box is not None:
            parts.append(box(*d.box, where))
        else:
            parts.append((d.vertices, d.faces) if d.faces is not None else convex_hull_polyhedron(d.vertices, where))
    sets = [JointSet3D(s.dip, s.dip_direction, s.spacing, s.kappa, s.persistence, s.radius, s.joint_type, s.origin,
                       s.spacing_sd) for s in c.joint_sets]
    points = np.concatenate([np.asarray(v, dtype=float) for v, _ in parts])
    single = JointPlanes.of([plane_normal(j.dip, j.dip_direction) for j in c.joints], [j.point for j in c.joints],
                            [np.inf if j.radius is None else j.radius for j in c.joints],
                            np.array([j.joint_type for j in c.joints], dtype=np.int64))
    joints = JointPlanes.concatenate([joint_planes(points, sets, c.seed), single])
    return cut_polyhedra(parts, joints, min_volume=c.min_volume, min_thickness=c.min_thickness)


def _add_cutting(model: Model, c: CuttingSection) -> None:
    """3D blocks cut as the section says (docs/cutting-3d.md), fixed by part or by ``fixed_box``."""
    for k, d in enumerate(c.domain):
        if d.material not in model.materials:
            raise ModelError(f"domain[{k}].material: unknown material {d.material!r}")
    cut = cut_section(c)
    fixed = np.array([c.domain[p].fixed for p in cut.block_part], dtype=bool)
    if c.fixed_box is not None:
        centroid = cut.centroids()
        fixed |= np.all((centroid >= c.fixed_box[0]) & (centroid <= c.fixed_box[1]), axis=1)
    if cut.skipped or cut.rejected:
        reasons = sorted({s.reason for s in cut.skipped})
        warnings.warn(f"cutting: {len(cut.skipped)} joint cut(s) skipped ({'; '.join(reasons) or 'none'}), "
                      f"{len(cut.rejected)} fragment(s) rejected; srdda.cut_polyhedra lists them", stacklevel=2)
    add_cut_polyhedra(model, cut, {k: d.material for k, d in enumerate(c.domain)}, fixed, prefix="cut",
                      joints=_cut_joint_materials(model, c))


def _cut_joint_materials(model: Model, c: CuttingSection) -> dict[int, str]:
    """Joint type -> joint material of the sets and joints that name one (one material per type)."""
    out: dict[int, str] = {}
    named = [(f"joint_sets[{k}]", s) for k, s in enumerate(c.joint_sets)] + \
        [(f"joints[{k}]", j) for k, j in enumerate(c.joints)]
    for where, j in named:
        if j.joint_material is None:
            continue
        if j.joint_material not in model.joint_materials:
            raise ModelError(f"{where}.joint_material: unknown joint material {j.joint_material!r}")
        if out.setdefault(j.joint_type, j.joint_material) != j.joint_material:
            raise ModelError(f"{where}.joint_material: joint_type {j.joint_type} already has joint material "
                             f"{out[j.joint_type]!r}; give this set its own joint_type")
    return out


def _history(h: HistorySection, where: str) -> MotionHistory:
    given = [h.constant is not None, h.table is not None, h.amplitude is not None]
    try:
        if sum(given) != 1:
            raise HistoryError("give exactly one of 'constant', 'table', or 'amplitude' with 'period'")
        if h.table is not None:
            return MotionHistory(table=np.array(h.table, dtype=float))
        if h.amplitude is not None:
            return MotionHistory(amplitude=h.amplitude, period=h.period, phase=h.phase)
        return MotionHistory(constant=h.constant)
    except HistoryError as exc:
        raise ModelFileError(f"{where}.history: {exc}") from None


def _add_links(model: Model, spec: ModelFile, names: dict[str, int], n: int, where: Any) -> None:
    """Hinges, pins, springs, prescribed motion and base acceleration (srdda.constraints)."""
    for i, h in enumerate(spec.hinges):
        w = where("hinges", i)
        model.add_hinge(h.at, _block_index(h.block_a, names, n, w), _block_index(h.block_b, names, n, w), h.at_b,
                        h.correct_drift, h.name)
    for i, p in enumerate(spec.pins):
        model.add_pin(p.at, _block_index(p.block, names, n, where("pins", i)), p.correct_drift, p.name)
    for i, s in enumerate(spec.springs):
        w = where("springs", i)
        model.add_spring(s.a, s.b, s.stiffness, s.rest_length, s.damping, s.kind,
                         _block_index(s.block_a, names, n, w), _block_index(s.block_b, names, n, w))
    for i, pm in enumerate(spec.prescribed_motion):
        w = where("prescribed_motion", i)
        model.add_prescribed_motion(pm.at, _history(pm.history, w), pm.quantity, pm.components, pm.by, pm.stiffness,
                                    _block_index(pm.block, names, n, w))
    for i, b in enumerate(spec.bolts):
        w = where("bolts", i)
        ground = b.block_b == "ground"
        model.add_bolt(b.a, b.b, b.stiffness, b.pretension, b.strength, b.shear_stiffness,
                       _block_index(b.block_a, names, n, w), -1 if ground else _block_index(b.block_b, names, n, w),
                       b.name or f"bolt {i}")


def _base_acceleration(section: BaseAccelerationSection, dim: int, base_dir: Path, source: str) -> MotionHistory:
    """The ground acceleration: a record file (srdda.io.records) or a history; ``source`` starts the messages."""
    record_options = {"format": None, "units": None, "scale": 1.0, "baseline": "none", "components": None}
    if section.record is None:
        given = [k for k, default in record_options.items() if getattr(section, k) != default]
        if given:
            raise ModelFileError(f"{source}: base_acceleration: {', '.join(given)} apply to a record; give "
                                 "'record' (an .AT2 or .csv file) or leave them out")
        return _history(section, "base_acceleration")
    if any(v is not None for v in (section.constant, section.table, section.amplitude)):
        raise ModelFileError(f"{source}: base_acceleration: give either 'record' or a history (constant, table, "
                             "amplitude), not both")
    path = Path(section.record)
    try:
        return record_history(path if path.is_absolute() else base_dir / path, dim, section.format, section.units,
                              section.scale, section.baseline, section.components)
    except RecordError as exc:
        raise ModelFileError(f"{source}: base_acceleration.record: {exc}") from None


def _history_dict(h: MotionHistory, what: str) -> dict[str, Any]:
    if h.function is not None:
        raise ModelFileError(f"{what} is a Python callable and cannot be written to a file")
    if h.table is not None:
        return {"table": np.asarray(h.table).tolist()}
    if h.amplitude is not None:
        return {"amplitude": list(h.amplitude), "period": h.period, "phase": h.phase}
    assert h.constant is not None  # a history is exactly one form
    return {"constant": list(h.constant)}


def _links_dict(model: Model) -> dict[str, Any]:
    out: dict[str, Any] = {}
    hinges = [h for h in model.hinges if h.block_b >= 0]
    pins = [h for h in model.hinges if h.block_b < 0]
    if hinges:
        out["hinges"] = [{"at": _pt(h.point_a), "at_b": _pt(h.point_b), "block_a": h.block_a, "block_b": h.block_b,
                          "correct_drift": h.correct_drift, "name": h.name} for h in hinges]
    if pins:
        out["pins"] = [{"at": _pt(h.point_a), "block": h.block_a, "correct_drift": h.correct_drift, "name": h.name}
                       for h in pins]
    if model.springs:
        out["springs"] = [{"a": _pt(s.point_a), "b": _pt(s.point_b), "block_a": s.block_a, "block_b": s.block_b,
                           "stiffness": s.stiffness, "damping": s.damping, "kind": s.kind,
                           **({} if s.rest_length is None else {"rest_length": s.rest_length})}
                          for s in model.springs]
    if model.prescribed:
        out["prescribed_motion"] = [
            {"at": _pt(p.point), "block": p.block, "history": _history_dict(p.history, f"prescribed motion at "
                                                                                     f"{_pt(p.point)}"),
             "quantity": p.quantity, "components": "".join(a for a, on in zip("xyz", p.components) if on), "by": p.by,
             **({} if p.stiffness is None else {"stiffness": p.stiffness})}
            for p in model.prescribed]
    if model.base_acceleration is not None:
        out["base_acceleration"] = _history_dict(model.base_acceleration, "base acceleration")
    if model.bolts:
        out["bolts"] = [{"a": _pt(b.point_a), "b": _pt(b.point_b), "block_a": b.block_a,
                         "block_b": "ground" if b.block_b < 0 else b.block_b, "stiffness": b.stiffness,
                         "pretension": b.pretension, "shear_stiffness": b.shear_stiffness, "name": b.name,
                         **({} if math.isinf(b.strength) else {"strength": b.strength})} for b in model.bolts]
    return out


def read_model_text(path: str | Path) -> str:
    """The text of a model file (UTF-8, a leading byte-order mark dropped); :class:`ModelFileError` if it is none."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ModelFileError(f"{p}: cannot read the model file ({exc.strerror})") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise ModelFileError(f"{p}: not a UTF-8 text file (byte 0x{raw[exc.start]:02x} on line {line} is not UTF-8; "
                             "a model file is TOML text saved as UTF-8)") from None
    if "\x00" in text:
        raise ModelFileError(f"{p}: not a text file (it holds NUL bytes; a model file is TOML text)")
    return text


def load_model(path: str | Path) -> tuple[Model, RunSettings]:
    """Read a TOML model file; raises :class:`ModelFileError` with a clear message."""
    p = Path(path)
    text = read_model_text(p)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(f"{p}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ModelFileError(f"{p}: not valid TOML (arrays or tables nested too deeply)") from None
    except ValueError:  # int() in tomllib refuses integers of more than 4300 digits
        raise ModelFileError(f"{p}: not valid TOML (an integer has more digits than Python reads, 4300; no model "
                             "value needs that many)") from None
    return model_from_dict(data, str(p), p.parent)


def _pt(p: np.ndarray) -> list[float]:
    return [float(c) for c in p]


def _run_dict(settings: RunSettings) -> dict[str, Any]:
    """The ``[run]`` table: every field that is set (None fields are left out, ``n_steps`` is ``steps``)."""
    fields = {k: v for k, v in dataclasses.asdict(settings).items() if v is not None}
    if "n_steps" in fields:
        fields["steps"] = fields.pop("n_steps")
    return fields


def model_to_dict(model: Model, settings: RunSettings, title: str = "") -> dict[str, Any]:
    """The model-file dictionary of a model (loads given as callables cannot be written)."""
    mats = list(model.materials)
    run = _run_dict(settings)
    out: dict[str, Any] = {"title": title, "units": "SI", "gravity": list(map(float, model.gravity)), "run": run,
                           **({"allow_overlap": True} if model.allow_overlap else {}),
                           "materials": {n: {"density": m.density, "young": m.young, "poisson": m.poisson,
                                             "plane": m.plane} for n, m in model.materials.items()}}
    if model.joint_materials:
        out["joint_materials"] = {
            n: {"friction_angle": j.friction_angle, "cohesion": j.cohesion, "tensile_strength": j.tensile_strength,
                **{k: getattr(j, k) for k in ("normal_stiffness", "shear_stiffness", "restitution")
                   if getattr(j, k) is not None},
                "between": [list(k) for k, v in model.joint_map.items() if v == n]}
            for n, j in model.joint_materials.items()}
    blocks = []
    for b in model.blocks:
        entry: dict[str, Any] = {"name": b.name, "material": mats[b.material],
                                 "vertices": [_pt(v) for v in b.vertices]}
        if b.faces is not None:
            entry["faces"] = [[int(i) for i in f] for f in b.faces]
        dim = len(b.vertices[0])
        if any(b.velocity):
            entry["velocity"] = list(b.velocity[:dim])
            entry["angular_velocity"] = list(b.velocity[dim:]) if b.faces is not None else b.velocity[dim]
        if any(b.stress):
            entry["stress"] = list(b.stress)
        if b.fixed:
            entry["fixed"] = True
        if b.edge_joints is not None:
            entry["edge_joints"] = [j if j is not None else "" for j in b.edge_joints]
        blocks.append(entry)
    out["blocks"] = blocks
    if model.fixed_points:
        out["fixed_points"] = [{"at": _pt(p), "block": i, **({} if math.isnan(k) else {"stiffness": k})}
                               for i, p, k in model.fixed_points]
    loads = []
    for i, p, ld in model.point_loads:
        if ld.function is not None:
            raise ModelFileError(f"point load at {_pt(p)} is a Python callable and cannot be written to a file")
        entry = {"at": _pt(p), "block": i}
        if ld.table is not None:
            entry["table"] = ld.table.tolist()
        elif ld.constant is not None:
            entry["force"] = list(ld.constant)
        else:  # a sine: a model file's point load is a force or a table
            raise ModelFileError(f"point load at {_pt(p)} is a sine history, which a model file cannot hold "
                                 "(give a force or a table)")
        loads.append(entry)
    if loads:
        out["point_loads"] = loads
    if model.point_springs:
        out["point_springs"] = [{"a": _pt(pa), "b": _pt(pb), "block_a": a, "block_b": b, "stiffness": k}
                                for a, pa, b, pb, k in model.point_springs]
    if model.measured_points:
        out["measured_points"] = [{"at": _pt(p), "block": i} for i, p in model.measured_points]
    out.update(_links_dict(model))
    if model.water is not None:
        w = model.water
        out["water"] = {"point": list(w.point), "normal": list(w.normal), "unit_weight": w.unit_weight,
                        "cracks": [{"point": list(c.point), "normal": list(c.normal), "depth": c.depth}
                                   for c in w.cracks]}
    if model.stages:
        out["stages"] = [_stage_dict(stage) for stage in model.stages]
    return out


def _stage_dict(stage: Stage) -> dict[str, Any]:
    """A ``[[stages]]`` table of a stage (what it leaves at its default is left out)."""
    out: dict[str, Any] = {"name": stage.name, "kind": stage.kind}
    for key in ("remove_blocks", "install_bolts", "fix_blocks", "free_blocks"):
        if getattr(stage, key):
            out[key] = list(getattr(stage, key))
    if stage.base_acceleration is not None:
        out["base_acceleration"] = _history_dict(stage.base_acceleration, f"stage {stage.name!r}'s base acceleration")
    if stage.materials:
        out["materials"] = {n: dataclasses.asdict(m) for n, m in stage.materials.items()}
    if stage.joint_materials:
        out["joint_materials"] = {n: {k: v for k, v in dataclasses.asdict(j).items() if v is not None}
                                  for n, j in stage.joint_materials.items()}
    if stage.run:
        out["run"] = {("steps" if k == "n_steps" else k): v for k, v in stage.run.items()}
    out.update(tolerance=stage.tolerance, max_steps=stage.max_steps, reset_displacements=stage.reset_displacements)
    if stage.water_level is not None:
        out["water_level"] = stage.water_level
    return out


def save_model(model: Model, settings: RunSettings, path: str | Path, title: str = "") -> None:
    """Write a model and its run settings as a TOML model file."""
    data = model_to_dict(model, settings, title)
    Path(path).write_text(tomli_w.dumps(data), encoding="utf-8")
