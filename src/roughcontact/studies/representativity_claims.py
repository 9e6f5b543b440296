"""The paper's claims on geometric representativity (its Fig. 1), measured on a run's aggregates.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from ..statistics.representativity import scale_free_l2_error
from .verdicts import judged_row


def _eps_sigma(rep: xr.Dataset) -> xr.DataArray:
    """Scale-free eps (eps sqrt(sigma)) of the present cases, mean over H: dims (k_l, k_s, seed)."""
    eps = rep["epsilon"] * np.sqrt(rep["std_height"]) if "std_height" in rep else rep["epsilon"]
    return eps.where(rep["case_present"]).mean("H")


def _eps_by_kl(rep: xr.Dataset) -> xr.DataArray:
    """Scale-free eps (eps sqrt(sigma)), mean over seeds, per (k_l, k_s)."""
    return _eps_sigma(rep).mean("seed")


#: Draws of i.i.d. Gaussian heights behind the representativity noise floor, and their seed.
NOISE_DRAWS, NOISE_SEED = 30, 2012


def noise_floor(n: int, n_bins: int, draws: int = NOISE_DRAWS, seed: int = NOISE_SEED) -> float:
    """ε_σ of exactly Gaussian heights with the study's bins and number of points: mean of ``draws`` maps [1].

    ``n x n`` i.i.d. standard normal heights, ``n_bins`` bins: what ε_σ reads for a perfectly
    Gaussian sample of that size, below which no surface can be called more representative.
    """
    rng = np.random.default_rng(seed)
    return float(np.mean([scale_free_l2_error(rng.standard_normal((n, n)), n_bins) for _ in range(draws)]))


def representativity_claims(rep: xr.Dataset) -> list[dict]:
    """The threshold k_l >~ 8-16, the weak dependence on k_s and eps falling with k_s (Fig. 1a, appendix)."""
    eps = _eps_by_kl(rep)
    by_kl = eps.mean("k_s")
    kls = [float(k) for k in by_kl.k_l.values]
    vals = [float(v) for v in by_kl.values]
    surface = json.loads(rep.attrs["scene_parameters"])["surface"]
    floor = noise_floor(int(surface["N"]), int(rep.attrs["n_bins"]))
    rows = [judged_row(
        "representativity grows with k_l up to k_l ≈ 8–16", "k_l ≈ 8–16",
        "eps_σ: " + ", ".join(f"{v:.3g} (k_l={k:g})" for k, v in zip(kls, vals, strict=True))
        + f"; noise floor {floor:.3g}; ratios to it: " + ", ".join(f"{v / floor:.2f}" for v in vals))]
    spread_ks = (eps.max("k_s") - eps.min("k_s")) / eps.mean("k_s")
    spread_kl = (by_kl.max() - by_kl.min()) / by_kl.mean()
    rows.append(judged_row(
        "k_s has a weaker effect than k_l (for k_s ≫ k_l)", "weak",
        f"relative spread over k_s at fixed k_l: {float(spread_ks.median()):.2f} (median over k_l); "
        f"over k_l: {float(spread_kl):.2f}"))
    rows.append(_ks_falls_row(rep))
    return rows


def _ks_falls_row(rep: xr.Dataset) -> dict:
    """Per k_l, eps_σ at the smallest k_s minus that at the largest, with its standard error over seeds."""
    eps = _eps_sigma(rep)
    ends = eps.isel(k_s=[0, -1])
    mean, sem = ends.mean("seed"), ends.std("seed", ddof=1) / np.sqrt(ends.notnull().sum("seed"))
    drop = mean.isel(k_s=0) - mean.isel(k_s=1)
    err = np.hypot(sem.isel(k_s=0), sem.isel(k_s=1))
    ks_lo, ks_hi = float(eps.k_s[0]), float(eps.k_s[-1])
    return judged_row(
        "ε decreases with k_s for all k_l (appendix)", "decreases for all k_l",
        f"ε_σ(k_s={ks_lo:g}) − ε_σ(k_s={ks_hi:g}): " + ", ".join(
            f"Δ = {float(d):.2g} ± {float(e):.2g} (k_l={float(k):g})"
            for k, d, e in zip(drop.k_l.values, drop.values, err.values, strict=True)))
