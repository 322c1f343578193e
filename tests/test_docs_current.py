"""Docs and example files that say what the program does today (issue 31 item 9)."""
from __future__ import annotations

from pathlib import Path

import pytest

from srdda import RunSettings
from srdda.io.modelfile import load_model

ROOT = Path(__file__).resolve().parents[1]


def test_theory_3d_says_3d_contacts_exist_and_describes_a_hinge_about_an_axis() -> None:
    text = (ROOT / "docs" / "theory-3d.md").read_text(encoding="utf-8")
    assert "must set\n`contacts = false`" not in text and "the next step" not in text
    assert "### Hinges in 3D: ball joints, and a hinge about an axis" in text
    assert "come next" not in (ROOT / "examples" / "solid" / "hinged-boxes.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize("name, penalty", [("wedge-fs0.8", 1e11), ("wedge-fs1.2", 1e11),
                                           ("slide-topple-slides", 1e10), ("slide-topple-topples", 1e10)])
def test_slope_check_examples_use_the_verified_cases_settings(name: str, penalty: float) -> None:
    # srdda verify wedge-3d runs k_n = 1e11 N/m, slide-topple-3d 1e10, both with the default settling
    _, settings = load_model(ROOT / "examples" / "solid" / f"{name}.toml")
    assert settings.penalty == penalty
    assert settings.open_close_settle_after == RunSettings(dt=1e-3, n_steps=1).open_close_settle_after


def test_results_doc_gives_the_frames_of_3d_rotations() -> None:
    text = (ROOT / "docs" / "results.md").read_text(encoding="utf-8")
    assert "ω in the global (space) frame" in text and "(body frame) to its current one (space frame)" in text


def test_example_files_name_only_commands_that_exist() -> None:
    # cube-drop.toml pointed at `srdda results ... energy`, which does not exist
    import re

    from srdda.apps.cli import main

    for path in sorted((ROOT / "examples").rglob("*.toml")):
        for command in re.findall(r"`?srdda ([a-z]+)\b", path.read_text(encoding="utf-8")):
            assert command in main.commands, (path.name, command)
