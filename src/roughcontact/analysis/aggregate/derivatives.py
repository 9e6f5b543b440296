"""Load derivatives of a load curve: finite differences in ``p0`` and least-squares slopes over windows of ``log A/A0``.

:func:`load_derivative` differentiates ``pbar`` with respect to ``p0`` (or ``log p0``) on the
solver's own load steps; :func:`windowed_load_slope` estimates ``d pbar / d p0`` by least squares
over windows of ``log A/A0`` (:func:`log_window_edges`), a smoother alternative to the finite differences.
"""

from __future__ import annotations

import numpy as np


def fd_weights(x0: float, x: np.ndarray) -> np.ndarray:
    """Finite-difference weights of the first derivative at ``x0`` from nodes ``x``.

    Fornberg's (1988) recursion: ``f'(x0) ~ w @ f(x)`` exactly for polynomials of degree
    ``len(x) - 1``, for any distinct, not necessarily uniform, nodes.

    Parameters
    ----------
    x0 : float
        Where the derivative is wanted.
    x : numpy.ndarray, shape (m,)
        Distinct nodes, m >= 2.

    Returns
    -------
    numpy.ndarray, shape (m,)
        Weights [1 / unit of x].
    """
    x = np.asarray(x, dtype=float)
    m = x.size
    c = np.zeros((m, 2))
    c[0, 0] = 1.0
    c1, c4 = 1.0, x[0] - x0
    for i in range(1, m):
        mn = min(i, 1)
        c2, c5, c4 = 1.0, c4, x[i] - x0
        for j in range(i):
            c3 = x[i] - x[j]
            c2 *= c3
            if j == i - 1:
                for k in range(mn, 0, -1):
                    c[i, k] = c1 * (k * c[i - 1, k - 1] - c5 * c[i - 1, k]) / c2
                c[i, 0] = -c1 * c5 * c[i - 1, 0] / c2
            for k in range(mn, 0, -1):
                c[j, k] = (c4 * c[j, k] - k * c[j, k - 1]) / c3
            c[j, 0] = c4 * c[j, 0] / c3
        c1 = c2
    return c[:, 1]


#: Variables in which :func:`load_derivative` may difference.
DERIVATIVE_VARIABLES = ("log_p0", "p0")


def load_derivative(values: np.ndarray, p0: np.ndarray, *, order: int = 2,
                    variable: str = "log_p0") -> np.ndarray:
    """``d values / d p0`` along the last axis by finite differences of order 2 or 4.

    Stencil: centred ``order + 1``-point Fornberg weights on the actual (non-uniform)
    nodes, shifted to one-sided ``order + 1`` points at the two ends, so the error is
    ``O(h^order)`` everywhere; for ``order=2`` this is exactly
    ``numpy.gradient(..., edge_order=2)``.

    ``variable="log_p0"`` (default) differences in ``ln p0`` and applies the chain rule
    ``d/d p0 = (1/p0) d/d ln p0``. Why: at small loads ``pbar`` carries a singular
    ``p0^(1-mu)`` term (the CEL's ``pbar = (h'E*/kappa)(1 + beta x^(1-mu))^(1/(1-mu))``,
    ``x ~ p0``), which is smooth in ``ln p0`` but not in ``p0``. On 30 uniform load
    steps reaching ``A/A0 = 0.15``, the second-order error at the second step falls from
    4 % (in ``p0``) to 1 % (in ``ln p0``), and the bias this puts into a log-log fit of
    ``mu`` over ``A/A0 in [0.01, 0.11]`` from +0.011 to +0.003; ``order=4`` removes it
    (< 1e-4) at the cost of about 1.3x (interior) to 3x (end points) more noise
    amplification. ``variable="p0"`` differences ``p0`` directly. A NaN only spoils the
    derivatives whose stencil contains it.

    Parameters
    ----------
    values : numpy.ndarray, shape (..., n_steps)
        Quantity along the load steps (e.g. ``pbar``) [any unit].
    p0 : numpy.ndarray, shape (..., n_steps) or (n_steps,)
        Applied pressure at each step, > 0 and strictly increasing along the last axis;
        all-NaN rows (grid holes) give all-NaN derivatives.
    order : {2, 4}
        Order of accuracy; needs at least ``order + 1`` steps.
    variable : {"log_p0", "p0"}
        Variable the differences are taken in.

    Returns
    -------
    numpy.ndarray, shape of ``values``
        Derivative [unit of values / unit of p0].
    """
    _check_stencil(order, variable)
    v = np.asarray(values, dtype=float)
    p = np.broadcast_to(np.asarray(p0, dtype=float), v.shape)
    n = v.shape[-1]
    if n < order + 1:
        raise ValueError(f"need >= {order + 1} load steps for order-{order} differences, got {n}")
    flat_v, flat_p = v.reshape(-1, n), p.reshape(-1, n)
    out = np.full_like(flat_v, np.nan)
    cache: dict[bytes, np.ndarray] = {}  # one weight matrix per load schedule: cases usually share theirs
    for i in range(flat_v.shape[0]):
        pi = flat_p[i]
        if np.all(np.isnan(pi)):
            continue
        _check_load_steps(pi, variable)
        key = pi.tobytes()
        if key not in cache:
            cache[key] = _derivative_matrix(pi, order, variable)
        out[i] = cache[key] @ flat_v[i]
    return out.reshape(v.shape)


