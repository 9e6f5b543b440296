"""The batched solve (:mod:`roughcontact.solver.batch`): :func:`solve_contact_batch`, its step loop and dataset."""

from __future__ import annotations

import time

import numpy as np
import xarray as xr

from ...statistics.patches import PATCH_LONG_NAMES
from ..results import periodic_elastic_attrs, to_dataset
from ..settings import SolverSettings
from ..validation import validate_heights, validate_pressures
from .solver import BATCH_METHOD, BatchSolver, per_case

#: Per-case variables of the batched dataset (dims ``case, step``).
PER_CASE = ("area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter", "iterations",
            "residual", "converged", "solver_path", *PATCH_LONG_NAMES)


def validate_batch(heights) -> np.ndarray:
    """``heights`` as a C-contiguous float64 ``(B, nx, ny)`` array, each case checked as :func:`validate_heights`."""
    if isinstance(heights, (str, bytes)):
        raise ValueError(f"heights must be a real numeric array, got the string {heights!r}")
    a = np.asarray(heights)
    if a.ndim != 3 or a.shape[0] < 1:
        raise ValueError(f"heights of a batch must have shape (B, nx, ny) with B >= 1, got {a.shape}")
    cases = per_case(lambda b: validate_heights(a[b], name=f"heights[{b}]", square=False), a.shape[0], a[0].size)
    return np.stack(cases)


def solve_contact_batch(heights, pressures, settings: SolverSettings | None = None, *, check_every: int | None = None,
                        progress=None, **options) -> xr.Dataset:
    """Solve ``B`` surfaces of one grid under one load schedule together (issue 48).

    Parameters
    ----------
    heights : array_like, shape (B, nx, ny)
        ``B`` rigid surfaces [length] on one periodic cell, each as :func:`~roughcontact.solver.solve.solve_contact`'s
        ``heights`` (axis 1 = x); none flat.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures [pressure], the same schedule for every case (as for
        :func:`~roughcontact.solver.solve.solve_contact`, checked against each case's rms height).
    settings : SolverSettings, optional
        As for :func:`~roughcontact.solver.solve.solve_contact`; the batch runs the periodic elastic iteration
        ``"pk-fourier-f32"`` without effects, on either array backend.
    check_every : int, optional
        Rounds between two host reads of the per-case flags (:data:`CHECK_EVERY` by backend).
    progress : callable, optional
        Called after each load step as ``progress(step, p0, area_fraction, iterations, converged,
        seconds)`` with per-case arrays of shape (B,).
    **options
        Fields of :class:`SolverSettings` replacing those of ``settings``.

    Returns
    -------
    xarray.Dataset
        :func:`~roughcontact.solver.solve.solve_contact`'s dataset with a leading dimension ``case`` (0..B-1) on the
        per-case variables (``area_fraction``, ``mean_contact_pressure``, ``mean_gap``,
        ``contact_perimeter``, ``iterations``, ``residual``, ``converged``, ``solver_path``, ``contact_nodes``,
        ``largest_patch_nodes``: dims ``case, step``); ``pressure`` and ``wall_time`` (the whole batch's step)
        over ``step``; attributes as there, plus ``batch_size`` and ``check_every``.

    Raises
    ------
    ValueError
        For invalid input, or what a batch does not run (effects, ``boundary="free"``, another
        elastic method, a flat surface), naming it.
    """
    p = validate_pressures(pressures)
    h = validate_batch(heights)
    checked = SolverSettings.from_options(settings, **options).checked(h.shape[1:])
    if checked.effects:
        names = ", ".join(type(e).__name__ for e in checked.effects)
        raise ValueError(f"a batch of surfaces runs the elastic solver only, not the effects ({names}); "
                         "solve each case with solve_contact")
    if checked.boundary != "periodic":
        raise ValueError(f"a batch of surfaces runs the periodic half-space only, got boundary={checked.boundary!r}; "
                         "solve each case with solve_contact")
    if checked.method != BATCH_METHOD:
        raise ValueError(f"a batch of surfaces runs the elastic method {BATCH_METHOD!r} only, got "
                         f"{checked.method!r}; solve each case with solve_contact")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be a callable or None, got {type(progress).__name__} {progress!r}")
    solver = BatchSolver(h, checked, check_every)
    solver.check_loads(p, "pressures")
    return _batch_dataset(solver, p, *_run_steps(solver, p, progress))


def _run_steps(solver: BatchSolver, p: np.ndarray, progress):
    """Every load step of the batch: per-case columns ``(B, n_steps)``, iterations, flags, paths, wall, rounds."""
    B, n_steps = solver.batch, p.size
    cols = {k: np.empty((B, n_steps)) for k in ("area_fraction", "mean_contact_pressure", "mean_gap",
                                                 "contact_perimeter", "residual")}
    cols.update({k: np.empty((B, n_steps), dtype=np.int64) for k in PATCH_LONG_NAMES})
    iters = np.empty((B, n_steps), dtype=np.int64)
    conv = np.empty((B, n_steps), dtype=bool)
    paths = np.empty((B, n_steps), dtype=np.int8)
    wall = np.empty(n_steps)
    rounds = np.empty(n_steps, dtype=np.int64)
    for k, p0 in enumerate(p):
        t0 = time.perf_counter()
        out = solver.solve(float(p0))
        wall[k] = time.perf_counter() - t0
        for name in cols:
            cols[name][:, k] = out[name]
        iters[:, k], conv[:, k], paths[:, k] = out["iterations"], out["converged"], out["solver_path"]
        rounds[k] = out["rounds"]
        if progress is not None:
            progress(k + 1, float(p0), out["area_fraction"], out["iterations"], out["converged"], wall[k])
    return cols, iters, conv, paths, wall, rounds


def _batch_dataset(solver: BatchSolver, p, cols, iters, conv, paths, wall, rounds) -> xr.Dataset:
    """The batch's dataset: case 0's single-solve layout, the per-case variables stacked over ``case``."""
    s = solver.settings
    attrs = {**periodic_elastic_attrs(s, solver.shape, solver.backend), "batch_size": solver.batch,
             "check_every": solver.check_every}
    first = {name: col[0] for name, col in cols.items()}
    first["wall_time"] = wall
    ds = to_dataset(p, first, iters[0], conv[0], ([], [], []), False, solver.shape, attrs, (), paths=paths[0],
                    length_unit=s.length_unit, pressure_unit=s.pressure_unit)
    stacked = {**cols, "iterations": iters, "converged": conv, "solver_path": paths}
    for name in PER_CASE:
        var = ds[name].variable
        ds[name] = xr.Variable(("case", "step"), stacked[name], var.attrs)
    ds["wall_time"].attrs["long_name"] = "wall-clock time of the load step (the whole batch's)"
    ds["rounds"] = xr.Variable(("step",), rounds, {"units": "1", "long_name": "rounds of the batched iteration "
                                                   "(iterations of the slowest case plus waits for checks)"})
    ds = ds.assign_coords(case=xr.Variable(("case",), np.arange(solver.batch),
                                           {"units": "1", "long_name": "case of the batch (0-based)"}))
    ds.attrs["elastic_method"] = solver.method
    ds.attrs["boundary"] = "periodic"
    return ds
