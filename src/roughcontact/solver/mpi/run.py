"""The MPI solve of one case: :func:`solve_contact_mpi`, the step loop and rank 0's dataset.

What is gathered, and why: every per-step output (A/A0, mean pressure, mean gap, perimeter,
residual, iterations, converged, contact nodes) is a collective reduction, so every rank holds it already and
rank 0 builds the dataset from its own copy: nothing is gathered for them. The largest contact patch is
joined on rank 0 from each slab's patches on its two edge rows and its largest inner one
(:func:`~roughcontact.statistics.patches.slab_patches`: two rows of ids a rank, not its field) and broadcast.
Fields are gathered to rank 0 only on request (``fields=True``: the last step's pressure and gap, ``Gatherv`` of the
slabs' rows), because a whole field is what the split exists to avoid holding on one process:
8 bytes a node, 0.5 GB at N = 8192 per field, 34 GB at N = 65536.
"""

from __future__ import annotations

import time

import numpy as np
import xarray as xr

from ...statistics.patches import PATCH_LONG_NAMES
from ..batch.solver import BATCH_METHOD
from ..results import periodic_elastic_attrs, to_dataset
from ..settings import SolverSettings
from ..validation import finite_float64, validate_pressures
from .slabs import Slabs
from .solver import MpiSolver, collective


class MpiUnavailableError(RuntimeError):
    """The MPI solver was asked for where mpi4py (or an MPI runtime) cannot be imported."""


def world():
    """``mpi4py.MPI.COMM_WORLD``, or :class:`MpiUnavailableError` saying how to install it."""
    try:
        from mpi4py import MPI
    except (ImportError, RuntimeError) as exc:  # no mpi4py; mpi4py's wheel without an MPI library to load
        raise MpiUnavailableError(f"the MPI solver needs mpi4py and an MPI runtime, not importable here ({exc}); "
                                  "install them with pip install 'roughcontact[mpi]'") from exc
    return MPI.COMM_WORLD


def check_settings(settings: SolverSettings, fields_shape) -> SolverSettings:
    """``settings`` checked for the grid, refusing what the MPI solver does not run, naming it."""
    s = settings.checked(fields_shape)
    if s.boundary != "periodic":
        raise ValueError(f"the MPI solver runs the periodic half-space only, got boundary={s.boundary!r}: the free "
                         "boundary's 2n x 2n padded grid is not split across ranks; solve it with solve_contact")
    if s.effects:
        names = ", ".join(type(e).__name__ for e in s.effects)
        raise ValueError(f"the MPI solver runs the elastic solver only, not the effects ({names}); solve the case "
                         "with solve_contact")
    if s.method != BATCH_METHOD:
        raise ValueError(f"the MPI solver runs the elastic method {BATCH_METHOD!r} only, got {s.method!r}")
    if s.array_backend != "numpy":
        raise ValueError(f"the MPI solver runs on the numpy array backend only, got {s.array_backend!r}")
    return s


def solve_contact_mpi(heights, shape, pressures, settings: SolverSettings | None = None, *, comm=None,
                      fft_library: str = "slab", fields: bool = False, progress=None,
                      **options) -> xr.Dataset | None:
    """Solve one case whose grid is split in slabs over the MPI ranks of ``comm`` (collective: every rank calls it).

    Parameters
    ----------
    heights : array_like, shape (x1 - x0, ny)
        This rank's rows ``[x0, x1)`` of the heights [length] (:class:`.slabs.Slabs` of ``shape``
        over ``comm``: :func:`rows_of` says which).
    shape : (int, int)
        The whole grid ``(nx, ny)``, axis 0 = x split over the ranks.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures [pressure], as for :func:`~roughcontact.solver.solve_contact`.
    settings : SolverSettings, optional
        As there; the periodic ``"pk-fourier-f32"`` iteration without effects on numpy.
    comm : mpi4py.MPI.Comm, optional
        The ranks (``COMM_WORLD`` by default).
    fft_library : str
        ``"slab"`` (default) or ``"mpi4py-fft"`` (:mod:`.slabs`).
    fields : bool
        Gather the last step's ``contact_pressure`` and ``gap`` fields to rank 0 (module docstring).
    progress : callable, optional
        On rank 0, after each step: ``progress(step, p0, area_fraction, iterations, converged, seconds)``.
    **options
        Fields of :class:`SolverSettings` replacing those of ``settings``.

    Returns
    -------
    xarray.Dataset or None
        On rank 0, :func:`~roughcontact.solver.solve_contact`'s dataset (dims ``step``; with
        ``fields``, ``contact_pressure`` and ``gap`` over ``field_step, x, y``), attributes as there
        plus ``mpi_ranks`` and ``fft_library``; ``fft_backend`` is ``"mpi-slab"`` (FFTW's slab transforms),
        ``"mpi-slab-mkl"`` (MKL's, ``ROUGHCONTACT_FFT=mkl``), ``"mpi-slab-scipy"`` (SciPy's, ``ROUGHCONTACT_FFT=numpy``
        or no pyFFTW) or ``"mpi-mpi4py-fft"``. None on the other ranks.

    Raises
    ------
    ValueError
        On every rank, for invalid input on any rank: more ranks than rows, a bad height or load,
        the free boundary, effects, another method.
    MpiUnavailableError
        Where mpi4py cannot be imported and no ``comm`` was given.
    """
    comm = world() if comm is None else comm
    nx, ny = (int(shape[0]), int(shape[1]))
    slabs = collective(comm, lambda: Slabs((nx, ny), comm.size, comm.rank))
    p = collective(comm, lambda: validate_pressures(pressures))
    s = collective(comm, lambda: check_settings(SolverSettings.from_options(settings, **options), (nx, ny)))
    h = collective(comm, lambda: _local_heights(heights, slabs))
    solver = collective(comm, lambda: MpiSolver(comm, slabs, h, s, fft_library))
    collective(comm, lambda: solver.check_loads(p, "pressures"))
    cols, iters, conv, paths = _run_steps(solver, p, progress if comm.rank == 0 else None)
    field = _gather_fields(solver) if fields else None
    solver.close()
    if comm.rank != 0:
        return None
    return _dataset(solver, p, cols, iters, conv, paths, field, fft_library)


