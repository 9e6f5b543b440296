#!/usr/bin/env bash
# Issue 48's GPU measurements as one command on a lent CUDA machine (the device tool), from the
# repository root, in at most ~9 minutes (every part under `timeout`, all of them under one deadline):
#
#   bash benchmarks/gpu/run.sh              # on the GPU (CuPy), paper sizes
#   RC_SMOKE=1 bash benchmarks/gpu/run.sh   # dry run of this script on a CPU: numpy backend, tiny sizes
#
# Parts, each in its own fresh process, each allowed to fail without stopping the others:
#   device   nvidia-smi and the versions
#   cold1    one 1024² 30-step paper case in a fresh process with an EMPTY kernel cache (CUPY_CACHE_DIR):
#            first and warm solve, batched (B = 1) and single (benchmarks/gpu/single_case.py)
#   cold2    the same in a second fresh process: the kernel cache is there now
#   grid     the paper grid's 60-case sample batched with B = 16, 64, 128 (bench_paper_grid.py --batch),
#            the projection to the 1200 cases
#   check    3 cases at N = 512, 30 steps, batched on the GPU against single numpy solves on the CPU
#   whole    the whole 1200-case grid with B = 128 in the time that is left but ~80 s (batches in turns over
#            k_s, so that a run cut short by its limit has seen every kind; each batch's row printed as it ends)
#   grid_k8  the sample with B = 64 and a host check every 8th round (check_every 8; default 1), if time is left
#   tests    tests/test_batch.py with ROUGHCONTACT_ARRAY_BACKEND=cupy (the real CuPy), if time is left
# Logs go to $OUT (8 files): cold1.log, cold2.log, grid.log, check.log, grid_k8.log, tests.log, whole.log
# and summary.txt (the device, the SUMMARY lines and each part's status; printed last).
# Wheels the machine lacks (pint and its needs, pyFFTW) travel in .whl/ (benchmarks/README.md).
set -u -o pipefail
OUT=${OUT:-/tmp/gpu-out}; mkdir -p "$OUT"
START=$SECONDS
BUDGET=${RC_BUDGET:-525}   # seconds for everything, setup included
SMOKE=${RC_SMOKE:-0}
PY=${PYTHON:-python3}
if [ -d .whl ] && [ "$SMOKE" != 1 ]; then
  $PY -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl \
    || echo "pip install of .whl/ failed (rc $?)"
  export PYTHONPATH=/tmp/site:$PWD/src:$PWD/tests
else
  export PYTHONPATH=$PWD/src:$PWD/tests
fi
export PYTHONUNBUFFERED=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
# a kernel cache of this run's own, empty at the start: cold1 fills it, cold2 reads it
export CUPY_CACHE_DIR=${RC_CUPY_CACHE:-/tmp/rc-cupy-cache}
rm -rf "$CUPY_CACHE_DIR"
if [ "$SMOKE" = 1 ]; then
  BACKEND=numpy; N=128; STEPS=4; LIMIT="--limit 8"; BATCHES="2 4 8"; NCHECK=64; B_K8=4
else
  BACKEND=cupy; N=1024; STEPS=30; LIMIT=""; BATCHES="16 64 128"; NCHECK=512; B_K8=64
fi
STATUS=()

# part NAME LIMIT_S COMMAND...: run with the smaller of LIMIT_S and the time left, log to $OUT/NAME.log
part() {
  local name=$1 limit=$2; shift 2
  local left=$((BUDGET - (SECONDS - START)))
  if [ "$left" -lt 15 ]; then STATUS+=("$name: skipped (no time left)"); echo "== $name: skipped"; return; fi
  [ "$limit" -gt "$left" ] && limit=$left
  echo "== $name (limit ${limit} s, $((SECONDS - START)) s into the run)"
  local t0=$SECONDS
  timeout --kill-after=5 "$limit" "$@" > "$OUT/$name.log" 2>&1
  local rc=$?
  local why="rc $rc"; [ "$rc" = 124 ] || [ "$rc" = 137 ] && why="TIMED OUT at ${limit} s"
  STATUS+=("$name: $why, $((SECONDS - t0)) s")
  tail -n 25 "$OUT/$name.log"
}

