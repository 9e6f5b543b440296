"""Which cases enter a fit: those with an unconverged load step are marked absent.
"""

from __future__ import annotations

import xarray as xr

from ..aggregate.combine import TOPOGRAPHY_DIM


# --------------------------------------------------------------------------- public
def is_topography_layout(agg: xr.Dataset) -> bool:
    """Whether an aggregate is a measured scene's (cases along ``topography``) rather than a grid's."""
    return TOPOGRAPHY_DIM in agg.dims


def exclude_unconverged(agg: xr.Dataset) -> tuple[xr.Dataset, list[tuple[float, float, float, int]] | list[str]]:
    """``agg`` with every case that has an unconverged step marked absent, and those cases.

    Only ``case_present`` changes, so the other cases of a group (their pressures, load
    schedules, seeds) enter the fit untouched. Cases are ``(k_l, k_s, H, seed)`` for a
    generated scene; for a measured one (dims ``(topography, step)``) they are the
    topographies' names, and ``n_unconverged`` is counted from ``converged`` if absent.
    """
    if is_topography_layout(agg):
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
