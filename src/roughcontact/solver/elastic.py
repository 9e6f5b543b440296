"""The elastic iteration: Polonsky & Keer's constrained CG, optionally Fourier-preconditioned.

:func:`pk_solve` solves one load step of the unilateral problem
``{p >= 0, g >= 0, p g = 0, mean(p) = p0}`` on a :class:`~.workspace.Workspace`
(docs/solver.md, "Algorithm").
"""

from __future__ import annotations

import math

import numpy as np

from .compressed import solve_f32
from .projection import enforce_mean
from .workspace import StallGuard, Workspace, dot


def pk_solve(ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool | None):
    """Solve one elastic load step in place on ``ws`` from the pressure in ``ws.P``.

    ``ws.P`` must be >= 0 with mean ``p0``; ``fresh`` says whether ``ws.w``
    already equals ``K P - h`` (True), must be computed (False), or equals it up to
    single-precision round-off (None: not recomputed, but not taken as fresh either).
    Returns ``(iterations, converged)`` with ``ws.P`` and ``ws.w`` consistent
    (``ws.w`` freshly recomputed) on exit.
    """
    if ws.method == "pk-fourier-f32":
        return solve_f32(ws, p0, tol, max_iter, fresh)
    return PKIteration(ws, p0, tol, max_iter, fresh).run()