def _check_stencil(order: int, variable: str) -> None:
    """Raise ``ValueError`` unless ``order`` is 2 or 4 and ``variable`` one of :data:`DERIVATIVE_VARIABLES`."""
    if order not in (2, 4):
        raise ValueError(f"order must be 2 or 4, got {order!r}")
    if variable not in DERIVATIVE_VARIABLES:
        raise ValueError(f"variable must be one of {DERIVATIVE_VARIABLES}, got {variable!r}")


def _check_load_steps(p0_row: np.ndarray, variable: str) -> None:
    """Raise ``ValueError`` unless the loads ``p0_row`` (n_steps,) rise strictly, finite (> 0 for ``log_p0``)."""
    if not (np.all(np.isfinite(p0_row)) and np.all(np.diff(p0_row) > 0)):
        raise ValueError(f"p0 must be finite and strictly increasing along the load steps, got {p0_row!r}")
    if variable == "log_p0" and p0_row[0] <= 0:
        raise ValueError(f"p0 must be > 0 to difference in ln p0, got {p0_row!r}")


def _derivative_matrix(p0_row: np.ndarray, order: int, variable: str) -> np.ndarray:
    """Matrix ``W``, shape (n_steps, n_steps), with ``W @ values = d values / d p0`` on the loads ``p0_row``.

    Row ``j`` holds the ``order + 1`` Fornberg weights (:func:`fd_weights`) of the stencil
    centred on step ``j``, shifted to one side at the two ends; with ``variable="log_p0"`` the
    weights are taken in ``ln p0`` and divided by ``p0`` (chain rule) [1 / unit of p0].
    """
    n, width, half = p0_row.size, order + 1, order // 2
    x = np.log(p0_row) if variable == "log_p0" else p0_row
    W = np.zeros((n, n))
    for j in range(n):
        lo = min(max(j - half, 0), n - width)
        W[j, lo:lo + width] = fd_weights(x[j], x[lo:lo + width])
    if variable == "log_p0":
        W /= p0_row[:, None]
    return W


def log_window_edges(area: np.ndarray, per_decade: int = 6, min_points: int = 2) -> np.ndarray:
    """Edges of windows of equal width ``1/per_decade`` decade in ``A/A0``, each holding steps.

    The edges sit on the fixed grid ``10^(k / per_decade)`` (integer ``k``) and cover the
    range of ``area``, so curves of different range get the same windows. Where the load
    steps are sparse in ``log A/A0`` (small loads on an equally spaced load schedule) a
    window holding fewer than ``min_points`` values of ``area`` is merged with the next
    one (the last with the previous one): those windows are wider, a whole number of
    grid windows.

    Parameters
    ----------
    area : numpy.ndarray, shape (n,)
        Reference area fractions ``A/A0`` [1] (e.g. a seed-mean load curve); non-finite
        and non-positive values are ignored; at least ``min_points`` must remain.
    per_decade : int
        Grid windows per decade (>= 1).
    min_points : int
        Fewest values of ``area`` a window must hold (>= 1).

    Returns
    -------
    numpy.ndarray, shape (n_windows + 1,)
        Increasing edges [1], the first <= ``min(area)``, the last > ``max(area)``.
    """
    for name, v in (("per_decade", per_decade), ("min_points", min_points)):
        if not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
    a = np.asarray(area, dtype=float).ravel()
    a = np.sort(a[np.isfinite(a) & (a > 0)])
    if a.size < min_points:
        raise ValueError(f"area holds {a.size} finite positive value(s); min_points={min_points}")
    k = np.floor(np.log10(a) * per_decade + 1e-9)
    grid = 10.0 ** (np.arange(k[0], k[-1] + 2) / per_decade)
    counts = np.histogram(a, bins=grid)[0]
    keep, held = [grid[0]], 0
    for j, c in enumerate(counts):
        held += c
        if held >= min_points:
            keep.append(grid[j + 1])
            held = 0
    if held:
        keep[-1] = grid[-1]
    return np.asarray(keep)


