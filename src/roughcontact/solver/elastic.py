"""The elastic iteration: Polonsky & Keer's constrained CG, optionally Fourier-preconditioned.

:func:`pk_solve` solves one load step of the unilateral problem
``{p >= 0, g >= 0, p g = 0, mean(p) = p0}`` on a :class:`~.workspace.Workspace`
(docs/solver.md, "Algorithm").
"""

from __future__ import annotations

import math

import numpy as np

from .projection import enforce_mean
from .workspace import StallGuard, Workspace, dot

#: After a projection that takes at least this fraction of ``F`` out of contact, the next ``beta``
#: is Fletcher-Reeves' (as after a full projection) instead of Polak-Ribiere's. Measured: on
#: frt-2's plateau (SurfaceTopography's file) Polak-Ribiere's kept history cycles with period 2
#: (~11 000 nodes join, ~4 400 leave) until the stall guard; Fletcher-Reeves' converges the step in
#: 16 iterations. On synthetic surfaces a projection clips ~10 of ~17 000 nodes: the rule rarely
#: applies there, and it changed the iterations by less than 1 % (4 cases at N = 512).
FR_AFTER_LOSS = 0.1


def pk_solve(ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool | None):
    """Solve one elastic load step in place on ``ws`` from the pressure in ``ws.P``.

    ``ws.P`` must be >= 0 with mean ``p0``; ``fresh`` says whether ``ws.w``
    already equals ``K P - h`` (True), must be computed (False), or equals it up to
    single-precision round-off (None: not recomputed, but not taken as fresh either).
    Returns ``(iterations, converged)`` with ``ws.P`` and ``ws.w`` consistent
    (``ws.w`` freshly recomputed) on exit.
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

    def __init__(self, ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool | None):
        self.ws, self.tol = ws, tol
        self.target = p0 * ws.size
        self.scale = ws.scale(p0)
        self.inv_norm = 1.0 / (self.target * self.scale)
        self.maskf = ws.mask.ravel()
        self.precond = ws.method != "pk"
        self.single = ws.method == "pk-fourier-f32"
        ws.setup_method()
        self.Zf = ws.Z.ravel() if self.precond else None
        # single precision: w drifts from K p - h by ~1e-7 of the steps taken; it is
        # recomputed in float64 when the residual falls below each of these levels
        self.next_sync = 1e-5
        self.ksig = ws.sigma if self.single else 1.0
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
            if self.single:
                self.ws.apply_m32_on(self.idx, g_c, a_c)
                a_c *= self.ksig  # the float32 product is M g / sigma
            else:
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
        if self.single:
            return self._step_single()
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

    def _step_single(self) -> bool:
        """:meth:`_step` with single-precision transforms: one forward and one inverse per step.

        ``t . K t`` comes from the spectrum of ``t`` (Parseval), so the step length is known
        before the inverse transform, and a step that leaves ``p >= 0`` folds the clipped part
        into that same inverse (:meth:`_project_single`): ``K p`` is never transformed afresh.
        """
        ws, idx, t_c, a_c = self.ws, self.idx, self.t_c, self.a_c
        spec = ws.spectrum32_on(idx, t_c)
        tau = self._trial(ws.quadratic32(spec) * ws.sigma ** 2)  # from t . K t
        if tau is None:
            return False
        if not bool((a_c <= 0.0).any()):
            self.p_c, self.a_c = a_c, self.p_c
            R = ws.displacement32(spec)  # K t / sigma
            np.multiply(R, R.dtype.type(tau * self.ksig), out=R)
            np.subtract(ws.w, R, out=ws.w)  # u <- u - tau K t: exact, no FFT pair for p
        elif not self._project_single(a_c, tau):
            self._project(a_c)
            return True
        self.fresh = False
        return True

    def _project_single(self, trial: np.ndarray, tau: float) -> bool:
        """Projection of ``trial = p - tau t`` onto ``p >= 0`` with the exact mean, ``w`` updated.

        The new pressure is ``s max(trial, 0)`` (``s`` restores the mean), so
        ``p_new - p = x - tau t`` with ``x = max(-trial, 0) + (s - 1) s^-1 p_new`` on ``F``: one
        forward transform of that change (``F[t]`` has given the step length and is not needed
        any more) and one inverse, and ``w`` moves by ``K (p_new - p)`` like an ordinary step;
        ``K p`` is never transformed afresh. Transforming the change itself, rather than ``x``
        combined with ``F[t]`` in the spectrum, saves two passes over the half spectrum. False
        (nothing done) when no pressure is left, for :meth:`_project`'s uniform restart.
        """
        ws, idx = self.ws, self.idx
        x = np.maximum(-trial, 0.0)  # the clipped part
        np.maximum(trial, 0.0, out=trial)
        total = float(trial.sum())
        if not total > 0.0:
            return False
        scale = self.target / total
        x += (scale - 1.0) * trial
        trial *= scale
        x -= tau * self.t_c  # p_new - p on F
        R = ws.displacement32(ws.spectrum32_on(idx, x))  # K (p_new - p) / sigma
        np.multiply(R, R.dtype.type(self.ksig), out=R)
        np.add(ws.w, R, out=ws.w)
        keep = trial > 0.0
        gone = idx[~keep]
        self.maskf[gone] = False
        ws.Pf[gone] = 0.0
        self.idx, self.p_c = idx[keep], trial[keep]
        if self.g_prev is not None:
            self.g_prev = None if gone.size >= FR_AFTER_LOSS * idx.size else self.g_prev[keep]
        t_c = self.t_c = self.t_c[keep]
        if t_c.size:
            t_c -= t_c.mean()
        self.g_c, self.a_c = np.empty_like(self.p_c), np.empty_like(self.p_c)
        return True

    def _project(self, trial: np.ndarray) -> None:
        """Polonsky-Keer projection of ``trial`` onto ``p >= 0``, exact mean, fresh ``K p``."""
        ws, old = self.ws, self.idx
        np.maximum(trial, 0.0, out=trial)
        ws.Pf[old] = trial
        ws.Tf[old] = self.t_c  # T is zero off F (the single-precision steps do not write it)
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


