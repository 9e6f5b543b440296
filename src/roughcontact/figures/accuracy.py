"""The accuracy study's figure: relative error of each metric against each numerical setting.
"""

from __future__ import annotations

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .record import note_series
from .style import OKABE_ITO, STYLE, new_figure, require


def fig_accuracy(summary: xr.Dataset) -> Figure:
    """What accuracy costs: relative error against solver work per surface (N² x iterations), log-log.

    Two panels: kappa at A/A0 = ``summary.attrs['kappa_at']`` and A/A0 at p_max. One
    series per axis varied (N, tol, n_steps, seeds), each point labelled with its value;
    the N axis is drawn twice, pixel-counted (solid) and perimeter-corrected (dashed);
    the shipped defaults are marked with a star. Zero errors (the reference itself)
    are not drawn on log axes; the legend counts them per series (:func:`series_label`).
    """
    require(summary, "summary", ["work_per_case", "err_kappa", "err_area", "axis", "value"])
    with matplotlib.rc_context(STYLE):
        return _draw_accuracy(summary)


def series_label(name: str, drawn: int, total: int) -> str:
    """A series' legend entry: its name, and how many of its ``total`` settings are not drawn (an error of zero,
    the reference setting itself, or none) when some are not."""
    if drawn == total:
        return name
    return f"{name} ({total - drawn} of {total} not drawn: zero error, the reference, or none)"


def _draw_accuracy(summary: xr.Dataset) -> Figure:
    fig = new_figure(3.2)
    axes = fig.subplots(1, 2)
    colours = dict(zip(("N", "tol", "n_steps", "seeds"), OKABE_ITO[1:5], strict=True))
    names = {"N": "grid N", "tol": "tolerance", "n_steps": "load steps", "seeds": "seeds"}
    axis_of = summary["axis"].values
    for ax, metric, title in ((axes[0], "kappa", f"$\\kappa$ at $A/A_0$ = {summary.attrs.get('kappa_at', 0.05):g}"),
                              (axes[1], "area", "$A/A_0$ at $p_{max}$")):
        for name, colour in colours.items():
            sel = np.flatnonzero(axis_of == name)
            if sel.size == 0:
                continue
            t = summary["work_per_case"].values[sel]
            order = np.argsort(t)
            for variant, style, label in ((metric, "-", names[name]),
                                          (f"{metric}_corrected", "--", "N, perimeter-corrected")):
                if variant.endswith("corrected") and name != "N":
                    continue
                e = summary[f"err_{variant}"].values[sel][order]
                ok = np.isfinite(e) & (e > 0)
                ax.plot(t[order][ok], e[ok], style, marker="o", ms=3, color=colour,
                        label=series_label(label, int(ok.sum()), int(e.size)))
                if style == "-":
                    for ti, ei, v in zip(t[order][ok], e[ok], summary["value"].values[sel][order][ok], strict=True):
                        ax.annotate(str(v), (ti, ei), textcoords="offset points", xytext=(3, 3), fontsize=6,
                                    color=colour)
        d = np.flatnonzero(axis_of == "defaults")
        if d.size:
            e = summary[f"err_{metric}"].values[d]
            if np.all(e > 0):
                ax.plot(summary["work_per_case"].values[d], e, "*", ms=10, color="black", label="defaults")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("solver work per surface, $N^2$ × iterations (seeds series: all k surfaces)")
        ax.set_ylabel("relative error [1]")
        ax.set_title(title, fontsize=9)
    # one entry per series: the two panels may leave out different settings, the left one's count is given
    handles, labels = axes[0].get_legend_handles_labels()
    uniq = dict(zip(labels, handles, strict=True))
    fig.legend(uniq.values(), uniq.keys(), loc="outside right center", fontsize=7, frameon=False)
    note_series(fig, list(uniq))
    return fig
