"""Damaged copies of results files (issue 32): how they are made, and what srdda must do with each.

The files come from a small 2D run with contacts (a block sliding on a tilted
base: every step records a contact set), uninterrupted (completed) and as a
kill leaves it (the file copied after a flush, status "running"). A damaged
copy is one of:

* ``chunk``: one byte flipped inside a data chunk of a dataset of /history,
  /contacts or /checkpoint (the header and model intact: the file keeps an
  intact prefix and must resume from it);
* ``flip``: 1 to 3 bytes flipped anywhere;
* ``zero``: a run of 16 to 4096 bytes set to zero anywhere;
* ``truncate``: the file cut at a random length;
* ``delete``: a dataset or an attribute deleted (with h5py);
* ``text``: one byte flipped inside a text attribute (settings, status, names, model text).

:func:`check` runs ``srdda plot``, ``srdda vtk`` and ``srdda run --resume`` on a
copy and returns what went wrong: a traceback, an exit code other than the
documented ones, a lock file left behind, a resume that fails on a file whose
header and model are intact, or a resume that does not end bit-identical to the
uninterrupted run (every /history and /contacts dataset, the final checkpoint).
"""
from __future__ import annotations

import dataclasses
import random
import shutil
import warnings
from pathlib import Path

import h5py
import numpy as np
from click.testing import CliRunner

import srdda
from srdda.apps.cli import main
from srdda.io.modelfile import load_model
from srdda.io.results_store import ResultsStore

KINDS = ("chunk", "flip", "zero", "truncate", "delete", "text")
MODEL = '''title = "A block sliding on a tilted base (results-file fuzz)"
gravity = [3.0, -9.5]
[run]
method = "srdda"
dt = "1 ms"
steps = 60
[materials.rock]
density = 2500.0
young = "1 GPa"
poisson = 0.25
[joint_materials.j]
friction_angle = 10.0
between = [["rock", "rock"]]
[[blocks]]
name = "base"
material = "rock"
vertices = [[-1.0, -0.5], [3.0, -0.5], [3.0, 0.0], [-1.0, 0.0]]
fixed = true
[[blocks]]
name = "block"
material = "rock"
vertices = [[0.0, 0.0], [0.5, 0.0], [0.5, 0.4], [0.0, 0.4]]
[[measured_points]]
at = [0.25, 0.2]
block = "block"
'''
FLUSH = 8  # recorded steps between flushes: 7 flushes in 60 steps
KILLED_AFTER = 4  # the killed file: copied after its 4th flush (steps 0-31)


class _CopiedAfterFlush(ResultsStore):
    """Copies its file right after flush ``KILLED_AFTER``: what a SIGKILL at that point leaves on disk."""

    flushes = 0
    copy_to: Path | None = None

    def flush(self) -> None:
        super().flush()
        self.flushes += 1
        if self.flushes == KILLED_AFTER and self.copy_to is not None:
            shutil.copy(self.path, self.copy_to)


