"""The manual's hook shows the docstrings' Sphinx roles as code (docs/hooks.py), not as literal ``:class:``."""
from __future__ import annotations

import importlib.util
import re
from collections.abc import Callable
from pathlib import Path

import srdda

HOOKS = Path(__file__).resolve().parents[1] / "docs" / "hooks.py"


def _plain_roles() -> Callable[[str], str]:
    spec = importlib.util.spec_from_file_location("docs_hooks", HOOKS)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    plain_roles: Callable[[str], str] = module.plain_roles
    return plain_roles


def test_roles_become_their_targets_as_code() -> None:
    plain_roles = _plain_roles()
    html = ("<p>see :class:<code>~srdda.model.Model</code>, :meth:<code>add_block</code> and "
            ":func:<code>srdda.geometry.polyhedron.normalize_polyhedron</code>; <code>x</code> stays</p>")
    assert plain_roles(html) == ("<p>see <code>Model</code>, <code>add_block</code> and "
                                 "<code>srdda.geometry.polyhedron.normalize_polyhedron</code>; <code>x</code> stays</p>")


def test_every_role_the_docstrings_use_is_one_the_hook_knows() -> None:
    """A role the hook does not list would show literally again: every role in the source is one of them."""
    known = set(re.findall(r"\(\?:([a-z|]+)\)", HOOKS.read_text(encoding="utf-8"))[0].split("|"))
    used = set()
    for path in Path(srdda.__file__).parent.rglob("*.py"):
        used |= set(re.findall(r":([a-z]+):`", path.read_text(encoding="utf-8")))
    assert used and used <= known, used - known
