"""The ensemble's section of a report: counts, runout, the collectors' statistics and the figures.

:func:`write_ensemble_report` writes it alone as ``report.md``/``report.html``
in the ensemble's folder; :func:`paper_report_section` appends it to the paper
report (:func:`srdda.apps.report.write_report`) when an ensemble was run into the
report's ``ensemble/`` folder (``srdda ensemble SPEC --out REPORT/ensemble``).
"""
from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import Any

from ..markup import CSS, html_table, md_table

__all__ = ["ensemble_section", "write_ensemble_report", "paper_report_section"]

ENSEMBLE_FOLDER = "ensemble"


def _g(x: float) -> str:
    return "-" if x != x else f"{x:.3g}"  # NaN (no crossing) as a dash


def ensemble_section(doc: dict[str, Any], figures: list[tuple[str, Path]], dim: int,
                     prefix: str = "") -> tuple[list[str], list[str]]:
    """Markdown lines and HTML parts of the section; figure links in Markdown are ``prefix + figures/NAME``."""
    energy = "J/m" if dim == 2 else "J"
    title = f"Probabilistic rockfall: {doc['title']}" if doc["title"] else "Probabilistic rockfall"
    r = doc["runout"]
    intro = (f"{doc['runs']} runs: {doc['ok']} completed ({doc['left_domain']} of them left the domain), "
             f"{doc['diverged']} diverged, {doc['failed']} failed"
             f"{'' if doc.get('complete', True) else ' (the ensemble is not complete yet)'}. Runout (horizontal "
             f"distance travelled by the tracked block): mean {_g(r['mean'])} m, P50 {_g(r['p50'])} m, P95 "
             f"{_g(r['p95'])} m, P99 {_g(r['p99'])} m, max {_g(r['max'])} m. Bounce height: the centroid's height "
             "above the ground straight below it (docs/ensembles.md).")
    header = ["collector", "crossed / runs", f"E mean ({energy})", "E P50", "E P95", "E P99",
              "bounce P50 (m)", "bounce P95", "bounce P99", "speed P95 (m/s)"]
    body = []
    for c in doc["collectors"]:
        e, h = c["kinetic"], c["bounce_height"]
        body.append([c["collector"], f"{c['crossed']} / {c['runs']}", _g(e["mean"]), _g(e["p50"]), _g(e["p95"]),
                     _g(e["p99"]), _g(h["p50"]), _g(h["p95"]), _g(h["p99"]), _g(c["speed"]["p95"])])
    md = [f"## {title}", "", intro, ""]
    hb = [f"<h2>{html.escape(title)}</h2><p>{html.escape(intro)}</p>"]
    if body:
        md += [md_table(header, body), ""]
        hb.append(html_table(header, body))
    for caption, path in figures:
        md += [f"![{caption}]({prefix}figures/{path.name})", "", f"*{caption}*", ""]
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        hb.append(f"<figure><img src='data:image/png;base64,{data}' alt='{html.escape(caption)}'>"
                  f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    return md, hb


def write_ensemble_report(out: Path, doc: dict[str, Any], figures: list[tuple[str, Path]], dim: int) -> None:
    """``report.md`` and a self-contained ``report.html`` holding the ensemble's section alone."""
    md, hb = ensemble_section(doc, figures, dim)
    (out / "report.md").write_text("\n".join(md), encoding="utf-8")
    (out / "report.html").write_text("<!doctype html><html><head><meta charset='utf-8'><title>srdda ensemble"
                                     f"</title><style>{CSS}</style></head><body>{''.join(hb)}</body></html>",
                                     encoding="utf-8")


def paper_report_section(report_dir: Path, md: list[str], hb: list[str]) -> None:
    """Append the section of the ensemble in ``report_dir/ensemble`` (if there is one) to a report's parts."""
    folder = report_dir / ENSEMBLE_FOLDER
    if not (folder / "summary.json").exists():
        return
    doc = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    figures = [(caption, folder / "figures" / name) for caption, name in doc.get("figures", [])]
    dim = 3 if "end_z" in doc else 2
    section_md, section_hb = ensemble_section(doc, figures, dim, prefix=f"{ENSEMBLE_FOLDER}/")
    md += section_md
    hb += section_hb
