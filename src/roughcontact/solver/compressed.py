"""One case on its :class:`~.workspace.Workspace`: the kernels of :class:`~.iteration.BatchIteration` over index sets.

:func:`pk_solve` runs one load step of an elastic iteration (docs/solver.md, "Algorithm") with the one
iteration class, :class:`~.iteration.BatchIteration`, for B = 1: ``"pk-fourier-f32"`` (Polonsky & Keer's CG
with the Fourier preconditioner and float32 products), ``"pk-fourier"`` (the same with float64 products) or
``"pk"`` (Polonsky & Keer's CG as Tamaas' ``PolonskyKeerRey``, no preconditioner). Its kernels here
(:class:`CompressedKernels`) hold the free set ``F`` as flat node indices (ascending, then the nodes that
joined, appended in order) and every vector on ``F`` compressed, one value per node, in numpy (or the
workspace's array module). The float32 transforms are the workspace's own half-space's products
(:class:`WorkspaceProducts`), loading and reading ``F``'s nodes only; the float64 ones its whole products.
Sums are numpy's pairwise ones over the compressed arrays and inner products einsum's
(:func:`~.workspace.dot`), ``w`` moves by ``K`` of the change scaled once and then added, and the per-case
decisions are Python numbers: the arithmetic of the single solve's own loop before this module, so that
its outputs are those of that loop bit for bit (checked when it was replaced, 2026-12-03: the 30 solver
fingerprints and every scene's files, ``benchmarks/bench_one_class.py``).

The batched kernels (:class:`~.batch.kernels.ArrayKernels` and its fused forms) run the same iteration with
masks for ``B`` cases at once (``"pk-fourier-f32"`` only); their sums run in another order and agree to
round-off.

Examples
--------
>>> import numpy as np
>>> from roughcontact.solver.workspace import Workspace
>>> from roughcontact.surfaces.synthetic import generate_surface
>>> h = generate_surface(32, 2, 8, 0.8, 0, rms_slope=0.1)
>>> ws = Workspace(h / 32, 1.0, 1, "pk-fourier-f32")
>>> ws.P.fill(1e-3)
>>> iterations, converged = pk_solve(ws, 1e-3, 1e-8, 1000, False)
>>> converged, bool(abs(ws.P.mean() - 1e-3) < 1e-15)
(True, True)
"""

from __future__ import annotations

import math

import numpy as np

from ..core.passes import move_field
from .iteration import BatchIteration
from .projection import enforce_mean
from .workspace import CONVERGED, GO, STALL_WINDOW, STOP, WAIT, Workspace, dot, loop_head


class _Dense:
    """A float64 product of a workspace field (written at ``F``'s nodes, zero elsewhere): one FFT pair."""

    def __init__(self, apply, field):
        self.apply, self.field = apply, field


class WorkspaceProducts:
    """The products of a workspace's half-space, as :class:`~.iteration.BatchIteration` calls them.

    A transform input is the product it was loaded into: for ``"pk-fourier-f32"`` the half-space's float32
    product (:attr:`k` for ``K``, :attr:`m` for the preconditioner ``M``), loaded by :class:`CompressedKernels`
    at ``F``'s nodes, whose forward transform gives a spectrum; for the float64 methods a whole product of
    the workspace's ``T`` (``K``) or ``Z`` (``M``) field, whose result stands for its spectrum and its
    inverse. ``None`` is no input (a case that stopped, a step whose ``w`` was recomputed in float64, or
    ``"pk"``'s direction, which needs no product), whose transforms are ``None``.
    """

    def __init__(self, ws: Workspace):
        ws.setup_method()
        self.single = ws.method == "pk-fourier-f32"
        self.hs = hs = ws.op
        if self.single:
            pre = getattr(hs, "precond", hs)  # the free operator's periodic preconditioner, or the operator
            self.k, self.m = hs, pre
            self.kmult32, self.kquad32, self.mmult32 = hs.kmult32, hs.kquad32, pre.mmult32
        else:
            self.k, self.m = _Dense(ws.apply_k, ws.T), _Dense(ws.apply_m, ws.Z)
            self.kmult32 = self.kquad32 = self.mmult32 = None
        self.input32 = None  # the iteration passes it as ``out``: the kernels load the product they need
        self._last = None

    def transform32(self, product):
        """The forward transform of what was loaded into ``product`` (its spectrum buffer); a float64
        product whole (its result, maybe a strided view of a buffer the next product overwrites)."""
        self._last = product
        if product is None:
            return None
        if type(product) is _Dense:
            return product.apply(product.field)
        return product.prod32.forward()

    def inverse32(self, spec, mult):
        """The inverse of the last transform's spectrum times ``mult``: ``K x / sigma`` on the grid for ``K``'s;
        for ``M``'s the product's buffer, which :class:`CompressedKernels` reads at ``F``'s nodes; a float64
        product's result as it is."""
        if spec is None or type(self._last) is _Dense:
            return spec
        if mult is self.kmult32:  # (the periodic operator is its own preconditioner: the multiplier tells)
            return self.k.displacement32(spec)
        return self._last.prod32.backward(spec, mult)


