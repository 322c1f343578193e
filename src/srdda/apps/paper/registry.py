"""Registry of the paper's examples: how to build each, and how to tabulate it.

An example is a model file under ``paper/`` of :func:`examples_dir` (or a Python builder)
plus a ``tables(results)`` function that turns one :class:`~srdda.Result` per
method into rows ``{"table", "quantity", "step", "method", "ours", "paper",
"exact", "unit"}`` (``step`` None where a row is not tied to a step, ``exact`` None
where there is no analytical value; ``unit`` the SI unit of the row's values,
``step`` for a number of steps).
"""
from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any

from ...integrators.methods import MethodName
from ...model import Model
from ...results import Result
from ...settings import RunSettings

__all__ = ["Example", "EXAMPLES", "register", "get_example", "examples_dir", "Row"]

Row = dict[str, Any]


def examples_dir() -> Path:
    """The shipped example model files: $SRDDA_EXAMPLES, else the package data ``srdda/data/examples``.

    They are package data (not a folder of the source tree) so that an
    installed wheel finds them from any working directory.
    """
    env = os.environ.get("SRDDA_EXAMPLES")
    if env:
        return Path(env)
    root = resources.files("srdda").joinpath("data", "examples")
    if not isinstance(root, Path):  # a zipped install: the model files are not files on disk
        raise RuntimeError(f"srdda's example model files are not on the file system ({root}); "
                           "install srdda unzipped (pip does)")
    return root


@dataclass(frozen=True)
class Example:
    """One paper example: ``name`` as on the command line, a builder and a tabulator."""

    name: str
    title: str
    tables: Callable[[dict[str, Result]], list[Row]]
    model_file: str | None = None  # under examples_dir() / "paper"
    builder: Callable[[MethodName], tuple[Model, RunSettings]] | None = None
    notes: str = ""  # the choices made where the paper is silent, for the report (Markdown)
    point_names: tuple[str, ...] = ()  # the paper's names of the measured points, in order (figures)

    def build(self, method: MethodName) -> tuple[Model, RunSettings]:
        """The model and run settings of this example for ``method``."""
        if self.builder is not None:
            return self.builder(method)
        from ...io.modelfile import load_model

        path = examples_dir() / "paper" / str(self.model_file)
        model, settings = load_model(path)
        return model, replace(settings, method=method)


EXAMPLES: dict[str, Example] = {}


def register(example: Example) -> Example:
    """Add ``example``; EXAMPLES stays in the paper's order (titles start with the section number)."""
    EXAMPLES[example.name] = example
    ordered = sorted(EXAMPLES.values(), key=lambda e: e.title)
    EXAMPLES.clear()
    EXAMPLES.update((e.name, e) for e in ordered)
    return example


def get_example(name: str) -> Example:
    if name not in EXAMPLES:
        raise KeyError(f"unknown paper example {name!r}; choose one of {', '.join(EXAMPLES)}")
    return EXAMPLES[name]
