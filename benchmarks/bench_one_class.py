#!/usr/bin/env python
"""The single solve on the one iteration class against the single solve before it, in one process (issue 63).

Since 2026-12-03 ``solve_contact``'s default iteration (``pk-fourier-f32``) is
:class:`roughcontact.solver.iteration.BatchIteration` with
:class:`~roughcontact.solver.compressed.CompressedKernels` (B = 1); before, it was ``PKIteration``'s own loop. This
script extracts the package of an earlier commit (``--before``, default 8f8d00a, the last with the former loop) with
``git archive`` into a temporary folder under another name (``rc_before``: its imports are relative), and solves the
paper case of ``bench_solver.py`` (k_l = 16, k_s = 32, H = 0.8, rms slope 0.1, seed 0; ``--steps`` loads to
p0/E* = 0.005, tol 1e-8) with both, interleaved after a warm-up each (the earlier commit first in each repeat),
single-threaded (``OMP_NUM_THREADS=1``):

- the outputs of the warm-up solves are compared variable by variable, by their bytes (every variable but the wall
  time, with every step's pressure and gap fields stored);
- the CPU (``process_time``) of the iterations alone (``pk_solve``'s calls from ``solver.steps``, which runs a
  rough surface's every step since 2026-12-03, from ``solver.contact`` before: the loop with its per-step set-up,
  the float32 products planned before the timer) and of the whole ``solve_contact`` call (the products
  planned once per process since 2026-12-03, each solve before), the least and the median of ``--repeats``, and
  the ratios after / before: of the least, and the median of the ratios paired within a repeat.

The header gives the UTC date and ``os.getloadavg()`` at the start; the last line the time and load at the end.

    OMP_NUM_THREADS=1 python benchmarks/bench_one_class.py [--n 64 128 256 512] [--steps 30] [--repeats 9]
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import io
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def before_package(commit: str, where: Path):
    """The ``roughcontact`` package of ``commit``, importable as ``rc_before`` (extracted under ``where``)."""
    blob = subprocess.run(["git", "-C", str(REPO), "archive", commit, "src/roughcontact"], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        tar.extractall(where, filter="data")
    (where / "src" / "roughcontact").rename(where / "rc_before")
    sys.path.insert(0, str(where))
    return importlib.import_module("rc_before")


def _same_bytes(a, b) -> bool:
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def one_size(packages: dict, n: int, steps: int, repeats: int) -> str:
    """The table row of one grid size."""
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / steps, 0.005, steps)
    spent = [0.0]
    solvers = {}
    for name, pkg in packages.items():
        # the module whose pk_solve the single solve calls: solver.steps since 2026-12-03 (its run_path), before
        # solver.contact
        try:
            caller = importlib.import_module(f"{pkg.__name__}.solver.steps")
        except ModuleNotFoundError:
            caller = importlib.import_module(f"{pkg.__name__}.solver.contact")
        solve = importlib.import_module(f"{pkg.__name__}.solver").solve_contact

        def timed(ws, *args, _real=caller.pk_solve):
            ws.setup_method()  # the float32 products made (planned) untimed: not the iteration's cost
            c0 = time.process_time()
            try:
                return _real(ws, *args)
            finally:
                spent[0] += time.process_time() - c0

        caller.pk_solve = timed
        solvers[name] = solve
    first = {name: solve(h, loads, store_fields=True) for name, solve in solvers.items()}
    names = [k for k in first["before"].data_vars if k != "wall_time"]
    differ = [k for k in names if not _same_bytes(first["before"][k].values, first["after"][k].values)]
    its = int(first["after"].iterations.sum())
    cpu_it = {name: [] for name in solvers}
    cpu_all = {name: [] for name in solvers}
    for _ in range(repeats):
        for name, solve in solvers.items():
            spent[0] = 0.0
            c0 = time.process_time()
            solve(h, loads)
            cpu_all[name].append(time.process_time() - c0)
            cpu_it[name].append(spent[0])

    def ratios(x):
        b, a = x["before"], x["after"]
        return min(a) / min(b), statistics.median(y / z for y, z in zip(a, b, strict=True))

    ri, ra = ratios(cpu_it), ratios(cpu_all)
    return (f"| {n}² | {its} | {'all ' + str(len(names)) if not differ else 'differ: ' + ', '.join(differ)} | "
            f"{1e3 * min(cpu_it['before']) / its:.4f} | {1e3 * min(cpu_it['after']) / its:.4f} | {ri[0]:.3f} | "
            f"{ri[1]:.3f} | {min(cpu_all['before']):.4f} | {min(cpu_all['after']):.4f} | {ra[0]:.3f} | {ra[1]:.3f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--n", type=int, nargs="+", default=[64, 128, 256, 512])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--before", default="8f8d00a", help="the commit whose single solve is the reference")
    a = ap.parse_args(argv)
    import roughcontact

    with tempfile.TemporaryDirectory() as tmp:
        packages = {"before": before_package(a.before, Path(tmp)), "after": roughcontact}
        print(f"bench_one_class {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, before = {a.before}, "
              f"{a.steps} steps, least and median of {a.repeats}, load {os.getloadavg()[0]:.2f}")
        print("| N | iterations | bytes equal | before ms/iter | after ms/iter | iterations after/before, least | "
              "paired median | before solve CPU s | after solve CPU s | solve after/before, least | paired median |")
        print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        rows = [one_size(packages, n, a.steps, a.repeats) for n in a.n]
        for row in rows:
            print(row, flush=True)
    print(f"ended {datetime.datetime.now(datetime.UTC):%H:%M} UTC, load {os.getloadavg()[0]:.2f}")
    return 0 if all("differ" not in r for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