class _FreeSet:
    """``F`` of one case: node indices, the vectors made on it, and what a round carries between passes."""

    def __init__(self, ws: Workspace):
        self.idx = ws.active_set()
        self.p = ws.Pf[self.idx]  # the pressure on F (the field's values there are written back by to_mean)
        self.vectors = []
        self.cand = self.g_cand = None  # nodes off F with w < gbar, and their gap
        self.g = None  # the round's gradient on F (zero mean)
        self.trial = self.clipped = None  # the step's trial pressure p - tau t, and its clipped part
        self.full = False  # the step left no pressure: a full projection with a fresh K p


class _Vector:
    """A vector on ``F``, compressed; ``valid`` False stands for none (Polak-Ribiere's missing ``g_prev``)."""

    def __init__(self, n: int, xp):
        self.a = xp.zeros(n)
        self.valid = False


class CompressedKernels:
    """The passes of :class:`~.iteration.BatchIteration`'s round for one case over compressed index sets.

    Implements the methods the iteration calls (:class:`~.batch.kernels.ArrayKernels` documents them) with
    the single solve's arithmetic for the workspace's method (``ws.method``); per-case numbers are
    ``(1, 1, 1)`` arrays of the iteration's, read once per call. ``flags_on_host``: the iteration may read
    the per-case flags at every step.
    """

    flags_on_host = True
    #: On the host ``w`` moves in one pass, :func:`~roughcontact.core.passes.move_field` (numpy's bits), if True.
    FUSED = True

    def __init__(self, ws: Workspace, products: WorkspaceProducts, target: float):
        self.ws, self.op, self.xp = ws, products, ws.xp
        self.target = target  # the load's total, p0 times the nodes
        self.F = None
        # float32 products (their inputs divided by sigma), and w recomputed in float64 below residual levels
        self.single = ws.method == "pk-fourier-f32"
        self.precond = ws.method != "pk"
        self.sigma = ws.sigma if self.single else 1.0
        self.inv_sigma = 1.0 / self.sigma
        self.joined_after = 0  # "pk": > 0, the nodes from this index on joined F in this iteration
        self.restart = False  # "pk": nodes joined, the next direction restarts the CG (delta = 0)
        # the float64 preconditioner's input, zero off F (made by the workspace's setup_method)
        self.Zf = ws.Z.ravel() if self.precond and not self.single else None
        self._proj = np.zeros(1, dtype=bool)  # the step's projection flag, as the host reads it
        self.fused = self.FUSED and self.xp is np and ws.w.flags.c_contiguous
        self._least_off = None  # the least w off F after the last move of w, for the next measure only

    # -- the free set and its vectors --------------------------------------------------------------

    def free_set(self, mask):
        """``F`` from the workspace's pressure (``mask`` is ``P > 0``, as the workspace makes it itself)."""
        self.F = _FreeSet(self.ws)
        if not self.single:
            self.ws.T.fill(0.0)  # the direction's field for the float64 products: zero off F
        return self.F

    def rcount(self, F):
        return F.idx.size

    def vector(self, F):
        v = _Vector(F.idx.size, self.xp)
        F.vectors.append(v)
        return v

    def to_mean(self, P, cases, target) -> None:
        """The pressure on ``F`` scaled to the exact total (summed in ``F``'s order) and written into the field."""
        F, tgt = self.F, target[0]
        if not F.p.size:
            return
        tot = F.p.sum()
        if tot > 0 and tgt > 0:
            F.p *= tgt / tot
        self.ws.Pf[F.idx] = F.p

    # -- a round ---------------------------------------------------------------------------------

    def measure(self, P, w, F, nF, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                next_sync, best, at, done, waiting, converged, go):
        """Gap on ``F`` (zero mean there), sign violations off ``F``, the residual and the decisions; ``gbar``."""
        ws, idx = self.ws, F.idx
        nf = idx.size
        gbar = 0.0
        g = None
        if nf:
            g = np.take(ws.wf, idx)
            gbar = g.sum() / nf
            g -= gbar
        F.g = g
        # sign violations: nodes off F with g < 0; none where the least w off F after the last move is not below
        least, self._least_off = self._least_off, None  # gbar (known for the next measure only)
        pen, F.cand, F.g_cand = 0.0, None, None
        if least is None or least < gbar:
            np.less(ws.w, gbar, out=ws.bbuf)
            np.greater(ws.bbuf, ws.mask, out=ws.bbuf)  # (w < gbar) & ~mask, for booleans
            F.cand = np.flatnonzero(ws.bbuf) if np.count_nonzero(ws.bbuf) else None
        if F.cand is not None:
            F.g_cand = ws.wf[F.cand] - gbar
            pen = -float(F.g_cand.min())
        orth = 0.0
        if nf:
            pen = max(pen, -float(g.min()))
            orth = dot(F.p, np.abs(g)) * inv_norm.item()
        residual = max(orth, pen / scale.item(), 0.0)
        self._decide(residual, tol, stall, it, max_iter, fresh, next_sync, best, at, done, waiting, converged, go,
                     levels=self.single)
        return gbar

    @staticmethod
    def _decide(r, tol, stall, it, max_iter, fresh, next_sync, best, at, done, waiting, converged, go,
                levels=True):
        """The loop head (:func:`~.workspace.loop_head`) on the iteration's ``(1, 1, 1)`` state: converge (on a
        fresh ``w``), recompute ``w`` in float64 (below ``tol``, or with ``levels`` below ``next_sync``), or the stall
        guard."""
        if done.item() or waiting.item():
            go[...] = False
            return
        level, b0, a0 = next_sync.item(), best.item(), at.item()
        decision, level1, b1, a1 = loop_head(r, tol, fresh.item(), level, levels, it.item(), max_iter.item(), b0, a0,
                                             stall)
        if level1 != level:
            next_sync[...] = level1
        if b1 != b0 or a1 != a0:
            best[...], at[...] = b1, a1
        go[...] = decision == GO
        if decision == CONVERGED:
            converged[...] = done[...] = True
        elif decision == WAIT:
            waiting[...] = True
        elif decision == STOP:
            done[...] = True

    def join(self, w, gbar, F, nF, go, done, it, inv_sigma, out=None):
        """Violating nodes join ``F`` (their ``p``, ``t`` and ``g_prev`` 0); loads the input of ``M``'s product.

        Preconditioned, the direction is kept across a join (zero on the joining nodes, so still zero-mean
        on ``F``), the gradient re-centred on the enlarged ``F`` and the next direction conjugated against
        it; ``"pk"`` restarts its CG at a join (Polonsky & Keer's rule, ``delta`` = 0).
        """
        if not go.item():
            return F, None, nF, None, None
        it[...] = it.item() + 1  # (numpy's in-place add on a (1, 1, 1) array costs 3x this)
        ws, g = self.ws, F.g
        if F.cand is not None:
            n_join = F.cand.size
            F.idx = np.concatenate([F.idx, F.cand])
            F.p = np.concatenate([F.p, self.xp.zeros(n_join)])
            g = np.concatenate([g, F.g_cand]) if g is not None else F.g_cand
            for v in F.vectors:
                v.a = np.concatenate([v.a, self.xp.zeros(n_join)])
            ws.mask.reshape(-1)[F.cand] = True
            if self.precond and F.idx.size > n_join:  # (as the former loop: not where F was empty)
                g -= g.sum() / F.idx.size  # the gradient on the enlarged set: zero mean on F (shifts d only)
            else:
                self.joined_after, self.restart = F.idx.size - n_join, True
            F.g = g
        n = F.idx.size
        if n == 0:
            go[...] = False
            done[...] = True
            return F, None, n, None, None
        if not self.precond:
            return F, None, n, None, None
        if self.single:
            self.op.m.loader.load(F.idx, g, self.inv_sigma)
        else:
            self.Zf[F.idx] = g
        return F, None, n, None, self.op.m

    def direction(self, R, sigma, nf, F, g, g_prev, t, g_old, delta, gprev_ok, go, done, inv_sigma, out=None):
        """The conjugate direction ``t``, zero mean on ``F`` so that the mean pressure is kept; loads ``t`` into
        ``K``'s product; ``(that product, g.t)``.

        Preconditioned: ``t = z + beta t``, ``z = P_F M P_F g`` from ``R``, with Polak-Ribiere's ``beta``
        (Fletcher-Reeves' where there is no ``g_prev``: after a projection that took a large part of ``F``
        away, ``FR_AFTER_LOSS``), and ``t = z`` at a restart or where that is no descent; a breakdown
        (``g.z`` not positive and finite) stops the case. ``"pk"``: ``t = g + delta G / g_old t``; at a restart
        after a join each joining node keeps ``t = g`` (< 0), the others restored to zero mean, so that the
        step moves it into the contact set as Polonsky & Keer's rule does (``g.t = |g|^2`` still holds: ``g``
        has zero mean on the former ``F``).
        """
        if not go.item():
            return None, 0.0
        ws, idx, g = self.ws, F.idx, F.g
        if self.restart:
            delta[...] = 0.0
            self.restart = False
        restart = not (delta.item() > 0.0 and g_old.item() > 0.0)
        tc = t.a
        if self.precond:
            a = self._preconditioned(R, idx)
            G = dot(g, a)
            if not (G > 0.0 and math.isfinite(G)):
                go[...] = False
                done[...] = True
                return None, 0.0
            if restart:
                tc[...] = a
            else:
                gold = g_old.item()
                beta = max(0.0, (G - dot(g_prev.a, a)) / gold) if g_prev.valid else G / gold
                tc *= beta
                tc += a
                if not dot(g, tc) > 0.0:  # conjugated across a change of F: no descent
                    tc[...] = a
            g_prev.a = g.copy()
            g_prev.valid = True
        else:
            G = dot(g, g)
            if restart:
                tc[...] = g
                if self.joined_after:
                    tc[: self.joined_after] -= tc.sum() / self.joined_after
                self.joined_after = 0
            else:
                tc *= delta.item() * G / g_old.item()
                tc += g
        g_old[...] = G
        delta[...] = 1.0
        if self.single:
            self.op.k.loader.load(idx, tc, self.inv_sigma)
        else:
            ws.Tf[idx] = tc
        return self.op.k, dot(g, tc)

    def _preconditioned(self, R, idx):
        """``z = P_F M P_F g`` at ``F``'s nodes ``idx``, mean over ``F`` removed, from ``M``'s product ``R``."""
        if self.single:
            a = self.xp.empty(idx.size)
            self.op.m.loader.take(R, idx, a)
            a *= self.ws.sigma  # the float32 product is M g / sigma
        else:
            a = R[self.ws.nodes(idx)]
            self.Zf[idx] = 0.0
        a -= a.sum() / idx.size
        return a

    def trial(self, spec, weights, sigma, gt, nan, P, t, F, target, go, done):
        """The exact step length ``tau = g.t / t.Kt`` and the trial ``p - tau t``; ``(tau, projects, scale)``,
        ``scale`` restoring the mean of the clipped trial where it projects.

        ``t . K t`` from the float32 spectrum of ``t`` (Parseval), or from the float64 product ``K t`` at ``F``'s
        nodes. A float64 step that leaves ``p >= 0`` is :meth:`_full_projection`.
        """
        self._proj[0] = False
        if spec is None or not go.item():
            return 0.0, self._proj, 1.0
        ws = self.ws
        if self.single:
            rt = self.op.k.prod32.quadratic(spec, weights) * ws.sigma ** 2  # t . K t
        else:
            rt = dot(spec[ws.nodes(F.idx)], t.a)
        tau = gt / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tau) and tau > 0.0):
            go[...] = False  # a null direction: nothing can move (the final check decides)
            done[...] = True
            return 0.0, self._proj, 1.0
        trial = np.multiply(t.a, -tau)
        trial += F.p
        F.trial, F.tau = trial, tau
        if not bool((trial <= 0.0).any()):
            return tau, self._proj, 1.0
        self._proj[0] = True
        if not self.single:
            F.full = True
            return tau, self._proj, 1.0
        F.clipped = np.maximum(-trial, 0.0)
        np.maximum(trial, 0.0, out=trial)
        total = float(trial.sum())
        F.full = not total > 0.0
        return tau, self._proj, (target.item() / total if not F.full else 1.0)

    def step_on(self, P, t, tau, go, F):
        """An unprojected step: ``p <- p - tau t`` on ``F``."""
        if go.item():
            F.p = F.trial

    def project(self, P, t, tau, go, scale, inv_sigma, out=None, F=None):
        """A projected step: ``p <- scale max(p - tau t, 0)`` on ``F``, and its change loaded into ``K``'s product.

        ``p_new - p = x - tau t`` with ``x = max(-trial, 0) + (scale - 1) scale^-1 p_new`` on ``F``, so
        ``w`` moves by ``K (p_new - p)`` like an ordinary step and ``K p`` is never transformed afresh.
        A float64 step, or one that leaves no pressure, is :meth:`_full_projection` instead (nothing loaded).
        """
        if F.full:
            self._full_projection(F, t)
            return None
        trial, x = F.trial, F.clipped
        x += (scale - 1.0) * trial
        trial *= scale
        x -= tau * t.a  # p_new - p on F
        F.p = trial
        self.op.k.loader.load(F.idx, x, self.inv_sigma)
        return self.op.k

    def _full_projection(self, F, t) -> None:
        """Polonsky & Keer's projection of the trial onto ``p >= 0`` with the exact mean, ``F`` its support
        (every node where the step left no pressure: the load spread evenly), ``w`` from a fresh ``K p`` in
        float64, Polak-Ribiere's history dropped, ``t`` kept on the old ``F`` and re-centred: every projected
        step of the float64 methods, and a float32 step that left no pressure."""
        ws, old = self.ws, F.idx
        trial = np.maximum(F.trial, 0.0, out=F.trial)
        ws.Pf[old] = trial
        T = self.xp.zeros(ws.size)
        T[old] = t.a
        if not self.single:
            ws.Tf[old] = 0.0  # the new F is within the old one
        enforce_mean(ws.P, self.target, None)
        F.idx = ws.active_set()
        F.p = ws.Pf[F.idx]
        tc = T[F.idx]
        if tc.size:
            tc -= tc.mean()
        t.a = tc
        for v in F.vectors:
            if v is not t:
                v.a, v.valid = self.xp.zeros(F.idx.size), False
        ws.refresh()

    def settle(self, w, R, factor, P, F, t, g_prev, nF, frac, proj, go, gprev_ok, fresh):
        """``w`` moved by ``R`` scaled by ``factor`` (``-tau sigma`` after a step, ``sigma`` after a projected
        step's change); a projected step's ``F`` loses the nodes at ``p = 0`` and ``t`` is re-centred on it;
        Polak-Ribiere's history dropped after a projection that took ``frac`` of ``F`` away."""
        if not go.item():
            return nF
        if F.full:  # w recomputed in float64
            F.full = False
            fresh[...] = True
            return F.idx.size
        ws = self.ws
        if not self.single:  # u <- u - tau K t, float64
            np.multiply(R, F.tau, out=R)
            ws.w -= R
            fresh[...] = False
            return nF
        f = factor.item()
        if self.fused:  # one pass, the same bits; the least w off F for the next measure
            self._least_off = move_field(ws.w, R, R.dtype.type(abs(f)), f < 0, ws.mask)
        else:
            np.multiply(R, R.dtype.type(abs(f)), out=R)
            if f < 0:
                np.subtract(ws.w, R, out=ws.w)  # u <- u - tau K t: exact, no FFT pair for p
            else:
                np.add(ws.w, R, out=ws.w)
        fresh[...] = False
        if not proj[0]:
            return nF
        idx = F.idx
        keep = F.trial > 0.0
        gone = idx[~keep]
        if self._least_off is not None and gone.size:  # the nodes leaving F are off it now
            self._least_off = min(self._least_off, float(np.fmin.reduce(ws.wf[gone], initial=math.inf)))
        ws.mask.reshape(-1)[gone] = False
        ws.Pf[gone] = 0.0
        F.idx, F.p = idx[keep], F.p[keep]
        if g_prev.valid:
            if gone.size >= frac * idx.size:
                g_prev.valid = False
            else:
                g_prev.a = g_prev.a[keep]
        tc = t.a = t.a[keep]
        if tc.size:
            tc -= tc.mean()
        return F.idx.size


