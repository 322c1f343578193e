"""The architecture: the dimension seam, the layers below the step, the engine below the applications.

Walks the source (AST) of the engine modules and fails where an integer
literal 2, 3, 6 or 12 (the 2D/3D point sizes and unknown counts) picks
columns (``x[:, 2]``, ``x[:, 3:]``), or sizes an array (``np.zeros((n, 2))``,
``reshape(-1, 6)``, ``np.eye(2)``), and on the 2D unknown count ``NDOF``
imported outside ``kinematics/``. What depends on the dimension belongs to the
block type (``srdda.kinematics.blocktype``) or to geometry.

Walks every import of every module (at the top, inside functions, under
``TYPE_CHECKING``) and fails on an import circle and on an engine module
importing ``srdda.apps`` (docs/architecture.md, *Layout*).
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

import srdda

ROOT = Path(srdda.__file__).parent

# Packages that are the dimension seam itself.
SEAM = ("kinematics/", "geometry/")
# Modules that are 2D by what they are, each with its reason; 3D has its own counterparts.
TWO_DIMENSIONAL = {
    "contact/narrowphase2d.py": "Shi's 2D vertex-edge and vertex-vertex detection",
    "contact/detect2d.py": "2D contact geometry: an edge's normal and tangent",
    "contact/broadphase2d.py": "2D bounding boxes for shapely's STRtree",
    "model.py": "the 2D model builder (polygons, plane stress/strain materials)",
    "cutmodel.py": "2D cut blocks into a 2D model",
    "history.py": "time histories of 2D vectors",
    "io/": "2D model files and Shi's 2D formats, results of 2D runs, 2D VTU output",
    "apps/": "the applications: the paper's 2D examples, figures, animations, reports, the command line and the "
             "verification models, each of a given dimension",
}
# Modules that are 3D by what they are, each with its reason; 2D has its own counterparts.
THREE_DIMENSIONAL = {
    "contact/broadphase3d.py": "3D bounding boxes in a hash grid (x, y, z cells)",
    "contact/narrowphase3d.py": "vertex-face and edge-edge detection between polyhedra (cross products)",
    "contact/detect3d.py": "3D contact geometry: face normals, a 2-vector shear in the contact plane",
}
DIMENSION_NUMBERS = {2, 3, 6, 12}
SIZING_CALLS = {"zeros", "ones", "empty", "full", "eye", "identity", "reshape", "broadcast_to", "tile", "repeat"}


def _engine_modules() -> list[Path]:
    out = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith(SEAM) or any(rel == k or (k.endswith("/") and rel.startswith(k))
                                       for k in (*TWO_DIMENSIONAL, *THREE_DIMENSIONAL)):
            continue
        out.append(path)
    return out


def _literals(node: ast.AST) -> list[ast.Constant]:
    return [n for n in ast.walk(node)
            if isinstance(n, ast.Constant) and type(n.value) is int and n.value in DIMENSION_NUMBERS]


def _call_name(call: ast.Call) -> str:
    f = call.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


def _leaks(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        hits: list[ast.Constant] = []
        if isinstance(node, ast.Subscript) and not (isinstance(node.value, ast.Attribute)
                                                    and node.value.attr == "shape"):
            hits = _literals(node.slice)
        elif isinstance(node, ast.Call) and _call_name(node) in SIZING_CALLS:
            hits = [c for arg in node.args for c in _literals(arg)]
        found += [f"line {c.lineno}: literal {c.value}" for c in hits]
        if isinstance(node, ast.ImportFrom) and any(a.name == "NDOF" for a in node.names):
            found.append(f"line {node.lineno}: imports NDOF")
    return sorted(set(found), key=lambda s: int(s.split()[1].rstrip(":")))


def test_engine_modules_exist():
    names = {p.relative_to(ROOT).as_posix() for p in _engine_modules()}
    # the step, its terms and the run must be among the walked modules (the walk itself is tested)
    assert {"step.py", "term.py", "state.py", "simulation.py", "assembly/system.py", "assembly/blocks.py",
            "constraints/lagrange.py", "constraints/springs.py", "contact/pipeline.py", "contact/law.py",
            "contact/openclose.py", "contact/record.py", "settings.py"} <= names


def test_no_dimension_literals_outside_the_seam():
    leaks = {p.relative_to(ROOT).as_posix(): _leaks(p) for p in _engine_modules()}
    leaks = {k: v for k, v in leaks.items() if v}
    assert not leaks, f"dimension-dependent code outside kinematics/ and geometry/: {leaks}"


def test_the_walk_finds_a_leak(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("import numpy as np\nx = np.zeros((4, 6))\ny = x[:, 2] ** 2\nz = x.reshape(-1, 3)\n"
                     "w = x[:, :2] * 2\nv = x.shape[:2]\n")
    assert _leaks(probe) == ["line 2: literal 6", "line 3: literal 2", "line 4: literal 3", "line 5: literal 2"]


# Modules below the step: the state, the term interface and everything the terms are made of.
BELOW_THE_STEP = ("kinematics/", "geometry/", "assembly/", "constraints/", "contact/", "integrators/", "term.py",
                  "state.py", "settings.py", "model.py", "modeldata/", "ledger.py", "results.py", "solvers/",
                  "history.py", "units.py", "stages.py")
ABOVE = {"srdda.step", "srdda.simulation"}


def _module_names(root: Path, package: str) -> dict[str, Path]:
    """Every module under ``root`` (the folder of ``package``) by its dotted name; a package by its own name."""
    names = {}
    for path in sorted(root.rglob("*.py")):
        parts = (package, *path.relative_to(root).with_suffix("").parts)
        names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return names


def _import_statements(name: str, path: Path) -> list[tuple[str, list[str]]]:
    """(module, names) of every import in module ``name``, anywhere in it (at the top, inside functions, under
    TYPE_CHECKING), relative ones resolved: ``from M import a, b`` is (M, [a, b]), ``import M`` is (M, [])."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            base = base[: len(base) - node.level + 1] if node.level else []
            out.append((".".join([*base, node.module] if node.module else base), [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            out += [(a.name, []) for a in node.names]
    return out


def _imports(path: Path) -> set[str]:
    """Absolute names of the srdda modules and module attributes ``path`` imports."""
    name = next(n for n, p in _module_names(ROOT, "srdda").items() if p == path)
    return {n for module, names in _import_statements(name, path) for n in (module, *(f"{module}.{a}" for a in names))
            if n.startswith("srdda")}


def _ancestors(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def import_graph(root: Path, package: str) -> dict[str, set[str]]:
    """Module -> the modules of ``package`` whose code runs because it imports them, from the source alone.

    ``from M import a`` depends on the module ``M.a`` where there is one, else on ``M`` (``a`` is a name that
    M's code defines). Importing a module runs the packages above it first: a dependency on each of them too,
    except on the importer's own packages, which Python has begun to run before the importer. So a package's
    ``__init__`` importing its own submodules is an edge from the package to each submodule and no circle; a
    submodule that takes a *name* from its package's ``__init__`` depends on that ``__init__``, which is a
    circle when the ``__init__`` imports the submodule.
    """
    modules = _module_names(root, package)

    def owner(dotted: str) -> str:
        while dotted and dotted not in modules:
            dotted = dotted.rpartition(".")[0]
        return dotted

    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        own = set(_ancestors(name))
        targets = set()
        for module, names in _import_statements(name, path):
            submodules = [f"{module}.{a}" for a in names if f"{module}.{a}" in modules]
            targets.update(submodules)
            if len(submodules) < len(names) or not names:  # a name from M's code, or ``import M``
                if owner(module) and (owner(module) not in own or len(submodules) < len(names)):
                    targets.add(owner(module))
        targets |= {a for t in targets for a in _ancestors(t) if a in modules and a not in own}
        targets.discard(name)
        graph[name] = targets
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles of ``graph``: its strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def test_modules_below_the_step_never_import_it():
    offenders = {}
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith(BELOW_THE_STEP):
            bad = sorted(n for n in _imports(path) if n in ABOVE or any(n.startswith(a + ".") for a in ABOVE))
            if bad:
                offenders[rel] = bad
    assert not offenders, f"modules below the step import it: {offenders}"


# Outside srdda/apps but not the engine, so they may import the apps: the public facade (it re-exports
# factor_of_safety), ``python -m srdda`` (the command line) and the aliases of the old module paths.
NOT_ENGINE = {"srdda", "srdda.__main__", "srdda._aliases"}


def test_no_import_circles():
    graph = import_graph(ROOT, "srdda")
    found = circles(graph)
    assert not found, "import circles (each list: modules that import each other, directly or not): " + "; ".join(
        f"{c}: {[(m, sorted(graph[m] & set(c))) for m in c]}" for c in found)


# What the model's records (srdda.modeldata) may import: the leaves below every term and the builder, so that
# the terms, the state, the stages and the builder all name the records without a circle (docs/architecture.md).
RECORDS_IMPORT = ("srdda.modeldata", "srdda.history", "srdda.geometry", "srdda.kinematics")


def test_the_model_records_import_no_term_and_no_builder():
    graph = import_graph(ROOT, "srdda")
    records = {m: targets for m, targets in graph.items() if m == "srdda.modeldata" or m.startswith("srdda.modeldata.")}
    assert {"srdda.modeldata.arrays", "srdda.modeldata.materials"} <= set(records)  # the walk saw them
    offenders = {m: sorted(t for t in targets if not any(t == a or t.startswith(a + ".") for a in RECORDS_IMPORT))
                 for m, targets in records.items()}
    offenders = {m: t for m, t in offenders.items() if t}
    assert not offenders, f"model records that import above the leaves: {offenders}"


def test_the_engine_never_imports_the_apps():
    graph = import_graph(ROOT, "srdda")
    assert "srdda.apps.cli" in graph and "srdda.step" in graph  # the walk saw both layers
    offenders = {m: sorted(t for t in targets if t == "srdda.apps" or t.startswith("srdda.apps."))
                 for m, targets in graph.items() if not m.startswith("srdda.apps") and m not in NOT_ENGINE}
    offenders = {m: t for m, t in offenders.items() if t}
    assert not offenders, f"engine modules that import applications: {offenders}"


def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "pkg"
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text, encoding="utf-8")
    return root


def test_the_walk_finds_circles_hidden_in_functions_and_type_checking(tmp_path):
    # a hides its circle with b in a function, c with d under TYPE_CHECKING; e takes a name from its package,
    # whose __init__ imports e (a circle); f, imported by its package's __init__, imports a: no circle (a
    # package's __init__ importing its own submodules is an edge like any other)
    root = _package(tmp_path, {
        "__init__.py": "from .sub import f\n",
        "a.py": "def g():\n    from . import b\n",
        "b.py": "import pkg.a\n",
        "c.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .d import D\n",
        "d.py": "from .c import C\n",
        "sub/__init__.py": "from .e import E\nfrom . import f\nVALUE = 1\n",
        "sub/e.py": "from . import VALUE\n",
        "sub/f.py": "from ..a import g\n",
    })
    graph = import_graph(root, "pkg")
    assert circles(graph) == [["pkg.a", "pkg.b"], ["pkg.c", "pkg.d"], ["pkg.sub", "pkg.sub.e"]]
    assert graph["pkg.sub.f"] == {"pkg.a"}  # not pkg.sub, its own package: Python ran it before f
    assert graph["pkg.b"] == {"pkg.a"}


def test_the_walk_finds_an_engine_module_importing_an_application(tmp_path):
    root = _package(tmp_path, {"__init__.py": "", "core.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                               "    from .apps.cli import main\n", "apps/__init__.py": "", "apps/cli.py": ""})
    assert import_graph(root, "pkg")["pkg.core"] == {"pkg.apps", "pkg.apps.cli"}


def test_the_import_walk_resolves_relative_imports():
    imported = _imports(ROOT / "constraints" / "springs.py")
    assert {"srdda.term", "srdda.assembly.system", "srdda.constraints.data"} <= imported


def test_the_documented_new_term_works():
    # docs/architecture.md shows how to add a term (a viscous drag); run it: a free block's speed
    # decays as exp(-c·t/m). 1e-5: the scheme's error in cΔt/m = 1e-4 over 1000 steps (5e-6 measured).
    import re

    import numpy as np

    import srdda
    from srdda.solvers import get_solver
    from srdda.state import initial_state
    from srdda.step import Stepper

    doc = (Path(__file__).parents[1] / "docs" / "architecture.md").read_text(encoding="utf-8")
    namespace: dict = {}
    exec(re.search(r"```python\n(.*?)```", doc, re.S).group(1), namespace)
    m = srdda.Model()
    m.add_material("rock", srdda.Material(density=1000.0, young=1e9, poisson=0.25))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock", velocity=(1.0, 0.0))
    arrays = m.arrays()
    stepper = Stepper(arrays, srdda.RunSettings(dt=1e-3, n_steps=1000), get_solver())
    stepper.terms.append(namespace["Drag"](100.0))
    state = initial_state(arrays, stepper.method)
    for _ in range(1000):
        state = stepper.step(state, 1e-3).state
    assert state.velocity[0, 0] == pytest.approx(np.exp(-100.0 * 1.0 / 1000.0), rel=1e-5)


def test_old_module_paths_import_with_a_deprecation_warning():
    # a fresh interpreter: every old path (and a module inside an old package) is the new module itself, and
    # its first import warns once, naming the new path; `from srdda import paper`, `python -m srdda` and
    # `python -m srdda.cli` work
    import json
    import subprocess
    import sys

    from srdda._aliases import MOVED, PUBLIC

    probe = """
import importlib, json, warnings
from srdda._aliases import MOVED


def imported(old):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if old == "srdda.paper":  # from a package, an attribute it does not have yet
            from srdda import paper as module
        else:
            module = importlib.import_module(old)
    return [module.__name__, [str(w.message) for w in caught if w.category is DeprecationWarning]]


names = ["srdda.paper", *(n for n in MOVED if n != "srdda.paper"), "srdda.cases.slope3d", "srdda.verify.registry"]
print(json.dumps({old: imported(old) for old in names}))
"""
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    out = json.loads(run.stdout)
    expected = {**MOVED, "srdda.cases.slope3d": "srdda.apps.verify.cases.slope3d",
                "srdda.verify.registry": "srdda.apps.verify.registry"}
    for old, new in expected.items():
        name, messages = out[old]
        assert name == new
        assert len(messages) == 1 and messages[0].startswith(f"{old} has moved to {PUBLIC.get(new, new)};")
    for module in ("srdda", "srdda.cli"):  # the command line, and its old module run as a script
        assert subprocess.run([sys.executable, "-m", module, "--version"], capture_output=True, text=True,
                              check=True).stdout.startswith("srdda, version")
