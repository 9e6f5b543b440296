"""The capped iteration: gradient projection / CG on ``{0 <= p <= H, mean(p) = p0}``.

Used when an effect bounds the pressure from above (:class:`~.effects.PlasticityCap`);
docs/solver.md, "Algorithm" (*With a hardness*).
"""

from __future__ import annotations

import math

import numpy as np

from .projection import project
from .workspace import StallGuard, Workspace, dot

#: Dostal's proportioning test: a gradient-projection step when the chopped gradient's squared norm
#: exceeds this fraction of the free gradient's (``Gamma^2``), else a CG step on the face. Measured
#: against 1 (30 steps, N = 512 and 1024, four capped cases): 0.1 took 7-12 % fewer iterations,
#: 0.03 9-14 % fewer and 0.88-0.94 of the CPU (two rounds at N = 1024); 0.01 within 1-2 % of 0.03.
PROPORTIONING = 0.03


def offset_no_free(w, zero, capd) -> float:
    """``gbar = -d`` when no node is strictly between the bounds.

    Any ``d`` in ``[max(-w) over p = 0, min(-w) over p = H]`` satisfies the sign
    conditions; the middle of that interval is taken (or of the violated one,
    which minimises the largest violation).
    """
    lo = float((-w[zero]).max()) if zero.any() else -math.inf
    hi = float((-w[capd]).min()) if capd.any() else math.inf
    if math.isfinite(lo) and math.isfinite(hi):
        d = 0.5 * (lo + hi)
    elif math.isfinite(lo):
        d = lo
    elif math.isfinite(hi):
        d = hi
    else:
        d = 0.0
    return -d


def _precondition(ws: Workspace, idx: np.ndarray, g_f: np.ndarray) -> tuple[np.ndarray, float]:
    """``z = P_F M P_F g`` with its mean over ``F`` removed, and ``g.z`` (one FFT pair)."""
    Z = ws.Z.ravel()
    Z[idx] = g_f
    z_f = ws.apply_m(ws.Z)[ws.nodes(idx)]
    Z[idx] = 0.0
    z_f -= z_f.sum() / idx.size
    return z_f, dot(g_f, z_f)


def box_solve(ws: Workspace, p0: float, tol: float, max_iter: int, cap: float, fresh: bool):
    """Solve one capped load step in place on ``ws`` from the pressure in ``ws.P``.

    ``ws.P`` must satisfy ``0 <= P <= cap`` with mean ``p0``. Gradient
    projection / CG with proportioning (module docstring); every step lowers
    the energy ``1/2 p.Kp - h.p`` and keeps the bounds and the mean. Returns
    ``(iterations, converged)`` with ``ws.w`` freshly recomputed on exit.

    The sets ``p = 0``, ``p = H`` and the free set (index array ``idx``) change
    only in projection steps; a CG step inside the face touches the full grid
    only for the transform, the update of ``w`` and two sign tests.
    """
    return BoxIteration(ws, p0, tol, max_iter, cap, fresh).run()


