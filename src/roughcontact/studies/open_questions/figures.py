"""Figures of the open-questions page: a few distinguishable curves per panel, log axes over decades.

Each function takes the numbers of :mod:`.analysis` and returns a matplotlib ``Figure``; the page
saves them with :func:`roughcontact.figures.style.save_figure` (byte-reproducible PNG and PDF).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter, ScalarFormatter
from scipy.special import erfc

from ...figures.style import DATA_COLOURS, DOUBLE_COLUMN_IN
from ...theory import persson_area


def shown(keys) -> list:
    """At most three of ``keys`` (first, middle, last): five curves and their theories would crowd a panel."""
    keys = sorted(keys)
    return keys if len(keys) <= 3 else [keys[0], keys[len(keys) // 2], keys[-1]]


def _figure(rows: int, cols: int, height: float) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(DOUBLE_COLUMN_IN, height), layout="constrained")
    return fig, np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()


def area_figure(curve: dict, cel: dict, onset: dict) -> Figure:
    """(a) A/A0 against pbar with the CEL and Persson; (b) 1 - A/A0 near full contact."""
    fig, (a, b) = _figure(1, 2, 3.0)
    pbar, area = curve["pbar"], curve["area"]
    fine = np.geomspace(pbar[0], pbar[-1], 400)
    a.loglog(pbar, area, "o", ms=3, color="k", label=f"measured ({onset['n']} surfaces)")
    a.loglog(pbar, cel["prediction"], "-", color=DATA_COLOURS[0], label="CEL (fitted at A/A0 ≤ 0.11)")
    a.loglog(fine, persson_area(fine, rms_slope=1.0, e_star=1.0), "--", color=DATA_COLOURS[1],
             label="Persson, erf")
    a.axhline(1.0, color="0.6", lw=0.6)
    a.set(xlabel=r"$p_0/(E^* h')$", ylabel=r"$A/A_0$", ylim=(5e-4, 3))
    a.legend(fontsize=7)
    sel = area < 1.0
    b.semilogy(pbar[sel], 1.0 - area[sel], "o", ms=3, color="k", label="measured")
    b.semilogy(fine, erfc(np.sqrt(2.0) * fine), "--", color=DATA_COLOURS[1], label=r"Persson, erfc($\sqrt{2}\bar p$)")
    lo, hi = np.nanmin(onset["pbar_fc"].values), np.nanmax(onset["pbar_fc"].values)
    b.axvspan(lo, hi, color="0.85", label="exact full-contact loads")
    b.set(xlabel=r"$p_0/(E^* h')$", ylabel=r"$1 - A/A_0$", xlim=(0.2, pbar[-1]), ylim=(1e-7, 1))
    b.legend(fontsize=7)
    return fig


def gap_stiffness_figure(curves: dict) -> Figure:
    """(a) mean gap / rms height and (b) stiffness h_rms / E*, measured and Persson, three H."""
    fig, (a, b) = _figure(1, 2, 3.0)
    for colour, h in zip(DATA_COLOURS, shown(curves), strict=False):
        c = curves[h]
        s = c["h_rms"]
        a.semilogx(c["pbar"], c["gap"] / s, "o", ms=3, color=colour, label=f"H = {h}")
        a.semilogx(c["pbar"], c["gap_persson"] / s, "--", color=colour)
        b.loglog(c["pbar"], c["stiffness"] * s, "o", ms=3, color=colour, label=f"H = {h}")
        finite = np.isfinite(c["stiffness"])  # Persson's K diverges at full contact: draw where ours is defined
        b.loglog(c["pbar"][finite], c["stiffness_persson"][finite] * s, "--", color=colour)
    a.set(xlabel=r"$p_0/(E^* h')$", ylabel=r"mean gap $/\,h_\mathrm{rms}$", ylim=(0, None))
    b.set(xlabel=r"$p_0/(E^* h')$", ylabel=r"$K\,h_\mathrm{rms}/E^*$")
    a.legend(fontsize=7, title="dots: measured; dashed: Persson", title_fontsize=7)
    return fig


def pressure_figure(distributions: list[dict]) -> Figure:
    """P(p) at four loads, pooled over the surfaces, against Persson's diffusion result."""
    fig, axes = _figure(2, 2, 4.6)
    for ax, d in zip(axes, distributions, strict=False):
        ax.step(d["x"], d["measured"], where="mid", color="k", lw=1, label="measured")
        ax.plot(d["x"], d["persson"], "--", color=DATA_COLOURS[1], label="Persson")
        ax.set(title=f"A/A0 = {d['area']:.3g}, " + r"$\bar p$" + f" = {d['pbar']:.3g}",
               xlim=(0, max(2.0, d["pbar"] + 2.0)))
        ax.title.set_fontsize(8)
        ax.set_xlabel(r"$p/(E^* h')$")
        ax.set_ylabel(r"$P(p)\;E^* h'$")
    axes[0].legend(fontsize=7)
    return fig


def cluster_figure(clusters: dict) -> Figure:
    """(a) cluster count and (b) the largest cluster's share of the contact area, against A/A0."""
    fig, (a, b) = _figure(1, 2, 3.0)
    area = clusters["area"]
    sel = area < 1.0
    a.loglog(area[sel], clusters["count"][sel], "o-", ms=3, color="k")
    a.set(xlabel=r"$A/A_0$", ylabel="contact clusters per cell")
    b.semilogx(area[sel], clusters["share"][sel], "o-", ms=3, color="k", label="measured (mean)")
    b.axhline(0.5, color="0.6", lw=0.6)
    b.axvline(0.42, color=DATA_COLOURS[1], ls="--", label="Dapp et al. (2012): 0.42")
    b.set(xlabel=r"$A/A_0$", ylabel="largest cluster / contact area", ylim=(0, 1.02))
    b.legend(fontsize=7)
    return fig


