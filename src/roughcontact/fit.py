"""Fitting the contact evolution law (CEL) to aggregated contact data.

The CEL (Yastrebov, Anciaux & Molinari 2012, Eq. 2) is
``a = A/A0 = (beta + [kappa p0 / (h' E*)]^(mu-1))^(1/(mu-1))``; it integrates
``d pbar / d p0 = beta a^(-mu)`` from the linear law ``a = kappa p0 / (h' E*)``.
Two estimators are offered, both restricted to a window of contact fraction
(the paper's ``a in [0.01, 0.11]``) and to converged load steps:

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

Behaviour on synthetic CEL data (tests/test_fit.py and :func:`simulate_cel_cases`), 12
seeds x 30 steps: with independent 0.1 % noise on ``A/A0`` both estimators land within
2 bootstrap standard errors of the truth in 90-97 % of draws, and the joint fit's
Jacobian error matches the actual scatter. The paper route keeps a small bias from
differentiating ``pbar`` (``mu`` about +0.002 on 30 steps, see
:func:`roughcontact.aggregate.load_derivative`). When the seeds differ in the *shape*
of their curves (constants scattered by 1-3 % per seed), the H-pooled joint fit is
pulled by the mixture (``kappa, mu, beta`` off by about 1.4, 1.7, 5 % at 3 %
scatter) while the paper route stays within 0.4 %; prefer ``"paper"`` as the primary
estimate and read ``"joint"`` as a cross-check.

Measured scenes (aggregate dims ``(topography, step)``, one case per topography file) are fitted
by :func:`fit_topographies`: all topographies pooled as one surface type, the topographies in
the place of the seeds (topography-mean curve for the paper route, bootstrap over whole
topographies). It runs the same per-group machinery as :func:`fit_cel` (``_fit_group``).
"""

from __future__ import annotations

import hashlib
import io
import math
from collections.abc import Sequence

import numpy as np
import xarray as xr
from scipy.optimize import least_squares

from .aggregate import CASE_DIMS, TOPOGRAPHY_DIM, add_derived
from .theory import KAPPA_BGT, cel_area, cel_pressure, power_law_alpha

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

_KAPPA_EXTRAPOLATIONS = ("cel", "poly2")


# -------------------------------------------------------------------- group data
class _Curves:
    """Load curves of one fit group, one row per seed (bootstrap picks rows)."""

    def __init__(self, a, p0, hp, kappa, dpbar, valid, strata, window):
        self.a, self.p0, self.hp, self.kappa, self.dpbar = a, p0, hp, kappa, dpbar
        self.valid = valid  # converged step with a finite area fraction
        self.strata = strata  # one integer label per row: its H, for stratified resampling
        self.window = window
        self.ok = valid & (a >= window[0]) & (a <= window[1])

    def take(self, rows: np.ndarray) -> _Curves:
        return _Curves(self.a[rows], self.p0[rows], self.hp[rows], self.kappa[rows],
                       self.dpbar[rows], self.valid[rows], self.strata[rows], self.window)

    def stratum_means(self) -> _Curves:
        """One row per H stratum: the seed-mean curve (steps valid in every seed)."""
        labels = np.unique(self.strata)
        rows = [np.flatnonzero(self.strata == lab) for lab in labels]
        valid = np.array([self.valid[r].all(axis=0) for r in rows])

        def mean(x):
            with np.errstate(invalid="ignore"):
                return np.array([np.where(v, x[r].mean(axis=0), np.nan) for r, v in zip(rows, valid, strict=True)])

        return _Curves(mean(self.a), mean(self.p0), np.array([self.hp[r].mean() for r in rows]),
                       mean(self.kappa), mean(self.dpbar), valid, labels, self.window)

    @property
    def n_seeds(self) -> int:
        return self.a.shape[0]


def _group_curves(agg: xr.Dataset, k_l: float, k_s: float, hs: Sequence[float],
                  window: tuple[float, float]) -> _Curves:
    rows = []
    for j, h in enumerate(hs):
        sub = agg.sel(k_l=k_l, k_s=k_s, H=h)
        present = sub["case_present"].values if "case_present" in sub else np.ones(sub.sizes["seed"], bool)
        for s in np.flatnonzero(present):
            case = sub.isel(seed=s)
            a = case["area_fraction"].transpose("step").values.astype(float)
            conv = case["converged"].transpose("step").values.astype(bool)
            row = (a,
                   case["pressure"].transpose("step").values.astype(float),
                   float(case["rms_slope"].values),
                   case["kappa"].transpose("step").values.astype(float),
                   case["dpbar_dp0"].transpose("step").values.astype(float),
                   conv & np.isfinite(a),
                   j)
            rows.append(row)
    if not rows:
        n = agg.sizes["step"]
        empty = np.empty((0, n))
        return _Curves(empty, empty, np.empty(0), empty, empty, np.empty((0, n), bool),
                       np.empty(0, int), window)
    cols = list(zip(*rows, strict=True))
    return _Curves(np.array(cols[0]), np.array(cols[1]), np.array(cols[2]), np.array(cols[3]),
                   np.array(cols[4]), np.array(cols[5]), np.array(cols[6], dtype=int), window)


# ---------------------------------------------------------------------- estimators
class FitError(ValueError):
    """A fit could not be carried out on the given points (too few, degenerate)."""


def _fit_paper(c: _Curves, min_points: int, extrapolation: str, average: bool):
    """Paper route. Returns (values, stderrs, n_points) as arrays over CONSTANTS."""
    if average:
        c = c.stratum_means()
    sel = c.ok & np.isfinite(c.dpbar) & (c.dpbar > 0)
    n_mb = int(sel.sum())
    if n_mb < min_points:
        raise FitError(f"{n_mb} points with d pbar/d p0 > 0 in the window (need >= {min_points})")
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
        raise FitError(f"{n_k} finite kappa points in the window (need >= {min_points})")
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


def _fit_joint(c: _Curves, e_star: float, min_points: int, x0_guess: np.ndarray):
    sel = c.ok & np.isfinite(c.p0) & (c.p0 > 0)
    n = int(sel.sum())
    if n < max(min_points, 4):
        raise FitError(f"{n} points in the window (need >= {max(min_points, 4)})")
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


def _resample(c: _Curves, rng: np.random.Generator) -> np.ndarray:
    """Seed indices drawn with replacement within each H stratum."""
    rows = []
    for label in np.unique(c.strata):
        idx = np.flatnonzero(c.strata == label)
        rows.append(idx[rng.integers(0, idx.size, idx.size)])
    return np.concatenate(rows)


