"""The area-load figure (Fig. 2): A/A0 over p0/(E* h') with the CEL, Persson and the asperity theories.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import matplotlib
import matplotlib.colors as mcolors
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..theory.asperity import asperity_area, asperity_max_load
from ..theory.laws import KAPPA_BGT, KAPPA_PERSSON, cel_area, linear_area, persson_area
from .captions import REFERENCE_STYLES
from .load_curves import (
    ASPERITY_STYLES,
    BAND_ALPHA,
    BAND_EDGE_ALPHA,
    BAND_EDGE_LW,
    BGT_LIMIT_LABEL,
    PERSSON_ERF_STYLE,
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
    mean_slope,
    n_outside,
    record_panels,
    reference_style,
    unconverged_handles,
    unconverged_steps,
)
from .style import STYLE, family_handles, lambda_label, legend_below, plain_log_labels, require
from .unresolved import mark_unresolved, shown_cases, unresolved_handles


def fig_area_load(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
                  k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
                  hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
                  estimator: str = "joint") -> Figure:
    """Contact-area fraction versus ``p0/E*`` (the paper's Fig. 2), one panel per ``k_s``.

    Each ``(lambda_l, lambda_s, H)`` family is its seed-mean curve with a +-1 standard
    deviation band (translucent, edged in the family's colour so that a thin band still
    shows; the largest s.d. is in the legend), over the converged steps: a step whose solve
    did not converge (``agg.converged`` False) is left out of the mean and band and drawn as
    a grey cross, and the legend counts those steps. Black solid: the BGT asymptote
    ``A/A0 = sqrt(2 pi) p0 / (h' E*)``. Persson's two curves share one colour
    (:data:`PERSSON_COLOUR`): his small-load asymptote (``kappa = sqrt(8/pi)``) thin
    dashed, on top of his full ``erf`` curve, thick and translucent (the two coincide at
    small load). With ``fit``, the H-pooled CEL of ``fit_k_l`` (default: the largest
    ``k_l`` shown, the most representative surfaces) as a thick grey line. Theory lines
    use the mean rms slope of the shown cases.

    Parameters
    ----------
    agg : xarray.Dataset
        Combined contact dataset: the attr ``e_star``, optionally ``converged``,
        ``case_present`` and ``alpha``; where some ``converged(k_l, k_s, H, seed, step)`` is
        False, also ``pressure`` [unit of e_star] and ``area_fraction`` [1] over those dims.
    stats : xarray.Dataset
        :func:`roughcontact.analysis.aggregate.seed_statistics` output (the workflow passes the
        aggregate, which holds both).
    fit : xarray.Dataset, optional
        :func:`roughcontact.analysis.fit.fit_cel` output.
    k_l, k_s, hurst : sequences of float, optional
        Subsets to show (default: all with data).
    fit_k_l : float, optional
        Whose fitted CEL to draw.
    estimator : str
        Which estimator of ``fit`` to draw.

    Returns
    -------
    matplotlib.figure.Figure
    """
    require(stats, "stats", ("area_fraction_mean", "area_fraction_std", "pressure_mean",
                              "rms_slope_mean", "n_seeds"))
    e_star = e_star_of(agg)
    hp = mean_slope(stats)
    alphas, bad = asperity_alphas(agg), unconverged_steps(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(STYLE):
        extent, crosses = _area_load_curves(axes, agg, stats, bad, e_star, kl_list, ks_list, h_list,
                                            colour, marker, style)
        xmax, ymax, sdmax = (float(v) for v in extent)
        drew_fit = _area_load_theory_panels(axes, ks_list, fit, cel_kl, estimator, xmax, ymax, e_star, hp, alphas)
        handles = family_handles(kl_list, h_list, colour, marker, style) + area_load_theory_handles(sdmax)
        handles += asperity_handles(alphas) + _area_load_cross_handles(axes, crosses) + unresolved_handles(fig)
        label = record_panels(fig, axes.flat, agg, stats, (kl_list, ks_list, h_list), fit, cel_kl, estimator, drew_fit)
        if label is not None:
            handles.append(Line2D([], [], **reference_style("cel_fit"), label=label))
        legend_below(fig, handles, f"$h' = {hp:.3g}$")
    return fig


def _area_load_curves(axes, agg, stats, bad, e_star: float, kl_list, ks_list, h_list, colour, marker, style):
    """First pass: the families of each ``k_s`` panel (:func:`_area_load_panel`) and the panel titles.

    Returns ``(extent, crosses)``: ``[max p0/E*, max A/A0 + s.d., max s.d.]`` [1] over all
    panels (NaN ignored) and, per panel, ``(p0/E*, A/A0)`` [1] of its unconverged steps.
    """
    extent, crosses = np.zeros(3), []  # largest p0/E*, A/A0 + s.d., s.d.
    for idx, ks in enumerate(ks_list):
        families = [(kl, ks, h) for kl in kl_list for h in h_list if has_seeds(stats, kl, ks, h)]
        panel_extent, panel_crosses = _area_load_panel(axes.flat[idx], agg, stats, bad, families, e_star,
                                                       colour, marker, style)
        extent = np.fmax(extent, panel_extent)
        crosses.append(panel_crosses)
        axes.flat[idx].set_title(lambda_label(ks, "s"))
    return extent, crosses


def _area_load_theory_panels(axes, ks_list, fit, cel_kl: float, estimator: str, xmax: float, ymax: float,
                             e_star: float, hp: float, alphas) -> bool:
    """Second pass: fitted CEL and theory of each panel over the common load range of all panels
    (:func:`_area_load_axes`); the axes beyond ``ks_list`` are hidden. Returns whether a fit was drawn."""
    drew_fit = False
    for idx, ks in enumerate(ks_list):
        consts = fit_constants(fit, cel_kl, ks, estimator)
        _area_load_axes(axes.flat[idx], consts, xmax, ymax, e_star, hp, alphas)
        drew_fit = drew_fit or consts is not None
    for ax in list(axes.flat)[len(ks_list):]:
        ax.set_visible(False)
    return drew_fit


def _area_load_cross_handles(axes, crosses) -> list:
    """Legend entries of the unconverged steps ``crosses`` (one ``(x, y)`` per shown panel), counting
    those outside their panel's limits."""
    n_off = sum(n_outside(ax, *c) for ax, c in zip(axes.flat, crosses, strict=False))  # hidden axes last
    return unconverged_handles(sum(x.size for x, _ in crosses), n_off)


def _area_load_family(ax, s: Mapping[str, np.ndarray], e_star: float, colour, marker, style) -> np.ndarray:
    """Seed-mean ``A/A0(p0/E*)`` of one family with its ``+-1`` s.d. band (edged, so it shows
    when thin). ``s``: ``pressure_mean`` [unit of e_star], ``area_fraction_mean`` and ``_std``
    [1], shape ``(n_steps,)`` each. Returns ``[max p0/E*, max A/A0 + s.d., max s.d.]`` [1]
    (NaN where no step has a value)."""
    x = s["pressure_mean"] / e_star
    y, sd = s["area_fraction_mean"], s["area_fraction_std"]
    face, edge = mcolors.to_rgba(colour, BAND_ALPHA), mcolors.to_rgba(colour, BAND_EDGE_ALPHA)
    ax.fill_between(x, y - sd, y + sd, facecolor=face, edgecolor=edge, lw=BAND_EDGE_LW, zorder=2)
    ax.plot(x, y, color=colour, marker=marker, ls=style, markevery=3, zorder=2.5, gid=FAMILY_GID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a family none of whose steps converged
        return np.array([np.nanmax(x), np.nanmax(y + sd), np.nanmax(sd)])


def _area_load_panel(ax, agg, stats, bad, families, e_star: float, colour, marker, style):
    """The families ``(kl, ks, h)`` of one area-load panel over their converged steps
    (:func:`converged_family`), and their unconverged steps as crosses.

    Returns ``(extent, (x, y))``: ``[max p0/E*, max A/A0 + s.d., max s.d.]`` [1] (NaN ignored)
    and ``p0/E*``, ``A/A0`` [1] of the unconverged steps, shape ``(n,)`` each.
    """
    extent, crosses = np.zeros(3), [(np.array([]), np.array([]))]
    for kl, ks, h in families:
        family = {"k_l": kl, "k_s": ks, "H": h}
        v = converged_family(agg, stats, bad, family, ("pressure_mean", "area_fraction_mean", "area_fraction_std"))
        extent = np.fmax(extent, _area_load_family(ax, v, e_star, colour[h], marker[kl], style[kl]))
        p, a = family_unconverged(agg, bad, family, "pressure", "area_fraction")
        crosses.append((p / e_star, a))
    x, y = (np.concatenate(v) for v in zip(*crosses, strict=True))
    draw_unconverged(ax, x, y)
    mark_unresolved(ax, agg, agg["pressure"] / e_star, agg["area_fraction"], shown_cases(families))
    return extent, (x, y)


def _area_load_axes(ax, consts, xmax: float, ymax: float, e_star: float, hp: float, alphas) -> None:
    """The fitted CEL (``consts``: ``(kappa, mu, beta)``, or None) and the theory of one area-load
    panel over ``p0/E*`` in ``[0, xmax]``; limits (``A/A0`` up to ``1.05 ymax``) and labels."""
    p = np.linspace(0, xmax * e_star, 200)
    if consts is not None:
        ax.plot(p / e_star, cel_area(p, kappa=consts[0], mu=consts[1], beta=consts[2], rms_slope=hp, e_star=e_star),
                **REFERENCE_STYLES["cel_fit"], gid="cel_fit")
    area_load_theory(ax, p, e_star, hp, alphas)
    small_load_inset(ax, e_star, hp)
    ax.set_xlim(0, xmax)
    ax.set_ylim(0, ymax * 1.05)
    ax.set_xlabel(r"$p_0/E^*$ [1]")
    ax.set_ylabel(r"$A/A_0$ [1]")


#: The gid of a family's seed-mean curve in an area-load panel (what the small-load inset repeats).
FAMILY_GID = "family"

#: Where the small-load inset sits in its panel, in axes fractions (x0, y0, width, height): the lower right
#: corner, below curves that rise from the origin.
INSET = (0.66, 0.08, 0.31, 0.25)


def small_load_inset(ax, e_star: float, hp: float) -> None:
    """The panel's seed-mean curves (its lines with gid :data:`FAMILY_GID`) again on log-log axes in an inset,
    with the BGT and Persson small-load limits, where the small-load regime (A/A0 proportional to p0: slope 1)
    shows; none when fewer than two points have a positive load and area."""
    curves = [line for line in ax.get_lines() if line.get_gid() == FAMILY_GID]
    xy = [(np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)) for line in curves]
    ok = [np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0) for x, y in xy]
    if sum(int(k.sum()) for k in ok) < 2:
        return
    inset = ax.inset_axes(INSET)
    for line, (x, y), k in zip(curves, xy, ok, strict=True):
        inset.plot(x[k], y[k], color=line.get_color(), ls=line.get_linestyle(), lw=0.8, zorder=2.5)
    x = np.concatenate([x[k] for (x, _), k in zip(xy, ok, strict=True)])
    p = np.geomspace(x.min(), x.max(), 50) * e_star
    inset.plot(p / e_star, linear_area(p, kappa=KAPPA_BGT, rms_slope=hp, e_star=e_star),
               **REFERENCE_STYLES["bgt_limit"], gid="bgt_limit")
    inset.plot(p / e_star, linear_area(p, kappa=KAPPA_PERSSON, rms_slope=hp, e_star=e_star), **PERSSON_LIMIT_STYLE,
               zorder=4, gid="persson_limit")
    inset.set_xscale("log")
    inset.set_yscale("log")
    for axis in (inset.xaxis, inset.yaxis):  # decades where two show: more labels collide in so small an inset
        plain_log_labels(axis, dense=False)
    inset.tick_params(labelsize=5, length=2, pad=1, which="both")
    inset.set_title("log-log: small loads", fontsize=6, pad=2)


def area_load_theory(ax, p: np.ndarray, e_star: float, hp: float, alphas) -> bool:
    """BGT and Persson small-load limits, Persson's erf curve and the asperity models at loads ``p``.

    An asperity model is drawn only up to the largest load it covers (its A/A0 = 1,
    :func:`~roughcontact.theory.asperity.asperity_max_load`); returns whether one was cut there, for a note.
    """
    x = p / e_star
    ax.plot(x, linear_area(p, kappa=KAPPA_BGT, rms_slope=hp, e_star=e_star), **REFERENCE_STYLES["bgt_limit"],
            gid="bgt_limit")
    ax.plot(x, persson_area(p, rms_slope=hp, e_star=e_star), **PERSSON_ERF_STYLE, zorder=3, gid="persson_erf")
    ax.plot(x, linear_area(p, kappa=KAPPA_PERSSON, rms_slope=hp, e_star=e_star), **PERSSON_LIMIT_STYLE,
            zorder=4, gid="persson_limit")
    cut = False
    for alpha, shade, _ in alphas:
        for model in ASPERITY_STYLES:
            inside = p <= asperity_max_load(alpha=alpha, rms_slope=hp, e_star=e_star, model=model)
            cut |= not inside.all()
            ax.plot(x[inside], asperity_area(p[inside], alpha=alpha, rms_slope=hp, e_star=e_star, model=model),
                    **asperity_style(model, shade), gid=asperity_gid(model, alpha))
    return cut


def area_load_theory_handles(sdmax: float) -> list:
    """Legend entries of the s.d. band (``sdmax``: its largest half-width [1]) and of the
    BGT and Persson curves."""
    grey = np.array([0.5, 0.5, 0.5])
    return [Patch(facecolor=(*grey, BAND_ALPHA), edgecolor=(*grey, BAND_EDGE_ALPHA), lw=BAND_EDGE_LW,
                  label=f"$\\pm 1$ s.d. over seeds (largest: {sdmax:.2g})"),
            Line2D([], [], **reference_style("bgt_limit"), label=BGT_LIMIT_LABEL),
            Line2D([], [], **PERSSON_LIMIT_STYLE,
                   label=r"Persson, small-load limit $A/A_0 = \sqrt{8/\pi}\,p_0/(h'E^*)$"),
            Line2D([], [], **PERSSON_ERF_STYLE,
                   label=r"Persson, full: $A/A_0 = \mathrm{erf}(\sqrt{2}\,p_0/(h'E^*))$")]
