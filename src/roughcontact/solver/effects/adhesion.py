"""Adhesion: an interaction energy of the gap (exponential or Maugis-Dugdale law).

The effect supplies its law as the ``functional`` (:mod:`..adhesion`), which makes the solver
use the gap iteration (:class:`~..adhesive.AdhesiveSolver`, Rey, Anciaux & Molinari 2017); it
reports the adhesive share of each step and, after the load steps, the pull-off pressure from
unloading under displacement control.
"""

from __future__ import annotations

import numpy as np

from ...core.quantities import cf_unit
from ..adhesion import Exponential, MaugisDugdale
from ..results import FRACTION_UNITS
from .base import Effect, register

#: The interaction laws by their config name.
LAWS = {"exponential": Exponential, "maugis-dugdale": MaugisDugdale}


@register
class Adhesion(Effect):
    """Adhesive interaction of the surfaces.

    Parameters
    ----------
    law : {"exponential", "maugis-dugdale"}
        Interaction law (:data:`LAWS`).
    work : float
        Work of adhesion ``w`` [pressure x length], > 0.
    range : float
        Range ``rho`` of the law [length], > 0.
    unloading : bool
        Trace the unloading after the last load step (the pull-off pressure; costs about as
        many solves as ``unloading_steps``).
    """

    name = "adhesion"

    def __init__(self, law: str, work: float, range: float, unloading: bool = True):  # noqa: A002
        if law not in LAWS:
            raise ValueError(f"law must be one of {sorted(LAWS)}, got {law!r}")
        self.functional = LAWS[law](work, range)
        self.law, self.unloading = law, bool(unloading)

    @classmethod
    def check_config(cls, contact: dict, fail) -> None:
        """The gap iteration runs on the periodic half-space, with no other effect."""
        others = sorted(set(contact["effects"]) - {cls.name})
        if others:
            fail("", f"cannot be combined with effects.{others[0]} (one effect on the gap iteration at a time); "
                 "remove one of them")
        boundary = contact["solver"].get("boundary", "periodic")
        if boundary != "periodic":
            fail("", f"needs solver.boundary: periodic (the adhesive iteration is periodic), got {boundary!r}")

    @classmethod
    def from_config(cls, block: dict, *, e_star: float) -> Adhesion:
        """``contact.effects.adhesion``: ``work`` relative to ``E*`` (a length), ``range`` a length."""
        return cls(block["law"], block["work"] * e_star, block["range"], block.get("unloading", True))

    def finish(self, p: np.ndarray, p_int, p0: float) -> dict:
        """The mean adhesive (tensile) pressure and the fraction of nodes in tension."""
        tensile = p < 0
        return {"adhesive_pressure": float(-p[tensile].sum()) / p.size,
                "tensile_area_fraction": np.count_nonzero(tensile) / p.size}

    def variables(self, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        return {"adhesive_pressure": (cf_unit(pressure=pressure_unit, pressure_power=1),
                                      "mean tensile pressure of the adhesive interaction (sum of p < 0 over A0)"),
                "tensile_area_fraction": (FRACTION_UNITS, "fraction of nodes in tension (p < 0)")}

    def attrs(self) -> dict:
        return {"adhesion_law": self.law, "work_of_adhesion": self.functional.w,
                "adhesion_range": self.functional.rho}

    def after_steps(self, solver, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        """The pull-off pressure from unloading (``rho / 4`` a step) after the last load step."""
        if not self.unloading:
            return {}
        gaps, loads = solver.unload(self.functional.rho / 4)
        pull_off = -float(np.nanmin(loads)) if loads.size else float("nan")
        return {"pull_off_pressure": (pull_off, cf_unit(pressure=pressure_unit, pressure_power=1),
                                      "pull-off pressure: the most tensile mean pressure on unloading under "
                                      "displacement control from the last load step (rho / 4 a step)")}
