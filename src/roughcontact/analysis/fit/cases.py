"""Which cases and steps enter a fit: cases with an unconverged load step are marked absent; of the others, the
steps that converged and whose contact the grid resolves (:func:`usable_steps`).

An *unresolved* step (``contact_resolved`` False: its largest contact patch holds fewer than 4 nodes,
:mod:`roughcontact.statistics.patches`) is a solved step, but its A/A0 is set by the grid, not by the load: it
climbs in stairs, flat while the load rises until the next node touches, so that ``d pbar / d p0 = 1/(A/A0)`` there
and kappa = E* h' A/(A0 p0) falls as 1/p0 along the plateau. It is left out of the fit like an unconverged step
(whose values are not the solution), step by step: the case's resolved steps still enter. It is not left out
silently: the fit job logs how many steps in the window it left out (:func:`unresolved_in_window`) and the
load-curve figures draw them. At the paper's resolution no step is unresolved (at A/A0 ~ 0.005 the largest patch
holds 79 to 134 nodes in three of its cases at N = 1024), nor in the demo, so their fits are unchanged; files of
older versions carry no flag, and all their converged steps enter.
"""

from __future__ import annotations

import xarray as xr

from ..aggregate.combine import TOPOGRAPHY_DIM


# --------------------------------------------------------------------------- public
def usable_steps(agg: xr.Dataset) -> xr.DataArray:
    """The steps a fit takes (bool, dims of ``agg.converged``): converged and, where ``agg`` carries
    ``contact_resolved``, resolved (the module docstring says why)."""
    ok = agg["converged"].astype(bool)
    return ok & agg["contact_resolved"].astype(bool) if "contact_resolved" in agg else ok


def unresolved_in_window(agg: xr.Dataset, window: tuple[float, float]) -> int:
    """How many converged steps of the present cases with ``window[0] <= A/A0 <= window[1]`` are unresolved, and
    so left out of the fit (0 without ``contact_resolved``)."""
    if "contact_resolved" not in agg:
        return 0
    a = agg["area_fraction"]
    present = agg["case_present"].astype(bool) if "case_present" in agg else True
    inside = (a >= window[0]) & (a <= window[1]) & agg["converged"].astype(bool) & present
    return int((inside & ~agg["contact_resolved"].astype(bool)).sum())


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
