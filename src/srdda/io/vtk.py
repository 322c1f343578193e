"""ParaView files: VTU meshes per recorded step and PVD time series, written with meshio.

Blocks are VTK polygon cells in 2D, polyhedron cells in 3D (one per block,
grouped by vertex count as meshio needs) with cell data ``block``,
``material``, ``fixed``, ``velocity``, ``angular_velocity``, ``strain_rate``,
``stress``, the derived ``strain`` (compliance · (σ - σ0)) and
``principal_stress``, ``area``/``volume`` and their change, and point data
``displacement``. Contacts are vertex cells at the contact point, or line
cells from the point to its partner point when one is given, with every stored
per-contact array, the derived ``slip`` and the size of the shear force
(:func:`contact_fields`). Rock bolts are line cells from end a
to end b with ``axial_force``, ``shear_force``, ``broken`` and ``bolt`` (its
index). A step without contacts gives a valid empty VTU (written as ASCII:
ParaView reads it, meshio's reader does not read empty meshes). The fields and
their units: docs/results.md, *ParaView*.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np

from ..contact.openclose import SLIDING
from ..geometry.polyhedron import PolyhedronMesh
from ..kinematics.blocktype import SOLID
from ..results import reference_rows, removed_blocks
from .results_reader import open_results
from .results_store import StoredResult, read_results

__all__ = ["blocks_mesh", "solid_blocks_mesh", "contacts_mesh", "bolts_mesh", "write_pvd", "write_vtu_series",
           "default_every", "series_rows", "ModelFields", "model_fields", "block_fields", "contact_fields",
           "principal_stresses", "MAX_SERIES_FILES"]


def _xyz(xy: np.ndarray) -> np.ndarray:
    """2D points (n, 2) as the 3D points VTK wants."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    return np.column_stack([xy, np.zeros(len(xy))])


def blocks_mesh(vertices: np.ndarray, block_ptr: np.ndarray, velocity: np.ndarray, stress: np.ndarray,
                material: np.ndarray, area: np.ndarray, initial_area: np.ndarray,
                fixed: np.ndarray | None = None, extra: Mapping[str, np.ndarray] | None = None) -> meshio.Mesh:
    """All blocks of one step as polygon cells with cell data (see the module docstring).

    Cells come grouped by vertex count; the ``block`` cell field gives each
    cell's block index.
    """
    counts = np.diff(block_ptr)
    nb = len(counts)
    per_block = {
        "block": np.arange(nb, dtype=np.int64),
        "material": np.asarray(material, dtype=np.int64),
        "fixed": np.zeros(nb, dtype=np.int64) if fixed is None else np.asarray(fixed, dtype=np.int64),
        "velocity": np.column_stack([velocity[:, :2], np.zeros(nb)]),
        "angular_velocity": velocity[:, 2],
        "strain_rate": velocity[:, 3:6],
        "stress": stress,
        "area": area,
        "area_change": area / initial_area - 1.0,
        **(extra or {}),
    }
    return _grouped_mesh(_xyz(vertices), counts, per_block,
                         lambda n, blocks: ("polygon", block_ptr[blocks][:, None] + np.arange(n)[None, :]))


def _grouped_mesh(points: np.ndarray, counts: np.ndarray, per_block: dict[str, np.ndarray],
                  cell_block: Callable[[int, np.ndarray], tuple[str, object]]) -> meshio.Mesh:
    """A mesh of one cell per block, grouped by vertex count (meshio needs one cell type per group)."""
    cells = []
    cell_data: dict[str, list[np.ndarray]] = {name: [] for name in per_block}
    for n in np.unique(counts):
        blocks = np.flatnonzero(counts == n)
        cells.append(cell_block(int(n), blocks))
        for name, values in per_block.items():
            cell_data[name].append(np.asarray(values)[blocks])
    return meshio.Mesh(points, cells, cell_data=cell_data)