class WorkspaceCase:
    """What :class:`~.iteration.BatchIteration` reads of its solver, for the one case of a workspace."""

    batch = 1

    def __init__(self, ws: Workspace, tol: float, p0: float):
        self.ws, self.tol, self.size = ws, tol, ws.size
        self.xp, self.be = ws.xp, ws.be
        self.op = WorkspaceProducts(ws)
        self.kernels = CompressedKernels(ws, self.op, p0 * ws.size)
        self.h_rms = np.full((1, 1, 1), ws.h_rms)
        self.P, self.w = ws.P[None], ws.w[None]

    def refresh(self, cases) -> None:
        """``w = K P - h`` in float64 (one FFT pair)."""
        self.ws.refresh()


def pk_solve(ws: Workspace, p0: float, tol: float, max_iter: int, fresh: bool | None) -> tuple[int, bool]:
    """Solve one elastic load step of ``ws.method`` in place on ``ws`` from the pressure in ``ws.P``.

    The unilateral problem ``{p >= 0, g >= 0, p g = 0, mean(p) = p0}`` (docs/solver.md, "Algorithm"). ``ws.P``
    must be >= 0 with mean ``p0``; ``fresh`` says whether ``ws.w`` already equals ``K P - h`` (True), must be
    computed (False), or equals it up to single-precision round-off (None: not recomputed, but not taken as
    fresh either). Returns ``(iterations, converged)``; on exit ``ws.P``, ``ws.w`` (freshly recomputed) and
    ``ws.mask`` (``P > 0``) are consistent.
    """
    case = WorkspaceCase(ws, tol, p0)
    f0 = np.array([1 if fresh is True else (0 if fresh is False else -1)])
    it = BatchIteration(case, np.full((1, 1, 1), p0), f0, np.array([max_iter]), stall=STALL_WINDOW)
    its, conv = it.run(1)
    np.greater(ws.P, 0.0, out=ws.mask)  # an early exit right after nodes joined leaves them flagged with p = 0
    return int(its[0]), bool(conv[0])
