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
    target = p0 * ws.size
    scale = ws.scale(p0)
    inv_norm = 1.0 / (target * scale)
    w, wf, Pf, T, Tf, mask, bbuf = ws.w, ws.wf, ws.Pf, ws.T, ws.Tf, ws.mask, ws.bbuf
    maskf = mask.ravel()

    precond = ws.method != "pk"
    single = ws.method == "pk-fourier-f32"
    ws.setup_method()
    if precond:
        Zf = ws.Z.ravel()
    apply_m = ws.apply_m32 if single else ws.apply_m
    apply_k = ws.apply_k32 if single else ws.apply_k
    # single precision: w drifts from K p - h by ~1e-7 of the steps taken; it is
    # recomputed in float64 when the residual falls below each of these levels
    next_sync = 1e-5
    ksig = ws.sigma if single else 1.0
    if not fresh:
        ws.refresh()
    idx = ws.active_set()
    p_c = Pf[idx]
    t_c = np.zeros_like(p_c)
    g_c, a_c = np.empty_like(p_c), np.empty_like(p_c)
    T.fill(0.0)
    fresh = True
    delta = 0.0
    g_old = 1.0
    it = 0
    guard = StallGuard(max_iter)
    converged = False
    gbar = 0.0
    residual = math.inf
    joined_after = 0  # > 0: nodes from this index on joined F this iteration

    while True:
        nf = idx.size
        # ---- gap on the free set, offset chosen so that it has zero mean there
        if nf:
            np.take(wf, idx, out=g_c)
            gbar = g_c.sum() / nf
            g_c -= gbar
        # ---- sign violations: out-of-contact nodes with g < 0
        np.less(w, gbar, out=bbuf)
        np.greater(bbuf, mask, out=bbuf)  # (w < gbar) & ~mask, for booleans
        ncand = np.count_nonzero(bbuf)
        pen = 0.0
        if ncand:
            cand = np.flatnonzero(bbuf)
            g_cand = wf[cand] - gbar
            pen = -float(g_cand.min())
        orth = 0.0
        if nf:
            pen = max(pen, -float(g_c.min()))
            np.abs(g_c, out=a_c)
            orth = dot(p_c, a_c) * inv_norm
        residual = max(orth, pen / scale, 0.0)

        if residual <= tol:
            if fresh:
                converged = True
                break
            # Incremental updates may have drifted: confirm on a fresh K p.
            _sync_pressure(ws, idx, p_c, target)
            ws.refresh()
            fresh = True
            continue
        if single and residual < next_sync and not fresh:
            # float64 gap below 1e-5 and after every further four decades
            while next_sync > residual:
                next_sync *= 1e-4
            _sync_pressure(ws, idx, p_c, target)
            ws.refresh()
            fresh = True
            continue
        if guard.stop(residual, it):
            break
        it += 1

        # ---- violating nodes join the free set and the CG restarts (PK's rule):
        # folding them into the search direction keeps the update of u exact.
        if ncand:
            joined_after = nf
            idx = np.concatenate([idx, cand])
            p_c = np.concatenate([p_c, np.zeros(ncand)])
            g_c = np.concatenate([g_c, g_cand])
            a_c = np.empty_like(p_c)
            t_c = np.empty_like(p_c)
            maskf[cand] = True
            delta = 0.0
            nf = idx.size
        if nf == 0:
            break

        # ---- conjugate direction (zero mean on F, so mean(p) is kept) and step
        if precond:
            if joined_after:
                # gradient on the enlarged set: zero mean on F (shifts d only)
                g_c -= g_c.sum() / nf
                joined_after = 0
            # z = P_F M P_F g, zero mean on F; beta = g.z / g_old.z_old
            Zf[idx] = g_c
            _take(apply_m(ws.Z).ravel(), idx, a_c)
            if single:
                a_c *= ksig  # the float32 product is M g / sigma
            Zf[idx] = 0.0
            a_c -= a_c.sum() / nf
            G = dot(g_c, a_c)
            if not (G > 0.0 and math.isfinite(G)):
                break  # breakdown at round-off level: the final check decides
            if delta > 0.0 and g_old > 0.0:
                t_c *= G / g_old
                t_c += a_c
            else:
                t_c[...] = a_c
        else:
            G = dot(g_c, g_c)
            if delta > 0.0 and g_old > 0.0:
                t_c *= delta * G / g_old
                t_c += g_c
            else:
                t_c[...] = g_c
                if joined_after:
                    # Restore zero mean on the nodes already in contact only: each
                    # joining node keeps t = g (< 0), so the step moves it into the
                    # contact set as PK's rule does instead of clipping it at once.
                    # g.t = |g|^2 still holds because g has zero mean on the old
                    # free set.
                    t_c[:joined_after] -= t_c.sum() / joined_after
                joined_after = 0
        g_old = G
        delta = 1.0
        Tf[idx] = t_c
        Rf = apply_k(T).ravel()
        _take(Rf, idx, a_c)
        if single:
            a_c *= ws.sigma  # the float32 product is K t / sigma
        rt = dot(a_c, t_c)
        tau = dot(g_c, t_c) / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tau) and tau > 0.0):
            break  # null direction: nothing can move, report as not converged
        # trial pressure in a_c
        np.multiply(t_c, -tau, out=a_c)
        a_c += p_c
        n_out = np.count_nonzero(a_c <= 0.0)
        if n_out == 0:
            p_c, a_c = a_c, p_c
            np.multiply(Rf, Rf.dtype.type(tau * ksig), out=Rf)
            wf -= Rf  # u <- u - tau K t: exact, no FFT pair for p
            fresh = False
            continue

        # ---- Polonsky-Keer projection onto p >= 0, exact mean, fresh K p
        np.maximum(a_c, 0.0, out=a_c)
        Pf[idx] = a_c
        enforce_mean(ws.P, target, None)
        idx = ws.active_set()
        t_c = Tf[idx]
        if t_c.size:
            t_c -= t_c.mean()
        T.fill(0.0)
        p_c = Pf[idx]
        g_c, a_c = np.empty_like(p_c), np.empty_like(p_c)
        if single and next_sync == 1e-5 and residual > next_sync:
            # far from convergence u = K p in float32 is accurate enough (~1e-7
            # of u); the float64 recomputations below 1e-5 take over from there
            np.multiply(ws.apply_k32(ws.P), ksig, out=w)
            w -= ws.h
            fresh = False
        else:
            ws.refresh()
            fresh = True

    Pf[idx] = p_c
    if not fresh:
        _sync_pressure(ws, idx, p_c, target)
        ws.refresh()
    # An early exit right after nodes joined leaves them flagged with p = 0.
    np.greater(ws.P, 0.0, out=mask)
    return it, converged


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