class BoxIteration:
    """Gradient projection / CG with proportioning for one capped load step.

    Flat views ``P`` and ``w`` of ``ws``'s pressure and gap (shape ``(nx*ny,)``);
    boolean masks ``zero_m`` (``p = 0``) and ``cap_m`` (``p = H``) and the free
    set ``idx`` (flat indices, ``0 < p < H``); ``t`` the CG direction, zero off
    ``idx``. Each :meth:`_measure` leaves the zero-mean gap ``g_f`` on the free
    set and the violations ``g_z`` (at ``p = 0``, indices ``vz``) and ``g_c``
    (at ``p = H``, indices ``vc``) for the move that follows.
    """

    def __init__(self, ws: Workspace, p0: float, tol: float, max_iter: int, cap: float, fresh: bool):
        n2 = ws.size
        self.ws, self.tol, self.cap = ws, tol, cap
        self.target = p0 * n2
        self.scale = ws.scale(p0)
        self.inv_norm = 1.0 / (self.target * self.scale)
        self.P, self.w = ws.Pf, ws.wf
        self.shape = ws.P.shape
        if not fresh:
            ws.refresh()
        self.fresh = True
        xp = ws.xp
        self.zero_m = xp.empty(n2, dtype=bool)
        self.cap_m = xp.empty(n2, dtype=bool)
        self.b1 = xp.empty(n2, dtype=bool)
        self.t = xp.zeros(n2)  # CG direction, zero off the free set
        self.precond = ws.method != "pk"
        if self.precond:
            ws.setup_method()
        self.kt = xp.empty(n2)
        # the moves' work arrays, allocated once: with fresh grid-sized temporaries at every move the
        # solve took up to 1.3x the CPU after another iteration had run in the process (N = 512; alike
        # with glibc's mmap threshold fixed), a cost of the allocator's state, not of the iteration
        self.g_all, self.trial, self.step, self.ks = (xp.empty(n2) for _ in range(4))
        self.seg = xp.zeros(n2)  # _leave_box's step: zero but on the free set while it is used
        # the last CG step's gradient on the face, zero elsewhere (Polak-Ribiere's beta)
        self.g_prev = xp.zeros(n2) if self.precond else None
        self.idx = self._active_sets()
        self.g_old = 0.0
        self.restart = True
        self.recentre = False  # the face changed under a kept direction: make it zero-mean again
        self.alpha = 0.0  # gradient-projection step length; 0 = not known yet
        self.expand = False  # the last CG step stopped short inside the box: a projection step follows
        self.it = 0
        self.guard = StallGuard(max_iter)
        self.converged = False

    def _active_sets(self) -> np.ndarray:
        """Masks of ``p = 0`` and ``p = H``; flat indices of the free set."""
        np.less_equal(self.P, 0.0, out=self.zero_m)
        np.greater_equal(self.P, self.cap, out=self.cap_m)
        np.logical_or(self.zero_m, self.cap_m, out=self.b1)
        np.logical_not(self.b1, out=self.b1)
        return np.flatnonzero(self.b1)

    def run(self) -> tuple[int, bool]:
        """Iterate to convergence or a stop; ``(iterations, converged)``."""
        while True:
            residual = self._measure()
            if residual <= self.tol:
                if self.fresh:
                    self.converged = True
                    break
                self.ws.refresh()
                self.fresh = True
                continue
            if self.guard.stop(residual, self.it):
                break
            self.it += 1
            # proportioning: sign violations at the bounds vs gradient on the face
            chopped = dot(self.g_z, self.g_z) + dot(self.g_c, self.g_c)
            G = dot(self.g_f, self.g_f)
            if self.idx.size == 0 or self.expand or chopped > PROPORTIONING * G:
                self.expand = False
                moved = self._projection_step()
            else:
                moved = self._cg_step(G)
            if not moved:
                break  # no descent left at this precision: the final check decides
        if not self.fresh:
            self.ws.refresh()
        np.greater(self.ws.P, 0.0, out=self.ws.mask)
        return self.it, self.converged

    def _measure(self) -> float:
        """Gap on the free set (zero mean there), violations at the bounds, residual."""
        w, b1, idx = self.w, self.b1, self.idx
        nf = idx.size
        self.p_f = self.P[idx]
        g_f = self.g_f = w[idx]
        if nf:
            gbar = float(g_f.sum()) / nf
            g_f -= gbar
        else:
            gbar = offset_no_free(w, self.zero_m, self.cap_m)
        self.gbar = gbar
        # sign violations: g < 0 at p = 0, g > 0 at p = H
        np.less(w, gbar, out=b1)
        b1 &= self.zero_m
        self.vz = np.flatnonzero(b1)
        self.g_z = w[self.vz] - gbar
        np.greater(w, gbar, out=b1)
        b1 &= self.cap_m
        self.vc = np.flatnonzero(b1)
        self.g_c = w[self.vc] - gbar
        pen = max(0.0, -float(self.g_z.min()) if self.vz.size else 0.0, -float(g_f.min()) if nf else 0.0)
        e_cap = float(self.g_c.max()) if self.vc.size else 0.0
        orth = dot(self.p_f, np.abs(g_f)) * self.inv_norm if nf else 0.0
        return max(orth, pen / self.scale, e_cap / self.scale)

    def _projection_step(self) -> bool:
        """Gradient projection ``P(p - alpha g)`` with an exact line search on the segment.

        False when the segment is no descent direction (round-off level).
        """
        ws, P, cap = self.ws, self.P, self.cap
        g = np.subtract(self.w, self.gbar, out=self.g_all)
        if not self.alpha > 0.0:
            self.alpha = self._first_alpha()
        trial = np.multiply(g, self.alpha, out=self.trial)
        np.subtract(P, trial, out=trial)
        step = project(trial, self.target, cap, out=self.step, work=self.b1)
        step -= P
        ks = self.ks
        np.copyto(ks.reshape(self.shape), ws.apply_k(step.reshape(self.shape)))  # one copy, strided or not
        sks, gs = dot(step, ks), dot(g, step)
        if not (sks > 0.0 and gs < 0.0 and math.isfinite(sks)):
            return False
        theta = min(1.0, -gs / sks)
        self.alpha = dot(step, step) / sks  # Barzilai-Borwein, for the next projection
        if theta < 1.0:
            step *= theta
            ks *= theta
        P += step
        np.clip(P, 0.0, cap, out=P)
        self.w += ks
        self._sets_changed(keep=False)
        return True

    def _first_alpha(self) -> float:
        """Cauchy step length ``r.r / r.Kr`` of the projected gradient ``r`` (one FFT pair)."""
        r = self.ws.xp.zeros(self.ws.size)  # projected gradient: free part and violations
        r[self.idx] = self.g_f
        r[self.vz] = self.g_z
        r[self.vc] = self.g_c
        act = np.concatenate([self.idx, self.vz, self.vc])
        r[act] -= r[act].mean()
        kr = self.ws.apply_k(r.reshape(self.shape)).ravel()
        rkr = dot(r, kr)
        return dot(r, r) / rkr if rkr > 0.0 else 1.0

    def _sets_changed(self, keep: bool) -> None:
        """After a move that may change the bounds: new sets, ``w`` updated.

        ``keep`` (a CG step that left the box, preconditioned iteration only): the direction
        and the last gradient stay, zeroed off the new face, and the next CG step conjugates
        against them with Polak-Ribiere's ``beta`` (as the elastic iteration does across joins:
        :class:`~.compressed.CompressedKernels`); else the CG restarts. A gradient-projection step always
        restarts it (keeping the direction there too cost 1.03-1.06x the CPU, measured at N = 512).
        """
        self.idx = self._active_sets()  # leaves the face's mask in b1
        keep = keep and self.precond
        if keep:
            np.multiply(self.t, self.b1, out=self.t)
            np.multiply(self.g_prev, self.b1, out=self.g_prev)
        self.restart, self.recentre = not keep, keep
        self.fresh = False

    def _cg_step(self, G: float) -> bool:
        """Conjugate gradient on the face ``{0 < p < H}``, direction zero-mean there.

        ``G = g_f.g_f``. With a preconditioner, ``z = P_F M P_F g`` (mean over ``F`` removed) as in
        :class:`~.compressed.CompressedKernels`. False at a breakdown or a null direction.
        """
        idx, t, g_f, p_f = self.idx, self.t, self.g_f, self.p_f
        z_f, Gz = (_precondition(self.ws, idx, g_f) if self.precond else (g_f, G))
        if not (Gz > 0.0 and math.isfinite(Gz)):
            return False
        if self.restart or self.g_old <= 0.0:
            t.fill(0.0)
            t_f = z_f
        else:
            t_f = t[idx]
            if self.recentre:
                t_f -= t_f.sum() / idx.size  # zero mean on the new face: the step keeps the load
            t_f *= self._beta(Gz, z_f)
            t_f += z_f
            if not dot(g_f, t_f) > 0.0:  # conjugated across a change of face: no descent
                t_f = z_f
        t[idx] = t_f
        if self.precond:
            self.g_prev[idx] = g_f
        self.g_old = Gz
        self.restart = self.recentre = False
        np.copyto(self.kt.reshape(self.shape), self.ws.apply_k(t.reshape(self.shape)))  # one copy, strided or not
        tkt, rt = dot(t_f, self.kt[idx]), dot(g_f, t_f)
        if not (tkt > 0.0 and rt > 0.0 and math.isfinite(tkt)):
            return False
        tau = rt / tkt
        if not self.precond:
            self.alpha = tau  # a step length along -g: a fair guess for the next projection
        y_f = p_f - tau * t_f
        if y_f.min() > 0.0 and y_f.max() < self.cap:
            self.P[idx] = y_f
            self.kt *= tau
            self.w -= self.kt
            self.fresh = False
            return True
        if not self._leave_box(y_f, t_f):
            return False
        self._sets_changed(keep=True)
        return True

    def _beta(self, Gz: float, z_f: np.ndarray) -> float:
        """``t = z + beta t``: Fletcher-Reeves' ``Gz / g_old`` without a preconditioner (a fixed face
        between restarts), Polak-Ribiere's ``max(0, z.(g - g_prev)) / g_old`` with one."""
        if not self.precond:
            return Gz / self.g_old
        return max(0.0, (Gz - dot(self.g_prev[self.idx], z_f)) / self.g_old)

    def _leave_box(self, y_f: np.ndarray, t_f: np.ndarray) -> bool:
        """The CG trial ``y_f`` left the box: move to the face's projection of it.

        The trial is projected onto ``{0 <= p_F <= H, sum p_F fixed}`` with a line
        search on the segment; when that is no descent, the CG step is truncated at
        the first bound met along ``-t``. False when no bound lies ahead (round-off).
        A move that stops short of the projected trial changes the bounds at a few nodes only, and
        from a pressure far from the solution CG steps then release one node each: the next move is a
        gradient-projection step (``expand``, as Dostál's expansion step), whatever the proportioning
        test says. Without it SurfaceTopography's sur-2.sur (cap 0.2 E* h') stalled at its 14th
        step with 24 000 nodes to release, one an iteration.
        """
        idx, p_f, cap, P = self.idx, self.p_f, self.cap, self.P
        x_f = project(y_f, float(p_f.sum()), cap)
        s_f = x_f - p_f
        step = self.seg
        step[idx] = s_f
        ks = self.ws.apply_k(step.reshape(self.shape))  # 2-D, maybe a strided view of the product's buffer
        step[idx] = 0.0
        sks, gs = dot(s_f, ks[self.ws.nodes(idx)]), dot(self.g_f, s_f)
        if sks > 0.0 and gs < 0.0:
            theta = 1.0 if gs + 0.5 * sks < 0.0 else -gs / sks  # the projected point if it lowers the energy
            if theta >= 1.0:
                P[idx] = x_f
            else:
                P[idx] = np.clip(p_f + theta * s_f, 0.0, cap)
                ks *= theta
                self.expand = True
            self.ws.w += ks
            return True
        # truncated CG step: up to the first bound met along -t
        with np.errstate(divide="ignore", invalid="ignore"):
            lim = np.where(t_f > 0.0, p_f / t_f, np.where(t_f < 0.0, (p_f - cap) / t_f, np.inf))
        j = int(np.argmin(lim))
        tmax = float(lim[j])
        if not (math.isfinite(tmax) and tmax >= 0.0):
            return False  # no bound ahead although the trial left the box: round-off
        new = np.clip(p_f - tmax * t_f, 0.0, cap)
        new[j] = 0.0 if t_f[j] > 0.0 else cap
        P[idx] = new
        self.kt *= tmax
        self.w -= self.kt
        self.expand = True
        return True
