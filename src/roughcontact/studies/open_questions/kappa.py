"""κ against the bandwidth α at fixed resolution (Q2) and on cells of two sizes (Q3): pure functions.

κ is read at ``A/A0 = 0.05`` (and 0.01, 0.1) from each case's load curve (log-linear in A between
steps, :func:`roughcontact.studies.reproduction.kappa_at`), from the pixel-counted area or the
perimeter-corrected one (``kappa * A_corr / A``). κ is quoted in units of ``sqrt(2 pi)``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.stats import f as f_dist

from ...theory import KAPPA_BGT, asperity_kappa, discrete_power_law_moments
from ..reproduction import kappa_at

#: Areas at which κ is compared.
KAPPA_AREAS = (0.01, 0.05, 0.1)

#: Where Q2e splits the points to place κ's bend: no point at 32 px per λ_s lies between α = 2.8 and 3.7
#: (below: only the N = 1024 cells with λ_l = L/16 and L/8).
BEND_SPLIT = 3.0


def corrected(con: xr.Dataset) -> xr.Dataset:
    """``con`` with ``area_fraction`` and ``kappa`` of the perimeter-corrected area (κ scales with A at fixed p0)."""
    out = con.copy()
    out["kappa"] = con["kappa"] * con["area_fraction_corrected"] / con["area_fraction"]
    out["area_fraction"] = con["area_fraction_corrected"]
    return out


def alpha_points(con: xr.Dataset, k_s: float, area: float = 0.05) -> dict[str, np.ndarray]:
    """One point per ``(k_l, H)`` at the given ``k_s``: α, κ/√2π seed mean and sem, BGT, Greenwood.

    ``alpha`` is the seed mean of the surfaces' own α (``m0 m4 / m2²`` of each generated surface, the
    aggregate's ``alpha``): the bandwidth of the surfaces that were solved. ``alpha_lattice`` is the α
    of the generator's expected spectrum on the grid's modes
    (:func:`~roughcontact.theory.discrete_power_law_moments`), the same for every seed; ``n`` the
    grid and ``k_s`` the cutoff of each point.
    """
    sub = con.sel(k_s=k_s)
    kap = kappa_at(sub, area) / KAPPA_BGT
    n = kap.notnull().sum("seed")
    mean, sem = kap.mean("seed"), kap.std("seed", ddof=1) / np.sqrt(n)
    alpha = sub["alpha"].mean("seed")
    grid = int(con.attrs["n"])
    k_l, hurst = np.repeat(sub["k_l"].values, sub.sizes["H"]), np.tile(sub["H"].values, sub.sizes["k_l"])
    flat = {"alpha": alpha.values.ravel(), "kappa": mean.values.ravel(), "sem": sem.values.ravel(), "k_l": k_l,
            "H": hurst, "k_s": np.full(k_l.size, float(k_s)), "n": np.full(k_l.size, grid),
            "alpha_lattice": np.array([discrete_power_law_moments(grid, kl, float(k_s), h)["alpha"]
                                       for kl, h in zip(k_l, hurst, strict=True)])}
    ok = np.isfinite(flat["kappa"]) & np.isfinite(flat["sem"])
    flat = {k: v[ok] for k, v in flat.items()}
    for model in ("bgt", "greenwood"):
        flat[model] = np.array([float(asperity_kappa(area, alpha=a, model=model)) for a in flat["alpha"]]) / KAPPA_BGT
    return flat


def weighted_fit(x: np.ndarray, y: np.ndarray, sem: np.ndarray | None, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Polynomial ``y = sum_k c_k x^k`` (``k <= degree``) by weighted least squares: ``(c, cov)``.

    With ``sem`` the weights are ``1 / sem^2`` and the covariance is scaled by the reduced chi-square
    when that exceeds 1 (scatter beyond the seed errors widens it, never narrows it). Without, the
    points are exact (a theory's curve): the covariance is 0.
    """
    design = np.stack([x**k for k in range(degree + 1)], axis=1)
    w = np.ones_like(x) if sem is None else 1.0 / sem**2
    cov = np.linalg.inv(design.T @ (design * w[:, None]))
    coef = cov @ (design.T @ (w * y))
    if sem is None:
        return coef, np.zeros_like(cov)
    chi2 = float(np.sum(w * (y - design @ coef) ** 2)) / max(x.size - degree - 1, 1)
    return coef, cov * max(chi2, 1.0)


def log_slope(alpha: np.ndarray, kappa: np.ndarray, sem: np.ndarray | None = None) -> tuple[float, float]:
    """Slope of κ against ln α by (weighted) least squares and its standard error (:func:`weighted_fit`)."""
    coef, cov = weighted_fit(np.log(alpha), kappa, sem, 1)
    return float(coef[1]), float(np.sqrt(cov[1, 1]))


