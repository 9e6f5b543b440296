#!/usr/bin/env python
"""One paper case in a fresh process: the first (cold) and the second (warm) solve, batched and single.

The paper case of ``bench_solver.py`` (``generate_surface(N, 16, 32, 0.8, 0, rms_slope=0.1)``, 30
load steps to p0/E* = 0.005, tol 1e-8) is solved four times in this order, each timed by wall clock
(the solve returns host arrays, so the GPU has finished):

1. ``solve_contact_batch`` of the case alone (B = 1): the process's first solve, which pays for
   CUDA's start, cuFFT's plans and every kernel's compilation or its load from the disk cache
   (``CUPY_CACHE_DIR``);
2. the same again: the warm batched solve;
3. ``solve_contact`` (the single-case path of issue 29) once, and
4. again: its warm solve.

The process's wall time from its start to the end of the first solve is the "cold" figure of
issue 48 (imports included). Run it twice in fresh processes to see the first with an empty and
then a filled kernel cache (benchmarks/gpu/run.sh). Lines starting with ``SUMMARY`` go into the
run's summary table.

Usage::

    python benchmarks/gpu/single_case.py --backend cupy [--n 1024] [--steps 30] [--label cold]
"""

from __future__ import annotations

import time

T0 = time.perf_counter()

import argparse  # noqa: E402
import os  # noqa: E402

os.environ.setdefault("OMP_NUM_THREADS", "1")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--backend", choices=("numpy", "cupy"), default="cupy")
    ap.add_argument("--n", type=int, default=1024)
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--check-every", type=int, help="rounds between host checks of the batch (default: backend's)")
    ap.add_argument("--label", default="run", help="names this process's lines in the summary")
    args = ap.parse_args(argv)

    import numpy as np

    from roughcontact.solver import solve_contact
    from roughcontact.solver.batch import solve_contact_batch
    from roughcontact.surfaces.synthetic import generate_surface

    t_import = time.perf_counter() - T0
    print(f"{args.label}: imports {t_import:.2f} s; CUPY_CACHE_DIR={os.environ.get('CUPY_CACHE_DIR', '(unset)')}, "
          f"cache files before: {_cache_files()}", flush=True)
    h = generate_surface(args.n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / args.steps, 0.005, args.steps)
    results = {}

    def timed(name, fn):
        t = time.perf_counter()
        ds = fn()
        wall = time.perf_counter() - t
        its = ds["iterations"].values
        results[name] = (wall, int(its.sum()), bool(ds["converged"].values.all()),
                         float(np.ravel(ds["area_fraction"].values)[-1]))
        since_start = time.perf_counter() - T0
        print(f"{args.label}: {name}: {wall:.3f} s wall, {int(its.sum())} iterations "
              f"({1e3 * wall / max(int(its.sum()), 1):.2f} ms each), converged {results[name][2]}, final A/A0 "
              f"{results[name][3]:.6f}; {since_start:.2f} s since the process started", flush=True)
        return since_start

    opts = {"tol": 1e-8, "array_backend": args.backend}
    first = timed("batch B=1 first", lambda: solve_contact_batch(h[None], loads, check_every=args.check_every,
                                                                  **opts))
    timed("batch B=1 warm", lambda: solve_contact_batch(h[None], loads, check_every=args.check_every, **opts))
    timed("single first", lambda: solve_contact(h, loads, **opts))
    timed("single warm", lambda: solve_contact(h, loads, **opts))
    dA = abs(results["batch B=1 warm"][3] - results["single warm"][3])
    print(f"SUMMARY {args.label}: process start to the end of its first solve {first:.2f} s (imports "
          f"{t_import:.2f} s, solve {results['batch B=1 first'][0]:.2f} s); warm batched B=1 "
          f"{results['batch B=1 warm'][0]:.3f} s ({results['batch B=1 warm'][1]} it); first single "
          f"{results['single first'][0]:.2f} s, warm single {results['single warm'][0]:.3f} s "
          f"({results['single warm'][1]} it); |dA/A0| batch - single at the last step {dA:.2g}; kernel cache "
          f"files after {_cache_files()}", flush=True)
    return 0


def _cache_files() -> int:
    """Files in CuPy's kernel cache directory (0 when absent)."""
    path = os.environ.get("CUPY_CACHE_DIR")
    if not path or not os.path.isdir(path):
        return 0
    return sum(len(files) for _, _, files in os.walk(path))


if __name__ == "__main__":
    raise SystemExit(main())
