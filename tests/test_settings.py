"""RunSettings: the one definition of the run settings, validated once, used by the API, files and CLI."""
from __future__ import annotations

import dataclasses
import math

import pytest
from click.testing import CliRunner
from pydantic import ValidationError

import srdda
import srdda.io
from srdda import settings as settings_module
from srdda.apps.cli import main
from srdda.io.modelfile import ModelFileError, model_from_dict
from srdda.settings import RunSettings


def _message(**kwargs) -> str:
    with pytest.raises(ValidationError) as info:
        RunSettings(**kwargs)
    return str(info.value)


@pytest.mark.parametrize("dt", [0.0, -1e-3, math.nan, math.inf, 1e-300, 1e300])
def test_a_time_step_the_run_cannot_use_is_rejected(dt):
    assert "dt" in _message(dt=dt, n_steps=10)


@pytest.mark.parametrize("factor", [0.0, 0.9999999, 1.0, 1.5])
def test_a_step_cut_factor_that_never_shrinks_the_step_is_rejected(factor):
    assert "step_cut_factor" in _message(dt=1e-3, n_steps=1, step_cut_factor=factor)


def test_a_solver_that_is_not_installed_is_rejected(monkeypatch):
    monkeypatch.setattr(settings_module, "available_solvers", lambda: ["auto", "dense", "superlu"])
    assert "solver 'pardiso' is not installed" in _message(dt=1e-3, n_steps=1, solver="pardiso")


def test_rho_inf_with_a_scheme_that_ignores_it_is_rejected():
    assert "rho_inf = 0.5 has no effect" in _message(dt=1e-3, n_steps=1, method="dda1", rho_inf=0.5)
    assert "rho_inf = 0.5 has no effect" in _message(dt=1e-3, n_steps=1, scheme="shi", rho_inf=0.5)
    RunSettings(dt=1e-3, n_steps=1, method="srdda", rho_inf=0.5)  # the paper's scheme uses it


def test_a_run_needs_a_length():
    assert "give n_steps" in _message(dt=1e-3)


def test_replace_validates_again():
    s = RunSettings(dt=1e-3, n_steps=1)
    with pytest.raises(ValidationError):
        dataclasses.replace(s, dt=-1.0)


def test_the_model_file_validates_into_the_same_settings():
    data = {"run": {"dt": "2 ms", "steps": 5, "penalty": "1 GN/m"}, "materials": {"m": {"density": 1.0,
            "young": 1e9, "poisson": 0.2}}, "blocks": [{"material": "m", "vertices": [[0, 0], [1, 0], [1, 1]]}]}
    _, s = model_from_dict(data)
    assert s == RunSettings(dt=2e-3, n_steps=5, penalty=1e9)
    data["run"]["step_cut_factor"] = 0.9999999
    with pytest.raises(ModelFileError, match=r"run.step_cut_factor"):
        model_from_dict(data)


def test_cli_override_that_conflicts_names_the_option(tmp_path):
    model = srdda.Model()
    model.add_material("m", srdda.Material(1000.0, 1e9, 0.2))
    model.add_block([[0, 0], [1, 0], [1, 1]], "m")
    path = tmp_path / "m.toml"
    srdda.io.save_model(model, RunSettings(dt=1e-3, n_steps=2, rho_inf=0.5), path)
    out = CliRunner().invoke(main, ["run", str(path), "--method", "dda0", "--out", str(tmp_path / "o")])
    assert out.exit_code == 2 and "--method" in out.output and "rho_inf = 0.5" in out.output
    assert "Traceback" not in out.output


def test_end_time_is_reached_exactly():
    model = srdda.Model(gravity=(0.0, -9.81))
    model.add_material("m", srdda.Material(1000.0, 1e9, 0.2))
    model.add_block([[0, 0], [1, 0], [1, 1]], "m")
    result = srdda.run(model, RunSettings(dt=0.3e-2, end_time=0.01))
    assert result.completed
    assert result.time[-1] == pytest.approx(0.01, rel=1e-12)  # the last step is shortened to land on it
    assert result.step[-1] == 4  # 3 steps of 3 ms and one of 1 ms


def test_cli_end_time_replaces_the_step_count(tmp_path):
    model = srdda.Model(gravity=(0.0, -9.81))
    model.add_material("m", srdda.Material(1000.0, 1e9, 0.2))
    model.add_block([[0, 0], [1, 0], [1, 1]], "m")
    path = tmp_path / "m.toml"
    srdda.io.save_model(model, RunSettings(dt=1e-3, n_steps=1000), path)
    out = CliRunner().invoke(main, ["run", str(path), "--end-time", "0.0105", "--out", str(tmp_path / "o"),
                                    "--quiet"])
    assert out.exit_code == 0, out.output
    stored = srdda.read_results(tmp_path / "o" / "results.h5")
    assert stored.array("time")[-1] == pytest.approx(0.0105, rel=1e-12) and stored.array("step")[-1] == 11
    bad = CliRunner().invoke(main, ["run", str(path), "--end-time", "-1", "--out", str(tmp_path / "p")])
    assert bad.exit_code == 2 and "end_time" in bad.output and "Traceback" not in bad.output
