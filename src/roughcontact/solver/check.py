"""The final check of every load step on a freshly recomputed displacement."""

from __future__ import annotations

import math

import numpy as np

from .box import offset_no_free
from .workspace import Workspace, dot

#: Relative tolerance of the final check ``|mean(p) - p0| <= MEAN_RTOL * p0``.
MEAN_RTOL = 1e-10


def final_check(ws: Workspace, p0: float, tol: float, cap: float | None):
    """The invariants of the module docstring on ``ws.P`` and a fresh ``ws.w``.

    Returns ``(ok, residual, gbar, w_sum)``: ``gbar`` is ``-d``, the offset that
    makes the gap zero-mean on the free set, ``w_sum`` the sum of ``ws.w``. A NaN
    or inf anywhere makes a sum non-finite, so finiteness is read off the sums.
    """
    P, w = ws.Pf, ws.wf
    target = p0 * ws.size
    scale = ws.scale(p0)
    p_sum, w_sum = float(P.sum()), float(w.sum())
    if not (math.isfinite(p_sum) and math.isfinite(w_sum)):
        return False, math.inf, 0.0, w_sum
    bounds = float(P.min()) >= 0.0 and (cap is None or float(P.max()) <= cap)
    mean_ok = abs(p_sum - target) <= MEAN_RTOL * target
    pos = ws.mask.ravel()
    np.greater(P, 0.0, out=pos)
    if cap is None:
        free = pos
        capd = None
    else:
        capd = P >= cap
        free = pos & ~capd
    w_f = w[free]
    nf = w_f.size
    if nf:
        gbar = float(w_f.mean())
        w_f -= gbar
        e_orth = dot(P[free], np.abs(w_f)) / (target * scale)
    else:
        gbar = offset_no_free(w, ~pos, capd if capd is not None else np.zeros_like(pos))
        e_orth = 0.0
    if capd is None:
        e_pen = max(0.0, gbar - float(w.min())) / scale
        e_cap = 0.0
    else:
        below = ~capd
        e_pen = max(0.0, gbar - float(w[below].min())) / scale if below.any() else 0.0
        e_cap = max(0.0, float(w[capd].max()) - gbar) / scale if capd.any() else 0.0
    residual = max(e_orth, e_pen, e_cap)
    ok = bounds and mean_ok and residual <= tol
    return ok, residual, gbar, w_sum


