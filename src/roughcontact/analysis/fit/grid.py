"""The CEL fit of a generated scene: per ``(k_l, k_s, H)`` and per ``(k_l, k_s)`` pooled over H.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from ...theory.spectra import power_law_alpha
from ..aggregate.combine import CASE_DIMS, is_profiles
from ..aggregate.derived import add_derived
from .bootstrap import GroupFit, check_schedules, fit_group, group_rng, shared_schedule
from .cases import usable_steps
from .estimators import CONSTANTS, METHODS, POOLED, Curves
from .settings import check_settings, estimate_vars, estimator_coords, h_label, paper_vars, settings_attrs


def _group_curves(agg: xr.Dataset, k_l: float, k_s: float, hs: Sequence[float],
                  window: tuple[float, float]) -> Curves:
    rows = []
    for j, h in enumerate(hs):
        sub = agg.sel(k_l=k_l, k_s=k_s, H=h)
        present = sub["case_present"].values if "case_present" in sub else np.ones(sub.sizes["seed"], bool)
        for s in np.flatnonzero(present):
            case = sub.isel(seed=s)
            a = case["area_fraction"].transpose("step").values.astype(float)
            conv = usable_steps(case).transpose("step").values
            row = (a,
                   case["pressure"].transpose("step").values.astype(float),
                   float(case["rms_slope"].values),
                   case["kappa"].transpose("step").values.astype(float),
                   case["dpbar_dp0"].transpose("step").values.astype(float),
                   conv & np.isfinite(a),
                   j)
            rows.append(row)
    if not rows:
        n = agg.sizes["step"]
        empty = np.empty((0, n))
        return Curves(empty, empty, np.empty(0), empty, empty, np.empty((0, n), bool),
                       np.empty(0, int), window)
    cols = list(zip(*rows, strict=True))
    return Curves(np.array(cols[0]), np.array(cols[1]), np.array(cols[2]), np.array(cols[3]),
                   np.array(cols[4]), np.array(cols[5]), np.array(cols[6], dtype=int), window)


def fit_cel(agg: xr.Dataset, *, window: tuple[float, float] = (0.01, 0.11), n_boot: int = 200,
            rng_seed: int = 2012, methods: Sequence[str] = METHODS, min_points: int = 6,
            kappa_extrapolation: str = "cel", paper_average: str = "seeds",
            confidence: float = 0.95, on_insufficient: str = "raise") -> xr.Dataset:
    """Fit the CEL constants per ``(k_l, k_s, H)`` and per ``(k_l, k_s)`` pooled over H.

    Parameters
    ----------
    agg : xarray.Dataset
        Combined contact dataset (:func:`roughcontact.analysis.aggregate.combine_cases`), dims
        ``(k_l, k_s, H, seed, step)``, global attr ``e_star``; ``kappa`` and
        ``dpbar_dp0`` are derived if absent.
    window, n_boot, rng_seed, methods, min_points, kappa_extrapolation, paper_average, confidence, on_insufficient
        The fit settings, each described in :mod:`.settings` (default ``on_insufficient="raise"``).

    Returns
    -------
    xarray.Dataset
        Dims ``k_l, k_s, H_group`` (one label per H, e.g. ``"0.36"``, then ``"pooled"``;
        float coordinate ``H_value`` along it, NaN for pooled), ``estimator`` (the
        ``methods`` run; not called "method", which ``xarray``'s ``.sel`` reserves), ``constant``
        (``kappa, mu, beta``). Variables, all with units "1":
        ``value``, ``stderr`` (the estimator's own), ``bootstrap_stderr``, ``ci_low``,
        ``ci_high`` (percentile interval), ``n_points(k_l, k_s, H_group, estimator, constant)``,
        ``n_seeds(k_l, k_s, H_group)`` (the group's surfaces: for a group pooled over H, each H's seeds
        summed), ``constrained(k_l, k_s, H_group, estimator, constant)`` (0 where the data do not
        constrain the constant, :func:`~.estimators.constrained_flags`),
        ``n_boot_ok(k_l, k_s, H_group, estimator)``,
        ``alpha_power_law(k_l, k_s, H_group)`` (Nayak alpha of the ideal spectrum, a profile's
        own when ``agg`` holds profiles, :func:`~roughcontact.analysis.aggregate.is_profiles`;
        NaN when pooled), ``alpha_surfaces(k_l, k_s, H_group)`` (mean of ``agg.alpha`` over the
        group's cases), ``paper_value(constant)``, ``paper_stderr(constant)``. Groups
        without any case are NaN with ``n_seeds = 0``. Attrs record the settings.
    """
    for dim in CASE_DIMS + ("step",):
        if dim not in agg.dims:
            raise ValueError(f"agg lacks dimension {dim!r}; pass the output of combine_cases")
    if "dpbar_dp0" not in agg or "kappa" not in agg:
        agg = add_derived(agg)
    if paper_average == "auto":
        paper_average = "seeds" if _seeds_share_schedules(agg, window) else "none"
    (lo, hi), methods = check_settings(window, n_boot, rng_seed, methods, min_points, kappa_extrapolation,
                                       confidence, paper_average, on_insufficient)
    e_star = float(agg.attrs["e_star"])

    kls, kss, hs = (agg[d].values for d in ("k_l", "k_s", "H"))
    labels = [h_label(h) for h in hs] + [POOLED]
    grid = _CelGrid((len(kls), len(kss), len(labels), len(methods), len(CONSTANTS)))
    fit_kw = dict(methods=methods, e_star=e_star, min_points=min_points, kappa_extrapolation=kappa_extrapolation,
                  paper_average=paper_average, n_boot=n_boot, confidence=confidence,
                  on_insufficient=on_insufficient, window=window)
    for i, kl in enumerate(kls):
        for j, ks in enumerate(kss):
            for g, label in enumerate(labels):
                group_hs = list(hs) if label == POOLED else [hs[g]]
                _fit_cel_group(agg, grid, (i, j, g), kl, ks, group_hs, label, (lo, hi), rng_seed, fit_kw)
    return _cel_dataset(agg, grid, labels, methods, confidence,
                        settings_attrs(lo, hi, n_boot, rng_seed, confidence, min_points, kappa_extrapolation,
                                        paper_average, e_star))


def _seeds_share_schedules(agg: xr.Dataset, window) -> bool:
    """Whether the seeds of every ``(k_l, k_s, H)`` share one load schedule p0/(E* h') (``paper_average='auto'``).

    They do when loaded by ``load.p_max``; with ``load.target_area`` each seed ends at its own p0.
    """
    bounds = tuple(float(v) for v in window)
    return all(shared_schedule(_group_curves(agg, kl, ks, [h], bounds))
               for kl in agg["k_l"].values for ks in agg["k_s"].values for h in agg["H"].values)


class _CelGrid:
    """:func:`fit_cel`'s result arrays, filled group by group.

    ``value, stderr, bstd, clo, chi`` (float, NaN: not fitted) and ``npts`` (int) have the
    shape ``(k_l, k_s, H_group, estimator, constant)``; ``nboot_ok`` the first four of those
    dims; ``nseeds`` (int), ``alpha`` and ``alpha_surf`` (float, NaN: none) the first three.
    """

    def __init__(self, shape5: tuple[int, int, int, int, int]):
        self.value, self.stderr, self.bstd, self.clo, self.chi = (np.full(shape5, np.nan) for _ in range(5))
        self.npts = np.zeros(shape5, dtype=np.int64)
        self.nseeds = np.zeros(shape5[:3], dtype=np.int64)
        self.nboot_ok = np.zeros(shape5[:4], dtype=np.int64)
        self.alpha = np.full(shape5[:3], np.nan)
        self.alpha_surf = np.full(shape5[:3], np.nan)

    def store(self, idx: tuple[int, int, int], res: GroupFit) -> None:
        """Copy one group's fit into position ``idx = (i_k_l, i_k_s, i_H_group)``."""
        self.value[idx], self.stderr[idx], self.npts[idx] = res.value, res.stderr, res.npts
        self.bstd[idx], self.clo[idx], self.chi[idx] = res.bstd, res.clo, res.chi
        self.nboot_ok[idx] = res.nboot_ok


def _fit_cel_group(agg: xr.Dataset, grid: _CelGrid, idx: tuple[int, int, int], kl: float, ks: float,
                   group_hs: list[float], label: str, bounds: tuple[float, float], rng_seed: int,
                   fit_kw: dict) -> None:
    """Fit the group ``(kl, ks, group_hs)`` (H label ``label``) of ``agg`` into ``grid[idx]``.

    ``bounds`` is the checked window ``(low, high)`` of ``A/A0``; ``fit_kw`` holds
    :func:`fit_group`'s settings (with the window as the user passed it, for messages). A group without cases only gets
    ``n_seeds = 0``.
    """
    curves = _group_curves(agg, kl, ks, group_hs, bounds)
    grid.nseeds[idx] = curves.n_seeds
    if curves.n_seeds == 0:
        return
    if fit_kw["paper_average"] == "seeds" and "paper" in fit_kw["methods"]:
        check_schedules(curves, [f"fit_cel: seeds at k_l={kl:g}, k_s={ks:g}, H={h_label(h)}"
                                  for h in group_hs])
    if label != POOLED and kl < ks:
        grid.alpha[idx] = power_law_alpha(kl, ks, group_hs[0], dimension=1 if is_profiles(agg) else 2)
    if "alpha" in agg:
        grid.alpha_surf[idx] = _mean_alpha_surfaces(agg, kl, ks, group_hs)
    res = fit_group(curves, rng=group_rng(rng_seed, kl, ks, label), caller="fit_cel",
                     where=f"k_l={kl:g}, k_s={ks:g}, H={label}", **fit_kw)
    grid.store(idx, res)


def _mean_alpha_surfaces(agg: xr.Dataset, kl: float, ks: float, group_hs: list[float]) -> float:
    """Mean of ``agg.alpha`` [1] over the present cases of the group ``(kl, ks, group_hs)``."""
    sub = agg["alpha"].sel(k_l=kl, k_s=ks, H=group_hs)
    if "case_present" in agg:
        sub = sub.where(agg["case_present"].sel(k_l=kl, k_s=ks, H=group_hs))
    return float(sub.mean(skipna=True))


def _cel_dataset(agg: xr.Dataset, grid: _CelGrid, labels: list[str], methods: Sequence[str],
                 confidence: float, attrs: dict) -> xr.Dataset:
    """:func:`fit_cel`'s result dataset from the filled ``grid``; ``agg`` gives the k_l, k_s, H coordinates."""
    kls, kss, hs = (agg[d].values for d in ("k_l", "k_s", "H"))
    dims5 = ("k_l", "k_s", "H_group", "estimator", "constant")
    one = {"units": "1"}
    return xr.Dataset(
        {
            **estimate_vars(dims5, grid.value, grid.stderr, grid.bstd, grid.clo, grid.chi, grid.npts,
                             confidence=confidence, resampled="seeds", methods=methods,
                             points="paper route with paper_average='seeds': seed-mean points, one per H and step"),
            "n_seeds": (dims5[:3], grid.nseeds, {**one, "long_name": "number of surfaces in the group: its seeds, "
                                                 "summed over its values of H (for a group pooled over H)"}),
            "n_boot_ok": (dims5[:4], grid.nboot_ok, {**one, "long_name": "bootstrap resamples that fitted"}),
            "alpha_power_law": (dims5[:3], grid.alpha, {**one, "long_name": "Nayak alpha of the ideal "
                                "continuous power-law spectrum (NaN for pooled groups; 20-60 % low "
                                "for k_l = 1, see theory.discrete_power_law_moments)"}),
            "alpha_surfaces": (dims5[:3], grid.alpha_surf, {**one, "long_name": "mean Nayak alpha of the "
                               "group's generated surfaces (agg variable alpha; NaN if absent)"}),
            **paper_vars(),
        },
        coords={
            "k_l": ("k_l", kls.astype(np.float64), dict(agg["k_l"].attrs)),
            "k_s": ("k_s", kss.astype(np.float64), dict(agg["k_s"].attrs)),
            "H_group": ("H_group", np.array(labels, dtype=object),
                        {"units": "1", "long_name": "Hurst exponent of the group, or 'pooled' over all H"}),
            "H_value": ("H_group", np.append(hs.astype(np.float64), np.nan),
                        {"units": "1", "long_name": "Hurst exponent (NaN: pooled)"}),
            **estimator_coords(methods),
        },
        attrs=attrs,
    )
