"""The batched solve's element-wise passes and per-case reductions: :class:`ArrayKernels`.

:class:`ArrayKernels` are the passes of a round as plain array expressions (any backend); the fused kernels
that replace them are :class:`.cpu.FusedCpuKernels` on the host (numba) and
:class:`.cuda.CupyKernels` on a GPU. The transforms and multipliers they work with are
:mod:`.halfspace`'s.
"""

from __future__ import annotations

import numpy as np


class ArrayKernels:
    """The element-wise passes and per-case reductions of a round, as plain array expressions.

    Every argument is an array of the backend: fields ``(B, nx, ny)``, per-case numbers
    ``(B, 1, 1)``, and the iteration's *vectors on the free set* ``F``: the direction ``t``, the last
    gradient ``g_prev`` and a round's gradient ``g`` and preconditioned gradient ``a``. Here a vector on
    ``F`` is a field, zero off ``F``; :class:`.cpu.FusedCpuKernels` holds it compressed, one value per node
    of ``F`` in its index order, so that a pass over it reads ``|F|`` consecutive values. The iteration
    makes them with :meth:`vector` (or gets them from a kernel) and hands them back unopened; only
    :meth:`gather` and :meth:`scatter` convert. Results of reductions are ``(B, 1, 1)`` float64 (or int64
    for counts).
    :class:`.cuda.CupyKernels` replaces them by fused CUDA kernels (one pass over the fields each) with
    the same results up to the order of summation; the methods named "in place" must update their
    field arguments in place in both.
    """

    def __init__(self, xp):
        self.xp = xp
        # whether the iteration may read the per-case flags at every step (free on the host; on a GPU a
        # synchronisation, so there it reads them at the checks only)
        self.flags_on_host = xp is np

    # -- where a field is split over processes (MPI ranks), their per-case parts combined --------
    # Every reduction below goes through exactly one of these; here each process holds whole fields.

    def allsum(self, local):
        """Per-case sums ``(B, 1, 1)`` of this process's part of the fields, added over the processes."""
        return local

    def allcount(self, local):
        """Per-case counts, added over the processes."""
        return local

    def allmin(self, local):
        """Per-case minima, the least over the processes."""
        return local

    def allany(self, local):
        """Per-case flags, true where any process's is."""
        return local

    def overwritten(self, out) -> None:
        """A transform has written over the buffer ``out`` (an in-place transform's input): nothing to do
        here; :class:`.cpu.FusedCpuKernels`' next sparse write there then zeroes all of it."""

    def free_set(self, mask):
        """The iteration's free set made from ``mask`` (``(B, nx, ny)`` bool): the mask itself here;
        :meth:`.cpu.FusedCpuKernels.free_set` keeps each case's node indices beside it."""
        return mask

    def vector(self, F):
        """A zero vector on ``F``."""
        return self.xp.zeros(F.shape)

    def gather(self, field, F):
        """``field``'s values on ``F`` as a vector on ``F``."""
        return field * F

    def scatter(self, vector, F):
        """A vector on ``F`` as a field, zero off ``F``."""
        return vector * F

    def rsum(self, x):
        return self.allsum(self.xp.sum(x, axis=(-2, -1), keepdims=True, dtype=np.float64))

    def to_mean(self, P, cases, target) -> None:
        """Each case ``b`` of ``cases`` (host ints) scaled in place to the total ``target[b]`` (host floats), where
        it has a positive total: the pressure's mean made exact before ``w`` is recomputed in float64."""
        for b in cases:
            tot = float(self.rsum(P[b:b + 1]).reshape(()))
            if tot > 0:
                P[b] *= target[b] / tot

    def rcount(self, m):
        return self.allcount(self.xp.sum(m, axis=(-2, -1), keepdims=True, dtype=np.int64))

    def rmin(self, x):
        return self.allmin(self.xp.min(x, axis=(-2, -1), keepdims=True))

    def masked_sum(self, x, mask):
        """``sum(x where mask)`` per case."""
        return self.rsum(x * mask)

    def gap_stats(self, w, F):
        """``(sum of w on F, min of w)`` per case (the measure's two reductions of the gap)."""
        return self.masked_sum(w, F), self.rmin(w)

    def orth(self, P, w, gbar, F):
        """``sum_F p |w - gbar|`` per case (complementarity, unnormalised)."""
        return self.rsum(P * self.xp.abs(w - gbar) * F)

    def dot(self, a, b):
        return self.rsum(a * b)

    def dot_on(self, a, b, F):
        """``a . b`` per case, both zero off ``F`` (a kernel may read ``F``'s nodes only)."""
        return self.dot(a, b)

    def to32(self, x, scale, out=None, F=None):
        """``float32(x * scale)``: the product in float64, rounded once (as ``SpectralProduct.load``).

        Into ``out`` where given (a transform's input buffer); with ``F``, ``x`` is a vector on ``F``
        (here a field zero off it) and the result a field, zero off ``F``.
        """
        if out is None:
            return (x * scale).astype(np.float32)
        self.xp.multiply(x, scale, out=out, casting="unsafe")
        return out

    def quadratic(self, spec, weights):
        """``sum(weights |spec|^2)`` per case over the half spectrum (float32 terms, float64 sum)."""
        re, im = spec.real, spec.imag
        return self.rsum(weights * (re * re + im * im))

    def scaled_into(self, R, factor, F):
        """``R * factor`` on ``F``, 0 off it, float64 (``R`` a float32 product)."""
        return R * factor * F

    def scaled_sum(self, R, factor, F):
        """:meth:`scaled_into` and its sum per case."""
        a = self.scaled_into(R, factor, F)
        return a, self.rsum(a)

    def add_scaled(self, w, R, factor):
        """``w += R * factor`` in place (``R`` float32, ``w`` float64)."""
        w += R * factor
        return w

    def sub_masked(self, x, c, F):
        """``x -= c`` on ``F`` in place (``c`` per case)."""
        x -= c * F
        return x

    def join_gap(self, w, gbar, F, go):
        """The free set after the join (``F | w < gbar`` where ``go``) and the gap ``w - gbar`` on it, 0 off it."""
        Fn = self.xp.where(go, F | (w < gbar), F)
        return Fn, (w - gbar) * Fn

    def join_stats(self, w, gbar, F, go):
        """:meth:`join_gap` with, per case, the new ``|F|`` and the gap's sum: ``(F, g, n, sum)``.

        ``F`` may be updated in place (and is returned).
        """
        Fn, g = self.join_gap(w, gbar, F, go)
        return Fn, g, self.rcount(Fn), self.rsum(g)

    def descent_dot(self, g, t, beta, a, F=None):
        """``g . (beta t + a)`` per case (``F``: all three are zero off it)."""
        return self.rsum(g * (t * beta + a))

    def new_direction(self, t, a, g, beta, keep, go, g_prev):
        """In place: ``t = beta t + a`` where ``keep``, else ``a`` where ``go``; ``g_prev = g`` where ``go``."""
        xp = self.xp
        t[...] = xp.where(keep, t * beta + a, xp.where(go, a, t))
        g_prev[...] = xp.where(go, g, g_prev)

    def center_dots(self, a, c, F, g, g_prev, t):
        """``a -= c`` on ``F`` (in place), then per case ``(g . a, g_prev . a, g . t)`` (all zero off ``F``)."""
        self.sub_masked(a, c, F)
        return self.dot_on(g, a, F), self.dot_on(g_prev, a, F), self.dot_on(g, t, F)

    def new_direction_input(self, t, a, g, beta, keep, go, g_prev, F, inv_sigma, out=None):
        """:meth:`new_direction` (all zero off ``F``), then the new ``t``'s transform input and ``g . t``.

        Returns ``(to32(t, inv_sigma), g . t)``, the first into ``out`` where given.
        """
        self.new_direction(t, a, g, beta, keep, go, g_prev)
        return self.to32(t, inv_sigma, out, F), self.dot_on(g, t, F)

    def proj_any(self, P, t, tau, F):
        """Whether ``p - tau t <= 0`` at a node of ``F``, per case."""
        return self.allany(self.xp.any(F & (P - tau * t <= 0.0), axis=(-2, -1), keepdims=True))

    def pos_sum(self, P, t, tau):
        """``sum(max(p - tau t, 0))`` per case."""
        return self.rsum(self.xp.maximum(P - tau * t, 0.0))

    def trial_stats(self, P, t, tau, F):
        """``(pos_sum, proj_any)`` of the trial ``p - tau t`` (``P`` and ``t`` zero off ``F``)."""
        return self.pos_sum(P, t, tau), self.proj_any(P, t, tau, F)

    def step_on(self, P, t, tau, go, F):
        """In place: ``P -= tau t`` where ``go``, for a step that leaves ``p > 0`` on ``F`` (no projection)."""
        P[...] = self.xp.where(go, P - tau * t, P)

    def project(self, P, t, tau, go, scale, inv_sigma, out=None, F=None):
        """The step where ``go``: ``P`` (in place) becomes ``scale max(p - tau t, 0)``; returns the change, float32.

        ``scale`` is ``target / sum(max(trial, 0))`` for projected cases and 1 for the others. The
        change is ``max(-trial, 0) + (scale - 1) max(trial, 0) - tau t`` (the single solve's
        ``x - tau t`` of :meth:`~roughcontact.solver.compressed.CompressedKernels.project`; ``-tau t`` unprojected), 0
        where not ``go``, times ``inv_sigma`` and rounded to float32 for the transform.
        """
        xp = self.xp
        trial = P - tau * t
        tp = xp.maximum(trial, 0.0)
        change = (tp - trial) + (scale - 1.0) * tp - tau * t
        change *= go
        P[...] = xp.where(go, tp * scale, P)
        return self.to32(change, inv_sigma, out)

    def shrink(self, P, F, t, g_prev):
        """In place: nodes of ``F`` whose pressure is 0 leave it; ``t`` and ``g_prev`` are 0 off ``F``."""
        keep = P > 0.0
        F &= keep
        t *= keep
        g_prev *= keep

    def shrink_stats(self, P, F, t, g_prev):
        """:meth:`shrink`, then per case the new ``|F|`` and ``sum(t)``."""
        self.shrink(P, F, t, g_prev)
        return self.rcount(F), self.rsum(t)

    # -- a round's passes between two transforms (:class:`.iteration.BatchIteration`) ---------------
    # Each is the sequence of the kernels above that the iteration runs between two transforms (or a
    # host read). Here they are those calls in turn; :class:`.cpu.FusedCpuKernels` makes each one
    # compiled call (a small grid's round is otherwise mostly the calls' own cost).

    def measure(self, P, w, F, nF, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                next_sync, best, at, done, waiting, converged, go):
        """The measure of a round: :meth:`gap_stats`, :meth:`gbar`, :meth:`orth`, :meth:`decide`; returns ``gbar``.

        The state arguments of :meth:`decide` are updated in place.
        """
        w_on_f, wmin = self.gap_stats(w, F)
        gbar = self.gbar(w_on_f, nF)
        self.decide(self.orth(P, w, gbar, F), wmin, gbar, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                    next_sync, best, at, done, waiting, converged, go)
        return gbar

    def join(self, w, gbar, F, nF, go, done, it, inv_sigma, out=None):
        """The join of a round, up to the preconditioner's transform input; ``(F, g, nF, nf, x32)``.

        ``it += go``; :meth:`join_stats` and :meth:`join_fix` (``go``, ``done`` in place); the gradient ``g``
        re-centred on the enlarged ``F`` (:meth:`sub_masked`); ``x32 = to32(g, inv_sigma)`` on ``F``, into
        ``out`` where given. ``nF`` is ``|F|`` before the join, the returned one after; ``nf`` is
        :meth:`join_fix`'s.
        """
        it += go
        F, g, n_new, gsum = self.join_stats(w, gbar, F, go)
        c, nf = self.join_fix(n_new, nF, gsum, go, done)
        self.sub_masked(g, c, F)
        return F, g, n_new, nf, self.to32(g, inv_sigma, out=out, F=F)

    def direction(self, R, sigma, nf, F, g, g_prev, t, g_old, delta, gprev_ok, go, done, inv_sigma, out=None):
        """The direction of a round from ``R = M g / sigma``; ``(to32(t, inv_sigma), g . t)`` of the new ``t``.

        ``a = R sigma`` on ``F`` (:meth:`scaled_sum`), zero mean there (:meth:`center_dots`), then
        :meth:`beta`, :meth:`direction_done` (``beta g.t + g.a``: the descent test) and
        :meth:`new_direction_input`; the CG's state in place.
        """
        a, a_sum = self.scaled_sum(R, sigma, F)
        G, gpa, gt_old = self.center_dots(a, a_sum / nf, F, g, g_prev, t)
        beta, restart = self.beta(G, gpa, g_old, delta, gprev_ok, go, done)
        keep = self.direction_done(beta * gt_old + G, restart, G, go, gprev_ok, g_old, delta)
        return self.new_direction_input(t, a, g, beta, keep, go, g_prev, F, inv_sigma, out=out)

    def trial(self, spec, weights, sigma, gt, nan, P, t, F, target, go, done):
        """The line search of a round from ``t``'s spectrum; ``(tau, proj, scale)``.

        ``t.Kt`` by Parseval (:meth:`quadratic` with ``weights``), :meth:`step_length`, :meth:`trial_stats`
        and :meth:`projection_scale` (``go``, ``done`` in place).
        """
        tau = self.step_length(self.quadratic(spec, weights), sigma, gt, nan, go, done)
        total, pany = self.trial_stats(P, t, tau, F)
        proj, scale = self.projection_scale(pany, total, target, go, done, tau)
        return tau, proj, scale

    def settle(self, w, R, factor, P, F, t, g_prev, nF, frac, proj, go, gprev_ok, fresh):
        """The end of a round's step: ``w += R factor`` (:meth:`add_scaled`), then :meth:`shrink_stats`,
        :meth:`shrink_fix` and ``t`` re-centred on the reduced ``F``; returns the new ``|F|``.

        ``nF`` is ``|F|`` before the shrink.
        """
        self.add_scaled(w, R, factor)
        n_new, t_sum = self.shrink_stats(P, F, t, g_prev)
        self.sub_masked(t, self.shrink_fix(nF, n_new, t_sum, frac, proj, go, gprev_ok, fresh), F)
        return n_new

    # -- the warm start of a load step (:meth:`.solver.BatchSolver.start`), in place --------

    def scale_start(self, P, w, h, s, plain):
        """Where ``plain``: ``P *= s`` and ``w = s w + (s - 1) h`` (``K P`` scales with ``P``)."""
        xp = self.xp
        w[...] = xp.where(plain, w * s + (s - 1.0) * h, w)
        P[...] = xp.where(plain, P * s, P)

    def extrapolate(self, P, w, P_last, P_older, w_last, w_older, c, ext, lin, inv_sigma, out=None):
        """The extrapolated start through the last two solutions, before its rescale.

        Where ``ext``: ``P = max(P_e, 0)`` with ``P_e = P_last + c (P_last - P_older)``; where ``lin``
        also ``w = w_last + c (w_last - w_older)``. Returns ``(sum of the new P per case, the
        transform input float32((max(P_e, 0) - P_e) inv_sigma))``, the second 0 where not ``lin``.
        """
        xp = self.xp
        Pe = (P_last - P_older) * c + P_last
        clipped = xp.maximum(Pe, 0.0)
        x32 = self.to32((clipped - Pe) * lin, inv_sigma, out)
        w[...] = xp.where(lin, (w_last - w_older) * c + w_last, w)
        P[...] = xp.where(ext, clipped, P)
        return self.rsum(clipped * ext), x32

    def finish_start(self, P, w, h, R, sigma, sc, loaded, ext, lin, p_fill):
        """After :meth:`extrapolate`: where ``lin`` ``w = (w + R sigma) sc + (sc - 1) h``; where ``ext``
        ``P = P sc`` (``loaded``) or ``p_fill`` (no pressure left)."""
        xp = self.xp
        if R is not None:
            w[...] = xp.where(lin, (w + R * sigma) * sc + (sc - 1.0) * h, w)
        P[...] = xp.where(ext, xp.where(loaded, P * sc, p_fill), P)

    # -- per-case decisions: (B, 1, 1) arrays; the state arguments are updated in place --------

    def gbar(self, s, n):
        """``s / n`` where ``n > 0``, else 0 (the gap's mean over ``F``)."""
        xp = self.xp
        return xp.where(n > 0, s / xp.where(n > 0, n, 1), 0.0)

    def decide(self, orth, wmin, gbar, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
               next_sync, best, at, done, waiting, converged, go):
        """The measure's decisions (:meth:`.iteration.BatchIteration.measure`), in place.

        Residual ``r = max(orth inv_norm, max(gbar - wmin, 0) / scale, 0)`` (``big`` where not
        finite), then the loop head :func:`~roughcontact.solver.workspace.loop_head` (with ``levels``) for every
        case neither done nor waiting: converged where fresh and ``r <= tol``; waiting for a float64
        recomputation where not fresh and ``r <= tol`` or below ``next_sync`` (lowered by four decades under
        ``r``); the stall guard (``best``, ``at``, ``stall``), ``max_iter``; ``go`` for the others. Written
        over arrays (a GPU's form, the CUDA kernel's too), the level is lowered at most six times a call: the
        rule's decisions unless the residual falls more than 24 decades below the level between two measures
        (tests/test_batch.py holds this form to the rule, with up to four lowerings a call).
        """
        xp = self.xp
        pen = xp.maximum(gbar - wmin, 0.0)
        o = orth * inv_norm
        r = xp.where(xp.isfinite(o) & xp.isfinite(pen), xp.maximum(xp.maximum(o, pen / scale), 0.0), big)
        active = ~(done | waiting)
        below = r <= tol
        conv = active & below & fresh
        sync_level = ~below & (r < next_sync)
        want = active & ~fresh & (below | sync_level)
        for _ in range(6):  # the rule's `while`, capped (a GPU's loop cannot ask the host whether to go on)
            next_sync[...] = xp.where(want & sync_level & (next_sync > r), next_sync * 1e-4, next_sync)
        rest = active & ~conv & ~want
        better = rest & (r < 0.5 * best) & (it < max_iter)  # (a step stopped at max_iter keeps its best)
        best[...] = xp.where(better, r, best)
        at[...] = xp.where(better, it, at)
        stop = rest & (~xp.isfinite(r) | (it >= max_iter) | (it - at >= stall))
        go[...] = rest & ~stop
        converged |= conv
        waiting |= want
        done |= conv | stop

    def join_fix(self, nnew, nold, gsum, go, done):
        """After the join: cases whose ``F`` is empty stop; ``(c, nf)``: the gradient's shift (its mean
        on ``F`` where nodes joined, else 0) and ``max(|F|, 1)``, float64."""
        xp = self.xp
        joined = go & (nnew > nold)
        empty = go & (nnew == 0)
        done |= empty
        go &= ~empty
        nf = xp.where(nnew > 0, nnew, 1).astype(np.float64)
        return xp.where(joined, gsum / nf, 0.0), nf

    def beta(self, G, gpa, g_old, delta, gprev_ok, go, done):
        """Polak-Ribiere's (or Fletcher-Reeves') ``beta`` and the restarts; ``(beta, restart)``.

        A breakdown (``G = g.z`` not positive and finite) stops the case.
        """
        xp = self.xp
        ok = (G > 0.0) & xp.isfinite(G)
        done |= go & ~ok
        go &= ok
        restart = ~((delta > 0.0) & (g_old > 0.0))
        d = xp.where(g_old != 0.0, g_old, 1.0)
        b = xp.where(gprev_ok, xp.maximum(0.0, (G - gpa) / d), G / d)
        return xp.where(restart | ~go, 0.0, b), restart

    def direction_done(self, dd, restart, G, go, gprev_ok, g_old, delta):
        """``keep``: the conjugate direction where it descends (``dd = g.t > 0``) or at a restart; the
        CG's history updated where ``go``."""
        xp = self.xp
        keep = go & (restart | (dd > 0.0))
        gprev_ok |= go
        g_old[...] = xp.where(go, G, g_old)
        delta[...] = xp.where(go, 1.0, delta)
        return keep

    def step_length(self, quad, sigma, gt, nan, go, done):
        """``tau = g.t / t.Kt`` (``t.Kt = quad sigma^2``) where it is positive and finite, else the case stops; 0
        where not ``go``."""
        xp = self.xp
        rt = quad * sigma ** 2
        tt = xp.where(rt > 0.0, gt / xp.where(rt > 0.0, rt, 1.0), nan)
        ok = xp.isfinite(tt) & (tt > 0.0)
        done |= go & ~ok
        go &= ok
        return xp.where(go, tt, 0.0)

    def projection_scale(self, pany, total, target, go, done, tau):
        """``(proj, scale)``: projected cases and their rescale ``target / total`` (1 elsewhere); a projection
        that leaves no load stops the case; ``tau`` 0 where not ``go`` (in place)."""
        xp = self.xp
        pj = go & pany
        bad = pj & ~(total > 0.0)
        done |= bad
        go &= ~bad
        proj = pj & ~bad
        tau[...] = xp.where(go, tau, 0.0)
        return proj, xp.where(proj, target / xp.where(total > 0.0, total, 1.0), 1.0)

    def shrink_fix(self, nold, nnew, tsum, frac, proj, go, gprev_ok, fresh):
        """After the shrink: Polak-Ribiere's history off after a large loss, ``fresh`` off where a step was
        taken; returns the direction's shift (its mean on the reduced ``F`` where projected)."""
        xp = self.xp
        gprev_ok &= ~(proj & ((nold - nnew) >= frac * nold))
        fresh &= ~go
        return xp.where(proj, tsum / xp.where(nnew > 0, nnew, 1), 0.0)
