"""Run every benchmark script in this folder (``make bench``)."""
import pathlib
import runpy
import sys

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
sys.exit(1 if failed else 0)
