"""The contact solver of one surface: units, effects, warm starts and the step loop.

Public entry points :func:`solve_contact` and :func:`solve_step` (re-exported
by :mod:`roughcontact.solver`, whose docstring states the problem, the units,
the algorithms and the convergence criterion).
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np
import xarray as xr

from ..core.quantities import cf_unit
from .box import box_solve
from .check import MEAN_RTOL, final_check
from .effects import PlasticityCap
from .elastic import pk_solve
from .halfspace import plans
from .projection import enforce_mean
from .results import (
    SOLVER_NAME,
    StepRecord,
    StepResult,
    cell_attrs,
    contact_perimeter,
    solver_description,
    to_dataset,
)
from .units import Units, check_loads, frexp_ratio
from .validation import (
    real_scalar,
    validate_boundary,
    validate_flag,
    validate_heights,
    validate_pressures,
    validate_solver_args,
    validate_store,
)
from .workspace import FALLBACKS, SOLVER_PATHS, STICKY, Workspace

#: Default iteration cap per load step.
DEFAULT_MAX_ITER = 10000


def _effects(hardness) -> list:
    return [] if hardness is None else [PlasticityCap(hardness)]


class ContactSolver:
    """Validated problem of one surface: units, effects, workspace and warm starts.

    ``heights`` (nx, ny) and the scalars are already validated, ``length`` a float
    ``L`` (square cell) or a pair ``(Lx, Ly)`` (:func:`~.validation.validate_length`);
    ``effects`` act on the iteration (:mod:`.effects`); ``method`` is the elastic
    iteration; ``boundary`` the half-space, one of :data:`~.validation.BOUNDARIES`.
    """

    def __init__(self, h, e_star, length, tol, max_iter, effects, threads, method, boundary="periodic"):
        self.shape = h.shape
        self.size = h.size
        self.length = length
        self.tol, self.max_iter = tol, max_iter
        self.effects = list(effects)
        self.units = Units(h, e_star, length)
        self.threads = threads
        self.method = method
        self.start_method = method  # the iteration each step starts on (_iterate)
        self.boundary = boundary
        self.periodic = boundary == "periodic"
        if self.units.flat and not self.periodic and self.effects:
            raise ValueError(
                "hardness: a perfectly flat surface (all heights equal) on the free half-space is a rigid "
                "flat punch, whose edge pressures would reach any hardness; boundary='free' with a "
                "hardness is not supported for a flat surface (give hardness=None or a rough surface)")
        self._punch = None  # flat surface on the free half-space: solution at unit load
        self.ws = None if self.units.flat else Workspace(self.units.heights, length, threads, method,
                                                         boundary)
        for effect in self.effects:
            effect.bind(self.units)
        caps = [e.upper_bound for e in self.effects if e.upper_bound is not None]
        self.cap = min(caps) if caps else None
        # the physical cap, for starting pressures given by the caller
        self.hardness = min((e.hardness for e in self.effects if isinstance(e, PlasticityCap)), default=None)
        self.prev = None  # internal p0 of the last solved step
        self._older = None  # (p0, pressure) of the step before the last
        self._last = None  # pressure of the last step
        self._pbuf = np.empty(self.shape)

    def check_loads(self, p: np.ndarray, name: str) -> None:
        """Refuse loads an effect cannot carry or float64 cannot represent."""
        for effect in self.effects:
            effect.check_loads(self.units, p, name)
        check_loads(self.units, p, self.shape, name)
        for effect in self.effects:
            effect.check_range(self.units)

    @property
    def backend(self) -> str:
        return self.ws.backend if self.ws is not None else plans(self.shape, self.threads).backend

    def _extrapolation(self, p_int: float) -> float:
        """Factor ``c`` of the linear extrapolation in the load, 0 when not used."""
        if self.cap is not None or self.method == "pk" or self._older is None:
            return 0.0
        if self._older[0] == self.prev:
            return 0.0
        c = (p_int - self.prev) / (self.prev - self._older[0])
        return c if 0.0 < c <= 2.0 else 0.0

    def start(self, p0: float, initial=None) -> bool:
        """Put the starting pressure for ``p0`` in the workspace; returns ``fresh``."""
        ws, cap = self.ws, self.cap
        p_int = self.units.to_internal(p0)
        target = p_int * ws.size
        if initial is not None:
            np.maximum(initial, 0.0, out=ws.P)
            if cap is None:
                top = float(ws.P.max())
                if top > 0:
                    ws.P /= top
            else:
                np.minimum(ws.P, self.hardness, out=ws.P)
                ws.P *= cap / self.hardness
            enforce_mean(ws.P, target, cap)
            return False
        if cap is not None and p_int >= cap:
            # p0 within an ulp of the hardness: every node at the cap
            ws.P.fill(cap)
            return False
        if self.prev is None:
            ws.P.fill(p_int)
            return False
        s = p_int / self.prev
        c = self._extrapolation(p_int)
        if c:
            # Extrapolated warm start, linear in the load through the last two
            # solutions (loads moving on in the same direction, by at most twice
            # the last increment); otherwise the scaled last solution below.
            ws.P -= self._older[1]
            ws.P *= c
            ws.P += self._last
            np.maximum(ws.P, 0.0, out=ws.P)
            enforce_mean(ws.P, target, None)
            return False
        if cap is None:
            # Warm start: p and u = K p scale together, so w = K p - h follows
            # without a transform.
            ws.w *= s
            ws.w += (s - 1.0) * ws.h
            ws.P *= s
            return True
        ws.P *= s
        enforce_mean(ws.P, target, cap)
        return False

    def _flat(self, p0: float, keep_gap: bool):
        # exact solution: u = K p0 = 0, so g = 0 with d = h
        n2 = self.size
        p = np.full(self.shape, p0)
        mean_ok = abs(float(p.sum()) - p0 * n2) <= MEAN_RTOL * p0 * n2
        gap = np.zeros(self.shape) if keep_gap else None
        cols = {}
        for effect in self.effects:
            cols.update(effect.finish(p, None, p0))
        return StepRecord(p, p > 0, 1.0, 0.0, 0.0, 0, 0.0, mean_ok, cols, "exact"), gap

    def _flat_punch(self, p0: float, keep_gap: bool):
        """A flat surface on the free half-space: the rigid square (or rectangular) flat punch.

        ``u = K p`` is no longer uniform under a uniform pressure, so the
        problem is solved, once, at unit load in units ``E* = Lx = 1`` with the
        gap scale ``p0 Lx / E*`` (:func:`gap_scale` of a flat surface) as unit;
        without a cap it is linear in ``p0``, so every step is that solution
        scaled (``iterations`` counts the solve at the first step, 0 after).
        """
        n2 = self.size
        its = 0
        if self._punch is None:
            ws = Workspace(np.zeros(self.shape), self.length, self.threads, self.method, self.boundary,
                           scale=1.0)
            ws.P.fill(1.0)
            its = pk_solve(ws, 1.0, self.tol, self.max_iter, False)[0]
            ok, residual, gbar, w_sum = final_check(ws, 1.0, self.tol, None)
            self._punch = (ws.P.copy(), ws.w - gbar, w_sum / n2 - gbar, float(residual), bool(ok))
        x, g1, mg1, residual, ok = self._punch
        p = x * p0
        mean_ok = ok and abs(float(p.sum()) - p0 * n2) <= MEAN_RTOL * p0 * n2
        fm, fe = frexp_ratio((p0, self.units.length), (self.units.e_star,))  # the gap scale p0 Lx / E*
        try:
            mean_gap = math.ldexp(mg1 * fm, fe)
        except OverflowError:
            mean_gap = math.inf
        with np.errstate(over="ignore", under="ignore"):
            gap = np.ldexp(g1 * fm, fe) if keep_gap else None
        if not (math.isfinite(mean_gap) and (gap is None or np.all(np.isfinite(gap)))):
            raise ValueError(
                f"pressures: the gap at p0={p0!r} overflows float64 in the units of heights; reduce "
                "p0 * length / e_star")
        mask = p > 0
        area = np.count_nonzero(mask) / n2
        step = StepRecord(p, mask, area, mean_gap, contact_perimeter(mask, self.length, periodic=False), its,
                          residual, mean_ok, {}, self.method)
        return step, gap

    def _iterate(self, p_int: float, fresh: bool) -> tuple[int, str]:
        """Iterate the step to ``tol``; ``(iterations, path)``, the path being the iteration that ended it.

        A step starts on :attr:`start_method`, the scene's iteration until a step has needed a
        fallback. An iteration that stalls (its residual stops falling, :class:`StallGuard`) before
        ``max_iter`` hands its pressure to the next, more robust one in :data:`FALLBACKS`, within the
        same ``max_iter`` in all: single-precision products stall at ~1e-5 on some measured surfaces
        whose gaps span many decades, where float64 converges; Polonsky & Keer's active-set rule can
        cycle far from the solution on a plateau with isolated spikes, where the monotone gradient
        projection (``"box"``, the capped iteration with a cap no node can reach) converges
        (tests/test_solver_hard_cases.py). A step that needed a fallback makes the method that
        converged it the start of the next steps (``STICKY``), so that one hard surface pays the
        stall window once, not at every step.
        """
        if self.cap is not None:
            return box_solve(self.ws, p_int, self.tol, self.max_iter, self.cap, fresh)[0], "box"
        path = self.start_method
        its, ok = self._run(path, p_int, self.max_iter, fresh)
        for method in FALLBACKS[path]:
            if ok or its >= self.max_iter:
                break
            path = method
            more, ok = self._run(method, p_int, self.max_iter - its, True)
            its += more
        if ok and STICKY and path != self.start_method:
            self.start_method = path
        return its, path

    def _run(self, path: str, p_int: float, max_iter: int, fresh: bool) -> tuple[int, bool]:
        """One iteration of :data:`SOLVER_PATHS` on the workspace; ``(iterations, converged)``.

        ``"box"`` is the capped iteration with the cap at twice the total load, which no node can
        reach (every node's pressure is at most the total), preconditioned unless the scene's
        iteration is the reference ``"pk"``.
        """
        ws = self.ws
        try:
            if path == "box":
                ws.method = "pk" if self.method == "pk" else "pk-fourier"
                return box_solve(ws, p_int, self.tol, max_iter, 2.0 * p_int * ws.size, fresh)
            ws.method = path
            return pk_solve(ws, p_int, self.tol, max_iter, fresh)
        finally:
            ws.method = self.method

    def solve(self, p0: float, initial=None, keep_gap: bool = False):
        """Solve the step for the physical mean pressure ``p0``; returns ``(StepRecord, gap)``."""
        if self.units.flat:
            return self._flat(p0, keep_gap) if self.periodic else self._flat_punch(p0, keep_gap)
        ws, units = self.ws, self.units
        n2 = self.size
        fresh = self.start(p0, initial)
        p_int = units.to_internal(p0)
        its, path = self._iterate(p_int, fresh)
        ok, residual, gbar, w_sum = final_check(ws, p_int, self.tol, self.cap)
        if self.cap is None and self.method != "pk":
            self._older = None if self.prev is None else (self.prev, self._last)
            self._last = ws.P.copy()
        self.prev = p_int
        p = units.pressure(ws.P, out=self._pbuf)
        cols = {}
        for effect in self.effects:
            cols.update(effect.finish(p, ws.P, p0))
        mask = p > 0
        area = np.count_nonzero(mask) / n2
        if area <= 0:
            raise RuntimeError(f"no contact node at p0={p0!r}: the solver lost the load (bug)")
        mean_gap = math.ldexp(w_sum / n2 - gbar, units.e_len)
        gap = units.length_field(ws.w - gbar) if keep_gap else None
        if not (math.isfinite(mean_gap) and (gap is None or np.all(np.isfinite(gap)))):
            raise ValueError(
                f"pressures: the gap at p0={p0!r} overflows float64 in the units of heights; reduce "
                "p0 * length / e_star or the heights")
        step = StepRecord(p, mask, area, mean_gap, contact_perimeter(mask, self.length, self.periodic), its,
                          float(residual), bool(ok), cols, path)
        return step, gap


def _method() -> str:
    """The elastic iteration: the switch ``roughcontact.solver.ELASTIC_METHOD`` (set there)."""
    return sys.modules[__package__].ELASTIC_METHOD


def solve_step(heights, p0: float, *, e_star: float = 1.0, length=1.0,
               tol: float = 1e-8, max_iter: int = DEFAULT_MAX_ITER, threads: int = 1,
               hardness: float | None = None, initial_pressure=None,
               boundary: str = "periodic") -> StepResult:
    """Solve the contact for one mean pressure.

    Parameters
    ----------
    heights : array_like, shape (n, n) or (nx, ny)
        Rigid surface heights [length]; the highest points touch first; as in
        :func:`solve_contact`.
    p0 : float
        Applied mean pressure [pressure]: ``0 < p0``, ``p0 < hardness`` if a
        hardness is given, and ``p0 * L / (e_star * s)`` in
        :data:`LOAD_RANGE` (``s`` the rms height, ``L`` the float ``length`` or ``Lx``).
    e_star, length, tol, max_iter, threads, hardness, boundary
        As in :func:`solve_contact` (``length`` a float ``L`` or a pair ``(Lx, Ly)``).
    initial_pressure : array_like, same shape as ``heights``, optional
        Starting pressure (clipped to ``[0, hardness]`` and brought to mean
        ``p0``); uniform ``p0`` when omitted.

    Returns
    -------
    StepResult
        Fields are fresh arrays owned by the caller.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    h = validate_heights(heights, square=False)
    p0_f = real_scalar("p0", p0, "a finite number > 0")
    if not (math.isfinite(p0_f) and p0_f > 0):
        raise ValueError(f"p0 must be a finite number > 0, got {p0!r}")
    e_star, length, tol, max_iter, hardness, threads = validate_solver_args(
        e_star, length, tol, max_iter, hardness, threads, shape=h.shape)
    boundary = validate_boundary(boundary)
    init = None
    if initial_pressure is not None:
        init = validate_heights(initial_pressure, name="initial_pressure", square=False)
        if init.shape != h.shape:
            raise ValueError(f"initial_pressure must have shape {h.shape}, the shape of heights, got {init.shape}")
    solver = ContactSolver(h, e_star, length, tol, max_iter, _effects(hardness), threads, _method(), boundary)
    solver.check_loads(np.array([p0_f]), "p0")
    t0 = time.perf_counter()
    st, gap = solver.solve(p0_f, initial=init, keep_gap=True)
    wall = time.perf_counter() - t0
    return StepResult(p0_f, st.pressure.copy(), gap, st.area, st.mean_gap, st.perimeter,
                      st.iterations, st.residual, st.converged, wall,
                      st.effect_columns.get("plastic_area_fraction"),
                      st.effect_columns.get("plastic_load_fraction"))


def solve_contact(heights, pressures, *, e_star: float = 1.0, length=1.0,
                  tol: float = 1e-8, max_iter: int = DEFAULT_MAX_ITER, store_fields=False,
                  threads: int = 1, hardness: float | None = None,
                  clusters: bool = False, boundary: str = "periodic", progress=None,
                  length_unit: str = "1", pressure_unit: str = "1") -> xr.Dataset:
    """Solve the normal contact of a rigid rough surface on an elastic half-space.

    Parameters
    ----------
    heights : array_like, shape (n, n) or (nx, ny)
        Rigid surface heights [length] on the cell (periodic, or the whole
        patch for ``boundary="free"``), axis 0 = x, axis 1 = y; the highest
        points touch first. Any ``n >= 4`` (``nx, ny >= 4``), odd or not;
        ``(nx, ny)`` with ``nx != ny`` needs ``length=(Lx, Ly)``.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures ``p0 > 0``, one load step each [pressure, same unit
        as ``e_star``], each with ``p0 * L / (e_star * s)`` in
        :data:`LOAD_RANGE` (``s`` the rms height of ``heights``, ``L`` the float
        ``length`` or ``Lx``) and, with a
        hardness, ``p0 < hardness``. Any order is accepted; each step
        warm-starts from the previous one, which pays off most for increasing
        loads.
    e_star : float
        Plane-strain modulus ``E* = E / (1 - nu**2)`` of the half-space, > 0.
    length : float or (float, float)
        A float ``L``: side of the square cell [length], > 0, for square
        ``heights`` only. A pair ``(Lx, Ly)``: the sides along x (axis 0) and
        y (axis 1) of a rectangular cell, each finite and > 0; pixels
        ``dx = Lx / nx`` and ``dy = Ly / ny`` (anisotropic when they differ).
        ``(L, L)`` on an ``n x n`` grid is the float ``L``, bit for bit.
    tol : float
        Convergence tolerance in (0, 1) on the scale-free residual of the module
        docstring.
    max_iter : int
        Iteration cap per step, >= 1.
    store_fields : bool or iterable of int
        ``True`` stores ``contact_pressure`` and ``gap`` for every step (dims
        ``step, x, y``); an iterable of 1-based step numbers stores only those
        (dims ``field_step, x, y``, coordinate ``field_step`` = step numbers).
    threads : int
        FFTW threads (default 1).
    hardness : float, optional
        Cap on the pressure (perfectly plastic interface) [pressure], > every p0,
        with ``hardness * L / (e_star * s)`` in :data:`LOAD_RANGE` (``L = Lx`` on a rectangle).
    clusters : bool
        Add contact-cluster statistics per step (4-connected labelling, periodic
        unless ``boundary="free"``, see :mod:`roughcontact.clusters`):
        ``cluster_count``, ``cluster_mean_area``, ``cluster_max_area`` and
        ``cluster_area_histogram``. Off: no labelling work.
    boundary : {"periodic", "free"}
        The elastic half-space. ``"periodic"`` (default): the cell is one
        period of an infinite periodic surface, ``u(q) = 2 p(q) / (E* |q|)``.
        ``"free"``: the cell is an isolated patch (a measured, non-periodic
        surface) on an infinite half-space loaded only there; nothing wraps
        around, ``u`` is the true (not zero-mean) displacement and ``d`` the true
        rigid-body approach; each product costs a ``2nx x 2ny`` FFT pair
        (:class:`~.halfspace.FreeHalfSpace`). A flat surface is then the rigid
        square (rectangular) flat punch (no hardness allowed).
    progress : callable, optional
        Called after each load step as ``progress(step, p0, area_fraction,
        iterations, converged, seconds)`` (``step`` 1-based, ``seconds`` the
        step's wall time), e.g. to log a long solve as it goes.
    length_unit : str
        Unit of ``heights`` and ``length``, one of
        :data:`roughcontact.quantities.LENGTH_UNITS` (default ``"1"``: nondimensional);
        only labels the output (the ``units`` of ``mean_gap``, ``gap``, ``x``, ``y``
        and, as its inverse, ``contact_perimeter``), the numbers do not depend on it.
    pressure_unit : str
        Unit of ``e_star``, ``pressures`` and ``hardness``, one of
        :data:`roughcontact.quantities.PRESSURE_UNITS` (default ``"1"``); labels
        ``pressure``, ``mean_contact_pressure`` and ``contact_pressure``.

    Returns
    -------
    xarray.Dataset
        Dimension ``step`` (coordinate 1..n_steps) with ``pressure``,
        ``area_fraction``, ``mean_contact_pressure``, ``mean_gap``,
        ``contact_perimeter``, ``iterations``, ``residual``, ``converged``,
        ``wall_time``, ``solver_path`` (the iteration that ended the step, a CF flag)
        and, with a hardness, ``plastic_area_fraction`` and
        ``plastic_load_fraction``; fields and ``x``/``y`` coordinates only when
        stored. Every variable carries ``units`` and ``long_name`` (CF strings from
        :func:`roughcontact.quantities.cf_unit`); the global attributes
        ``length_units`` and ``pressure_units`` are the units of the attributes
        ``length`` (or ``length_x``, ``length_y``) and ``e_star`` (and
        ``hardness``); ``boundary`` records the half-space. The cell
        (:func:`~.results.cell_attrs`): a square cell has ``length`` (L) and
        ``n``; a rectangular one (``length=(Lx, Ly)`` with ``nx != ny`` or
        ``Lx != Ly``) has ``length_x`` and ``length_y`` instead, and no
        ``length`` or ``n``; ``nx`` and ``ny`` (nodes along x and y) are always
        there. Stored fields have ``x`` and ``y`` coordinates ``i dx`` and ``j dy``.
        ``converged`` is True only when the final check of the module docstring
        passed on a freshly recomputed displacement.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    h = validate_heights(heights, square=False)
    p = validate_pressures(pressures)
    e_star, length, tol, max_iter, hardness, threads = validate_solver_args(
        e_star, length, tol, max_iter, hardness, threads, shape=h.shape)
    store = validate_store(store_fields, p.size)
    clusters = validate_flag("clusters", clusters)
    boundary = validate_boundary(boundary)
    cf_unit(length_unit, pressure_unit)  # ValueError for a unit outside the declared sets
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be a callable or None, got {type(progress).__name__} {progress!r}")
    solver = ContactSolver(h, e_star, length, tol, max_iter, _effects(hardness), threads, _method(), boundary)
    solver.check_loads(p, "pressures")
    cols, iters, conv, paths, fields, masks = _run_steps(solver, p, store, clusters, progress)
    sides, grid = cell_attrs(h.shape, length)
    attrs = {"e_star": e_star, **sides, "tol": tol, "max_iter": max_iter, "threads": threads,
             "fft_backend": solver.backend, **grid, "solver": SOLVER_NAME,
             "solver_description": solver_description(solver.periodic, np.ndim(length) == 0)}
    ds = to_dataset(p, cols, iters, conv, fields, store_fields, h.shape, attrs, solver.effects, paths=paths,
                    length_unit=length_unit, pressure_unit=pressure_unit)
    ds.attrs["elastic_method"] = solver.method
    ds.attrs["boundary"] = boundary
    if masks is not None:
        from ..statistics.clusters import cluster_dataset

        stats = cluster_dataset(masks, ds["step"].values, length, periodic=solver.periodic,
                                length_unit=length_unit)
        ds = ds.merge(stats.drop_vars("step"), combine_attrs="override")
    return ds


def _run_steps(solver: ContactSolver, p: np.ndarray, store: set, clusters: bool, progress=None):
    """Solve every load step; per-step columns, iterations, flags, path codes, stored fields, masks."""
    n_steps = p.size
    names = ["area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter", "residual",
             "wall_time"] + [v for e in solver.effects for v in e.variables()]
    cols = {k: np.empty(n_steps) for k in names}
    iters = np.empty(n_steps, dtype=np.int64)
    conv = np.empty(n_steps, dtype=bool)
    paths = np.empty(n_steps, dtype=np.int8)
    fields_p, fields_g, field_steps = [], [], []
    masks = [] if clusters else None
    for k, p0 in enumerate(p):
        p0 = float(p0)
        t0 = time.perf_counter()
        st, gap = solver.solve(p0, keep_gap=k + 1 in store)
        cols["wall_time"][k] = time.perf_counter() - t0
        cols["area_fraction"][k] = st.area
        cols["mean_contact_pressure"][k] = p0 / st.area
        cols["mean_gap"][k] = st.mean_gap
        cols["contact_perimeter"][k] = st.perimeter
        cols["residual"][k] = st.residual
        for name, value in st.effect_columns.items():
            cols[name][k] = value
        iters[k] = st.iterations
        conv[k] = st.converged
        paths[k] = SOLVER_PATHS.index(st.path)
        if k + 1 in store:
            fields_p.append(st.pressure.copy())
            fields_g.append(gap)
            field_steps.append(k + 1)
        if masks is not None:
            masks.append(st.mask.copy())
        if progress is not None:
            progress(k + 1, p0, st.area, st.iterations, st.converged, cols["wall_time"][k])
    return cols, iters, conv, paths, (fields_p, fields_g, field_steps), masks
