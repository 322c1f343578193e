"""docs/cli.md documents every command of `srdda` with an example, and every option of each."""
from __future__ import annotations

import re
from pathlib import Path

from srdda.apps.cli import main

DOC = Path(__file__).resolve().parents[1] / "docs" / "cli.md"


def _sections() -> dict[str, str]:
    """The text under each '## `srdda NAME`' heading, by NAME."""
    parts = re.split(r"^## `srdda (\S+)`.*$", DOC.read_text(encoding="utf-8"), flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


def test_every_command_has_a_section_with_an_example() -> None:
    sections = _sections()
    assert set(sections) == set(main.commands)
    for name, text in sections.items():
        examples = re.findall(r"```\n(.*?)```", text, flags=re.S)
        assert any(line.startswith(f"srdda {name}") for block in examples for line in block.splitlines()), name


def test_every_option_is_documented_in_its_command_section() -> None:
    sections = _sections()
    missing = [f"{name} {opt}" for name, cmd in main.commands.items() for param in cmd.params
               if param.param_type_name == "option" for opt in param.opts + param.secondary_opts
               if f"`{opt}" not in sections[name]]
    assert missing == []
