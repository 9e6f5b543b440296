"""The settings of a CEL fit, checked, and the variables and attributes every fit dataset shares.

Fit settings (keyword arguments of :func:`~.grid.fit_cel` and :func:`~.topographies.fit_topographies`)
-----------------------------------------------------------------------------------------------------
window : (float, float)
    Contact-fraction window ``low <= A/A0 <= high``, ``0 < low < high <= 1``. Only converged
    steps inside it enter any fit.
n_boot : int
    Bootstrap resamples over seeds (or topographies), >= 10 (the paper-level analysis uses >= 200).
rng_seed : int
    Seed (>= 0) of the bootstrap; each group's stream also depends on the group.
methods : sequence of {"paper", "joint"}
    Estimators to run (:mod:`.estimators`).
min_points : int
    Fewest in-window points a fit accepts (>= 3; the joint fit needs >= 4).
kappa_extrapolation : {"cel", "poly2"}
    How the paper route extrapolates ``kappa_eff(a)`` to ``a = 0``.
paper_average : {"seeds", "none", "auto"}
    ``"seeds"``: the paper route fits the seed-mean curve of each H (mean ``A/A0``, ``kappa``,
    ``d pbar/d p0`` per load step, steps converged in every seed; the window applies to the mean
    ``A/A0``), which needs one load schedule per H. Averaging before taking logs matters: the log
    of a noisy finite difference is biased low by about half its relative variance, and that
    variance grows with ``A/A0``, which tilts ``mu``. ``"none"``: every (seed, step) point, each seed on
    its own schedule. ``"auto"`` (the pipeline's): ``"seeds"`` where every group's seeds share one
    schedule p0/(E* h'), else ``"none"`` (``load.target_area``, where each seed ends at its own p0);
    the result's ``paper_average`` attribute says which.
confidence : float
    Coverage of the percentile interval, in (0, 1).
on_insufficient : {"raise", "nan"}
    A group with cases but too few in-window points: raise ValueError naming the group and the
    window, or leave its values NaN.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .estimators import CONSTANTS, KAPPA_EXTRAPOLATIONS, METHODS, PAPER_CEL, constrained_flags


def check_window(window) -> tuple[float, float]:
    """The fit window ``(low, high)`` of area fractions, ``0 < low < high <= 1``; else a ValueError."""
    try:
        lo, hi = (float(w) for w in window)
    except (TypeError, ValueError):
        raise ValueError(f"window must be a pair (low, high) of area fractions, got {window!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi)) or not (0.0 < lo < hi <= 1.0):
        raise ValueError(f"window must satisfy 0 < low < high <= 1 (area fractions A/A0), got {window!r}")
    return lo, hi


def h_label(h: float) -> str:
    """A Hurst exponent as the fit tables label it (``%g``)."""
    return f"{float(h):g}"


def check_settings(window, n_boot, rng_seed, methods, min_points, kappa_extrapolation, confidence,
                    paper_average, on_insufficient) -> tuple[tuple[float, float], tuple[str, ...]]:
    """The validated window ``(low, high)`` and methods; ValueError naming the first bad setting."""
    lo, hi = check_window(window)
    if not isinstance(n_boot, (int, np.integer)) or n_boot < 10:
        raise ValueError(f"n_boot must be an integer >= 10, got {n_boot!r}")
    if not isinstance(rng_seed, (int, np.integer)) or rng_seed < 0:
        raise ValueError(f"rng_seed must be an integer >= 0, got {rng_seed!r}")
    methods = tuple(methods)
    if not methods or any(m not in METHODS for m in methods) or len(set(methods)) != len(methods):
        raise ValueError(f"methods must be distinct names from {METHODS}, got {methods!r}")
    if not isinstance(min_points, (int, np.integer)) or min_points < 3:
        raise ValueError(f"min_points must be an integer >= 3, got {min_points!r}")
    if kappa_extrapolation not in KAPPA_EXTRAPOLATIONS:
        raise ValueError(f"kappa_extrapolation must be one of {KAPPA_EXTRAPOLATIONS}, got "
                         f"{kappa_extrapolation!r}")
    if not (0.0 < float(confidence) < 1.0):
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
    if paper_average not in ("seeds", "none"):
        raise ValueError(f"paper_average must be 'seeds' or 'none', got {paper_average!r}")
    if on_insufficient not in ("raise", "nan"):
        raise ValueError(f"on_insufficient must be 'raise' or 'nan', got {on_insufficient!r}")
    return (lo, hi), methods


def estimate_vars(dims: tuple[str, ...], value, stderr, bstd, clo, chi, npts, *, confidence: float,
                   resampled: str, points: str, methods: Sequence[str]) -> dict:
    """The per-constant variables of a fit result, over ``dims`` (ending in estimator, constant).

    ``resampled`` names what the bootstrap draws (seeds, topographies); ``points`` says what
    the paper route's points are; ``methods`` the estimators, in order.
    """
    one = {"units": "1"}
    pct = f"{100 * float(confidence):g}%"
    return {
        "value": (dims, value, {**one, "long_name": "fitted CEL constant"}),
        "stderr": (dims, stderr, {**one, "long_name": "standard error from the fit itself "
                                  "(OLS / Jacobian covariance; ignores correlation along a load curve)"}),
        "bootstrap_stderr": (dims, bstd, {**one, "long_name": "bootstrap standard error "
                             f"({resampled} resampled with replacement; times sqrt(n/(n-1)))"}),
        "ci_low": (dims, clo, {**one, "long_name": f"lower end of the {pct} bootstrap percentile interval"}),
        "ci_high": (dims, chi, {**one, "long_name": f"upper end of the {pct} bootstrap percentile interval"}),
        "constrained": (dims, constrained_flags(value, clo, chi, methods), {**one, "long_name": "1 if the "
                        "bootstrap interval is narrower than the value itself, 0 if the data do not "
                        "constrain the constant (interval wider than the value, no interval, or the "
                        "value on a bound of the joint fit)"}),
        "n_points": (dims, npts, {**one, "long_name": f"in-window points used by the fit ({points})"}),
    }


def paper_vars() -> dict:
    """The published CEL constants and their uncertainties as dataset variables over ``constant``."""
    one = {"units": "1"}
    return {
        "paper_value": (("constant",), np.array([PAPER_CEL[c][0] for c in CONSTANTS]),
                        {**one, "long_name": "Yastrebov et al. (2012) value, k_l=16, k_s=32"}),
        "paper_stderr": (("constant",), np.array([PAPER_CEL[c][1] for c in CONSTANTS]),
                         {**one, "long_name": "Yastrebov et al. (2012) stated uncertainty"}),
    }


def estimator_coords(methods: Sequence[str]) -> dict:
    """The ``estimator`` and ``constant`` coordinates of a fit dataset, with their long names."""
    return {
        "estimator": ("estimator", np.array(methods, dtype=object),
                      {"units": "1", "long_name": "estimator: 'paper' (log-log d pbar/d p0 + kappa extrapolation) "
                                                  "or 'joint' (nonlinear least squares on A/A0(p0))"}),
        "constant": ("constant", np.array(CONSTANTS, dtype=object), {"units": "1", "long_name": "CEL constant"}),
    }


def settings_attrs(lo, hi, n_boot, rng_seed, confidence, min_points, kappa_extrapolation, paper_average,
                    e_star) -> dict:
    """The fit's settings as global attributes of its dataset."""
    return {
        "window_low": lo, "window_high": hi, "n_boot": int(n_boot), "rng_seed": int(rng_seed),
        "confidence": float(confidence), "min_points": int(min_points),
        "kappa_extrapolation": kappa_extrapolation, "paper_average": paper_average,
        "e_star": e_star,
        "description": "Contact evolution law A/A0 = (beta + [kappa p0/(h' E*)]^(mu-1))^(1/(mu-1))",
    }