DEVICE=$({
  echo "date $(date -u '+%Y-%m-%d %H:%M:%S UTC'), commit $(git rev-parse --short HEAD 2>/dev/null || echo '?'), smoke $SMOKE"
  nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv 2>&1 || echo "no nvidia-smi"
  $PY -c "import sys, numpy; print('python', sys.version.split()[0], 'numpy', numpy.__version__)"
  $PY -c "import cupy; print('cupy', cupy.__version__, 'CUDA runtime', cupy.cuda.runtime.runtimeGetVersion())" 2>&1 | tail -1
  $PY -c "import scipy; print('scipy', scipy.__version__)" 2>&1 | tail -1
  lscpu 2>/dev/null | grep -m1 'Model name' || true
} 2>&1)
echo "$DEVICE"

part cold1 110 $PY benchmarks/gpu/single_case.py --backend $BACKEND --n $N --steps $STEPS --label cold1
part cold2 70 $PY benchmarks/gpu/single_case.py --backend $BACKEND --n $N --steps $STEPS --label cold2
# shellcheck disable=SC2086
part grid 200 $PY benchmarks/bench_paper_grid.py --backend $BACKEND --n $N --steps $STEPS $LIMIT --batch $BATCHES
part check 80 $PY benchmarks/bench_paper_grid.py --backend $BACKEND --n $NCHECK --steps $STEPS --limit 3 \
  --batch 3 --compare 3 --compare-backend numpy --label check
# the whole grid: what is left but ~80 s for the two parts after it; in the smoke run a few batches
if [ "$SMOKE" = 1 ]; then WHOLE_OPTS="--limit 48 --max-batches 4"; else WHOLE_OPTS=""; fi
# shellcheck disable=SC2086
part whole $((BUDGET - (SECONDS - START) - 80)) $PY benchmarks/bench_paper_grid.py --backend $BACKEND --n $N \
  --steps $STEPS --whole --batch "${RC_WHOLE_BATCH:-128}" $WHOLE_OPTS --label whole
# shellcheck disable=SC2086
part grid_k8 60 $PY benchmarks/bench_paper_grid.py --backend $BACKEND --n $N --steps $STEPS $LIMIT --batch $B_K8 \
  --check-every 8 --label grid_k8
if [ "$SMOKE" = 1 ]; then
  part tests 120 $PY -m pytest -q -p no:cacheprovider -n 0 tests/test_batch.py
else
  part tests 60 env ROUGHCONTACT_ARRAY_BACKEND=cupy $PY -m pytest -q -p no:cacheprovider tests/test_batch.py -x
fi

{
  echo "# issue 48 GPU run: summary ($(date -u '+%H:%M:%S UTC'), $((SECONDS - START)) s in all)"
  echo "$DEVICE"
  grep -h '^SUMMARY' "$OUT"/cold1.log "$OUT"/cold2.log "$OUT"/grid.log "$OUT"/check.log "$OUT"/grid_k8.log \
    "$OUT"/whole.log 2>/dev/null | sed 's/^SUMMARY /- /'
  grep -h '^| [0-9]' "$OUT"/whole.log 2>/dev/null | tail -n 1 \
    | awk -F'|' '{print "- whole grid, last batch row: cases so far, wall so far:" $(NF-1)}'
  grep -h -E 'passed|failed|error' "$OUT"/tests.log 2>/dev/null | tail -n 1 | sed 's/^/- tests: /'
  grep -h -i 'warning.*fused\|fused kernel' "$OUT"/*.log 2>/dev/null | sort -u | head -n 5 | sed 's/^/- /'
  echo "| part | status |"
  echo "|---|---|"
  for s in "${STATUS[@]}"; do echo "| ${s%%:*} | ${s#*: } |"; done
} > "$OUT/summary.txt"
echo
cat "$OUT/summary.txt"
