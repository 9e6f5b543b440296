"""The hard-case scene's outcome per file, with ContactMechanics' free-boundary CG as the peer.

For each contact file of a finished scene (``results/{scene}/contact/*.nc``) it reports the grid,
the steps converged, the iterations, the paths that ended the steps (``solver_path``), the largest
residual and the CPU seconds of the job (its Snakemake benchmark file), then solves the chosen load
steps again with ContactMechanics' ``constrained_conjugate_gradients`` on a ``FreeFFTElasticHalfSpace``
(tolerances as the scene's ``tol``: ``pentol = tol * rms height``, ``forcetol = tol * p0 * dx dy``)
and gives the largest relative difference of A/A0 where it converges.

    python benchmarks/hardcases/table.py [--scene hardcases] [--steps 1,10,20,30 | --all] [--out FILE]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import xarray as xr

from roughcontact.pipeline.datasets import surface_heights
from roughcontact.pipeline.runcost import read_job
from roughcontact.solver.workspace import SOLVER_PATHS


def peer_area(h: np.ndarray, length, e_star: float, p0: float, tol: float, maxiter: int):
    """ContactMechanics' A/A0 at mean pressure ``p0``, its iterations and success (free boundary)."""
    import ContactMechanics as cm
    from ContactMechanics.Optimization import constrained_conjugate_gradients

    nx, ny = h.shape
    lx, ly = (length, length) if np.ndim(length) == 0 else length
    substrate = cm.FreeFFTElasticHalfSpace((nx, ny), e_star, physical_sizes=(lx, ly))
    res = constrained_conjugate_gradients(substrate, h, external_force=p0 * lx * ly, pentol=tol * float(np.std(h)),
                                          forcetol=tol * p0 * (lx / nx) * (ly / ny), maxiter=maxiter)
    f = np.asarray(res.jac)[:nx, :ny]
    return np.count_nonzero(np.abs(f) > 0) / (nx * ny), int(res.nit), bool(res.success)


def job_cpu(results: Path, name: str) -> float:
    """CPU seconds of the contact job (NaN without its benchmark file).

    The exact figure its log ends with (:func:`roughcontact.pipeline.runcost.read_job`), not
    Snakemake's ``cpu_time``, which samples a job every 30 s and missed 23 of opd-1's 38 s.
    """
    bench = results / "benchmarks" / "contact" / f"{name}.tsv"
    return read_job(bench)["cpu_time"] if bench.exists() else float("nan")


def row(results: Path, name: str, steps, maxiter: int) -> dict:
    con = xr.open_dataset(results / "contact" / f"{name}.nc").squeeze()
    with xr.open_dataset(results / "surfaces" / f"{name}.nc") as surf:
        h, length = surface_heights(surf.load(), name)
    paths = Counter(SOLVER_PATHS[int(c)] for c in con["solver_path"].values)
    out = {"file": name, "grid": f"{h.shape[0]} x {h.shape[1]}", "converged": int(con["converged"].sum()),
           "steps": con.sizes["step"], "iterations": int(con["iterations"].sum()),
           "paths": ", ".join(f"{k} {v}" for k, v in sorted(paths.items())),
           "max residual": float(con["residual"].max()), "CPU s": job_cpu(results, name)}
    diffs, failed, t0 = [], [], time.process_time()
    for step in steps or range(1, con.sizes["step"] + 1):
        k = step - 1
        a_cm, _, ok = peer_area(h, length, float(con.attrs["e_star"]), float(con["pressure"][k]),
                                float(con.attrs["tol"]), maxiter)
        if ok:
            a = float(con["area_fraction"][k])
            diffs.append(abs(a - a_cm) / a_cm)
        else:
            failed.append(step)
    out["peer steps"] = f"{len(diffs)} of {len(diffs) + len(failed)}" + (f" (fails at {failed})" if failed else "")
    out["max |dA|/A (peer)"] = max(diffs) if diffs else float("nan")
    out["peer CPU s"] = time.process_time() - t0
    return out


def markdown(rows: list[dict]) -> str:
    keys = list(rows[0])
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for r in rows:
        cells = [f"{v:.2g}" if isinstance(v, float) and k.startswith("max") else
                 f"{v:.1f}" if isinstance(v, float) else str(v) for k, v in r.items()]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="hardcases")
    parser.add_argument("--steps", default="1,10,20,30", help="load steps checked against the peer")
    parser.add_argument("--all", action="store_true", help="check every load step against the peer")
    parser.add_argument("--maxiter", type=int, default=10000, help="the peer's iteration cap")
    parser.add_argument("--out", type=Path, help="write the table here too")
    args = parser.parse_args(argv)
    results = Path("results") / args.scene
    names = sorted(p.stem for p in (results / "contact").glob("*.nc"))
    if not names:
        raise SystemExit(f"{results / 'contact'}: no contact files; run the scene first")
    steps = None if args.all else [int(s) for s in args.steps.split(",")]
    table = markdown([row(results, name, steps, args.maxiter) for name in names])
    print(table)
    if args.out:
        args.out.write_text(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
