"""The docs tell the truth: docs/model-file.md against the schema, docs/results.md against a results file.

Both sides are read at test time (the schema's fields, the file's datasets), so
a field or dataset added, renamed or removed without its documentation fails here.
"""
from __future__ import annotations

import dataclasses
import json
import re
import tomllib
import types
import typing
from pathlib import Path

import h5py
import pytest
from pydantic import AliasChoices, BaseModel
from pydantic.fields import FieldInfo

import srdda
from srdda.io import schema
from srdda.io.modelfile import load_model, model_from_dict
from srdda.io.results_store import ResultsStore
from srdda.apps.paper import examples_dir

DOCS = Path(__file__).resolve().parents[1] / "docs"


# -- docs/model-file.md ------------------------------------------------------------------
def _is_table(annotation: object) -> bool:
    """A pydantic model or pydantic dataclass (RunSettings): a table of the file."""
    return isinstance(annotation, type) and (issubclass(annotation, BaseModel)
                                             or hasattr(annotation, "__pydantic_fields__"))


def _fields(cls: type) -> dict[str, FieldInfo]:
    """A table's fields by the name a file writes (a field's validation alias where it has one)."""
    fields = cls.model_fields if issubclass(cls, BaseModel) else cls.__pydantic_fields__
    out = {}
    for name, info in fields.items():
        alias = info.validation_alias
        out[alias.choices[-1] if isinstance(alias, AliasChoices) else name] = info
    return out


