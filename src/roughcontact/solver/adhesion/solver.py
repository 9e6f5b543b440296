"""The solver of one surface when an effect supplies an interaction energy: the gap iteration.

:class:`AdhesiveSolver` has :class:`~roughcontact.solver.contact.ContactSolver`'s interface (``solve``,
``check_loads``, ``paths``, ``settings``, ...), so :func:`~roughcontact.solver.solve.solve_contact` runs
either without knowing which; :func:`~roughcontact.solver.solve.prepare` picks this one when an effect's
``functional`` is set. Each load step is solved under pressure control by the gap iteration
(:mod:`.iteration`), warm-started from the previous step's gap; :meth:`AdhesiveSolver.unload` traces the
unloading under displacement control and finds the pull-off pressure with its status
(:class:`Unloading`).

The pull-off
------------
Under displacement control the mean pressure falls as the surfaces are drawn apart, reaches
its most tensile value (the pull-off pressure a load-controlled test would measure) and rises
towards 0 once no node touches. The trace steps the mean gap by ``step`` (``rho / 4`` by
default) from the last load step, each step warm-started from the last, until the surfaces
have separated (a converged step with no node in contact, past the most tensile one) or
``max_steps``. The most tensile converged step ``k`` is then bracketed: the stretch from the
converged state before ``k`` to the step after it is traced again with a step four times
shorter, and again, until the pull-off changes by less than ``rtol`` of itself (on a sphere's
DMT side the fixed ``rho / 4`` step read 0.908 of the peak that ``rho / 100`` reads, 0.991).
Steps whose final check fails are kept in the trace, flagged, and excluded from the minimum.
The pull-off is NaN, with the reason in :data:`PULL_OFF_STATUS`, unless the grid resolves the
process zone, the last load step converged, the surfaces separated, the steps on both sides of
the minimum converged, the refinement met ``rtol`` and, at the pull-off, the attraction dies out
inside the cell (:func:`~.laws.attraction_across_cell` below
:data:`~.laws.MAX_ATTRACTION_ACROSS_CELL`: else the cell's edge cuts the body's attraction off
and the periodic images pull). When it is NaN no step of the trace is reported converged
(:class:`Unloading`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from ..results import StepRecord, contact_perimeter
from ..units import Units, check_loads
from .iteration import AdhesiveIteration, pressure_control
from .laws import (
    MAX_ATTRACTION_ACROSS_CELL,
    MIN_ZONE_CELLS,
    PULL_OFF_REASONS,
    WARN_ZONE_CELLS,
    attraction_across_cell,
    unresolved_zone_message,
    zone_cells,
)

#: The iterations an adhesive step can end on (the ``solver_path`` flag).
ADHESIVE_PATHS = ("adhesive",)

#: ``solver`` attribute of an adhesive solve's output: the gap iteration that ran.
ADHESIVE_SOLVER_NAME = "roughcontact.solver.adhesion.AdhesiveIteration"
#: ``solver_description`` attribute of an adhesive solve's output.
ADHESIVE_SOLVER_DESCRIPTION = (
    "Gap-controlled constrained conjugate gradient (Polonsky & Keer 1999 with the roles of pressure and gap "
    "exchanged, Rey, Anciaux & Molinari 2017) on a periodic FFT-BEM elastic half-space, u(q) = 2 p(q) / (E* |q|), "
    "minimising 1/2 <g + h, M (g + h)> + sum phi(g) over g >= 0 at an imposed mean gap, phi the adhesion law's "
    "energy (attribute adhesion_law); each load step under pressure control by an Illinois regula falsi on the "
    "mean gap, warm-started from the previous step's gap; no preconditioner; converged when "
    "max(max_{g>0} |p + tension(g)|, max(0, -min_{g=0}(p + tension(0))), |mean(p) - p0|) <= tol rms(M h) with "
    "g >= 0 and the imposed mean gap to 1e-12, checked on a freshly recomputed displacement, and the grid "
    "resolves the adhesive process zone (E* rho^2 / w over at least 1.5 cells, attribute adhesive_zone_cells)"
)
#: Step refinements near the minimum before giving up (each shortens the step 4x).
MAX_REFINEMENTS = 8


@dataclass
class Unloading:
    """The unloading trace of :meth:`AdhesiveSolver.unload` and its pull-off (module docstring).

    Attributes
    ----------
    mean_gap, mean_pressure, area_fraction : ndarray, shape (k,)
        Every unloading step, sorted by mean gap [length], [pressure], [-]; the refined stretch
        near the minimum included. ``mean_pressure`` is NaN where the step's final check failed.
    checked : ndarray of bool, shape (k,)
        Each step's own final check (the adhesive residual <= tol on a fresh FFT).
    pull_off : float
        The pull-off pressure ``-min(mean_pressure)`` [pressure], > 0 when tensile; NaN unless
        ``status`` is ``"trusted"``.
    status : str
        One of :data:`PULL_OFF_STATUS`; :data:`PULL_OFF_REASONS` says why for any other.
    step : float
        The last (shortest) step of the trace [length].
    rtol : float
        The refinement's tolerance on the pull-off.
    across_cell : float
        :func:`~.laws.attraction_across_cell` at the most tensile step that passed its check
        (the pull-off's step when trusted), NaN without one [-].
    """

    mean_gap: np.ndarray
    mean_pressure: np.ndarray
    area_fraction: np.ndarray
    checked: np.ndarray
    pull_off: float
    status: str
    step: float
    rtol: float
    across_cell: float = math.nan

    @property
    def converged(self) -> np.ndarray:
        """Each step converged: its own check passed *and* the pull-off is trusted (bool, shape (k,)).

        Whatever makes the pull-off untrusted leaves no step of the trace standing as a converged
        point of the unloading curve (:data:`~.laws.UNTRUSTED_TRACE_STEPS` says why); a step that
        met its own residual keeps its finite ``mean_pressure`` (``checked``).
        """
        return self.checked & (self.status == "trusted")

    @property
    def unconverged(self) -> int:
        """How many unloading steps are not reported converged (:attr:`converged`)."""
        return int(np.count_nonzero(~self.converged))

    @property
    def reason(self) -> str:
        """Why the pull-off is NaN (empty when trusted)."""
        return PULL_OFF_REASONS.get(self.status, "")


@dataclass
class _Point:
    """One unloading step: mean gap, its state (gap field) and what its final check found."""

    gbar: float
    gap: np.ndarray | None
    mean_p: float
    area: float
    converged: bool
    across_cell: float = math.nan

#: Long names of the per-step variables whose definition differs from the non-adhesive solver's.
LONG_NAMES = {
    "area_fraction": "real contact area fraction A / A0 (fraction of nodes with gap = 0)",
    "mean_contact_pressure": "mean contact pressure F / A = p0 / (A / A0), adhesive tension included",
    "residual": "final scale-free residual of the adhesive problem: max |p + tension(g)| where g > 0 and "
                "max(0, -min(p + tension(0))) where g = 0, over the rms pressure of M h",
    "converged": "residual <= tol, g >= 0 and mean(p) = p0 within tol on a freshly recomputed displacement",
}


class AdhesiveSolver:
    """One surface under an interaction law on the periodic half-space (``settings`` checked).

    Parameters
    ----------
    h : ndarray, shape (nx, ny)
        Validated heights [length].
    settings : SolverSettings
        Checked settings; exactly one effect supplies a ``functional`` (its law, physical units).
    """

    paths = ADHESIVE_PATHS
    long_names = LONG_NAMES

    # settings: a SolverSettings, not imported (nor annotated): the settings import the effects, which import this
    # package, and the solver would stand above them
    def __init__(self, h: np.ndarray, settings):
        laws = [e for e in settings.effects if e.functional is not None]
        if len(laws) != 1 or any(e.pressure_cap is not None for e in settings.effects):
            raise ValueError("effects: one interaction law at a time, and not with a pressure cap "
                             f"(got {[e.name for e in settings.effects]})")
        if settings.boundary != "periodic":
            raise ValueError(f"boundary: {laws[0].name} needs the periodic half-space, got {settings.boundary!r}")
        self.settings, self.effects = settings, list(settings.effects)
        self.shape, self.size, self.periodic = h.shape, h.size, True
        self.method, self.units = "adhesive", Units(h, settings.e_star, settings.length)
        if self.units.flat:
            raise ValueError(f"heights: {laws[0].name} needs a rough surface (all heights are equal)")
        self.law = laws[0].functional
        self.it = AdhesiveIteration(h, self.law, settings.e_star, settings.length)
        self.gap = h.max() - h  # the rigid surface touching at its highest node
        self.zone_cells = zone_cells(self.law, settings.e_star, settings.length, h.shape)
        self.resolved = self.zone_cells >= MIN_ZONE_CELLS
        if not self.resolved:
            warnings.warn(unresolved_zone_message(self.zone_cells, self.law, settings.e_star)
                          + "; no step is reported converged", stacklevel=4)
        elif self.zone_cells < WARN_ZONE_CELLS:
            warnings.warn(f"the adhesive process zone E* rho^2 / w spans {self.zone_cells:.3g} grid cells, fewer "
                          f"than {WARN_ZONE_CELLS:g}: steps count as converged, but a sphere's pull-off reads about "
                          "1 % high at 1.5 cells (docs/solver.md); refine the grid for a converged pull-off",
                          stacklevel=4)
        self.last_converged = False

    backend = "numpy"

    def check_loads(self, p: np.ndarray, name: str) -> None:
        """Refuse loads an effect cannot carry or float64 cannot represent."""
        for effect in self.effects:
            effect.check_loads(self.units, p, name)
        check_loads(self.units, p, self.shape, name)

    def solve(self, p0: float, initial=None, keep_gap: bool = False):
        """Solve the step for the mean pressure ``p0`` from the last step's gap; ``(StepRecord, gap)``."""
        s = self.settings
        self.it.iterations = 0
        residual, out = pressure_control(self.it, p0, self.gap, s.tol, s.max_iter)
        self.gap = out.gap
        mask = out.gap == 0.0
        cols = {}
        for effect in self.effects:
            cols.update(effect.finish(out.pressure, None, p0, gap=out.gap))
        converged = bool(residual <= s.tol) and self.resolved
        self.last_converged = converged
        step = StepRecord(out.pressure, mask, out.area_fraction, out.mean_gap,
                          contact_perimeter(mask, s.length, True), out.iterations, float(residual),
                          converged, cols, "adhesive")
        return step, (out.gap.copy() if keep_gap else None)

    def _unload_to(self, start: np.ndarray, gbar: float) -> _Point:
        """One displacement-controlled step to the mean gap ``gbar`` [length] from the gap ``start``."""
        s = self.settings
        self.it.start(start, gbar)
        self.it.solve(gbar, s.tol, s.max_iter)
        _, residual, mean_p = self.it.check(gbar)
        gap = self.it.g.copy()
        converged = bool(residual <= s.tol)
        return _Point(gbar, gap, mean_p if converged else math.nan,
                      float(np.count_nonzero(gap == 0.0)) / gap.size, converged, attraction_across_cell(self.law, gap))

    def _trace(self, start: _Point, step: float, stop, max_steps: int) -> list[_Point]:
        """``[start]`` and steps of ``step`` [length] from it until ``stop(points)`` or ``max_steps``.

        Each step starts from the state of the one before (converged or not: the iterate is a valid
        gap field, ``g >= 0`` with the right mean). Only the states a refinement can start from are
        kept (the last step's and the one before the most tensile step): a trace of many steps
        holds two or three fields, not one per step.
        """
        points = [start]
        for i in range(1, max_steps + 1):
            points.append(self._unload_to(points[-1].gap, start.gbar + i * step))
            best = _most_tensile(points)
            keep = {len(points) - 1, points.index(best) - 1 if best is not None else 0, 0}
            for j, point in enumerate(points[:-1]):
                if j not in keep:
                    point.gap = None
            if stop(points):
                break
        return points

    def unload(self, step: float, rtol: float = 1e-3, max_steps: int = 1000) -> Unloading:
        """Unload under displacement control from the last load step; the trace and its pull-off.

        Parameters
        ----------
        step : float
            First step of the mean gap [length], > 0 (``rho / 4`` from the effect); refined 4x at a
            time near the minimum (module docstring).
        rtol : float
            Tolerance on the pull-off's change between two refinements, relative.
        max_steps : int
            Most steps of the coarse trace before the surfaces count as not separated.

        Returns
        -------
        Unloading
            The trace (all steps, sorted by mean gap) and the pull-off with its status.
        """
        loaded = _Point(float(self.gap.mean()), self.gap, math.nan, math.nan, self.last_converged)

        def separated(points):
            best, last = _most_tensile(points), points[-1]
            return best is not None and last.converged and last.area == 0.0 and last.mean_p > best.mean_p

        points = self._trace(loaded, step, separated, max_steps)
        trace, status = points[1:], None
        if not self.resolved:
            status = "adhesive_zone_unresolved"
        elif not self.last_converged:
            status = "last_load_step_not_converged"
        elif not separated(points):
            status = "not_separated"
        pull_off = math.nan
        for _ in range(MAX_REFINEMENTS + 1):
            if status is not None:
                break
            best = _most_tensile(points)
            k = points.index(best) if best is not None else 0
            if k < 1 or k + 1 >= len(points) or not (points[k - 1].converged and points[k + 1].converged):
                status = "unconverged_step_beside_minimum"
                break
            previous, pull_off = pull_off, -best.mean_p
            if abs(pull_off - previous) <= rtol * abs(pull_off):  # False while previous is NaN
                break
            before, end, step = points[k - 1], points[k + 1].gbar, step / 4
            points = self._trace(before, step, lambda pts: False, int(round((end - before.gbar) / step)))
            trace += points[1:]
        else:
            status = "refinement_not_converged"
        trace.sort(key=lambda pt: pt.gbar)
        best = _most_tensile(trace)  # the most tensile converged step of the whole trace, every refinement's
        status = status or ("attraction_spans_cell" if best.across_cell >= MAX_ATTRACTION_ACROSS_CELL else "trusted")
        if status == "trusted":
            pull_off = -best.mean_p
        return Unloading(np.array([pt.gbar for pt in trace]), np.array([pt.mean_p for pt in trace]),
                         np.array([pt.area for pt in trace]), np.array([pt.converged for pt in trace], dtype=bool),
                         pull_off if status == "trusted" else math.nan, status, step, rtol,
                         best.across_cell if best is not None else math.nan)


def _most_tensile(points: list[_Point]) -> _Point | None:
    """The converged point of lowest mean pressure (the first of equals), or None."""
    done = [pt for pt in points if pt.converged and not math.isnan(pt.mean_p)]
    return min(done, key=lambda pt: pt.mean_p) if done else None