def solid_blocks_mesh(vertices: np.ndarray, mesh: PolyhedronMesh, velocity: np.ndarray, stress: np.ndarray,
                      material: np.ndarray, volume: np.ndarray, initial_volume: np.ndarray,
                      fixed: np.ndarray | None = None, extra: Mapping[str, np.ndarray] | None = None
                      ) -> meshio.Mesh:
    """All 3D blocks of one step as VTK polyhedron cells (their faces), grouped by vertex count as meshio needs.

    Cell data: ``block``, ``material``, ``fixed``, ``velocity`` (vx, vy, vz),
    ``angular_velocity`` (ωx, ωy, ωz), ``strain_rate`` and ``stress`` (xx, yy,
    zz, yz, zx, xy), ``volume`` and ``volume_change`` (V/V0 - 1).
    """
    nb = mesh.n_blocks
    counts = np.diff(mesh.block_ptr)
    faces = np.split(mesh.face_vertex, mesh.face_ptr[1:-1])
    per_block_faces: list[list[np.ndarray]] = [[] for _ in range(nb)]
    for block, face in zip(mesh.face_block, faces):
        per_block_faces[block].append(face)
    per_block = {
        "block": np.arange(nb, dtype=np.int64),
        "material": np.asarray(material, dtype=np.int64),
        "fixed": np.zeros(nb, dtype=np.int64) if fixed is None else np.asarray(fixed, dtype=np.int64),
        "velocity": velocity[:, SOLID.translation],
        "angular_velocity": velocity[:, SOLID.rotation],
        "strain_rate": velocity[:, SOLID.strain],
        "stress": stress,
        "volume": volume,
        "volume_change": volume / initial_volume - 1.0,
        **(extra or {}),
    }
    return _grouped_mesh(np.asarray(vertices, dtype=float), counts, per_block,
                         lambda n, blocks: (f"polyhedron{n}", [per_block_faces[b] for b in blocks]))


def contacts_mesh(contacts: Mapping[str, np.ndarray]) -> meshio.Mesh:
    """Contacts of one step: ``point`` (n, 2) or (n, 3) required, ``point_b`` (n, dim) optional (line cells).

    Every other array whose first axis has n rows becomes cell data; in 2D,
    2-vectors such as ``normal`` are padded to 3D. 3D contacts keep their
    (n, 2) arrays (``shear``, ``direction``: components in the contact's frame).
    """
    if "point" not in contacts:
        raise ValueError("contacts need a 'point' array (n, 2) or (n, 3): where each contact is")
    point = np.asarray(contacts["point"], dtype=float)
    dim = point.shape[-1] if point.ndim == 2 and point.shape[-1] in (2, 3) else 2
    pa = point.reshape(-1, dim)
    n = len(pa)
    if "point_b" in contacts:
        points = np.concatenate([pa, np.asarray(contacts["point_b"], dtype=float).reshape(-1, dim)])
        cells = [("line", np.column_stack([np.arange(n), n + np.arange(n)]))]
    else:
        points = pa
        cells = [("vertex", np.arange(n)[:, None])]
    data = {}
    for name, value in contacts.items():
        if name in ("point", "point_b"):
            continue
        arr = np.asarray(value)
        if arr.shape[:1] != (n,):
            raise ValueError(f"contact array {name!r} has {arr.shape[:1]} rows, expected {n}")
        if arr.dtype == bool:  # VTK has no boolean arrays
            arr = arr.astype(np.uint8)
        if dim == 2 and arr.ndim == 2 and arr.shape[1] == 2:
            arr = _xyz(arr)
        data[name] = [arr]
    return meshio.Mesh(_xyz(points) if dim == 2 else points, cells, cell_data=data)


def bolts_mesh(ends: np.ndarray, axial_force: np.ndarray, shear_force: np.ndarray, broken: np.ndarray
               ) -> meshio.Mesh:
    """Rock bolts of one step as line cells from end a to end b (``ends`` (n, 2, dim)) with their forces."""
    ends = np.asarray(ends, dtype=float)
    n, dim = len(ends), ends.shape[-1]
    points = ends.reshape(-1, dim)
    points = _xyz(points) if dim == 2 else points
    data = {"bolt": [np.arange(n, dtype=np.int64)], "axial_force": [np.asarray(axial_force, dtype=float)],
            "shear_force": [np.asarray(shear_force, dtype=float)], "broken": [np.asarray(broken).astype(np.uint8)]}
    return meshio.Mesh(points, [("line", np.arange(2 * n).reshape(n, 2))], cell_data=data)


