"""The command line: exit codes and messages, not tracebacks."""
import json
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from srdda.apps.cli import main

DATA = Path(__file__).parent / "data"


def test_run_writes_histories(tmp_path):
    res = CliRunner().invoke(main, ["run", str(DATA / "two_blocks.toml"), "--out", str(tmp_path), "--quiet",
                                    "--method", "srdda", "--steps", "5"])
    assert res.exit_code == 0, res.output
    h = np.load(tmp_path / "histories.npz")
    assert h["step"].tolist() == [0, 1, 2, 3, 4, 5]
    assert h["centroid"].shape == (6, 2, 2)
    assert json.loads((tmp_path / "summary.json").read_text())["method"] == "srdda"


def test_bad_model_file_gives_a_message_not_a_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text((DATA / "two_blocks.toml").read_text().replace("poisson = 0.2", "poisson = 0.8"))
    res = CliRunner().invoke(main, ["check", str(bad)])
    assert res.exit_code == 2
    assert "materials.rock.poisson" in res.output and "Traceback" not in res.output


def test_check_and_info():
    runner = CliRunner()
    res = runner.invoke(main, ["check", str(DATA / "two_blocks.toml")])
    assert res.exit_code == 0 and "2 blocks" in res.output
    res = runner.invoke(main, ["info"])
    assert res.exit_code == 0 and "superlu" in res.output


def test_diverging_run_stops_with_a_message_and_keeps_its_steps(tmp_path):
    # a block under a gravity of 1e200 m/s²: its kinetic energy overflows at the first step
    model = tmp_path / "overflow.toml"
    model.write_text("""
gravity = [0.0, -1e200]
[run]
dt = 0.01
steps = 10
[materials.rock]
density = 2500.0
young = 1e6
poisson = 0.2
[[blocks]]
material = "rock"
vertices = [[0, 0], [1, 0], [1, 1], [0, 1]]
""")
    res = CliRunner().invoke(main, ["run", str(model), "--out", str(tmp_path / "out"), "--quiet"])
    assert res.exit_code == 3, res.output
    assert "diverged: step 1:" in res.output and "kinetic" in res.output
    assert np.load(tmp_path / "out" / "histories.npz")["step"].tolist() == [0]


def test_paper_report_lists_every_row(tmp_path):
    res = CliRunner().invoke(main, ["paper", "rod", "--method", "dda0", "--report", str(tmp_path), "--quiet"])
    assert res.exit_code == 0, res.output
    text = (tmp_path / "report.md").read_text()
    # Table 3 has 4 steps and Table 4 two directions: 6 rows, each with DDA0's value beside the paper's
    rows = [line for line in text.splitlines() if line.startswith(("| area |", "| omega_max"))]
    assert len(rows) == 6 and "### Table 4" in text and (tmp_path / "report.html").exists()
