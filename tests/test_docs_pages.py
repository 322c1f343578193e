"""The manual's user pages stay short enough to read (issue 33): at most 400 lines each.

The development log (docs/dev/) keeps the history of the work at whatever length it has; a user page
that grows past the bound is split by topic into sub-pages (as docs/contacts/, docs/verification/).
"""
from __future__ import annotations

from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"
LONGEST = 400  # lines: the "about 400"


def test_no_user_page_is_longer_than_the_bound() -> None:
    pages = [page for page in DOCS.rglob("*.md") if "dev" not in page.relative_to(DOCS).parts]
    assert len(pages) > 40  # every user page was found
    long = {str(page.relative_to(DOCS)): n for page in pages
            if (n := len(page.read_text(encoding="utf-8").splitlines())) > LONGEST}
    assert long == {}
