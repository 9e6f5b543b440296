"""Projections onto the feasible pressures ``{0 <= p (<= H), sum(p) = total}``."""

from __future__ import annotations

import numpy as np


def project(y: np.ndarray, total: float, cap: float, out: np.ndarray | None = None,
            work: np.ndarray | None = None) -> np.ndarray:
    """Euclidean projection of ``y`` onto ``{0 <= x <= cap, sum(x) = total}``.

    The projection is ``x = clip(y - lam, 0, cap)`` with the offset ``lam`` such
    that ``sum(x) = total`` (requires ``0 < total < cap * y.size``):
    ``phi(lam) = sum(clip(y - lam, 0, cap)) - total`` is piecewise linear and
    non-increasing, so Newton steps (slope minus the number of nodes strictly
    inside the box) inside a bisection bracket find it, exactly once the nodes
    inside stop changing. The last rounding error of the sum is spread over
    the nodes inside the box; when the cap is below the resolution of ``y``
    (the bracket shrinks to adjacent floats with no node inside), ``x``
    interpolates between the two sides of the jump. ``out`` (float, not ``y``) and ``work``
    (bool), of ``y``'s shape, spare the two allocations of a call; the result is ``out`` then
    (except for a cap below the resolution of ``y``, where it is a new array).
    """
    size = y.size
    if total >= cap * size:  # only reachable through round-off of p0 -> hardness
        if out is None:
            return np.full_like(y, cap)
        out.fill(cap)
        return out
    lo = float(y.min()) - cap  # phi(lo) = size * cap - total > 0
    hi = float(y.max())  # phi(hi) = -total < 0
    lam = float(y.mean()) - total / size  # exact when nothing is clipped
    if abs(float(np.clip(y, 0.0, cap).sum()) - total) <= 1e-14 * total:
        # already feasible up to round-off: no shift, so that nodes at a bound
        # stay exactly there (a shift by a rounding error of lam would move the
        # capped nodes an ulp inside the box and make them free)
        lam = 0.0
    if not lo < lam < hi:
        lam = 0.5 * (lo + hi)
    z = np.empty_like(y) if out is None else out
    inside = np.empty_like(y, dtype=bool) if work is None else work
    for k in range(400):
        np.subtract(y, lam, out=z)
        np.greater(z, 0.0, out=inside)
        inside &= z < cap
        np.clip(z, 0.0, cap, out=z)
        phi = float(z.sum()) - total
        if abs(phi) <= 1e-14 * total:
            break
        if phi > 0:
            lo = lam
        else:
            hi = lam
        m = np.count_nonzero(inside)
        new = lam + phi / m if m and k < 100 else 0.5 * (lo + hi)
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
            if not lo < new < hi:
                return _across_jump(y, lo, hi, total, cap)
        lam = new
    _spread_rounding(z, total, cap, inside)
    return z


def _across_jump(y: np.ndarray, lo: float, hi: float, total: float, cap: float) -> np.ndarray:
    """The bracket ``(lo, hi)`` collapsed onto a jump of ``phi``: interpolate across it."""
    zl = np.clip(y - lo, 0.0, cap)
    zh = np.clip(y - hi, 0.0, cap)
    sl, sh = float(zl.sum()), float(zh.sum())
    theta = (total - sh) / (sl - sh) if sl > sh else 0.0
    zl -= zh
    zl *= min(max(theta, 0.0), 1.0)
    zh += zl
    return zh


def _spread_rounding(z: np.ndarray, total: float, cap: float, inside: np.ndarray) -> None:
    """Spread the last rounding error of ``sum(z)`` over the nodes strictly inside the box (in place)."""
    err = total - float(z.sum())
    if err:
        np.greater(z, 0.0, out=inside)
        inside &= z < cap
        m = np.count_nonzero(inside)
        if m:
            z[inside] += err / m
            np.clip(z, 0.0, cap, out=z)


def enforce_mean(P: np.ndarray, target: float, hardness: float | None) -> None:
    """Make ``P.sum() == target`` in place, keeping ``0 <= P <= hardness``.

    Without a cap this is a plain rescale (uniform field if ``P`` is 0). With a
    cap, the nodes already loaded are projected onto ``{0 <= p <= H, sum = target}``
    (:func:`project`, a common shift of their pressures) when they can carry
    ``target``; otherwise the whole field is.
    """
    if hardness is None:
        s = P.sum()
        if s > 0:
            P *= target / s
        else:
            P.fill(target / P.size)
        return
    flat = P.reshape(-1)
    np.clip(flat, 0.0, hardness, out=flat)
    pos = np.flatnonzero(flat > 0)
    if hardness * pos.size > target * (1.0 + 1e-12):
        flat[pos] = project(flat[pos], target, hardness)
    else:
        flat[...] = project(flat, target, hardness)
