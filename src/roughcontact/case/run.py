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
>>> [ds] = run_case(h, case, length=1.0, rms_slope=0.1)
>>> ds.sizes["step"], ds.attrs["load_p0_max"]
(5, 0.005)

A batch (heights of shape ``(B, nx, ny)``, one load schedule for all) gives one dataset per case:

>>> hs = np.stack([generate_surface(64, 2, 16, 0.8, seed=s, rms_slope=0.1) for s in range(3)])
>>> [d.attrs["batch_size"] for d in run_case(hs, case, length=1.0, rms_slope=[0.1] * 3)]
[3, 3, 3]

A case split over MPI ranks (``ContactCase(..., ranks=R)``) runs from its surface's file, every rank reading
its own rows: ``run_case(path, case, ...)``, one dataset as well.
"""

from __future__ import annotations

import dataclasses
import json
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
        MPI ranks the case is split over: 1 solves it in this process, more in ``ranks`` processes that
        :func:`run_case` starts from the surface's file (:mod:`roughcontact.case.__main__`).
    """

    schedule: LoadSchedule
    settings: SolverSettings = field(default_factory=default_settings)
    outputs: Mapping = field(default_factory=lambda: dict(NO_OUTPUTS))
    warm_start: str = "extrapolated"
    ranks: int = 1

    def solver_settings(self, length) -> SolverSettings:
        """The settings of :func:`roughcontact.solver.solve_contact` for a cell of ``length`` (float or pair)."""
        return dataclasses.replace(self.settings, length=length)


def run_case(surfaces, case: ContactCase, *, length, rms_slope, log=None, name=None, observers: Sequence = (),
             launcher: str = "mpiexec", shape=None, comm=None) -> list[xr.Dataset]:
    """Solve a group of cases as ``case`` asks: loads resolved, every step solved, outputs added; one dataset a case.

    A group is what one solve computes together: one surface, ``B`` surfaces of one grid solved as a batch
    (:func:`roughcontact.solver.solve_contact_batch`), or one surface split over ``case.ranks`` MPI processes.

    Parameters
    ----------
    surfaces : numpy.ndarray, shape (nx, ny), (n,) or (B, nx, ny); or a path
        The surface [length] (a map, or a profile of ``n`` points), or ``B`` surfaces of one grid. With
        ``case.ranks`` > 1, the path of a NetCDF file with ``heights`` over ``(x, y)`` (other dimensions of
        length 1: a surface job's file), of which every rank reads its own rows.
    case : ContactCase
        What to compute. A batch runs one load schedule (the resolved loads must be equal: loads relative to
        E*) and, as a case over ranks, computes the per-step columns only (stiffness and, for a batch, the
        full-contact load allowed): stored fields, clusters, P(p), effects, ``target_area`` or another warm start
        are each refused with a ``ValueError`` (a scene's before any job:
        :mod:`roughcontact.pipeline.config.checks`); over ranks also the free boundary and CuPy.
    length : float or (float, float)
        The cell's side ``L`` or sides ``(Lx, Ly)`` [length].
    rms_slope : float, or sequence of B floats for a batch
        The surface's rms slope h' (loads relative to it, κ); a batch's, one per case.
    log : logging.Logger, optional
        Where each step's line (with the time left), the loads and the warnings go.
    name : str, or sequence of B str for a batch, optional
        The case's name, at the start of its warnings (jobs' lines meet in one console).
    observers : sequence
        More observers of each step (:class:`roughcontact.solver.solve.StepView`) of one surface in this process.
    launcher, shape, comm
        Over ranks: the command that starts MPI processes (:func:`mpi_command`: ``mpiexec``, ``srun`` on SLURM); the
        file's grid ``(nx, ny)`` (else read from its header); without ``comm``, ``run_case`` starts the ranks'
        program (:mod:`roughcontact.case.__main__`) under ``launcher``, in which every rank calls it with its
        ``comm``: each solves its rows, rank 0 gets the list and the others an empty one.

    Returns
    -------
    list of xarray.Dataset
        One per case of the group, in order: :func:`roughcontact.solver.solve_contact`'s dataset, with
        ``contact_stiffness`` and ``full_contact_pressure`` where asked and the load's attributes (``load_*``,
        :meth:`~.loading.LoadSchedule.resolve`). A batch's cases add ``rounds`` and ``wall_time`` of the whole batch,
        ``batch_size`` and ``check_every``; a case over ranks ``mpi_ranks`` and ``fft_library``. Over ranks, a
        launcher not found or the ranks' refusal is a ``ValueError`` (their one line), any other end of theirs a
        ``RuntimeError`` with their last lines.
    """
    if case.ranks != 1:
        return _over_ranks(surfaces, case, shape=shape, length=length, rms_slope=rms_slope, launcher=launcher,
                           log=log, name=name, comm=comm)
    if isinstance(surfaces, (str, os.PathLike)):
        raise ValueError(f"run_case: surfaces={os.fspath(surfaces)!r} is a path, which only a case over MPI ranks "
                         "reads (ContactCase ranks > 1); give the heights as an array to solve them in this process")
    if np.ndim(surfaces) == 3:
        return _run_batch(np.asarray(surfaces), case, length=length, rms_slope=rms_slope, log=log, names=name,
                          observers=observers)
    return [_run_one(surfaces, case, length=length, rms_slope=rms_slope, log=log, name=name, observers=observers)]