class PKIteration:
    """Polonsky & Keer's CG on the free set ``F`` for one load step, state and moves.

    The free set ``idx`` (flat indices into the ``(n, n)`` fields of ``ws``) holds
    the nodes in contact and those that joined since the last projection; on it
    ``p_c`` is the pressure, ``g_c`` the gap with its mean over ``F`` removed,
    ``t_c`` the search direction and ``a_c`` scratch (all float64, shape
    ``(idx.size,)``). ``fresh`` says whether ``ws.w`` equals ``K P - h`` exactly or
    has been updated incrementally since. ``pk`` and ``pk-fourier`` (float64 products);
    ``pk-fourier-f32`` runs :class:`~.iteration.BatchIteration` (:func:`~.compressed.solve_f32`).
    """

    def __init__(self, ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool | None):
        self.ws, self.tol = ws, tol
        self.target = p0 * ws.size
        self.scale = ws.scale(p0)
        self.inv_norm = 1.0 / (self.target * self.scale)
        self.maskf = ws.mask.ravel()
        self.precond = ws.method != "pk"
        ws.setup_method()
        self.Zf = ws.Z.ravel() if self.precond else None
        if fresh is False:
            ws.refresh()
        self.idx = ws.active_set()
        self.p_c = ws.Pf[self.idx]
        self.t_c = np.zeros_like(self.p_c)
        self.g_c, self.a_c = np.empty_like(self.p_c), np.empty_like(self.p_c)
        ws.T.fill(0.0)
        self.fresh = fresh is not None
        self.delta, self.g_old = 0.0, 1.0
        self.it = 0
        self.guard = StallGuard(max_iter)
        self.converged = False
        self.gbar = 0.0
        self.residual = math.inf
        self.joined_after = 0  # > 0: nodes from this index on joined F this iteration
        self.ncand, self.cand, self.g_cand = 0, None, None
        self.g_prev = None  # the last direction's gradient on F (Polak-Ribiere)

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
        self.ncand = int(np.count_nonzero(ws.bbuf))
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
        """Violating nodes join ``F``.

        Without a preconditioner the CG restarts (PK's rule) and folding the joining nodes into
        the search direction keeps the update of ``u`` exact. With one, the direction is kept,
        zero on the joining nodes (so still zero-mean on ``F``), and the next one is conjugated
        against it: a restart at every join makes the iteration a preconditioned steepest descent
        for as long as a few nodes join at each iteration (fine-scale surfaces: 2-3x the
        iterations in that phase). :meth:`_direction` restarts when that direction is no descent.
        """
        self.joined_after = self.idx.size
        self.idx = np.concatenate([self.idx, self.cand])
        self.p_c = np.concatenate([self.p_c, self.ws.xp.zeros(self.ncand)])
        self.g_c = np.concatenate([self.g_c, self.g_cand])
        self.a_c = np.empty_like(self.p_c)
        if self.precond:
            self.t_c = np.concatenate([self.t_c, self.ws.xp.zeros(self.ncand)])
            if self.g_prev is not None:
                self.g_prev = np.concatenate([self.g_prev, self.ws.xp.zeros(self.ncand)])
        else:
            self.t_c = np.empty_like(self.p_c)
            self.delta = 0.0
        self.maskf[self.cand] = True

    def _direction(self) -> bool:
        """Conjugate direction ``t_c``, zero mean on ``F`` so that mean(p) is kept.

        Preconditioned: ``t = z + beta t`` with Polak-Ribiere's ``beta`` (:meth:`_beta`), kept
        across joins and projections, and ``t = z`` when that is no descent direction.
        False at a breakdown (``g.z`` not positive and finite, round-off level).
        """
        g_c, t_c, a_c, nf = self.g_c, self.t_c, self.a_c, self.idx.size
        restart = not (self.delta > 0.0 and self.g_old > 0.0)
        if self.precond:
            if self.joined_after:
                # gradient on the enlarged set: zero mean on F (shifts d only)
                g_c -= g_c.sum() / nf
                self.joined_after = 0
            # z = P_F M P_F g, zero mean on F
            self.Zf[self.idx] = g_c
            a_c[...] = self.ws.apply_m(self.ws.Z)[self.ws.nodes(self.idx)]
            self.Zf[self.idx] = 0.0
            a_c -= a_c.sum() / nf
            G = dot(g_c, a_c)
            if not (G > 0.0 and math.isfinite(G)):
                return False
            if restart:
                t_c[...] = a_c
            else:
                t_c *= self._beta(G, a_c)
                t_c += a_c
                if not dot(g_c, t_c) > 0.0:  # conjugated across a change of F: no descent
                    t_c[...] = a_c
            self.g_prev = g_c.copy()
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

    def _beta(self, G: float, z_c: np.ndarray) -> float:
        """Polak-Ribiere's ``beta = max(0, z.(g - g_prev) / g_old.z_old)`` for ``t = z + beta t``.

        Fletcher-Reeves' ``G / g_old`` where there is no ``g_prev`` (after a full projection, or
        one that took a large part of ``F`` away: :data:`FR_AFTER_LOSS`).
        ``g_prev`` is the last direction's gradient on ``F``, 0 on the nodes that joined since:
        where ``F`` has changed, the directions are no longer conjugate and the max with 0
        restarts the CG by itself once the new gradient stops being orthogonal to the old one.
        """
        if self.g_prev is None:
            return G / self.g_old
        return max(0.0, (G - dot(self.g_prev, z_c)) / self.g_old)

    def _step(self) -> bool:
        """Exact line search along ``-t``; project onto ``p >= 0`` if the step leaves it.

        False for a null direction (nothing can move: reported as not converged).
        """
        ws, idx, t_c, a_c = self.ws, self.idx, self.t_c, self.a_c
        ws.Tf[idx] = t_c
        R = ws.apply_k(ws.T)  # maybe a strided view of the product's buffer: used in 2-D, not copied
        a_c[...] = R[ws.nodes(idx)]
        tau = self._trial(dot(a_c, t_c))
        if tau is None:
            return False
        if not bool((a_c <= 0.0).any()):
            self.p_c, self.a_c = a_c, self.p_c
            np.multiply(R, tau, out=R)
            ws.w -= R  # u <- u - tau K t: exact, no FFT pair for p
            self.fresh = False
        else:
            self._project(a_c)
        return True

    def _trial(self, rt: float) -> float | None:
        """The exact step length ``tau = g.t / t.Kt`` (``rt = t.Kt``) and the trial ``p - tau t`` in ``a_c``.

        None for a null direction (``tau`` not positive and finite).
        """
        tau = dot(self.g_c, self.t_c) / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tau) and tau > 0.0):
            return None
        np.multiply(self.t_c, -tau, out=self.a_c)
        self.a_c += self.p_c
        return tau

    def _project(self, trial: np.ndarray) -> None:
        """Polonsky-Keer projection of ``trial`` onto ``p >= 0``, exact mean, fresh ``K p``."""
        ws, old = self.ws, self.idx
        np.maximum(trial, 0.0, out=trial)
        ws.Pf[old] = trial
        ws.Tf[old] = self.t_c
        enforce_mean(ws.P, self.target, None)
        self.idx = ws.active_set()
        self.g_prev = None
        t_c = self.t_c = ws.Tf[self.idx]
        if t_c.size:
            t_c -= t_c.mean()
        ws.Tf[old] = 0.0  # the new F is within the old one
        self.p_c = ws.Pf[self.idx]
        self.g_c, self.a_c = np.empty_like(self.p_c), np.empty_like(self.p_c)
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


