#!/usr/bin/env python
"""The sphere's pull-off against the resolution of the adhesive process zone (docs/solver.md, "Adhesion").

A rigid sphere ``h = -(x^2 + y^2) / 2R`` (R = 1, E* = 1) on an ``N x N`` periodic cell of side ``L``,
exponential law with work ``w`` and range ``rho = w^(2/3) R^(1/3) / mu_T`` (Tabor parameter ``mu_T``),
is pressed by a tiny load and unloaded by the adhesion effect's own refined unloading
(:meth:`roughcontact.solver.adhesion.solver.AdhesiveSolver.unload`). Printed per case: the process zone's
cells ``E* rho^2 / w / dx``, the pull-off force over ``pi w R`` (measured with the resolution check
switched off, so that unresolved grids show what they would report), the attraction across the cell
at the pull-off (``attraction_across_cell``: for the centred sphere the tension at the cell's edge over
``w / rho``), the status the solver gives it and the steps whose own residual check failed. JKR's
pull-off is 1.5, Derjaguin's (DMT) 2; no sphere exceeds 2.

Usage::

    python benchmarks/adhesion_resolution.py                  # the resolution table of docs/solver.md (~5 min)
    python benchmarks/adhesion_resolution.py --cell           # its cell-size table (L = R/2 against 2R, ~10 s)
    python benchmarks/adhesion_resolution.py --cases 2,64 8,64,2.0 --length 0.5   # mu_T,N[,L]
"""

from __future__ import annotations

import argparse
import math
import time
import warnings

import numpy as np

import roughcontact.solver.adhesion.solver as adhesive
from roughcontact.solver import Adhesion, solve_contact
from roughcontact.solver.adhesion import MAX_ATTRACTION_ACROSS_CELL, MIN_ZONE_CELLS, PULL_OFF_STATUS

#: (mu_T, N) of the table in docs/solver.md.
CASES = [(8, 64), (8, 128), (4, 64), (4, 128), (4, 256), (2.44, 64), (2.44, 128), (2.44, 256), (2, 64), (2, 128),
         (2, 256), (1.41, 64), (1.41, 128), (1, 64), (1, 128)]
#: (mu_T, N, L) of the cell-size table in docs/solver.md: the DMT side at L = R / 2 and 2 R.
CELL_CASES = [(mu_t, 64, length) for mu_t in (0.05, 0.1, 0.2, 0.3, 0.5) for length in (0.5, 2.0)]


def sphere(n: int, length: float, radius: float = 1.0) -> np.ndarray:
    """Heights [length] of a sphere of ``radius`` on ``n x n`` nodes of a cell of side ``length``."""
    x = (np.arange(n) - n // 2) * length / n
    return -(x[:, None] ** 2 + x[None, :] ** 2) / (2 * radius)


def pull_off(mu_t: float, n: int, length: float, w: float = 1e-4) -> dict:
    """One case: its zone cells, pull-off over pi w R with the check off, and the status with it on."""
    rho = w ** (2 / 3) / mu_t
    loads = [2e-4 * math.pi * w / length ** 2]
    effect = Adhesion("exponential", w, rho)
    t0 = time.process_time()
    saved, adhesive.MIN_ZONE_CELLS = adhesive.MIN_ZONE_CELLS, 0.0  # what an unchecked grid reports
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = solve_contact(sphere(n, length), loads, effects=(effect,), length=length, tol=1e-8)
    finally:
        adhesive.MIN_ZONE_CELLS = saved
    cells = float(ds["adhesive_zone_cells"])
    status = PULL_OFF_STATUS[int(ds["pull_off_status"])]
    if cells < MIN_ZONE_CELLS:
        status = "adhesive_zone_unresolved"  # what the solver says with its check on
    loads = ds["unload_mean_pressure"].values
    raw = -float(np.nanmin(loads)) * length ** 2 / (math.pi * w)
    return {"mu_T": mu_t, "N": n, "L": length, "cells": cells, "F": raw, "status": status,
            "across": float(ds["attraction_across_cell"]), "failed": int(np.count_nonzero(np.isnan(loads))),
            "steps": int(ds.sizes["unload_step"]), "cpu": time.process_time() - t0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="*", help="mu_T,N or mu_T,N,L (default: the table of docs/solver.md)")
    ap.add_argument("--cell", action="store_true", help="the cell-size table (L = R/2 against 2R) instead")
    ap.add_argument("--length", type=float, default=0.5, help="cell side L / R where a case gives none (default 0.5)")
    args = ap.parse_args()
    cases = [tuple(float(v) for v in c.split(",")) for c in args.cases] if args.cases else (
        CELL_CASES if args.cell else CASES)
    print(f"sphere R = 1, E* = 1, w = 1e-4, L = {args.length:g} unless given; zone check {MIN_ZONE_CELLS:g} cells, "
          f"attraction across the cell below {MAX_ATTRACTION_ACROSS_CELL:g}")
    print("| mu_T | N | L/R | zone cells | F/(pi w R) | attraction across cell | status (check on) | unloading steps "
          "| residual failed | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for case in cases:
        r = pull_off(case[0], int(case[1]), case[2] if len(case) > 2 else args.length)
        print(f"| {r['mu_T']:g} | {r['N']} | {r['L']:g} | {r['cells']:.3g} | {r['F']:.4f} | {r['across']:.3g} | "
              f"{r['status']} | {r['steps']} | {r['failed']} | {r['cpu']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