def alpha_figure(pixel: dict, corrected: dict, pixel_2048: dict | None = None,
                 corrected_2048: dict | None = None, pixel_4096: dict | None = None,
                 corrected_4096: dict | None = None, bends: tuple | None = None) -> Figure:
    """κ(0.05)/√2π against α at λ_s = 32 Δx, (a) pixel-counted, (b) perimeter-corrected, with BGT and Greenwood.

    The paper grid's points (N = 1024) are dots by λ_l; the kappa-alpha scene's (N = 2048), when
    given, open squares; the kappa-alpha-4096 scene's (N = 4096, λ_s = L/128), when given, open diamonds.
    α is each point's seed mean of its surfaces' measured α. ``bends``, when given, holds
    :func:`.kappa.bend` of each panel's points: its straight lines below and above the split are drawn.
    """
    fig, axes = _figure(1, 2, 3.2)
    every = np.concatenate([pixel["alpha"]] + ([pixel_4096["alpha"]] if pixel_4096 is not None else []))
    line = np.geomspace(every.min(), every.max(), 60)
    # the y range reaches down to the models' lowest value (they fall far below the data at large alpha)
    floor = min(0.45, *(np.nanmin(p[m]) - 0.05 for p in (pixel, pixel_2048, pixel_4096) if p is not None
                        for m in ("bgt", "greenwood")))
    for ax, pts, more, most, title in zip(axes, (pixel, corrected), (pixel_2048, corrected_2048),
                                          (pixel_4096, corrected_4096),
                                          ("pixel-counted area", "perimeter-corrected area"), strict=True):
        if more is not None:
            ax.errorbar(more["alpha"], more["kappa"], yerr=more["sem"], fmt="s", ms=5, mfc="none", color="k",
                        label=r"N = 2048, $\lambda_l = L/4, L/8$")
        if most is not None:
            ax.errorbar(most["alpha"], most["kappa"], yerr=most["sem"], fmt="D", ms=4, mfc="none", color="0.4",
                        label=r"N = 4096, $\lambda_s = L/128$")
        for colour, kl in zip(DATA_COLOURS, np.unique(pts["k_l"]), strict=False):
            sel = pts["k_l"] == kl
            ax.errorbar(pts["alpha"][sel], pts["kappa"][sel], yerr=pts["sem"][sel], fmt="o", ms=3, color=colour,
                        label=rf"$\lambda_l = L/{kl:g}$")
        # the models are functions of alpha: drawn through every point's alpha, so that they span the whole range
        every_pts = [p for p in (pts, more, most) if p is not None]
        alpha = np.concatenate([p["alpha"] for p in every_pts])
        order = np.argsort(alpha)
        for model, style in (("bgt", ":"), ("greenwood", "--")):
            ax.semilogx(alpha[order], np.concatenate([p[model] for p in every_pts])[order], style, color="k",
                        label=model.upper() if model == "bgt" else "Greenwood")
        if bends is not None:
            fit = bends[0 if ax is axes[0] else 1]
            for part, style in (("below", "-."), ("above", "-")):
                lo, hi, a, b = fit["lines"][part]
                x = np.geomspace(lo, hi, 30)
                ax.semilogx(x, a + b * np.log(x), style, color="0.5", lw=1,
                            label=rf"lines in $\ln\alpha$ below and above $\alpha$ = {fit['split']:g}"
                            if part == "above" else None)
        ax.set(xscale="log", xlabel=r"Nayak's $\alpha$ (measured, seed mean)",
               ylabel=r"$\kappa(A/A_0 = 0.05)/\sqrt{2\pi}$", title=title,
               xlim=(line[0] / 1.2, line[-1] * 1.2), ylim=(floor, 1.05))
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.title.set_fontsize(8)
    fig.legend(*axes[0].get_legend_handles_labels(), fontsize=6, ncol=4, loc="outside lower center")
    return fig


def cell_figure(small, large) -> Figure:
    """κ(A)/√2π on the L and the 2L cell (seed means ± standard error), one panel per H."""
    hs = list(large["H"].values)
    fig, axes = _figure(1, len(hs), 3.0)
    for ax, h in zip(axes, hs, strict=True):
        for colour, (label, ds) in zip(DATA_COLOURS, (("L, N = 1024", small), ("2L, N = 2048", large)), strict=False):
            sub = ds.sel(H=h)
            k = sub["kappa"] / np.sqrt(2 * np.pi)
            n = np.sqrt(sub.sizes["seed"])
            area = sub["area_fraction"].mean("seed").values
            mean, sem = k.mean("seed").values, k.std("seed", ddof=1).values / n
            ax.semilogx(area, mean, "-", color=colour, label=label)
            ax.fill_between(area, mean - sem, mean + sem, color=colour, alpha=0.3, lw=0)
        ax.set(xlabel=r"$A/A_0$", ylabel=r"$\kappa/\sqrt{2\pi}$", title=f"H = {h:g}")
        ax.title.set_fontsize(8)
    axes[0].legend(fontsize=7)
    return fig
