"""Earthquake records (srdda.io.records): .AT2 and CSV files, units, scale, baseline correction, resampling,
the model file's [base_acceleration] record, and one clear error per bad file."""
import tomllib
from pathlib import Path

import numpy as np
import pytest

from srdda.io.modelfile import ModelFileError, load_model, model_from_dict
from srdda.io.records import (SYNTHETIC_RECORD, RecordError, baseline_correct, read_record, record_history,
                              synthetic_record, write_at2, write_csv)
from srdda.units import STANDARD_GRAVITY

DT = 0.02


def _wave(n: int = 301) -> tuple[np.ndarray, np.ndarray]:
    """A record with a velocity drift: a sine plus an offset (values in g)."""
    t = DT * np.arange(n)
    return t, 0.2 * np.sin(2 * np.pi * 1.5 * t) + 0.01


def test_at2_round_trip_keeps_the_values_to_the_formats_digits(tmp_path: Path):
    t, a = _wave()
    path = tmp_path / "wave.AT2"
    write_at2(path, DT, a)
    rec = read_record(path)
    np.testing.assert_allclose(rec.time, t, rtol=0, atol=1e-15)  # i·DT, computed the same way
    # E format with 7 decimals in the mantissa: 8 significant digits, relative 5e-8
    np.testing.assert_allclose(rec.values[:, 0], a, rtol=1e-7, atol=1e-12)
    assert rec.units == "g" and rec.axes == ("x",)


def test_at2_in_the_older_npts_dt_layout_is_read(tmp_path: Path):
    path = tmp_path / "old.at2"
    path.write_text("PEER\nev\nACCELERATION TIME SERIES IN UNITS OF G\n   3   0.0100   NPTS, DT\n 0.1 0.2 -0.3\n")
    rec = read_record(path)
    np.testing.assert_array_equal(rec.values[:, 0], [0.1, 0.2, -0.3])
    np.testing.assert_allclose(rec.time, [0.0, 0.01, 0.02], rtol=1e-15)


def test_csv_round_trip_is_exact(tmp_path: Path):
    t, a = _wave()
    values = np.column_stack([a, -0.5 * a, 0.1 * a])
    path = tmp_path / "wave.csv"
    write_csv(path, t, values)
    rec = read_record(path)
    np.testing.assert_array_equal(rec.time, t)  # repr() keeps every bit
    np.testing.assert_array_equal(rec.values, values)
    assert rec.axes == ("x", "y", "z") and rec.units == "m/s2"


def test_units_and_scale(tmp_path: Path):
    t, a = _wave()
    path = tmp_path / "wave.AT2"
    write_at2(path, DT, a)
    in_g = record_history(path, scale=2.0).table
    as_si = record_history(path, units="m/s2").table
    as_gal = record_history(path, units="cm/s2").table
    raw = read_record(path).values[:, 0]
    n = len(raw)
    # exact conversions of the same samples: a multiplication each, round-off only
    np.testing.assert_allclose(in_g[:n, 1], 2.0 * STANDARD_GRAVITY * raw, rtol=1e-15)
    np.testing.assert_allclose(as_si[:n, 1], raw, rtol=1e-15)
    np.testing.assert_allclose(as_gal[:n, 1], 0.01 * raw, rtol=1e-15)
    assert np.all(in_g[:, 2] == 0.0)  # an .AT2 drives x only by default
    # the record ends: one zero sample one interval after the last
    assert in_g[-1, 0] == pytest.approx(t[-1] + DT, rel=1e-14) and np.all(in_g[-1, 1:] == 0.0)


