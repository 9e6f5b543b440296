"""A scene's ``contact`` block as a library case: :func:`contact_case`, the one place scene vocabulary becomes
:class:`~roughcontact.case.ContactCase`, :class:`~roughcontact.case.LoadSchedule` and
:class:`~roughcontact.solver.SolverSettings`."""

from __future__ import annotations

from collections.abc import Mapping

from ..case import ContactCase, LoadSchedule
from ..solver import SolverSettings, effects_from_config


def load_schedule(block: Mapping) -> LoadSchedule:
    """The load schedule of a validated ``contact`` block (its ``load``)."""
    load = block["load"]
    return LoadSchedule(int(load["n_steps"]), load.get("schedule", "uniform"),
                        None if "target_area" in load else load["p_max"], load.get("p_min"),
                        load.get("relative_to", "e_star"), load.get("target_area"))


def contact_case(block: Mapping, *, length_unit: str = "1", threads: int = 1) -> ContactCase:
    """The case a validated scene's ``contact`` block asks for (``length_unit``: the study's; ``threads``: the job's).

    ``solver`` gives the settings (``e_star``, ``tol``, ``max_iter``, ``boundary``, ``pressure_unit``,
    ``array_backend``, ``ranks``), ``effects`` the effects (their parameters relative to ``e_star``), ``load``
    the schedule (:func:`load_schedule`) and ``outputs`` the outputs.
    """
    solver = block["solver"]
    e_star = solver["e_star"]
    settings = SolverSettings(e_star=e_star, tol=solver["tol"], max_iter=solver["max_iter"], threads=threads,
                              boundary=solver["boundary"], method=None,
                              effects=effects_from_config(block["effects"], e_star=e_star),
                              length_unit=length_unit, pressure_unit=solver["pressure_unit"],
                              array_backend=solver.get("array_backend", "numpy"))
    return ContactCase(load_schedule(block), settings, outputs=block["outputs"], ranks=solver.get("ranks", 1))
