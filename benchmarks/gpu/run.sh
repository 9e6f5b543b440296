#!/usr/bin/env bash
# The GPU checks of issue 29, as one command on a lent CUDA machine (the device tool), from the
# repository root. Wheels the machine lacks (pint and its needs, pyFFTW) travel in .whl/ (pip
# download ... --python-version 3.12, see benchmarks/README.md). Writes its logs under $OUT.
set -u -o pipefail
OUT=${OUT:-/tmp/gpu-out}; mkdir -p "$OUT"
if [ -d .whl ]; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
  export PYTHONPATH=/tmp/site:$PWD/src:$PWD/tests
else
  export PYTHONPATH=$PWD/src:$PWD/tests
fi
export PYTHONUNBUFFERED=1 OMP_NUM_THREADS=1
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$OUT/gpu.txt"
python3 -c "import cupy, numpy; print('cupy', cupy.__version__, 'numpy', numpy.__version__)" | tee -a "$OUT/gpu.txt"
# 1. the paper case on the GPU at 1024 .. 8192 (and the hard-case suite and the backend tests)
timeout 150 python3 benchmarks/bench_solver.py --backend cupy --n 1024 4096 8192 --out "$OUT/bench_gpu.md" 2>&1 | tee "$OUT/bench_gpu.log" | tail -8
ROUGHCONTACT_ARRAY_BACKEND=cupy timeout 100 python3 -m pytest -q -p no:cacheprovider tests/test_hard_case_suite.py \
  tests/test_solver_exact.py tests/test_array_backend.py -k "not measured" 2>&1 | tee "$OUT/suite_gpu.log" | tail -15
# 2. the paper grid's projected cost from its 60-case sample
timeout 210 python3 benchmarks/bench_paper_grid.py --backend cupy 2>&1 | tee "$OUT/grid_gpu.log" | tail -4
