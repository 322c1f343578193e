"""``srdda convert``: existing DDA inputs (legacy text or DDAML) to an srdda model file in SI units."""
from __future__ import annotations

import warnings
from pathlib import Path

import click
import tomli_w

from .ddainput import DDAInput, DDAInputError
from .ddaml import read_ddaml
from .legacy import read_legacy
from .modelfile import model_to_dict
from ..units import UNIT_SYSTEMS

__all__ = ["convert", "read_dda", "shipped_inputs"]

SHIPPED = Path(__file__).resolve().parent.parent / "data" / "legacy"  # package data: found from any folder


def shipped_inputs() -> dict[str, Path]:
    """The legacy DDA inputs shipped with srdda (``srdda convert --example NAME``): name -> geometry file."""
    return {p.stem: p for p in sorted(SHIPPED.glob("*.geo"))}


def _is_xml(path: Path) -> bool:
    try:
        head = path.read_text(encoding="utf-8", errors="replace").lstrip()[:1]
    except OSError as exc:
        raise DDAInputError(f"{path}: cannot read ({exc.strerror})") from None
    return head == "<"


def read_dda(geometry: str | Path, analysis: str | Path | None = None, units: str = "auto") -> DDAInput:
    """Read a DDA geometry + analysis pair (format detected from the content), converted to SI.

    Without ``analysis``, the file next to ``geometry`` with the suffix ``.ana``
    is used; when there is none, the geometry alone is read and the analysis
    takes :data:`~srdda.io.ddainput.DEFAULT_ANALYSIS` (warned). ``units`` names
    the files' unit system (``UNIT_SYSTEMS``) or "auto" (from the gravity;
    :meth:`DDAInput.in_si`). The returned ``notes`` say what was done.
    """
    gpath = Path(geometry)
    apath = Path(analysis) if analysis is not None else gpath.with_suffix(".ana")
    reader = read_ddaml if _is_xml(gpath) else read_legacy
    if analysis is None and not apath.exists():
        warnings.warn(f"{gpath}: no analysis file {apath.name}: the default analysis is used (docs/cutting.md)",
                      stacklevel=2)
        data = reader(gpath).in_si(units)
        data.use_default_analysis()
        return data
    if not apath.exists():
        raise DDAInputError(f"{apath}: analysis file not found")
    if _is_xml(gpath) != _is_xml(apath):
        raise DDAInputError(f"{gpath} and {apath}: one is DDAML (XML) and the other legacy text")
    return reader(gpath, apath).in_si(units)


def header_comment(data: DDAInput) -> str:
    """The comment block that opens a converted model file: its source and the notes of the reading."""
    lines = [f"converted by srdda convert from {data.source}", *data.notes]
    return "".join(f"# {line}\n" for line in lines) + "\n"


@click.command("convert")
@click.argument("files", nargs=-1, type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False), help="The srdda model file to write.")
@click.option("--domain-type", "domain_types", type=int, multiple=True,
              help="Keep only blocks inside the region enclosed by joints of this type (repeatable); "
                   "default: every closed loop is a block, as in Shi's DC.")
@click.option("--units", type=click.Choice(["auto", *UNIT_SYSTEMS]), default="auto", show_default=True,
              help="Units of the input files (converted to SI); auto: from the gravity the files imply "
                   "(9.81 SI, 32.2 ft-lbf-slug, 386 in-lbf).")
@click.option("--example", type=click.Choice(list(shipped_inputs())), default=None,
              help="Convert an input shipped with srdda instead of FILES (a slope in Shi's legacy format, ft units).")
@click.option("--overwrite", is_flag=True, help="Replace OUTPUT if it exists (else that is an error).")
def convert(files: tuple[str, ...], output: str, domain_types: tuple[int, ...], units: str, example: str | None,
            overwrite: bool) -> None:
    """Convert DDA input files (GEOMETRY [ANALYSIS], legacy text or DDAML) to an srdda model file (SI).

    Without ANALYSIS, GEOMETRY's .ana is used, or documented defaults when there is none.
    """
    if example is not None:
        if files:
            raise click.UsageError("give FILES or --example, not both")
        files = (str(shipped_inputs()[example]),)
    if not files:
        raise click.UsageError("give a geometry file (and optionally its analysis file), or --example NAME")
    if len(files) > 2:
        raise click.UsageError("give a geometry file and optionally its analysis file")
    if Path(output).exists() and not overwrite:  # a model file may hold a user's edits: never replaced unasked
        raise click.UsageError(f"{output} already exists; pass --overwrite to replace it, or choose another -o")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            data = read_dda(files[0], files[1] if len(files) > 1 else None, units)
            cut = data.cut(list(domain_types) or None)
            model = data.to_model(cut)
            settings = data.run_settings()
        except DDAInputError as exc:
            raise click.UsageError(str(exc)) from None
    for w in caught:
        click.echo(f"warning: {w.message}", err=True)
    text = tomli_w.dumps(model_to_dict(model, settings, title=f"converted from {data.source}"))
    Path(output).write_text(header_comment(data) + text, encoding="utf-8")
    for note in data.notes:
        click.echo(note)
    click.echo(f"{output}: {cut.n_blocks} blocks, {len(model.fixed_points)} fixed points, "
               f"{len(model.point_loads)} load points, {len(model.measured_points)} measured points")
