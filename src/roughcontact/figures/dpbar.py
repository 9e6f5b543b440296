"""The d pbar / d p0 figure (Fig. 4): the load derivative of the mean contact pressure over A/A0,
with the CEL's power law.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..analysis.aggregate.derivatives import log_window_edges, windowed_load_slope
from ..theory.laws import cel_dpbar_dp0
from .captions import ROUTE_LEGEND
from .load_curves import (
    PAPER_CONSTANTS,
    constant_text,
    constrained_constants,
    converged_family,
    draw_unconverged,
    e_star_of,
    family_panels,
    family_unconverged,
    fit_constants,
    fit_estimates,
    has_seeds,
    n_outside,
    note_families,
    title_figure,
    unconverged_handles,
    unconverged_steps,
)
from .record import note_fit
from .style import OKABE_ITO, STYLE, family_handles, lambda_label, legend_below, plain_log_labels, require

#: Windows per decade of ``A/A0`` of the windowed ``d pbar / d p0`` (see aggregate.windowed_load_slope).
DPBAR_PER_DECADE = 6


#: Style of the paper's power law and of this run's fit in the d pbar / d p0 figure.
_PAPER_LAW_STYLE = {"color": OKABE_ITO[0], "lw": 1.0, "ls": (0, (4, 2)), "zorder": 5}


_FIT_LAW_STYLE = {"color": "0.55", "lw": 2.6, "alpha": 0.6, "ls": "-", "zorder": 4}


def _windowed_dpbar(agg: xr.Dataset, kl: float, ks: float, h: float, per_decade: int,
                    bad: xr.DataArray | None = None):
    """Seed mean and s.e.m. of the windowed ``d pbar / d p0`` of one family.

    Windows: :func:`roughcontact.analysis.aggregate.log_window_edges` of the seed-mean load curve;
    slopes per seed by :func:`roughcontact.analysis.aggregate.windowed_load_slope`, the unconverged
    steps (``bad``, :func:`unconverged_steps` of ``agg``) left out of both. Returns
    ``(a, mean, sem)``, each shape ``(n_windows,)``: mean ``A/A0`` [1], seed-mean slope [1]
    and its standard error [1] (NaN with fewer than two seeds in a window).
    """
    case = agg.sel(k_l=kl, k_s=ks, H=h)
    dims = ("seed", "step")
    a = case["area_fraction"].transpose(*dims).values
    if bad is not None:
        a = np.where(bad.sel(k_l=kl, k_s=ks, H=h).transpose(*dims).values, np.nan, a)
    pbar = case["mean_contact_pressure"].transpose(*dims).values
    p0 = case["pressure"].broadcast_like(case["area_fraction"]).transpose(*dims).values
    keep = case["case_present"].values if "case_present" in case else np.ones(a.shape[0], bool)
    a, pbar, p0 = a[keep], pbar[keep], p0[keep]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN steps
        reference = np.nanmean(a, axis=0)
    if np.sum(np.isfinite(reference) & (reference > 0)) < 2:
        return (np.array([]),) * 3
    edges = log_window_edges(reference, per_decade)
    a_w, slope = windowed_load_slope(pbar, p0, a, edges)
    n = np.isfinite(slope).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows
        mean = np.nanmean(slope, axis=0)
        sem = np.where(n >= 2, np.nanstd(slope, axis=0, ddof=1) / np.sqrt(n), np.nan)
        x = np.nanmean(a_w, axis=0)
    return x, mean, sem


def _log_bars(y: np.ndarray, sem: np.ndarray) -> np.ndarray:
    """``[lower, upper]`` bar lengths of ``+-1`` s.e.m. drawn in log space: ``y e^(+-sem/y)``.

    Symmetric on a log axis and always above zero (the lower end is ``y e^(-sem/y)``,
    not ``y - sem``); equal to ``+-sem`` to first order in ``sem/y``. Shape ``(2, n)``.
    """
    r = np.where(np.isfinite(sem), sem / y, 0.0)
    return np.vstack([y * (1.0 - np.exp(-r)), y * (np.exp(r) - 1.0)])


def _dpbar_family(ax, agg, stats, bad, family, colour, marker, style, per_decade):
    """Draw one family over its converged steps: faint finite differences, windowed slopes with
    log-space bars, and the unconverged steps' finite differences as crosses.

    ``family``: ``{"k_l": .., "k_s": .., "H": ..}``; ``bad``: :func:`unconverged_steps` of ``agg``.
    Returns ``(x_raw, y_raw, bar_lo, bar_hi, x_bad, y_bad)`` [1] of what was drawn, 1-D each, for
    the axis limits and the count of unconverged steps.
    """
    s = converged_family(agg, stats, bad, family, ("area_fraction_mean", "dpbar_dp0_mean"))
    xr_, yr_ = s["area_fraction_mean"], s["dpbar_dp0_mean"]
    raw = np.isfinite(xr_) & np.isfinite(yr_) & (xr_ > 0) & (yr_ > 0)
    ax.plot(xr_[raw], yr_[raw], ls="none", marker=marker, ms=1.6, color=colour, alpha=0.35, mew=0, zorder=2)
    x, y, sem = _windowed_dpbar(agg, family["k_l"], family["k_s"], family["H"], per_decade, bad)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    bars = _log_bars(y[ok], sem[ok])
    ax.errorbar(x[ok], y[ok], yerr=bars, color=colour, marker=marker, ls=style, ms=3.5,
                elinewidth=0.8, capsize=2.0, zorder=3)
    x_bad, y_bad = family_unconverged(agg, bad, family, "area_fraction", "dpbar_dp0")
    draw_unconverged(ax, x_bad, y_bad)
    return xr_[raw], yr_[raw], y[ok] - bars[0], y[ok] + bars[1], x_bad, y_bad


#: The constants of the power law ``beta (A0/A)^mu``: name, mathtext, index in ``(kappa, mu, beta)``.
_LAW_CONSTANTS = (("beta", r"$\beta$", 2), ("mu", r"$\mu$", 1))


def _fit_law_label(estimates: Mapping[str, tuple[float, float, float]], ks: float, many: bool, estimator: str,
                   cel_kl: float, constrained: Mapping[str, bool] | None = None) -> str:
    """Legend text of the fitted power law: its route, the value of each of beta and mu that the data
    constrain, rounded to its interval (:func:`~.load_curves.constant_text`), and "not constrained by the data"
    for the others (an interval wider than the value is no number), e.g. ``mu = 0.54, beta not constrained by
    the data``.

    ``estimates``: :func:`~.load_curves.fit_estimates`; ``constrained``: per name (default: all constrained).
    """
    where = lambda_label(cel_kl, "l") + (", " + lambda_label(ks, "s") if many else "")
    constrained = constrained or {}
    parts = [constant_text(name, estimates[name]) for name, _, _ in _LAW_CONSTANTS if constrained.get(name, True)]
    loose = [tex for name, tex, _ in _LAW_CONSTANTS if not constrained.get(name, True)]
    if loose:
        parts.append(", ".join(loose) + " not constrained by the data")
    return rf"fitted ({ROUTE_LEGEND[estimator]}), {where}: " + ", ".join(parts)


def fig_dpbar(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
              k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
              hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
              estimator: str = "paper", per_decade: int = DPBAR_PER_DECADE) -> Figure:
    """``d pbar / d p0`` versus ``A/A0`` on log-log axes (the paper's Fig. 4).

    Large markers: per seed, the least-squares slope of ``pbar`` against ``p0`` over
    windows of equal width ``1/per_decade`` decade in ``A/A0`` (merged where the load
    steps are sparse; :func:`roughcontact.analysis.aggregate.windowed_load_slope`), averaged over
    seeds, with ``+-1`` s.e.m. bars drawn in log space (``y e^(+-sem/y)``, always above
    zero); non-positive values cannot be drawn on the log axis and are left out. Small
    faint markers: the seed mean of the pointwise finite differences
    (``dpbar_dp0_mean``); those outside the axis range are counted in the legend. Steps
    whose solve did not converge (``agg.converged`` False) are left out of both and drawn
    as grey crosses, counted in the legend. Lines: the paper's ``0.21 (A0/A)^0.55``
    (black dashed) and, with ``fit``, the fitted ``beta (A0/A)^mu`` of ``fit_k_l`` (thick
    grey); the legend gives the value of each of mu and beta that the data constrain and
    says "not constrained" of the others (:func:`constrained_constants`).

    Parameters
    ----------
    agg : xarray.Dataset
        Combined contact dataset with ``pressure``, ``mean_contact_pressure`` and
        ``area_fraction`` over ``(k_l, k_s, H, seed, step)`` and the attr ``e_star``;
        optionally ``converged`` (and then ``dpbar_dp0``) over the same dims.
    stats, fit, k_l, k_s, hurst, fit_k_l, estimator
        As in :func:`fig_area_load`.
    per_decade : int
        Windows per decade of ``A/A0`` (>= 1).

    Returns
    -------
    matplotlib.figure.Figure
    """
    require(stats, "stats", ("dpbar_dp0_mean", "area_fraction_mean", "n_seeds"))
    require(agg, "agg", ("pressure", "mean_contact_pressure", "area_fraction"))
    e_star_of(agg)
    bad = unconverged_steps(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    fit_handles, counts = [], (0, 0, 0)  # faint points off the axis, unconverged steps, those off the axes
    with matplotlib.rc_context(STYLE):
        for idx, ks in enumerate(ks_list):
            families = [{"k_l": kl, "k_s": ks, "H": h} for kl in kl_list for h in h_list if has_seeds(stats, kl, ks, h)]
            label, *panel_counts = _dpbar_ks_panel(axes.flat[idx], agg, stats, fit, bad, families, colour, marker,
                                                   style, cel_kl, ks, estimator, len(ks_list) > 1, per_decade)
            fit_handles += [Line2D([], [], **{k: v for k, v in _FIT_LAW_STYLE.items() if k != "zorder"},
                                   label=label)] if label else []
            counts = tuple(c + d for c, d in zip(counts, panel_counts, strict=True))
        n_off, n_bad, n_bad_off = counts
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = family_handles(kl_list, h_list, colour, marker, style)
        handles += _dpbar_handles(per_decade, n_off) + unconverged_handles(n_bad, n_bad_off) + fit_handles
        note_families(fig, [(kl, ks, h) for ks in ks_list for kl in kl_list for h in h_list
                            if has_seeds(stats, kl, ks, h)])
        title_figure(fig, agg, stats)
        legend_below(fig, handles, r"bars: $\pm 1$ s.e.m. over seeds, in log space ($y\,e^{\pm s/y}$)")
    return fig


def _dpbar_ks_panel(ax, agg, stats, fit, bad, families, colour, marker, style, cel_kl: float, ks: float,
                    estimator: str, many: bool, per_decade: int) -> tuple[str, int, int, int]:
    """Draw the panel of one ``k_s``: its ``families`` (:func:`_dpbar_family`) and, where any point
    can be drawn on log axes, the power laws, limits and labels (:func:`_dpbar_panel`).

    Returns ``(label, n_off, n_bad, n_bad_off)``: the fitted law's legend text ("" without one),
    the faint finite differences outside the axis range, the unconverged steps and those of them
    outside the axes (all of them in a panel with nothing drawable).
    """
    drawn = [_dpbar_family(ax, agg, stats, bad, family, colour[family["H"]], marker[family["k_l"]],
                           style[family["k_l"]], per_decade) for family in families]
    x_raw, y_raw, lo, hi, x_bad, y_bad = (np.concatenate(v) for v in zip(*drawn, strict=True))
    if x_raw.size == 0 or lo.size == 0:
        return "", 0, x_bad.size, x_bad.size  # nothing drawable on log axes in this panel
    label = _dpbar_panel(ax, fit, cel_kl, ks, estimator, many, x_raw, lo, hi)
    n_off = int(np.sum((y_raw < ax.get_ylim()[0]) | (y_raw > ax.get_ylim()[1])))
    return label, n_off, x_bad.size, n_outside(ax, x_bad, y_bad)


def _dpbar_panel(ax, fit, cel_kl: float, ks: float, estimator: str, many: bool, x_raw, lo, hi) -> str:
    """The paper's and the fitted power law of one panel, its limits and labels.

    ``x_raw``: the drawn ``A/A0`` [1]; ``lo``, ``hi``: ends of the drawn bars [1], 1-D each.
    Returns the fitted law's legend text (:func:`_fit_law_label`), "" without a fit.
    """
    a = np.geomspace(float(x_raw.min()), float(x_raw.max()), 100)
    lines = [cel_dpbar_dp0(a, mu=PAPER_CONSTANTS["mu"], beta=PAPER_CONSTANTS["beta"])]
    ax.plot(a, lines[0], **_PAPER_LAW_STYLE, gid="dpbar_paper")
    consts, label = fit_constants(fit, cel_kl, ks, estimator), ""
    if consts is not None:
        lines.append(cel_dpbar_dp0(a, mu=consts[1], beta=consts[2]))
        (curve,) = ax.plot(a, lines[-1], **_FIT_LAW_STYLE, gid="dpbar_fit")
        group = {"k_l": cel_kl, "k_s": ks, "H_group": "pooled"}
        constrained = constrained_constants(fit, group, estimator, ("mu", "beta"))
        label = _fit_law_label(fit_estimates(fit, group, estimator), ks, many, estimator, cel_kl, constrained)
        note_fit(ax.figure, curve, estimator, label, f"k_l = {cel_kl:g}, k_s = {ks:g}, H pooled",
                 (float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan))))
    # the range follows the window means and the laws; a bar longer than a factor 3 runs
    # off the axis rather than squeezing every other point into a sliver of it
    means = np.sqrt(lo * hi)  # bars are y e^(-s/y) .. y e^(s/y) around the mean y
    ylo = max(float(lo.min()), float(means.min()) / 3)
    ylo = min(ylo, *(float(v.min()) for v in lines)) / 1.3
    yhi = min(float(hi.max()), float(means.max()) * 3)
    yhi = max(yhi, *(float(v.max()) for v in lines)) * 1.3
    ax.set_ylim(ylo, yhi)
    ax.set_xlim(float(x_raw.min()) / 1.15, float(x_raw.max()) * 1.15)
    _dpbar_axes(ax, ks)
    return label


def _dpbar_axes(ax, ks: float) -> None:
    """Log axes with plain decimal labels (at least two on each, whatever its range: :func:`plain_log_labels`),
    title and labels of a d pbar / d p0 panel."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        plain_log_labels(axis)
    ax.set_title(lambda_label(ks, "s"))
    ax.set_xlabel(r"$A/A_0$ [1]")
    ax.set_ylabel(r"$\partial\bar p/\partial p_0$ [1]")


def _dpbar_handles(per_decade: int, n_off: int) -> list[Line2D]:
    """Legend entries of the two estimates and of the paper's power law."""
    off = f"; {n_off} outside the axis" if n_off else ""
    style = {k: v for k, v in _PAPER_LAW_STYLE.items() if k != "zorder"}
    return [
        Line2D([], [], color="0.35", marker="o", ms=3.5, ls="-",
               label=rf"least-squares slope of $\bar p(p_0)$ in windows of 1/{per_decade} decade of $A/A_0$"),
        Line2D([], [], color="0.35", marker="o", ms=1.6, alpha=0.35, ls="none",
               label=f"pointwise finite differences (faint){off}"),
        Line2D([], [], **style, label=r"paper: $\beta\,(A_0/A)^{\mu}$, $\beta$ = 0.21, $\mu$ = 0.55"),
    ]
