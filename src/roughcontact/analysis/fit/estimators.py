"""The two estimators of the contact evolution law (CEL) constants, their bounds and constrained flags.

The CEL (Yastrebov, Anciaux & Molinari 2012, Eq. 2) is
``a = A/A0 = (beta + [kappa p0 / (h' E*)]^(mu-1))^(1/(mu-1))``; it integrates
``d pbar / d p0 = beta a^(-mu)`` from the linear law ``a = kappa p0 / (h' E*)``.
Two estimators are offered, both restricted to a window of contact fraction
(the paper's ``a in [0.01, 0.11]``) and to converged load steps whose contact the grid resolves (:mod:`.cases`):

``"paper"`` (the paper's route; by default on the seed-mean curve of each H)
    1. ``mu`` and ``beta`` from an ordinary least-squares line through
       ``log(d pbar / d p0) = log(beta) - mu log(a)`` (Fig. 4).
    2. ``kappa`` by extrapolating the normalised inverse mean pressure
       ``kappa_eff(a) = E* h' / pbar = h' E* a / p0`` (Fig. 3) to ``a -> 0``. Inverting the
       CEL, ``p0 = (h' E*/kappa) (a^(mu-1) - beta)^(1/(mu-1))``, hence
       ``kappa_eff(a) = kappa a (a^(mu-1) - beta)^(1/(1-mu)) = kappa g(a)`` with
       ``g(a) = (1 - beta a^(1-mu))^(1/(1-mu))``, ``g(0) = 1``. With ``mu, beta`` from
       step 1, ``kappa_eff`` is linear in the single unknown ``kappa``; its least-squares
       value ``kappa = sum(g_i y_i) / sum(g_i^2)`` is the CEL-consistent intercept at
       ``a = 0``. (``kappa_extrapolation="poly2"`` instead takes the intercept of a
       quadratic in ``a`` fitted over the window; it ignores the CEL's ``a^(1-mu)``
       curvature and is offered only as a cross-check.)

``"joint"``
    Nonlinear least squares of all three constants on ``log a`` versus ``p0``
    (``scipy.optimize.least_squares``, analytic Jacobian); log residuals because the
    seed scatter of ``a`` is multiplicative and the window spans a decade.

Uncertainties: ``stderr`` is each estimator's own asymptotic standard error (OLS
covariance for the paper route, with ``kappa``'s conditional on ``mu, beta``;
``s^2 (J^T J)^-1`` for the joint fit). Points along one load curve are correlated,
so these understate the scatter between surfaces; ``bootstrap_stderr`` and the 95 %
percentile interval ``[ci_low, ci_high]`` come from resampling whole seeds with
replacement (stratified by H for the H-pooled fit) and refitting. The bootstrap
standard deviation is multiplied by ``sqrt(n / (n - 1))`` (``n`` seeds per H stratum),
the factor by which the bootstrap variance of a mean over ``n`` clusters falls short of
the unbiased one; the percentile interval is left as drawn. Groups with a single seed
per stratum get no bootstrap (NaN, ``n_boot_ok = 0``): one surface says nothing about
the scatter between surfaces.

Behaviour on synthetic CEL data (tests/test_fit.py and ``simulate_cel_cases`` in tests/cel_synthetic.py),
12 seeds x 30 steps: with independent 0.1 % noise on ``A/A0`` both estimators land within
2 bootstrap standard errors of the truth in 90-97 % of draws, and the joint fit's
Jacobian error matches the actual scatter. The paper route keeps a small bias from
differentiating ``pbar`` (``mu`` about +0.002 on 30 steps, see
:func:`roughcontact.analysis.aggregate.load_derivative`). When the seeds differ in the *shape*
of their curves (constants scattered by 1-3 % per seed), the H-pooled joint fit is
pulled by the mixture (``kappa, mu, beta`` off by about 1.4, 1.7, 5 % at 3 %
scatter) while the paper route stays within 0.4 %; prefer ``"paper"`` as the primary
estimate and read ``"joint"`` as a cross-check.

Measured scenes (aggregate dims ``(topography, step)``, one case per topography file) are fitted
by :func:`~roughcontact.analysis.fit.topographies.fit_topographies`: all topographies pooled as one
surface type, the topographies in the place of the seeds (topography-mean curve for the paper route,
bootstrap over whole topographies), with the same per-group machinery as
:func:`~roughcontact.analysis.fit.grid.fit_cel` (``bootstrap.fit_group``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import least_squares

from ...theory.laws import KAPPA_BGT

#: The constants of the CEL, in the order of the ``constant`` coordinate.
CONSTANTS = ("kappa", "mu", "beta")


#: Estimators implemented by :func:`fit_cel`.
METHODS = ("paper", "joint")


#: The paper's values (value, stated uncertainty) for lambda_l = L/16, lambda_s = L/32:
#: kappa = (1.145 +- 0.002) sqrt(2 pi), mu = 0.55 +- 0.02, beta = 0.210 +- 0.005.
PAPER_CEL = {
    "kappa": (1.145 * KAPPA_BGT, 0.002 * KAPPA_BGT),
    "mu": (0.55, 0.02),
    "beta": (0.210, 0.005),
}


#: Label of the H-pooled group on the ``H_group`` coordinate.
POOLED = "pooled"


KAPPA_EXTRAPOLATIONS = ("cel", "poly2")


# -------------------------------------------------------------------- group data
class Curves:
    """Load curves of one fit group, one row per seed (bootstrap picks rows)."""

    def __init__(self, a, p0, hp, kappa, dpbar, valid, strata, window):
        self.a, self.p0, self.hp, self.kappa, self.dpbar = a, p0, hp, kappa, dpbar
        self.valid = valid  # converged step with a finite area fraction
        self.strata = strata  # one integer label per row: its H, for stratified resampling
        self.window = window
        self.ok = valid & (a >= window[0]) & (a <= window[1])

    def take(self, rows: np.ndarray) -> Curves:
        return Curves(self.a[rows], self.p0[rows], self.hp[rows], self.kappa[rows],
                       self.dpbar[rows], self.valid[rows], self.strata[rows], self.window)

    def stratum_means(self) -> Curves:
        """One row per H stratum: the seed-mean curve (steps valid in every seed)."""
        labels = np.unique(self.strata)
        rows = [np.flatnonzero(self.strata == lab) for lab in labels]
        valid = np.array([self.valid[r].all(axis=0) for r in rows])

        def mean(x):
            with np.errstate(invalid="ignore"):
                return np.array([np.where(v, x[r].mean(axis=0), np.nan) for r, v in zip(rows, valid, strict=True)])

        return Curves(mean(self.a), mean(self.p0), np.array([self.hp[r].mean() for r in rows]),
                       mean(self.kappa), mean(self.dpbar), valid, labels, self.window)

    @property
    def n_seeds(self) -> int:
        return self.a.shape[0]


# ---------------------------------------------------------------------- estimators
class FitError(ValueError):
    """A fit could not be carried out on the given points (too few, degenerate)."""


class TooFewPoints(FitError):
    """Fewer usable points in the fit window than the fit needs (``min_points``)."""


def fit_paper(c: Curves, min_points: int, extrapolation: str, average: bool):
    """Paper route. Returns (values, stderrs, n_points) as arrays over CONSTANTS."""
    if average:
        c = c.stratum_means()
    sel = c.ok & np.isfinite(c.dpbar) & (c.dpbar > 0)
    n_mb = int(sel.sum())
    if n_mb < min_points:
        raise TooFewPoints(f"{n_mb} points with d pbar/d p0 > 0 in the window (need >= {min_points})")
    x = np.log(c.a[sel])
    y = np.log(c.dpbar[sel])
    X = np.column_stack([np.ones_like(x), -x])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    resid = y - X @ coef
    s2 = float(resid @ resid) / max(n_mb - 2, 1)
    cov = s2 * np.linalg.pinv(X.T @ X)
    log_beta, mu = coef
    beta = math.exp(log_beta)
    se_mu = math.sqrt(max(cov[1, 1], 0.0))
    se_beta = beta * math.sqrt(max(cov[0, 0], 0.0))  # delta method on beta = exp(c0)

    selk = c.ok & np.isfinite(c.kappa)
    n_k = int(selk.sum())
    if n_k < min_points:
        raise TooFewPoints(f"{n_k} finite kappa points in the window (need >= {min_points})")
    ak, yk = c.a[selk], c.kappa[selk]
    if extrapolation == "cel":
        if not (0.0 < mu < 1.0):
            raise FitError(f"log-log fit gave mu={mu:.4g} outside (0, 1); the CEL form does not apply")
        base = 1.0 - beta * ak ** (1.0 - mu)
        if np.any(base <= 0):
            raise FitError("beta a^(1-mu) >= 1 inside the window: the CEL cannot describe these data")
        g = base ** (1.0 / (1.0 - mu))
        kappa = float(g @ yk / (g @ g))
        rk = yk - kappa * g
        se_kappa = math.sqrt(float(rk @ rk) / max(n_k - 1, 1) / float(g @ g))
    else:
        Xk = np.column_stack([np.ones_like(ak), ak, ak**2])
        ck, *_ = np.linalg.lstsq(Xk, yk, rcond=None)
        rk = yk - Xk @ ck
        covk = float(rk @ rk) / max(n_k - 3, 1) * np.linalg.pinv(Xk.T @ Xk)
        kappa, se_kappa = float(ck[0]), math.sqrt(max(covk[0, 0], 0.0))
    return (np.array([kappa, mu, beta]), np.array([se_kappa, se_mu, se_beta]),
            np.array([n_k, n_mb, n_mb]))


def _log_cel(theta, x0):
    """log a of the CEL and its Jacobian; ``x0 = p0 / (h' E*)``."""
    kappa, mu, beta = theta
    u = 1.0 - mu
    x = kappa * x0
    logx = np.log(x)
    s = np.exp(u * logx)
    D = 1.0 + beta * s
    logD = np.log(D)
    f = logx - logD / u
    J = np.empty((x0.size, 3))
    J[:, 0] = 1.0 / (kappa * D)
    J[:, 1] = -logD / u**2 + beta * s * logx / (u * D)
    J[:, 2] = -s / (u * D)
    return f, J


JOINT_LOWER = np.array([1e-6, 1e-6, 1e-12])


JOINT_UPPER = np.array([np.inf, 1.0 - 1e-6, np.inf])


def fit_joint(c: Curves, e_star: float, min_points: int, x0_guess: np.ndarray):
    """The joint fit: nonlinear least squares of the CEL to ``log A/A0`` over every curve in the window.

    Returns the constants; raises :class:`TooFewPoints` when fewer than ``max(min_points, 4)`` points are in it."""
    sel = c.ok & np.isfinite(c.p0) & (c.p0 > 0)
    n = int(sel.sum())
    if n < max(min_points, 4):
        raise TooFewPoints(f"{n} points in the window (need >= {max(min_points, 4)})")
    xs = (c.p0 / (c.hp[:, None] * e_star))[sel]
    la = np.log(c.a[sel])
    guess = np.clip(np.asarray(x0_guess, float), JOINT_LOWER * 10, np.where(
        np.isfinite(JOINT_UPPER), JOINT_UPPER - 1e-3, np.inf))

    def fun(th):
        return _log_cel(th, xs)[0] - la

    def jac(th):
        return _log_cel(th, xs)[1]

    res = least_squares(fun, guess, jac=jac, bounds=(JOINT_LOWER, JOINT_UPPER),
                        x_scale="jac", method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    if not res.success or not np.all(np.isfinite(res.x)):
        raise FitError(f"least_squares did not converge: {res.message}")
    J = res.jac
    s2 = 2.0 * res.cost / max(n - 3, 1)
    cov = s2 * np.linalg.pinv(J.T @ J)
    return res.x.copy(), np.sqrt(np.clip(np.diag(cov), 0.0, None)), np.array([n, n, n])


#: Distance to a bound of the joint fit, relative to ``max(1, |bound|)``, within which a constant
#: sits on it (scipy's rule for an active bound, looser than its 1e-10).
BOUND_RTOL = 1e-6


def at_bound(estimator: str, constant: str, value: float) -> bool:
    """Whether a fitted constant sits on a bound of its estimator: only the joint least squares has
    bounds (:data:`JOINT_LOWER`, :data:`JOINT_UPPER`); there the bootstrap draws pile up on the
    bound and the interval shrinks to nothing, so the data do not constrain the constant."""
    if estimator != "joint":
        return False
    i = CONSTANTS.index(constant)
    return any(np.isfinite(b) and abs(float(value) - b) <= BOUND_RTOL * max(1.0, abs(b))
               for b in (float(JOINT_LOWER[i]), float(JOINT_UPPER[i])))


#: Distance between an end of the bootstrap interval and the estimate, relative to the larger of the two,
#: within which the end touches the estimate. The percentile bootstrap returns the estimate itself when the
#: fit sits on the edge of its resamples: a resample of the same seeds (in another order) refits to the same
#: number, to the reproducibility of the fit: about 1e-15 relative for the paper route's least squares, but up
#: to a few 1e-6 for the joint fit where it is ill-conditioned (measured: kappa = 102.00116 with standard error
#: 4045 on two generated profiles, whose every fitting resample was the two seeds again, gave the interval
#: [102.00123, 102.00144]). An interval that the scatter between surfaces sets lies much farther from its
#: estimate: the paper's tightest constant, kappa, is known to 0.2 %. A degenerate interval, narrower than
#: this relative to the value, touches its estimate too.
TOUCH_RTOL = 1e-5

#: When the data do not constrain a fitted constant: the rule :func:`constrained_flags` follows, as the fit
#: dataset's ``constrained`` variable, the fit's log and the report print it (besides a missing interval).
UNCONSTRAINED_RULE = ("the bootstrap interval is wider than the value, does not hold the value strictly inside "
                      f"it (an end at the value, within {TOUCH_RTOL:g} relative, or beyond it), or the value or "
                      "an end of the interval lies on a bound of the fit")


def _touches(end: np.ndarray, value: np.ndarray) -> np.ndarray:
    """Whether ``end`` equals ``value`` to :data:`TOUCH_RTOL` of the larger magnitude."""
    return np.abs(end - value) <= TOUCH_RTOL * np.maximum(np.abs(end), np.abs(value))


def constrained_flags(value, ci_low, ci_high, estimators: Sequence[str] | None = None) -> np.ndarray:
    """1 where the data constrain a fitted constant, else 0 (int8).

    A constant is not constrained when the bootstrap interval is wider than the value, does not hold
    the value strictly inside it (an end at the value, within 1e-05 relative, or beyond it), or the value or
    an end of the interval lies on a bound of the fit; or when it has no interval (a NaN end or value).
    Such a constant is not determined by the data and must not be reported as a number: kappa = 4.79 in
    [3.1, 6368] (wider than itself); beta = 1.87 in [0.18, 1.87] (the percentile interval ends on the
    estimate: the fit sits on the edge of its resamples, and the data do not bound it on that side).
    The wording is :data:`UNCONSTRAINED_RULE`'s, with :data:`TOUCH_RTOL`; a bound is one of the joint
    fit's (:func:`at_bound`; the paper's route has none).

    Parameters
    ----------
    value, ci_low, ci_high : array_like
        The fitted constants and the ends of their bootstrap intervals, of one shape.
    estimators : sequence of str, optional
        The estimator of each index along the second-last axis (the constants along the last, in
        :data:`CONSTANTS` order): needed for the bounds, which are checked only where given.

    Returns
    -------
    numpy.ndarray
        int8 of the shape of ``value``: 1 constrained, 0 not.

    Examples
    --------
    >>> constrained_flags([4.79, 2.87, 1.87413], [3.1, 2.80, 0.181539], [6368, 2.95, 1.87413]).tolist()
    [0, 1, 0]
    """
    value, lo, hi = (np.asarray(x, dtype=float) for x in (value, ci_low, ci_high))
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(value) & np.isfinite(lo) & np.isfinite(hi) & ((hi - lo) < np.abs(value))
        ok &= (lo < value) & (value < hi) & ~_touches(lo, value) & ~_touches(hi, value)
    if estimators is not None:
        for idx in np.ndindex(value.shape):
            if ok[idx]:
                ok[idx] = not any(at_bound(estimators[idx[-2]], CONSTANTS[idx[-1]], x[idx]) for x in (value, lo, hi))
    return ok.astype(np.int8)
