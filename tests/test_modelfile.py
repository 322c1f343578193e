"""The model file: units, references, round trip, and errors that name the field."""
from pathlib import Path

import numpy as np
import pytest

import srdda
from srdda.io import ModelFileError, load_model, model_from_dict, save_model

DATA = Path(__file__).parent / "data"


def test_load_converts_units_and_resolves_blocks():
    model, settings = load_model(DATA / "two_blocks.toml")
    a = model.arrays()
    assert settings.dt == pytest.approx(2e-3) and settings.method == "dda1" and settings.penalty == 1e9
    assert a.block_density[0] == 2500.0 and model.materials["rock"].young == 1e10
    assert a.attached.point_block[a.attached.fixed_rows].tolist() == [0]  # located by coordinates
    assert a.attached.point_block[a.attached.point_spring_rows_b].tolist() == [1]  # by index
    assert a.attached.point_block[a.attached.measured_rows].tolist() == [1]
    assert a.attached.load_force[0](0.02) == pytest.approx([500.0, 0.0])  # linear interpolation of the table


def test_round_trip_gives_the_same_model(tmp_path):
    model, settings = load_model(DATA / "two_blocks.toml")
    save_model(model, settings, tmp_path / "copy.toml")
    model2, settings2 = load_model(tmp_path / "copy.toml")
    a, b = model.arrays(), model2.arrays()
    assert settings2 == settings
    for name in ("vertex_position", "block_ptr", "block_density", "block_elasticity", "block_velocity"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for name in ("point_position", "point_block"):
        assert np.array_equal(getattr(a.attached, name), getattr(b.attached, name)), name


def test_a_sine_point_load_is_a_clear_error_when_saved(tmp_path):
    # a model file's point load is a force or a table; a sine one used to fail with a TypeError
    model, settings = load_model(DATA / "two_blocks.toml")
    model.add_point_load(model.point_loads[0][1], srdda.TimeHistory.sine((1.0, 0.0), 0.5),
                         block=model.point_loads[0][0])
    with pytest.raises(ModelFileError, match="sine history"):
        save_model(model, settings, tmp_path / "copy.toml")
    assert not (tmp_path / "copy.toml").exists()


def test_model_file_runs():
    model, settings = load_model(DATA / "two_blocks.toml")
    assert srdda.run(model, settings).completed


def _base():
    return {"run": {"dt": 0.001, "steps": 1}, "materials": {"m": {"density": 1.0, "young": 1e9, "poisson": 0.2}},
            "blocks": [{"material": "m", "vertices": [[0, 0], [1, 0], [0, 1]]}]}


@pytest.mark.parametrize("patch, field, problem", [
    (lambda d: d["run"].pop("dt"), "run.dt", "required field is missing"),
    (lambda d: d["run"].update(stepz=3), "run.stepz", "unknown field"),
    (lambda d: d["run"].update(method="dda2"), "run.method", "dda0"),
    (lambda d: d["materials"]["m"].update(young="3 psi"), "materials.m.young", "unit 'psi'"),
    (lambda d: d["materials"]["m"].update(poisson=0.7), "materials.m.poisson", "less than 0.5"),
    (lambda d: d["blocks"][0].update(vertices=[[0, 0], [1, 1]]), "blocks[0].vertices", "at least 3"),
    (lambda d: d["blocks"][0].update(vertices=[[0, 0], [1, 1], [1, 0], [0, 1]]), "blocks[0]", "not simple"),
    (lambda d: d["blocks"][0].update(material="granite"), "blocks[0].material", "unknown material"),
    (lambda d: d.update(fixed_points=[{"at": [5, 5]}]), "fixed point", "lies in no block"),
    (lambda d: d.update(point_loads=[{"at": [0.1, 0.1]}]), "point_loads[0]", "exactly one of"),
    (lambda d: d.update(point_springs=[{"a": [0.1, 0.1], "b": [0.1, 0.1], "block_a": "x", "stiffness": 1}]),
     "point_springs[0]", "no block named 'x'"),
])
def test_bad_input_names_the_field(patch, field, problem):
    data = _base()
    patch(data)
    with pytest.raises(ModelFileError) as info:
        model_from_dict(data, "m.toml")
    msg = str(info.value)
    assert msg.startswith("m.toml") and field in msg and problem in msg, msg


def test_unreadable_and_malformed_files(tmp_path):
    with pytest.raises(ModelFileError, match="cannot read"):
        load_model(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[run\ndt = 1")
    with pytest.raises(ModelFileError, match="not valid TOML"):
        load_model(bad)


def test_an_ensemble_file_given_as_a_model_says_so():
    # a new user's first try: `srdda run` on an ensemble file gave six schema errors; now one sentence
    ensemble = Path(__file__).parents[1] / "examples" / "ensembles" / "rockfall-2d.toml"
    with pytest.raises(ModelFileError, match=r"ensemble file .* `srdda ensemble`"):
        load_model(ensemble)
