"""MkDocs hook: the docstrings' Sphinx roles shown as code in the API reference.

The docstrings name other objects the Sphinx way (:class:`~srdda.model.Model`,
:meth:`add_block`), which mkdocstrings renders literally as
``:class:<code>~srdda.model.Model</code>``. This hook shows the name alone, as
code: the last component where the role's target starts with ``~`` (Sphinx's
short form), else the target as written.
"""
from __future__ import annotations

import re
from typing import Any

ROLE = re.compile(r":(?:class|meth|func|mod|attr|data|exc|obj):<code>(~?)([^<]+)</code>")


def plain_roles(html: str) -> str:
    """``html`` with every rendered Sphinx role replaced by its target as code."""
    return ROLE.sub(lambda m: f"<code>{m.group(2).rsplit('.', 1)[-1] if m.group(1) else m.group(2)}</code>", html)


def on_page_content(html: str, **kwargs: Any) -> str:
    return plain_roles(html)
