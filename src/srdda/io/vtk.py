"""ParaView files: VTU meshes per recorded step and PVD time series, written with meshio.

Blocks are VTK polygon cells (one per block, grouped by vertex count as meshio
needs) with cell data ``block``, ``material``, ``fixed``, ``velocity`` (vx, vy,
0), ``angular_velocity``, ``strain_rate`` (εx, εy, γxy rates), ``stress`` (σx,
σy, τxy), ``area`` and ``area_change`` (A/A0 - 1). Contacts are vertex cells
at the contact point, or line cells from the point to its partner point when
one is given, with ``normal_force``, ``shear_force``, ``normal`` and any other
per-contact array. Rock bolts are line cells from end a to end b with
``axial_force``, ``shear_force``, ``broken`` and ``bolt`` (its index). A step
without contacts gives a valid empty VTU (written as ASCII: ParaView reads it,
meshio's reader does not read empty meshes).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import meshio
import numpy as np

from ..geometry.polyhedron import PolyhedronMesh
from ..kinematics.blocktype import SOLID
from .results_store import StoredResult, read_results

__all__ = ["blocks_mesh", "solid_blocks_mesh", "contacts_mesh", "bolts_mesh", "write_pvd", "write_vtu_series"]


def _xyz(xy: np.ndarray) -> np.ndarray:
    """2D points (n, 2) as the 3D points VTK wants."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    return np.column_stack([xy, np.zeros(len(xy))])


def blocks_mesh(vertices: np.ndarray, block_ptr: np.ndarray, velocity: np.ndarray, stress: np.ndarray,
                material: np.ndarray, area: np.ndarray, initial_area: np.ndarray,
                fixed: np.ndarray | None = None) -> meshio.Mesh:
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
    }
    return _grouped_mesh(_xyz(vertices), counts, per_block,
                         lambda n, blocks: ("polygon", block_ptr[blocks][:, None] + np.arange(n)[None, :]))


def _grouped_mesh(points: np.ndarray, counts: np.ndarray, per_block: dict[str, np.ndarray],
                  cell_block: Callable[[int, np.ndarray], tuple[str, object]]) -> meshio.Mesh:
    """A mesh of one cell per block, grouped by vertex count (meshio needs one cell type per group)."""
    cells, cell_data = [], {name: [] for name in per_block}
    for n in np.unique(counts):
        blocks = np.flatnonzero(counts == n)
        cells.append(cell_block(int(n), blocks))
        for name, values in per_block.items():
            cell_data[name].append(np.asarray(values)[blocks])
    return meshio.Mesh(points, cells, cell_data=cell_data)


def solid_blocks_mesh(vertices: np.ndarray, mesh: PolyhedronMesh, velocity: np.ndarray, stress: np.ndarray,
                      material: np.ndarray, volume: np.ndarray, initial_volume: np.ndarray,
                      fixed: np.ndarray | None = None) -> meshio.Mesh:
    """All 3D blocks of one step as VTK polyhedron cells (their faces), grouped by vertex count as meshio needs.

    Cell data: ``block``, ``material``, ``fixed``, ``velocity`` (vx, vy, vz),
    ``angular_velocity`` (ωx, ωy, ωz), ``strain_rate`` and ``stress`` (xx, yy,
    zz, yz, zx, xy), ``volume`` and ``volume_change`` (V/V0 - 1).
    """
    nb = mesh.n_blocks
    counts = np.diff(mesh.block_ptr)
    faces = np.split(mesh.face_vertex, mesh.face_ptr[1:-1])
    per_block_faces = [[] for _ in range(nb)]
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
    }
    return _grouped_mesh(np.asarray(vertices, dtype=float), counts, per_block,
                         lambda n, blocks: (f"polyhedron{n}", [per_block_faces[b] for b in blocks]))


def contacts_mesh(contacts: Mapping[str, np.ndarray]) -> meshio.Mesh:
    """Contacts of one step: ``point`` (n, 2) required, ``point_b`` (n, 2) optional (line cells).

    Every other array whose first axis has n rows becomes cell data (2-vectors
    such as ``normal`` are padded to 3D).
    """
    if "point" not in contacts:
        raise ValueError("contacts need a 'point' array (n, 2): where each contact is")
    pa = np.asarray(contacts["point"], dtype=float).reshape(-1, 2)
    n = len(pa)
    if "point_b" in contacts:
        pb = np.asarray(contacts["point_b"], dtype=float).reshape(-1, 2)
        points = _xyz(np.concatenate([pa, pb]))
        cells = [("line", np.column_stack([np.arange(n), n + np.arange(n)]))]
    else:
        points = _xyz(pa)
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
        if arr.ndim == 2 and arr.shape[1] == 2:
            arr = _xyz(arr)
        data[name] = [arr]
    return meshio.Mesh(points, cells, cell_data=data)


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


def write_vtu_series(results: StoredResult | str | Path, directory: str | Path, every: int = 1,
                     contacts: ContactSeries | None = None, prefix: str = "blocks") -> dict[str, Path]:
    """VTU files of every ``every``-th recorded step (and the last) of a results file, and PVD collections.

    ``contacts(i)`` may give the contact arrays of recorded step ``i``; by
    default the contacts stored in the results file are used (at the steps
    they were recorded). Returns the PVD paths (``blocks``, and ``contacts``
    when there are any, ``bolts`` for a model with rock bolts).
    """
    res = results if isinstance(results, StoredResult) else read_results(results)
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    if contacts is None and res.contacts:
        index = {int(s): i for i, s in enumerate(res.contacts["step"])}
        def contacts(i: int) -> Mapping[str, np.ndarray] | None:  # noqa: E306 - the stored contacts
            j = index.get(int(res.step[i]))
            return None if j is None else res.contacts_at(j)
    area0 = res.area[0]
    solids = res.mesh
    block_files, contact_files, block_times, contact_times = [], [], [], []
    bolt_files = []
    has_bolts = "bolt_ends" in res.histories and res.bolt_ends.shape[1] > 0
    for i in sorted({*range(0, len(res.step), every), len(res.step) - 1}):
        name = f"{prefix}_{int(res.step[i]):07d}.vtu"
        if solids is not None:
            mesh = solid_blocks_mesh(res.vertices[i], solids, res.velocity[i], res.stress[i], res.block_material,
                                     res.area[i], area0, res.block_fixed)
        else:
            mesh = blocks_mesh(res.vertices[i], res.block_ptr, res.velocity[i], res.stress[i], res.block_material,
                               res.area[i], area0, res.block_fixed)
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
    pvds = {"blocks": write_pvd(out / f"{prefix}.pvd", block_files, block_times)}
    if contact_files:
        pvds["contacts"] = write_pvd(out / "contacts.pvd", contact_files, contact_times)
    if bolt_files:
        pvds["bolts"] = write_pvd(out / "bolts.pvd", bolt_files, block_times)
    return pvds
