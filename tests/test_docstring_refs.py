"""Names that docstrings refer to (:attr:`...`, :meth:`...`, `Result.x`, ...) exist in the package."""
from __future__ import annotations

import dataclasses
import importlib
import inspect
import pathlib
import pkgutil
import re
import types

import srdda

ROLE = re.compile(r":(?:attr|meth|class|func|data|mod|exc):`~?(\.?[\w.]+)`")
DOTTED = re.compile(r"(?<![`\w])``?([A-Z]\w*(?:\.\w+)+)``?(?![\w(`])")  # `Result.energy`, ``Model.add_hinge``


def _modules() -> list[types.ModuleType]:
    names = [m.name for m in pkgutil.walk_packages(srdda.__path__, "srdda.")]
    return [srdda] + [importlib.import_module(n) for n in names]


def _has(obj: object, name: str) -> bool:
    if hasattr(obj, name):
        return True
    fields = getattr(obj, "__dataclass_fields__", {})
    return name in fields or name in getattr(obj, "__annotations__", {}) or any(
        name in getattr(base, "__annotations__", {}) for base in getattr(obj, "__mro__", ()))


def _resolve(path: str, module: types.ModuleType, owner: object, everywhere: dict[str, list[object]]) -> bool:
    if path.startswith("."):  # relative to the module's package (a package's own module)
        package = module.__name__ if hasattr(module, "__path__") else module.__package__
        try:
            importlib.import_module(path, package)
            return True
        except ImportError:
            return False
    head, *rest = path.split(".")
    starts: list[object] = [owner] if owner is not None and not rest and _has(owner, head) else []
    if head == "srdda":
        starts = [srdda]
    elif hasattr(module, head):
        starts = [getattr(module, head)]
    starts += everywhere.get(head, [])
    for obj in starts:
        ok = True
        for part in rest:
            if inspect.ismodule(obj) and not hasattr(obj, part):
                try:
                    obj = importlib.import_module(f"{obj.__name__}.{part}")
                    continue
                except ImportError:
                    ok = False
                    break
            if not _has(obj, part):
                ok = False
                break
            obj = getattr(obj, part, None)
        if ok:
            return True
    return False


def _docstrings(module: types.ModuleType):
    """(where, docstring, the class a bare name may belong to) of the module and its classes and functions."""
    yield module.__name__, module.__doc__ or "", None
    for name, obj in vars(module).items():
        if getattr(obj, "__module__", None) != module.__name__:
            continue
        if inspect.isclass(obj) or inspect.isfunction(obj):
            yield f"{module.__name__}.{name}", obj.__doc__ or "", obj if inspect.isclass(obj) else None
        if inspect.isclass(obj):
            for attr, member in list(vars(obj).items()):  # _has may add a class its __annotations__
                doc = getattr(member, "__doc__", None) if isinstance(member, (types.FunctionType, property,
                                                                             staticmethod, classmethod)) else None
                if doc:
                    yield f"{module.__name__}.{name}.{attr}", doc, obj


def test_every_name_a_docstring_refers_to_exists() -> None:
    modules = _modules()
    everywhere: dict[str, list[object]] = {}
    for m in modules:
        everywhere.setdefault(m.__name__.rsplit(".", 1)[-1], []).append(m)
        for name, obj in vars(m).items():
            if inspect.isclass(obj) or inspect.isfunction(obj) or inspect.ismodule(obj):
                everywhere.setdefault(name, []).append(obj)
    unresolved = []
    for m in modules:
        for where, doc, owner in _docstrings(m):
            for path in ROLE.findall(doc) + DOTTED.findall(doc):
                if not _resolve(path, m, owner, everywhere):
                    unresolved.append(f"{where}: {path}")
    assert not unresolved, "\n".join(sorted(unresolved))


SECTION = re.compile(r"(docs/[\w/.-]+\.md)[,:]?\s*\(?\s*\*([^*]+)\*")  # docs/x.md, *A section*
SOURCE = pathlib.Path(srdda.__file__).parent
REPO = SOURCE.parents[1]


def test_every_manual_section_the_code_names_is_on_that_page() -> None:
    """``docs/x.md, *Section*`` in the code (docstrings and comments) names a page that has that text: a section
    that moved to a sub-page or to the development log takes its reference along."""
    found, missing = 0, []
    for path in SOURCE.rglob("*.py"):
        for page, section in SECTION.findall(path.read_text(encoding="utf-8")):
            found += 1
            target = REPO / page
            words = " ".join(section.split())
            if not target.exists() or words not in " ".join(target.read_text(encoding="utf-8").split()):
                missing.append(f"{path.relative_to(REPO)}: {page}, *{words}*")
    assert found > 5  # the pattern matched the references
    assert not missing, "\n".join(missing)
