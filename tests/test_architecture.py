"""The architecture: the dimension seam and the layers below the step.

Walks the source (AST) of the engine modules and fails where an integer
literal 2, 3, 6 or 12 (the 2D/3D point sizes and unknown counts) picks
columns (``x[:, 2]``, ``x[:, 3:]``), or sizes an array (``np.zeros((n, 2))``,
``reshape(-1, 6)``, ``np.eye(2)``), and on the 2D unknown count ``NDOF``
imported outside ``kinematics/``. What depends on the dimension belongs to the
block type (``srdda.kinematics.blocktype``) or to geometry.
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
    "paper/": "the paper's 2D examples",
    "plotting.py": "2D figures",
    "animation.py": "2D animations",
    "report.py": "the report of the paper's 2D examples",
    "cli.py": "the command line (figure sizes, 2D outputs)",
    "cli_results.py": "the command line (figure sizes, 2D outputs)",
    "modelview.py": "pictures of 2D and 3D models (xyz points, segment ends)",
    "render3d.py": "3D pictures (xyz points, segment ends)",
    "cases/": "verification problems: models of a given dimension",
    "verify/": "verification problems: models of a given dimension",
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
                  "state.py", "settings.py", "model.py", "ledger.py", "results.py", "solvers.py", "history.py",
                  "units.py", "stages.py")
ABOVE = {"srdda.step", "srdda.simulation"}


def _imports(path: Path) -> set[str]:
    """Absolute names of the srdda modules ``path`` imports (relative imports resolved)."""
    package = ("srdda." + ".".join(path.relative_to(ROOT).with_suffix("").parts)).rsplit(".", 1)[0]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[: len(base) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            names.add(module)
            names.update(f"{module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
    return {n for n in names if n.startswith("srdda")}


def test_modules_below_the_step_never_import_it():
    offenders = {}
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith(BELOW_THE_STEP):
            bad = sorted(n for n in _imports(path) if n in ABOVE or any(n.startswith(a + ".") for a in ABOVE))
            if bad:
                offenders[rel] = bad
    assert not offenders, f"modules below the step import it: {offenders}"


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
