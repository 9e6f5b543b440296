"""The elastic iteration of one load step, one class for one case, a batch and MPI ranks: :class:`BatchIteration`."""

from __future__ import annotations

import math

import numpy as np

from .workspace import FR_AFTER_LOSS, STALL_WINDOW


class BatchIteration:
    """Polonsky & Keer's elastic iteration (docs/solver.md, "Algorithm") on ``B`` cases at once: one class for all.

    The kernels (``solver.kernels``) hold the arithmetic of each backend: one case on its workspace over index
    sets (:class:`~roughcontact.solver.compressed.CompressedKernels`, ``solve_contact``'s, every elastic method),
    ``B`` cases with masks on the host (:class:`~roughcontact.solver.batch.cpu.FusedCpuKernels`) or a GPU
    (:class:`~roughcontact.solver.batch.cuda.CupyKernels`), one case over MPI ranks
    (:class:`~roughcontact.solver.mpi.kernels.MpiKernels`); the operator (``solver.op``) its transforms.

    State per case (fields ``(B, nx, ny)``, numbers ``(B, 1, 1)``): ``P`` (the solver's, zero off
    ``F``) and ``w = K P - h`` (the solver's, updated in place), ``F`` the free set, ``t`` the
    direction and ``g_prev`` the last direction's gradient (vectors on ``F``, in the kernels' form:
    :class:`~roughcontact.solver.batch.kernels.ArrayKernels`), ``g_old``, ``delta``,
    whether ``g_prev`` is valid, the iteration count, the stall guard's best residual and its
    iteration, ``next_sync``, and the round's flags: ``done`` (converged or stopped), ``waiting``
    (for a float64 recomputation at the next check), ``fresh`` (``w`` recomputed since the last
    step). ``fresh0`` per case is the single solve's ``fresh`` argument as an int: 1 True, 0 False
    (recomputed first), -1 None.
    """

    def __init__(self, solver, p_int, fresh0, max_iter, op=None, stall: int | None = None):
        self.s, xp = solver, solver.xp
        self.xp, self.k = xp, solver.kernels
        # the products (float32: the solver's operator; float64: its Float64Products, a fallback's)
        self.op = solver.op if op is None else op
        self.stall = STALL_WINDOW if stall is None else int(stall)
        B = solver.batch
        self.tol = solver.tol
        self.p_int = p_int  # (B, 1, 1) float64 on the device
        self.target = p_int * solver.size
        self.scale = solver.h_rms  # (B, 1, 1)
        self.inv_norm = 1.0 / (self.target * self.scale)
        self.sigma, self.inv_sigma = solver.h_rms, 1.0 / solver.h_rms
        self.max_iter = max_iter  # (B,) host ints
        must = np.flatnonzero(fresh0 == 0)
        if must.size:
            solver.refresh(must)
        self.fresh = xp.asarray((fresh0 >= 0).reshape(B, 1, 1))  # refreshed ones are fresh now
        self.F = self.k.free_set(solver.P > 0.0)
        self.nF = self.k.rcount(self.F)
        self.t = self.k.vector(self.F)  # vectors on F (the kernels' form: fields, or compressed on the host)
        self.g_prev = self.k.vector(self.F)
        self.gprev_ok = xp.zeros((B, 1, 1), dtype=bool)
        self.delta = xp.zeros((B, 1, 1))
        self.g_old = xp.ones((B, 1, 1))
        self.it = xp.zeros((B, 1, 1), dtype=np.int64)
        self.best = xp.full((B, 1, 1), math.inf)
        self.at = xp.zeros((B, 1, 1), dtype=np.int64)
        self.next_sync = xp.full((B, 1, 1), 1e-5)
        self.done = xp.zeros((B, 1, 1), dtype=bool)
        self.converged = xp.zeros((B, 1, 1), dtype=bool)
        self.waiting = xp.zeros((B, 1, 1), dtype=bool)
        self.go = xp.zeros((B, 1, 1), dtype=bool)  # the cases that move in this round (measure)
        self.max_iter_d = xp.asarray(np.asarray(max_iter, dtype=np.int64).reshape(B, 1, 1))
        self.rounds = 0
        # on the host the per-case flags cost nothing to read: a step that projects no case moves w by
        # K of -tau t from t's spectrum, already made for the step length (one forward transform less);
        # on a GPU that read would be a synchronisation a round
        self.host = self.k.flags_on_host

    def run(self, check_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Iterate every case to convergence or a stop; ``(iterations, converged)`` per case (host).

        A round measures every case, then moves those that iterate. Every ``check_every``-th round
        the host reads the per-case flags between the two (the only host synchronisation of the
        loop: a few bytes per case), recomputes ``w`` in float64 for the cases waiting for it and
        lets them measure again, as the single solve's loop does after its recomputations, so that
        they move in that same round. With ``check_every = 1`` no case ever waits; with more, a case
        that asks for a recomputation idles until the next check.
        """
        s = self.s
        while True:
            for j in range(check_every):
                self.measure()
                if j == check_every - 1 and self.check():
                    break
                self.act()
                self.rounds += 1
            else:
                continue
            break
        self.finish()
        return (s.be.to_host(self.it).reshape(-1).astype(np.int64),
                s.be.to_host(self.converged).reshape(-1).astype(bool))

    def _flags(self):
        s = self.s
        if self.xp is np:  # numpy arrays: read in place
            return self.done.reshape(-1), self.waiting.reshape(-1)
        flags = s.be.to_host(self.xp.concatenate([self.done.reshape(-1), self.waiting.reshape(-1)]))
        return flags[: s.batch], flags[s.batch:]

    def check(self) -> bool:
        """The host's check after a measure: recomputations for the waiting cases; True when all are done."""
        done, waiting = self._flags()
        sync = waiting.nonzero()[0]  # (a method: np.flatnonzero's wrappers cost more than one case's round here)
        if sync.size:
            self.resync(sync)
            idx = self.s.xp.asarray(sync)
            self.fresh[idx] = True
            self.waiting[idx] = False
            self.measure()  # the others' decisions stand (measuring an unchanged case again changes nothing)
            done, _ = self._flags()
        return np.count_nonzero(done) == done.size  # (numpy's all() on a few flags costs 5x this)

    def resync(self, cases: np.ndarray) -> None:
        """Pressure brought to the exact mean and ``w`` recomputed in float64 for ``cases`` (host ints)."""
        s = self.s
        if self.host:  # in place, case by case (a gather and scatter of whole fields costs more)
            self.k.to_mean(s.P, cases, s.be.to_host(self.target).reshape(-1))
            s.refresh(cases)
            return
        idx = s.xp.asarray(cases)
        P = s.P[idx]
        tot = self.k.rsum(P)
        tgt = self.target[idx]
        P *= self.xp.where(tot > 0, tgt / self.xp.where(tot > 0, tot, 1.0), 1.0)
        s.P[idx] = P
        s.refresh(cases)

    def finish(self) -> None:
        """``w`` fresh for every case (the final check needs it)."""
        stale = np.flatnonzero(~self.s.be.to_host(self.fresh).reshape(-1))
        if stale.size:
            self.resync(stale)
            self.fresh[self.s.xp.asarray(stale)] = True

    def measure(self) -> None:
        """The first half of a round for every case: residual and decisions (the loop head).

        Converged, waiting and stopped cases are flagged; ``self.go`` says which iterate in
        :meth:`act`. Measuring again a case whose state has not changed decides the same (the stall
        guard's and ``next_sync``'s updates are idempotent).
        """
        s = self.s
        # gap on F (zero mean there: gbar is -d), sign violations off F (min of w), complementarity
        self.gbar = self.k.measure(s.P, s.w, self.F, self.nF, self.inv_norm, self.scale, self.tol, self.stall,
                                   math.inf, self.it, self.max_iter_d, self.fresh, self.next_sync, self.best,
                                   self.at, self.done, self.waiting, self.converged, self.go)

    def act(self) -> None:
        """The second half of the loop for the cases that iterate: join, direction, step."""
        k, op, s = self.k, self.op, self.s
        go = self.go
        # join: violating nodes (w < gbar off F) enter F; their p, t and g_prev are 0 already (in either form);
        # the gradient re-centred on the enlarged F where nodes joined (shifts d only), and its transform input
        self.F, g, self.nF, nf, x32 = k.join(s.w, self.gbar, self.F, self.nF, go, self.done, self.it,
                                            self.inv_sigma, out=op.input32)
        spec, gt = self._direction(g, go, nf, x32)
        self._step(go, spec, gt)

    def _direction(self, g, go, nf, x32):
        """``t = z + beta t`` (``t = z`` at a restart or where that is no descent); a breakdown stops the case.

        ``x32``: the transform input of ``g / sigma``. Returns the new direction's float32 spectrum (of
        ``t / sigma``) and ``g . t`` per case.
        """
        op = self.op
        # g, t, g_prev and a are vectors on F (fields zero off F, or compressed): the kernels touch F's nodes only
        R = op.inverse32(op.transform32(x32), op.mmult32)  # M g / sigma
        t32, gt = self.k.direction(R, self.sigma, nf, self.F, g, self.g_prev, self.t, self.g_old, self.delta,
                                   self.gprev_ok, go, self.done, self.inv_sigma, out=op.input32)
        return op.transform32(t32), gt

    def _step_host(self, spec, tau, proj, pscale):
        """The move of :meth:`_step` where the per-case flags are on the host (numpy); ``(R, factor)`` for ``w``.

        A case that does not project moves ``p`` by ``-tau t`` and ``w`` by ``-tau K t``, ``K t`` from
        ``t``'s spectrum, already made for the step length: one inverse transform, as the single
        solve's step. A projected case transforms its change (:meth:`_step`). Each case's arithmetic
        is its own whatever the others do, so that a case's result does not depend on its batch.
        """
        k, op = self.k, self.op
        t, F, go = self.t, self.F, self.go
        pj = self.s.be.to_host(proj).reshape(-1)
        projected = np.count_nonzero(pj)
        if not projected:
            k.step_on(self.s.P, t, tau, go, F)
            return op.inverse32(spec, op.kmult32), -tau * self.sigma
        kept = spec[~pj].copy() if projected < pj.size else None  # the spectrum's buffer is the next transform's
        d32 = k.project(self.s.P, t, tau, go, pscale, self.inv_sigma, out=op.input32, F=F)
        mixed = op.transform32(d32)
        factor = self.sigma
        if kept is not None:
            mixed[~pj] = kept
            factor = self.xp.where(proj, self.sigma, -tau * self.sigma)
        return op.inverse32(mixed, op.kmult32), factor

    def _step(self, go, spec, gt) -> None:
        """Exact line search along ``-t``, the projection onto ``p >= 0``, ``w`` moved by ``K`` of the change.

        ``spec``: the float32 spectrum of ``t / sigma``; ``gt``: ``g . t`` per case.
        """
        k, op, s = self.k, self.op, self.s
        t, F = self.t, self.F
        tau, proj, pscale = k.trial(spec, op.kquad32, self.sigma, gt, math.nan, s.P, t, F, self.target, go,
                                    self.done)
        if not self.host:
            # w <- w + K (p_new - p): one forward and one inverse float32 transform (every case)
            d32 = k.project(s.P, t, tau, go, pscale, self.inv_sigma, out=op.input32, F=F)
            R, factor = op.inverse32(op.transform32(d32), op.kmult32), self.sigma
        else:
            R, factor = self._step_host(spec, tau, proj, pscale)
        # w moved; a projected case's F loses the nodes at p = 0; Polak-Ribiere's history off after a projection
        # that took a large part of F away; zero mean of t on the reduced F
        self.nF = k.settle(s.w, R, factor, s.P, F, t, self.g_prev, self.nF, FR_AFTER_LOSS, proj, go, self.gprev_ok,
                           self.fresh)
