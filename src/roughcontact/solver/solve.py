"""The public entry points: :func:`solve_contact` (a load schedule) and :func:`solve_step` (one load).

Both take the surface, the loads and a :class:`~.settings.SolverSettings` (or its fields as
keyword options), validate them once (:func:`prepare`) and run a :class:`~.contact.ContactSolver`.
docs/solver.md states the problem, units, algorithms and convergence criterion.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..core.cell import Cell
from ..statistics.patches import PATCH_LONG_NAMES, contact_patches
from .adhesion.solver import ADHESIVE_SOLVER_DESCRIPTION, ADHESIVE_SOLVER_NAME, AdhesiveSolver
from .contact import ContactSolver
from .results import SOLVER_NAME, StepResult, solver_description, to_dataset
from .settings import SolverSettings
from .validation import real_scalar, validate_heights, validate_pressures, validate_store


def prepare(heights, loads: np.ndarray, name: str, settings: SolverSettings | None,
            options: dict) -> ContactSolver | AdhesiveSolver:
    """The validated solver of ``heights`` for ``settings`` with ``options`` replacing its fields.

    The iteration follows from what the effects supply: an interaction energy (``functional``)
    needs the gap iteration (:class:`~.adhesion.solver.AdhesiveSolver`), anything else the pressure
    iterations (:class:`~.contact.ContactSolver`). ``loads`` (already validated numbers) are
    checked against the effects and float64's range, the error naming the argument ``name``.
    A profile (1-D ``heights``, :meth:`~roughcontact.core.cell.Cell.profile`) is solved as its one-row
    grid ``(n, 1)``: the solver's ``shape``.
    """
    h = validate_heights(heights, square=False, profile=True)
    checked = SolverSettings.from_options(settings, **options).checked(h.shape)
    adhesive = any(e.functional is not None for e in checked.effects)
    if h.ndim == 1:
        check_profile(checked, adhesive)
        h = h[:, None]
    kind = AdhesiveSolver if adhesive else ContactSolver
    solver = kind(h, checked)
    solver.check_loads(loads, name)
    return solver


def check_profile(settings: SolverSettings, adhesive: bool) -> None:
    """Refuse, for a profile, what the solver does on maps only: an interaction energy (adhesion: its
    zone's resolution checks and the gap iteration are 2-D) and the CuPy backend (not measured on a
    one-row grid). The plasticity cap works on profiles.

    A profile is solved as its one-row grid ``(n, 1)`` (:meth:`~roughcontact.core.cell.Cell.profile`):
    the surface the same along y (plane strain; Johnson 1985, ch. 2), the kernel ``2 / (E* |q|)``
    along x, periodic or free (the plane-strain strip, :func:`~.love.line_influence`).
    """
    if adhesive:
        names = ", ".join(type(e).__name__ for e in settings.effects if e.functional is not None)
        raise ValueError(f"effects: {names} acts on maps (2-D heights) only; a profile (1-D heights) takes the "
                         "elastic solver and the plasticity cap (hardness): remove the adhesion effect, or "
                         "solve a map")
    if settings.array_backend != "numpy":
        raise ValueError(f"array_backend {settings.array_backend!r} solves maps (2-D heights) only; a profile "
                         "(1-D heights) is solved on the host: set array_backend to 'numpy'")


def solve_step(heights, p0: float, settings: SolverSettings | None = None, *, initial_pressure=None,
               **options) -> StepResult:
    """Solve the contact for one mean pressure.

    Parameters
    ----------
    heights : array_like, shape (n, n), (nx, ny), or (n,) for a profile
        Rigid surface heights [length]; the highest points touch first; as in
        :func:`solve_contact`.
    p0 : float
        Applied mean pressure [pressure]: ``0 < p0``, ``p0 < hardness`` if a
        hardness is given, and ``p0 * L / (e_star * s)`` in
        :data:`~.units.LOAD_RANGE` (``s`` the rms height, ``L`` the float ``length`` or ``Lx``).
    settings : SolverSettings, optional
        The half-space, iteration and effects (defaults when omitted).
    initial_pressure : array_like, same shape as ``heights``, optional
        Starting pressure (clipped to ``[0, hardness]`` and brought to mean
        ``p0``); uniform ``p0`` when omitted.
    **options
        Fields of :class:`SolverSettings` replacing those of ``settings`` (``e_star``, ``length``,
        ``tol``, ...), and ``hardness`` (adds the plasticity cap).

    Returns
    -------
    StepResult
        Fields are fresh arrays owned by the caller.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    p0_f = real_scalar("p0", p0, "a finite number > 0")
    if not (math.isfinite(p0_f) and p0_f > 0):
        raise ValueError(f"p0 must be a finite number > 0, got {p0!r}")
    solver = prepare(heights, np.array([p0_f]), "p0", settings, options)
    shape = np.shape(heights)  # the user's: (n,) for a profile, whose solver shape is (n, 1)
    init = None
    if initial_pressure is not None:
        init = validate_heights(initial_pressure, name="initial_pressure", square=False, profile=True)
        if init.shape != shape:
            raise ValueError(f"initial_pressure must have shape {shape}, the shape of heights, "
                             f"got {init.shape}")
        init = init.reshape(solver.shape)
    t0 = time.perf_counter()
    st, gap = solver.solve(p0_f, initial=init, keep_gap=True)
    wall = time.perf_counter() - t0
    return StepResult(p0_f, st.pressure.reshape(shape).copy(), gap.reshape(shape), st.area, st.mean_gap, st.perimeter,
                      st.iterations, st.residual, st.converged, wall,
                      st.effect_columns.get("plastic_area_fraction"),
                      st.effect_columns.get("plastic_load_fraction"))


