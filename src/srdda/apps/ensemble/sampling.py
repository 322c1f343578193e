"""Samples of an ensemble, how a sample is applied to the base model, and the spec read and checked by applying one.

Run ``i``'s values come from ``numpy.random.default_rng([seed, i])`` alone (a
SeedSequence of the spec's seed and the run index), drawn in the order of the
spec's parameters: a run's sample does not depend on how many runs, workers or
which order, so an ensemble gives the same table on any cluster and a resumed
ensemble draws what an uninterrupted one would.

A sample is applied to a copy of the base model's dictionary (the parsed model
file), so each run is built, validated and run exactly as ``srdda run`` would
build it; a value that makes the model invalid fails that run only.
"""
from __future__ import annotations

import copy
import math
import re
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from ...io.modelfile import ModelFileError, format_validation, model_from_dict, read_model_text
from .spec import BLOCK_SHORTCUTS, Choice, EnsembleSpec, LogNormal, Normal, SpecError, Uniform

__all__ = ["ApplyError", "sample", "apply_values", "set_path", "tracked_block", "load_spec"]


class ApplyError(ValueError):
    """A parameter's path or reference does not exist in the base model (the message names it)."""


def _draw(p: Uniform | Normal | LogNormal | Choice, rng: np.random.Generator) -> float:
    if isinstance(p, Uniform):
        return float(rng.uniform(p.low, p.high))
    if isinstance(p, Normal):
        return float(rng.normal(p.mean, p.std))
    if isinstance(p, LogNormal):
        # the log's σ² = ln(1 + (std/mean)²) and μ = ln(mean) - σ²/2 give the value this mean and std
        s2 = math.log1p((p.std / p.mean) ** 2)
        return float(rng.lognormal(math.log(p.mean) - 0.5 * s2, math.sqrt(s2)))
    weights = None if p.weights is None else np.asarray(p.weights) / sum(p.weights)
    return float(p.values[int(rng.choice(len(p.values), p=weights))])


def sample(spec: EnsembleSpec, index: int) -> dict[str, float]:
    """The values of run ``index``: a function of (seed, index) only."""
    rng = np.random.default_rng([spec.seed, index])
    return {p.name: _draw(p, rng) for p in spec.parameters}


_SEGMENT = re.compile(r"^([^.\[\]]+)((?:\[\d+\])*)$")


