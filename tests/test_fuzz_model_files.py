"""Fuzzing the model-file reader: no mutated file ends in a traceback (issue 15).

Valid model files (the paper's, the cutting and 3D examples) are mutated with
a fixed seed: bytes flipped, lines dropped or duplicated, numbers replaced by
extreme or non-finite values, keys renamed, the file truncated. ``srdda check``
must answer every one with exit 0 (still valid) or 2 and one message, never an
exception. ``make test`` runs 150 mutants (a few seconds); the slow run 600.
"""
from __future__ import annotations

import random
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from srdda.cli import main
from srdda.paper import examples_dir

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted((examples_dir() / "paper").glob("*.toml")) + [ROOT / "examples" / "solid" / "hinged-boxes.toml",
                                                               ROOT / "examples" / "cutting" / "tunnel.toml"]
NUMBERS = ["0", "-1", "1e300", "-1e300", "1e-300", "nan", "inf", "-inf", "1e23", "3.5", "\"x\"", "[]", "true"]


def _mutant(text: str, rng: random.Random) -> bytes:
    kind = rng.randrange(6)
    lines = text.splitlines()
    if kind == 0:  # replace one number
        spots = [m.span() for m in re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", text)]
        a, b = rng.choice(spots)
        return (text[:a] + rng.choice(NUMBERS) + text[b:]).encode()
    if kind == 1:  # drop a line
        del lines[rng.randrange(len(lines))]
    elif kind == 2:  # duplicate a line
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
    elif kind == 3:  # rename a key
        keys = [i for i, line in enumerate(lines) if "=" in line and not line.lstrip().startswith("#")]
        i = rng.choice(keys)
        lines[i] = lines[i].replace(lines[i].split("=")[0].strip(), "x" + lines[i].split("=")[0].strip(), 1)
    elif kind == 4:  # truncate
        return text.encode()[: rng.randrange(len(text))]
    else:  # flip bytes
        data = bytearray(text.encode())
        for _ in range(rng.randrange(1, 4)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        return bytes(data)
    return "\n".join(lines).encode()


def _check_mutants(tmp_path: Path, count: int, seed: int) -> None:
    rng = random.Random(seed)
    runner = CliRunner()
    failures = []
    for k in range(count):
        source = rng.choice(SOURCES)
        path = tmp_path / f"m{k}.toml"
        path.write_bytes(_mutant(source.read_text(encoding="utf-8"), rng))
        result = runner.invoke(main, ["check", str(path)])
        if result.exit_code not in (0, 2) or (result.exception is not None and not isinstance(result.exception,
                                                                                               SystemExit)):
            failures.append((source.name, path.read_bytes()[:200], repr(result.exception), result.output[-300:]))
    assert not failures, f"{len(failures)} of {count} mutants ended in a traceback: {failures[:3]}"


def test_mutated_model_files_never_end_in_a_traceback(tmp_path):
    _check_mutants(tmp_path, 150, seed=1)


@pytest.mark.slow
def test_many_mutated_model_files_never_end_in_a_traceback(tmp_path):
    _check_mutants(tmp_path, 600, seed=2)