@pytest.mark.parametrize("baseline", ["mean", "linear", "quadratic"])
def test_baseline_correction_brings_the_ground_to_rest(tmp_path: Path, baseline: str):
    t, a = _wave()
    path = tmp_path / "wave.AT2"
    write_at2(path, DT, a)
    raw = record_history(path)
    corrected = record_history(path, baseline=baseline)
    after = corrected.table[-1, 0] + 1.0
    drift = raw.integral(after)[0]
    assert abs(drift) > 0.5  # the offset of 0.01 g over 6 s leaves the uncorrected ground moving at ~0.6 m/s
    # the corrected velocity (the run's own integral of the table) is 0 at the end: round-off of ~300
    # trapezoids of ~2 m/s², i.e. 1e-13 of the peak velocity
    assert abs(corrected.integral(after)[0]) < 1e-12 * np.max(np.abs(raw.table[:, 1]))
    # what was subtracted is a polynomial of the stated degree in t (the end sample stays 0)
    removed = raw.table[:-1, 1] - corrected.table[:-1, 1]
    degree = {"mean": 0, "linear": 1, "quadratic": 2}[baseline]
    fit = np.polynomial.polynomial.Polynomial.fit(raw.table[:-1, 0], removed, degree)
    assert np.max(np.abs(fit(raw.table[:-1, 0]) - removed)) < 1e-12
    assert corrected.table[-1, 1] == 0.0


def test_baseline_least_squares_beats_the_constant_on_a_linear_velocity_drift():
    """A linear baseline removes a quadratic velocity drift (an acceleration offset growing in t); the mean cannot."""
    t = np.linspace(0.0, 10.0, 1001)
    a = (0.3 * np.cos(2 * np.pi * t) + 0.02 + 0.004 * t)[:, None]
    wave = 0.3 / (2 * np.pi) * np.sin(2 * np.pi * t)  # the velocity of the drift-free record
    v = {m: np.cumsum(np.r_[0, 0.5 * np.diff(t) * (c[1:, 0] + c[:-1, 0])])
         for m in ("mean", "linear") for c in [baseline_correct(t, a, m)]}
    assert abs(v["mean"][-1]) < 1e-12 and abs(v["linear"][-1]) < 1e-12  # both end at rest
    # the mean leaves 0.004(t²/2 - 5t) (5 cm/s at mid-record); the linear fit takes the drift and a
    # sliver of the sine (orthogonal to the basis but for its ends)
    assert np.max(np.abs(v["mean"] - wave)) > 0.04
    assert np.max(np.abs(v["linear"] - wave)) < 0.1 * np.max(np.abs(v["mean"] - wave))


def test_the_record_is_a_function_of_time_linear_between_samples(tmp_path: Path):
    f = 1.3  # Hz
    t = DT * np.arange(200)
    path = tmp_path / "sine.csv"
    write_csv(path, t, np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)]))
    history = record_history(path)
    probe = np.random.default_rng(0).uniform(0.0, t[-1], 500)  # any times, not the samples, not a step grid
    got = np.array([history(s) for s in probe])
    exact = np.column_stack([np.sin(2 * np.pi * f * probe), np.cos(2 * np.pi * f * probe)])
    # linear interpolation of a unit sine: error at most (2πf)²·DT²/8 = 3.3e-3
    bound = (2 * np.pi * f) ** 2 * DT**2 / 8
    assert np.max(np.abs(got - exact)) <= bound * (1 + 1e-9)
    at_samples = np.array([history(s) for s in t])
    np.testing.assert_array_equal(at_samples, np.column_stack([np.sin(2 * np.pi * f * t),
                                                               np.cos(2 * np.pi * f * t)]))  # the samples


def test_the_shipped_synthetic_record_is_the_documented_generators():
    dt, values = synthetic_record()
    rec = read_record(SYNTHETIC_RECORD)
    assert rec.time[1] == pytest.approx(dt, rel=1e-12) and len(rec.time) == len(values)
    np.testing.assert_allclose(rec.values[:, 0], values, rtol=1e-7, atol=1e-12)  # the file's 8 digits
    assert np.max(np.abs(rec.values)) == pytest.approx(0.35, rel=1e-7)


