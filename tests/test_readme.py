"""The README as a new user reads it: its command lines name files that ship, its convert example converts a
Shi-format input shipped in the package, its Python example runs."""
from __future__ import annotations

import re
import shlex
from pathlib import Path

from click.testing import CliRunner

from srdda.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.S)


def test_every_readme_command_names_files_that_ship() -> None:
    # issue 31 item 8: `srdda convert circleslope.geo circleslope.ana` named files that did not ship
    lines = [line for block in _blocks("") for line in block.splitlines() if "srdda " in line]
    named = [word for line in lines for word in shlex.split(line.split("#")[0])
             if word.startswith(("src/", "examples/")) and "." in Path(word).name]
    assert any("circleslope.geo" in w for w in named)
    missing = [w for w in named if not (ROOT / w).exists()]
    assert not missing, missing


def test_convert_example_converts_the_shipped_shi_input(tmp_path: Path) -> None:
    out = tmp_path / "slope.toml"
    res = CliRunner().invoke(main, ["convert", "--example", "circleslope", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "7 blocks" in res.output
    check = CliRunner().invoke(main, ["check", str(out)])
    assert check.exit_code == 0 and "7 blocks (2D)" in check.output


def test_the_readme_python_example_runs() -> None:
    (code,) = _blocks("python")
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the README's own example
    assert namespace["result"].completed
    assert namespace["box3d"].arrays().n_blocks == 2
