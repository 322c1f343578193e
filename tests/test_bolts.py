"""Rock bolts (srdda.constraints.bolts): against Shi's recurrence of the same discrete equations, pretension,
breaking (recorded, kept, in the energy ledger), resume, the model file, results file, VTU and figures."""
import dataclasses
import tomllib
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from srdda import Material, Model, RunSettings, run
from srdda.constraints import bolt_forces
from srdda.io.modelfile import ModelFileError, model_from_dict, model_to_dict
from srdda.io.results_store import ResultsStore, load_checkpoint, read_results
from srdda.io.vtk import write_vtu_series
from srdda.apps.plotting import fig_bolt_forces, fig_model

RHO = 1000.0  # a unit square: 1000 kg per m
MASS = RHO
ANCHOR = (-2.5, 0.0)  # on the ground, 3 m left of the block's centroid (0.5, 0)


def _bolted(k: float, pretension: float = 0.0, strength: float | None = None, v0: float = 0.0,
            shear: float = 0.0) -> Model:
    """A free unit square in zero gravity, bolted from its centroid to a ground anchor along x."""
    m = Model()
    m.add_material("rock", Material(density=RHO, young=1e10, poisson=0.25))
    m.add_block([[0, -0.5], [1, -0.5], [1, 0.5], [0, 0.5]], "rock", velocity=(v0, 0.0), name="mass")
    m.add_bolt((0.5, 0.0), ANCHOR, k, pretension, strength, shear, block_a=0, block_b=-1, name="b1")
    return m


def _recurrence(k: float, pretension: float, strength: float, v0: float, dt: float, n: int):
    """Shi's scheme for m·ẍ = -N, N = P0 + k·x (the bolt's force at the end of the step) while N <= strength,
    then free flight: (2m/Δt² + k)Δx = 2m V0/Δt - N(x0). Returns x per step and the break step."""
    x, v, out, broke = 0.0, v0, [0.0], None
    for i in range(n):
        kk, p0 = (0.0, 0.0) if broke is not None else (k, pretension)
        dx = (2 * MASS / dt * v - (p0 + kk * x)) / (2 * MASS / dt**2 + kk)
        v = 2 * dx / dt - v
        x += dx
        out.append(x)
        if broke is None and pretension + k * x > strength:
            broke = i + 1
    return np.array(out), broke


def test_pretension_pulls_as_the_scheme_recurrence():
    k, p0, dt, n = 4e4, 500.0, 1e-3, 300
    res = run(_bolted(k, p0), RunSettings(dt=dt, n_steps=n, method="dda0"))
    x = res.array("centroid")[:, 0, 0] - 0.5
    expected, _ = _recurrence(k, p0, np.inf, 0.0, dt, n)
    # the same discrete equations solved two ways: round-off of 1e-2 m amplitudes
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-12)
    force = res.array("bolt_force")[:, 0]
    assert force[0] == pytest.approx(p0, rel=1e-12)  # at installation the bolt holds its pretension
    np.testing.assert_allclose(force, p0 + k * expected, rtol=1e-9)


def test_a_bolt_breaks_at_its_strength_records_it_and_stays_broken():
    k, strength, v0, dt, n = 4e4, 300.0, 0.5, 1e-3, 200
    res = run(_bolted(k, 0.0, strength, v0), RunSettings(dt=dt, n_steps=n, method="dda0"))
    x = res.array("centroid")[:, 0, 0] - 0.5
    expected, broke = _recurrence(k, 0.0, strength, v0, dt, n)
    assert broke is not None and 5 < broke < n  # the test breaks the bolt part-way
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-12)
    broken = res.array("bolt_broken")[:, 0]
    assert not broken[:broke].any() and broken[broke:].all()
    times = res.array("bolt_break_time")[:, 0]
    assert np.isnan(times[:broke]).all() and np.all(times[broke:] == pytest.approx(broke * dt, rel=1e-12))
    assert np.all(res.array("bolt_force")[broke:, 0] == 0.0)
    # the energy the bolt held at its break leaves as 'dissipated': ½k x_b² (round-off)
    dissipated = res.energy[-1]["dissipated"]
    assert dissipated == pytest.approx(0.5 * k * expected[broke] ** 2, rel=1e-9)
    assert res.energy[broke]["spring"] == 0.0 and res.energy[broke - 1]["spring"] > 0.0


