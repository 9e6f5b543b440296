"""Shared reading and fitting for the independent checks of docs/open-questions (numpy, scipy, xarray only).

Nothing here imports roughcontact: the checks recompute the page's claims from the published
NetCDF files with code written apart from the package's analysis (issue 61). Paths are relative to
this folder: ``../data`` (the page's data) and ``../../reproduction`` (the aggregates Q2 and Q3 read).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "data"
REPRODUCTION = HERE.parent.parent / "reproduction"
SQRT_2PI = float(np.sqrt(2 * np.pi))


def load(path: Path) -> xr.Dataset:
    """A published NetCDF file, read whole into memory (and closed)."""
    with xr.open_dataset(path) as ds:
        return ds.load()


def one_cell(ds: xr.Dataset) -> xr.Dataset:
    """A scene of one (k_l, k_s) pair without those two length-1 dimensions."""
    return ds.isel(k_l=0, k_s=0)


def kappa_at(area: np.ndarray, kappa: np.ndarray, target: float) -> float:
    """κ of one case where its load curve crosses A/A0 = ``target``: linear in ln A between the two steps."""
    ok = np.isfinite(area) & np.isfinite(kappa) & (area > 0)
    a, k = area[ok], kappa[ok]
    if a.size < 2 or not a.min() <= target <= a.max():
        return float("nan")
    order = np.argsort(a)
    return float(np.interp(np.log(target), np.log(a[order]), k[order]))


def mean_sem(values: np.ndarray) -> tuple[float, float, int]:
    """Mean, standard error (s.d. with n − 1 over √n) and count of the finite values."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(v.mean()), float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else float("nan"), int(v.size)


def wls(x: np.ndarray, y: np.ndarray, err: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Weighted polynomial fit (weights 1/err²), lowest power first: coefficients, covariance, reduced χ².

    The covariance is multiplied by the reduced χ² when that exceeds 1 (scatter beyond the errors).
    """
    v = np.vander(x, degree + 1, increasing=True)
    w = 1.0 / err**2
    cov = np.linalg.inv((v * w[:, None]).T @ v)
    coef = cov @ ((v * w[:, None]).T @ y)
    chi2 = float(np.sum(w * (y - v @ coef) ** 2) / max(x.size - degree - 1, 1))
    return coef, cov * max(chi2, 1.0), chi2


def crossing(area: np.ndarray, values: np.ndarray, target: float) -> float:
    """``values`` where the increasing ``area`` curve crosses ``target``, linear in A/A0 between the two steps."""
    k = int(np.searchsorted(area, target))
    t = (target - area[k - 1]) / (area[k] - area[k - 1])
    return float(values[k - 1] + t * (values[k] - values[k - 1]))