#: How each load step after the first starts (``warm_start`` of :func:`solve_contact`).
WARM_STARTS = ("extrapolated", "scaled")


@dataclass(frozen=True)
class StepView:
    """What an observer of a solve sees of one load step (fields are the solver's: copy to keep them).

    Attributes
    ----------
    step : int
        1-based load step.
    p0 : float
        Applied mean pressure [pressure].
    pressure : numpy.ndarray, shape (nx, ny)
        Contact pressure [pressure] (host array).
    gap : numpy.ndarray or None, shape (nx, ny)
        Gap [length] where an observer asked for it (``needs_gap = True``) or the step's fields are
        stored; else None.
    mask : numpy.ndarray of bool, shape (nx, ny)
        The contact set.
    iterations : int
        Iterations of the step.
    converged : bool
        The step's final check passed.
    """

    step: int
    p0: float
    pressure: np.ndarray
    gap: np.ndarray | None
    mask: np.ndarray
    iterations: int
    converged: bool


def solve_contact(heights, pressures, settings: SolverSettings | None = None, *, store_fields=False,
                  progress=None, observers=(), warm_start: str = "extrapolated", **options) -> xr.Dataset:
    """Solve the normal contact of a rigid rough surface on an elastic half-space.

    Parameters
    ----------
    heights : array_like, shape (n, n), (nx, ny); (n,) a profile; (B, nx, ny) a batch (``solve_contact_batch``)
        Rigid surface heights [length] on the cell (periodic, or the whole patch for
        ``boundary="free"``), axis 0 = x; the highest points touch first. Any ``nx, ny >= 4``;
        ``nx != ny`` needs ``length=(Lx, Ly)``. A profile (``n >= 4`` points, a float ``length``) is
        solved in plane strain (:func:`check_profile` says what it takes): ``area_fraction`` is the
        contact length fraction, ``contact_perimeter`` the contact intervals' ends per unit length,
        fields ``x`` only, global attribute ``surface_dimension = 1``.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures ``p0 > 0`` [pressure, ``e_star``'s unit], ``p0 L / (e_star s)`` in
        :data:`~.units.LOAD_RANGE` (``s`` the rms height, ``L`` or ``Lx``), below any cap; increasing is best.
    settings : SolverSettings, optional
        The half-space, the iteration, the effects and the unit labels; defaults when omitted.
    store_fields : bool or iterable of int
        ``True`` stores ``contact_pressure`` and ``gap`` for every step (dims ``step, x, y``); 1-based
        step numbers store only those (dims ``field_step, x, y``).
    observers : sequence
        Each with ``observe(step)`` (a :class:`StepView` after every step; with the gap if the observer
        has ``needs_gap = True``) and ``dataset(steps)`` (merged, in order), e.g.
        :class:`~roughcontact.statistics.clusters.ClusterObserver` (the ``cluster_*`` statistics) or
        ``PressureDistribution``.
    warm_start : {"extrapolated", "scaled"}
        A step starts from the last two solutions extrapolated in the load, or the last one scaled.
    progress : callable, optional
        Called after each load step as ``progress(step, p0, area_fraction, iterations, converged,
        seconds)`` (``step`` 1-based, ``seconds`` the step's wall time).
    **options
        Fields of :class:`SolverSettings` replacing those of ``settings``, and ``hardness``
        [pressure] (adds :class:`~.effects.PlasticityCap`: the pressure capped, > every p0).

    Returns
    -------
    xarray.Dataset
        Dimension ``step``: ``pressure``, ``area_fraction``, ``mean_contact_pressure``, ``mean_gap``,
        ``contact_perimeter``, ``iterations``, ``residual``, ``converged``, ``wall_time``, ``solver_path`` (a CF
        flag: the iteration that ended the step), ``contact_nodes`` and ``largest_patch_nodes``
        (:func:`~roughcontact.statistics.patches.contact_patches`), each effect's variables; stored fields.
        CF ``units`` and ``long_name`` on each; global attributes: the settings, the cell
        (:meth:`~.core.cell.Cell.solver_attrs`), ``boundary``, ``elastic_method``. ``converged``: the final check
        of docs/solver.md ("Convergence criterion") passed on a freshly recomputed displacement.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    if _is_batch(heights):  # B surfaces of one grid
        return _batch(heights, pressures, settings, store_fields, progress, observers, options)
    p = validate_pressures(pressures)
    store = validate_store(store_fields, p.size)
    _check_progress(progress, warm_start)
    solver = prepare(heights, p, "pressures", settings, options)
    observers = _check_observers(observers, profile=Cell.of(solver.shape, solver.settings.length).line)
    cols, iters, conv, paths, fields = _run_steps(solver, p, store, progress, observers, scaled=warm_start == "scaled")
    return _observed(_dataset(solver, p, cols, iters, conv, paths, fields, store_fields), observers)


def _check_progress(progress, warm_start: str = "extrapolated") -> None:
    """``progress`` a callable or None and ``warm_start`` one of :data:`WARM_STARTS`, else a ValueError."""
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be a callable or None, got {type(progress).__name__} {progress!r}")
    if warm_start not in WARM_STARTS:
        raise ValueError(f"warm_start must be one of {WARM_STARTS}, got {warm_start!r}")


def _is_batch(heights) -> bool:
    """Whether ``heights`` is a ``(B, nx, ny)`` batch; ragged input is not (its validation names it)."""
    try:
        return np.ndim(heights) == 3
    except ValueError:  # numpy refuses to size a ragged nested sequence
        return False


def _batch(heights, pressures, settings, store_fields, progress, observers, options) -> xr.Dataset:
    """:func:`solve_contact` of a ``(B, nx, ny)`` batch: :func:`~.batch.solve_contact_batch`, refusing what
    it does not produce."""
    from .batch import solve_contact_batch

    if not (store_fields is False or store_fields is None) or tuple(observers or ()):
        raise ValueError("a batch of surfaces (heights of shape (B, nx, ny)) stores no fields and takes no "
                         "observers; solve each case with 2-D heights for those")
    return solve_contact_batch(heights, pressures, settings, progress=progress, **options)


def _observed(ds: xr.Dataset, observers) -> xr.Dataset:
    """``ds`` with each observer's per-step variables."""
    for observer in observers:
        ds = ds.merge(observer.dataset(ds["step"].values).drop_vars("step"), combine_attrs="override")
    return ds