def test_the_shear_spring_resists_motion_across_the_bolt():
    ks, dt, n = 4e4, 1e-3, 200
    m = _bolted(1e5, shear=ks)
    m.blocks[0].velocity = (0.0, 0.1, 0.0)  # moves across the bolt
    res = run(m, RunSettings(dt=dt, n_steps=n, method="dda0"))
    y = res.array("centroid")[:, 0, 1]
    # across the bolt: the dowel spring k_s (the axial spring's transverse share is its geometric
    # stiffness N/ℓ = 0 without tension, second order in y): the first step of Shi's recurrence
    dx1 = (2 * MASS / dt * 0.1) / (2 * MASS / dt**2 + ks)
    assert y[1] == pytest.approx(dx1, rel=1e-6)
    shear = res.array("bolt_shear_force")[:, 0]
    np.testing.assert_allclose(shear[1:50], ks * np.abs(y[1:50]), rtol=1e-3)  # |P0·(d - d0)|, d ⟂ n0


def test_a_broken_bolt_survives_a_checkpoint_and_the_resumed_run_equals_the_whole(tmp_path: Path):
    k, strength, v0, dt = 4e4, 300.0, 0.5, 1e-3
    model = _bolted(k, 0.0, strength, v0)
    arrays = model.arrays()
    settings = RunSettings(dt=dt, n_steps=120, method="srdda")
    whole = run(arrays, settings)
    path = tmp_path / "bolt.h5"
    run(arrays, dataclasses.replace(settings, n_steps=80), recorders=[ResultsStore(path, settings, flush_every=10)])
    state = load_checkpoint(path, arrays)
    bolts, whole_bolts = state.carried["bolts"], whole.final_state.carried["bolts"]  # the bolt term's state
    assert state.step == 80 and bolts.broken.all()
    assert bolts.break_time[0] == whole_bolts.break_time[0]
    rest = run(arrays, dataclasses.replace(settings, n_steps=40), state=state)
    np.testing.assert_array_equal(rest.final_state.vertices, whole.final_state.vertices)  # a pure function
    np.testing.assert_array_equal(rest.final_state.carried["bolts"].broken, whole_bolts.broken)
    stored = read_results(path)
    assert stored.bolt_names == ("b1",)
    assert stored.bolt_force.shape == (81, 1) and stored.bolt_ends.shape == (81, 1, 2, 2)
    np.testing.assert_array_equal(stored.bolt_broken[:, 0], whole.array("bolt_broken")[:81, 0])


def test_bolts_in_the_vtu_output_and_the_figures(tmp_path: Path):
    path = tmp_path / "bolt.h5"
    settings = RunSettings(dt=1e-3, n_steps=60, method="dda0")
    run(_bolted(4e4, 0.0, 300.0, 0.5), settings, recorders=[ResultsStore(path, settings, flush_every=20)])
    pvds = write_vtu_series(path, tmp_path / "vtk", every=20)
    assert "bolts" in pvds
    res = read_results(path)
    last = meshio.read(tmp_path / "vtk" / "bolts_0000060.vtu")
    np.testing.assert_allclose(last.points[:, :2], res.bolt_ends[-1].reshape(-1, 2))
    assert last.cells_dict["line"].tolist() == [[0, 1]]
    assert last.cell_data["broken"][0].tolist() == [1]
    first = meshio.read(tmp_path / "vtk" / "bolts_0000000.vtu")
    assert first.cell_data["axial_force"][0][0] == pytest.approx(res.bolt_force[0, 0])
    fig = fig_model(res, 0, None)
    lines = [ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata()) == 2]
    np.testing.assert_allclose(lines[0].get_xydata(), res.bolt_ends[0, 0])  # the bolt drawn end to end
    forces = fig_bolt_forces(res)
    np.testing.assert_allclose(forces.axes[0].get_lines()[0].get_ydata(), res.bolt_force[:, 0] / 1e3)


MODEL = """
[run]
dt = 1e-3
steps = 2
[materials.rock]
density = 2500.0
young = 1e9
poisson = 0.25
[[blocks]]
name = "slope"
material = "rock"
vertices = [[-3, -2], [3, -2], [3, 0], [-3, 0]]
fixed = true
[[blocks]]
name = "block"
material = "rock"
vertices = [[0, 0], [1, 0], [1, 0.5], [0, 0.5]]
"""


