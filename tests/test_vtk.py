"""ParaView output read back with meshio: cell counts, fields and values."""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

import srdda
from srdda.io.results_store import ResultsStore, read_results
from srdda.io.vtk import contacts_mesh, write_vtu_series
from results_models import two_block_model


def _contacts(arrays, state):
    """Synthetic contacts: one per block at its first vertex, touching the next vertex."""
    p = state.vertices[arrays.block_ptr[:-1]]
    q = state.vertices[arrays.block_ptr[:-1] + 1]
    n = np.tile([0.0, 1.0], (arrays.n_blocks, 1))
    return {"point": p, "point_b": q, "normal": n, "normal_force": np.full(arrays.n_blocks, 10.0 * state.step),
            "shear_force": np.arange(arrays.n_blocks, dtype=float), "bonded": np.array([True, False]),
            "state": np.array([2, 0], dtype=np.int8)}


@pytest.fixture(scope="module")
def stored(tmp_path_factory: pytest.TempPathFactory):
    path = tmp_path_factory.mktemp("vtk") / "run.h5"
    settings = srdda.RunSettings(dt=1e-3, n_steps=12, method="dda0")
    srdda.run(two_block_model(), settings,
              recorders=[ResultsStore(path, settings, flush_every=5, contact_provider=_contacts, contact_every=2)])
    return read_results(path)


def _by_block(mesh: meshio.Mesh, name: str) -> np.ndarray:
    """Cell data of all polygon cells, reordered by the ``block`` field."""
    block = np.concatenate(mesh.cell_data["block"])
    values = np.concatenate(mesh.cell_data[name])
    return values[np.argsort(block)]


def test_block_vtu_files_hold_every_block_and_field(stored, tmp_path: Path) -> None:
    pvds = write_vtu_series(stored, tmp_path, every=5)
    files = [d.get("file") for d in ET.parse(pvds["blocks"]).getroot().iter("DataSet")]
    times = [float(d.get("timestep")) for d in ET.parse(pvds["blocks"]).getroot().iter("DataSet")]
    assert files == ["blocks_0000000.vtu", "blocks_0000005.vtu", "blocks_0000010.vtu", "blocks_0000012.vtu"]
    np.testing.assert_array_equal(times, stored.time[[0, 5, 10, 12]])
    mesh = meshio.read(tmp_path / files[-1])
    assert [c.type for c in mesh.cells] == ["polygon", "polygon"]
    assert sorted(len(c.data[0]) for c in mesh.cells) == [4, 5]  # a square and a pentagon
    assert sum(len(c.data) for c in mesh.cells) == 2
    np.testing.assert_array_equal(mesh.points[:, :2], stored.vertices[-1])
    np.testing.assert_array_equal(_by_block(mesh, "velocity")[:, :2], stored.velocity[-1][:, :2])
    np.testing.assert_array_equal(_by_block(mesh, "angular_velocity"), stored.velocity[-1][:, 2])
    np.testing.assert_array_equal(_by_block(mesh, "stress"), stored.stress[-1])
    np.testing.assert_array_equal(_by_block(mesh, "material"), [0, 1])
    # dda0 grows a spinning block's area (1 + Δr²) per step: the square spins, the pentagon does not
    change = _by_block(mesh, "area_change")
    np.testing.assert_allclose(change, stored.area[-1] / stored.area[0] - 1, rtol=0, atol=1e-15)
    assert change[0] > 0 and abs(change[1]) < 1e-12


def test_contact_vtu_files_hold_lines_and_forces(stored, tmp_path: Path) -> None:
    pvds = write_vtu_series(stored, tmp_path)
    files = [d.get("file") for d in ET.parse(pvds["contacts"]).getroot().iter("DataSet")]
    assert len(files) == 7  # recorded steps 0..12, contacts every 2nd
    mesh = meshio.read(tmp_path / "contacts_0000004.vtu")
    assert [c.type for c in mesh.cells] == ["line"] and len(mesh.cells[0].data) == 2
    np.testing.assert_array_equal(mesh.cell_data["normal_force"][0], [40.0, 40.0])
    np.testing.assert_array_equal(mesh.cell_data["shear_force"][0], [0.0, 1.0])
    np.testing.assert_array_equal(mesh.cell_data["normal"][0], [[0, 1, 0], [0, 1, 0]])
    np.testing.assert_array_equal(mesh.cell_data["bonded"][0], [1, 0])  # booleans as 0/1
    np.testing.assert_array_equal(mesh.cell_data["state"][0], [2, 0])


def test_vertex_contacts_and_bad_contact_arrays() -> None:
    mesh = contacts_mesh({"point": np.zeros((3, 2)), "normal_force": np.ones(3)})
    assert mesh.cells[0].type == "vertex" and len(mesh.cells[0].data) == 3
    with pytest.raises(ValueError, match="'shear_force' has"):
        contacts_mesh({"point": np.zeros((3, 2)), "shear_force": np.ones(2)})
