"""The tutorials (docs/tutorials/) and Getting started run as written and show what a user sees.

Each page is run top to bottom in an empty folder that sees the repository's examples/: every
`$ srdda ...` line of a ```console block is run through `python -m srdda`, and the lines the page
shows under it must appear in its output, in order; every ```python block is run, and the ```text
block right after it must appear in what it printed. A shown line of "..." stands for lines left out,
and "..." inside a line for text left out (timings, paths). So a changed command, option, output line or
figure fails here, and the page cannot drift from the program.
"""
from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = sorted(p for p in (ROOT / "docs" / "tutorials").glob("*.md") if p.name != "index.md")
RUNNABLE = [ROOT / "docs" / "getting-started.md", *TUTORIALS]
BLOCK = re.compile(r"^```(\w+)\n(.*?)^```", flags=re.M | re.S)


def expect_lines(shown: str, output: str, where: str) -> None:
    """Every line ``shown`` (but "..." and blank ones) is a line of ``output``, in the same order."""
    lines = [line.rstrip() for line in output.splitlines()]
    at = 0
    for want in shown.splitlines():
        if want.strip() in ("", "..."):
            continue
        pattern = re.compile(".*".join(re.escape(part) for part in want.rstrip().split("...")))
        while at < len(lines) and not pattern.fullmatch(lines[at]):
            at += 1
        assert at < len(lines), f"{where}: {want!r} is not in the output (in this order):\n{output}"
        at += 1


def run_console(block: str, where: str) -> None:
    """The ``$ srdda ...`` commands of a console block, each output against the lines shown under it."""
    for chunk in re.split(r"^\$ ", block, flags=re.M)[1:]:
        command, _, shown = chunk.partition("\n")
        argv = shlex.split(command)
        assert argv[0] == "srdda", f"{where}: only srdda commands run here: {command}"
        done = subprocess.run([sys.executable, "-m", "srdda", *argv[1:]], capture_output=True, text=True,
                              env={**os.environ, "COLUMNS": "100"}, timeout=600)
        output = done.stdout + done.stderr
        assert done.returncode == 0, f"{where}: `{command}` exited {done.returncode}:\n{output}"
        expect_lines(shown, output, f"{where}: `{command}`")


@pytest.mark.slow
@pytest.mark.parametrize("page", RUNNABLE, ids=lambda page: page.stem)
def test_the_tutorial_runs_as_written(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    (tmp_path / "src").symlink_to(ROOT / "src")  # quake-bolted-block.toml names its record by a path into src/
    monkeypatch.chdir(tmp_path)
    blocks = BLOCK.findall(page.read_text(encoding="utf-8"))
    namespace: dict[str, object] = {}
    for n, (kind, body) in enumerate(blocks):
        where = f"{page.name}, block {n + 1}"
        if kind == "console":
            run_console(body, where)
        elif kind == "python":
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                exec(compile(body, where, "exec"), namespace)  # noqa: S102 - the page's own example
            if n + 1 < len(blocks) and blocks[n + 1][0] == "text":
                expect_lines(blocks[n + 1][1], printed.getvalue(), where)
    assert any(kind == "console" for kind, _ in blocks), f"{page.name} runs no command"


def test_every_tutorial_is_listed_and_short() -> None:
    index = (ROOT / "docs" / "tutorials" / "index.md").read_text(encoding="utf-8")
    assert len(TUTORIALS) >= 4
    for page in TUTORIALS:
        assert f"({page.name})" in index, page.name
        assert len(page.read_text(encoding="utf-8").splitlines()) < 400, page.name
