"""One case of the κ-gap study: a surface solved with one setting, every area definition recorded per load step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from ...case import ContactCase, LoadSchedule, run_case
from ...solver import SolverSettings, contact_perimeter
from ...solver.reference.stanley_kato import StanleyKato
from ...surfaces.synthetic import finite_difference_rms_slope, generate_surface, spectral_moments
from ...theory.perimeter import PERIMETER_C, perimeter_corrected_area

#: Areas at which κ is compared (the paper's window, up to ≈ 10 %).
TARGET_AREAS = (0.01, 0.02, 0.05, 0.1)


#: The paper's κ at the representative point, in units of √(2π).
KAPPA_BGT = math.sqrt(2.0 * math.pi)


#: Roles a variant may have.
ROLES = ("baseline", "resolution", "solver", "load")


#: Solvers a variant may use.
METHODS = ("bem", "stanley-kato")


#: Iteration cap per load step of the reference iteration.
SK_MAX_ITER = 200_000


def definitions(thresholds: Sequence[str]) -> list[str]:
    """Names of the area definitions recorded for gap thresholds ``thresholds`` (config strings)."""
    return ["pressure", *[f"gap_{t}" for t in thresholds], "corrected"]


def area_variable(definition: str) -> str:
    """The NetCDF variable of a definition's area: CF names hold letters, digits and '_' only.

    ``gap_1e-4`` -> ``area_gap_1em4`` ('-' as 'm', '.' as 'p').
    """
    return "area_" + definition.replace("-", "m").replace(".", "p")


def _areas(pressure: np.ndarray, gap: np.ndarray, scale: float, thresholds: Sequence[str],
           length: float, contact: np.ndarray) -> dict[str, float]:
    """Area fractions [1] of one solved step under every definition."""
    n = pressure.shape[0]
    perim = contact_perimeter(contact, length)
    out = {"pressure": float(contact.mean())}
    for t in thresholds:
        out[f"gap_{t}"] = float((gap < float(t) * scale).mean())
    out["corrected"] = float(perimeter_corrected_area(out["pressure"], perim, length / n, PERIMETER_C))
    out["perimeter"] = perim
    return out


class _Areas:
    """Observer of a solve (:func:`roughcontact.case.run_case`): every area definition of each step."""

    needs_gap = True

    def __init__(self, scale: float, thresholds: Sequence[str], length: float):
        self.scale, self.thresholds, self.length, self.rows = scale, thresholds, length, []

    def observe(self, step) -> None:
        row = _areas(step.pressure, step.gap, self.scale, self.thresholds, self.length, step.mask)
        row.update(p0=step.p0, carried_load=float(step.pressure.mean()), iterations=step.iterations,
                   stopped=step.converged)
        self.rows.append(row)

    def dataset(self, steps) -> xr.Dataset:
        return xr.Dataset(coords={"step": steps})  # the rows are read off the observer


def _bem_rows(h, schedule: LoadSchedule, *, length, tol, scale, thresholds) -> list[dict]:
    """The main solver through the case runner, each step started from the last pressure scaled to its load."""
    areas = _Areas(scale, thresholds, length)
    case = ContactCase(schedule, SolverSettings(tol=tol), warm_start="scaled")
    run_case(h, case, length=length, rms_slope=float(spectral_moments(h, length)["rms_slope"]), observers=[areas])
    return areas.rows


def _sk_steps(h, loads, *, length, tol):
    """Stanley & Kato's iteration, load by load, warm-started, stopped by its own rule."""
    sk = StanleyKato(h, length=length)
    for p0 in loads:
        r = sk.solve(p0, tol=tol, max_iter=SK_MAX_ITER)
        yield r.pressure, r.gap, r.gap <= 0, r.iterations, r.stopped


