"""The command line as a new user meets it: exit codes as docs/cli.md says, `run --dt`, help texts in the
user's words, progress bars (with an estimate for `verify`) on the commands that take long."""
from __future__ import annotations

import re
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from srdda.apps import cli, cli_results
from srdda.apps.cli import main
from srdda.io.results_store import read_results
from srdda.apps.verify import CASES, EXPECTED_SECONDS, expected_seconds

DATA = Path(__file__).parent / "data"
MODEL = DATA / "two_blocks.toml"


def test_an_output_holding_results_is_bad_input_exit_2(tmp_path: Path) -> None:
    runner = CliRunner()
    args = ["run", str(MODEL), "--out", str(tmp_path), "--quiet", "--steps", "3"]
    assert runner.invoke(main, args).exit_code == 0
    again = runner.invoke(main, args)
    assert again.exit_code == 2, again.output
    assert "--overwrite" in again.output and "Traceback" not in again.output


def test_run_dt_overrides_the_model_s_time_step(tmp_path: Path) -> None:
    res = CliRunner().invoke(main, ["run", str(MODEL), "--out", str(tmp_path), "--quiet", "--steps", "4",
                                    "--dt", "2.5e-4"])
    assert res.exit_code == 0, res.output
    stored = read_results(tmp_path / "results.h5")
    assert stored.settings.dt == 2.5e-4
    assert stored.time[-1] == pytest.approx(4 * 2.5e-4, rel=1e-12)
    bad = CliRunner().invoke(main, ["run", str(MODEL), "--out", str(tmp_path / "b"), "--dt", "-1"])
    assert bad.exit_code == 2 and "--dt" in bad.output


def _commands(group: click.Group) -> list[tuple[str, click.Command]]:
    return [(name, cmd) for name, cmd in group.commands.items()]


def test_help_texts_name_no_internal_issue_numbers() -> None:
    runner = CliRunner()
    for name, _ in [("", main), *_commands(main)]:
        text = runner.invoke(main, [name, "--help"] if name else ["--help"]).output
        assert not re.search(r"\bissue \d+", text), (name, text)


class _Bar:
    """A stand-in for tqdm that records what a command tells its bar."""

    made: list[_Bar] = []

    def __init__(self, total=None, **kwargs) -> None:
        self.total, self.n, self.kwargs = total, 0, kwargs
        _Bar.made.append(self)

    def update(self, n: int = 1) -> None:
        self.n += n

    def set_description(self, text: str) -> None:
        self.kwargs["desc"] = text

    def write(self, text: str, file=None) -> None:
        click.echo(text, err=True)

    def __enter__(self) -> _Bar:
        return self

    def __exit__(self, *exc) -> None:
        pass


@pytest.fixture
def bars(monkeypatch: pytest.MonkeyPatch) -> list[_Bar]:
    _Bar.made = []
    monkeypatch.setattr(cli, "tqdm", _Bar)
    monkeypatch.setattr(cli_results, "tqdm", _Bar)
    return _Bar.made


def test_every_verification_case_has_an_estimate() -> None:
    assert set(EXPECTED_SECONDS) == set(CASES)
    assert all(0 < quick <= full for quick, full in EXPECTED_SECONDS.values())


def test_verify_counts_its_estimate_down(bars: list[_Bar]) -> None:
    res = CliRunner().invoke(main, ["verify", "free-spin-2d", "free-fall-2d", "--quick"])
    assert res.exit_code == 0, res.output
    (bar,) = bars
    expected = expected_seconds("free-spin-2d", True) + expected_seconds("free-fall-2d", True)
    assert bar.total == round(expected) and bar.n == bar.total


def test_vtk_and_animate_show_progress(tmp_path: Path, bars: list[_Bar]) -> None:
    runner = CliRunner()
    assert runner.invoke(main, ["run", str(MODEL), "--out", str(tmp_path), "--steps", "9", "--quiet"]).exit_code == 0
    bars.clear()
    res = runner.invoke(main, ["vtk", str(tmp_path), "-o", str(tmp_path / "vtk"), "--every", "4"])
    assert res.exit_code == 0, res.output
    assert [(b.total, b.n) for b in bars] == [(4, 4)]  # steps 0, 4, 8 and the last, 9
    bars.clear()
    res = runner.invoke(main, ["animate", str(tmp_path), "-o", str(tmp_path / "a.gif"), "--frames", "5"])
    assert res.exit_code == 0, res.output
    assert [(b.total, b.n) for b in bars] == [(5, 5)]
