#!/usr/bin/env python
"""Where an iteration's CPU goes: per-call CPU timers around the elastic iteration's parts.

Wraps the passes of the single solve's kernels (:class:`roughcontact.solver.compressed.CompressedKernels`, which
:class:`roughcontact.solver.iteration.BatchIteration` calls for one case), its float64 recomputations, the float32
transforms of
:class:`roughcontact.core.backend.SpectralProduct` (forward, spectrum product, backward), its
Parseval sum, the sparse loads and read-backs and the float64 products, solves the benchmark's
paper case (k_l 16, k_s 32, H 0.8, rms slope 0.1, 30 steps to p0/E* = 0.005, tol 1e-8) on one
thread and prints each part's CPU seconds, share of the solve, calls and ms per iteration.
Method rows include the transform rows indented below them. The timers add a few microseconds a
call; compare shares, not the solve's total with the benchmark's.

    python benchmarks/profile_iteration.py [--n 1024]

``--batched plain|fused`` profiles the batched iteration on the same case (B = 1) instead: each kernel
method of its kernels (``plain``: :class:`roughcontact.solver.batch.kernels.ArrayKernels`, numpy
expressions; ``fused``: :class:`roughcontact.solver.batch.cpu.FusedCpuKernels`, numba loops over the free
set's indices), the batched transforms and the warm start, so that the options compare side by side
(benchmarks/README.md, "One iteration code"). A kernel that calls another is counted in both: the plain
kernels' round passes (``measure``, ``join``, ``direction``, ``trial``, ``settle``) call their other kernels,
where the fused kernels make each pass one compiled call (its row alone).
"""

from __future__ import annotations

import argparse
import collections
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

CPU = time.process_time
METHODS = ("measure", "join", "direction", "trial", "step_on", "project", "settle")


def timer(acc: collections.Counter, calls: collections.Counter, owner, name: str, key: str) -> None:
    """Replace ``owner.name`` by the same callable adding its CPU seconds into ``acc[key]`` and its calls into
    ``calls[key]``."""
    f = getattr(owner, name)

    def timed(*a, **k):
        t = CPU()
        out = f(*a, **k)
        acc[key] += CPU() - t
        calls[key] += 1
        return out
    setattr(owner, name, timed)


def instrument(acc: collections.Counter, calls: collections.Counter) -> None:
    """Wrap the iteration's methods and the transforms with CPU timers adding into ``acc``."""
    import roughcontact.core.backend as be
    import roughcontact.solver.compressed as co
    import roughcontact.solver.halfspace as hs
    import roughcontact.solver.iteration as it

    def wrap(owner, name, key):
        timer(acc, calls, owner, name, key)

    for name in METHODS:
        wrap(co.CompressedKernels, name, name)
    wrap(it.BatchIteration, "resync", "resync")

    def forward(self):
        t = CPU()
        self.fwd.execute()
        acc["  f32 forward"] += CPU() - t
        calls["  f32 forward"] += 1
        return self.spec

    def backward(self, spec, mult):
        t0 = CPU()
        be.multiply_spectrum(spec, mult)
        t1 = CPU()
        self.bwd.execute()
        acc["  spectrum product"] += t1 - t0
        acc["  f32 backward"] += CPU() - t1
        calls["  spectrum product"] += 1
        calls["  f32 backward"] += 1
        return self.out

    be._FFTWProduct.forward, be._FFTWProduct.backward = forward, backward
    wrap(be.SpectralProduct, "quadratic", "  Parseval sum")
    wrap(hs.SparseLoad, "load", "  sparse load")
    wrap(hs.SparseLoad, "take", "  sparse read-back")
    wrap(hs.PeriodicHalfSpace, "apply", "  float64 product")


def instrument_batched(acc: collections.Counter, calls: collections.Counter, kernels: str) -> None:
    """Timers on the batched iteration's kernels (``kernels``: "plain" or "fused"), transforms and start."""
    import roughcontact.solver.batch.halfspace as bo
    import roughcontact.solver.batch.kernels as bk
    import roughcontact.solver.batch.solver as bs
    from roughcontact.solver.batch.cpu import FusedCpuKernels

    cls = FusedCpuKernels if kernels == "fused" else bk.ArrayKernels
    if kernels == "plain":
        bs.FusedCpuKernels = lambda: bk.ArrayKernels(np)  # the solver's kernels on the host: the plain ones

    def wrap(owner, name, key):
        timer(acc, calls, owner, name, key)

    for name in sorted({n for c in cls.__mro__ if c is not object for n in vars(c)}):
        if not name.startswith("_") and callable(getattr(cls, name)) and name not in ("buffer", "free_set"):
            wrap(cls, name, "  " + name)
    wrap(bo.BatchFFT, "rfft2", "forward transform")
    wrap(bo.BatchFFT, "irfft2", "inverse transform")
    wrap(bs.BatchSolver, "start", "warm start")
    wrap(bs.BatchSolver, "refresh", "float64 refresh")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1024)
    ap.add_argument("--batched", choices=("plain", "fused"), default=None,
                    help="profile the batched iteration (B = 1) with these kernels instead of the single solve")
    args = ap.parse_args()
    from roughcontact.solver import solve_contact, solve_contact_batch
    from roughcontact.surfaces.synthetic import generate_surface

    acc, calls = collections.Counter(), collections.Counter()
    h = generate_surface(args.n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / 30, 0.005, 30)
    if args.batched:
        instrument_batched(acc, calls, args.batched)
        solve_contact_batch(h[None], loads[:2], tol=1e-8)  # warm-up: the kernels' cache, the plans
        acc.clear()
        calls.clear()
        t = CPU()
        ds = solve_contact_batch(h[None], loads, tol=1e-8)
    else:
        instrument(acc, calls)
        t = CPU()
        ds = solve_contact(h, loads, tol=1e-8)
    cpu = CPU() - t
    its = int(ds["iterations"].values.sum())
    what = f"batched iteration ({args.batched} kernels)" if args.batched else "single solve"
    print(f"N = {args.n}, {what}: solve CPU {cpu:.2f} s, {its} iterations, {1e3 * cpu / its:.2f} ms an iteration, "
          f"load {os.getloadavg()[0]:.2f}")
    for key in sorted(acc, key=lambda k: -acc[k]):
        print(f"{key:20s} {acc[key]:7.2f} s {100 * acc[key] / cpu:5.1f} %  calls {calls[key]:6d}  "
              f"{1e3 * acc[key] / its:6.2f} ms/iter")


if __name__ == "__main__":
    main()
