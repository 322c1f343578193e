"""Run settings that contradict each other are an error; settings that would be ignored are a warning."""
from __future__ import annotations

import warnings

import pytest

import srdda


def test_contact_penalty_and_auto_penalty_together_are_an_error() -> None:
    with pytest.raises(ValueError, match="contact_penalty .* or auto_penalty .* not both"):
        srdda.RunSettings(dt=1e-3, n_steps=10, contact_penalty=1e9, auto_penalty=10.0)


def test_min_dt_not_below_dt_is_an_error() -> None:
    with pytest.raises(ValueError, match="min_dt = 0.001 s must be below dt = 0.001 s"):
        srdda.RunSettings(dt=1e-3, n_steps=10, min_dt=1e-3)


def test_contact_settings_without_contacts_warn_naming_them() -> None:
    with pytest.warns(UserWarning, match="contacts = false: contact_penalty, shear_ratio have no effect"):
        srdda.RunSettings(dt=1e-3, n_steps=10, contacts=False, contact_penalty=1e9, shear_ratio=0.2)


def test_secant_iterations_without_the_secant_pass_warn() -> None:
    with pytest.warns(UserWarning, match="secant_max_iterations has no effect with method 'dda0'"):
        srdda.RunSettings(dt=1e-3, n_steps=10, method="dda0", secant_max_iterations=3)


def test_consistent_settings_give_no_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        srdda.RunSettings(dt=1e-3, n_steps=10, method="srdda", secant_max_iterations=3, contact_penalty=1e9)
        srdda.RunSettings(dt=1e-3, n_steps=10, contacts=False)


def test_the_cli_gives_a_settings_warning_as_one_line(tmp_path) -> None:
    from click.testing import CliRunner

    from srdda.apps.cli import main

    model = tmp_path / "m.toml"
    model.write_text('[run]\ndt = 0.001\nsteps = 2\ncontacts = false\nshear_ratio = 0.2\n\n'
                     '[materials.rock]\ndensity = 2000\nyoung = 1e9\npoisson = 0.2\n\n'
                     '[[blocks]]\nmaterial = "rock"\nvertices = [[0, 0], [1, 0], [1, 1], [0, 1]]\n')
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        res = CliRunner().invoke(main, ["check", str(model)])
    assert res.exit_code == 0, res.output
    assert "warning: contacts = false: shear_ratio has no effect\n" in res.output
    assert "UserWarning" not in res.output and "pydantic" not in res.output