def _write(mesh: meshio.Mesh, path: Path) -> None:
    empty = sum(len(c.data) for c in mesh.cells) == 0
    meshio.write(path, mesh, file_format="vtu", binary=not empty)


def write_pvd(path: str | Path, files: Sequence[str | Path], times: Sequence[float]) -> Path:
    """A ParaView collection of ``files`` (paths relative to the PVD's folder) at ``times``."""
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for f, t in zip(files, times, strict=True):
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=str(f))
    path = Path(path)
    ET.ElementTree(root).write(path, xml_declaration=True, encoding="utf-8")
    return path


ContactSeries = Callable[[int], Mapping[str, np.ndarray] | None]
MAX_SERIES_FILES = 200  # the default --every keeps each PVD series at or under this many files


def default_every(n_recorded: int, max_files: int = MAX_SERIES_FILES) -> int:
    """The smallest step stride that keeps a series of ``n_recorded`` steps (and the last) within ``max_files``."""
    return max(1, -(-max(n_recorded - 1, 0) // max(max_files - 1, 1)))


def series_rows(n_recorded: int, every: int) -> list[int]:
    """Recorded rows a series writes: every ``every``-th and the last."""
    return sorted({*range(0, n_recorded, every), n_recorded - 1}) if n_recorded else []


@dataclass(frozen=True)
class ModelFields:
    """What the derived block fields need of the stored model (read from the results file's ``/model``)."""

    compliance: np.ndarray  # (nb, k, k): strain = compliance · (σ - σ0), engineering shear strains
    initial_stress: np.ndarray  # (nb, k)


def model_fields(res: StoredResult) -> ModelFields:
    """The stored model's compliance and initial stresses."""
    with open_results(res.path) as f:
        return ModelFields(f["model"]["compliance"][()], f["model"]["stress"][()])


def principal_stresses(stress: np.ndarray) -> np.ndarray:
    """Principal stresses (n, 2) in 2D or (n, 3) in 3D, largest first (Pa; tension positive)."""
    stress = np.asarray(stress, dtype=float)
    if stress.shape[-1] == 3:
        sx, sy, txy = stress.T
        mean, radius = 0.5 * (sx + sy), np.hypot(0.5 * (sx - sy), txy)
        return np.column_stack([mean + radius, mean - radius])
    sx, sy, sz, tyz, tzx, txy = stress.T
    tensor = np.stack([np.stack([sx, txy, tzx], -1), np.stack([txy, sy, tyz], -1), np.stack([tzx, tyz, sz], -1)],
                      axis=-2)
    return np.linalg.eigvalsh(tensor)[:, ::-1]


def block_fields(stress: np.ndarray, fields: ModelFields) -> dict[str, np.ndarray]:
    """Per-block strain since the start (compliance · (σ - σ0); engineering shear strains) and principal stresses."""
    strain = np.einsum("bij,bj->bi", fields.compliance, np.asarray(stress) - fields.initial_stress)
    return {"strain": strain, "principal_stress": principal_stresses(stress)}


def contact_fields(contacts: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The stored contact arrays plus ``slip`` (1: sliding) and ``shear_force`` as its size (N).

    The contact set stores the shear force on block a in the contact's frame
    (the locked spring's force, or the friction that acted); files written
    before it did (format 1) get no shear force.
    """
    out = dict(contacts)
    if "state" in contacts:
        out["slip"] = (np.asarray(contacts["state"]) == SLIDING).astype(np.uint8)
    if "shear_force" in contacts:
        force = np.asarray(contacts["shear_force"], dtype=float)
        out["shear_force"] = np.linalg.norm(force.reshape(len(force), -1), axis=1)
    return out


def stage_fields(res: StoredResult, i: int) -> tuple[int, np.ndarray, np.ndarray]:
    """Of recorded row ``i`` of a staged run: its stage (-1 before any, or without stages), the blocks the
    stages begun by then removed, and the vertices its displacements are measured from (those at the start of
    the last stage begun that resets displacements; the initial ones without)."""
    step = int(res.step[i])
    begun = [row for row in res.stages if row["first_step"] <= step]
    removed = removed_blocks(step, res.stages, len(res.block_names))
    at = int(reference_rows(res.step, res.stages)[i])
    reference = np.asarray(res.initial_vertices if at == 0 else res.vertices[at], dtype=float)
    return (begun[-1]["index"] if begun else -1), removed, reference


def write_vtu_series(results: StoredResult | str | Path, directory: str | Path, every: int | None = None,
                     contacts: ContactSeries | None = None, prefix: str = "blocks",
                     progress: Callable[[], None] | None = None) -> dict[str, Path]:
    """VTU files of every ``every``-th recorded step (and the last) of a results file, and PVD collections.

    ``every`` None: :func:`default_every` (each series at most
    :data:`MAX_SERIES_FILES` files). ``contacts(i)`` may give the contact
    arrays of recorded step ``i``; by default the contacts stored in the
    results file are used (at the steps they were recorded), with the derived
    fields of :func:`contact_fields`. Blocks carry the derived fields of
    :func:`block_fields` and a point field ``displacement`` (from the initial
    vertices). ``progress()`` is called after each step written. Returns the
    PVD paths (``blocks``, and ``contacts`` when there are any, ``bolts`` for
    a model with rock bolts).
    """
    res = results if isinstance(results, StoredResult) else read_results(results)
    every = default_every(len(res.step)) if every is None else every
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    fields = model_fields(res)
    if contacts is None and res.contacts:
        index = {int(s): i for i, s in enumerate(res.contacts["step"])}
        def contacts(i: int) -> Mapping[str, np.ndarray] | None:  # noqa: E306 - the stored contacts
            j = index.get(int(res.step[i]))
            return None if j is None else contact_fields(res.contacts_at(j))
    area0 = res.area[0]
    solids = res.mesh
    block_files, contact_files, block_times, contact_times = [], [], [], []
    bolt_files = []
    has_bolts = "bolt_ends" in res.histories and res.bolt_ends.shape[1] > 0
    for i in series_rows(len(res.step), every):
        name = f"{prefix}_{int(res.step[i]):07d}.vtu"
        extra = block_fields(res.stress[i], fields)
        stage, removed, reference = stage_fields(res, i)
        if res.stages:
            extra.update(stage=np.full(len(res.block_names), stage), removed=removed.astype(np.int64))
        if solids is not None:
            mesh = solid_blocks_mesh(res.vertices[i], solids, res.velocity[i], res.stress[i], res.block_material,
                                     res.area[i], area0, res.block_fixed, extra)
        else:
            mesh = blocks_mesh(res.vertices[i], res.block_ptr, res.velocity[i], res.stress[i], res.block_material,
                               res.area[i], area0, res.block_fixed, extra)
        displacement = np.asarray(res.vertices[i], dtype=float) - reference
        mesh.point_data["displacement"] = _xyz(displacement) if displacement.shape[-1] == 2 else displacement
        _write(mesh, out / name)
        block_files.append(name)
        block_times.append(res.time[i])
        if has_bolts:
            bname = f"bolts_{int(res.step[i]):07d}.vtu"
            _write(bolts_mesh(res.bolt_ends[i], res.bolt_force[i], res.bolt_shear_force[i], res.bolt_broken[i]),
                   out / bname)
            bolt_files.append(bname)
        c = contacts(i) if contacts is not None else None
        if c is not None:
            cname = f"contacts_{int(res.step[i]):07d}.vtu"
            _write(contacts_mesh(c), out / cname)
            contact_files.append(cname)
            contact_times.append(res.time[i])
        if progress is not None:
            progress()
    pvds = {"blocks": write_pvd(out / f"{prefix}.pvd", block_files, block_times)}
    if contact_files:
        pvds["contacts"] = write_pvd(out / "contacts.pvd", contact_files, contact_times)
    if bolt_files:
        pvds["bolts"] = write_pvd(out / "bolts.pvd", bolt_files, block_times)
    return pvds
