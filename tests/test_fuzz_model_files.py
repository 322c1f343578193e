"""Fuzzing the model-file reader: no mutated file ends in a traceback (issues 15 and 32).

Valid model files (the paper's, the cutting, constraint and 3D examples) are
mutated with a fixed seed: bytes flipped, lines dropped or duplicated, numbers
replaced by extreme, non-finite, boolean or over-long values, keys renamed, the
file truncated. ``srdda check`` must answer every one with exit 0 (still valid)
or 2 and one message, never an exception; and a mutant that ``check`` accepts
must run (two steps) to exit 0 or 3 (diverged), never to a usage error or an
exception: ``check`` finds what ``run`` cannot do. ``make test`` runs 150
mutants (seconds); the slow test 600; ``tests/fuzz_full.py`` 1,000 and more
(docs/reliability.md gives its last figures).
"""
from __future__ import annotations

import random
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from srdda.apps.cli import main
from srdda.apps.paper import examples_dir

ROOT = Path(__file__).resolve().parents[1]
SOURCES_2D = sorted((examples_dir() / "paper").glob("*.toml")) + [
    ROOT / "examples" / "cutting" / "tunnel.toml", ROOT / "examples" / "constraints" / "hinged-wall.toml"]
SOURCES_3D = [ROOT / "examples" / "solid" / name for name in ("hinged-boxes.toml", "cube-drop.toml", "wedge-fs0.8.toml",
                                                              "incline.toml")]
SOURCES = SOURCES_2D + SOURCES_3D
NUMBERS = ["0", "-1", "1e300", "-1e300", "1e-300", "nan", "inf", "-inf", "1e23", "3.5", "\"x\"", "[]", "true", "false",
           "9" * 5000]


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


def check_mutants(folder: Path, count: int, seed: int) -> tuple[dict[str, int], list[tuple[str, ...]]]:
    """Check ``count`` mutants (seed ``seed``); run the ones check accepts.

    Returns how they ended (counts by outcome) and the failures: the mutants
    that ended in an exception or a traceback, or that check accepted and the
    run refused.
    """
    rng = random.Random(seed)
    runner = CliRunner()
    failures, outcomes = [], {}
    for k in range(count):
        source = rng.choice(SOURCES)
        path = folder / f"m{k}.toml"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(_mutant(source.read_text(encoding="utf-8"), rng))
        result = runner.invoke(main, ["check", str(path)])
        outcome = f"{'3D' if source in SOURCES_3D else '2D'} check {result.exit_code}"
        bad = result.exit_code not in (0, 2)
        if result.exit_code == 0:
            result = runner.invoke(main, ["run", str(path), "--steps", "2", "--out", str(folder / f"o{k}"), "--quiet"])
            outcome += f", run {result.exit_code}"
            bad = result.exit_code not in (0, 3)
        bad = bad or (result.exception is not None and not isinstance(result.exception, SystemExit))
        if bad or "Traceback" in result.output:
            failures.append((source.name, str(path.read_bytes()[:200]), repr(result.exception), result.output[-300:]))
        outcomes[outcome] = outcomes.get(outcome, 0) + 1
    return outcomes, failures


def test_mutated_model_files_never_end_in_a_traceback(tmp_path):
    outcomes, failures = check_mutants(tmp_path, 150, seed=1)
    assert not failures, f"{len(failures)} of 150 mutants failed: {failures[:3]}"
    assert sum(n for o, n in outcomes.items() if o.startswith("3D")) > 20  # both kinds of model are fuzzed
    assert sum(n for o, n in outcomes.items() if "run 0" in o) > 20  # and runs of the mutants check accepts


@pytest.mark.slow
def test_many_mutated_model_files_never_end_in_a_traceback(tmp_path):
    _, failures = check_mutants(tmp_path, 600, seed=2)
    assert not failures, f"{len(failures)} of 600 mutants failed: {failures[:3]}"