def _check_observers(observers, profile: bool = False) -> tuple:
    """``observers`` as a tuple, each with ``observe`` and ``dataset`` (else a ValueError naming it); for a
    ``profile``, none that says ``profiles = False`` (a map's statistic)."""
    try:
        observers = tuple(observers)
    except TypeError:
        raise ValueError(f"observers must be a sequence of observers, got {type(observers).__name__}") from None
    for ob in observers:
        if not (callable(getattr(ob, "observe", None)) and callable(getattr(ob, "dataset", None))):
            raise ValueError(f"observers: {type(ob).__name__} has no observe(step) and dataset(steps) methods")
        if profile and not getattr(ob, "profiles", True):
            raise ValueError(f"observers: {type(ob).__name__} is a map's statistic (2-D heights) and does not apply "
                             "to a profile (1-D heights): remove it")
    return observers


def _dataset(solver: ContactSolver | AdhesiveSolver, p, cols, iters, conv, paths, fields,
             store_fields) -> xr.Dataset:
    """The solve's output dataset (:func:`solve_contact`'s Returns)."""
    s = solver.settings
    cell = Cell.of(solver.shape, s.length)
    sides, grid = cell.solver_attrs()
    if isinstance(solver, AdhesiveSolver):
        name, description = ADHESIVE_SOLVER_NAME, ADHESIVE_SOLVER_DESCRIPTION
    else:
        name, description = SOLVER_NAME, solver_description(solver.periodic, cell.square, cell.line)
    attrs = {"e_star": s.e_star, **sides, "tol": s.tol, "max_iter": s.max_iter, "threads": s.threads,
             "fft_backend": solver.backend, **grid, "solver": name, "solver_description": description}
    ds = to_dataset(p, cols, iters, conv, fields, store_fields, solver.shape, attrs, solver.effects, paths=paths,
                    length_unit=s.length_unit, pressure_unit=s.pressure_unit, path_names=solver.paths,
                    long_names=solver.long_names)
    ds.attrs["elastic_method"] = solver.method
    ds.attrs["boundary"] = s.boundary
    for effect in solver.effects:
        for name, variable in effect.after_steps(solver, s.length_unit, s.pressure_unit).items():
            ds[name] = variable
    return ds


