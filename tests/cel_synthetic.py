"""Synthetic CEL data and a spread check: what only the tests use.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from roughcontact.analysis.aggregate.combine import CASE_DIMS
from roughcontact.analysis.fit.estimators import PAPER_CEL, POOLED
from roughcontact.theory.laws import cel_area, cel_pressure
from roughcontact.theory.spectra import power_law_alpha


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
