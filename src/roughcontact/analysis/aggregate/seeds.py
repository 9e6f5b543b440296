"""Statistics over seeds: mean, standard deviation and standard error per ``(k_l, k_s, H)``.

The seed statistics ``<var>_mean/_std/_sem`` keep the ``units`` of ``<var>`` (and for
``epsilon`` its reference length).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from ...core.quantities import REFERENCE_ATTRS
from .combine import first_bad_case
from .derived import add_derived

#: Quantities reduced over seeds by :func:`seed_statistics`.
SEED_STAT_VARIABLES = ("area_fraction", "kappa", "mean_contact_pressure", "dpbar_dp0")


# ---------------------------------------------------------------- seed statistics
def seed_reduce(da: xr.DataArray, present: xr.DataArray, n: xr.DataArray, label: str,
                 units: str) -> dict[str, xr.DataArray]:
    """Mean, std (ddof=1) and sem over ``seed`` of the present cases; data NaNs propagate."""
    vals = da.where(present)
    data_nan = (da.isnull() & present).any("seed")
    mean = (vals.sum("seed", skipna=True) / n).where(~data_nan & (n > 0))
    dev2 = ((vals - mean) ** 2).sum("seed", skipna=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.sqrt(dev2 / (n - 1)).where(~data_nan & (n > 1))
        sem = std / np.sqrt(n)
    mean.attrs = {"units": units, "long_name": f"mean over seeds of {label}"}
    std.attrs = {"units": units, "long_name": f"standard deviation (ddof=1) over seeds of {label}"}
    sem.attrs = {"units": units, "long_name": f"standard error of the seed mean of {label}"}
    return {"mean": mean, "std": std, "sem": sem}


def _n_seeds(present: xr.DataArray, min_seeds: int, what: str) -> xr.DataArray:
    if not isinstance(min_seeds, (int, np.integer)) or min_seeds < 1:
        raise ValueError(f"min_seeds must be an integer >= 1, got {min_seeds!r}")
    n = present.sum("seed").astype(np.int64)
    few = (n > 0) & (n < min_seeds)
    if bool(few.any()):
        raise ValueError(f"{what}: only {int(n.where(few).min())} seed(s) at "
                         f"{first_bad_case(few)}; min_seeds={min_seeds} (set min_seeds=1 to "
                         "accept NaN standard deviations)")
    n.attrs = {"units": "1", "long_name": "number of seeds (0: no such case)"}
    return n


def seed_statistics(ds: xr.Dataset, *, variables: Sequence[str] = SEED_STAT_VARIABLES,
                    min_seeds: int = 2) -> xr.Dataset:
    """Mean, standard deviation and standard error over seeds per ``(k_l, k_s, H)``.

    Only cases with ``case_present`` enter; a NaN in a present case's data makes that
    statistic NaN (it is not skipped). ``std`` uses ``ddof=1``, ``sem = std / sqrt(n)``.

    Parameters
    ----------
    ds : xarray.Dataset
        Combined contact dataset; ``kappa``/``dpbar_dp0`` are derived by
        :func:`add_derived` if absent.
    variables : sequence of str
        Variables to reduce (default :data:`SEED_STAT_VARIABLES`).
    min_seeds : int
        Smallest accepted seed count for a present ``(k_l, k_s, H)`` (>= 1).

    Returns
    -------
    xarray.Dataset
        Dims ``(k_l, k_s, H[, step])``: ``<var>_mean``, ``<var>_std``, ``<var>_sem`` for each
        variable with the ``units`` of the variable, ``pressure_mean`` [unit of e_star],
        ``rms_slope_mean`` [1] and ``n_seeds(k_l, k_s, H)``; attrs of ``ds`` kept.
    """
    if "dpbar_dp0" not in ds or "kappa" not in ds:
        ds = add_derived(ds)
    present = ds["case_present"] if "case_present" in ds else xr.ones_like(ds["rms_slope"], dtype=bool)
    n = _n_seeds(present, min_seeds, "seed_statistics")
    out = xr.Dataset(attrs=dict(ds.attrs))
    for var in list(variables) + ["pressure", "rms_slope"]:
        if var not in ds:
            raise ValueError(f"variables: {var!r} is not in the dataset (has {sorted(ds.data_vars)})")
        units = str(ds[var].attrs.get("units", "1"))
        label = str(ds[var].attrs.get("long_name", var))
        stats = seed_reduce(ds[var], present, n, label, units)
        if var in ("pressure", "rms_slope") and var not in variables:
            out[f"{var}_mean"] = stats["mean"]
            continue
        for k, v in stats.items():
            out[f"{var}_{k}"] = v
    out["n_seeds"] = n
    return out


def representativity_statistics(ds: xr.Dataset, *, min_seeds: int = 2) -> xr.Dataset:
    """Mean, std and sem over seeds of the Gaussian L2 error ``epsilon`` per ``(k_l, k_s, H)``.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`combine_cases` with ``kind="representativity"``: ``epsilon``
        (and optionally ``rms_height``, ``rms_slope``) over ``(k_l, k_s, H, seed)``.
    min_seeds : int
        Smallest accepted seed count for a present ``(k_l, k_s, H)`` (>= 1).

    Returns
    -------
    xarray.Dataset
        Dims ``(k_l, k_s, H)``: ``epsilon_mean``, ``epsilon_std``, ``epsilon_sem`` [unit and
        reference length of epsilon], ``rms_height_mean``/``rms_slope_mean`` where available, ``n_seeds``.
    """
    if "epsilon" not in ds:
        raise ValueError("ds lacks variable 'epsilon'; pass combine_cases(..., kind='representativity')")
    present = ds["case_present"] if "case_present" in ds else xr.ones_like(ds["epsilon"], dtype=bool)
    n = _n_seeds(present, min_seeds, "representativity_statistics")
    out = xr.Dataset(attrs=dict(ds.attrs))
    eps = ds["epsilon"]
    stats = seed_reduce(eps, present, n, str(eps.attrs.get("long_name", "epsilon")),
                         str(eps.attrs.get("units", "1")))
    for k, v in stats.items():
        out[f"epsilon_{k}"] = v.assign_attrs({a: eps.attrs[a] for a in REFERENCE_ATTRS if a in eps.attrs})
    for var in ("rms_height", "rms_slope"):
        if var in ds:
            st = seed_reduce(ds[var], present, n, str(ds[var].attrs.get("long_name", var)),
                              str(ds[var].attrs.get("units", "1")))
            out[f"{var}_mean"] = st["mean"]
    out["n_seeds"] = n
    return out


def scale_free_statistics(rep: xr.Dataset) -> xr.Dataset | None:
    """Seed statistics of the scale-free eps, or None when ``rep`` lacks the per-case data.

    Parameters
    ----------
    rep : xarray.Dataset
        Aggregated representativity dataset with per-case ``epsilon`` [height unit^-1/2]
        and ``std_height`` [height unit] over ``(k_l, k_s, H, seed)`` (as the workflow's
        ``aggregate/representativity.nc`` holds them).

    Returns
    -------
    xarray.Dataset or None
        :func:`roughcontact.analysis.aggregate.representativity_statistics` of
        ``epsilon * sqrt(std_height)``: ``epsilon_mean``, ``epsilon_sem``, ... [1] and
        ``n_seeds`` over ``(k_l, k_s, H)``.
    """
    if not all(v in rep and "seed" in rep[v].dims for v in ("epsilon", "std_height")):
        return None
    present = rep["case_present"] if "case_present" in rep else True
    sigma = rep["std_height"].where(present & (rep["std_height"] > 0))
    eps = rep["epsilon"] * np.sqrt(sigma)
    # its own attributes only: not epsilon's reference length (xarray may keep the first operand's)
    eps.attrs = {"units": "1", "long_name": "L2 error of the normalised heights (h - hbar)/sigma"}
    keep = [v for v in ("case_present",) if v in rep]
    return representativity_statistics(rep[keep].assign(epsilon=eps), min_seeds=1)
