"""The module paths of srdda 0.1 that moved, kept importable for one release with a DeprecationWarning.

``import srdda.verify`` (or ``from srdda import verify``, ``from srdda.cases.slope3d import wedge_model``)
gives the module at its new path (the same module object, so that what a user sets on it holds for both
names) and warns once per old name, naming the new path. :func:`install` puts the finder on
``sys.meta_path``; ``srdda/__init__.py`` calls it. Drop this module, and the call, in the release after
next (docs/architecture.md, *Old module paths*).
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from types import CodeType, ModuleType

__all__ = ["MOVED", "new_name", "install"]

# old module path -> new module path (a package's submodules follow it)
MOVED = {
    **{f"srdda.{name}": f"srdda.apps.{name}" for name in (
        "cli", "cli_results", "report", "plotting", "animation", "render3d", "modelview", "summary",
        "timehistories", "fos", "paper", "verify", "bench", "ensemble")},
    "srdda.cases": "srdda.apps.verify.cases",
    "srdda.solvers_iterative": "srdda.solvers._iterative",
    "srdda.backends.conjugate_gradient": "srdda.solvers._gpu",
}
# what the warning tells a user to import where the new module is private
PUBLIC = {"srdda.solvers._iterative": "srdda.solvers", "srdda.solvers._gpu": "srdda.solvers"}


def new_name(old: str) -> str | None:
    """The new path of module ``old`` (a moved module or one inside a moved package), or None."""
    for prefix, target in MOVED.items():
        if old == prefix or old.startswith(prefix + "."):
            return target + old[len(prefix):]
    return None


class _Alias(importlib.abc.Loader):
    """Loads an old name as the module of its new name (the import system keeps what sys.modules holds)."""

    def __init__(self, target: str) -> None:
        self.target = target

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        return None  # a placeholder, replaced in exec_module

    def _warn(self, old: str) -> None:
        warnings.warn(f"{old} has moved to {PUBLIC.get(self.target, self.target)}; import it from there (the old "
                      "path goes in the next release)", DeprecationWarning, stacklevel=3)

    def exec_module(self, module: ModuleType) -> None:
        self._warn(module.__name__)
        sys.modules[module.__name__] = importlib.import_module(self.target)

    def get_code(self, fullname: str) -> CodeType:
        """What ``python -m OLD`` runs: the new module as ``__main__`` (``python -m srdda.cli``)."""
        self._warn(fullname)
        return compile(f"import runpy\nrunpy.run_module({self.target!r}, run_name='__main__', alter_sys=True)\n",
                       fullname, "exec")


class _Finder(importlib.abc.MetaPathFinder):
    """Finds the old names (:data:`MOVED`) before any other finder looks for them on disk."""

    def find_spec(self, fullname: str, path: object = None,
                  target: object = None) -> importlib.machinery.ModuleSpec | None:
        new = new_name(fullname)
        return None if new is None else importlib.machinery.ModuleSpec(fullname, _Alias(new))


def install() -> None:
    """Put the finder of the old names first on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
