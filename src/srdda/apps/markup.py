"""Tables and the page style of srdda's reports, in Markdown and HTML (the paper report, an ensemble's report)."""
from __future__ import annotations

import html

__all__ = ["md_table", "html_table", "CSS"]


def md_table(header: list[str], body: list[list[str]]) -> str:
    """A Markdown table (``|`` in a cell escaped)."""
    def cell(s: str) -> str:
        return s.replace("|", "\\|")
    lines = ["| " + " | ".join(cell(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


def html_table(header: list[str], body: list[list[str]]) -> str:
    """An HTML table, every cell escaped."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    rows = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in body)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>"


# the style sheet of every report page (tables right-aligned but for their first column, figures fitted)
CSS = ("body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em}"
       "table{border-collapse:collapse;margin:1em 0;font-size:90%}"
       "td,th{border:1px solid #bbb;padding:3px 6px;text-align:right}th{background:#eee}"
       "td:first-child{text-align:left}img{max-width:100%}.err{color:#a00}figcaption{font-size:90%}")
