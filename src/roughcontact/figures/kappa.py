"""The kappa figure (Fig. 3): kappa = E* h' A/(A0 p0) over A/A0 with the CEL and the theories' kappa.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..theory.asperity import asperity_kappa
from ..theory.laws import KAPPA_BGT, KAPPA_PERSSON, cel_kappa
from .captions import REFERENCE_STYLES
from .load_curves import (
    ASPERITY_STYLES,
    BGT_LIMIT_LABEL,
    PAPER_CEL_LABEL,
    PAPER_CONSTANTS,
    PERSSON_LIMIT_STYLE,
    asperity_alphas,
    asperity_gid,
    asperity_handles,
    asperity_style,
    converged_family,
    draw_unconverged,
    e_star_of,
    family_panels,
    family_unconverged,
    fit_constants,
    has_seeds,
    n_outside,
    record_panels,
    reference_style,
    unconverged_handles,
    unconverged_steps,
)
from .style import STYLE, family_handles, lambda_label, legend_below, require
from .unresolved import mark_unresolved, shown_cases, unresolved_handles


def kappa_theory(ax, amax: float, alphas, ylo: float, yhi: float) -> list:
    """BGT and Persson limits, the paper's CEL and the asperity models on ``[0, amax]``; sets the y
    limits from ``[ylo, yhi]`` (data) and the asperity curves; returns the legend entries."""
    ax.axhline(KAPPA_BGT, **REFERENCE_STYLES["bgt_limit"], gid="bgt_limit")
    a = np.linspace(0, amax, 200)
    ax.plot(a, cel_kappa(a, **PAPER_CONSTANTS), **REFERENCE_STYLES["cel_paper"], gid="cel_paper")
    a = np.linspace(0, amax, 120)
    for alpha, shade, _ in alphas:
        for model in ASPERITY_STYLES:
            k = asperity_kappa(a, alpha=alpha, model=model)
            ax.plot(a, k, **asperity_style(model, shade), gid=asperity_gid(model, alpha))
            ylo = min(ylo, float(np.min(k)))
    pad = 0.05 * (yhi - ylo)
    shown = ylo - pad <= KAPPA_PERSSON <= yhi + pad
    if shown:
        ax.axhline(KAPPA_PERSSON, **PERSSON_LIMIT_STYLE, zorder=3, gid="persson_limit")
    ax.set_ylim(ylo - pad, yhi + pad)
    return [Line2D([], [], **reference_style("bgt_limit"), label=BGT_LIMIT_LABEL),
            Line2D([], [], **PERSSON_LIMIT_STYLE, label=(
                r"Persson small-load limit, $\kappa=\sqrt{8/\pi}$" if shown
                else rf"Persson, $\kappa=\sqrt{{8/\pi}}$ = {KAPPA_PERSSON:.2f}: below the axis")),
            *asperity_handles(alphas),
            Line2D([], [], **reference_style("cel_paper"), label=PAPER_CEL_LABEL)]


def _kappa_panel(ax, agg, stats, bad, families, colour, marker, style):
    """Seed-mean ``kappa(A/A0)`` with s.e.m. bars of each family ``(kl, ks, h)`` of one panel over
    its converged steps (:func:`converged_family`), and its unconverged steps as crosses.

    Returns ``(amax, ylo, yhi, (x, y))``: the largest mean ``A/A0`` [1], the range of mean -+ s.e.m.
    [1], and ``A/A0``, ``kappa`` [1] of the unconverged steps, shape ``(n,)`` each.
    """
    amax, ylo, yhi, crosses = 0.0, np.inf, -np.inf, [(np.array([]), np.array([]))]
    for kl, ks, h in families:
        family = {"k_l": kl, "k_s": ks, "H": h}
        v = converged_family(agg, stats, bad, family, ("area_fraction_mean", "kappa_mean", "kappa_sem"))
        x, y, e = v["area_fraction_mean"], v["kappa_mean"], v["kappa_sem"]
        ax.errorbar(x, y, yerr=e, color=colour[h], marker=marker[kl], ls=style[kl],
                    markevery=2, errorevery=2, elinewidth=0.6)
        if np.isfinite(x).any():  # else every step of the family failed
            amax = max(amax, float(np.nanmax(x)))
            ylo, yhi = min(ylo, float(np.nanmin(y - e))), max(yhi, float(np.nanmax(y + e)))
        crosses.append(family_unconverged(agg, bad, family, "area_fraction", "kappa"))
    x, y = (np.concatenate(v) for v in zip(*crosses, strict=True))
    draw_unconverged(ax, x, y)
    mark_unresolved(ax, agg, agg["area_fraction"], agg["kappa"], shown_cases(families))
    return amax, ylo, yhi, (x, y)


def _kappa_fit_handles(fit, label: str) -> list:
    """Legend entries of the fitted CEL (``label``: :func:`cel_fit_label`) and its window."""
    return [Line2D([], [], **reference_style("cel_fit"), label=label),
            Patch(facecolor="0.9", edgecolor="none", label=(
                f"fit window $A/A_0 \\in$ [{float(fit.attrs.get('window_low', np.nan)):g}, "
                f"{float(fit.attrs.get('window_high', np.nan)):g}]"))]


def fig_kappa(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
              k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
              hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
              estimator: str = "paper") -> Figure:
    """``kappa = E* h' / pbar`` versus ``A/A0`` (the paper's Fig. 3), one panel per ``k_s``.

    Seed means with standard-error bars per ``(lambda_l, H)`` over the converged steps: a step
    whose solve did not converge (``agg.converged`` False) is left out of the means and drawn
    as a grey cross, and the legend counts those steps (none without ``converged``). The BGT
    limit ``sqrt(2 pi)`` (Persson's ``sqrt(8/pi) ~ 1.60`` lies below the usual range and is
    only drawn if inside it); with ``fit``, the CEL's ``kappa(a) = kappa (1 - beta
    a^(1-mu))^(1/(1-mu))`` of ``fit_k_l`` and the fit window (shaded).

    Parameters
    ----------
    agg : xarray.Dataset
        As in :func:`fig_area_load`; where some ``converged(k_l, k_s, H, seed, step)`` is False
        it must hold ``area_fraction`` and ``kappa`` [1] over the same dims.
    stats, fit, k_l, k_s, hurst, fit_k_l, estimator
        As in :func:`fig_area_load`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    require(stats, "stats", ("kappa_mean", "kappa_sem", "area_fraction_mean", "n_seeds"))
    e_star_of(agg)
    alphas, bad = asperity_alphas(agg), unconverged_steps(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(STYLE):
        drew_fit, n_bad, n_off = False, 0, 0
        for idx, ks in enumerate(ks_list):
            ax = axes.flat[idx]
            families = [(kl, ks, h) for kl in kl_list for h in h_list if has_seeds(stats, kl, ks, h)]
            amax, ylo, yhi, crosses = _kappa_panel(ax, agg, stats, bad, families, colour, marker, style)
            consts = fit_constants(fit, cel_kl, ks, estimator)
            if consts is not None:
                a = np.linspace(0, amax, 200)
                ax.plot(a, cel_kappa(a, kappa=consts[0], mu=consts[1], beta=consts[2]),
                        **REFERENCE_STYLES["cel_fit"], gid="cel_fit")
                ax.axvspan(float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan)),
                           color="0.9", zorder=0, lw=0, gid="fit_window")
                ylo, yhi = min(ylo, consts[0]), max(yhi, consts[0])
                drew_fit = True
            theory = kappa_theory(ax, amax, alphas, min(ylo, KAPPA_BGT), max(yhi, KAPPA_BGT))
            ax.set_xlim(0, amax * 1.02)
            ax.set_title(lambda_label(ks, "s"))
            ax.set_xlabel(r"$A/A_0$ [1]")
            ax.set_ylabel(r"$\kappa = E^* h'/\bar p$ [1]")
            n_bad, n_off = n_bad + crosses[0].size, n_off + n_outside(ax, *crosses)
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = family_handles(kl_list, h_list, colour, marker, style) + theory
        handles += unconverged_handles(n_bad, n_off) + unresolved_handles(fig)
        label = record_panels(fig, axes.flat, agg, stats, (kl_list, ks_list, h_list), fit, cel_kl, estimator, drew_fit)
        if label is not None:
            handles += _kappa_fit_handles(fit, label)
        legend_below(fig, handles, "error bars: s.e.m.")
    return fig
