"""Which settings produced which case, once cases are combined into one file.

Every per-case file records the exact parameters of the jobs behind it (its
``scene_parameters`` attribute, see :mod:`roughcontact.pipeline.params`). A combined file must not
claim one set of settings for all its cases when a targeted rerun solved some of them
differently: :func:`split_settings` finds what all cases share and what varies, and
:func:`settings_variables` turns each varying setting into a per-case variable.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from ..analysis.aggregate.combine import CASE_DIMS, TOPOGRAPHY_DIM
from .params import recorded

#: Prefix of the per-case variables that hold a varying setting.
PREFIX = "setting_"


def flatten(tree: Mapping, prefix: str = "") -> dict:
    """``{"solver": {"tol": 1e-8}}`` -> ``{"solver.tol": 1e-8}``; empty mappings stay leaves."""
    out = {}
    for key, value in tree.items():
        if isinstance(value, Mapping) and value:
            out.update(flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def unflatten(flat: Mapping) -> dict:
    """The inverse of :func:`flatten`."""
    out: dict = {}
    for dotted, value in flat.items():
        *parents, leaf = dotted.split(".")
        node = out
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return out


def split_settings(settings: Sequence[Mapping]) -> tuple[dict, list[str]]:
    """The settings every case shares (nested, as recorded) and the dotted keys that vary.

    A key missing from some cases counts as varying.
    """
    flats = [flatten(s) for s in settings]
    keys = sorted(set().union(*flats)) if flats else []
    first = flats[0] if flats else {}
    same = [k for k in keys if all(k in f and _equal(f[k], first[k]) for f in flats)]
    return unflatten({k: first[k] for k in same}), [k for k in keys if k not in same]


def _equal(a, b) -> bool:
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def case_dims(ds: xr.Dataset) -> tuple[str, ...]:
    """The case dimensions of a combined dataset: ``topography`` (measured) or ``k_l, k_s, H, seed``."""
    return (TOPOGRAPHY_DIM,) if TOPOGRAPHY_DIM in ds.dims else CASE_DIMS


def settings_variables(combined: xr.Dataset, cases: Sequence[Mapping], settings: Sequence[Mapping],
                       varying: Sequence[str]) -> dict[str, xr.DataArray]:
    """One variable over the case dims of ``combined`` per varying setting.

    ``cases[i]`` gives the case coordinates (``k_l, k_s, H, seed``, or a measured case's
    ``topography``) of ``settings[i]``.
    Numbers become float64 (NaN where no case was solved), anything else its JSON text
    (empty where no case was solved). Names are ``setting_<key with '.' as '_'>``.
    """
    dims = case_dims(combined)
    shape = tuple(combined.sizes[d] for d in dims)
    flats = [flatten(s) for s in settings]
    out = {}
    for key in varying:
        values = [f.get(key) for f in flats]
        numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
        data = np.full(shape, np.nan) if numeric else np.full(shape, "", dtype=object)
        da = xr.DataArray(data, dims=dims, coords={d: combined[d] for d in dims})
        for case, value in zip(cases, values, strict=True):
            da.loc[{d: case[d] for d in dims}] = float(value) if numeric else json.dumps(value, sort_keys=True)
        da.attrs = {"units": "1", "long_name": f"setting '{key}' of each case (it differs between cases)"}
        if numeric:
            da.attrs["allow_nan"] = 1
        out[PREFIX + key.replace(".", "_")] = da
    return out


def attach_settings(combined: xr.Dataset, datasets: Sequence[xr.Dataset]) -> tuple[xr.Dataset, dict, list[str]]:
    """``combined`` with a variable per varying setting, the shared settings, the varying keys.

    ``datasets`` are the per-case files ``combined`` was made from; each one's recorded
    parameters (:func:`roughcontact.pipeline.params.recorded`) are its settings.
    """
    settings = [recorded(ds) for ds in datasets]
    cases = [{d: ds[d].values[0] for d in case_dims(combined)} for ds in datasets]
    common, varying = split_settings(settings)
    return combined.assign(settings_variables(combined, cases, settings, varying)), common, varying
