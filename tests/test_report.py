"""The paper report: tables laid out ours beside the paper's, figures embedded, numbers from its own runs."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import srdda
from srdda.io.results_store import read_results
from srdda.apps.paper import EXAMPLES, Example
from srdda.apps.report import make_report, pivot_table
from results_models import rod_model, rod_settings

METHODS = ("dda0", "dda1", "srdda")


def _stub_tables(results):
    """Area of the rod at step 100 against a made-up 'paper' value, and ω at the last step (no paper value)."""
    rows = []
    for m, res in results.items():
        rows.append({"table": "Table S1", "quantity": "area", "step": 100, "method": m,
                     "ours": float(res.area[100][0]), "paper": 1.000093, "exact": 1.0, "unit": "m²"})
        rows.append({"table": "Table S2", "quantity": "omega", "step": None, "method": m,
                     "ours": float(res.velocity[-1][0, 2]), "paper": None, "exact": None, "unit": "rad/s"})
    return rows


@pytest.fixture
def stub_examples(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    build = lambda method: (rod_model(), rod_settings(method, n_steps=150))  # noqa: E731
    monkeypatch.setitem(EXAMPLES, "stubrod", Example("stubrod", "Stub rod", _stub_tables, builder=build,
                                                          notes="Stub choices: a 0.1 m thick rod."))

    def broken(results):
        raise KeyError("step 9999 was not recorded")

    monkeypatch.setitem(EXAMPLES, "broken", Example("broken", "Broken tables", broken, builder=build))
    return ["stubrod", "broken"]


def test_report_is_written_from_its_own_runs(tmp_path: Path, stub_examples: list[str]) -> None:
    runs, (md, html) = make_report(tmp_path, stub_examples, METHODS, command="srdda paper test --report x")
    text = md.read_text()
    assert "## Stub rod" in text and "### Table S1" in text and "### Table S2" in text
    assert "## Stub rod\n\nStub choices: a 0.1 m thick rod." in text  # the example's choices, under its title
    # issue 31 item 5: the inputs open each example, before its results
    section = text.split("## Stub rod", 1)[1]
    assert section.index("### Inputs") < section.index("| method | status")
    for entry in ("| time step Δt |", "| material ", "| default joint |", "| contact penalty k_n |",
                  "| linear solver |"):
        assert entry in section.split("| method | status")[0], entry
    # each caption once (the image's alt text names the figure, it does not repeat the caption)
    first = section.split("\n## ", 1)[0]
    captions = re.findall(r"^\*(.+)\*$", first, flags=re.M)
    assert captions and all(first.count(c) == 1 for c in captions)
    ledger = next(c for c in captions if c.startswith("Energy ledger"))
    assert "Kinetic energy:" in ledger and "Balance error" in ledger  # each drawn curve explained
    # every 'ours' number of the report is the value in the run's own results file
    for m in METHODS:
        stored = read_results(tmp_path / "runs" / f"stubrod_{m}.h5")
        area = stored.area[100][0]
        assert f"{area:.8f}" in text  # the paper prints 6 decimals; the report shows 2 more
    header = [line for line in text.splitlines() if line.startswith("| quantity")][0]
    assert header.count("ours") == 3 and header.count("paper") == 3
    # figures: PNG files for Markdown, base64 images in the self-contained HTML, one per figure
    n_fig = len(runs[0].figures)
    assert n_fig >= 2
    assert len(list((tmp_path / "figures").glob("stubrod_*.png"))) == n_fig
    html_text = html.read_text()
    assert len(re.findall(r"src='data:image/png;base64,", html_text)) == len(list((tmp_path / "figures").glob("*.png")))
    # a failing table is reported, not fatal
    assert runs[1].errors and "step 9999" in runs[1].errors[0]
    assert "Error:" in text and "step 9999" in html_text


def test_pivot_table_puts_ours_beside_the_paper() -> None:
    rows = [{"table": "T", "quantity": "w", "step": None, "method": m, "ours": o, "paper": p, "exact": 2.0,
             "unit": "rad/s"} for m, o, p in (("dda0", 1.9, 1.95), ("srdda", 2.002, 2.1))]
    header, body = pivot_table(rows, ["dda0", "srdda"])
    assert header == ["quantity", "unit", "CS (step)", "exact", "DDA0 ours", "DDA0 paper", "SRDDA ours",
                      "SRDDA paper"]
    assert body == [["w", "rad/s", "", "2.000000", "1.90000000 (-5.0000%)", "1.95 (-2.5000%)",
                     "2.00200000 (+0.1000%)", "2.1 (+5.0000%)"]]


def test_examples_are_listed_in_the_papers_order() -> None:
    # `srdda paper all` and the report follow section 4's order, whatever the import order
    assert [e.title.split()[0] for e in EXAMPLES.values()] == ["4.1", "4.2", "4.3", "4.4", "4.5"]
    # each says, in the report, what it chose where the paper is silent
    assert all(len(e.notes) > 40 for e in EXAMPLES.values())


UNIT = re.compile(r"\([^()]+\)\s*$")  # a label ends with its unit in parentheses: "y (m)", "kinetic (kJ/m)"


def _axes_without_units(figures) -> list[str]:
    missing = []
    for caption, fig in figures:
        for ax in fig.axes:
            if not ax.get_visible() or not (ax.lines or ax.collections):
                continue  # removed or empty panels draw nothing to read
            for which, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
                if not UNIT.search(label):
                    missing.append(f"{caption[:40]!r}: {which} label {label!r} of {ax.get_title()!r}")
    return missing


def test_every_report_axis_and_table_column_has_a_unit(tmp_path: Path, stub_examples: list[str]) -> None:
    from srdda.apps.report import FIGURES, _runs_table, run_examples

    run_ = run_examples(stub_examples[:1], METHODS)[0]
    rod_figures = FIGURES["rod"](run_.results, rod_model())  # the paper's swing figure on the same runs
    assert _axes_without_units(run_.figures + rod_figures) == []
    assert len(run_.figures) >= 3  # model, trajectories per method, energy ledger, ω
    header, _ = _runs_table(run_)
    assert all(UNIT.search(h) for h in header if h not in ("method", "status", "results file"))
    header, body = pivot_table(run_.rows, METHODS)
    assert header[1] == "unit" and all(row[1] for row in body)