def _over_ranks(surfaces, case: ContactCase, *, shape, length, rms_slope, launcher, log, name, comm) -> list:
    """:func:`run_case` of a case over ranks: started under the launcher, or on a rank (``comm``)."""
    if not isinstance(surfaces, (str, os.PathLike)):
        raise ValueError(f"run_case: a case over {case.ranks} MPI ranks reads its surface from a file on every "
                         "rank: give the surface's file (NetCDF with 'heights' over (x, y)) as surfaces, or give "
                         "ContactCase ranks=1 to solve the array in this process")
    if comm is not None:
        solved = _solve_on_ranks(surfaces, case, comm, shape=shape, length=length, rms_slope=rms_slope)
        return [] if solved is None else [solved]
    return [_run_on_ranks(surfaces, case, shape=shape, length=length, rms_slope=rms_slope, launcher=launcher,
                          log=log, name=name)]


def _run_one(heights, case: ContactCase, *, length, rms_slope, log, name, observers: Sequence) -> xr.Dataset:
    """:func:`run_case` of one surface in this process."""
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


def _refuse_over_ranks(case: ContactCase) -> None:
    """``ValueError`` naming what ``case`` asks that a solve over MPI ranks cannot compute
    (:mod:`roughcontact.solver.mpi` solves the periodic elastic problem and reports per-step columns); a scene's
    are refused before any job by :func:`roughcontact.pipeline.config.checks.check_ranks`."""
    settings = case.settings
    refused = [(bool(case.outputs.get("full_contact_load")), "outputs['full_contact_load']"),
               (settings.boundary != "periodic", f"boundary={settings.boundary!r}"),
               (settings.array_backend not in (None, "numpy"), f"array_backend={settings.array_backend!r}"),
               (settings.method not in (None, BATCH_METHOD), f"method={settings.method!r}")]
    refused = _beyond_per_step_columns(case) + [what for flag, what in refused if flag]
    if refused:
        raise ValueError(f"run_case: a case over MPI ranks computes the periodic elastic solve's per-step "
                         f"columns only, not {', '.join(refused)}; run it with ranks=1 (the heights as an array) "
                         "for those")


def mpi_command(launcher: str, ranks: int) -> list[str]:
    """The command that starts ``ranks`` processes: ``launcher`` (e.g. ``"mpiexec"``, ``"srun"``, or with options:
    ``"mpiexec --bind-to core"``) split into words, then ``-n ranks``.

    ``mpiexec`` not on ``PATH`` is the one beside this Python (``pip install 'roughcontact[mpi]'`` puts MPICH's
    there); a launcher found nowhere is a ``ValueError`` naming it and the remedy.
    """
    words = shlex.split(launcher)
    if not words:
        raise ValueError("contact.solver.ranks: the MPI launcher (the rule's 'launcher' resource) is empty; set it to "
                         "mpiexec (local runs) or srun (SLURM)")
    found = shutil.which(words[0])
    if found is None and words[0] == "mpiexec" and (Path(sys.executable).parent / "mpiexec").exists():
        found = str(Path(sys.executable).parent / "mpiexec")
    if found is None:
        raise ValueError(f"contact.solver.ranks: the MPI launcher {words[0]!r} (the rule's 'launcher' resource) is not "
                         "found; install one with pip install 'roughcontact[mpi]' (mpiexec), or on a cluster run "
                         "with --workflow-profile profiles/slurm (srun)")
    return [found, *words[1:], "-n", str(int(ranks))]


#: A step line of the ranks (:func:`_print_step`), re-logged as :func:`run_case`'s.
_MPI_STEP = re.compile(r"^step (\d+): p0=(\S+) A/A0=(\S+) iterations=(\d+) converged=(True|False) (\S+) s$")


def case_document(case: ContactCase) -> dict:
    """``case`` as plain values (JSON): its schedule, its settings, its outputs, its warm start and ranks.

    :func:`case_from_document` makes the same case again. Effects are objects of their own and are not
    written: a case with effects is a ``ValueError`` here (a case over ranks, the one written, refuses them).
    """
    if case.settings.effects:
        raise ValueError(f"case_document: a case with effects ({', '.join(e.name for e in case.settings.effects)}) "
                         "is not written as plain values")
    settings = {f.name: getattr(case.settings, f.name) for f in dataclasses.fields(case.settings)
                if f.name != "effects"}
    if isinstance(settings["length"], tuple):
        settings["length"] = list(settings["length"])
    return {"schedule": dataclasses.asdict(case.schedule), "settings": settings,
            "options": {"outputs": dict(case.outputs), "warm_start": case.warm_start, "ranks": case.ranks}}


def case_from_document(doc: Mapping) -> ContactCase:
    """The :class:`ContactCase` that :func:`case_document` wrote as ``doc``."""
    settings = dict(doc["settings"])
    if isinstance(settings["length"], list):
        settings["length"] = tuple(settings["length"])
    return ContactCase(LoadSchedule(**doc["schedule"]), SolverSettings(**settings), **doc["options"])