def cell_size_comparison(small: xr.Dataset, large: xr.Dataset, areas=KAPPA_AREAS) -> list[dict]:
    """κ on the L cell (``small``) against the 2L cell (``large``) per H and area.

    Each row: ``H``, ``area``, means and standard errors (units of √2π), the z-score of the
    difference, and the ratio of the seed standard deviations with its 95 % interval
    (F distribution with ``n_L - 1`` and ``n_2L - 1`` degrees of freedom).
    """
    rows = []
    for h in large["H"].values:
        for area in areas:
            a = kappa_at(small.sel(H=h), area).values.ravel() / KAPPA_BGT
            b = kappa_at(large.sel(H=h), area).values.ravel() / KAPPA_BGT
            a, b = a[np.isfinite(a)], b[np.isfinite(b)]
            sa, sb = a.std(ddof=1), b.std(ddof=1)
            se = np.hypot(sa / np.sqrt(a.size), sb / np.sqrt(b.size))
            ratio = sb / sa
            lo = ratio / np.sqrt(f_dist.ppf(0.975, b.size - 1, a.size - 1))
            hi = ratio / np.sqrt(f_dist.ppf(0.025, b.size - 1, a.size - 1))
            rows.append({"H": float(h), "area": area, "small": (a.mean(), sa / np.sqrt(a.size)),
                         "large": (b.mean(), sb / np.sqrt(b.size)), "z": (b.mean() - a.mean()) / se,
                         "sd_ratio": (ratio, lo, hi)})
    return rows


def trend_test(base: dict, new: dict) -> dict:
    """The ``new`` points against the line ``κ = a + b ln α`` fitted (weighted) to ``base``.

    ``z = (κ_new - line(α_new)) / sqrt(sem_new² + s²)``, ``s`` the weighted residual standard deviation
    of ``base`` about its line (the scatter a point of the same kind shows beyond its own error).
    """
    x = np.log(base["alpha"])
    w = 1.0 / base["sem"] ** 2
    b, a = np.polyfit(x, base["kappa"], 1, w=np.sqrt(w))
    resid = base["kappa"] - (a + b * x)
    s = float(np.sqrt(np.sum(w * resid**2) / np.sum(w) * x.size / max(x.size - 2, 1)))
    line = a + b * np.log(new["alpha"])
    return {"line": line, "z": (new["kappa"] - line) / np.sqrt(new["sem"] ** 2 + s**2), "scatter": s}


def log_curvature(alpha: np.ndarray, kappa: np.ndarray, sem: np.ndarray) -> tuple[float, float]:
    """The ``(ln α)²`` coefficient of a weighted quadratic fit of κ against ln α, and its standard error.

    As in :func:`log_slope`, the error is scaled by the root of the reduced chi-square when that
    exceeds 1. Zero within its error: the fall is linear in ln α; positive: it bends upward (slows).
    """
    coef, cov = weighted_fit(np.log(alpha), kappa, sem, 2)
    return float(coef[2]), float(np.sqrt(cov[2, 2]))


def bend(points: dict, alpha_key: str = "alpha", split: float = BEND_SPLIT) -> dict:
    """Where κ's fall in ln α bends: the fits over all points, below and above ``split`` in α.

    ``all`` and ``above``: ``(slope, its se, curvature, its se, n)`` (:func:`log_slope`,
    :func:`log_curvature`); ``below``: ``(slope, se, n)``. ``line_top``: the line above ``split`` at
    the largest α, ``(alpha, line, its se, measured, z)`` with ``z = (κ − line) / √(s² + se²)``, ``s``
    the point's seed error scaled by the root of the above-fit's reduced χ² (when > 1), as its errors
    are. ``lines``: the straight lines below and above, ``(alpha_from, alpha_to, intercept, slope)``.
    ``alpha_key`` picks the α (``alpha``: measured; ``alpha_lattice``: the expected spectrum's).
    """
    alpha, kap, sem = points[alpha_key], points["kappa"], points["sem"]

    def fits(sel):
        m, e = log_slope(alpha[sel], kap[sel], sem[sel])
        c, ce = log_curvature(alpha[sel], kap[sel], sem[sel])
        return m, e, c, ce, int(sel.sum())

    above, below = alpha >= split, alpha < split
    x = np.log(alpha[above])
    coef, cov = weighted_fit(x, kap[above], sem[above], 1)
    design = np.stack([np.ones_like(x), x], axis=1)
    chi2 = float(np.sum((kap[above] - design @ coef) ** 2 / sem[above] ** 2)) / max(x.size - 2, 1)
    top = int(np.argmax(alpha))
    xt = np.array([1.0, np.log(alpha[top])])
    line, line_se = float(xt @ coef), float(np.sqrt(xt @ cov @ xt))
    z = (kap[top] - line) / np.sqrt(sem[top] ** 2 * max(chi2, 1.0) + line_se**2)
    low, _ = weighted_fit(np.log(alpha[below]), kap[below], sem[below], 1)
    return {"all": fits(np.ones(alpha.size, bool)), "above": fits(above),
            "lines": {"below": (float(alpha[below].min()), split, *map(float, low)),
                      "above": (split, float(alpha[above].max()), *map(float, coef))},
            "below": log_slope(alpha[below], kap[below], sem[below]) + (int(below.sum()),), "split": split,
            "line_top": (float(alpha[top]), line, line_se, float(kap[top]), float(z)),
            "range": (float(alpha.min()), float(alpha.max()))}


def merged_points(*points: dict) -> dict:
    """Several :func:`alpha_points` results as one set of points."""
    return {k: np.concatenate([p[k] for p in points]) for k in points[0]}
