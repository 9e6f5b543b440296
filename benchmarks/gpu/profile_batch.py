#!/usr/bin/env python
"""Where a batched round's time goes on the GPU: every kernel method and transform timed, synchronised.

Wraps each method of the batch's kernels object (fused CuPy kernels or plain expressions), its operator
and its FFT object with a device synchronisation before and after, and solves ``--steps`` load steps of
the paper case (N = 1024, k_l = 16, k_s = 32, H = 0.8) for each batch size; prints the methods by total
time, per round and per case-round, and the rounds' wall time without the wrappers for comparison.

    python benchmarks/gpu/profile_batch.py --backend cupy --n 1024 --batch 1 16
    python benchmarks/gpu/profile_batch.py --backend numpy --n 64 --batch 1 4      # a smoke run
"""

from __future__ import annotations

import argparse
import collections
import functools
import time

import numpy as np


def sync(backend):
    if backend == "cupy":
        import cupy

        cupy.cuda.Device().synchronize()


def wrap_class(cls, name, totals, counts, backend):
    """Wrap every public or private method of ``cls`` (not dunders) with a synchronised timer."""
    for attr, fn in list(vars(cls).items()):
        if attr.startswith("__") or not callable(fn):
            continue

        def timed(*args, _fn=fn, _key=f"{name}.{attr}", **kw):
            sync(backend)
            t0 = time.perf_counter()
            out = _fn(*args, **kw)
            sync(backend)
            totals[_key] += time.perf_counter() - t0
            counts[_key] += 1
            return out

        setattr(cls, attr, functools.wraps(fn)(timed))


def run(backend, n, steps, batch, profile):
    from roughcontact.solver.batch import solve_contact_batch
    from roughcontact.surfaces.synthetic import generate_surface

    h = np.stack([generate_surface(n, 16, 32, 0.8, seed, rms_slope=0.1) for seed in range(batch)])
    loads = np.linspace(0.005 / 30, 0.005, 30)[:steps]
    solve_contact_batch(h[:1], loads[:1], array_backend=backend)  # plans, kernels
    sync(backend)
    t0 = time.perf_counter()
    ds = solve_contact_batch(h, loads, array_backend=backend)
    sync(backend)
    wall = time.perf_counter() - t0
    return wall, int(ds["rounds"].sum()), bool(ds["converged"].all())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--backend", default="cupy")
    ap.add_argument("--n", type=int, default=1024)
    ap.add_argument("--steps", type=int, default=2)
    ap.add_argument("--batch", type=int, nargs="+", default=[1, 16])
    ap.add_argument("--no-wrap", action="store_true", help="time whole solves only, no per-method profile")
    args = ap.parse_args()
    if args.backend == "cupy":
        import cupy
        from cupy._core import _accelerator

        print("cupy", cupy.__version__, "reduction accelerators", _accelerator.get_reduction_accelerators(),
              "routine accelerators", _accelerator.get_routine_accelerators(), flush=True)
    for b in args.batch:
        wall, rounds, ok = run(args.backend, args.n, args.steps, b, False)
        print(f"B = {b}: unwrapped {wall:.3f} s, {rounds} rounds, {1e3 * wall / rounds:.3f} ms a round, "
              f"{1e3 * wall / rounds / b:.3f} ms a case-round, converged {ok}", flush=True)
    if args.no_wrap:
        return
    from roughcontact.solver import iteration as batch_iteration
    from roughcontact.solver.batch import (
        cuda as batch_cuda,
        halfspace as batch_halfspace,
        kernels as batch_kernels,
    )

    totals, counts = collections.defaultdict(float), collections.Counter()
    classes = [(batch_kernels.ArrayKernels, "k"), (batch_halfspace.BatchOperator, "op"),
               (batch_halfspace.BatchFFT, "fft")]
    if hasattr(batch_cuda, "CupyKernels"):
        classes.append((batch_cuda.CupyKernels, "cuk"))
    for cls, name in classes:
        wrap_class(cls, name, totals, counts, args.backend)
    wrap_class(batch_iteration.BatchIteration, "it", totals, counts, args.backend)
    for b in args.batch:
        totals.clear()
        counts.clear()
        wall, rounds, ok = run(args.backend, args.n, args.steps, b, True)
        print(f"\nB = {b}, wrapped: {wall:.3f} s, {rounds} rounds; top methods (inclusive; it.* contain the others):")
        for key, t in sorted(totals.items(), key=lambda kv: -kv[1])[:24]:
            print(f"  {key:28s} {t:8.3f} s  {counts[key]:7d} calls  {1e6 * t / max(counts[key], 1):9.1f} us/call  "
                  f"{1e3 * t / rounds:7.3f} ms/round", flush=True)


if __name__ == "__main__":
    main()
