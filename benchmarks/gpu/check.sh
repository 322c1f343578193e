#!/usr/bin/env bash
# Issue 34's check on a machine with one CUDA GPU (the lent H100/H200), in one call of about 8 minutes.
#
# Needs: python3 with numpy, scipy, numba, h5py, click, tqdm, threadpoolctl, pytest, hypothesis and CuPy
# (the device image has them), and srdda's other dependencies as wheels in .whl/ (made by
# benchmarks/gpu/wheels.sh, carried with the call: no network there). srdda runs from src/ (PYTHONPATH).
# Writes at most 8 files to $OUT (env.txt, tests.log, compare.json, cg.json, bench.json, wall_1m.json,
# log.txt, summary.txt) and prints the summary last. BUDGET (s, default 480) bounds the measurements;
# each phase stops at its own deadline and the summary says what was skipped.
set -u
START=$(date +%s)
BUDGET=${BUDGET:-480}
SMALL=${SMALL:-}  # "--small --fake-gpu": a rehearsal on small models without a GPU (the bench rows then on the CPU)
DEADLINE=$((START + BUDGET))
OUT=${OUT:-/tmp/srdda-gpu-out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
cd "$(dirname "$0")/../.."

if [ -z "$SMALL" ]; then  # a rehearsal runs in srdda's own virtual environment, which has them
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site \
        .whl/*.whl || { echo "installing the carried wheels failed"; exit 1; }
fi
export PYTHONPATH="$PWD/src:/tmp/site"
DRIVER="python3 benchmarks/gpu/driver.py"
LOG="$OUT/log.txt"

{
    date -u; nvidia-smi; nproc; free -g
    python3 -c "import sys, numpy, scipy, numba, cupy; print('python', sys.version.split()[0], 'numpy', numpy.__version__,
'scipy', scipy.__version__, 'numba', numba.__version__, 'cupy', cupy.__version__, 'cuda runtime',
cupy.cuda.runtime.runtimeGetVersion(), 'threading layer', numba.config.THREADING_LAYER)"
    python3 -m srdda info
} > "$OUT/env.txt" 2>&1
tail -n 4 "$OUT/env.txt"

# the 1,000,000-block wall is built at low priority on a spare core while the correctness checks run, and
# stepped on the GPU once the timed measurements are done (the file /tmp/srdda-go)
rm -f /tmp/srdda-go
nice -n 19 $DRIVER wall1m --out "$OUT/wall_1m.json" --go /tmp/srdda-go --steps 3 --deadline $((DEADLINE + 20)) \
    $SMALL >> "$LOG" 2>&1 &
WALL1M=$!

echo "== GPU tests ($(($(date +%s) - START)) s)"
timeout $((START + 120 - $(date +%s))) python3 -m pytest -q -p no:cacheprovider -ra tests/test_backends.py \
    > "$OUT/tests.log" 2>&1
echo "pytest exit $? (124: stopped at its time limit)"; tail -n 3 "$OUT/tests.log"

echo "== 20 steps CPU / GPU / direct ($(($(date +%s) - START)) s)"
$DRIVER compare --out "$OUT/compare.json" --deadline $((START + 220)) $SMALL >> "$LOG" 2>&1 || echo "compare failed"

echo "== srdda bench --device gpu and cpu ($(($(date +%s) - START)) s)"
$DRIVER bench --out "$OUT/bench.json" --deadline $((DEADLINE - 90)) --timeout 100 $SMALL >> "$LOG" 2>&1 \
    || echo "bench failed"

echo "== CG on step systems ($(($(date +%s) - START)) s)"
$DRIVER systems --out "$OUT/cg.json" --deadline $((DEADLINE - 30)) $SMALL >> "$LOG" 2>&1 || echo "systems failed"

echo "== 1,000,000-block wall ($(($(date +%s) - START)) s)"
touch /tmp/srdda-go
wait $WALL1M || echo "wall_1m failed"

echo "== done in $(($(date +%s) - START)) s; last lines of the log:"
tail -n 5 "$LOG"
$DRIVER summary --out "$OUT"
