"""The solver of one surface when an effect supplies an interaction energy: the gap iteration.

:class:`AdhesiveSolver` has :class:`~.contact.ContactSolver`'s interface (``solve``,
``check_loads``, ``paths``, ``settings``, ...), so :func:`~.solve.solve_contact` runs either
without knowing which; :func:`~.solve.prepare` picks this one when an effect's ``functional``
is set. Each load step is solved under pressure control by :mod:`.adhesion`'s iteration on the
gap, warm-started from the previous step's gap; :meth:`AdhesiveSolver.unload` traces the
unloading under displacement control (the pull-off force).
"""

from __future__ import annotations

import math

import numpy as np

from .adhesion import AdhesiveIteration, _pressure_control as pressure_control
from .results import StepRecord, contact_perimeter
from .settings import SolverSettings
from .units import Units, check_loads

#: The iterations an adhesive step can end on (the ``solver_path`` flag).
ADHESIVE_PATHS = ("adhesive",)

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

    def __init__(self, h: np.ndarray, settings: SolverSettings):
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
            cols.update(effect.finish(out.pressure, None, p0))
        step = StepRecord(out.pressure, mask, out.area_fraction, out.mean_gap,
                          contact_perimeter(mask, s.length, True), out.iterations, float(residual),
                          bool(residual <= s.tol), cols, "adhesive")
        return step, (out.gap.copy() if keep_gap else None)

    def unload(self, increment: float, max_steps: int = 400) -> tuple[np.ndarray, np.ndarray]:
        """Unload under displacement control from the last step until no node touches.

        The mean gap grows by ``increment`` [length] a step, each step warm-started from the last;
        returns the mean gaps [length] and mean pressures [pressure] of the steps, shape (k,).
        The most tensile mean pressure is the pull-off pressure under load control.
        """
        s, gap = self.settings, self.gap
        gbar, gaps, loads = float(gap.mean()), [], []
        for _ in range(max_steps):
            gbar += increment
            self.it.start(gap, gbar)
            self.it.solve(gbar, s.tol, s.max_iter)
            _, residual, mean_p = self.it.check(gbar)
            gap = self.it.g.copy()
            gaps.append(gbar)
            loads.append(mean_p if math.isfinite(residual) else math.nan)
            if not np.any(gap == 0.0):
                break
        return np.array(gaps), np.array(loads)
