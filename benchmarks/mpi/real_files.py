#!/usr/bin/env python
"""Real instrument files through the iterations of issue 63: single solve, batched (B = 1) and MPI ranks.

SurfaceTopography's example files (tests/data/surfacetopography, ``bench_real_files.py``'s list and reading:
µm, undefined points filled harmonically, detrended, cropped where it crops) solved on the periodic
half-space, E* = 1e5, 30 equal load steps to a mean pressure of 500, tol 1e-8, three ways: ``solve_contact``
(the single solve), ``solve_contact_batch`` on ``h[None]`` (the fused host kernels) and
``mpiexec -n R python -m roughcontact.solver.mpi`` (each rank its slab; the float64 fallback over ranks). One
line per file and solver: converged steps, iterations, the paths that ended the steps, CPU and the last A/A0;
then the largest difference of A/A0 from the single solve's, in nodes, over the steps.

    OMP_NUM_THREADS=1 python benchmarks/mpi/real_files.py [--ranks 2]
"""

from __future__ import annotations

import argparse
import collections
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

E_STAR, P_MAX, STEPS = 1e5, 500.0, 30


def line(name: str, solver: str, ds, cpu: float) -> str:
    from roughcontact.solver.workspace import SOLVER_PATHS

    conv = np.asarray(ds["converged"]).reshape(-1)
    paths = dict(collections.Counter(SOLVER_PATHS[x] for x in np.asarray(ds["solver_path"]).reshape(-1)))
    return (f"{name} {solver}: conv {int(conv.sum())}/{conv.size} iters {int(np.sum(ds['iterations']))} "
            f"paths {paths} cpu {cpu:.1f} A30 {float(np.asarray(ds['area_fraction']).reshape(-1)[-1]):.6f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=HERE.parents[1] / "tests" / "data" / "surfacetopography")
    ap.add_argument("--ranks", type=int, default=2)
    a = ap.parse_args()
    import xarray as xr
    from bench_real_files import FILES

    from roughcontact.solver import solve_contact, solve_contact_batch
    from roughcontact.surfaces.topography import read_topography

    loads = [P_MAX * (k + 1) / STEPS for k in range(STEPS)]
    mpiexec = Path(sys.executable).parent / "mpiexec"
    for name, crop in FILES:
        s = read_topography(a.data / name, unit="um", undefined="harmonic", detrend="height",
                            **({"non_square": crop} if crop else {}))
        h, n = s.heights, s.heights.size
        kw = {"e_star": E_STAR, "length": s.length, "tol": 1e-8}
        areas = {}
        for solver, fn, heights in (("single", solve_contact, h), ("batched", solve_contact_batch, h[None])):
            c = time.process_time()
            ds = fn(heights, loads, **kw)
            print(line(name, solver, ds, time.process_time() - c), flush=True)
            areas[solver] = np.asarray(ds["area_fraction"]).reshape(-1)
        with tempfile.TemporaryDirectory() as tmp:
            src, out = Path(tmp) / "h.nc", Path(tmp) / "c.nc"
            lx, ly = (s.length, s.length) if np.isscalar(s.length) else s.length
            xr.Dataset({"heights": (("x", "y"), h)}).to_netcdf(src)
            cmd = [str(mpiexec), "-n", str(a.ranks), sys.executable, "-m", "roughcontact.solver.mpi", "--surface",
                   str(src), "--length", repr(float(lx)), "--length-y", repr(float(ly)), "--e-star", repr(E_STAR),
                   "--loads", *map(repr, loads), "--out", str(out)]
            t = time.perf_counter()
            res = subprocess.run(cmd, capture_output=True, text=True)
            if res.returncode:
                print(f"{name} mpi-{a.ranks}: failed: {res.stderr.strip().splitlines()[-1]}", flush=True)
                continue
            with xr.open_dataset(out) as ds:
                ds = ds.load()
            print(line(name, f"mpi-{a.ranks}", ds, a.ranks * (time.perf_counter() - t)) + " (cpu: ranks x wall)",
                  flush=True)
            areas[f"mpi-{a.ranks}"] = np.asarray(ds["area_fraction"]).reshape(-1)
        for solver in list(areas)[1:]:
            print(f"{name} {solver}: A/A0 apart from the single solve, at most "
                  f"{int(round(np.max(np.abs(areas[solver] - areas['single'])) * n))} nodes", flush=True)


if __name__ == "__main__":
    main()
