#!/usr/bin/env bash
# Issue 34's short check on a machine with one CUDA GPU, in one call of about 6 minutes: the GPU tests, then
# `srdda bench` rows of the acceptance models on the GPU and on the same machine's CPU cores, each model in a
# fresh process (the first compiles the numba kernels into src/'s caches). Carries what check.sh carries
# (.whl, made by wheels.sh). BUDGET (s, default 380) bounds it; a row that no longer fits is skipped and says
# so. Writes tests.log, one JSON file a row and rows.err (the rows' warnings) to $OUT, and prints a line a row.
# ROWS ("model device contact-solver" rows, separated by ";") replaces the default rows; SRC (default src) is
# the source tree the rows run (a copy of an earlier commit, for a baseline on the same machine); NO_TESTS=1
# skips the tests.
set -u
START=$(date +%s)
BUDGET=${BUDGET:-380}
OUT=${OUT:-/tmp/srdda-gpu-out}
mkdir -p "$OUT"
cd "$(dirname "$0")/../.."
[ -n "${NO_WHEELS:-}" ] || python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl \
    || { echo "installing the carried wheels failed"; exit 1; }
export PYTHONPATH="$PWD/${SRC:-src}:/tmp/site" PYTHONUNBUFFERED=1
nvidia-smi -L; nproc
if [ -z "${NO_TESTS:-}" ]; then
    timeout 120 python3 -m pytest -q -p no:cacheprovider -ra tests/test_backends.py > "$OUT/tests.log" 2>&1
    echo "GPU tests: exit $? (124: stopped at 120 s)"; tail -n 2 "$OUT/tests.log"
fi
ROWS=${ROWS:-"wall_100k gpu open-close;wall_100k cpu open-close;wall3d_10k gpu open-close;wall3d_10k cpu open-close;slope3d_1k gpu newton;slope3d_1k cpu newton"}
IFS=";" read -r -a rows <<< "$ROWS"
for row in "${rows[@]}"; do
    set -- $row
    left=$((START + BUDGET - $(date +%s)))
    if [ "$left" -lt 60 ]; then echo "$1 $2 $3: skipped, $left s left"; continue; fi
    timeout "$left" python3 -m srdda bench --json --model "$1" --device "$2" --contact-solver "$3" \
        --timeout $((left - 15)) > "$OUT/$1-$2-$3${SRC:+-old}.json" 2>> "$OUT/rows.err"
    python3 - "$OUT/$1-$2-$3${SRC:+-old}.json" <<'PY'
import json, sys
try:
    rows = json.load(open(sys.argv[1]))["rows"]
except Exception as exc:
    print(sys.argv[1], "no result:", type(exc).__name__)
    sys.exit()
for r in rows:
    keys = ("model", "device", "contact_solver", "steps", "steps_per_s", "solves_per_step", "cg_iterations_per_solve",
            "rejected_steps", "share_detection", "share_assembly", "share_solve", "share_open_close", "gpu_peak_mb",
            "status")
    print({k: (round(r[k], 4) if isinstance(r.get(k), float) else r.get(k)) for k in keys})
PY
done
echo "done in $(($(date +%s) - START)) s"
