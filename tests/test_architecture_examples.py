"""The examples of docs/architecture.md run as written: a term added without editing the step (carrying its
own state), and a contact law added without touching the step, in 2D and 3D (issue 28)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"


def _example(heading: str) -> str:
    """The first python block of the section ``heading`` of docs/architecture.md."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index(heading):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.parametrize("heading", ["## The term interface", "## The contact pipeline"])
def test_the_documented_example_runs_and_its_assertions_hold(heading):
    # each example ends with assertions against a closed form (the drag's terminal speed; a frictionless
    # block's ½ g sin ψ t² beside one that Mohr-Coulomb holds), so running it is the test
    exec(compile(_example(heading), f"{DOC.name}: {heading}", "exec"), {"__name__": "architecture_example"})