def _group_rng(rng_seed: int, k_l: float, k_s: float, label: str) -> np.random.Generator:
    # Keyed by the group, so a group's resamples do not depend on which other groups exist.
    key = f"{float(k_l)!r}|{float(k_s)!r}|{label}".encode()
    digest = int.from_bytes(hashlib.sha256(key).digest()[:8], "little")
    return np.random.default_rng(np.random.SeedSequence(entropy=int(rng_seed), spawn_key=(digest,)))


def _check_window(window) -> tuple[float, float]:
    try:
        lo, hi = (float(w) for w in window)
    except (TypeError, ValueError):
        raise ValueError(f"window must be a pair (low, high) of area fractions, got {window!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi)) or not (0.0 < lo < hi <= 1.0):
        raise ValueError(f"window must satisfy 0 < low < high <= 1 (area fractions A/A0), got {window!r}")
    return lo, hi


def _h_label(h: float) -> str:
    return f"{float(h):g}"


def _check_settings(window, n_boot, rng_seed, methods, min_points, kappa_extrapolation, confidence,
                    paper_average, on_insufficient) -> tuple[tuple[float, float], tuple[str, ...]]:
    """The validated window ``(low, high)`` and methods; ValueError naming the first bad setting."""
    lo, hi = _check_window(window)
    if not isinstance(n_boot, (int, np.integer)) or n_boot < 10:
        raise ValueError(f"n_boot must be an integer >= 10, got {n_boot!r}")
    if not isinstance(rng_seed, (int, np.integer)) or rng_seed < 0:
        raise ValueError(f"rng_seed must be an integer >= 0, got {rng_seed!r}")
    methods = tuple(methods)
    if not methods or any(m not in METHODS for m in methods) or len(set(methods)) != len(methods):
        raise ValueError(f"methods must be distinct names from {METHODS}, got {methods!r}")
    if not isinstance(min_points, (int, np.integer)) or min_points < 3:
        raise ValueError(f"min_points must be an integer >= 3, got {min_points!r}")
    if kappa_extrapolation not in _KAPPA_EXTRAPOLATIONS:
        raise ValueError(f"kappa_extrapolation must be one of {_KAPPA_EXTRAPOLATIONS}, got "
                         f"{kappa_extrapolation!r}")
    if not (0.0 < float(confidence) < 1.0):
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
    if paper_average not in ("seeds", "none"):
        raise ValueError(f"paper_average must be 'seeds' or 'none', got {paper_average!r}")
    if on_insufficient not in ("raise", "nan"):
        raise ValueError(f"on_insufficient must be 'raise' or 'nan', got {on_insufficient!r}")
    return (lo, hi), methods


def _differing_stratum(curves: _Curves):
    """The first stratum whose rows have different normalised load schedules ``p0 / (E* h')``, or None.

    That schedule is what the CEL is a function of: surfaces of different rms slope loaded
    relative to it (``load.relative_to: rms_slope``) share it, as seeds of one generated surface
    type share ``p0``.
    """
    normalised = curves.p0 / curves.hp[:, None]
    for lab in np.unique(curves.strata):
        sched = normalised[curves.strata == lab]
        if not np.allclose(sched, sched[0], rtol=1e-12, atol=0.0, equal_nan=True):
            return lab
    return None


def _shared_schedule(curves: _Curves) -> bool:
    """Whether every stratum of ``curves`` has one normalised load schedule (see :func:`_differing_stratum`)."""
    return _differing_stratum(curves) is None


def _check_schedules(curves: _Curves, who: Sequence[str]) -> None:
    """ValueError unless the rows of each stratum share one load schedule (the seed mean needs it).

    ``who[label]`` names the rows of stratum ``label`` in the message.
    """
    lab = _differing_stratum(curves)
    if lab is not None:
        raise ValueError(f"{who[lab]} have different load schedules p0/(E* h'), so their curves cannot be "
                         "averaged step by step; pass paper_average='none' or load them alike "
                         "(load.relative_to: rms_slope)")


class _GroupFit:
    """One group's results: arrays over ``(estimator, constant)``, ``n_boot_ok`` over ``estimator``."""

    def __init__(self, n_methods: int):
        shape = (n_methods, len(CONSTANTS))
        self.value, self.stderr, self.bstd, self.clo, self.chi = (np.full(shape, np.nan) for _ in range(5))
        self.npts = np.zeros(shape, dtype=np.int64)
        self.nboot_ok = np.zeros(n_methods, dtype=np.int64)


def _fit_group(curves: _Curves, *, methods: Sequence[str], e_star: float, min_points: int,
               kappa_extrapolation: str, paper_average: str, n_boot: int, confidence: float,
               rng: np.random.Generator, on_insufficient: str, caller: str, where: str, window) -> _GroupFit:
    """Every estimator on one group's curves, then the bootstrap over its rows (seeds, topographies).

    The machinery shared by :func:`fit_cel` (one call per group) and :func:`fit_topographies`
    (one call for all topographies). ``rng`` draws the resamples; ``caller``, ``where`` and
    ``window`` (as the user passed it) name the group in errors.
    """
    out = _GroupFit(len(methods))
    q = 100.0 * (1.0 - float(confidence)) / 2.0

    def run(method, c, guess):
        if method == "paper":
            return _fit_paper(c, min_points, kappa_extrapolation, paper_average == "seeds")
        return _fit_joint(c, e_star, min_points, guess)

    full = {}
    for m, method in enumerate(methods):
        guess = np.array([PAPER_CEL[c][0] for c in CONSTANTS])
        if method == "joint" and "paper" in full:
            # The paper route is a good, cheap starting point when it is sane.
            pv = full["paper"][0]
            if np.all(np.isfinite(pv)) and 0 < pv[1] < 1 and pv[0] > 0 and pv[2] > 0:
                guess = pv
        try:
            full[method] = run(method, curves, guess)
        except FitError as err:
            if on_insufficient == "raise":
                raise ValueError(
                    f"{caller} ({method}) at {where} with window={window!r}: {err}; "
                    "widen `window`, add load steps, or pass on_insufficient='nan'"
                ) from None
            continue
        out.value[m], out.stderr[m], out.npts[m] = full[method]

    # A stratum with one seed has no seed-to-seed information: the bootstrap
    # would report zero scatter, so it is skipped (NaN, n_boot_ok = 0).
    n_min = min(np.bincount(curves.strata)[np.unique(curves.strata)]) if curves.n_seeds else 0
    if n_min < 2:
        return out
    # The bootstrap variance of a mean over n clusters is (n-1)/n times the
    # unbiased one; rescaling by n/(n-1) matters with the paper's 12 seeds.
    inflate = math.sqrt(n_min / (n_min - 1.0))
    boot = {method: np.full((n_boot, 3), np.nan) for method in full}
    for b in range(n_boot):
        sample = curves.take(_resample(curves, rng))
        for method in full:
            try:
                boot[method][b] = run(method, sample, full[method][0])[0]
            except (FitError, np.linalg.LinAlgError):
                pass  # counted through n_boot_ok
    for m, method in enumerate(methods):
        if method not in boot:
            continue
        draws = boot[method][np.all(np.isfinite(boot[method]), axis=1)]
        out.nboot_ok[m] = draws.shape[0]
        if draws.shape[0] >= 2:
            out.bstd[m] = inflate * draws.std(axis=0, ddof=1)
            out.clo[m] = np.percentile(draws, q, axis=0)
            out.chi[m] = np.percentile(draws, 100.0 - q, axis=0)
    return out


def _estimate_vars(dims: tuple[str, ...], value, stderr, bstd, clo, chi, npts, *, confidence: float,
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


def _paper_vars() -> dict:
    one = {"units": "1"}
    return {
        "paper_value": (("constant",), np.array([PAPER_CEL[c][0] for c in CONSTANTS]),
                        {**one, "long_name": "Yastrebov et al. (2012) value, k_l=16, k_s=32"}),
        "paper_stderr": (("constant",), np.array([PAPER_CEL[c][1] for c in CONSTANTS]),
                         {**one, "long_name": "Yastrebov et al. (2012) stated uncertainty"}),
    }


def _estimator_coords(methods: Sequence[str]) -> dict:
    return {
        "estimator": ("estimator", np.array(methods, dtype=object),
                      {"units": "1", "long_name": "estimator: 'paper' (log-log d pbar/d p0 + kappa extrapolation) "
                                                  "or 'joint' (nonlinear least squares on A/A0(p0))"}),
        "constant": ("constant", np.array(CONSTANTS, dtype=object), {"units": "1", "long_name": "CEL constant"}),
    }


def _settings_attrs(lo, hi, n_boot, rng_seed, confidence, min_points, kappa_extrapolation, paper_average,
                    e_star) -> dict:
    return {
        "window_low": lo, "window_high": hi, "n_boot": int(n_boot), "rng_seed": int(rng_seed),
        "confidence": float(confidence), "min_points": int(min_points),
        "kappa_extrapolation": kappa_extrapolation, "paper_average": paper_average,
        "e_star": e_star,
        "description": "Contact evolution law A/A0 = (beta + [kappa p0/(h' E*)]^(mu-1))^(1/(mu-1))",
    }


# --------------------------------------------------------------------------- public
def _is_topography_layout(agg: xr.Dataset) -> bool:
    return TOPOGRAPHY_DIM in agg.dims


def exclude_unconverged(agg: xr.Dataset) -> tuple[xr.Dataset, list[tuple[float, float, float, int]] | list[str]]:
    """``agg`` with every case that has an unconverged step marked absent, and those cases.

    Only ``case_present`` changes, so the other cases of a group (their pressures, load
    schedules, seeds) enter the fit untouched. Cases are ``(k_l, k_s, H, seed)`` for a
    generated scene; for a measured one (dims ``(topography, step)``) they are the
    topographies' names, and ``n_unconverged`` is counted from ``converged`` if absent.
    """
    if _is_topography_layout(agg):
        return _exclude_unconverged_topographies(agg)
    if "n_unconverged" not in agg:
        return agg, []
    present = agg["case_present"] if "case_present" in agg else xr.ones_like(agg["n_unconverged"], dtype=bool)
    bad = present & (agg["n_unconverged"] > 0)
    excluded = [tuple(float(v) if d != "seed" else int(v) for d, v in zip(bad.dims, idx, strict=True))
                for idx in bad.to_series()[bad.to_series()].index]
    out = agg.copy()
    out["case_present"] = (present & ~bad).assign_attrs(present.attrs or {
        "units": "1", "long_name": "a dataset exists for this case (False: grid hole, not expected)"})
    return out, excluded


def _exclude_unconverged_topographies(agg: xr.Dataset) -> tuple[xr.Dataset, list[str]]:
    if "n_unconverged" in agg:
        n_unc = agg["n_unconverged"]
    elif "converged" in agg:
        n_unc = (~agg["converged"].astype(bool)).sum("step")
    else:
        return agg, []
    present = agg["case_present"].astype(bool) if "case_present" in agg else xr.ones_like(n_unc, dtype=bool)
    bad = present & (n_unc > 0)
    excluded = [str(name) for name in agg[TOPOGRAPHY_DIM].values[bad.transpose(TOPOGRAPHY_DIM).values]]
    out = agg.copy()
    out["case_present"] = (present & ~bad).assign_attrs(dict(present.attrs) or {
        "units": "1", "long_name": "the topography enters the fit (False: excluded, e.g. for unconverged steps)"})
    return out, excluded


def fit_cel(agg: xr.Dataset, *, window: tuple[float, float] = (0.01, 0.11), n_boot: int = 200,
            rng_seed: int = 2012, methods: Sequence[str] = METHODS, min_points: int = 6,
            kappa_extrapolation: str = "cel", paper_average: str = "seeds",
            confidence: float = 0.95, on_insufficient: str = "raise") -> xr.Dataset:
    """Fit the CEL constants per ``(k_l, k_s, H)`` and per ``(k_l, k_s)`` pooled over H.

    Parameters
    ----------
    agg : xarray.Dataset
        Combined contact dataset (:func:`roughcontact.aggregate.combine_cases`), dims
        ``(k_l, k_s, H, seed, step)``, global attr ``e_star``; ``kappa`` and
        ``dpbar_dp0`` are derived if absent.
    window : (float, float)
        Contact-fraction window ``low <= A/A0 <= high``, ``0 < low < high <= 1``. Only
        converged steps inside it enter any fit.
    n_boot : int
        Bootstrap resamples over seeds (>= 10; the paper-level analysis uses >= 200).
    rng_seed : int
        Seed (>= 0) of the bootstrap; each group's stream also depends on the group.
    methods : sequence of {"paper", "joint"}
        Estimators to run (see the module docstring).
    min_points : int
        Fewest in-window points a fit accepts (>= 3; the joint fit needs >= 4).
    kappa_extrapolation : {"cel", "poly2"}
        How the paper route extrapolates ``kappa_eff(a)`` to ``a = 0``.
    paper_average : {"seeds", "none"}
        ``"seeds"`` (default): the paper route fits the seed-mean curve of each H (mean
        ``A/A0``, ``kappa``, ``d pbar/d p0`` per load step, steps converged in every
        seed; the window applies to the mean ``A/A0``), which needs one load schedule
        per H. Averaging before taking logs matters: the log of a noisy finite
        difference is biased low by about half its relative variance, and that variance
        grows with ``A/A0``, which tilts ``mu``. ``"none"``: every (seed, step) point.
    confidence : float
        Coverage of the percentile interval, in (0, 1).
    on_insufficient : {"raise", "nan"}
        A group with cases but too few in-window points: raise ValueError (default)
        naming the group and the window, or leave its values NaN.

    Returns
    -------
    xarray.Dataset
        Dims ``k_l, k_s, H_group`` (one label per H, e.g. ``"0.36"``, then ``"pooled"``;
        float coordinate ``H_value`` along it, NaN for pooled), ``estimator`` (the
        ``methods`` run; not called "method", which ``xarray``'s ``.sel`` reserves), ``constant``
        (``kappa, mu, beta``). Variables, all with units "1":
        ``value``, ``stderr`` (the estimator's own), ``bootstrap_stderr``, ``ci_low``,
        ``ci_high`` (percentile interval), ``n_points(k_l, k_s, H_group, estimator, constant)``,
        ``n_seeds(k_l, k_s, H_group)``, ``n_boot_ok(k_l, k_s, H_group, estimator)``,
        ``alpha_power_law(k_l, k_s, H_group)`` (Nayak alpha of the ideal spectrum, NaN
        when pooled), ``alpha_surfaces(k_l, k_s, H_group)`` (mean of ``agg.alpha`` over the
        group's cases), ``paper_value(constant)``, ``paper_stderr(constant)``. Groups
        without any case are NaN with ``n_seeds = 0``. Attrs record the settings.
    """
    (lo, hi), methods = _check_settings(window, n_boot, rng_seed, methods, min_points, kappa_extrapolation,
                                        confidence, paper_average, on_insufficient)
    for dim in CASE_DIMS + ("step",):
        if dim not in agg.dims:
            raise ValueError(f"agg lacks dimension {dim!r}; pass the output of combine_cases")
    if "dpbar_dp0" not in agg or "kappa" not in agg:
        agg = add_derived(agg)
    e_star = float(agg.attrs["e_star"])

    kls, kss, hs = (agg[d].values for d in ("k_l", "k_s", "H"))
    labels = [_h_label(h) for h in hs] + [POOLED]
    grid = _CelGrid((len(kls), len(kss), len(labels), len(methods), len(CONSTANTS)))
    fit_kw = dict(methods=methods, e_star=e_star, min_points=min_points, kappa_extrapolation=kappa_extrapolation,
                  paper_average=paper_average, n_boot=n_boot, confidence=confidence,
                  on_insufficient=on_insufficient, window=window)
    for i, kl in enumerate(kls):
        for j, ks in enumerate(kss):
            for g, label in enumerate(labels):
                group_hs = list(hs) if label == POOLED else [hs[g]]
                _fit_cel_group(agg, grid, (i, j, g), kl, ks, group_hs, label, (lo, hi), rng_seed, fit_kw)
    return _cel_dataset(agg, grid, labels, methods, confidence,
                        _settings_attrs(lo, hi, n_boot, rng_seed, confidence, min_points, kappa_extrapolation,
                                        paper_average, e_star))


class _CelGrid:
    """:func:`fit_cel`'s result arrays, filled group by group.

    ``value, stderr, bstd, clo, chi`` (float, NaN: not fitted) and ``npts`` (int) have the
    shape ``(k_l, k_s, H_group, estimator, constant)``; ``nboot_ok`` the first four of those
    dims; ``nseeds`` (int), ``alpha`` and ``alpha_surf`` (float, NaN: none) the first three.
    """

    def __init__(self, shape5: tuple[int, int, int, int, int]):
        self.value, self.stderr, self.bstd, self.clo, self.chi = (np.full(shape5, np.nan) for _ in range(5))
        self.npts = np.zeros(shape5, dtype=np.int64)
        self.nseeds = np.zeros(shape5[:3], dtype=np.int64)
        self.nboot_ok = np.zeros(shape5[:4], dtype=np.int64)
        self.alpha = np.full(shape5[:3], np.nan)
        self.alpha_surf = np.full(shape5[:3], np.nan)

    def store(self, idx: tuple[int, int, int], res: _GroupFit) -> None:
        """Copy one group's fit into position ``idx = (i_k_l, i_k_s, i_H_group)``."""
        self.value[idx], self.stderr[idx], self.npts[idx] = res.value, res.stderr, res.npts
        self.bstd[idx], self.clo[idx], self.chi[idx] = res.bstd, res.clo, res.chi
        self.nboot_ok[idx] = res.nboot_ok


def _fit_cel_group(agg: xr.Dataset, grid: _CelGrid, idx: tuple[int, int, int], kl: float, ks: float,
                   group_hs: list[float], label: str, bounds: tuple[float, float], rng_seed: int,
                   fit_kw: dict) -> None:
    """Fit the group ``(kl, ks, group_hs)`` (H label ``label``) of ``agg`` into ``grid[idx]``.

    ``bounds`` is the checked window ``(low, high)`` of ``A/A0``; ``fit_kw`` holds
    :func:`_fit_group`'s settings (with the window as the user passed it, for messages). A group without cases only gets
    ``n_seeds = 0``.
    """
    curves = _group_curves(agg, kl, ks, group_hs, bounds)
    grid.nseeds[idx] = curves.n_seeds
    if curves.n_seeds == 0:
        return
    if fit_kw["paper_average"] == "seeds" and "paper" in fit_kw["methods"]:
        _check_schedules(curves, [f"fit_cel: seeds at k_l={kl:g}, k_s={ks:g}, H={_h_label(h)}"
                                  for h in group_hs])
    if label != POOLED and kl < ks:
        grid.alpha[idx] = power_law_alpha(kl, ks, group_hs[0])
    if "alpha" in agg:
        grid.alpha_surf[idx] = _mean_alpha_surfaces(agg, kl, ks, group_hs)
    res = _fit_group(curves, rng=_group_rng(rng_seed, kl, ks, label), caller="fit_cel",
                     where=f"k_l={kl:g}, k_s={ks:g}, H={label}", **fit_kw)
    grid.store(idx, res)


def _mean_alpha_surfaces(agg: xr.Dataset, kl: float, ks: float, group_hs: list[float]) -> float:
    """Mean of ``agg.alpha`` [1] over the present cases of the group ``(kl, ks, group_hs)``."""
    sub = agg["alpha"].sel(k_l=kl, k_s=ks, H=group_hs)
    if "case_present" in agg:
        sub = sub.where(agg["case_present"].sel(k_l=kl, k_s=ks, H=group_hs))
    return float(sub.mean(skipna=True))


def _cel_dataset(agg: xr.Dataset, grid: _CelGrid, labels: list[str], methods: Sequence[str],
                 confidence: float, attrs: dict) -> xr.Dataset:
    """:func:`fit_cel`'s result dataset from the filled ``grid``; ``agg`` gives the k_l, k_s, H coordinates."""
    kls, kss, hs = (agg[d].values for d in ("k_l", "k_s", "H"))
    dims5 = ("k_l", "k_s", "H_group", "estimator", "constant")
    one = {"units": "1"}
    return xr.Dataset(
        {
            **_estimate_vars(dims5, grid.value, grid.stderr, grid.bstd, grid.clo, grid.chi, grid.npts,
                             confidence=confidence, resampled="seeds", methods=methods,
                             points="paper route with paper_average='seeds': seed-mean points, one per H and step"),
            "n_seeds": (dims5[:3], grid.nseeds, {**one, "long_name": "number of seeds (surfaces) in the group"}),
            "n_boot_ok": (dims5[:4], grid.nboot_ok, {**one, "long_name": "bootstrap resamples that fitted"}),
            "alpha_power_law": (dims5[:3], grid.alpha, {**one, "long_name": "Nayak alpha of the ideal "
                                "continuous power-law spectrum (NaN for pooled groups; 20-60 % low "
                                "for k_l = 1, see theory.discrete_power_law_moments)"}),
            "alpha_surfaces": (dims5[:3], grid.alpha_surf, {**one, "long_name": "mean Nayak alpha of the "
                               "group's generated surfaces (agg variable alpha; NaN if absent)"}),
            **_paper_vars(),
        },
        coords={
            "k_l": ("k_l", kls.astype(np.float64), dict(agg["k_l"].attrs)),
            "k_s": ("k_s", kss.astype(np.float64), dict(agg["k_s"].attrs)),
            "H_group": ("H_group", np.array(labels, dtype=object),
                        {"units": "1", "long_name": "Hurst exponent of the group, or 'pooled' over all H"}),
            "H_value": ("H_group", np.append(hs.astype(np.float64), np.nan),
                        {"units": "1", "long_name": "Hurst exponent (NaN: pooled)"}),
            **_estimator_coords(methods),
        },
        attrs=attrs,
    )


def _derive_topographies(agg: xr.Dataset) -> xr.Dataset:
    """``agg`` (dims ``topography, step``) with ``kappa`` and ``dpbar_dp0`` derived as for generated cases.

    :func:`roughcontact.aggregate.add_derived` works on the generated layout, so the
    topographies are mapped onto it (as seeds of one placeholder ``(k_l, k_s, H)``) and back.
    """
    case = agg.rename({TOPOGRAPHY_DIM: "seed"}).expand_dims({d: [0.0] for d in CASE_DIMS[:3]})
    derived = add_derived(case).isel({d: 0 for d in CASE_DIMS[:3]}, drop=True).rename({"seed": TOPOGRAPHY_DIM})
    out = agg.copy()
    for name in ("kappa", "dpbar_dp0", "n_unconverged"):
        dims = [d for d in (TOPOGRAPHY_DIM, "step") if d in derived[name].dims]
        out[name] = derived[name].transpose(*dims)
    return out


def _topography_curves(agg: xr.Dataset, window: tuple[float, float]) -> tuple[_Curves, list[str]]:
    """The load curves of the present topographies (one row each, one stratum) and their names."""
    names = [str(t) for t in agg[TOPOGRAPHY_DIM].values]
    dims = (TOPOGRAPHY_DIM, "step")
    present = (agg["case_present"].transpose(TOPOGRAPHY_DIM).values.astype(bool) if "case_present" in agg
               else np.ones(len(names), bool))

    def steps(name, dtype=float):
        return agg[name].broadcast_like(agg["area_fraction"]).transpose(*dims).values.astype(dtype)[present]

    a = steps("area_fraction")
    valid = steps("converged", bool) & np.isfinite(a)
    hp = agg["rms_slope"].transpose(TOPOGRAPHY_DIM).values.astype(float)[present]
    curves = _Curves(a, steps("pressure"), hp, steps("kappa"), steps("dpbar_dp0"), valid,
                     np.zeros(a.shape[0], dtype=int), window)
    return curves, [n for n, p in zip(names, present, strict=True) if p]


def fit_topographies(agg: xr.Dataset, *, window: tuple[float, float] = (0.01, 0.11), n_boot: int = 200,
                     rng_seed: int = 2012, methods: Sequence[str] = METHODS, min_points: int = 6,
                     kappa_extrapolation: str = "cel", paper_average: str = "seeds",
                     confidence: float = 0.95, on_insufficient: str = "nan") -> xr.Dataset:
    """Fit the CEL constants to all topographies of a measured scene, pooled as one surface type.

    The topographies play the part of :func:`fit_cel`'s seeds in a single group: the same
    estimators, and a bootstrap that resamples whole topographies (one stratum). With a
    single topography there is no surface-to-surface scatter to resample: the bootstrap
    columns are NaN and ``n_boot_ok`` is 0. Topographies with ``case_present == False``
    (e.g. set by :func:`exclude_unconverged`) are left out.

    Parameters
    ----------
    agg : xarray.Dataset
        Contact aggregate of a measured scene, dims ``(topography, step)`` (string
        coordinate ``topography``): ``area_fraction`` [1], ``pressure`` (``p0``, per step
        or per topography and step) [unit of ``e_star``], ``mean_contact_pressure``,
        ``converged``, ``rms_slope(topography)`` [1], optionally ``alpha(topography)`` [1]
        and ``case_present(topography)``; global attr ``e_star``. ``kappa`` and
        ``dpbar_dp0`` are derived if absent.
    window, n_boot, rng_seed, methods, min_points, kappa_extrapolation, confidence
        As in :func:`fit_cel`. The bootstrap stream is keyed by ``rng_seed`` alone.
    paper_average : {"seeds", "none", "auto"}
        ``"seeds"``: the paper route fits the topography-mean curve (needs one normalised load
        schedule ``p0 / (E* h')`` for all topographies); ``"none"``: every (topography, step)
        point; ``"auto"``: ``"seeds"`` where the schedules agree, else ``"none"`` (the choice is
        the result's ``paper_average`` attribute).
    on_insufficient : {"nan", "raise"}
        Too few in-window points: NaN values (default; a measured surface may simply not
        reach the window) or a ValueError naming the window.

    Returns
    -------
    xarray.Dataset
        Dims ``estimator``, ``constant`` and ``topography``. Variables, all with units "1":
        ``value``, ``stderr``, ``bootstrap_stderr``, ``ci_low``, ``ci_high``, ``constrained``,
        ``n_points(estimator, constant)``, ``n_boot_ok(estimator)``, ``n_topographies`` (scalar,
        topographies fitted), ``in_fit(topography)`` (1 if it entered the fit),
        ``alpha_surfaces`` (scalar, mean Nayak alpha of the fitted topographies, NaN if
        ``agg`` has no ``alpha``), ``paper_value(constant)``, ``paper_stderr(constant)``.
        Attrs record the settings, as :func:`fit_cel`'s, and ``layout = "topographies"``.
    """
    _check_topography_aggregate(agg)
    if "dpbar_dp0" not in agg or "kappa" not in agg:
        agg = _derive_topographies(agg)
    curves, fitted = _topography_curves(agg, _check_window(window))
    if paper_average == "auto":
        paper_average = "seeds" if _shared_schedule(curves) else "none"
    (lo, hi), methods = _check_settings(window, n_boot, rng_seed, methods, min_points, kappa_extrapolation,
                                        confidence, paper_average, on_insufficient)
    e_star = float(agg.attrs["e_star"])
    if paper_average == "seeds" and "paper" in methods and curves.n_seeds:
        _check_schedules(curves, ["fit_topographies: the topographies"])
    res = _GroupFit(len(methods))
    if curves.n_seeds:
        res = _fit_group(curves, methods=methods, e_star=e_star, min_points=min_points,
                         kappa_extrapolation=kappa_extrapolation, paper_average=paper_average, n_boot=n_boot,
                         confidence=confidence, rng=_group_rng(rng_seed, 0.0, 0.0, "topographies"),
                         on_insufficient=on_insufficient, caller="fit_topographies",
                         where=f"{curves.n_seeds} topographies pooled", window=window)
    attrs = {**_settings_attrs(lo, hi, n_boot, rng_seed, confidence, min_points, kappa_extrapolation,
                               paper_average, e_star), "layout": "topographies"}
    return _topography_dataset(agg, res, curves.n_seeds, fitted, methods, confidence, attrs)


def _check_topography_aggregate(agg: xr.Dataset) -> None:
    """ValueError unless ``agg`` is a measured scene's contact aggregate that :func:`fit_topographies` can fit.

    It needs dims ``(topography, step)`` and no generated-case dim, the variables
    ``area_fraction, pressure, converged, rms_slope`` and the global attribute ``e_star``.
    """
    if not _is_topography_layout(agg) or "step" not in agg.dims:
        raise ValueError(f"agg must have dims (topography, step), got {tuple(agg.dims)}; "
                         "generated scenes are fitted by fit_cel")
    clash = [d for d in CASE_DIMS if d in agg.dims]
    if clash:
        raise ValueError(f"agg mixes topographies with generated-case dims {clash}; not supported")
    missing = [v for v in ("area_fraction", "pressure", "converged", "rms_slope") if v not in agg]
    if missing:
        raise ValueError(f"agg lacks variable(s) {missing}")
    if "e_star" not in agg.attrs:
        raise ValueError("agg lacks the global attribute 'e_star' (contact modulus)")


def _topography_dataset(agg: xr.Dataset, res: _GroupFit, n_fitted: int, fitted: list[str],
                        methods: Sequence[str], confidence: float, attrs: dict) -> xr.Dataset:
    """:func:`fit_topographies`' result dataset from the pooled fit ``res`` of the ``n_fitted`` topographies ``fitted``.

    ``agg`` gives the topography names (all of them, fitted or not) and ``alpha``.
    """
    alpha_surf = np.nan
    if "alpha" in agg and fitted:
        alpha_surf = float(agg["alpha"].sel({TOPOGRAPHY_DIM: fitted}).mean(skipna=True))
    names = agg[TOPOGRAPHY_DIM].values
    in_fit = np.isin(np.array([str(t) for t in names]), fitted).astype(np.int8)
    dims = ("estimator", "constant")
    one = {"units": "1"}
    return xr.Dataset(
        {
            **_estimate_vars(dims, res.value, res.stderr, res.bstd, res.clo, res.chi, res.npts,
                             confidence=confidence, resampled="topographies", methods=methods,
                             points="paper route with paper_average='seeds': topography-mean points, one per step"),
            "n_topographies": ((), np.int64(n_fitted), {**one, "long_name": "number of topographies fitted"}),
            "n_boot_ok": (dims[:1], res.nboot_ok, {**one, "long_name": "bootstrap resamples that fitted"}),
            "in_fit": ((TOPOGRAPHY_DIM,), in_fit, {**one, "long_name": "1 if the topography entered the fit, "
                                                   "0 if excluded (e.g. unconverged steps)"}),
            "alpha_surfaces": ((), alpha_surf, {**one, "long_name": "mean Nayak alpha of the fitted "
                                                "topographies (agg variable alpha; NaN if absent)"}),
            **_paper_vars(),
        },
        coords={
            TOPOGRAPHY_DIM: (TOPOGRAPHY_DIM, np.array([str(t) for t in names], dtype=object),
                             {"units": "1", "long_name": "name of the measured topography"}),
            **_estimator_coords(methods),
        },
        attrs=attrs,
    )


def kappa_spread(fit_ds: xr.Dataset, *, estimator: str = "paper") -> xr.Dataset:
    """How far each H's ``kappa`` lies from the H-pooled value, per ``(k_l, k_s)``.

    Parameters
    ----------
    fit_ds : xarray.Dataset
        Output of :func:`fit_cel` (must contain the ``"pooled"`` group and ``estimator``).
    estimator : str
        Estimator whose ``kappa`` is compared.

    Returns
    -------
    xarray.Dataset
        Dims ``(k_l, k_s, H)``: ``kappa_relative_deviation = kappa_H / kappa_pooled - 1`` [1],
        ``kappa_z = (kappa_H - kappa_pooled) / bootstrap_stderr_H`` [1]; and
        ``max_abs_relative_deviation(k_l, k_s)`` over H [1].
    """
    if "estimator" not in fit_ds.coords or estimator not in list(fit_ds["estimator"].values):
        have = list(fit_ds["estimator"].values) if "estimator" in fit_ds.coords else []
        raise ValueError(f"estimator {estimator!r} is not in fit_ds (has {have})")
    labels = list(fit_ds["H_group"].values)
    if POOLED not in labels:
        raise ValueError("fit_ds has no 'pooled' H_group; pass the output of fit_cel")
    k = fit_ds["value"].sel(estimator=estimator, constant="kappa")
    se = fit_ds["bootstrap_stderr"].sel(estimator=estimator, constant="kappa")
    pooled = k.sel(H_group=POOLED, drop=True)
    per_h = [lab for lab in labels if lab != POOLED]
    kh = k.sel(H_group=per_h)
    hvals = fit_ds["H_value"].sel(H_group=per_h).values
    rel = (kh / pooled - 1.0).rename(H_group="H").assign_coords(H=hvals)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = ((kh - pooled) / se.sel(H_group=per_h)).rename(H_group="H").assign_coords(H=hvals)
    rel = rel.drop_vars([c for c in rel.coords if c not in ("k_l", "k_s", "H")])
    z = z.drop_vars([c for c in z.coords if c not in ("k_l", "k_s", "H")])
    rel.attrs = {"units": "1", "long_name": f"kappa(H) / kappa(pooled) - 1 ({estimator})"}
    z.attrs = {"units": "1", "long_name": f"(kappa(H) - kappa(pooled)) / bootstrap stderr(H) ({estimator})"}
    mx = abs(rel).max("H", skipna=True)
    mx.attrs = {"units": "1", "long_name": "largest |kappa(H)/kappa(pooled) - 1| over H"}
    return xr.Dataset({"kappa_relative_deviation": rel, "kappa_z": z,
                       "max_abs_relative_deviation": mx})


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


def constrained_flags(value, ci_low, ci_high, estimators: Sequence[str] | None = None) -> np.ndarray:
    """1 where the bootstrap interval ``[ci_low, ci_high]`` is narrower than ``|value|``, else 0 (int8).

    A constant whose 95 % interval is wider than itself (e.g. kappa = 4.79 with the
    interval [3.1, 6368]) is not determined by the data and must not be reported as a number.
    With ``estimators`` (the names along the second-last axis; constants along the last, in
    :data:`CONSTANTS` order), a constant on a bound of its estimator (:func:`at_bound`) is 0 too.
    """
    value, lo, hi = (np.asarray(x, dtype=float) for x in (value, ci_low, ci_high))
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(value) & np.isfinite(lo) & np.isfinite(hi) & ((hi - lo) < np.abs(value))
    if estimators is not None:
        for idx in np.ndindex(value.shape):
            ok[idx] &= not at_bound(estimators[idx[-2]], CONSTANTS[idx[-1]], value[idx])
    return ok.astype(np.int8)


def _csv_float(x) -> str:
    x = float(x)
    return "" if not np.isfinite(x) else f"{x:.6g}"


def to_csv_table(fit_ds: xr.Dataset) -> str:
    """Human-readable CSV of a :func:`fit_cel` or :func:`fit_topographies` result.

    One row per group/estimator/constant (floats with 6 significant digits; empty cell for
    NaN). For :func:`fit_cel`, columns ``k_l, k_s, H_group, estimator, constant, value,
    stderr, bootstrap_stderr, ci_low, ci_high, constrained, n_points, n_seeds, n_boot_ok,
    paper_value, paper_stderr``; groups without cases are omitted; rows are sorted by k_l,
    k_s, then the dataset's H_group, estimator, constant order. For
    :func:`fit_topographies` (a dataset with ``n_topographies``), columns ``group, estimator,
    constant, value, stderr, bootstrap_stderr, ci_low, ci_high, constrained, n_points,
    n_topographies, n_boot_ok, paper_value, paper_stderr`` with ``group`` =
    ``"pooled (N topographies)"``; no row if no topography was fitted.

    Parameters
    ----------
    fit_ds : xarray.Dataset
        Output of :func:`fit_cel` or :func:`fit_topographies`.

    Returns
    -------
    str
        The table, with a header line and a trailing newline.
    """
    measured = "n_topographies" in fit_ds
    needed = ("value", "stderr", "bootstrap_stderr", "ci_low", "ci_high", "constrained", "n_points",
              "n_topographies" if measured else "n_seeds", "n_boot_ok", "paper_value", "paper_stderr")
    missing = [v for v in needed if v not in fit_ds]
    if missing:
        raise ValueError(f"fit_ds lacks {missing}; pass the output of fit_cel or fit_topographies")
    if measured:
        return _csv_table_topographies(fit_ds)
    fmt = _csv_float

    buf = io.StringIO()
    cols = ["k_l", "k_s", "H_group", "estimator", "constant", "value", "stderr", "bootstrap_stderr",
            "ci_low", "ci_high", "constrained", "n_points", "n_seeds", "n_boot_ok", "paper_value", "paper_stderr"]
    buf.write(",".join(cols) + "\n")
    for kl in fit_ds["k_l"].values:
        for ks in fit_ds["k_s"].values:
            for hg in fit_ds["H_group"].values:
                sel = dict(k_l=kl, k_s=ks, H_group=hg)
                n_s = int(fit_ds["n_seeds"].sel(sel))
                if n_s == 0:
                    continue
                for m in fit_ds["estimator"].values:
                    for c in fit_ds["constant"].values:
                        full = dict(sel, estimator=m, constant=c)
                        row = [fmt(kl), fmt(ks), str(hg), str(m), str(c)]
                        row += [fmt(fit_ds[v].sel(full)) for v in ("value", "stderr", "bootstrap_stderr",
                                                                 "ci_low", "ci_high")]
                        row += ["yes" if int(fit_ds["constrained"].sel(full)) else "no",
                                str(int(fit_ds["n_points"].sel(full))), str(n_s),
                                str(int(fit_ds["n_boot_ok"].sel(dict(sel, estimator=m))))]
                        row += [fmt(fit_ds["paper_value"].sel(constant=c)),
                                fmt(fit_ds["paper_stderr"].sel(constant=c))]
                        buf.write(",".join(row) + "\n")
    return buf.getvalue()


#: Columns of the CSV table of a :func:`fit_topographies` result.
TOPOGRAPHY_CSV_COLUMNS = ("group", "estimator", "constant", "value", "stderr", "bootstrap_stderr", "ci_low",
                          "ci_high", "constrained", "n_points", "n_topographies", "n_boot_ok", "paper_value",
                          "paper_stderr")


def _csv_table_topographies(fit_ds: xr.Dataset) -> str:
    buf = io.StringIO()
    buf.write(",".join(TOPOGRAPHY_CSV_COLUMNS) + "\n")
    n_t = int(fit_ds["n_topographies"])
    if n_t == 0:
        return buf.getvalue()
    # A label without commas keeps every cell unquoted, like fit_cel's table.
    group = f"pooled ({n_t} topograph{'y' if n_t == 1 else 'ies'})"
    for m in fit_ds["estimator"].values:
        for c in fit_ds["constant"].values:
            full = dict(estimator=m, constant=c)
            row = [group, str(m), str(c)]
            row += [_csv_float(fit_ds[v].sel(full)) for v in ("value", "stderr", "bootstrap_stderr", "ci_low",
                                                              "ci_high")]
            row += ["yes" if int(fit_ds["constrained"].sel(full)) else "no", str(int(fit_ds["n_points"].sel(full))),
                    str(n_t), str(int(fit_ds["n_boot_ok"].sel(estimator=m)))]
            row += [_csv_float(fit_ds[v].sel(constant=c)) for v in ("paper_value", "paper_stderr")]
            buf.write(",".join(row) + "\n")
    return buf.getvalue()


# ----------------------------------------------------------------- synthetic data
def _synthetic_case(kl, ks, h, seed, p0, a, rms_slope, e_star, truth) -> xr.Dataset:
    """One synthetic case in the per-case contact format (see simulate_cel_cases)."""
    n = p0.size
    d5 = CASE_DIMS + ("step",)
    pbar = p0 / a

    def step_var(x, units, long_name):
        return d5, np.asarray(x).reshape(1, 1, 1, 1, n), {"units": units, "long_name": long_name}

    def case_var(x, units, long_name):
        return CASE_DIMS, np.full((1, 1, 1, 1), x), {"units": units, "long_name": long_name}

    placeholder = "(synthetic placeholder)"
    return xr.Dataset(
        {
            "pressure": step_var(p0, "E*", "applied mean pressure p0"),
            "area_fraction": step_var(a, "1", "real contact area fraction A/A0"),
            "mean_contact_pressure": step_var(pbar, "E*", "mean contact pressure F/A"),
            "kappa": step_var(e_star * rms_slope / pbar, "1", "E* h' / pbar"),
            "iterations": step_var(np.ones(n, dtype=np.int64), "1", f"solver iterations {placeholder}"),
            "residual": step_var(np.zeros(n), "1", f"solver residual {placeholder}"),
            "converged": step_var(np.ones(n, dtype=bool), "1", f"solver converged {placeholder}"),
            "wall_time": step_var(np.zeros(n), "s", f"wall time {placeholder}"),
            "rms_slope": case_var(float(rms_slope), "1", "rms slope h'"),
            "alpha": case_var(power_law_alpha(kl, ks, h), "1", "Nayak alpha (ideal power-law spectrum)"),
        },
        coords={"k_l": [float(kl)], "k_s": [float(ks)], "H": [float(h)],
                "seed": np.array([seed], dtype=np.int64), "step": np.arange(1, n + 1, dtype=np.int64)},
        attrs={"e_star": float(e_star), "synthetic": "CEL", **truth},
    )


def simulate_cel_cases(*, k_l: Sequence[float] = (16.0,), k_s: Sequence[float] = (32.0,),
                       hurst: Sequence[float] = (0.5,), seeds: Sequence[int] = tuple(range(4)),
                       kappa: float = PAPER_CEL["kappa"][0], mu: float = PAPER_CEL["mu"][0],
                       beta: float = PAPER_CEL["beta"][0], n_steps: int = 30,
                       area_max: float = 0.15, rms_slope: float = 0.1, e_star: float = 1.0,
                       seed_scatter: float = 0.02, point_noise: float = 0.0,
                       rng_seed: int = 0) -> tuple[list[xr.Dataset], list[str]]:
    """Synthetic per-case contact datasets following the CEL, in the workflow's format.

    For validating aggregation, fits and figures without running the solver. Each case
    ``(k_l, k_s, H, seed)`` with ``k_l < k_s`` gets ``p0_i = p_max i / n_steps``
    (``i = 1..n_steps``, ``p_max`` such that the noiseless CEL reaches ``area_max``) and
    ``A/A0 = (1 + n_i) CEL(p0_i; kappa (1 + e1), mu (1 + e2), beta (1 + e3))``: each case
    draws its own multiplicative perturbations ``e1, e2, e3 ~ N(0, seed_scatter^2)`` of
    the constants (a smooth surface-to-surface difference in level *and* shape), and
    each step an independent ``n_i ~ N(0, point_noise^2)``. ``pbar = p0 / (A/A0)``, ``kappa = E* h'/pbar``. Solver
    diagnostics are placeholders (converged, 0 residual, 1 iteration, no wall time);
    ``mean_gap`` and ``contact_perimeter`` are not modelled and absent.

    Parameters
    ----------
    k_l, k_s, hurst : sequences of float
        Case grid; combinations with ``k_l >= k_s`` are skipped.
    seeds : sequence of int
        Seed labels (>= 0).
    kappa, mu, beta : float
        True CEL constants.
    n_steps : int
        Load steps (>= 3).
    area_max : float
        Noiseless ``A/A0`` at the last step, in (0, 1).
    rms_slope : float
        ``h'`` of every case (> 0).
    e_star : float
        Contact modulus (> 0), written as the global attr ``e_star``.
    seed_scatter, point_noise : float
        Relative standard deviations (>= 0) of the per-case and per-step noise.
    rng_seed : int
        Seed of the noise (>= 0).

    Returns
    -------
    (list of xarray.Dataset, list of str)
        The datasets and synthetic file names ``"synthetic/kl{..}_ks{..}_H{..}_s{..}.nc"``.
    """
    if not isinstance(n_steps, (int, np.integer)) or n_steps < 3:
        raise ValueError(f"n_steps must be an integer >= 3, got {n_steps!r}")
    if not (0.0 < area_max < 1.0):
        raise ValueError(f"area_max must lie in (0, 1), got {area_max!r}")
    for name, v in (("seed_scatter", seed_scatter), ("point_noise", point_noise)):
        if not (np.isfinite(v) and v >= 0):
            raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
    p_max = float(cel_pressure(area_max, kappa=kappa, mu=mu, beta=beta, rms_slope=rms_slope,
                               e_star=e_star))
    p0 = p_max * np.arange(1, n_steps + 1) / n_steps
    rng = np.random.default_rng(rng_seed)
    out, names = [], []
    for kl in k_l:
        for ks in k_s:
            if not float(kl) < float(ks):
                continue
            for h in hurst:
                for s in seeds:
                    ek, em, eb = 1.0 + seed_scatter * rng.standard_normal(3)
                    if not (0.0 < mu * em < 1.0 and ek > 0 and eb > 0):
                        raise ValueError("seed_scatter too large: a perturbed constant left its range")
                    a = cel_area(p0, kappa=kappa * ek, mu=mu * em, beta=beta * eb,
                                 rms_slope=rms_slope, e_star=e_star)
                    a = a * (1.0 + point_noise * rng.standard_normal(n_steps))
                    if np.any(a <= 0) or np.any(a >= 1):
                        raise ValueError("noise too large: an area fraction left (0, 1); lower "
                                         "seed_scatter/point_noise")
                    out.append(_synthetic_case(kl, ks, h, int(s), p0, a, rms_slope, e_star,
                                               dict(kappa_true=float(kappa), mu_true=float(mu),
                                                    beta_true=float(beta))))
                    names.append(f"synthetic/kl{kl:g}_ks{ks:g}_H{h:g}_s{int(s)}.nc")
    if not out:
        raise ValueError("no case with k_l < k_s in the given grid")
    return out, names