def windowed_load_slope(pbar: np.ndarray, p0: np.ndarray, area: np.ndarray, edges: np.ndarray, *,
                        min_points: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """``d pbar / d p0`` as the least-squares slope of ``pbar`` against ``p0`` per window of ``A/A0``.

    The load steps whose area fraction lies in ``[edges[j], edges[j+1])`` form window
    ``j``; a straight line ``pbar = a + b p0`` is fitted to them and ``b`` is returned with
    the steps' mean ``A/A0``. The slope is exact for a linear ``pbar(p0)``, and for a
    quadratic one on equally spaced loads it is exactly ``pbar'`` at the steps' mean
    ``p0`` (the odd moments of the loads about their mean vanish); in general its error is
    ``O(d^2 pbar''')`` for a window of half-width ``d`` in ``p0``. With windows of equal
    width in ``log A/A0`` (:func:`log_window_edges`) the estimate averages over many steps
    at large ``A/A0``, where finite differences are noisiest on a log axis, and reduces to
    the secant of two steps where steps are sparse. Non-finite values are left out.

    Parameters
    ----------
    pbar : numpy.ndarray, shape (..., n_steps)
        Mean contact pressure ``F/A`` [pressure unit].
    p0 : numpy.ndarray, shape (..., n_steps) or (n_steps,)
        Applied mean pressure ``F/A0`` [same pressure unit].
    area : numpy.ndarray, shape (..., n_steps)
        Area fraction ``A/A0`` [1] that assigns the steps to windows.
    edges : numpy.ndarray, shape (n_windows + 1,)
        Increasing window edges in ``A/A0`` [1].
    min_points : int
        Fewest steps a window needs (>= 2); fewer give NaN.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., n_windows)
        Mean ``A/A0`` of the window's steps [1] and the slope ``d pbar / d p0`` [1].
    """
    if not isinstance(min_points, (int, np.integer)) or min_points < 2:
        raise ValueError(f"min_points must be an integer >= 2, got {min_points!r}")
    y = np.asarray(pbar, dtype=float)
    x = np.broadcast_to(np.asarray(p0, dtype=float), y.shape)
    a = np.broadcast_to(np.asarray(area, dtype=float), y.shape)
    e = np.asarray(edges, dtype=float)
    if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0):
        raise ValueError("edges must be a 1-D increasing array of at least two values")
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(a)
    a_mean = np.full(y.shape[:-1] + (e.size - 1,), np.nan)
    slope = np.full_like(a_mean, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        for j in range(e.size - 1):
            m = ok & (a >= e[j]) & (a < e[j + 1])
            n = m.sum(axis=-1)
            xm = np.where(m, x, 0.0).sum(axis=-1) / n
            ym = np.where(m, y, 0.0).sum(axis=-1) / n
            dx = np.where(m, x - xm[..., None], 0.0)
            sxx = (dx * dx).sum(axis=-1)
            b = (dx * np.where(m, y - ym[..., None], 0.0)).sum(axis=-1) / sxx
            good = (n >= min_points) & (sxx > 0)
            slope[..., j] = np.where(good, b, np.nan)
            a_mean[..., j] = np.where(good, np.where(m, a, 0.0).sum(axis=-1) / n, np.nan)
    return a_mean, slope
