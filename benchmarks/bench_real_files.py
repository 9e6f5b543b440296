#!/usr/bin/env python
"""SurfaceTopography's test files through the solver directly: iterations, paths, CPU per file.

Reads each file as the hard-case scene does (unit um, harmonic fill of undefined points, height
detrend; frt-2, opd-1 and sur-2 cropped to their centred squares), solves 30 steps to a mean
pressure of 500 (E* = 1e5, free boundary, tol 1e-8) on one thread and prints one line per file:
grid, steps converged, iterations, the paths that ended the steps, the solve's CPU seconds and A/A0
at the last step. Without Snakemake or a peer: for the scene with ContactMechanics beside it, see
``benchmarks/hardcases/``. Compare two commits by running it on each (``PYTHONPATH=<tree>/src``).

    python benchmarks/bench_real_files.py [--data tests/data/surfacetopography]
"""

from __future__ import annotations

import argparse
import collections
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

FILES = (("frt-2.frt", "crop"), ("mi-1.mi", None), ("opd-1.opd", "crop"), ("sur-2.sur", "crop"), ("x3p-2.x3p", None))


def solve_file(path: Path, crop: str | None) -> str:
    """One file's line: grid, converged steps, iterations, paths, CPU [s], final A/A0."""
    from roughcontact.solver import solve_contact
    from roughcontact.solver.workspace import SOLVER_PATHS
    from roughcontact.surfaces.topography import read_topography

    kw = {"non_square": crop} if crop else {}
    s = read_topography(path, unit="um", undefined="harmonic", detrend="height", **kw)
    loads = [500.0 * (k + 1) / 30 for k in range(30)]
    cpu = time.process_time()
    ds = solve_contact(s.heights, loads, e_star=1e5, length=s.length, tol=1e-8, boundary="free")
    cpu = time.process_time() - cpu
    paths = dict(collections.Counter(SOLVER_PATHS[x] for x in ds["solver_path"].values))
    return (f"{path.name} {s.heights.shape} conv {int(ds['converged'].sum())}/30 iters {int(ds['iterations'].sum())} "
            f"paths {paths} cpu {cpu:.1f} A30 {float(ds['area_fraction'][-1]):.6f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = Path(__file__).resolve().parents[1]
    ap.add_argument("--data", type=Path, default=here / "tests" / "data" / "surfacetopography")
    args = ap.parse_args()
    for name, crop in FILES:
        print(solve_file(args.data / name, crop), flush=True)


if __name__ == "__main__":
    main()
