"""``srdda convert``: existing DDA inputs (legacy text or DDAML) to an srdda model file."""
from __future__ import annotations

import warnings
from pathlib import Path

import click

from .ddainput import DDAInput, DDAInputError
from .ddaml import read_ddaml
from .legacy import read_legacy
from .modelfile import save_model

__all__ = ["convert", "read_dda"]


def _is_xml(path: Path) -> bool:
    try:
        head = path.read_text(encoding="utf-8", errors="replace").lstrip()[:1]
    except OSError as exc:
        raise DDAInputError(f"{path}: cannot read ({exc.strerror})") from None
    return head == "<"


def read_dda(geometry: str | Path, analysis: str | Path | None = None) -> DDAInput:
    """Read a DDA geometry + analysis pair (format detected from the content).

    Without ``analysis``, the file next to ``geometry`` with the suffix ``.ana`` is used.
    """
    gpath = Path(geometry)
    apath = gpath.with_suffix(".ana") if analysis is None else Path(analysis)
    if not apath.exists():
        raise DDAInputError(f"{apath}: analysis file not found (give it after the geometry file)")
    xml_g, xml_a = _is_xml(gpath), _is_xml(apath)
    if xml_g != xml_a:
        raise DDAInputError(f"{gpath} and {apath}: one is DDAML (XML) and the other legacy text")
    return (read_ddaml if xml_g else read_legacy)(gpath, apath)


@click.command("convert")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False), help="The srdda model file to write.")
@click.option("--domain-type", "domain_types", type=int, multiple=True,
              help="Keep only blocks inside the region enclosed by joints of this type (repeatable); "
                   "default: every closed loop is a block, as in Shi's DC.")
def convert(files: tuple[str, ...], output: str, domain_types: tuple[int, ...]) -> None:
    """Convert DDA input files (GEOMETRY [ANALYSIS], legacy text or DDAML) to an srdda model file."""
    if len(files) > 2:
        raise click.UsageError("give a geometry file and optionally its analysis file")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            data = read_dda(files[0], files[1] if len(files) > 1 else None)
            cut = data.cut(list(domain_types) or None)
            model = data.to_model(cut)
            settings = data.run_settings()
        except DDAInputError as exc:
            raise click.UsageError(str(exc)) from None
    for w in caught:
        click.echo(f"warning: {w.message}", err=True)
    save_model(model, settings, output, title=f"converted from {data.source}")
    click.echo(f"{output}: {cut.n_blocks} blocks, {len(model.fixed_points)} fixed points, "
               f"{len(model.point_loads)} load points, {len(model.measured_points)} measured points")
