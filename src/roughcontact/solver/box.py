"""The capped iteration: gradient projection / CG on ``{0 <= p <= H, mean(p) = p0}``.

Used when an effect bounds the pressure from above (:class:`~.effects.PlasticityCap`);
package docstring, "With a hardness".
"""

from __future__ import annotations

import math

import numpy as np

from .projection import project
from .workspace import StallGuard, Workspace, dot


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
    z_f = ws.apply_m(ws.Z).ravel()[idx]
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
    n2 = ws.size
    target = p0 * n2
    scale = ws.scale(p0)
    inv_norm = 1.0 / (target * scale)
    P, w = ws.Pf, ws.wf
    shape = ws.P.shape
    if not fresh:
        ws.refresh()
    fresh = True
    zero_m = np.empty(n2, dtype=bool)
    cap_m = np.empty(n2, dtype=bool)
    b1 = np.empty(n2, dtype=bool)
    t = np.zeros(n2)  # CG direction, zero off the free set
    precond = ws.method != "pk"
    if precond:
        ws.setup_method()
    kt = np.empty(n2)

    def active_sets():
        np.less_equal(P, 0.0, out=zero_m)
        np.greater_equal(P, cap, out=cap_m)
        np.logical_or(zero_m, cap_m, out=b1)
        np.logical_not(b1, out=b1)
        return np.flatnonzero(b1)

    idx = active_sets()
    g_old = 0.0
    restart = True
    alpha = 0.0  # gradient-projection step length; 0 = not known yet
    it = 0
    guard = StallGuard(max_iter)
    converged = False
    residual = math.inf

    while True:
        nf = idx.size
        p_f = P[idx]
        g_f = w[idx]
        if nf:
            gbar = float(g_f.sum()) / nf
            g_f -= gbar
        else:
            gbar = offset_no_free(w, zero_m, cap_m)
        # sign violations: g < 0 at p = 0, g > 0 at p = H
        np.less(w, gbar, out=b1)
        b1 &= zero_m
        vz = np.flatnonzero(b1)
        g_z = w[vz] - gbar
        np.greater(w, gbar, out=b1)
        b1 &= cap_m
        vc = np.flatnonzero(b1)
        g_c = w[vc] - gbar
        pen = max(0.0, -float(g_z.min()) if vz.size else 0.0, -float(g_f.min()) if nf else 0.0)
        e_cap = float(g_c.max()) if vc.size else 0.0
        orth = dot(p_f, np.abs(g_f)) * inv_norm if nf else 0.0
        residual = max(orth, pen / scale, e_cap / scale)

        if residual <= tol:
            if fresh:
                converged = True
                break
            ws.refresh()
            fresh = True
            continue
        if guard.stop(residual, it):
            break
        it += 1

        # ---- proportioning: sign violations at the bounds vs gradient on the face
        chopped = dot(g_z, g_z) + dot(g_c, g_c)
        G = dot(g_f, g_f)
        if nf == 0 or chopped > G:
            # ---- gradient projection: P(p - alpha g), exact line search on the segment
            g = w - gbar
            if not alpha > 0.0:
                r = np.zeros(n2)  # projected gradient: free part and violations
                r[idx] = g_f
                r[vz] = g_z
                r[vc] = g_c
                act = np.concatenate([idx, vz, vc])
                r[act] -= r[act].mean()
                kr = ws.apply_k(r.reshape(shape)).ravel()
                rkr = dot(r, kr)
                alpha = dot(r, r) / rkr if rkr > 0.0 else 1.0
            step = project(P - alpha * g, target, cap)
            step -= P
            ks = ws.apply_k(step.reshape(shape)).ravel()
            sks, gs = dot(step, ks), dot(g, step)
            if not (sks > 0.0 and gs < 0.0 and math.isfinite(sks)):
                break  # no descent left at this precision: report as not converged
            theta = min(1.0, -gs / sks)
            alpha = dot(step, step) / sks  # Barzilai-Borwein, for the next projection
            if theta < 1.0:
                step *= theta
                ks *= theta
            P += step
            np.clip(P, 0.0, cap, out=P)
            w += ks
            idx = active_sets()
            restart = True
            fresh = False
            continue

        # ---- conjugate gradient on the face {0 < p < H}, direction zero-mean there;
        # with a preconditioner, z = P_F M P_F g (mean over F removed) as in pk_solve
        z_f, Gz = (_precondition(ws, idx, g_f) if precond else (g_f, G))
        if not (Gz > 0.0 and math.isfinite(Gz)):
            break  # breakdown at round-off level: the final check decides
        if restart or g_old <= 0.0:
            t.fill(0.0)
            t_f = z_f
        else:
            t_f = t[idx]
            t_f *= Gz / g_old
            t_f += z_f
        t[idx] = t_f
        g_old = Gz
        restart = False
        np.copyto(kt, ws.apply_k(t.reshape(shape)).ravel())
        tkt, rt = dot(t_f, kt[idx]), dot(g_f, t_f)
        if not (tkt > 0.0 and rt > 0.0 and math.isfinite(tkt)):
            break  # null direction: report as not converged
        tau = rt / tkt
        if not precond:
            alpha = tau  # a step length along -g: a fair guess for the next projection
        y_f = p_f - tau * t_f
        if y_f.min() > 0.0 and y_f.max() < cap:
            P[idx] = y_f
            kt *= tau
            w -= kt
            fresh = False
            continue
        # the CG step leaves the box: project the trial point onto the face
        # {0 <= p_F <= H, sum p_F fixed} and search on the segment to it
        x_f = project(y_f, float(p_f.sum()), cap)
        s_f = x_f - p_f
        step = np.zeros(n2)
        step[idx] = s_f
        ks = ws.apply_k(step.reshape(shape)).ravel()
        sks, gs = dot(s_f, ks[idx]), dot(g_f, s_f)
        if sks > 0.0 and gs < 0.0:
            theta = 1.0 if gs + 0.5 * sks < 0.0 else -gs / sks  # the projected point if it lowers the energy
            if theta >= 1.0:
                P[idx] = x_f
            else:
                P[idx] = np.clip(p_f + theta * s_f, 0.0, cap)
                ks *= theta
            w += ks
        else:
            # truncated CG step: up to the first bound met along -t
            with np.errstate(divide="ignore", invalid="ignore"):
                lim = np.where(t_f > 0.0, p_f / t_f, np.where(t_f < 0.0, (p_f - cap) / t_f, np.inf))
            j = int(np.argmin(lim))
            tmax = float(lim[j])
            if not (math.isfinite(tmax) and tmax >= 0.0):
                break  # no bound ahead although the trial left the box: round-off, give up
            new = np.clip(p_f - tmax * t_f, 0.0, cap)
            new[j] = 0.0 if t_f[j] > 0.0 else cap
            P[idx] = new
            kt *= tmax
            w -= kt
        idx = active_sets()
        restart = True
        fresh = False

    if not fresh:
        ws.refresh()
    np.greater(ws.P, 0.0, out=ws.mask)
    return it, converged