def _section_class(annotation: object) -> tuple[type, str] | None:
    """The schema class a field holds and how TOML writes it: "[[x]]" (list), "[x.<name>]" (dict), "[x]"."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if _is_table(annotation):
        return annotation, "table"
    if origin is list and args and _is_table(args[0]):
        return args[0], "array"
    if origin is dict and _is_table(args[1]):
        return args[1], "named"
    if origin in (typing.Union, types.UnionType):
        found = [c for c in (_section_class(a) for a in args) if c is not None]
        return found[0] if found else None
    return None


def schema_tables() -> dict[str, type[BaseModel]]:
    """Every table of the model file by its dotted path ("" = top level), walked from ``ModelFile``."""
    tables: dict[str, type[BaseModel]] = {"": schema.ModelFile}
    todo = [("", schema.ModelFile)]
    while todo:
        prefix, cls = todo.pop()
        for name, info in _fields(cls).items():
            found = _section_class(info.annotation)
            if found is not None:
                path = f"{prefix}.{name}" if prefix else name
                tables[path] = found[0]
                todo.append((path, found[0]))
    return tables


def documented_tables() -> dict[str, dict[str, str]]:
    """The reference of the model file, docs/model-file/*.md (a `## ` heading per table, each page linked from
    docs/model-file.md's *Reference*): table path -> {field: default cell}."""
    index = (DOCS / "model-file.md").read_text(encoding="utf-8")
    pages = sorted((DOCS / "model-file").glob("*.md"))
    assert pages and all(f"(model-file/{page.name})" in index[index.index("\n## Reference"):] for page in pages)
    reference = "\n".join(page.read_text(encoding="utf-8") for page in pages)
    out: dict[str, dict[str, str]] = {}
    current: list[str] = []
    for line in reference.splitlines():
        if line.startswith("# "):
            current = []  # a page's title names no table
        if line.startswith("## "):
            current = ([""] if "Top level" in line else
                       [t.replace(".<name>", "") for t in re.findall(r"`\[{1,2}([\w.<>]+)\]{1,2}`", line)])
            assert current, f"heading names no table: {line}"
            for path in current:
                assert path not in out, f"{path} documented twice"
                out[path] = {}
        row = re.match(r"^\| `(\w+)` \| ([^|]*) \|", line)
        if row and current:
            for path in current:
                out[path][row.group(1)] = row.group(2)
    return out


def test_every_schema_field_is_documented_and_nothing_else():
    tables, documented = schema_tables(), documented_tables()
    assert set(documented) == set(tables), "documented tables differ from the schema's"
    for path, cls in tables.items():
        assert set(documented[path]) == set(_fields(cls)), f"[{path or 'top level'}]"
        for name, info in _fields(cls).items():
            # a required field says so, an optional one gives its default
            assert ("required" in documented[path][name]) == info.is_required(), f"{path}.{name}"


def test_the_model_file_example_loads():
    text = (DOCS / "model-file.md").read_text(encoding="utf-8")
    example = re.search(r"```toml\n(.*?)```", text, flags=re.S).group(1)
    model, settings = model_from_dict(tomllib.loads(example), "docs/model-file.md")
    assert len(model.blocks) == 2 and len(model.hinges) == 1 and len(model.springs) == 1
    assert len(model.prescribed) == 1 and model.base_acceleration is not None
    assert settings.dt == pytest.approx(1e-3)


# -- docs/results.md ---------------------------------------------------------------------
def _layout_rows() -> list[tuple[str, str, str]]:
    """(path, shape, content) rows of the layout table of docs/results.md."""
    text = (DOCS / "results.md").read_text(encoding="utf-8")
    table = text[text.index("**Layout**"):text.index("**Contact output hook.**")]
    return re.findall(r"^\| `([^`]+)`[^|]* \| ([^|]*) \| (.*) \|$", table, flags=re.M)


def _shape(cell: str, sizes: dict[str, int]) -> tuple[int | str, ...] | None:
    """A documented shape "(n, nb, 2)" with its symbols resolved; "..." stays a wildcard; None: no shape."""
    cell = cell.strip()
    if not cell.startswith("("):
        return None
    dims = [d.replace(" ", "") for d in cell.strip("()").split(",") if d.strip()]

    def size(dim: str) -> int | str:
        if dim == "..." or dim.isdigit():
            return dim if dim == "..." else int(dim)
        symbol, _, plus = dim.partition("+")  # "k+1"
        return sizes[symbol] + (int(plus) if plus else 0)

    return tuple(size(d) for d in dims)


def _matches(actual: tuple[int, ...], documented: tuple[int | str, ...]) -> bool:
    if documented and documented[-1] == "...":
        return actual[:len(documented) - 1] == documented[:-1]
    return actual == documented


@pytest.fixture(scope="module")
def results_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The nunchaku (a hinge, three measured points) with a block on a stick (contacts) hanging from a bolt,
    12 steps, flushed twice."""
    path = tmp_path_factory.mktemp("results") / "nunchaku.h5"
    model, settings = load_model(examples_dir() / "paper" / "nunchaku.toml")
    model.add_block([[0.2, 0.05], [0.4, 0.05], [0.4, 0.15], [0.2, 0.15]], "stick", name="bob")
    model.add_bolt([0.3, 0.1], [0.3, 1.0], 1e5, block_b=-1, name="bolt")  # the bob hangs from the ground
    settings = dataclasses.replace(settings, n_steps=12)
    result = srdda.run(model, settings, recorders=[ResultsStore(path, settings, flush_every=6)])
    assert result.completed
    return path


def test_every_history_and_contact_dataset_has_its_documented_shape(results_file: Path):
    rows = _layout_rows()
    with h5py.File(results_file, "r") as f:
        arrays_model = f["model"]
        n = len(f["history/step"])
        sizes = {"n": n, "nb": len(arrays_model["block_ptr"]) - 1, "nv": len(arrays_model["vertices"]),
                 "nm": len(arrays_model["measured_rows"]), "nμ": f["history/multipliers"].shape[1],
                 "nbo": len(arrays_model["links.bolt_rows_a"]),
                 "ne": len(json.loads(f["history/energy"].attrs["names"])), "k": len(f["contacts/step"]),
                 "nc": int(f["contacts/offsets"][-1])}
        assert sizes["nμ"] == 2 and sizes["k"] > 0 and sizes["nc"] > 0 and sizes["nbo"] == 1  # what is checked
        documented: dict[str, tuple[int | str, ...]] = {}
        for cell_path, shape_cell, _ in rows:
            shape = _shape(shape_cell, sizes)
            if shape is not None and cell_path.startswith(("/history/", "/contacts/")):
                documented[cell_path] = shape
        written = {f"/{group}/{name}": f[group][name].shape for group in ("history", "contacts") for name in f[group]}
        for path, shape in written.items():
            expected = documented.get(path, documented.get(path.rsplit("/", 1)[0] + "/<field>"))
            assert expected is not None, f"{path} is not documented"
            assert _matches(shape, expected), f"{path}: file {shape}, docs {expected}"
        for path in documented:
            assert "<" in path or path in written, f"{path} is documented but not written"

        root = next(content for p, _, content in rows if p == "/")
        text = {a[: -len("_crc32")] for a in f.attrs if a.endswith("_crc32")}  # a text and its checksum
        assert set(re.findall(r"`(\w+)`", root)) == set(f.attrs) - {f"{a}_crc32" for a in text}, "root attributes"
        assert text == {"format", "srdda_version", "method", "status", "created"}, "checksummed text attributes"
        energy = next(content for p, _, content in rows if p == "/history/energy")
        names = re.findall(r"`(\w+)`", energy.split("names", 1)[1])
        assert names == json.loads(f["history/energy"].attrs["names"]), "energy columns"