def _split(path: str) -> list[str | int]:
    """``blocks.stone.velocity[0]`` as ['blocks', 'stone', 'velocity', 0]."""
    parts: list[str | int] = []
    for segment in path.split("."):
        m = _SEGMENT.match(segment)
        if m is None:
            raise ApplyError(f"path {path!r}: {segment!r} is not a field name with optional [index]es")
        parts.append(m.group(1))
        parts += [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
    return parts


def _child(node: Any, key: str | int, where: str) -> Any:
    if isinstance(node, dict):
        if key not in node:
            raise ApplyError(f"{where}: no field {key!r} in the base model (it has: {', '.join(map(str, node))})")
        return node[key]
    if isinstance(node, list):
        if isinstance(key, int):
            if not 0 <= key < len(node):
                raise ApplyError(f"{where}: index {key} out of range (0..{len(node) - 1})")
            return node[key]
        named = [item for item in node if isinstance(item, dict) and item.get("name") == key]
        if not named:
            raise ApplyError(f"{where}: no entry named {key!r}")
        return named[0]
    raise ApplyError(f"{where}: {key!r} is below a value, not a table or list")


def set_path(data: dict[str, Any], path: str, value: float) -> None:
    """Set the model-file field at ``path`` (tables by key, lists by [index] or by an entry's name)."""
    parts = _split(path)
    node: Any = data
    for key in parts[:-1]:
        node = _child(node, key, f"path {path!r}")
    last = parts[-1]
    _child(node, last, f"path {path!r}")  # the field must exist in the base model
    if isinstance(node, list) and isinstance(last, str):
        raise ApplyError(f"path {path!r}: ends at a list entry, not a value")
    node[last] = value


def tracked_block(data: dict[str, Any], spec: EnsembleSpec) -> int:
    """Index of the spec's tracked block: ``block`` by name or index, else the base model's one movable block."""
    blocks = data["blocks"]
    if spec.block is not None:
        return _block_index(blocks, spec.block, "block")
    movable = [i for i, b in enumerate(blocks) if not b.get("fixed", False)]
    if len(movable) != 1:
        raise ApplyError(f"block: the base model has {len(movable)} movable blocks; name the tracked one "
                         "with block = \"NAME\"")
    return movable[0]


def _block_index(blocks: list[dict[str, Any]], ref: str | int, where: str) -> int:
    if isinstance(ref, int):
        if not 0 <= ref < len(blocks):
            raise ApplyError(f"{where}: block index {ref} out of range (0..{len(blocks) - 1})")
        return ref
    for i, b in enumerate(blocks):
        if b.get("name") == ref:
            return i
    raise ApplyError(f"{where}: no block named {ref!r}")


# Block-attached points of a model file: (section, point key, block key); they move with their block.
_ATTACHED = (("fixed_points", "at", "block"), ("point_loads", "at", "block"), ("measured_points", "at", "block"),
             ("pins", "at", "block"), ("prescribed_motion", "at", "block"), ("point_springs", "a", "block_a"),
             ("point_springs", "b", "block_b"), ("springs", "a", "block_a"), ("springs", "b", "block_b"),
             ("hinges", "at", "block_a"), ("hinges", "at_b", "block_b"))


def _map_block(data: dict[str, Any], index: int, transform: Any) -> None:
    """Apply ``transform`` (n, dim) -> (n, dim) to a block's vertices (or box corners) and attached points."""
    block = data["blocks"][index]
    key = "vertices" if block.get("vertices") is not None else "box"
    block[key] = transform(np.asarray(block[key], dtype=float)).tolist()
    name = block.get("name")
    for section, point, ref in _ATTACHED:
        for entry in data.get(section, []):
            if point in entry and entry.get(ref) in (index, name) and entry.get(ref) is not None:
                entry[point] = transform(np.asarray([entry[point]], dtype=float))[0].tolist()


def _stretch(data: dict[str, Any], index: int, factors: np.ndarray) -> None:
    """Stretch a block about the mean of its vertices by ``factors`` per axis."""
    block = data["blocks"][index]
    centre = np.asarray(block.get("vertices") or block["box"], dtype=float).mean(axis=0)
    _map_block(data, index, lambda x: centre + (x - centre) * factors[: x.shape[1]])


def _apply_block_shortcut(data: dict[str, Any], index: int, shortcut: str, value: float) -> None:
    block = data["blocks"][index]
    dim = len((block.get("vertices") or block["box"])[0])
    axis = {"x": 0, "y": 1, "z": 2}
    if shortcut.startswith("release_d"):
        shift = np.zeros(dim)
        shift[axis[shortcut[-1]]] = value
        if value != 0.0:  # an exact zero leaves the coordinates bit for bit
            _map_block(data, index, lambda x: x + shift)
    elif shortcut.startswith("velocity_"):
        velocity = list(block.get("velocity") or [0.0] * dim)
        velocity[axis[shortcut[-1]]] = value
        block["velocity"] = velocity
    elif shortcut == "angular_velocity":
        block["angular_velocity"] = value
    elif shortcut.startswith("angular_velocity_"):
        omega = block.get("angular_velocity", 0.0)
        omega = list(omega) if isinstance(omega, list) else [0.0, 0.0, float(omega)]
        omega[axis[shortcut[-1]]] = value
        block["angular_velocity"] = omega
    elif shortcut == "scale" and value != 1.0:  # an exact 1 leaves the vertices bit for bit
        _stretch(data, index, np.full(dim, value))
    elif shortcut == "aspect" and value != 1.0:
        # horizontal extents × a^(1/dim), the vertical one × a^(1/dim - 1): width/height × a, same area/volume
        factors = np.full(dim, value ** (1.0 / dim))
        factors[-1] = value ** (1.0 / dim - 1.0)
        _stretch(data, index, factors)


def apply_values(base: dict[str, Any], spec: EnsembleSpec, values: dict[str, float]) -> dict[str, Any]:
    """A copy of the base model's dictionary with the sample ``values`` set (the base is not changed)."""
    data = copy.deepcopy(base)
    for i, p in enumerate(spec.parameters):
        where = f"parameters[{i}] ({p.name})"
        value = values[p.name]
        try:
            if p.path is not None:
                set_path(data, p.path, value)
            elif p.shortcut in BLOCK_SHORTCUTS:
                ref = p.block if p.block is not None else tracked_block(data, spec)
                _apply_block_shortcut(data, _block_index(data["blocks"], ref, "block"), p.shortcut, value)
            elif p.shortcut == "density":
                assert p.material is not None  # Parameter's check: density names its material
                _child(data.get("materials", {}), p.material, "material")["density"] = value
            elif p.shortcut == "friction":
                assert p.joint is not None  # Parameter's check: friction names its joint material
                _child(data.get("joint_materials", {}), p.joint, "joint")["friction_angle"] = value
            elif p.shortcut == "stiffness":
                data["run"]["contact_penalty"] = value
        except ApplyError as exc:
            raise ApplyError(f"{where}: {exc}") from None
    return data


def load_spec(path: str | Path, runs: int | None = None) -> tuple[EnsembleSpec, dict[str, Any]]:
    """Read and check a spec and its base model: the spec (``runs`` overriding its count) and the model's dict.

    The base model is validated (one :class:`SpecError` naming the model file
    and the field) and every parameter is applied once to it with its base
    value, so a wrong path or reference is found before any run starts.
    """
    p = Path(path)
    try:
        data = tomllib.loads(read_model_text(p))
    except ModelFileError as exc:
        raise SpecError(str(exc).replace("model file", "spec file")) from None
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise SpecError(f"{p}: not valid TOML ({exc})") from None
    if runs is not None:
        data["runs"] = runs
    try:
        spec = EnsembleSpec.model_validate(data)
    except ValidationError as exc:
        raise SpecError(format_validation(exc, str(p), "invalid ensemble spec")) from None
    model_path = (p.parent / spec.model)
    try:
        base = tomllib.loads(read_model_text(model_path))
        model, _ = model_from_dict(base, str(model_path))
    except ModelFileError as exc:
        raise SpecError(f"{p}: model: {exc}") from None
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise SpecError(f"{p}: model: {model_path}: not valid TOML ({exc})") from None
    try:
        apply_values(base, spec, sample(spec, 0))
    except ApplyError as exc:
        raise SpecError(f"{p}: {exc}") from None
    dim = len(model.blocks[0].vertices[0])
    for c in spec.all_collectors(dim):
        if len(c.at) != dim:
            raise SpecError(f"{p}: collector {c.name!r}: 'at' and 'normal' need {dim} coordinates (a {dim}D model)")
    if spec.stop.domain is not None and len(spec.stop.domain[0]) != dim:
        raise SpecError(f"{p}: stop.domain: needs {dim} coordinates per corner (a {dim}D model)")
    return spec, base