def solve_case(h: np.ndarray, setting: Mapping, *, length: float, thresholds: Sequence[str]) -> xr.Dataset:
    """Solve surface ``h`` (n, n) [length] for one variant ``setting``; E* = 1.

    ``setting``: ``method`` (:data:`METHODS`), ``tol`` (string), ``p_max`` [E*],
    ``n_steps``, ``schedule`` (geometric: from ``p_max / 30`` to ``p_max``). Returns a
    Dataset over ``step`` with the applied load
    ``p0``, the ``carried_load`` (the mean contact pressure; equal to p0 for the main
    solver), ``area_<definition>`` for every :func:`definitions` entry,
    ``contact_perimeter``, ``iterations``, ``stopped`` (the solver's own rule ended the
    step: the main solver's converged check, or Stanley & Kato's load and move rule); attrs
    carry both rms slopes and the rms height. No timing: a rerun writes the same bytes (a job's
    wall time is in its Snakemake benchmark file).
    """
    p_max = float(setting["p_max"])
    # A geometric schedule starts where the paper's uniform one does, at p_max/30, so that
    # both reach below A/A0 = 0.01 whatever their number of steps (E* = 1).
    load = LoadSchedule(int(setting["n_steps"]), setting["schedule"], p_max=p_max, p_min=p_max / 30)
    scale = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    tol = float(setting["tol"])
    if setting["method"] == "bem":
        rows = _bem_rows(h, load, length=length, tol=tol, scale=scale, thresholds=thresholds)
    else:
        rows = []
        for p0, (pressure, gap, contact, its, ok) in zip(load.pressures(1.0), _sk_steps(
                h, load.pressures(1.0), length=length, tol=tol), strict=True):
            row = _areas(pressure, gap, scale, thresholds, length, contact)
            row.update(p0=p0, carried_load=float(pressure.mean()), iterations=its, stopped=ok)
            rows.append(row)
    return _case_dataset(rows, h, length, thresholds)


def _case_dataset(rows: list[dict], h: np.ndarray, length: float, thresholds: Sequence[str]) -> xr.Dataset:
    def var(key, units, long_name, dtype=float):
        return xr.DataArray(np.array([r[key] for r in rows], dtype=dtype), dims="step",
                            attrs={"units": units, "long_name": long_name})

    ds = xr.Dataset(coords={"step": xr.DataArray(np.arange(1, len(rows) + 1), dims="step",
                                                 attrs={"units": "1", "long_name": "load step"})})
    ds["p0"] = var("p0", "1", "applied mean pressure p0 / E*")
    ds["carried_load"] = var("carried_load", "1", "mean contact pressure carried / E*")
    for d in definitions(thresholds):
        ds[area_variable(d)] = var(d, "1", f"contact area fraction A/A0, {describe(d)}")
    ds["contact_perimeter"] = var("perimeter", "1", "contact perimeter per unit area times L")
    ds["iterations"] = var("iterations", "1", "iterations of the load step", np.int64)
    # Not "converged": Stanley & Kato's rule bounds the load and the last move, not the invariants.
    ds["stopped"] = var("stopped", "1", "the solver's own rule ended the step (main solver: its converged "
                        "check; Stanley & Kato: carried load and last move within tol)", np.int8)
    stats = spectral_moments(h, length)
    ds.attrs.update(rms_slope_spectral=stats["rms_slope"], rms_slope_discrete=finite_difference_rms_slope(h, length),
                    rms_height=stats["rms_height"], n=int(h.shape[0]))
    return ds


def describe(definition: str) -> str:
    """A reader's name for an area definition."""
    if definition == "pressure":
        return "nodes with p > 0"
    if definition == "corrected":
        return f"perimeter-corrected, A_pix - c P dx with c = {PERIMETER_C:.3f}"
    return f"nodes with gap < {definition.removeprefix('gap_')} rms height"


def case_surface(k_l: str, k_s: str, hurst: str, seed: int, n: int, block: Mapping) -> np.ndarray:
    """The study's surface: the same continuous surface at every ``n`` (:func:`generate_surface`)."""
    return generate_surface(n, float(k_l), float(k_s), float(hurst), int(seed),
                            rms_slope=block["surface"]["rms_slope"], length=block["surface"]["L"])
