"""The elastic iteration: Polonsky & Keer's constrained CG, optionally Fourier-preconditioned.

:func:`pk_solve` solves one load step of the unilateral problem
``{p >= 0, g >= 0, p g = 0, mean(p) = p0}`` on a :class:`~.workspace.Workspace`
(package docstring, "Algorithm").
"""

from __future__ import annotations

import math

import numpy as np

from .projection import enforce_mean
from .workspace import StallGuard, Workspace, dot


def pk_solve(ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool):
    """Solve one elastic load step in place on ``ws`` from the pressure in ``ws.P``.

    ``ws.P`` must be >= 0 with mean ``p0``; ``fresh`` says whether ``ws.w``
    already equals ``K P - h``. Returns ``(iterations, converged)`` with ``ws.P``
    and ``ws.w`` consistent (``ws.w`` freshly recomputed) on exit.
    """
    return PKIteration(ws, p0, tol, max_iter, fresh).run()


class PKIteration:
    """Polonsky & Keer's CG on the free set ``F`` for one load step, state and moves.

    The free set ``idx`` (flat indices into the ``(n, n)`` fields of ``ws``) holds
    the nodes in contact and those that joined since the last projection; on it
    ``p_c`` is the pressure, ``g_c`` the gap with its mean over ``F`` removed,
    ``t_c`` the search direction and ``a_c`` scratch (all float64, shape
    ``(idx.size,)``). ``fresh`` says whether ``ws.w`` equals ``K P - h`` exactly or
    has been updated incrementally since. With ``pk-fourier-f32`` the products
    are single precision and ``ws.w`` is recomputed in float64 below each level
    ``next_sync`` of the residual.
    """

    def __init__(self, ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool):
        self.ws, self.tol = ws, tol
        self.target = p0 * ws.size
        self.scale = ws.scale(p0)
        self.inv_norm = 1.0 / (self.target * self.scale)
        self.maskf = ws.mask.ravel()
        self.precond = ws.method != "pk"
        self.single = ws.method == "pk-fourier-f32"
        ws.setup_method()
        self.Zf = ws.Z.ravel() if self.precond else None
        self.apply_m = ws.apply_m32 if self.single else ws.apply_m
        self.apply_k = ws.apply_k32 if self.single else ws.apply_k
        # single precision: w drifts from K p - h by ~1e-7 of the steps taken; it is
        # recomputed in float64 when the residual falls below each of these levels
        self.next_sync = 1e-5
        self.ksig = ws.sigma if self.single else 1.0
        if not fresh:
            ws.refresh()
        self.idx = ws.active_set()
        self.p_c = ws.Pf[self.idx]
        self.t_c = np.zeros_like(self.p_c)
        self.g_c, self.a_c = np.empty_like(self.p_c), np.empty_like(self.p_c)
        ws.T.fill(0.0)
        self.fresh = True
        self.delta, self.g_old = 0.0, 1.0
        self.it = 0
        self.guard = StallGuard(max_iter)
        self.converged = False
        self.gbar = 0.0
        self.residual = math.inf
        self.joined_after = 0  # > 0: nodes from this index on joined F this iteration
        self.ncand, self.cand, self.g_cand = 0, None, None

    def run(self) -> tuple[int, bool]:
        """Iterate to convergence or a stop; ``(iterations, converged)``."""
        while True:
            residual = self.residual = self._measure()
            if residual <= self.tol:
                if self.fresh:
                    self.converged = True
                    break
                self._resync()  # incremental updates may have drifted: confirm on a fresh K p
                continue
            if self.single and residual < self.next_sync and not self.fresh:
                # float64 gap below 1e-5 and after every further four decades
                while self.next_sync > residual:
                    self.next_sync *= 1e-4
                self._resync()
                continue
            if self.guard.stop(residual, self.it):
                break
            self.it += 1
            if self.ncand:
                self._join()
            if self.idx.size == 0:
                break
            if not (self._direction() and self._step()):
                break  # breakdown or a null direction: the final check decides
        return self._finish()

    def _measure(self) -> float:
        """Gap on ``F`` (zero mean there), sign violations off ``F``, and the residual."""
        ws, idx, g_c = self.ws, self.idx, self.g_c
        nf = idx.size
        if nf:
            np.take(ws.wf, idx, out=g_c)
            self.gbar = g_c.sum() / nf
            g_c -= self.gbar
        # sign violations: out-of-contact nodes with g < 0
        np.less(ws.w, self.gbar, out=ws.bbuf)
        np.greater(ws.bbuf, ws.mask, out=ws.bbuf)  # (w < gbar) & ~mask, for booleans
        self.ncand = np.count_nonzero(ws.bbuf)
        pen = 0.0
        if self.ncand:
            self.cand = np.flatnonzero(ws.bbuf)
            self.g_cand = ws.wf[self.cand] - self.gbar
            pen = -float(self.g_cand.min())
        orth = 0.0
        if nf:
            pen = max(pen, -float(g_c.min()))
            np.abs(g_c, out=self.a_c)
            orth = dot(self.p_c, self.a_c) * self.inv_norm
        return max(orth, pen / self.scale, 0.0)

    def _join(self) -> None:
        """Violating nodes join ``F`` and the CG restarts (PK's rule).

        Folding them into the search direction keeps the update of ``u`` exact.
        """
        self.joined_after = self.idx.size
        self.idx = np.concatenate([self.idx, self.cand])
        self.p_c = np.concatenate([self.p_c, np.zeros(self.ncand)])
        self.g_c = np.concatenate([self.g_c, self.g_cand])
        self.a_c = np.empty_like(self.p_c)
        self.t_c = np.empty_like(self.p_c)
        self.maskf[self.cand] = True
        self.delta = 0.0

    def _direction(self) -> bool:
        """Conjugate direction ``t_c``, zero mean on ``F`` so that mean(p) is kept.

        False at a breakdown (``g.z`` not positive and finite, round-off level).
        """
        g_c, t_c, a_c, nf = self.g_c, self.t_c, self.a_c, self.idx.size
        restart = not (self.delta > 0.0 and self.g_old > 0.0)
        if self.precond:
            if self.joined_after:
                # gradient on the enlarged set: zero mean on F (shifts d only)
                g_c -= g_c.sum() / nf
                self.joined_after = 0
            # z = P_F M P_F g, zero mean on F; beta = g.z / g_old.z_old
            self.Zf[self.idx] = g_c
            _take(self.apply_m(self.ws.Z).ravel(), self.idx, a_c)
            if self.single:
                a_c *= self.ksig  # the float32 product is M g / sigma
            self.Zf[self.idx] = 0.0
            a_c -= a_c.sum() / nf
            G = dot(g_c, a_c)
            if not (G > 0.0 and math.isfinite(G)):
                return False
            if restart:
                t_c[...] = a_c
            else:
                t_c *= G / self.g_old
                t_c += a_c
        else:
            G = dot(g_c, g_c)
            if restart:
                t_c[...] = g_c
                if self.joined_after:
                    # Restore zero mean on the nodes already in contact only: each
                    # joining node keeps t = g (< 0), so the step moves it into the
                    # contact set as PK's rule does instead of clipping it at once.
                    # g.t = |g|^2 still holds because g has zero mean on the old
                    # free set.
                    t_c[: self.joined_after] -= t_c.sum() / self.joined_after
                self.joined_after = 0
            else:
                t_c *= self.delta * G / self.g_old
                t_c += g_c
        self.g_old = G
        self.delta = 1.0
        return True

    def _step(self) -> bool:
        """Exact line search along ``-t``; project onto ``p >= 0`` if the step leaves it.

        False for a null direction (nothing can move: reported as not converged).
        """
        ws, idx, t_c, a_c = self.ws, self.idx, self.t_c, self.a_c
        ws.Tf[idx] = t_c
        Rf = self.apply_k(ws.T).ravel()
        _take(Rf, idx, a_c)
        if self.single:
            a_c *= ws.sigma  # the float32 product is K t / sigma
        rt = dot(a_c, t_c)
        tau = dot(self.g_c, t_c) / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tau) and tau > 0.0):
            return False
        np.multiply(t_c, -tau, out=a_c)  # trial pressure in a_c
        a_c += self.p_c
        if np.count_nonzero(a_c <= 0.0) == 0:
            self.p_c, self.a_c = a_c, self.p_c
            np.multiply(Rf, Rf.dtype.type(tau * self.ksig), out=Rf)
            ws.wf -= Rf  # u <- u - tau K t: exact, no FFT pair for p
            self.fresh = False
        else:
            self._project(a_c)
        return True

    def _project(self, trial: np.ndarray) -> None:
        """Polonsky-Keer projection of ``trial`` onto ``p >= 0``, exact mean, fresh ``K p``."""
        ws = self.ws
        np.maximum(trial, 0.0, out=trial)
        ws.Pf[self.idx] = trial
        enforce_mean(ws.P, self.target, None)
        self.idx = ws.active_set()
        t_c = self.t_c = ws.Tf[self.idx]
        if t_c.size:
            t_c -= t_c.mean()
        ws.T.fill(0.0)
        self.p_c = ws.Pf[self.idx]
        self.g_c, self.a_c = np.empty_like(self.p_c), np.empty_like(self.p_c)
        if self.single and self.next_sync == 1e-5 and self.residual > self.next_sync:
            # far from convergence u = K p in float32 is accurate enough (~1e-7
            # of u); the float64 recomputations below 1e-5 take over from there
            np.multiply(ws.apply_k32(ws.P), self.ksig, out=ws.w)
            ws.w -= ws.h
            self.fresh = False
        else:
            ws.refresh()
            self.fresh = True

    def _resync(self) -> None:
        """Pressure of ``F`` back into the field with the exact mean; ``w`` from a fresh ``K p``."""
        _sync_pressure(self.ws, self.idx, self.p_c, self.target)
        self.ws.refresh()
        self.fresh = True

    def _finish(self) -> tuple[int, bool]:
        """Leave ``ws.P``, ``ws.w`` and ``ws.mask`` consistent; ``(iterations, converged)``."""
        ws = self.ws
        ws.Pf[self.idx] = self.p_c
        if not self.fresh:
            self._resync()
        # An early exit right after nodes joined leaves them flagged with p = 0.
        np.greater(ws.P, 0.0, out=ws.mask)
        return self.it, self.converged


def _take(src: np.ndarray, idx: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = src[idx]``, converting a float32 ``src`` to float64."""
    if src.dtype == out.dtype:
        np.take(src, idx, out=out)
    else:
        out[...] = src[idx]


def _sync_pressure(ws, idx, p_c, target):
    """Write the contact-set pressure back to the full field with the exact mean.

    Between full rebuilds the mean drifts only by round-off; the rescale is
    ``1 + O(1e-16)`` and keeps ``mean(p) = p0`` to machine precision.
    """
    if not p_c.size:
        return
    s = p_c.sum()
    if s > 0 and target > 0:
        p_c *= target / s
    ws.Pf[idx] = p_c


