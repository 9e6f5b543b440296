#!/usr/bin/env python
"""A round's passes as one compiled call each, against the kernels one at a time, beside the single solve (issue 63).

The batched iteration (:class:`roughcontact.solver.iteration.BatchIteration`) runs a round as five passes
between its transforms (``measure``, ``join``, ``direction``, ``trial``, ``settle`` of
:class:`~roughcontact.solver.batch.kernels.ArrayKernels`). On the host
(:class:`~roughcontact.solver.batch.cpu.FusedCpuKernels`) each is one compiled call; ``ArrayKernels`` composes
the same fused kernels one at a time (about 25 calls a round, as the MPI ranks run them and as 4474440 did). On a
small grid those calls' own cost is much of a round. Three solvers, interleaved in one process after a warm-up
each, on the paper case of ``bench_solver.py`` (k_l = 16, k_s = 32, H = 0.8, rms slope 0.1, seed 0; ``--steps``
loads to p0/E* = 0.005, tol 1e-8), single-threaded (``OMP_NUM_THREADS=1``):

- ``single``: :func:`roughcontact.solver.solve_contact` (``PKIteration`` before 2026-12-03; since, ``BatchIteration``
  with :class:`~roughcontact.solver.compressed.CompressedKernels`);
- ``composed``: :func:`roughcontact.solver.solve_contact_batch` on ``h[None]`` (B = 1), the passes compiled whole;
- ``apart``: the same with ``FusedCpuKernels``' five passes replaced by ``ArrayKernels``' compositions.

Per solver: the CPU (``process_time``) of the iterations alone (``BatchIteration.run``; ``PKIteration.run`` before
2026-12-03: what one iteration class must match) and of the whole call (with the set-up, the per-step checks and the
dataset), the least and the median of ``--repeats``; then the ratios to ``single``: of the least, and the median
of the ratios paired within a repeat. The outputs of ``composed`` and ``apart`` are checked to be equal (the
same arithmetic). The header gives the UTC date and ``os.getloadavg()`` at the start and the end.

    OMP_NUM_THREADS=1 python benchmarks/bench_round_passes.py [--n 64 128 256] [--steps 10] [--repeats 15]
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

PASSES = ("measure", "join", "direction", "trial", "settle")


def one_size(n: int, steps: int, repeats: int) -> list[str]:
    """The table rows of one grid size."""
    from roughcontact.solver import iteration, solve_contact, solve_contact_batch
    from roughcontact.solver.batch import cpu
    from roughcontact.solver.batch.kernels import ArrayKernels
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / steps, 0.005, steps)
    spent = [0.0]
    runs = {}
    for cls in (iteration.BatchIteration,):
        runs[cls] = cls.run

        def timed_run(self, *args, _run=runs[cls]):
            c0 = time.process_time()
            try:
                return _run(self, *args)
            finally:
                spent[0] += time.process_time() - c0

        cls.run = timed_run
    fused = {name: getattr(cpu.FusedCpuKernels, name) for name in PASSES}

    def passes(whole: bool):
        for name in PASSES:
            setattr(cpu.FusedCpuKernels, name, fused[name] if whole else getattr(ArrayKernels, name))

    def composed():
        passes(True)
        return solve_contact_batch(h[None], loads)

    def apart():
        passes(False)
        return solve_contact_batch(h[None], loads)

    solvers = {"single": lambda: solve_contact(h, loads), "composed": composed, "apart": apart}
    try:
        first = {name: fn() for name, fn in solvers.items()}  # warm-up: plans, the kernels' cache
        for name in first["apart"].data_vars:
            if name != "wall_time":
                np.testing.assert_array_equal(first["composed"][name].values, first["apart"][name].values,
                                              err_msg=name)
        its = {name: int(ds.iterations.sum()) for name, ds in first.items()}
        cpu_it = {name: [] for name in solvers}
        cpu_all = {name: [] for name in solvers}
        for _ in range(repeats):
            for name, fn in solvers.items():
                spent[0] = 0.0
                c0 = time.process_time()
                fn()
                cpu_all[name].append(time.process_time() - c0)
                cpu_it[name].append(spent[0])
    finally:
        passes(True)
        for cls, run in runs.items():
            cls.run = run
    rows = []
    for name in solvers:
        it, whole = cpu_it[name], cpu_all[name]
        if name == "single":
            ratios = "|  |  |  |"
        else:
            paired = statistics.median(a / b for a, b in zip(it, cpu_it["single"], strict=True))
            ratios = (f"| {min(it) / min(cpu_it['single']):.3f} | {paired:.3f} | "
                      f"{min(whole) / min(cpu_all['single']):.3f} |")
        rows.append(f"| {n}² | {name} | {its[name]} | {1e3 * min(it) / its[name]:.4f} | "
                    f"{1e3 * statistics.median(it) / its[name]:.4f} | {min(whole):.4f} | "
                    f"{statistics.median(whole):.4f} {ratios}")
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[64, 128, 256])
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=15)
    a = ap.parse_args(argv)
    load0 = os.getloadavg()
    rows = []
    for n in a.n:
        rows += one_size(n, a.steps, a.repeats)
    load1 = os.getloadavg()
    print(f"bench_round_passes {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, {a.steps} steps to 0.005, "
          f"repeats {a.repeats}, one thread, load {load0[0]:.2f} -> {load1[0]:.2f}")
    print("| N | solver | iterations | iteration CPU ms/iter, least | median | solve CPU s, least | median | "
          "iteration / single, least | paired median | solve / single, least |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
