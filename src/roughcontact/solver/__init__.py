"""Pressure-controlled FFT-BEM normal contact solver (Polonsky & Keer 1999), with effects (plasticity, adhesion).

A rigid rough surface of heights ``h`` (highest points touch first) pressed onto an elastic half-space
of plane-strain modulus ``E*``, periodic or free, on a square or rectangular cell or a 1-D profile:
:func:`solve_contact` solves a load schedule, :func:`solve_step` one load, :func:`solve_contact_batch`
many surfaces of one grid together; :class:`SolverSettings` says how. The problem, the internal units,
the iterations and the convergence criterion are stated in docs/solver.md ("The problem, units,
algorithm and convergence criterion"); the modules refer to its sections.

Parts: :mod:`.halfspace` (and :mod:`.love`) the elastic operators, periodic and free; :mod:`.workspace`
the fields of one surface and the iterations' names; :mod:`.iteration` the elastic iteration (one class for
one case, a batch and MPI ranks), :mod:`.compressed` its kernels for one case (the elastic load step) and
:mod:`.box` the capped iteration, :mod:`.projection` their projections; :mod:`.check` the final check;
:mod:`.results` the assembly of the output; :mod:`.units` and :mod:`.validation` the checks of the
input; :mod:`.settings` and :mod:`.options` what a solve is asked to do; :mod:`.contact` one surface's
solver; :mod:`.solve` the entry points and the step loop. Folders: :mod:`.effects` what acts on the
iteration, one module per effect, found by name; :mod:`.adhesion` the gap iteration of adhesive contact
and its solver (Rey, Anciaux & Molinari 2017); :mod:`.batch` many surfaces of one grid in one solve
(issue 48); :mod:`.mpi` one case split over MPI ranks (issue 50); :mod:`.reference` methods of other
kinds that studies run beside ours (Stanley & Kato's iteration, for the κ-gap study).

A name that another module needs is imported from the module that defines it and documents it
(``from roughcontact.solver.workspace import SOLVER_PATHS``); this package exports the public API only.

The FFT plans and buffers are shared per grid size within a process, so two solves of the same size
must not run concurrently in threads of one process (separate processes, as under Snakemake, are fine).
"""

from .batch import solve_contact_batch
from .effects import EFFECTS, Adhesion, Effect, PlasticityCap, effects_from_config
from .options import get_options, set_options
from .results import StepResult, contact_perimeter, step_notes
from .settings import SolverSettings
from .solve import solve_contact, solve_step

__all__ = [
    "EFFECTS",
    "Adhesion",
    "Effect",
    "PlasticityCap",
    "SolverSettings",
    "StepResult",
    "contact_perimeter",
    "effects_from_config",
    "get_options",
    "set_options",
    "solve_contact",
    "solve_contact_batch",
    "solve_step",
    "step_notes",
]
