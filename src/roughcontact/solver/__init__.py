"""Pressure-controlled FFT-BEM normal contact solver (Polonsky & Keer 1999), with effects (plasticity, adhesion).

A rigid rough surface of heights ``h`` (highest points touch first) pressed onto an elastic half-space
of plane-strain modulus ``E*``, periodic or free, on a square or rectangular cell or a 1-D profile:
:func:`solve_contact` solves a load schedule, :func:`solve_step` one load, :func:`solve_contact_batch`
many surfaces of one grid together; :class:`SolverSettings` says how. The problem, the internal units,
the iterations and the convergence criterion are stated in docs/solver.md ("The problem, units,
algorithm and convergence criterion"); the modules refer to its sections.

Parts: :mod:`.halfspace` (and :mod:`.love`) the elastic operators, periodic and free; :mod:`.workspace`
the fields of one surface and the iterations' names; :mod:`.elastic` and :mod:`.box` the pressure
iterations (elastic, capped), :mod:`.projection` their projections; :mod:`.check` the final check;
:mod:`.results` the assembly of the output; :mod:`.units` and :mod:`.validation` the checks of the
input; :mod:`.settings` and :mod:`.options` what a solve is asked to do; :mod:`.contact` one surface's
solver; :mod:`.solve` the entry points and the step loop. Folders: :mod:`.effects` what acts on the
iteration, one module per effect, found by name; :mod:`.adhesion` the gap iteration of adhesive contact
and its solver (Rey, Anciaux & Molinari 2017); :mod:`.batch` many surfaces of one grid in one solve
(issue 48); :mod:`.mpi` one case split over MPI ranks (issue 50); :mod:`.reference` methods of other
kinds that studies run beside ours (Stanley & Kato's iteration, for the κ-gap study).

The FFT plans and buffers are shared per grid size within a process, so two solves of the same size
must not run concurrently in threads of one process (separate processes, as under Snakemake, are fine).
"""

from ..core.backend import ARRAY_BACKENDS
from .batch import solve_contact_batch
from .check import MEAN_RTOL
from .contact import ContactSolver
from .effects import EFFECTS, Adhesion, Effect, PlasticityCap, effects_from_config
from .halfspace import FreeHalfSpace, PeriodicHalfSpace, displacement, elastic_kernel, free_influence
from .options import get_options, set_options
from .results import (
                      FRACTION_UNITS,
                      SOLVER_DESCRIPTION,
                      SOLVER_NAME,
                      StepResult,
                      contact_perimeter,
                      step_notes,
)
from .settings import DEFAULT_MAX_ITER, SolverSettings
from .solve import solve_contact, solve_step
from .units import LOAD_RANGE, gap_scale
from .validation import BOUNDARIES
from .workspace import ELASTIC_METHODS, FALLBACKS, SOLVER_PATHS, STALL_WINDOW

__all__ = [
    "ARRAY_BACKENDS",
    "BOUNDARIES",
    "Adhesion",
    "DEFAULT_MAX_ITER",
    "EFFECTS",
    "ELASTIC_METHODS",
    "FALLBACKS",
    "FRACTION_UNITS",
    "LOAD_RANGE",
    "MEAN_RTOL",
    "SOLVER_DESCRIPTION",
    "SOLVER_NAME",
    "SOLVER_PATHS",
    "STALL_WINDOW",
    "ContactSolver",
    "Effect",
    "FreeHalfSpace",
    "PeriodicHalfSpace",
    "PlasticityCap",
    "SolverSettings",
    "StepResult",
    "contact_perimeter",
    "get_options",
    "set_options",
    "displacement",
    "effects_from_config",
    "elastic_kernel",
    "free_influence",
    "gap_scale",
    "solve_contact",
    "solve_contact_batch",
    "solve_step",
    "step_notes",
]
