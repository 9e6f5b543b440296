"""Quantities derived from a combined contact dataset: ``kappa``, ``dpbar_dp0``, ``n_unconverged``, ``n_unresolved``.

``pressure`` and ``mean_contact_pressure`` share the unit of the global attribute ``e_star`` (its
``pressure_units`` where recorded, e.g. ``"MPa"``), so that ``kappa = E* h' / pbar``
and ``dpbar_dp0`` are dimensionless ("1"), as are area fractions and slopes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import xarray as xr

from .combine import CASE_DIMS, CONTACT_REQUIRED, TOPOGRAPHY_DIM, combine_cases, first_bad_case
from .derivatives import load_derivative


def add_derived(ds: xr.Dataset, *, kappa_rtol: float = 1e-6, derivative_order: int = 2,
                derivative_variable: str = "log_p0") -> xr.Dataset:
    """Add ``kappa``, ``dpbar_dp0``, ``n_unconverged`` (and ``n_unresolved``) to a combined contact dataset.

    - ``kappa = E* h' / pbar`` [1], recomputed from ``e_star`` (global attr),
      ``rms_slope`` and ``mean_contact_pressure``. If the input already has ``kappa``,
      it must agree to ``kappa_rtol`` wherever both are finite, and ``pbar`` must equal
      ``p0 / (A/A0)`` to the same tolerance at converged steps; else ValueError.
    - ``dpbar_dp0`` [1]: ``d pbar / d p0`` per case along the load steps by
      :func:`load_derivative` (default: second-order non-uniform finite differences in
      ``ln p0``, see there for why). Unconverged steps stay in the stencils (the load
      curve has no other value there); the fits drop the unconverged steps themselves.
    - ``n_unconverged(k_l, k_s, H, seed)``: number of steps with ``converged == False``;
      float64 so that grid holes (``case_present == False``) can be NaN.
    - ``n_unresolved(k_l, k_s, H, seed)``, where the cases carry ``contact_resolved``
      (:mod:`roughcontact.statistics.patches`; files of older versions do not): number of steps whose
      contact the grid does not resolve, float64 as ``n_unconverged``.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`combine_cases` with ``kind="contact"``.
    kappa_rtol : float
        Relative tolerance of the consistency checks (> 0).
    derivative_order : {2, 4}
        Order of the finite differences for ``dpbar_dp0``.
    derivative_variable : {"log_p0", "p0"}
        Variable the differences are taken in.

    Returns
    -------
    xarray.Dataset
        A copy of ``ds`` with those variables added (``kappa`` replaced by the
        recomputed values).
    """
    e_star = _check_derived_inputs(ds, kappa_rtol)
    out = ds.copy()
    present = ds["case_present"] if "case_present" in ds else xr.ones_like(ds["rms_slope"], dtype=bool)
    converged = ds["converged"].astype(bool)

    out["kappa"] = _checked_kappa(ds, e_star, converged, present, kappa_rtol)
    out["kappa"].attrs = {"units": "1", "long_name": "kappa = E* h' / pbar (normalised inverse mean contact pressure)"}
    out["dpbar_dp0"] = _dpbar_dp0(ds, present, derivative_order, derivative_variable)
    out["n_unconverged"] = _n_false(converged, present)
    out["n_unconverged"].attrs = {"units": "1", "long_name": "number of unconverged load steps (NaN: no such case)"}
    if "contact_resolved" in ds:
        out["n_unresolved"] = _n_false(ds["contact_resolved"].astype(bool), present)
        out["n_unresolved"].attrs = {"units": "1", "long_name": "number of load steps whose contact is unresolved "
                                     "(largest patch under 4 nodes; NaN: no such case)"}
    return out


def _check_derived_inputs(ds: xr.Dataset, kappa_rtol: float) -> float:
    """The contact modulus ``e_star`` [pressure unit] of ``ds``, after checking :func:`add_derived`'s inputs.

    ``ValueError`` for a bad ``kappa_rtol``, a missing required variable or ``e_star``, an
    ``e_star`` that is not finite and positive, or pressures in different units.
    """
    if not (np.isfinite(kappa_rtol) and kappa_rtol > 0):
        raise ValueError(f"kappa_rtol must be a finite number > 0, got {kappa_rtol!r}")
    missing = [v for v in CONTACT_REQUIRED if v not in ds.data_vars]
    if missing:
        raise ValueError(f"ds lacks variable(s) {missing}; pass the output of combine_cases")
    if "e_star" not in ds.attrs:
        raise ValueError("ds lacks the global attribute 'e_star' (contact modulus)")
    e_star = float(ds.attrs["e_star"])
    if not (np.isfinite(e_star) and e_star > 0):
        raise ValueError(f"e_star must be a finite number > 0, got {ds.attrs['e_star']!r}")
    _check_pressure_units(ds)
    return e_star


def _checked_kappa(ds: xr.Dataset, e_star: float, converged: xr.DataArray, present: xr.DataArray,
                   kappa_rtol: float) -> xr.DataArray:
    """``kappa = E* h' / pbar`` [1] over the dims of ``mean_contact_pressure``, NaN where ``pbar <= 0``.

    Checked first: ``pbar == p0 / (A/A0)`` to ``kappa_rtol`` at the converged steps of present
    cases with ``A/A0 > 0``, then a stored ``kappa`` against the recomputed one wherever both
    are finite; ``ValueError`` naming the first offending case and step otherwise.
    ``converged`` and ``present`` are boolean masks broadcastable to ``pbar``.
    """
    pbar = ds["mean_contact_pressure"]
    a = ds["area_fraction"]
    p0 = ds["pressure"]
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = e_star * ds["rms_slope"] / pbar
        pbar_check = p0 / a
    kappa = kappa.where(np.isfinite(kappa) & (pbar > 0))
    usable = converged & (a > 0) & np.isfinite(pbar) & present
    bad = usable & ~(abs(pbar - pbar_check) <= kappa_rtol * abs(pbar_check))
    if bool(bad.any()):
        raise ValueError("mean_contact_pressure differs from pressure / area_fraction beyond "
                         f"rtol={kappa_rtol} at {first_bad_case(bad)}")
    if "kappa" in ds:
        both = np.isfinite(ds["kappa"]) & np.isfinite(kappa)
        bad = both & ~(abs(ds["kappa"] - kappa) <= kappa_rtol * abs(kappa))
        if bool(bad.any()):
            raise ValueError("stored kappa differs from e_star * rms_slope / mean_contact_pressure "
                             f"beyond rtol={kappa_rtol} at {first_bad_case(bad)}")
    return kappa.transpose(*pbar.dims)


def _dpbar_dp0(ds: xr.Dataset, present: xr.DataArray, order: int, variable: str) -> xr.Variable:
    """``d pbar / d p0`` [1] by :func:`load_derivative`, dims of ``mean_contact_pressure`` (``step`` last).

    ``ValueError`` if ``step`` is not the last dimension, or (prefixed "pressure / derivative
    settings") if :func:`load_derivative` rejects the load schedule or the settings.
    """
    pbar = ds["mean_contact_pressure"]
    p0 = ds["pressure"]
    dims = pbar.dims
    if dims[-1] != "step":
        raise ValueError(f"mean_contact_pressure must have 'step' as last dimension, got {dims}")
    # Holes carry no load schedule; NaN there keeps the monotonicity check to real cases.
    p0_arr = np.where(present.broadcast_like(pbar).transpose(*dims).values,
                      p0.broadcast_like(pbar).transpose(*dims).values, np.nan)
    try:
        deriv = load_derivative(pbar.values, p0_arr, order=order, variable=variable)
    except ValueError as err:
        raise ValueError(f"pressure / derivative settings: {err}") from None
    return xr.Variable(dims, deriv, attrs={
        "units": "1",
        "long_name": "d pbar / d p0 (finite differences along the load steps)",
        "stencil": f"order-{order} Fornberg differences in {variable}"})


def _n_false(flag: xr.DataArray, present: xr.DataArray) -> xr.DataArray:
    """Steps per case where ``flag`` is False (float64; NaN where ``present`` is False), case dims in canonical
    order."""
    n_unc = (~flag).sum("step").where(present).astype(np.float64)
    return n_unc.transpose(*[d for d in (*CASE_DIMS, TOPOGRAPHY_DIM) if d in n_unc.dims])


def _check_pressure_units(ds: xr.Dataset) -> None:
    """``pressure``, ``mean_contact_pressure`` and ``e_star`` share one unit (kappa, dpbar_dp0 [1]).

    Only the units that are recorded are compared (a variable without ``units`` passes).
    """
    units = {v: ds[v].attrs["units"] for v in ("pressure", "mean_contact_pressure") if "units" in ds[v].attrs}
    if "pressure_units" in ds.attrs:
        units["e_star (attribute pressure_units)"] = ds.attrs["pressure_units"]
    if len(set(units.values())) > 1:
        raise ValueError(f"pressures must share one unit for kappa = E* h' / pbar and d pbar / d p0 to be "
                         f"dimensionless, got units {units}")


def aggregate_contact(datasets: Sequence[xr.Dataset], names: Sequence[str], *,
                      expected: Iterable[tuple] | None = None) -> xr.Dataset:
    """:func:`combine_cases` (``kind="contact"``) followed by :func:`add_derived`."""
    return add_derived(combine_cases(datasets, names, expected=expected, kind="contact"))
