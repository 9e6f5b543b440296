"""Adhesion: an interaction energy of the gap (exponential or Maugis-Dugdale law).

The effect supplies its law as the ``functional`` (:mod:`..adhesion`), which makes the solver
use the gap iteration (:class:`~..adhesion.solver.AdhesiveSolver`, Rey, Anciaux & Molinari 2017); it
reports the adhesive share of each step and, after the load steps, the unloading branch under
displacement control and the pull-off pressure with its status (:mod:`..adhesion.solver`).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ...core.quantities import cf_unit
from ..adhesion import (
    MAX_ATTRACTION_ACROSS_CELL,
    MIN_ZONE_CELLS,
    PULL_OFF_STATUS,
    UNTRUSTED_TRACE_STEPS,
    Exponential,
    MaugisDugdale,
    process_zone_length,
    unresolved_zone_message,
    zone_cells,
)
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
        Trace the unloading after the last load step under displacement control: the unloading
        branch and the pull-off pressure with its status (:meth:`~..adhesion.solver.AdhesiveSolver.unload`).
    pull_off_rtol : float
        Tolerance on the pull-off's change when the unloading step near the minimum is refined, relative.

    Examples
    --------
    >>> from roughcontact.solver import solve_contact
    >>> from roughcontact.surfaces.synthetic import generate_surface
    >>> h = generate_surface(64, 2, 16, 0.5, seed=0, rms_slope=0.1)
    >>> ds = solve_contact(h, [0.001, 0.002], effects=(Adhesion("exponential", 2e-6, 1e-3),))
    >>> str(ds["pull_off_status"].attrs["flag_meanings"].split()[int(ds["pull_off_status"])])
    'trusted'
    """

    name = "adhesion"
    #: an adhesive scene draws the load cycle and the pull-off, not the contact evolution law
    keeps_elastic_law = False
    adds_tension = True
    contact_name = "adhesive contact"
    #: Fraction of the largest tension above which a node out of contact counts in ``adhesive_area_fraction``.
    ZONE_FRACTION = 0.5

    def __init__(self, law: str, work: float, range: float, unloading: bool = True,  # noqa: A002
                 pull_off_rtol: float = 1e-3):
        if law not in LAWS:
            raise ValueError(f"law must be one of {sorted(LAWS)}, got {law!r}")
        self.functional = LAWS[law](work, range)
        self.law, self.unloading = law, bool(unloading)
        if not (isinstance(pull_off_rtol, (int, float)) and 0 < pull_off_rtol < 1):
            raise ValueError(f"pull_off_rtol must be a number in (0, 1), got {pull_off_rtol!r}")
        self.pull_off_rtol = float(pull_off_rtol)

    def check_config(self, fail, *, others=(), boundary: str = "periodic") -> None:
        """The gap iteration runs on the periodic half-space, with no other effect; a scene's law is exponential."""
        if others:
            fail("", f"cannot be combined with effects.{sorted(others)[0]} (one effect on the gap iteration at a "
                     "time); remove one of them")
        if boundary != "periodic":
            fail("", f"needs solver.boundary: periodic (the adhesive iteration is periodic), got {boundary!r}")
        if self.law == "maugis-dugdale":
            fail(".law", "maugis-dugdale is refused in a scene: its tension jumps at g = rho, so the discrete "
                 "problem traps in many states and its pull-off does not converge with the grid (docs/solver.md, "
                 "'Adhesion'); use law: exponential (the library's MaugisDugdale stays for studies of that trap)")

    def check_grid(self, e_star: float, length, shape, pixel: str, fail, *, n_field: str | None = None,
                   most_n: int | None = None) -> None:
        """The grid resolves the process zone ``E* rho^2 / w`` (:data:`~..adhesion.MIN_ZONE_CELLS` cells of ``pixel``).

        ``length`` (L or (Lx, Ly)) in the range's unit. With ``n_field`` (the field that sets a square grid's N,
        ``length`` its side L) the remedy names the N it needs, or, beyond ``most_n``, how far the zone must widen.
        Work and zone are read relative to ``e_star`` (a scene's ``work`` is w / E*).
        """
        law = LAWS[self.law](self.functional.w / e_star, self.functional.rho)  # E* = 1: a scene's own numbers
        cells = zone_cells(law, 1.0, length, shape)
        if cells >= MIN_ZONE_CELLS:
            return
        problem = unresolved_zone_message(cells, law, 1.0, pixel)
        if n_field is None:
            fail("", problem)
            return
        need = math.ceil(MIN_ZONE_CELLS * length / process_zone_length(law, 1.0))
        if most_n is None or need <= most_n:
            fail("", f"{problem} ({n_field} >= {need})")
            return
        # no grid a scene allows resolves it: the zone E* rho^2 / w must grow instead
        zone = MIN_ZONE_CELLS * length / most_n
        fail("", f"{problem}: it needs {n_field} >= {need}, beyond the largest grid a scene allows (N = {most_n}); "
                 f"widen the process zone E* rho^2 / w to >= {zone:.3g} instead: "
                 f"range >= {1.002 * math.sqrt(zone * law.w):.3g}, or work <= {0.998 * law.rho ** 2 / zone:.3g}, "
                 "or a smaller cell L")

    @property
    def figures(self) -> tuple[str, ...]:
        """The load cycle and the pull-off, drawn from the unloading branch: none without ``unloading``."""
        return ("hysteresis", "pull_off") if self.unloading else ()

    @property
    def tables(self) -> tuple[str, ...]:
        """The pull-off table, from the unloading branch: none without ``unloading``."""
        return ("pull_off",) if self.unloading else ()

    @classmethod
    def from_config(cls, block: dict, *, e_star: float) -> Adhesion:
        """``contact.effects.adhesion``: ``work`` relative to ``E*`` (a length), ``range`` a length."""
        return cls(block["law"], block["work"] * e_star, block["range"], block.get("unloading", True),
                   block.get("pull_off_rtol", 1e-3))

    @property
    def intro_fact(self) -> dict:
        """The law's name and whether the solve unloads (``{"law": str, "unloading": bool}``)."""
        return {"law": self.law, "unloading": self.unloading}

    @classmethod
    def intro_text(cls, fact) -> str:
        loaded = f"with the {fact['law']} adhesion law, loaded in steps under pressure control"
        if not fact["unloading"]:
            return loaded + " (not unloaded: no pull-off is computed)"
        return loaded + ", then unloaded under displacement control to the pull-off pressure"

    def finish(self, p: np.ndarray, p_int, p0: float, gap: np.ndarray | None = None) -> dict:
        """The attractive traction of the law out of contact, and the area where it is strong.

        Both come from the law at the gap (``tension(g)`` where ``g > 0``), not from the sign of the
        pressure: with the exponential law every node out of contact carries some tension, and
        below the residual's scale the sign of ``p`` is noise.
        """
        law, out = self.functional, gap > 0
        tension = law.tension(gap[out])
        return {"adhesive_pressure": float(tension.sum()) / gap.size,
                "adhesive_area_fraction": np.count_nonzero(tension >= self.ZONE_FRACTION * law.max_tension)
                / gap.size}

    def variables(self, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        return {"adhesive_pressure": (cf_unit(pressure=pressure_unit, pressure_power=1),
                                      "attractive traction of the interaction law on the nodes out of contact, "
                                      "summed over A0: sum of tension(g) where g > 0, over the node count"),
                "adhesive_area_fraction": (FRACTION_UNITS, "fraction of nodes out of contact whose adhesive traction "
                                           f"is at least {self.ZONE_FRACTION:g} of the law's largest, w / rho")}

    def attrs(self) -> dict:
        return {"adhesion_law": self.law, "work_of_adhesion": self.functional.w,
                "adhesion_range": self.functional.rho}

    def after_steps(self, solver, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        """The process zone's resolution, and after unloading its branch and the pull-off with its status.

        Returns name -> :class:`xarray.Variable`: ``adhesive_zone_cells`` always; with ``unloading``
        the branch along ``unload_step`` (``unload_mean_gap``, ``unload_mean_pressure``,
        ``unload_area_fraction``, ``unload_converged``), ``pull_off_pressure`` (NaN unless trusted,
        the reason in its ``comment``), ``pull_off_status`` (a CF flag), ``unload_unconverged_steps``
        and ``attraction_across_cell``.
        """
        pressure = cf_unit(pressure=pressure_unit, pressure_power=1)
        out = {"adhesive_zone_cells": xr.Variable((), solver.zone_cells, {
            "units": FRACTION_UNITS, "long_name": "grid cells spanned by the adhesive process zone E* rho^2 / w "
                                                  "(the larger pixel side); steps count as converged from 1.5"})}
        if not self.unloading:
            return out
        un = solver.unload(self.functional.rho / 4, rtol=self.pull_off_rtol)
        out.update(unloading_variables(un, cf_unit(length=length_unit, length_power=1), pressure))
        return out


def unloading_variables(un, length_units: str, pressure_units: str) -> dict:
    """The unloading branch and the pull-off of :class:`~..adhesion.solver.Unloading` ``un`` as CF variables.

    Along ``unload_step``: ``unload_mean_gap`` [length], ``unload_mean_pressure`` [pressure],
    ``unload_area_fraction``, ``unload_converged`` (a flag: 0 on every step unless the pull-off is
    trusted, :attr:`~..adhesion.solver.Unloading.converged`); scalars ``unload_unconverged_steps``,
    ``pull_off_pressure`` (NaN unless trusted; its ``comment`` says how it was found, or why it is
    NaN), ``pull_off_status`` (a CF flag over :data:`PULL_OFF_STATUS`) and ``attraction_across_cell``.
    """
    dim = ("unload_step",)
    comment = un.reason or (f"the most tensile converged step, the step near it refined 4x at a time to "
                            f"{un.step:.3g} until it moved by less than {un.rtol:g} of itself")

    def flag(dims, codes, long_name, meanings, **attrs):
        return xr.Variable(dims, codes, {"units": FRACTION_UNITS, "long_name": long_name,
                                         "flag_values": np.arange(len(meanings), dtype=np.int8),
                                         "flag_meanings": " ".join(meanings), **attrs})

    return {
        "unload_mean_gap": xr.Variable(dim, un.mean_gap, {
            "units": length_units, "long_name": "mean gap on unloading under displacement control"}),
        "unload_mean_pressure": xr.Variable(dim, un.mean_pressure, {
            "units": pressure_units,
            "long_name": "mean pressure on unloading (NaN where the step's own residual check failed)"}),
        "unload_area_fraction": xr.Variable(dim, un.area_fraction, {
            "units": FRACTION_UNITS, "long_name": "real contact area fraction on unloading (nodes with gap = 0)"}),
        "unload_converged": flag(dim, un.converged.astype(np.int8),
                                 "unloading step converged: adhesive residual <= tol on a fresh FFT and the "
                                 "pull-off trusted (pull_off_status trusted); 0 on every step otherwise",
                                 ("false", "true"), comment=UNTRUSTED_TRACE_STEPS),
        "unload_unconverged_steps": xr.Variable((), un.unconverged, {
            "units": FRACTION_UNITS,
            "long_name": "unloading steps not flagged converged (unload_converged = 0): all of them unless the "
                         "pull-off is trusted; those whose own residual check failed have a NaN mean pressure"}),
        "pull_off_pressure": xr.Variable((), un.pull_off, {
            "units": pressure_units, "comment": comment,
            "long_name": "pull-off pressure: minus the most tensile mean pressure on unloading under displacement "
                         "control from the last load step; NaN unless pull_off_status is trusted"}),
        "pull_off_status": flag((), np.int8(PULL_OFF_STATUS.index(un.status)),
                                "whether the pull-off pressure can be trusted, else why not", PULL_OFF_STATUS),
        "attraction_across_cell": xr.Variable((), un.across_cell, {
            "units": FRACTION_UNITS,
            "long_name": "at the most tensile unloading step that met its residual (the pull-off's), the strongest "
                         "adhesive tension held all along a row or column of the cell (the largest over lines of "
                         "the line's weakest tension(g)) over the law's largest, w / rho; for a body centred in the "
                         "cell the tension at the cell's edge; from "
                         f"{MAX_ATTRACTION_ACROSS_CELL:g} pull_off_status is attraction_spans_cell"}),
    }

