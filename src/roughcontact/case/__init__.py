"""A contact case as a library object: one surface, one load schedule, the solver's settings, the outputs asked for.

:class:`ContactCase` says what to compute (a :class:`~roughcontact.solver.SolverSettings`, one
:class:`LoadSchedule`, the outputs); :func:`run_case` computes it on a group of surfaces (one surface, a batch of
surfaces of one grid, or one surface file split over MPI ranks: ``python -m roughcontact.case`` is the ranks'
program) and gives one dataset per case. Tamaas' ``load_path(solver, loads)``
is the closest peer. The pipeline builds its cases from a scene's ``contact`` block in one function
(:func:`roughcontact.pipeline.case.contact_case`); nothing here reads a scene.

Examples
--------
>>> from roughcontact.case import ContactCase, LoadSchedule, run_case
>>> from roughcontact.solver import SolverSettings
>>> from roughcontact.surfaces.synthetic import generate_surface
>>> h = generate_surface(64, 2, 16, 0.8, seed=0, rms_slope=0.1)
>>> case = ContactCase(LoadSchedule(4, p_max=0.005), SolverSettings(e_star=1.0), outputs={"fields": [],
...                    "clusters": True})
>>> [ds] = run_case(h, case, length=1.0, rms_slope=0.1)
>>> ds.sizes["step"], int(ds.cluster_count.values[-1]) > 0
(4, True)
"""

from .loading import LoadSchedule, pressure_for_area, schedule
from .outputs import contact_observers, full_contact_variable
from .progress import eta, step_logger
from .run import NO_OUTPUTS, ContactCase, case_document, case_from_document, default_settings, mpi_command, run_case

__all__ = ["NO_OUTPUTS", "ContactCase", "LoadSchedule", "case_document", "case_from_document", "contact_observers",
           "default_settings", "eta", "full_contact_variable", "mpi_command", "pressure_for_area", "run_case",
           "schedule", "step_logger"]
