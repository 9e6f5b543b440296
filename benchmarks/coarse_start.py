#!/usr/bin/env python
"""A coarse-to-fine start against the uniform one: one load step, measured side by side.

Issue 29 asked to try a coarse-to-fine start (solve on a coarsened grid, prolong the pressure as
the fine solve's start). This measures it through the public API: the step is solved on every
second node (``h[::2, ::2]``, itself started from its own coarse grid down to ``--coarsest``
nodes a side), the pressure prolonged bilinearly (periodic) and handed to the fine solve as
``initial_pressure``; the row compares that, coarse solves included, with the uniform start.
The CPU column is the best of ``--rounds`` interleaved runs, one thread. Results and the
decision (not adopted): docs/solver.md, "coarse-to-fine start".

    python benchmarks/coarse_start.py [--n 1024 2048 4096] [--rounds 2] [--coarsest 128]
"""

from __future__ import annotations

import argparse
import os
import resource

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

LOADS = (0.005 / 30, 0.005)  # p0 / E*: the paper case's first step and its last (A/A0 ~ 0.4 % and ~ 12 %)


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def prolong(p: np.ndarray) -> np.ndarray:
    """Bilinear, periodic: ``p`` on the nodes ``(2i, 2j)`` of a grid twice its size, the others their means."""
    q = np.empty((2 * p.shape[0], p.shape[1]))
    q[::2] = p
    q[1::2] = 0.5 * (p + np.roll(p, -1, axis=0))
    out = np.empty((q.shape[0], 2 * p.shape[1]))
    out[:, ::2] = q
    out[:, 1::2] = 0.5 * (q + np.roll(q, -1, axis=1))
    return out


def coarse_start(h: np.ndarray, p0: float, coarsest: int) -> tuple[np.ndarray | None, int]:
    """``(start, coarse iterations)`` for ``h`` at ``p0``: None (uniform) below ``2 coarsest`` a side."""
    from roughcontact.solver import solve_step

    if h.shape[0] < 2 * coarsest:
        return None, 0
    hc = np.ascontiguousarray(h[::2, ::2])
    init, its = coarse_start(hc, p0, coarsest)
    step = solve_step(hc, p0, initial_pressure=init)
    return prolong(step.pressure), its + step.iterations


def row(n: int, k_l: float, k_s: float, hurst: float, p0: float, rounds: int, coarsest: int) -> str:
    """One table row: iterations, best CPU of each start, their ratio, equal A/A0, all converged."""
    from roughcontact.solver import solve_step
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(n, k_l, k_s, hurst, 0, rms_slope=0.1)
    runs = {"uniform": [], "coarse": []}
    for _ in range(rounds):
        for kind in runs:
            t = cpu()
            init, coarse_its = coarse_start(h, p0, coarsest) if kind == "coarse" else (None, 0)
            step = solve_step(h, p0, initial_pressure=init)
            runs[kind].append((cpu() - t, step.iterations, coarse_its, step.area_fraction, step.converged))
    u, c = runs["uniform"], runs["coarse"]
    tu, tc = min(x[0] for x in u), min(x[0] for x in c)
    return (f"| {n} | {k_l:g}, {k_s:g}, {hurst:g} | {p0:.3g} | {u[0][3]:.4f} | {u[0][1]} | {c[0][1]} + {c[0][2]} | "
            f"{tu:.2f} | {tc:.2f} | {tc / tu:.2f} | {u[0][3] == c[0][3]} | {all(x[4] for x in u + c)} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--coarsest", type=int, default=128, help="smallest coarse side solved [nodes]")
    args = ap.parse_args(argv)
    from roughcontact.solver import solve_step

    print("| N | k_l, k_s, H | p0/E* | A/A0 | its uniform | its coarse (fine + coarse) | CPU uniform [s] "
          "| CPU coarse [s] | coarse / uniform | same A/A0 | all converged |")
    print("|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---|")
    for n in args.n:
        for k_l, k_s, hurst in ((16, 32 * max(1, n // 1024), 0.8), (1, n // 2, 0.52)):
            solve_step(np.zeros((n, n)) + np.eye(n), 0.001)  # plans and start-up outside the timings
            for p0 in LOADS:
                print(row(n, k_l, k_s, hurst, p0, args.rounds, args.coarsest), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
