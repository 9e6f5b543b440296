#!/usr/bin/env python
"""Projected cost of the paper's contact grid from a stratified sample of its cases.

The paper grid (config/config.yaml, ``contact``) is k_l in {1, 2, 8, 16} x k_s in {32, 64, 128,
256, 512} x five H x 12 seeds = 1200 cases at N = 1024, 30 load steps to p0/E* = 0.005, tol 1e-8.
The sample takes every (k_l, k_s) pair with ``--hurst`` (default 0.2, 0.52, 0.84) and seed 0:
60 cases, each standing for 20 of the grid. Per case it generates the surface as the pipeline does
(:func:`roughcontact.surfaces.synthetic.generate_surface`, not timed) and solves it with
:func:`roughcontact.solver.solve_contact` on ``--backend`` (numpy: one thread; cupy: the GPU), timing
the solve (CPU and wall; on the GPU the solve returns host arrays, so it has synchronised).

Prints one row per case and the projection: the sample's solve time x 1200 / sample size, in CPU
hours (numpy) or wall minutes (cupy). The pipeline adds surface generation and I/O per case
(measured by ``python -m roughcontact.pipeline.runcost``; ~1.3 s CPU per surface at N = 1024).

Usage::

    python benchmarks/bench_paper_grid.py                       # 60 cases, numpy, one thread
    python benchmarks/bench_paper_grid.py --backend cupy        # on a CUDA GPU
    python benchmarks/bench_paper_grid.py --n 256 --limit 4     # a smoke run
"""

from __future__ import annotations

import argparse
import itertools
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

K_L = (1, 2, 8, 16)
K_S = (32, 64, 128, 256, 512)
GRID_CASES = 1200


def sample(hursts, limit=None) -> list[tuple[int, int, float]]:
    """The stratified sample: every (k_l, k_s) pair with each H of ``hursts``, seed 0."""
    cases = list(itertools.product(K_L, K_S, hursts))
    return cases[:limit] if limit else cases


def solve_case(n: int, k_l: int, k_s: int, hurst: float, backend: str, steps: int) -> dict:
    """Generate one surface (untimed) and solve it; times, iterations and the final A/A0."""
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(n, k_l, k_s, hurst, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / steps, 0.005, steps)
    w0, c0 = time.perf_counter(), time.process_time()
    ds = solve_contact(h, loads, tol=1e-8, array_backend=backend)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return {"k_l": k_l, "k_s": k_s, "H": hurst, "wall": wall, "cpu": cpu,
            "iterations": int(ds["iterations"].values.sum()), "converged": bool(ds["converged"].values.all()),
            "area": float(ds["area_fraction"].values[-1])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1024, help="grid points per side (default 1024)")
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--hurst", type=float, nargs="+", default=[0.2, 0.52, 0.84])
    ap.add_argument("--backend", choices=("numpy", "cupy"), default="numpy")
    ap.add_argument("--limit", type=int, help="only the first this many cases (smoke runs)")
    args = ap.parse_args(argv)
    cases = sample(args.hurst, args.limit)
    # units registry, FFT plans (cupy: kernels) made outside the timing
    solve_case(args.n, 16, 32, 0.8, args.backend, 2)
    print(f"# {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load {os.getloadavg()}, "
          f"backend {args.backend}, N = {args.n}, {len(cases)} cases")
    print("| k_l | k_s | H | iterations | converged | A/A0 | CPU [s] | wall [s] |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    rows = []
    for k_l, k_s, hurst in cases:
        r = solve_case(args.n, k_l, k_s, hurst, args.backend, args.steps)
        rows.append(r)
        print(f"| {k_l} | {k_s} | {hurst} | {r['iterations']} | {'yes' if r['converged'] else 'NO'} | "
              f"{r['area']:.4f} | {r['cpu']:.2f} | {r['wall']:.2f} |", flush=True)
    scale = GRID_CASES / len(rows)
    cpu, wall = sum(r["cpu"] for r in rows), sum(r["wall"] for r in rows)
    print(f"\nsample: {len(rows)} cases, {sum(r['iterations'] for r in rows)} iterations, "
          f"{sum(not r['converged'] for r in rows)} with an unconverged step; CPU {cpu:.1f} s, wall {wall:.1f} s")
    print(f"projected grid of {GRID_CASES} cases (solves only): {cpu * scale / 3600:.2f} CPU-hours, "
          f"{wall * scale / 60:.1f} wall minutes; load at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