def test_bolts_in_the_model_file_round_trip():
    text = MODEL + """
[[bolts]]
a = [0.5, 0.25]
b = [1.5, -1.0]
stiffness = "2 MN/m"
pretension = 1000.0
strength = 5.0e4
shear_stiffness = 1.0e5
name = "rock bolt"

[[bolts]]
a = [0.2, 0.25]
b = [0.2, 3.0]
block_b = "ground"
stiffness = 1.0e6
"""
    model, settings = model_from_dict(tomllib.loads(text), "m.toml")
    first, second = model.bolts
    assert (first.block_a, first.block_b, first.stiffness, first.strength) == (1, 0, 2e6, 5e4)
    assert second.block_b == -1 and second.strength == np.inf and second.name == "bolt 1"
    again, _ = model_from_dict(model_to_dict(model, settings), "again")
    assert len(again.bolts) == 2 and all(np.array_equal(getattr(a, f.name), getattr(b, f.name))
                                         for a, b in zip(again.bolts, model.bolts) for f in dataclasses.fields(a))
    arrays = model.arrays()
    state = run(arrays, settings).final_state
    assert bolt_forces(arrays.links, state).axial.shape == (2,)


@pytest.mark.parametrize("bolt, message", [
    ('a = [0.5, 0.25]\nb = [1.5, -1.0]\nstiffness = 0.0\n', "bolts[0].stiffness"),
    ('a = [0.5, 0.25]\nb = [0.6, 0.3]\nstiffness = 1e6\n', "both ends lie in block 'block'"),
    ('a = [0.5, 0.25]\nb = [1.5, -1.0]\nstiffness = 1e6\npretension = 10.0\nstrength = 5.0\n', "exceeds the strength"),
    ('a = [0.5, 0.25]\nb = [1.5, 3.0]\nstiffness = 1e6\n', "lies in no block"),
    ('a = [0.5, 0.25]\nb = [1.5, -1.0]\nstiffness = 1e6\nlength = 3\n', "bolts[0].length: unknown field"),
    ('a = [0.5, 0.25]\nb = [1.5, -1.0]\nstiffness = 1e6\nblock_b = "nowhere"\n', "no block named 'nowhere'"),
])
def test_a_bad_bolt_is_one_error_naming_it(bolt: str, message: str):
    with pytest.raises(ModelFileError) as err:
        model_from_dict(tomllib.loads(MODEL + "[[bolts]]\n" + bolt), "m.toml")
    assert message in str(err.value)


def test_the_model_figure_draws_the_bolts_and_the_example_loads():
    from srdda.io.modelfile import load_model
    from srdda.io.records import SYNTHETIC_RECORD, record_history
    from srdda.apps.plotting import fig_configuration

    arrays = _bolted(4e4).arrays()
    fig = fig_configuration(arrays)
    bolt_lines = [ln for ln in fig.axes[0].get_lines() if ln.get_label() == "bolt"]
    np.testing.assert_allclose(bolt_lines[0].get_xydata(), [[0.5, 0.0], list(ANCHOR)])
    example = Path(__file__).resolve().parents[1] / "examples" / "records" / "quake-bolted-block.toml"
    model, settings = load_model(example)
    assert [b.name for b in model.bolts] == ["lower bolt", "upper bolt"] and settings.end_time == 6.5
    expected = record_history(SYNTHETIC_RECORD, scale=1.5, baseline="linear", components="x")
    np.testing.assert_array_equal(model.base_acceleration.table, expected.table)


def test_a_bolt_in_3d_moves_its_extruded_block_as_in_2d():
    k, p0, dt, n = 4e4, 500.0, 1e-3, 100
    flat = run(_bolted(k, p0, shear=1e4), RunSettings(dt=dt, n_steps=n, method="dda0"))
    solid = run(_bolted(k, p0, shear=1e4).extruded(1.0), RunSettings(dt=dt, n_steps=n, method="dda0",
                                                                     contacts=False))
    # the same discrete equations in the plane z = 0 (a unit thickness): round-off
    np.testing.assert_allclose(solid.array("centroid")[:, 0, :2], flat.array("centroid")[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(solid.array("bolt_force"), flat.array("bolt_force"), rtol=1e-9)
