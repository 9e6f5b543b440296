"""The contact solver of one surface: units, effects, warm starts and the step loop.

Public entry points :func:`solve_contact` and :func:`solve_step` (re-exported
by :mod:`roughcontact.solver`); docs/solver.md states the problem, the units,
the algorithms and the convergence criterion.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.backend import get_backend
from .box import box_solve
from .check import MEAN_RTOL, final_check
from .compressed import pk_solve
from .projection import enforce_mean
from .results import StepRecord, contact_perimeter
from .settings import SolverSettings
from .steps import LINEAR, SCALED, UNIFORM, fall_back, run_path, start_fresh, start_kind
from .units import Units, check_loads, frexp_ratio
from .workspace import SOLVER_PATHS, STICKY, Workspace

#: ``fresh`` as :func:`~.compressed.pk_solve` takes it, by :func:`~.steps.start_fresh`'s code (1, 0, -1)
_PK_FRESH = {1: True, 0: False, -1: None}


class ContactSolver:
    """Validated problem of one surface: units, effects, workspace and warm starts.

    ``h`` (nx, ny) is validated heights [length]; ``settings`` a :class:`~.settings.SolverSettings`
    already :meth:`~.settings.SolverSettings.checked` for ``h.shape`` (the cell, the elastic
    iteration, the half-space and the effects acting on the iteration, :mod:`.effects`).
    """

    #: the iterations a step can end on (the ``solver_path`` flag)
    paths = SOLVER_PATHS
    #: per-step long names that differ from :func:`~.results.to_dataset`'s (none)
    long_names: dict = {}

    def __init__(self, h: np.ndarray, settings: SolverSettings):
        self.settings = settings
        self.shape, self.size = h.shape, h.size
        self.length = settings.length
        self.tol, self.max_iter = settings.tol, settings.max_iter
        self.effects = list(settings.effects)
        self.units = Units(h, settings.e_star, settings.length)
        self.threads = settings.threads
        self.method = settings.method
        self.start_method = self.method  # the iteration each step starts on (_iterate)
        self.boundary = settings.boundary
        self.periodic = self.boundary == "periodic"
        for effect in self.effects:
            effect.check_surface(self.units, self.periodic)
        self._punch = None  # flat surface on the free half-space: solution at unit load
        self.array_backend = settings.array_backend
        self.ws = None if self.units.flat else Workspace(self.units.heights, self.length, self.threads,
                                                         self.method, self.boundary,
                                                         backend=self.array_backend)
        for effect in self.effects:
            effect.bind(self.units)
        caps = [e.upper_bound for e in self.effects if e.upper_bound is not None]
        self.cap = min(caps) if caps else None
        self.hardness = settings.hardness  # the physical cap, for starting pressures given by the caller
        self.prev = None  # internal p0 of the last solved step
        self._older = None  # (p0, pressure, w or None) of the step before the last
        self._last = None  # pressure of the last step
        self._last_w = None  # its w = K p - h (float32 iteration only: _linear_start)
        self._pbuf = np.empty(self.shape)

    def check_loads(self, p: np.ndarray, name: str) -> None:
        """Refuse loads an effect cannot carry or float64 cannot represent."""
        for effect in self.effects:
            effect.check_loads(self.units, p, name)
        check_loads(self.units, p, self.shape, name)
        for effect in self.effects:
            effect.check_range(self.units)

    @property
    def backend(self) -> str:
        return self.ws.backend if self.ws is not None else get_backend(self.array_backend).fft_name()

    def start(self, p0: float, initial=None) -> bool | None:
        """Put the starting pressure for ``p0`` in the workspace; returns ``fresh``.

        A given ``initial`` pressure (clipped, scaled to the cap or its maximum, then to the load), or every node
        at the cap where ``p0`` reaches it; else the start of :func:`~.steps.start_kind` (the reference ``"pk"``
        does not extrapolate). ``fresh``: True when ``ws.w`` equals ``K P - h``, False when it must be
        recomputed, None when it is ``K P - h`` up to single-precision round-off of a small part
        (:meth:`_linear_start`).
        """
        ws, cap = self.ws, self.cap
        p_int = self.units.to_internal(p0)
        target = p_int * ws.size
        if initial is not None:
            np.maximum(ws.be.asarray(initial), 0.0, out=ws.P)
            if cap is None:
                top = float(ws.P.max())
                if top > 0:
                    ws.P /= top
            else:
                np.minimum(ws.P, self.hardness, out=ws.P)
                ws.P *= cap / self.hardness
            enforce_mean(ws.P, target, cap)
            return False
        if cap is not None and p_int >= cap:
            # p0 within an ulp of the hardness: every node at the cap
            ws.P.fill(cap)
            return False
        older = None if self.method == "pk" or self._older is None else self._older
        # the linear update of w: the last two steps ended on the float32 iteration (a capped step keeps no gap)
        linear = self.start_method == "pk-fourier-f32" and self._last_w is not None and older is not None \
            and older[2] is not None
        kind, c = start_kind(p_int, self.prev, None if older is None else older[0], linear)
        kind, c = int(kind), float(c)
        if kind == UNIFORM:
            ws.P.fill(p_int)
        elif kind == SCALED:
            s = p_int / self.prev
            ws.P *= s
            if cap is None:
                # p and u = K p scale together, so w = K p - h follows without a transform
                ws.w *= s
                ws.w += (s - 1.0) * ws.h
            else:
                enforce_mean(ws.P, target, cap)
        else:
            # linear in the load through the last two solutions, clipped at 0 (and at the cap)
            ws.P -= older[1]
            ws.P *= c
            ws.P += self._last
            if kind == LINEAR:
                self._linear_start(c, target)
            else:
                np.maximum(ws.P, 0.0, out=ws.P)
                enforce_mean(ws.P, target, cap)
        return _PK_FRESH[int(start_fresh(kind, cap is not None))]

    def _linear_start(self, c: float, target: float) -> None:
        """``ws.w`` for the extrapolated ``P`` (in ``ws.P``, before its clip) without a float64 product
        (:data:`~.steps.LINEAR`).

        ``K`` is linear, so ``P = (1 + c) p_last - c p_older`` has ``w = (1 + c) w_last - c w_older``
        exactly (float64 sums of the last two steps' fresh gaps). The clip of ``P`` at zero (nodes
        leaving contact) adds ``K x`` for the clipped part ``x``: one float32 product, whose round-off
        (~1e-7 of ``K x``) the float32 iteration's float64 recomputations absorb as they do its own.
        The rescale to the mean is exact (``K (s P) = s K P``). It replaces a float64 product per step (a
        float64 pair costs ~2.5 float32 pairs at N = 1024).
        """
        ws = self.ws
        np.subtract(self._last_w, self._older[2], out=ws.w)
        ws.w *= c
        ws.w += self._last_w
        clipped = np.maximum(ws.P, 0.0)
        np.subtract(clipped, ws.P, out=ws.P)  # x >= 0, nonzero where P < 0
        if bool(ws.P.any()):
            ws.setup_method()
            ws.w += ws.sigma * ws.apply_k32(ws.P)
        ws.P[...] = clipped
        s = target / float(ws.P.sum())
        ws.P *= s
        ws.w *= s
        ws.w += (s - 1.0) * ws.h  # K (s P) - h = s (w + h) - h

    def _flat(self, p0: float, keep_gap: bool):
        # exact solution: u = K p0 = 0, so g = 0 with d = h
        n2 = self.size
        p = np.full(self.shape, p0)
        mean_ok = abs(float(p.sum()) - p0 * n2) <= MEAN_RTOL * p0 * n2
        gap = np.zeros(self.shape) if keep_gap else None
        cols = {}
        for effect in self.effects:
            cols.update(effect.finish(p, None, p0))
        return StepRecord(p, p > 0, 1.0, 0.0, 0.0, 0, 0.0, mean_ok, cols, "exact"), gap

    def _flat_punch(self, p0: float, keep_gap: bool):
        """A flat surface on the free half-space: the rigid square (or rectangular) flat punch.

        ``u = K p`` is no longer uniform under a uniform pressure, so the
        problem is solved, once, at unit load in units ``E* = Lx = 1`` with the
        gap scale ``p0 Lx / E*`` (:func:`~.units.gap_scale` of a flat surface) as unit;
        without a cap it is linear in ``p0``, so every step is that solution
        scaled (``iterations`` counts the solve at the first step, 0 after).
        """
        n2 = self.size
        its = 0
        if self._punch is None:
            ws = Workspace(np.zeros(self.shape), self.length, self.threads, self.method, self.boundary,
                           scale=1.0, backend=self.array_backend)
            ws.P.fill(1.0)
            its = pk_solve(ws, 1.0, self.tol, self.max_iter, False)[0]
            ok, residual, gbar, w_sum = final_check(ws, 1.0, self.tol, None)
            self._punch = (ws.be.to_host(ws.P), ws.be.to_host(ws.w - gbar), w_sum / n2 - gbar, float(residual),
                           bool(ok))
        x, g1, mg1, residual, ok = self._punch
        p = x * p0
        mean_ok = ok and abs(float(p.sum()) - p0 * n2) <= MEAN_RTOL * p0 * n2
        fm, fe = frexp_ratio((p0, self.units.length), (self.units.e_star,))  # the gap scale p0 Lx / E*
        try:
            mean_gap = math.ldexp(mg1 * fm, fe)
        except OverflowError:
            mean_gap = math.inf
        with np.errstate(over="ignore", under="ignore"):
            gap = np.ldexp(g1 * fm, fe) if keep_gap else None
        if not (math.isfinite(mean_gap) and (gap is None or np.all(np.isfinite(gap)))):
            raise ValueError(
                f"pressures: the gap at p0={p0!r} overflows float64 in the units of heights; reduce "
                "p0 * length / e_star")
        mask = p > 0
        area = np.count_nonzero(mask) / n2
        step = StepRecord(p, mask, area, mean_gap, contact_perimeter(mask, self.length, periodic=False), its,
                          residual, mean_ok, {}, self.method)
        return step, gap

    def _iterate(self, p_int: float, fresh: bool | None) -> tuple[int, str]:
        """Iterate the step to ``tol``; ``(iterations, path)``, the path being the iteration that ended it.

        A step starts on :attr:`start_method`, the scene's iteration until a step has needed a
        fallback; a step that stalls before ``max_iter`` is handed down the fallbacks
        (:func:`~.steps.fall_back`). A step that needed a fallback makes the method that
        converged it the start of the next steps (``STICKY``), so that one hard surface pays the
        stall window once, not at every step.
        """
        ws, tol = self.ws, self.tol
        if self.cap is not None:
            return box_solve(ws, p_int, tol, self.max_iter, self.cap, fresh)[0], "box"
        path = self.start_method
        its, ok = run_path(ws, path, p_int, tol, self.max_iter, fresh, self.method)
        its, path, ok = fall_back(path, its, ok, self.max_iter,
                                  lambda method, left: run_path(ws, method, p_int, tol, left, True, self.method))
        if ok and STICKY and path != self.start_method:
            self.start_method = path
        return its, path

    def solve(self, p0: float, initial=None, keep_gap: bool = False):
        """Solve the step for the physical mean pressure ``p0``; returns ``(StepRecord, gap)``."""
        if self.units.flat:
            return self._flat(p0, keep_gap) if self.periodic else self._flat_punch(p0, keep_gap)
        ws, units = self.ws, self.units
        n2 = self.size
        fresh = self.start(p0, initial)
        p_int = units.to_internal(p0)
        its, path = self._iterate(p_int, fresh)
        ok, residual, gbar, w_sum = final_check(ws, p_int, self.tol, self.cap)
        if self.method != "pk":
            self._older = None if self.prev is None else (self.prev, self._last, self._last_w)
            self._last = ws.P.copy()
            # fresh after every step (compressed.pk_solve, box); kept for the float32 iteration only
            self._last_w = ws.w.copy() if path == "pk-fourier-f32" else None
        self.prev = p_int
        p = units.pressure(ws.be.to_host(ws.P), out=self._pbuf)
        cols = {}
        for effect in self.effects:
            cols.update(effect.finish(p, ws.P, p0))
        mask = p > 0
        area = np.count_nonzero(mask) / n2
        if area <= 0:
            raise RuntimeError(f"no contact node at p0={p0!r}: the solver lost the load (bug)")
        mean_gap = math.ldexp(w_sum / n2 - gbar, units.e_len)
        gap = units.length_field(ws.be.to_host(ws.w - gbar)) if keep_gap else None
        if not (math.isfinite(mean_gap) and (gap is None or np.all(np.isfinite(gap)))):
            raise ValueError(
                f"pressures: the gap at p0={p0!r} overflows float64 in the units of heights; reduce "
                "p0 * length / e_star or the heights")
        step = StepRecord(p, mask, area, mean_gap, contact_perimeter(mask, self.length, self.periodic), its,
                          float(residual), bool(ok), cols, path)
        return step, gap
