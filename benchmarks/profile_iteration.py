#!/usr/bin/env python
"""Where an iteration's CPU goes: per-call CPU timers around the elastic iteration's parts.

Wraps the methods of :class:`roughcontact.solver.elastic.PKIteration`, the float32 transforms of
:class:`roughcontact.core.backend.SpectralProduct` (forward, spectrum product, backward), its
Parseval sum, the sparse loads and read-backs and the float64 products, solves the benchmark's
paper case (k_l 16, k_s 32, H 0.8, rms slope 0.1, 30 steps to p0/E* = 0.005, tol 1e-8) on one
thread and prints each part's CPU seconds, share of the solve, calls and ms per iteration.
Method rows include the transform rows indented below them. The timers add a few microseconds a
call; compare shares, not the solve's total with the benchmark's.

    python benchmarks/profile_iteration.py [--n 1024]
"""

from __future__ import annotations

import argparse
import collections
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

CPU = time.process_time
METHODS = ("_measure", "_direction", "_step_single", "_project_single", "_join", "_resync", "_finish", "_project")


def instrument(acc: collections.Counter, calls: collections.Counter) -> None:
    """Wrap the iteration's methods and the transforms with CPU timers adding into ``acc``."""
    import roughcontact.core.backend as be
    import roughcontact.solver.elastic as el
    import roughcontact.solver.halfspace as hs

    def wrap(cls, name, key):
        f = getattr(cls, name)

        def timed(*a, **k):
            t = CPU()
            out = f(*a, **k)
            acc[key] += CPU() - t
            calls[key] += 1
            return out
        setattr(cls, name, timed)

    for name in METHODS:
        wrap(el.PKIteration, name, name)

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1024)
    args = ap.parse_args()
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    acc, calls = collections.Counter(), collections.Counter()
    instrument(acc, calls)
    h = generate_surface(args.n, 16, 32, 0.8, 0, rms_slope=0.1)
    t = CPU()
    ds = solve_contact(h, np.linspace(0.005 / 30, 0.005, 30), tol=1e-8)
    cpu = CPU() - t
    its = int(ds["iterations"].values.sum())
    print(f"N = {args.n}: solve CPU {cpu:.2f} s, {its} iterations, {1e3 * cpu / its:.2f} ms an iteration, "
          f"load {os.getloadavg()[0]:.2f}")
    for key in sorted(acc, key=lambda k: -acc[k]):
        print(f"{key:20s} {acc[key]:7.2f} s {100 * acc[key] / cpu:5.1f} %  calls {calls[key]:6d}  "
              f"{1e3 * acc[key] / its:6.2f} ms/iter")


if __name__ == "__main__":
    main()
