#!/usr/bin/env python
"""The batched iteration on one case (B = 1) beside the single solve and Tamaas, in one process (issue 63).

The paper case of ``bench_solver.py`` (k_l = 16, k_s = 32, H = 0.8, rms slope 0.1, seed 0, ``--steps``
equal loads to p0/E* = ``--p-max``, tol 1e-8), single-threaded (``OMP_NUM_THREADS=1``), solved by

- ``single``: :func:`roughcontact.solver.solve_contact` on the map (compressed sets: ``PKIteration`` before
  2026-12-03, since then ``BatchIteration`` with :class:`~roughcontact.solver.compressed.CompressedKernels`);
- ``batched``: :func:`roughcontact.solver.solve_contact_batch` on ``h[None]`` (the batched iteration with the
  fused CPU kernels of ``solver/batch/cpu.py``, B = 1): the iteration the MPI solver runs on each rank;
- ``batched-apart`` (``--apart``): the same with the batches' out-of-place float32 transforms, not one case's
  in-place ones (the A/B of ``BatchFFT``'s in-place plans);
- ``tamaas``: Tamaas' ``PolonskyKeerRey`` (``bench_solver.run_tamaas``), once (its cold start costs it most).

Ours run ``--repeats`` times each, interleaved (``single, batched, single, ...``) after one warm-up each (the
numba kernels' load from their cache and the FFT plans), so that load drift hits both alike; the table gives
the least and the median CPU (``process_time``) and wall (``perf_counter``) seconds, the iterations, CPU
milliseconds per iteration, and the ratios. The header line says the UTC date and ``os.getloadavg()`` at the
start and the end.

    OMP_NUM_THREADS=1 python benchmarks/bench_one_iteration.py [--n 1024] [--steps 30] [--repeats 3]
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))


def timed(fn):
    """``(cpu, wall, dataset)`` of one call."""
    w0, c0 = time.perf_counter(), time.process_time()
    ds = fn()
    return time.process_time() - c0, time.perf_counter() - w0, ds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1024)
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--p-max", type=float, default=0.005)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-tamaas", action="store_true")
    ap.add_argument("--batch", type=int, default=1,
                    help="the batched rows solve B copies of the map at once; their CPU is then given per case "
                         "(the total divided by B), so that the ratio is a case's cost in a batch against the "
                         "single solve's")
    ap.add_argument("--apart", action="store_true",
                    help="add the row 'batched-apart': B = 1 with the batches' out-of-place transforms instead of "
                         "one case's in-place ones (the A/B of solver/batch/halfspace.py's in-place plans)")
    a = ap.parse_args(argv)
    from bench_solver import run_tamaas

    from roughcontact.solver import solve_contact, solve_contact_batch
    from roughcontact.surfaces.synthetic import generate_surface

    load0 = os.getloadavg()
    h = generate_surface(a.n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(a.p_max / a.steps, a.p_max, a.steps)
    hb = np.repeat(h[None], a.batch, axis=0)
    ours = {"single": lambda: solve_contact(h, loads), "batched": lambda: solve_contact_batch(hb, loads)}
    if a.apart:
        from roughcontact.solver.batch import halfspace

        def apart():
            shipped = halfspace.fft_module.has_shipped_plans
            halfspace.fft_module.has_shipped_plans = lambda shape: False  # BatchFFT plans out of place
            try:
                return solve_contact_batch(hb, loads)
            finally:
                halfspace.fft_module.has_shipped_plans = shipped

        ours["batched-apart"] = apart
    for fn in ours.values():
        fn()  # warm-up: plans, the kernels' cache
    runs = {k: [] for k in ours}
    for _ in range(a.repeats):
        for name, fn in ours.items():
            runs[name].append(timed(fn))
    tamaas = None if a.no_tamaas else run_tamaas(h, loads, 1e-8)
    load1 = os.getloadavg()
    print(f"bench_one_iteration {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, N = {a.n}, "
          f"{a.steps} steps to {a.p_max}, repeats {a.repeats}, B = {a.batch} (batched rows: CPU and wall per case), "
          f"load {load0[0]:.2f} -> {load1[0]:.2f}")
    rows = []
    for name, rs in runs.items():
        per = a.batch if name != "single" else 1  # a batch's cost per case
        its = int(rs[0][2].iterations.sum()) // per
        conv = all(bool(r[2].converged.all()) for r in rs)
        area = float(np.asarray(rs[0][2].area_fraction).reshape(-1)[-1])
        cpu = [r[0] / per for r in rs]
        wall = [r[1] / per for r in rs]
        rows.append((name, min(cpu), statistics.median(cpu), min(wall), its, conv, area))
    if tamaas is not None:
        rows.append(("tamaas", tamaas["cpu"], tamaas["cpu"], tamaas["wall"], int(sum(tamaas["iterations"])), True,
                     tamaas["area"][-1]))
    print("| solver | CPU [s] least | CPU [s] median | wall [s] least | iterations | CPU ms/iter | converged | "
          "A/A0 last | Tamaas CPU / ours |")
    print("|---|---|---|---|---|---|---|---|---|")
    t_cpu = tamaas["cpu"] if tamaas else None
    for name, cmin, cmed, wmin, its, conv, area in rows:
        ratio = f"{t_cpu / cmin:.1f}x" if t_cpu and name != "tamaas" else ""
        print(f"| {name} | {cmin:.2f} | {cmed:.2f} | {wmin:.2f} | {its} | {1e3 * cmin / its:.2f} | {conv} | "
              f"{area:.6f} | {ratio} |")
    single = rows[0]
    for row in rows[1:]:
        if row[0] != "tamaas":
            print(f"{row[0]} / single CPU (least): {row[1] / single[1]:.3f}; per iteration: "
                  f"{(row[1] / row[4]) / (single[1] / single[4]):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
