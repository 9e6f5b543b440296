#!/usr/bin/env bash
# Strong and weak scaling of the MPI solver on this machine's cores, its cost against the single solve,
# and the memory per rank at N = 8192 (benchmarks/README.md, "The solver over MPI ranks"; 2026-11-28:
# about 35 min on 2 busy cores, 10 GiB at the peak). Usage: bash benchmarks/mpi/run_scaling.sh OUT.txt
set -euo pipefail
out=${1:-scaling.txt}
bin=$(dirname "$(command -v python)")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
s=benchmarks/mpi/scaling.py
{
  date -u; uptime; nproc; free -g | head -2
  for n in 1024 2048; do
    python $s --make "$n" "$tmp/h$n.npy"
    for r in 1 2; do "$bin/mpiexec" -n "$r" python $s "$tmp/h$n.npy" 4; done
    # weak: the cell tiled twice along x on 2 ranks (the same work per rank as 1 rank on N x N)
    "$bin/mpiexec" -n 2 python $s "$tmp/h$n.npy" 4 --tile 2
    python $s --single "$tmp/h$n.npy" 4   # solve_contact and the batched solver, no MPI
    uptime
  done
  # memory: every field is allocated within a step's first iterations; from the third step on the warm
  # start holds the last two solutions too
  python $s --make 8192 "$tmp/h8192.npy"
  for r in 1 2; do "$bin/mpiexec" -n "$r" python $s "$tmp/h8192.npy" 1 --max-iter 4; uptime; done
  "$bin/mpiexec" -n 2 python $s "$tmp/h8192.npy" 3 --max-iter 4
  date -u; uptime
} 2>&1 | tee "$out"
