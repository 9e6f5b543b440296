"""The normal contact stiffness per unit nominal area, ``K = -d p0 / d u_mean``, along the load steps.

Users of interfacial-stiffness models (Persson; Pohrt & Popov; Campañá, Persson & Müser) compare
``K`` against load; here it comes from the mean gap ``u_mean`` the solver reports at each step,
differentiated along the steps by the same finite differences in ``ln p0`` as ``d pbar / d p0``
(:func:`.aggregate.derivatives.load_derivative`). At full contact the mean gap
is zero and the stiffness of a periodic half-space is unbounded: those steps, and the steps whose
stencil reaches them, are NaN.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..core.quantities import cf_unit
from .aggregate.derivatives import load_derivative


def contact_stiffness(mean_gap: np.ndarray, p0: np.ndarray, area_fraction: np.ndarray) -> np.ndarray:
    """``K = -d p0 / d u_mean`` per step [pressure / length], shape ``(n_steps,)``.

    Parameters
    ----------
    mean_gap : numpy.ndarray, shape (n_steps,)
        Mean gap over the cell at each step [length].
    p0 : numpy.ndarray, shape (n_steps,)
        Applied mean pressure, > 0 and increasing [pressure].
    area_fraction : numpy.ndarray, shape (n_steps,)
        ``A/A0`` at each step [-]; steps at full contact (``A/A0 = 1``), and those whose
        second-order stencil (the step and its neighbours) touches one, give NaN.
    """
    u = np.asarray(mean_gap, dtype=np.float64)
    p = np.asarray(p0, dtype=np.float64)
    a = np.asarray(area_fraction, dtype=np.float64)
    if not (u.shape == p.shape == a.shape and u.ndim == 1 and u.size >= 3):
        raise ValueError("stiffness: mean_gap, p0 and area_fraction must be 1-D of one length >= 3 "
                         f"(got shapes {u.shape}, {p.shape}, {a.shape})")
    du = load_derivative(u, p, order=2, variable="log_p0")
    full = a >= 1.0
    near = full.copy()
    near[1:] |= full[:-1]
    near[:-1] |= full[1:]
    near[-1] |= full[-3]  # the one-sided end stencils reach two steps in
    near[0] |= full[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = -1.0 / du
    return np.where(near | ~(du < 0), np.nan, k)


def stiffness_variable(result: xr.Dataset, length_unit: str = "1", pressure_unit: str = "1") -> xr.DataArray:
    """``contact_stiffness(step)`` of a solve's dataset (``pressure``, ``mean_gap``, ``area_fraction``).

    ``length_unit`` and ``pressure_unit`` are the solve's (:func:`roughcontact.core.quantities.cf_unit`).
    """
    k = contact_stiffness(result["mean_gap"].values, result["pressure"].values, result["area_fraction"].values)
    return xr.DataArray(k, dims=("step",), attrs={
        "units": cf_unit(length_unit, pressure_unit, length_power=-1, pressure_power=1),
        "long_name": "normal contact stiffness per unit nominal area -d p0 / d (mean gap) (NaN at and "
                     "next to full contact)",
        "allow_nan": 1})