@pytest.mark.parametrize("text, message", [
    ("PEER\nev\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS= 3, DT= 0.01 SEC\n0.1 0.2\n", ":4: the header says NPTS=3"),
    ("PEER\nev\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS= 3, DT= 0.01 SEC\n0.1 0.x2 0.3\n", ":5: '0.x2'"),
    ("PEER\nev\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS 3 DT 0.01\n0.1 0.2 0.3\n", ":4: expected 'NPTS="),
    ("PEER\nev\nVELOCITY TIME SERIES IN UNITS OF CM/S\nNPTS= 1, DT= 0.01 SEC\n0.1\n", ":3: the header says"),
    ("PEER\nev\n", "4 header lines"),
])
def test_a_bad_at2_is_one_error_naming_the_file_and_line(tmp_path: Path, text: str, message: str):
    path = tmp_path / "bad.AT2"
    path.write_text(text)
    with pytest.raises(RecordError) as err:
        record_history(path)
    assert str(path) in str(err.value) and message in str(err.value)


@pytest.mark.parametrize("text, message", [
    ("time, ax, ay\n0, 1, 2\n0.1, 1, x\n", ":3: 'x' is not a number"),
    ("time, ax, ay\n0, 1, 2\n0.1, 1\n", ":3: 2 columns"),
    ("0, 1, 2\n0.1, 1, 2\n0.1, 0, 0\n", ":3: times must increase strictly"),
    ("time, ax, ay\n0.5, 1, 2\n0.6, 1, 2\n", ":2: the record must start at time 0"),
    ("t, a\n0, 1\n", ":1: the header must be"),
    ("0, 1, 2\n", "at least two rows"),
])
def test_a_bad_csv_is_one_error_naming_the_file_and_line(tmp_path: Path, text: str, message: str):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(RecordError) as err:
        record_history(path)
    assert str(path) in str(err.value) and message in str(err.value)


def test_components_must_fit_the_record_and_the_model(tmp_path: Path):
    path = tmp_path / "r.csv"
    write_csv(path, np.arange(3.0), np.ones((3, 3)))
    with pytest.raises(RecordError, match="components must name"):
        record_history(path, dim=2)  # az in a 2D model
    assert record_history(path, dim=3).table.shape == (4, 4)
    single = tmp_path / "one.AT2"
    write_at2(single, 0.01, np.ones(4))
    table = record_history(single, components="y").table
    assert np.all(table[:-1, 2] == STANDARD_GRAVITY) and np.all(table[:, 1] == 0.0)


MODEL = """
gravity = [0.0, -9.81]
[run]
dt = 1e-3
steps = 3
[materials.rock]
density = 2500.0
young = 1e9
poisson = 0.25
[[blocks]]
material = "rock"
vertices = [[0, 0], [1, 0], [1, 1], [0, 1]]
[base_acceleration]
"""


def test_the_model_file_reads_a_record_relative_to_its_folder(tmp_path: Path):
    (tmp_path / "records").mkdir()
    write_at2(tmp_path / "records" / "q.AT2", 0.01, np.array([0.0, 0.1, -0.1, 0.05]))
    model_path = tmp_path / "m.toml"
    model_path.write_text(MODEL + 'record = "records/q.AT2"\nscale = 2.0\nbaseline = "mean"\ncomponents = "x"\n')
    model, _ = load_model(model_path)
    expected = record_history(tmp_path / "records" / "q.AT2", scale=2.0, baseline="mean")
    np.testing.assert_array_equal(model.base_acceleration.table, expected.table)


@pytest.mark.parametrize("extra, message", [
    ('record = "missing.AT2"\n', "base_acceleration.record:"),
    ('record = "bad.AT2"\n', "bad.AT2:5: 'oops' is not a number"),
    ('record = "bad.AT2"\nconstant = [1.0, 0.0]\n', "either 'record' or a history"),
    ('constant = [1.0, 0.0]\nscale = 2.0\n', "scale apply to a record"),
    ('record = "bad.AT2"\nbaseline = "cubic"\n', "base_acceleration.baseline"),
])
def test_a_bad_record_in_a_model_file_is_one_clear_error(tmp_path: Path, extra: str, message: str):
    (tmp_path / "bad.AT2").write_text("PEER\nev\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS= 2, DT= 0.01 SEC\n"
                                      "0.1 oops\n")
    with pytest.raises(ModelFileError) as err:
        model_from_dict(tomllib.loads(MODEL + extra), "m.toml", tmp_path)
    assert message in str(err.value)
