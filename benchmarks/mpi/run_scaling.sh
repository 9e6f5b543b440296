#!/usr/bin/env bash
# Strong and weak scaling of the MPI solver on this machine's cores, and the memory per rank at
# N = 8192 (benchmarks/README.md, "The solver over MPI ranks"). Usage: bash benchmarks/mpi/run_scaling.sh OUT.txt
set -euo pipefail
out=${1:-scaling.txt}
bin=$(dirname "$(command -v python)")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
{
  date -u; uptime; nproc; free -g | head -2
  for n in 1024 2048; do
    python benchmarks/mpi/scaling.py --make "$n" "$tmp/h$n.npy"
    for r in 1 2; do "$bin/mpiexec" -n "$r" python benchmarks/mpi/scaling.py "$tmp/h$n.npy" 4; done
    # weak: the cell tiled twice along x on 2 ranks (the same work per rank as 1 rank on N x N)
    "$bin/mpiexec" -n 2 python benchmarks/mpi/scaling.py "$tmp/h$n.npy" 4 --tile 2
    uptime
  done
  python benchmarks/mpi/scaling.py --make 8192 "$tmp/h8192.npy"
  for r in 1 2; do "$bin/mpiexec" -n "$r" python benchmarks/mpi/scaling.py "$tmp/h8192.npy" 1 --max-iter 4; uptime; done
} 2>&1 | tee "$out"