def _run_on_ranks(surface_file, case: ContactCase, *, shape, length, rms_slope: float, launcher: str, log,
                  name) -> xr.Dataset:
    """:func:`run_case` of one surface file over ``case.ranks`` MPI processes, started under ``launcher``.

    The loads are resolved here too (for the log and the step lines); the case, the cell and the surface's rms
    slope are written as plain values (:func:`case_document`, JSON: every float exact) for the ranks' program
    ``launcher -n ranks python -m roughcontact.case JOB`` (:mod:`roughcontact.case.__main__`), whose ranks
    resolve the same loads (checked on the file they write). Every rank reads its own rows of ``surface_file``
    (the grid is split in slabs along x), so no process but rank 0's writer ever holds a whole field; rank 0
    writes the per-step columns to a temporary file, read back here.
    """
    _refuse_over_ranks(case)
    if shape is None:
        shape = _file_grid(surface_file)
    cell = Cell.of(shape, length)
    loads, load_info = case.schedule.resolve(case.settings.e_star, rms_slope, cell.shape[0] * cell.shape[1], None,
                                             log, name, cap=case.settings.hardness)
    with tempfile.TemporaryDirectory(prefix="roughcontact-mpi-") as tmp:
        out, job = Path(tmp) / "contact.nc", Path(tmp) / "case.json"
        job.write_text(json.dumps({"case": case_document(case), "surface_file": os.path.abspath(surface_file),
                                   "shape": [int(n) for n in cell.shape], "length": list(cell.sides),
                                   "rms_slope": float(rms_slope), "out": os.fspath(out)}))
        cmd = [*mpi_command(launcher, case.ranks), sys.executable, "-m", "roughcontact.case", os.fspath(job)]
        if log is not None:
            log.info("%s over %d MPI ranks: %s", name or "case", case.ranks, " ".join(cmd[:-1]))
        result = _run_ranks(cmd, out, step_logger(log, len(loads)), log)
    if result.attrs.get("load_p0_max") != load_info["load_p0_max"]:  # the ranks resolve the same schedule
        raise RuntimeError(f"the MPI ranks solved up to p0 = {result.attrs.get('load_p0_max')!r}, not the "
                           f"{load_info['load_p0_max']!r} this case resolves to")
    if log is not None:
        _warn(log, result, name or "case", case.settings.tol)
    return result


def _solve_on_ranks(surface_file, case: ContactCase, comm, *, shape, length, rms_slope: float) -> xr.Dataset | None:
    """:func:`run_case` of one surface file on every rank of ``comm``: each rank reads and solves its rows; rank 0
    prints each step's line to stderr (as :func:`_run_ranks` reads it) and gets the dataset, the others None."""
    from ..solver.mpi import solve_contact_mpi
    from ..solver.mpi.program import check_world, file_rows
    from ..solver.mpi.solver import collective

    def check():
        check_world(comm, case.ranks)
        _refuse_over_ranks(case)

    collective(comm, check)
    rows, found, _ = collective(comm, lambda: file_rows(surface_file, comm))

    def same_grid():
        if shape is not None and tuple(found) != tuple(shape):
            raise ValueError(f"{surface_file}: its grid is {found[0]} x {found[1]}, not the {shape[0]} x {shape[1]} "
                             "the case was planned for; solve it again from the file")

    collective(comm, same_grid)
    loads, load_info = case.schedule.resolve(case.settings.e_star, rms_slope, found[0] * found[1], None,
                                             cap=case.settings.hardness)
    result = solve_contact_mpi(rows, found, loads, case.solver_settings(length), comm=comm,
                               progress=_print_step if comm.rank == 0 else None)
    if comm.rank != 0:
        return None
    # rank 0 writes it as a file of its own (CF-checked); the attribute before the load's, as the pipeline's
    # files of a case over ranks have always had them
    result.attrs["Conventions"] = "CF-1.8"
    return _finished(result, None, case, length, load_info, None, "case")


def _print_step(step, p0, area, iterations, converged, seconds):
    """A step's line of the ranks (rank 0's stderr), in the form :data:`_MPI_STEP` reads."""
    print(f"step {step}: p0={p0:.6g} A/A0={area:.6g} iterations={iterations} converged={converged} "
          f"{seconds:.2f} s", file=sys.stderr, flush=True)


def _file_grid(path) -> tuple[int, int]:
    """The ``(nx, ny)`` of a surface file's ``heights`` from its header (nothing else read)."""
    try:
        with xr.open_dataset(path) as ds:
            if "heights" not in ds.variables or not {"x", "y"} <= set(ds["heights"].dims):
                raise ValueError(f"{path}: holds no variable 'heights' over (x, y); give a surface job's file")
            sizes = ds["heights"].sizes
            return int(sizes["x"]), int(sizes["y"])
    except OSError as exc:
        raise ValueError(f"{path}: cannot be read as NetCDF ({exc})") from None


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
                           "launcher (the rule's 'launcher' resource) must run the command it is given")
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
