"""Run every benchmark script in this folder and ``srdda bench --quick`` (``make bench``).

The full set of standard models (issue 14: slopes, brick walls) is ``srdda bench``.
"""
import pathlib
import runpy
import sys

from srdda.apps.bench.runner import QUICK, format_table, run_cases

here = pathlib.Path(__file__).parent
failed = []
for script in sorted(here.glob("bench_*.py")):
    print(f"== {script.name} ==", flush=True)
    sys.argv = [str(script)]
    try:
        runpy.run_path(str(script), run_name="__main__")
    except Exception as exc:  # report and go on with the other benchmarks
        print(f"{script.name} failed: {exc!r}", flush=True)
        failed.append(script.name)
print("== srdda bench --quick ==", flush=True)
rows = run_cases(list(QUICK), None, True, "dda0", None, 900.0)
print(format_table(rows), flush=True)
if any(r["status"] != "completed" for r in rows):
    failed.append("srdda bench --quick")
sys.exit(1 if failed else 0)
