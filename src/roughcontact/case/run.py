"""One way to run a contact case: :class:`ContactCase` (what to compute) and :func:`run_case` (computing it).

A case is one surface under one load schedule with one set of solver settings and outputs. The
pipeline's contact jobs (:func:`roughcontact.pipeline.case.contact_case` builds their case from a scene's
``contact`` block), the accuracy study and the κ-gap study all build a :class:`ContactCase` and call
:func:`run_case`: it is the only caller of the solver outside :mod:`roughcontact.solver`, and
:class:`~.loading.LoadSchedule` the only load schedule.

Examples
--------
>>> from roughcontact.solver import SolverSettings
>>> from roughcontact.surfaces.synthetic import generate_surface
>>> h = generate_surface(64, 2, 16, 0.8, seed=0, rms_slope=0.1)
>>> case = ContactCase(LoadSchedule(5, p_max=0.005), SolverSettings(tol=1e-9))
>>> ds = run_case(h, case, length=1.0, rms_slope=0.1)
>>> ds.sizes["step"], ds.attrs["load_p0_max"]
(5, 0.005)

A batch (heights of shape ``(B, nx, ny)``, one load schedule for all) gives one dataset per case:

>>> hs = np.stack([generate_surface(64, 2, 16, 0.8, seed=s, rms_slope=0.1) for s in range(3)])
>>> [d.attrs["batch_size"] for d in run_case(hs, case, length=1.0, rms_slope=[0.1] * 3)]
[3, 3, 3]

A case split over MPI ranks (``ContactCase(..., ranks=R)``) runs from its surface's file, every rank reading
its own rows: :func:`run_case_on_ranks`.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from ..analysis.stiffness import stiffness_variable
from ..core.cell import Cell
from ..solver import SolverSettings, solve_contact, step_notes
from ..solver.batch.solver import BATCH_METHOD
from ..statistics.clusters import ClusterObserver
from .loading import LoadSchedule
from .outputs import contact_observers, full_contact_variable
from .progress import step_logger

#: The outputs a case computes when it names none.
NO_OUTPUTS = {"fields": [], "clusters": False}


def default_settings() -> SolverSettings:
    """A case's solver settings when it gives none: :class:`~roughcontact.solver.SolverSettings`' defaults, the
    iteration and the array backend left to the options at the solve (``method=None``, ``array_backend=None``)."""
    return SolverSettings(method=None, array_backend=None)


@dataclass(frozen=True)
class ContactCase:
    """What to compute for one surface: the solver's settings, one load schedule and the outputs asked for.

    Attributes
    ----------
    schedule : LoadSchedule
        The load steps (resolved per surface by :func:`run_case`; relative to ``settings.e_star``).
    settings : roughcontact.solver.SolverSettings
        The solver's settings: modulus, tolerance, iteration, boundary, effects, units, threads, array backend.
        Their ``length`` is replaced by the surface's own (:func:`run_case`'s ``length``).
    outputs : mapping
        ``fields`` (1-based steps whose pressure and gap to store), ``clusters`` (bool), and optionally
        ``stiffness`` (bool), ``full_contact_load`` (bool), ``pressure_distribution`` (``{"bins", "max"}``).
    warm_start : {"extrapolated", "scaled"}
        How a step after the first starts (:func:`roughcontact.solver.solve_contact`).
    ranks : int
        MPI ranks the case is split over: 1 solves it in this process (:func:`run_case`), more in ``ranks``
        processes of :mod:`roughcontact.solver.mpi` (:func:`run_case_on_ranks`).
    """

    schedule: LoadSchedule
    settings: SolverSettings = field(default_factory=default_settings)
    outputs: Mapping = field(default_factory=lambda: dict(NO_OUTPUTS))
    warm_start: str = "extrapolated"
    ranks: int = 1

    def solver_settings(self, length) -> SolverSettings:
        """The settings of :func:`roughcontact.solver.solve_contact` for a cell of ``length`` (float or pair)."""
        return dataclasses.replace(self.settings, length=length)


def run_case(heights: np.ndarray, case: ContactCase, *, length, rms_slope, log=None, name=None,
             observers: Sequence = ()) -> xr.Dataset | list[xr.Dataset]:
    """Solve one surface (or a batch of them) as ``case`` asks: loads resolved, every step solved, outputs added.

    Parameters
    ----------
    heights : numpy.ndarray, shape (nx, ny) or (B, nx, ny)
        The surface [length], or ``B`` surfaces of one grid solved together
        (:func:`roughcontact.solver.solve_contact_batch`).
    case : ContactCase
        What to compute. A batch runs one load schedule for all its cases: their resolved loads must be
        equal (loads relative to E*), and it computes neither stored fields, clusters, P(p), effects nor
        a ``target_area`` search (each refused with a ``ValueError``; a scene's ``contact.solver.batch`` is
        refused with them before any job, :func:`roughcontact.pipeline.config.checks.check_batch`).
    length : float or (float, float)
        The cell's side ``L`` or sides ``(Lx, Ly)`` [length].
    rms_slope : float, or sequence of B floats for a batch
        The surface's rms slope h' (loads relative to it, κ); a batch's, one per case.
    log : logging.Logger, optional
        Where each step's line (with the time left), the loads and the warnings go.
    name : str, or sequence of B str for a batch, optional
        The case's name, at the start of its warnings (jobs' lines meet in one console).
    observers : sequence
        More observers of each step (:class:`roughcontact.solver.solve.StepView`), besides those
        ``case.outputs`` asks for (none for a batch).

    Returns
    -------
    xarray.Dataset or list of xarray.Dataset
        :func:`roughcontact.solver.solve_contact`'s dataset, with ``contact_stiffness`` and
        ``full_contact_pressure`` where asked, and the load's attributes (``load_*``,
        :meth:`~.loading.LoadSchedule.resolve`). A batch gives one such dataset per case, in order: the
        batched solve's case ``b`` (its per-case variables over ``step``), with ``wall_time`` and
        ``rounds`` of the whole batch and the attributes ``batch_size`` and ``check_every``.
    """
    if case.ranks != 1:
        raise ValueError(f"run_case: a case over {case.ranks} MPI ranks reads its surface from a file on every rank; "
                         "run it with run_case_on_ranks (the surface's file), or give ContactCase ranks=1")
    if np.ndim(heights) == 3:
        return _run_batch(np.asarray(heights), case, length=length, rms_slope=rms_slope, log=log, names=name,
                          observers=observers)
    settings = case.solver_settings(length)

    def area_at(p0: float) -> float:  # a target_area probe: the surface at one load
        return float(solve_contact(heights, [p0], settings).area_fraction[-1])

    case.schedule.check_final_load(settings.effects, settings.e_star, rms_slope)
    loads, load_info = case.schedule.resolve(settings.e_star, rms_slope, heights.size, area_at, log, name,
                                             cap=settings.hardness)
    outputs = case.outputs
    clusters = [ClusterObserver(length, settings.boundary == "periodic", length_unit=settings.length_unit)
                ] if outputs["clusters"] else []
    result = solve_contact(heights, loads, store_fields=outputs["fields"] or False,
                           progress=step_logger(log, len(loads)), warm_start=case.warm_start,
                           observers=[*clusters, *contact_observers(outputs, settings.e_star * rms_slope), *observers],
                           settings=settings)
    return _finished(result, heights, case, length, load_info, log, name or "case")


def _refused_over_ranks(case: ContactCase) -> list[str]:
    """What ``case`` asks that a solve over MPI ranks cannot compute (:mod:`roughcontact.solver.mpi` solves the
    periodic elastic problem and reports per-step columns), named; a scene's are refused before any job by
    :func:`roughcontact.pipeline.config.checks.check_ranks`."""
    settings = case.settings
    refused = [(bool(case.outputs.get("full_contact_load")), "outputs['full_contact_load']"),
               (settings.boundary != "periodic", f"boundary={settings.boundary!r}"),
               (settings.array_backend not in (None, "numpy"), f"array_backend={settings.array_backend!r}"),
               (settings.method not in (None, BATCH_METHOD), f"method={settings.method!r}")]
    return _beyond_per_step_columns(case) + [what for flag, what in refused if flag]


def mpi_command(launcher: str, ranks: int) -> list[str]:
    """The command that starts ``ranks`` processes: ``launcher`` (e.g. ``"mpiexec"``, ``"srun"``, or with options:
    ``"mpiexec --bind-to core"``) split into words, then ``-n ranks``.

    ``mpiexec`` not on ``PATH`` is the one beside this Python (``pip install 'roughcontact[mpi]'`` puts MPICH's
    there); a launcher found nowhere is a ``ValueError`` naming it and the remedy.
    """
    words = shlex.split(launcher)
    if not words:
        raise ValueError("contact.solver.ranks: the MPI launcher (the rule's 'mpi' resource) is empty; set it to "
                         "mpiexec (local runs) or srun (SLURM)")
    found = shutil.which(words[0])
    if found is None and words[0] == "mpiexec" and (Path(sys.executable).parent / "mpiexec").exists():
        found = str(Path(sys.executable).parent / "mpiexec")
    if found is None:
        raise ValueError(f"contact.solver.ranks: the MPI launcher {words[0]!r} (the rule's 'mpi' resource) is not "
                         "found; install one with pip install 'roughcontact[mpi]' (mpiexec), or on a cluster run "
                         "with --workflow-profile profiles/slurm (srun)")
    return [found, *words[1:], "-n", str(int(ranks))]


#: A step line of ``python -m roughcontact.solver.mpi`` (its ``_log_step``), re-logged as :func:`run_case`'s.
_MPI_STEP = re.compile(r"^step (\d+): p0=(\S+) A/A0=(\S+) iterations=(\d+) converged=(True|False) (\S+) s$")


def run_case_on_ranks(surface_file, case: ContactCase, *, shape, length, rms_slope: float,
                      launcher: str = "mpiexec", log=None, name=None) -> xr.Dataset:
    """Solve one surface over ``case.ranks`` MPI processes: :func:`run_case`'s dataset, computed by
    ``launcher -n ranks python -m roughcontact.solver.mpi`` (:mod:`roughcontact.solver.mpi`).

    Every rank reads its own rows of ``surface_file`` (the grid is split in slabs along x), so no
    process but rank 0's writer ever holds a whole field; rank 0 writes the per-step columns to a
    temporary file, read back here. The load schedule is resolved here as :func:`run_case` does and
    passed exactly (``repr`` of each p0).

    Parameters
    ----------
    surface_file : path
        A NetCDF file with ``heights`` over ``(x, y)`` (other dimensions of length 1): a surface job's file.
    case : ContactCase
        With ``ranks`` >= 1; the periodic elastic solve with per-step outputs only (stiffness allowed):
        stored fields, clusters, P(p), the full-contact load, effects, the free boundary, CuPy, another
        method and ``target_area`` are refused with a ``ValueError`` (a scene's are refused before any
        job: :func:`roughcontact.pipeline.config.checks.check_ranks`).
    shape : (int, int)
        The file's grid ``(nx, ny)``.
    length : float or (float, float)
        The cell's side ``L`` or sides ``(Lx, Ly)`` [length].
    rms_slope : float
        The surface's rms slope h' (loads relative to it, κ).
    launcher : str
        The command that starts MPI processes (:func:`mpi_command`): ``mpiexec`` locally, ``srun`` in a SLURM job.
    log : logging.Logger, optional
        Each step's line (as :func:`run_case`'s), the ranks' peak memory, the warnings.
    name : str, optional
        The case's name in warnings.

    Returns
    -------
    xarray.Dataset
        :func:`roughcontact.solver.solve_contact`'s layout (attributes ``mpi_ranks``, ``fft_library``),
        with ``contact_stiffness`` where asked and the load's attributes.

    Raises
    ------
    ValueError
        A refused setting, a launcher not found, or the MPI solver's own refusal (its one-line message).
    RuntimeError
        The MPI processes ended otherwise (the last lines of their output).
    """
    refused = _refused_over_ranks(case)
    if refused:
        raise ValueError(f"run_case_on_ranks: a case over MPI ranks computes the periodic elastic solve's per-step "
                         f"columns only, not {', '.join(refused)}; run it with run_case (ranks=1) for those")
    cell = Cell.of(shape, length)
    loads, load_info = case.schedule.resolve(case.settings.e_star, rms_slope, cell.shape[0] * cell.shape[1], None,
                                             log, name, cap=case.settings.hardness)
    with tempfile.TemporaryDirectory(prefix="roughcontact-mpi-") as tmp:
        out = Path(tmp) / "contact.nc"
        cmd = [*mpi_command(launcher, case.ranks), *_mpi_solver_args(surface_file, case, loads, cell, out)]
        if log is not None:
            log.info("%s over %d MPI ranks: %s", name or "case", case.ranks, " ".join(cmd[:cmd.index("--loads")]))
        result = _run_ranks(cmd, out, step_logger(log, len(loads)), log)
    return _finished(result, None, case, length, load_info, log, name or "case")


def _mpi_solver_args(surface_file, case: ContactCase, loads, cell: Cell, out: Path) -> list[str]:
    """``python -m roughcontact.solver.mpi`` with ``case``'s settings and ``loads`` (exact: ``repr``) writing
    ``out``."""
    sides = ["--length", repr(cell.sides[0])] + ([] if cell.square else ["--length-y", repr(cell.sides[1])])
    s = case.settings
    return [sys.executable, "-m", "roughcontact.solver.mpi", "--surface", os.fspath(surface_file),
            "--expect-ranks", str(int(case.ranks)), "--loads", *(repr(float(p)) for p in loads), *sides,
            "--e-star", repr(float(s.e_star)), "--tol", repr(float(s.tol)), "--max-iter", str(int(s.max_iter)),
            "--length-unit", s.length_unit, "--pressure-unit", s.pressure_unit, "--out", os.fspath(out)]


def _run_ranks(cmd: list[str], out: Path, progress, log) -> xr.Dataset:
    """Run the MPI command, passing its step lines to ``progress`` and its other lines to ``log`` as they come;
    the file ``out`` it wrote, loaded."""
    tail: list[str] = []
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        for line in proc.stdout:
            line = line.rstrip("\n")
            tail = [*tail[-19:], line]
            step = _MPI_STEP.match(line)
            if step is not None and progress is not None:
                progress(int(step[1]), float(step[2]), float(step[3]), int(step[4]), step[5] == "True", float(step[6]))
            elif step is None and line and log is not None:
                log.info("mpi: %s", line)
    if proc.returncode == 2:  # the MPI solver's bad input: its own one line
        errors = [line.removeprefix("error: ") for line in tail if line.startswith("error: ")]
        raise ValueError(errors[-1] if errors else "\n".join(tail))
    if proc.returncode != 0:
        raise RuntimeError(f"the MPI solve ({' '.join(cmd[:4])} ...) ended with exit status {proc.returncode}; its "
                           "last lines:\n" + "\n".join(tail))
    if not out.is_file():  # a launcher that ends well without running the solve (a wrapper that drops it)
        raise RuntimeError(f"the MPI solve ({' '.join(cmd[:4])} ...) ended with status 0 but wrote no file; the "
                           "launcher (the rule's 'mpi' resource) must run the command it is given")
    return xr.load_dataset(out)


def _finished(result: xr.Dataset, heights: np.ndarray, case: ContactCase, length, load_info: dict, log,
              name: str) -> xr.Dataset:
    """One case's solve with the outputs computed after it (stiffness, full-contact load), its load
    attributes and its warnings logged: the same for a single case and for each case of a batch."""
    if case.outputs.get("stiffness"):
        result["contact_stiffness"] = stiffness_variable(result, case.settings.length_unit, case.settings.pressure_unit)
    if case.outputs.get("full_contact_load"):
        result["full_contact_pressure"] = full_contact_variable(heights, length, case.settings.e_star,
                                                                result["pressure"].attrs["units"])
    result.attrs.update(load_info)
    if log is not None:
        _warn(log, result, name, case.settings.tol)
    return result


def _run_batch(heights: np.ndarray, case: ContactCase, *, length, rms_slope, log, names,
               observers: Sequence) -> list[xr.Dataset]:
    """:func:`run_case` of ``B`` surfaces under one load schedule: one batched solve, split into its cases."""
    n_cases = heights.shape[0]
    slopes = _per_case(rms_slope, n_cases, "rms_slope", float)
    names = _per_case(names if names is not None else [f"case {b}" for b in range(n_cases)], n_cases, "name", str)
    _check_batchable(case, observers)
    e_star = case.settings.e_star
    resolved = [case.schedule.resolve(e_star, slope, heights[0].size, None, cap=case.settings.hardness)
                for slope in slopes]
    loads = resolved[0][0]
    for (other, _), label in zip(resolved[1:], names[1:], strict=True):
        if other != loads:
            raise ValueError(f"run_case: a batch runs one load schedule, but {label} resolves to other loads than "
                             f"{names[0]} (final p0 {other[-1]:.17g} against {loads[-1]:.17g}; load.relative_to "
                             f"{case.schedule.relative_to!r}): batch cases whose loads are equal, or run them one "
                             "by one")
    if log is not None:
        log.info("batch of %d cases (%s .. %s): p0 from %.6g to %.6g (p0/E* up to %.4g) in %d steps", n_cases,
                 names[0], names[-1], loads[0], loads[-1], loads[-1] / e_star, len(loads))
    result = solve_contact(heights, loads, case.solver_settings(length), progress=step_logger(log, len(loads)))
    return [_finished(result.isel(case=b).drop_vars("case"), heights[b], case, length, resolved[b][1], log, label)
            for b, label in enumerate(names)]


def _per_case(values, n_cases: int, what: str, kind) -> list:
    """``values`` as a list of ``n_cases`` (one value for every case when it is a single one), else a ValueError."""
    if isinstance(values, (str, bytes)) or np.ndim(values) == 0:
        values = [values] * n_cases
    values = [kind(v) for v in values]
    if len(values) != n_cases:
        raise ValueError(f"run_case: a batch of {n_cases} surfaces needs {n_cases} {what} values (one per case), "
                         f"got {len(values)}")
    if kind is float and not all(math.isfinite(v) and v > 0 for v in values):
        raise ValueError(f"run_case: every {what} of a batch must be a finite number > 0, got {values}")
    return values


def _beyond_per_step_columns(case: ContactCase) -> list[str]:
    """What ``case`` asks beyond the per-step columns of one load schedule solved with the default warm start
    (what a batch and a solve over MPI ranks compute), named: stored fields, clusters, P(p), effects, a
    ``target_area`` search, another warm start."""
    outputs = case.outputs
    asked = [(bool(outputs.get("fields")), "outputs['fields'] (stored fields)"),
             (bool(outputs.get("clusters")), "outputs['clusters']"),
             ("pressure_distribution" in outputs, "outputs['pressure_distribution'] (P(p))"),
             (bool(case.settings.effects), f"effects ({', '.join(e.name for e in case.settings.effects)})"),
             (case.schedule.target_area is not None, "schedule.target_area (each case's own load search)"),
             (case.warm_start != "extrapolated", f"warm_start={case.warm_start!r}")]
    return [what for flag, what in asked if flag]


def _check_batchable(case: ContactCase, observers: Sequence) -> None:
    """What a batched solve cannot produce, refused naming the case's field and the remedy."""
    asked = _beyond_per_step_columns(case) + (["observers"] if tuple(observers) else [])
    if asked:
        raise ValueError(f"run_case: a batch of surfaces (heights of shape (B, nx, ny)) computes per-step columns "
                         f"only, not {', '.join(asked)}; run each case with 2-D heights for those")


def _warn(log, result: xr.Dataset, name: str, tol: float) -> None:
    """The solve's step notes (fallbacks, stalls) and its unconverged steps, as warnings naming the case."""
    for note in step_notes(result):
        log.warning("%s: %s", name, note)
    unconverged = int((~result.converged.values).sum())
    if unconverged:
        log.warning("%s: %d of %d load steps did not converge to tol=%g (max residual %.3g); "
                    "they are flagged in the output's 'converged' variable",
                    name, unconverged, result.sizes["step"], tol, float(result.residual.max()))
