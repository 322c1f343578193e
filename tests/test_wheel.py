"""The wheel works outside the repository: built, installed in a fresh virtual environment, run from tmp.

The wheel is built from a copy of the source tree (so no stale ``build/``
folder of the clone can leak into it), installed with ``--no-deps`` into a
venv without system site packages, and the dependencies are made importable
by a ``.pth`` file naming this interpreter's site-packages folders. A ``.pth``
line only puts a folder on ``sys.path``; the ``.pth`` files inside it (the
editable install of srdda) are not run, so ``import srdda`` can only find the
installed wheel, which the test checks from ``srdda.__file__``.
"""
from __future__ import annotations

import json
import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _run(args: list[str], cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "SRDDA_EXAMPLES", "PYTHONHOME")}
    return subprocess.run(args, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=timeout)


def _copy_source(dest: Path) -> Path:
    dest.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(REPO / name, dest / name)
    shutil.copytree(REPO / "src", dest / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "*.nbi",
                                                                              "*.nbc"))
    return dest


def test_the_wheel_runs_the_paper_rod_from_any_folder(tmp_path: Path) -> None:
    source = _copy_source(tmp_path / "source")
    build = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(tmp_path / "dist"), str(source)],
                 cwd=tmp_path)
    assert build.returncode == 0, build.stdout
    assert "deprecat" not in build.stdout.lower(), build.stdout  # the build must print no deprecation warning
    (wheel,) = (tmp_path / "dist").glob("srdda-*.whl")

    venv = tmp_path / "venv"
    made = _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], cwd=tmp_path)
    assert made.returncode == 0, made.stdout
    python, srdda = venv / "bin" / "python", venv / "bin" / "srdda"
    installed = _run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-index", "--no-deps",
                      "--quiet", str(wheel)], cwd=tmp_path)
    assert installed.returncode == 0, installed.stdout
    purelib = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                        cwd=tmp_path).stdout.strip())
    (purelib / "test_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")

    work = tmp_path / "elsewhere"
    work.mkdir()
    where = _run([str(python), "-c", "import srdda; print(srdda.__file__)"], cwd=work)
    assert where.returncode == 0, where.stdout
    assert Path(where.stdout.strip()).is_relative_to(venv), where.stdout  # the wheel, not the source tree

    helped = _run([str(srdda), "--help"], cwd=work)
    assert helped.returncode == 0, helped.stdout
    assert "paper" in helped.stdout and "convert" in helped.stdout

    rod = _run([str(srdda), "paper", "rod", "--json", "--quiet"], cwd=work)
    assert rod.returncode == 0, rod.stdout
    document = json.loads(rod.stdout)
    assert document["example"] == "rod"
    assert {r["method"] for r in document["rows"]} == {"dda0", "dda1", "srdda"}
    # Table 3: the rod's area under SRDDA stays its initial value (rigid rotation; the table
    # rounds to 1e-6, the paper prints 1.000000)
    areas = [r["ours"] for r in document["rows"] if r["quantity"] == "area" and r["method"] == "srdda"]
    assert areas and all(abs(a - 1.0) < 1e-6 for a in areas)
    assert list(work.iterdir()) == []  # `srdda paper` without --report writes nothing
    # the README's convert example and `srdda show` from the wheel: the Shi-format input ships as package data
    converted = _run([str(srdda), "convert", "--example", "circleslope", "-o", "slope.toml"], cwd=work)
    assert converted.returncode == 0 and "7 blocks" in converted.stdout, converted.stdout
    shown = _run([str(srdda), "show", "slope.toml", "-o", "slope.png"], cwd=work)
    assert shown.returncode == 0 and (work / "slope.png").stat().st_size > 10_000, shown.stdout