def sources(folder: Path) -> tuple[Path, Path, Path]:
    """The model file, the uninterrupted run's results and a killed run's results, written in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    model_file = folder / "slide.toml"
    model_file.write_text(MODEL, encoding="utf-8")
    model, settings = load_model(model_file)
    complete, killed = folder / "complete.h5", folder / "killed.h5"
    store = _CopiedAfterFlush(complete, settings, flush_every=FLUSH, model_text=MODEL)
    store.copy_to = killed
    assert srdda.run(model, settings, recorders=[store], keep_history=False).completed
    return model_file, complete, killed


def _datasets(path: Path) -> list[str]:
    """The appended datasets of a results file that have stored chunks."""
    with h5py.File(path, "r") as f:
        out = []
        for group in ("history", "contacts", "checkpoint"):
            out += [f"{group}/{k}" for k in f[group] if f[group][k].id.get_num_chunks() > 0]
        return out


def _text_spots(data: bytes) -> list[int]:
    """Offsets of the bytes of text attributes (JSON settings, names, the model text, the status)."""
    spots = []
    for marker in (b'"dt"', b'"record_every"', b'["base"', b"completed", b"running", b"title =", b"kinetic"):
        start = data.find(marker)
        if start >= 0:
            spots += range(start, start + len(marker))
    return spots


def damage(source: Path, target: Path, kind: str, rng: random.Random) -> str:
    """Write a damaged copy of ``source`` to ``target``; returns what was done."""
    data = bytearray(source.read_bytes())
    if kind == "chunk":
        name = rng.choice(_datasets(source))
        with h5py.File(source, "r") as f:
            ds = f[name]
            info = ds.id.get_chunk_info(rng.randrange(ds.id.get_num_chunks()))
        where = info.byte_offset + rng.randrange(info.size)
        data[where] ^= 1 << rng.randrange(8)
        what = f"{kind}: {name}, byte {where}"
    elif kind == "flip":
        spots = [rng.randrange(len(data)) for _ in range(rng.randint(1, 3))]
        for where in spots:
            data[where] ^= 1 << rng.randrange(8)
        what = f"{kind}: bytes {spots}"
    elif kind == "zero":
        start, length = rng.randrange(len(data)), rng.randint(16, 4096)
        data[start:start + length] = bytes(len(data[start:start + length]))
        what = f"{kind}: bytes {start}..{start + length}"
    elif kind == "truncate":
        cut = rng.randrange(len(data))
        del data[cut:]
        what = f"{kind}: at byte {cut}"
    elif kind == "text":
        where = rng.choice(_text_spots(bytes(data)))
        data[where] ^= 1 << rng.randrange(7)
        what = f"{kind}: byte {where} ({bytes(data[max(0, where - 8):where + 8])!r})"
    else:  # delete
        target.write_bytes(bytes(data))
        with h5py.File(target, "a") as f:
            names: list[str] = []
            f.visit(names.append)
            objects = [n for n in names if isinstance(f[n], h5py.Dataset)]
            attributes = [(n, a) for n in ["/", *names] for a in f[n].attrs]
            if rng.random() < 0.5:
                name = rng.choice(objects)
                del f[name]
                return f"{kind}: dataset {name}"
            obj, attr = rng.choice(attributes)
            del f[obj].attrs[attr]
            return f"{kind}: attribute {attr!r} of {obj}"
    target.write_bytes(bytes(data))
    return what


def _one_line(result, allowed: tuple[int, ...]) -> str | None:
    """What is wrong with a command's outcome: a traceback, an exception, an exit code not allowed."""
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        return f"exception {result.exception!r}"
    if "Traceback" in result.output:
        return "traceback in the output"
    if result.exit_code not in allowed:
        return f"exit {result.exit_code}: {result.output[-300:]}"
    return None


def _same_run(path: Path, reference: Path) -> str | None:
    """None if the resumed file holds what the uninterrupted run wrote, bit for bit; else the first difference."""
    with h5py.File(path, "r") as a, h5py.File(reference, "r") as b:
        for group in ("history", "contacts"):
            if set(a[group]) != set(b[group]):
                return f"/{group} holds {sorted(a[group])}, the uninterrupted run {sorted(b[group])}"
            for name in b[group]:
                if not np.array_equal(a[group][name][()], b[group][name][()], equal_nan=True):
                    return f"/{group}/{name} differs from the uninterrupted run"
    model = srdda.io.results_store.model_arrays_from_file(reference)
    last, ref = (srdda.io.results_store.load_checkpoint(p, model) for p in (path, reference))
    for f in dataclasses.fields(ref):
        x, y = getattr(last, f.name), getattr(ref, f.name)
        if isinstance(y, np.ndarray) and not np.array_equal(x, y, equal_nan=True):
            return f"the final checkpoint's {f.name} differs"
    return None


def check(damaged: Path, reference: Path, kind: str, work: Path) -> tuple[list[str], str]:
    """Run plot, vtk and --resume on ``damaged`` (in its own folder ``work``).

    Returns what went wrong (empty: nothing) and how the resume ended: "resumed", "refused" (one message).
    """
    runner = CliRunner()
    problems = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for args in (["plot", str(damaged), "-o", str(work / "model.png")], ["vtk", str(damaged), "-o",
                                                                            str(work / "vtk")]):
            wrong = _one_line(runner.invoke(main, args), (0, 1, 2))
            if wrong:
                problems.append(f"{args[0]}: {wrong}")
        resumed = runner.invoke(main, ["run", "--resume", str(damaged), "--quiet"])
    wrong = _one_line(resumed, (0, 2))
    if wrong:
        problems.append(f"resume: {wrong}")
    elif resumed.exit_code == 0:
        different = _same_run(damaged, reference)
        if different:
            problems.append(f"resume: {different}")
    elif kind == "chunk":  # header and model intact: it must resume
        problems.append(f"resume refused a file whose header and model are intact: {resumed.output[-300:]}")
    left = [p.name for p in work.iterdir() if p.name.endswith((".lock", ".reserve")) or ".reserve-" in p.name]
    if left:
        problems.append(f"left behind: {left}")
    return problems, "resumed" if resumed.exit_code == 0 else f"refused: {resumed.output.strip().splitlines()[-1]}"
