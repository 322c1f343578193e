"""The full fuzzing of issue 32's acceptance, apart from ``make test`` (which runs samples of both).

    .venv/bin/python tests/fuzz_full.py [--model-files 1000] [--results-files 120] [--seed 3]

* Mutated model files (tests/test_fuzz_model_files.py, 2D and 3D sources):
  ``srdda check`` exits 0 or 2 with one message, and a mutant it accepts runs
  two steps to exit 0 or 3; each mutant gets 60 s (SIGALRM) before it counts
  as a hang.
* Damaged results files (tests/results_fuzz.py, every kind in turn): ``plot``,
  ``vtk`` and ``run --resume`` end without a traceback, leave no lock, and a
  resume that runs ends bit-identical to the uninterrupted run; a file whose
  header and model are intact is always resumed. Each file is checked in a
  child process with a 300 s timeout, so a hang or a crash of HDF5 counts as a
  failure too.

Prints the outcomes by kind and the time taken; exits 1 if anything failed.
docs/reliability.md quotes the last full run.
"""
from __future__ import annotations

import argparse
import json
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import results_fuzz  # noqa: E402
import test_fuzz_model_files  # noqa: E402


def _alarm(signum, frame):
    raise TimeoutError("no answer within 60 s")


def model_files(count: int, seed: int, folder: Path) -> tuple[Counter, int]:
    """Check ``count`` mutants, one at a time under a 60 s alarm; returns the outcomes and the failures."""
    outcomes: Counter = Counter()
    failed = 0
    signal.signal(signal.SIGALRM, _alarm)
    for k in range(count):
        signal.alarm(60)
        try:
            found, failures = test_fuzz_model_files.check_mutants(folder / f"m{k}", 1, seed * 1_000_000 + k)
        except TimeoutError as exc:
            found, failures = {"hung": 1}, [(str(exc),)]
        finally:
            signal.alarm(0)
        outcomes.update(found)
        failed += len(failures)
        for failure in failures:
            print(f"model file {k}: {failure}", flush=True)
    return outcomes, failed


def _one_results_file(source: str, complete: str, kind: str, seed: int, folder: str) -> None:
    """Child process: damage one copy, check it, print the outcome as JSON."""
    rng = random.Random(seed)
    work = Path(folder)
    what = results_fuzz.damage(Path(source), work / "results.h5", kind, rng)
    problems, how = results_fuzz.check(work / "results.h5", Path(complete), kind, work)
    print(json.dumps({"what": what, "problems": problems, "how": how}))


def results_files(count: int, seed: int, folder: Path) -> tuple[Counter, int]:
    _, complete, killed = results_fuzz.sources(folder / "sources")
    rng = random.Random(seed)
    outcomes: Counter = Counter()
    failed = 0
    for i in range(count):
        kind = results_fuzz.KINDS[i % len(results_fuzz.KINDS)]
        source = rng.choice([complete, killed])
        work = folder / f"r{i}"
        work.mkdir(parents=True)
        args = [sys.executable, __file__, "--one", str(source), str(complete), kind, str(rng.randrange(1 << 30)),
                str(work)]
        try:
            child = subprocess.run(args, capture_output=True, text=True, timeout=300)
            result = json.loads(child.stdout.strip().splitlines()[-1]) if child.returncode == 0 else {
                "what": kind, "problems": [f"exit {child.returncode}: {child.stderr[-500:]}"], "how": "crashed"}
        except subprocess.TimeoutExpired:
            result = {"what": kind, "problems": ["no answer within 300 s"], "how": "hung"}
        how = result["how"]
        if how.startswith("refused"):  # why, without the file's name: "damaged: the stored model ...", ...
            how = "refused, " + re.sub(r"^.*?results\.h5:? ", "", how).split(" (")[0].split(";")[0]
        outcomes[f"{kind} ({source.stem}): {how}"] += 1
        if result["problems"]:
            failed += 1
            print(f"results file {i}: {result['what']}: {result['problems']}", flush=True)
    return outcomes, failed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model-files", type=int, default=1000)
    parser.add_argument("--results-files", type=int, default=120)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--one", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        source, complete, kind, seed, folder = args.one
        _one_results_file(source, complete, kind, int(seed), folder)
        return 0
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, fuzz, count in (("model files", model_files, args.model_files),
                                  ("results files", results_files, args.results_files)):
            start = time.perf_counter()
            outcomes, bad = fuzz(count, args.seed, Path(tmp) / name.replace(" ", "-"))
            failed += bad
            print(f"{name}: {count} in {time.perf_counter() - start:.0f} s, {bad} failed")
            for outcome, n in sorted(outcomes.items()):
                print(f"  {outcome}: {n}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
