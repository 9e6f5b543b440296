"""The CEL fit of a measured scene: all topographies pooled as one surface type.

The topographies stand in the place of the seeds (topography-mean curve for the paper route,
bootstrap over whole topographies); the same per-group machinery as the grid fit
(:func:`roughcontact.analysis.fit.bootstrap.fit_group`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from ..aggregate.combine import CASE_DIMS, TOPOGRAPHY_DIM
from ..aggregate.derived import add_derived
from .bootstrap import GroupFit, check_schedules, fit_group, group_rng, shared_schedule
from .cases import is_topography_layout, usable_steps
from .estimators import METHODS, Curves
from .settings import check_settings, check_window, estimate_vars, estimator_coords, paper_vars, settings_attrs


def _derive_topographies(agg: xr.Dataset) -> xr.Dataset:
    """``agg`` (dims ``topography, step``) with ``kappa`` and ``dpbar_dp0`` derived as for generated cases.

    :func:`roughcontact.analysis.aggregate.add_derived` works on the generated layout, so the
    topographies are mapped onto it (as seeds of one placeholder ``(k_l, k_s, H)``) and back.
    """
    case = agg.rename({TOPOGRAPHY_DIM: "seed"}).expand_dims({d: [0.0] for d in CASE_DIMS[:3]})
    derived = add_derived(case).isel({d: 0 for d in CASE_DIMS[:3]}, drop=True).rename({"seed": TOPOGRAPHY_DIM})
    out = agg.copy()
    for name in ("kappa", "dpbar_dp0", "n_unconverged"):
        dims = [d for d in (TOPOGRAPHY_DIM, "step") if d in derived[name].dims]
        out[name] = derived[name].transpose(*dims)
    return out


def _topography_curves(agg: xr.Dataset, window: tuple[float, float]) -> tuple[Curves, list[str]]:
    """The load curves of the present topographies (one row each, one stratum) and their names."""
    names = [str(t) for t in agg[TOPOGRAPHY_DIM].values]
    dims = (TOPOGRAPHY_DIM, "step")
    present = (agg["case_present"].transpose(TOPOGRAPHY_DIM).values.astype(bool) if "case_present" in agg
               else np.ones(len(names), bool))

    def steps(name, dtype=float):
        return agg[name].broadcast_like(agg["area_fraction"]).transpose(*dims).values.astype(dtype)[present]

    a = steps("area_fraction")
    valid = usable_steps(agg).broadcast_like(agg["area_fraction"]).transpose(*dims).values[present] & np.isfinite(a)
    hp = agg["rms_slope"].transpose(TOPOGRAPHY_DIM).values.astype(float)[present]
    curves = Curves(a, steps("pressure"), hp, steps("kappa"), steps("dpbar_dp0"), valid,
                     np.zeros(a.shape[0], dtype=int), window)
    return curves, [n for n, p in zip(names, present, strict=True) if p]


def fit_topographies(agg: xr.Dataset, *, window: tuple[float, float] = (0.01, 0.11), n_boot: int = 200,
                     rng_seed: int = 2012, methods: Sequence[str] = METHODS, min_points: int = 6,
                     kappa_extrapolation: str = "cel", paper_average: str = "seeds",
                     confidence: float = 0.95, on_insufficient: str = "nan") -> xr.Dataset:
    """Fit the CEL constants to all topographies of a measured scene, pooled as one surface type.

    The topographies play the part of :func:`fit_cel`'s seeds in one group (same estimators; the
    bootstrap resamples whole topographies). With one topography the bootstrap columns are NaN
    and ``n_boot_ok`` is 0. Topographies with ``case_present == False`` are left out.

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
        The fit settings of :mod:`.settings`; the bootstrap stream is keyed by ``rng_seed`` alone.
    paper_average : {"seeds", "none", "auto"}
        ``"seeds"``: the paper route fits the topography-mean curve (needs one normalised load
        schedule ``p0 / (E* h')`` for all); ``"none"``: every (topography, step) point; ``"auto"``:
        ``"seeds"`` where the schedules agree, else ``"none"`` (the result's ``paper_average``).
    on_insufficient : {"nan", "raise"}
        Default ``"nan"``: a measured surface may simply not reach the window.

    Returns
    -------
    xarray.Dataset
        Dims ``estimator``, ``constant`` and ``topography``. Variables, all with units "1":
        ``value``, ``stderr``, ``bootstrap_stderr``, ``ci_low``, ``ci_high``, ``constrained``,
        ``n_points(estimator, constant)``, ``n_boot_ok(estimator)``, ``n_topographies`` (scalar,
        topographies fitted), ``in_fit(topography)`` (1 if it entered the fit),
        ``alpha_surfaces`` (scalar, mean Nayak alpha of the fitted topographies, NaN if
        ``agg`` has no ``alpha``), ``paper_value(constant)``, ``paper_stderr(constant)``; attrs
        the settings, as :func:`fit_cel`'s, and ``layout = "topographies"``.
    """
    _check_topography_aggregate(agg)
    if "dpbar_dp0" not in agg or "kappa" not in agg:
        agg = _derive_topographies(agg)
    curves, fitted = _topography_curves(agg, check_window(window))
    if paper_average == "auto":
        paper_average = "seeds" if shared_schedule(curves) else "none"
    (lo, hi), methods = check_settings(window, n_boot, rng_seed, methods, min_points, kappa_extrapolation,
                                        confidence, paper_average, on_insufficient)
    e_star = float(agg.attrs["e_star"])
    if paper_average == "seeds" and "paper" in methods and curves.n_seeds:
        check_schedules(curves, ["fit_topographies: the topographies"])
    res = GroupFit(len(methods))
    if curves.n_seeds:
        res = fit_group(curves, methods=methods, e_star=e_star, min_points=min_points,
                         kappa_extrapolation=kappa_extrapolation, paper_average=paper_average, n_boot=n_boot,
                         confidence=confidence, rng=group_rng(rng_seed, 0.0, 0.0, "topographies"),
                         on_insufficient=on_insufficient, caller="fit_topographies",
                         where=f"{curves.n_seeds} topographies pooled", window=window)
    attrs = {**settings_attrs(lo, hi, n_boot, rng_seed, confidence, min_points, kappa_extrapolation,
                               paper_average, e_star), "layout": "topographies"}
    return _topography_dataset(agg, res, curves.n_seeds, fitted, methods, confidence, attrs)


def _check_topography_aggregate(agg: xr.Dataset) -> None:
    """ValueError unless ``agg`` is a measured scene's contact aggregate that :func:`fit_topographies` can fit.

    It needs dims ``(topography, step)`` and no generated-case dim, the variables
    ``area_fraction, pressure, converged, rms_slope`` and the global attribute ``e_star``.
    """
    if not is_topography_layout(agg) or "step" not in agg.dims:
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


def _topography_dataset(agg: xr.Dataset, res: GroupFit, n_fitted: int, fitted: list[str],
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
            **estimate_vars(dims, res.value, res.stderr, res.bstd, res.clo, res.chi, res.npts,
                             confidence=confidence, resampled="topographies", methods=methods,
                             points="paper route with paper_average='seeds': topography-mean points, one per step"),
            "n_topographies": ((), np.int64(n_fitted), {**one, "long_name": "number of topographies fitted"}),
            "n_boot_ok": (dims[:1], res.nboot_ok, {**one, "long_name": "bootstrap resamples that fitted"}),
            "in_fit": ((TOPOGRAPHY_DIM,), in_fit, {**one, "long_name": "1 if the topography entered the fit, "
                                                   "0 if excluded (e.g. unconverged steps)"}),
            "alpha_surfaces": ((), alpha_surf, {**one, "long_name": "mean Nayak alpha of the fitted "
                                                "topographies (agg variable alpha; NaN if absent)"}),
            **paper_vars(),
        },
        coords={
            TOPOGRAPHY_DIM: (TOPOGRAPHY_DIM, np.array([str(t) for t in names], dtype=object),
                             {"units": "1", "long_name": "name of the measured topography"}),
            **estimator_coords(methods),
        },
        attrs=attrs,
    )