def rows_of(shape, comm) -> tuple[int, int]:
    """``(x0, x1)``: the rows of an ``(nx, ny)`` grid this rank of ``comm`` holds (:class:`.slabs.Slabs`)."""
    s = Slabs(shape, comm.size, comm.rank)
    return s.x0, s.x1


def _local_heights(heights, slabs: Slabs) -> np.ndarray:
    """This rank's rows, checked: real, finite, of the slab's shape (the grid at least 4 x 4)."""
    nx, ny = slabs.shape
    if min(nx, ny) < 4:
        raise ValueError(f"heights must be at least 4 x 4 (nx, ny >= 4), got shape {slabs.shape}")
    name = f"heights (rows {slabs.x0}..{slabs.x1 - 1})"
    a = np.asarray(heights)
    if a.dtype == object or a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real numeric array, got dtype {a.dtype}")
    if a.shape != slabs.local_shape:
        raise ValueError(f"heights: this rank holds rows {slabs.x0}..{slabs.x1 - 1} of the grid {slabs.shape}, "
                         f"shape {slabs.local_shape}; got {a.shape}")
    return finite_float64(a, name)


def _run_steps(solver: MpiSolver, p: np.ndarray, progress):
    """Every load step: per-step columns (wall time the slowest rank's), iterations, flags, path codes."""
    n = p.size
    names = ("area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter", "residual", "wall_time")
    cols = {k: np.empty(n) for k in names}
    cols.update({k: np.empty(n, dtype=np.int64) for k in PATCH_LONG_NAMES})
    iters = np.empty(n, dtype=np.int64)
    conv = np.empty(n, dtype=bool)
    paths = np.empty(n, dtype=np.int8)
    for k, p0 in enumerate(p):
        t0 = time.perf_counter()
        out = solver.solve(float(p0))
        cols["wall_time"][k] = max(solver.comm.allgather(time.perf_counter() - t0))
        for name in (*names[:-1], *PATCH_LONG_NAMES):
            cols[name][k] = out[name][0]
        iters[k], conv[k], paths[k] = out["iterations"][0], out["converged"][0], out["solver_path"][0]
        if progress is not None:
            progress(k + 1, float(p0), cols["area_fraction"][k], int(iters[k]), bool(conv[k]),
                     cols["wall_time"][k])
    return cols, iters, conv, paths


def _gather_fields(solver: MpiSolver):
    """The last step's pressure and gap, whole, on rank 0 (``Gatherv`` of the rows); None elsewhere."""
    comm, slabs = solver.comm, solver.slabs
    nx, ny = slabs.shape
    out = []
    for part in solver.fields():
        whole = np.empty((nx, ny)) if comm.rank == 0 else None
        counts = [(x1 - x0) * ny for x0, x1 in slabs.rows]
        offsets = [x0 * ny for x0, _ in slabs.rows]
        comm.Gatherv(np.ascontiguousarray(part), [whole, (counts, offsets)] if comm.rank == 0 else None, root=0)
        out.append(whole)
    return out


def _dataset(solver: MpiSolver, p, cols, iters, conv, paths, field, fft_library: str) -> xr.Dataset:
    """Rank 0's dataset: :func:`~roughcontact.solver.solve_contact`'s layout and attributes."""
    s = solver.settings
    attrs = {**periodic_elastic_attrs(s, solver.shape, solver.backend), "mpi_ranks": solver.comm.size,
             "fft_library": fft_library}
    fields = ([field[0]], [field[1]], [p.size]) if field is not None else ([], [], [])
    ds = to_dataset(p, cols, iters, conv, fields, [p.size] if field is not None else False, solver.shape, attrs,
                    (), paths=paths, length_unit=s.length_unit, pressure_unit=s.pressure_unit)
    ds["wall_time"].attrs["long_name"] = "wall-clock time of the load step (the slowest MPI rank's)"
    ds.attrs["elastic_method"] = solver.method
    ds.attrs["boundary"] = "periodic"
    return ds
