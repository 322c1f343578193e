"""`srdda check` finds what `srdda run` cannot do or would silently change (issue 32, item 3).

Each case was accepted by `check` before: the run then stopped at its first
steps ("singular system"), or ran a model other than the one written (the last
of two joint materials, `true` read as 1), or ended "completed" with infinite
energies. Now `check` and `run` refuse each with one message naming the item
(exit 2), before any output is made, and a run whose values overflow ends
"diverged" (exit 3).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import srdda
from srdda.apps.cli import main
from srdda.io.modelfile import load_model

ROOT = Path(__file__).resolve().parents[1]
WALL = (ROOT / "examples" / "constraints" / "hinged-wall.toml").read_text()  # a wall hinged to a fixed foundation
BOXES = (ROOT / "examples" / "solid" / "hinged-boxes.toml").read_text()  # 3D: a box pinned, a box hinged to it
HINGE = '[[hinges]]\nat = [0.4, 0.0]\nblock_a = "wall"\nblock_b = "foundation"\nname = "toe"\n'
TIE = 'a = [0.0, 2.0]\nb = [-1.0, 0.0]\nblock_a = "wall"\n'


def _refused(tmp_path: Path, text: str, expected: str) -> str:
    """`check` and `run` of ``text`` end with exit 2 and one message holding ``expected``; no output folder."""
    path = tmp_path / "model.toml"
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    for args in (["check", str(path)], ["run", str(path), "--out", str(out), "--quiet"]):
        result = CliRunner().invoke(main, args)
        assert result.exit_code == 2, result.output
        assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
        assert expected in result.output and "Traceback" not in result.output, result.output
    assert not out.exists()
    return result.output


@pytest.mark.parametrize("old, new, field", [
    ("poisson = 0.2", "poisson = false", "materials.masonry.poisson"),
    ('at = [0.0, 2.0]\nblock = "wall"', 'at = [0.0, 2.0]\nblock = true', "measured_points[0].block"),
    ("steps = 2000", "steps = true", "run.steps"),
    ("at = [0.4, 0.0]", "at = [0.4, false]", "hinges[0].at"),
])
def test_a_boolean_where_a_number_or_a_name_is_expected_is_refused(tmp_path: Path, old: str, new: str,
                                                                   field: str) -> None:
    assert old in WALL
    _refused(tmp_path, WALL.replace(old, new, 1), f"{field}: true/false is not valid here")


def test_booleans_where_the_schema_wants_them_still_pass(tmp_path: Path) -> None:
    path = tmp_path / "model.toml"
    path.write_text(WALL.replace("[[blocks]]\nname = \"wall\"", "[[blocks]]\nname = \"wall\"\nfixed = false", 1)
                    .replace('name = "toe"', 'name = "toe"\ncorrect_drift = true'))
    result = CliRunner().invoke(main, ["check", str(path)])
    assert result.exit_code == 0 and result.output.startswith("ok:"), result.output


def test_an_integer_too_long_to_read_is_one_message(tmp_path: Path) -> None:
    # Python reads at most 4300 digits of an integer; tomllib let its ValueError through (a traceback)
    _refused(tmp_path, WALL.replace("steps = 2000", "steps = " + "9" * 5000), "not valid TOML (an integer has more "
                                                                              "digits than Python reads, 4300")


def test_two_joint_materials_for_one_pair_of_materials_are_refused(tmp_path: Path) -> None:
    # before: the second silently replaced the first (5° of friction instead of 35°)
    joints = ('[joint_materials.rough]\nfriction_angle = 35.0\nbetween = [["masonry", "masonry"]]\n'
              '[joint_materials.smooth]\nfriction_angle = 5.0\nbetween = [["masonry", "masonry"]]\n')
    text = WALL.replace("[[blocks]]", joints + "[[blocks]]", 1)
    _refused(tmp_path, text, "joint material 'smooth': the block materials ('masonry', 'masonry') already have "
                             "joint material 'rough'")


def test_a_moving_block_without_mass_that_nothing_holds_is_refused(tmp_path: Path) -> None:
    # density 0 and one fixed point: nothing resists its rotation about that point (the run stopped at step 1
    # with "singular system" when nothing held it at all, and solved a singular system by round-off with one point)
    rod = (ROOT / "src" / "srdda" / "data" / "examples" / "paper" / "rod.toml").read_text()
    _refused(tmp_path, rod.replace("density = 2500.0", "density = 0.0"),
             "moving blocks without mass (density 0) that nothing holds: 'rod' (material 'rock')")


def test_massless_blocks_held_at_enough_points_pass() -> None:
    # the paper's pendulum: a massless rod held by its pivot and by the bob's spring (two points), as it must run
    model, settings = load_model(ROOT / "src" / "srdda" / "data" / "examples" / "paper" / "pendulum.toml")
    assert srdda.run(model, srdda.RunSettings(dt=settings.dt, n_steps=3, penalty=settings.penalty,
                                              contacts=False)).completed
    m = srdda.Model()
    m.add_material("air", srdda.Material(0.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "air")
    m.add_pin([0.0, 0.0], 0)
    with pytest.raises(srdda.ModelError, match="without mass"):
        m.arrays()  # one pin: it turns freely about it
    m.add_pin([1.0, 1.0], 0)
    assert srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=3, contacts=False)).completed  # two pins hold it


def test_a_hinge_given_twice_is_refused(tmp_path: Path) -> None:
    assert HINGE in WALL
    _refused(tmp_path, WALL + "\n" + HINGE.replace('"toe"', '"toe2"'),
             "redundant constraints: 'toe2' repeats what 'toe' already imposes")


def test_a_3d_pin_given_twice_is_refused(tmp_path: Path) -> None:
    _refused(tmp_path, BOXES + '\n[[pins]]\nat = [0.0, 0.1, 0.1]\nblock = "a"\nname = "again"\n',
             "redundant constraints: 'again' repeats what 'pin 1' already imposes")  # hinges are counted first


@pytest.mark.parametrize("points, redundant", [
    ([[0, 0], [1, 0], [1, 1], [0, 1]], "'pin 3' repeats what 'pin 0' and 'pin 1' and 'pin 2' already impose"),
    ([[0, 0], [0.5, 0], [1, 0]], "'pin 2' repeats what 'pin 0' and 'pin 1' already impose"),  # on one line
    ([[0, 0], [1, 0], [1, 1]], None),  # three pins not on a line: 6 constraints on 6 unknowns, independent
])
def test_pins_over_constraining_a_block_are_refused(points: list[list[float]], redundant: str | None) -> None:
    m = srdda.Model()
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    for p in points:
        m.add_pin(p, 0)
    if redundant is None:
        assert m.arrays().links.n_hinges == len(points)
    else:
        with pytest.raises(srdda.ModelError, match=redundant):
            m.arrays()


@pytest.mark.parametrize("section, what", [
    ('[[pins]]\nat = [1e6, 1.0]\nblock = "wall"\n', "pin 1: point (1000000.0, 1.0) lies outside block 'wall'"),
    ('[[fixed_points]]\nat = [1e6, 1.0]\nblock = "wall"\n',
     "fixed point: point (1000000.0, 1.0) lies outside block 'wall'"),
    ('[[point_loads]]\nat = [0.2, 1e6]\nblock = "wall"\nforce = [1.0, 0.0]\n',
     "point load: point (0.2, 1000000.0) lies outside block 'wall'"),
    ('[[springs]]\na = [1e6, 2.0]\nb = [-1.0, 0.0]\nblock_a = "wall"\nblock_b = "foundation"\nstiffness = 1e6\n',
     "spring end a: point (1000000.0, 2.0) lies outside block 'wall'"),
])
def test_a_point_outside_its_named_block_is_refused(tmp_path: Path, section: str, what: str) -> None:
    _refused(tmp_path, WALL + "\n" + section, what)


def test_a_run_whose_values_overflow_ends_diverged_not_completed(tmp_path: Path) -> None:
    # a block of density 1e300 under 1e6 m/s²: positions and velocities stay finite, the kinetic energy
    # overflows at step 2 (½·1e300·(2e4 m/s)² > 1.8e308). Before, the run ended "completed" (exit 0) with
    # infinite energies in four of its six recorded steps.
    path = tmp_path / "model.toml"
    path.write_text('gravity = [1e6, 0.0]\n[run]\ndt = 0.01\nsteps = 5\ncontacts = false\n'
                    '[materials.rock]\ndensity = 1e300\nyoung = 1e9\npoisson = 0.2\n'
                    '[[blocks]]\nmaterial = "rock"\nvertices = [[0, 0], [1, 0], [1, 1], [0, 1]]\n')
    result = CliRunner().invoke(main, ["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    assert result.exit_code == 3, result.output
    assert "diverged: step 2: non-finite energies: kinetic" in result.output
    stored = srdda.read_results(tmp_path / "out" / "results.h5")
    assert stored.status.startswith("diverged") and np.all(np.isfinite(stored.array("energy")))
    assert stored.step.tolist() == [0, 1]  # the overflowing step is not recorded
