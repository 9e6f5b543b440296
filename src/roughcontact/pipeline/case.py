"""A scene's block as a library case: :func:`contact_case` (a ``contact`` block) and :func:`accuracy_case` (a setting
of the ``accuracy`` study), the one place scene vocabulary becomes :class:`~roughcontact.case.ContactCase`,
:class:`~roughcontact.case.LoadSchedule` and :class:`~roughcontact.solver.SolverSettings`."""

from __future__ import annotations

from collections.abc import Mapping

from ..case import ContactCase, LoadSchedule
from ..solver import SolverSettings, effects_from_config
from ..solver.effects import Effect


def load_schedule(block: Mapping) -> LoadSchedule:
    """The load schedule of a validated ``contact`` block (its ``load``)."""
    load = block["load"]
    return LoadSchedule(int(load["n_steps"]), load.get("schedule", "uniform"),
                        None if "target_area" in load else load["p_max"], load.get("p_min"),
                        load.get("relative_to", "e_star"), load.get("target_area"))


def contact_effects(block: Mapping) -> tuple[Effect, ...]:
    """The effects a validated ``contact`` block names (``effects``, relative to ``solver.e_star``), in its order.

    The one place the pipeline turns a block into its effects: it asks them what they need and give
    (:class:`~roughcontact.solver.effects.Effect`: ``needs_gap_iteration``, ``keeps_elastic_law``, ``figures``, ...)
    and lets them check what concerns them, never testing their names.
    """
    blocks = block.get("effects") or {}
    return effects_from_config(blocks, e_star=block["solver"]["e_star"]) if blocks else ()


def follows_elastic_law(block: Mapping) -> bool:
    """Whether contact in a validated ``contact`` block follows the contact evolution law: every effect keeps it
    (:attr:`~roughcontact.solver.effects.Effect.keeps_elastic_law`; none adhesive), so the law is fitted and its
    figures and theories drawn."""
    return all(effect.keeps_elastic_law for effect in contact_effects(block))


def effect_field_error(name: str, field: str, message: str) -> None:
    """Raise an effect's refusal (``fail`` of :meth:`~roughcontact.case.LoadSchedule.check_final_load`) as a
    ``ValueError`` naming its config field, ``contact.effects.<name><field>``."""
    raise ValueError(f"contact.effects.{name}{field}: {message}")


def check_case_loads(case: ContactCase, rms_slope: float) -> None:
    """Refuse, in a case's job before any solve, a final load one of its effects cannot carry, naming the config
    field and the remedy: a surface normalised by rms height has its slope, so a load relative to it, known only
    there (the planner checked every final load it could know: :mod:`.config.checks`)."""
    case.schedule.check_final_load(case.settings.effects, case.settings.e_star, rms_slope, fail=effect_field_error)


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
                              effects=contact_effects(block),
                              length_unit=length_unit, pressure_unit=solver["pressure_unit"],
                              array_backend=solver.get("array_backend", "numpy"))
    return ContactCase(load_schedule(block), settings, outputs=block["outputs"], ranks=solver.get("ranks", 1))


def accuracy_case(block: Mapping, *, threads: int = 1) -> ContactCase:
    """The case of one setting of a validated ``accuracy`` block (``setting``: its ``tol`` and ``n_steps``; the
    study's ``p_max``): the paper's uniform steps to ``p_max E*`` with E* = 1 (``threads``: the job's)."""
    setting = block["setting"]
    return ContactCase(LoadSchedule(int(setting["n_steps"]), p_max=block["p_max"]),
                       SolverSettings(tol=float(setting["tol"]), threads=threads))