def _run_steps(solver: ContactSolver | AdhesiveSolver, p: np.ndarray, store: set, progress=None,
               observers=(), scaled: bool = False):
    """Solve every load step; per-step columns, iterations, flags, path codes, stored fields."""
    n_steps = p.size
    names = ["area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter", "residual",
             "wall_time"] + [v for e in solver.effects for v in e.variables()]
    cols = {k: np.empty(n_steps) for k in names}
    cols.update({k: np.empty(n_steps, dtype=np.int64) for k in PATCH_LONG_NAMES})
    iters = np.empty(n_steps, dtype=np.int64)
    conv = np.empty(n_steps, dtype=bool)
    paths = np.empty(n_steps, dtype=np.int8)
    fields_p, fields_g, field_steps = [], [], []
    needs_gap = any(getattr(ob, "needs_gap", False) for ob in observers)
    last = None
    for k, p0 in enumerate(p):
        p0 = float(p0)
        t0 = time.perf_counter()
        initial = None if last is None else last * (p0 / last.mean())
        st, gap = solver.solve(p0, initial=initial, keep_gap=k + 1 in store or needs_gap)
        if scaled:
            last = st.pressure.copy()
        cols["wall_time"][k] = time.perf_counter() - t0
        cols["area_fraction"][k] = st.area
        cols["mean_contact_pressure"][k] = p0 / st.area
        cols["mean_gap"][k] = st.mean_gap
        cols["contact_perimeter"][k] = st.perimeter
        cols["residual"][k] = st.residual
        cols["contact_nodes"][k], cols["largest_patch_nodes"][k] = contact_patches(st.mask, solver.periodic)
        for name, value in st.effect_columns.items():
            cols[name][k] = value
        iters[k] = st.iterations
        conv[k] = st.converged
        paths[k] = solver.paths.index(st.path)
        if k + 1 in store:
            fields_p.append(st.pressure.copy())
            fields_g.append(gap)
            field_steps.append(k + 1)
        view = StepView(k + 1, p0, st.pressure, gap, st.mask, int(st.iterations), bool(st.converged))
        for observer in observers:
            observer.observe(view)
        if progress is not None:
            progress(k + 1, p0, st.area, st.iterations, st.converged, cols["wall_time"][k])
    return cols, iters, conv, paths, (fields_p, fields_g, field_steps)
