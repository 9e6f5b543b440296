"""Figures of geometric representativity: eps over the cutoffs (Fig. 1) and example surfaces.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import matplotlib
import matplotlib.colors as mcolors
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from ..analysis.aggregate.seeds import scale_free_statistics
from .captions import PROFILES_GID
from .record import note, note_series
from .style import (
    DATA_COLOURS,
    DOUBLE_COLUMN_IN,
    LINESTYLES,
    MARKERS,
    OKABE_ITO,
    SINGLE_COLUMN_IN,
    STYLE,
    fmt,
    new_figure,
    number_unit,
    pick,
    plain_log_labels,
    require,
    unit_tex,
)


def _rep_hurst(rep: xr.Dataset, hurst: float | None) -> float:
    hs = [float(h) for h in rep["H"].values]
    if hurst is None:
        if len(hs) != 1:
            raise ValueError(f"rep_stats holds several H {hs}; pass hurst= one of them")
        return hs[0]
    return pick(rep["H"].values, hurst, "hurst")[0]


def _recorded(rep: xr.Dataset) -> tuple[dict, dict]:
    """The parameters a representativity aggregate records and their ``surface`` block (``{}`` when none)."""
    try:
        recorded = json.loads(rep.attrs.get("scene_parameters", "{}"))
    except ValueError:
        recorded = {}
    recorded = recorded if isinstance(recorded, dict) else {}
    surface = recorded.get("surface", {})
    return recorded, surface if isinstance(surface, dict) else {}


def _rep_summary(rep: xr.Dataset, h: float) -> str:
    """What a representativity figure shows: grid N, seeds, histogram bins, H, rms height."""
    recorded, surface = _recorded(rep)
    parts = [f"$N = {int(surface['N'])}$"] if "N" in surface else []
    seeds = rep["n_seeds"].values[rep["n_seeds"].values > 0]
    if seeds.size:
        lo, hi = int(seeds.min()), int(seeds.max())
        parts.append(f"{lo} seeds" if lo == hi else f"{lo}-{hi} seeds")
    bins = rep.attrs.get("n_bins", recorded.get("n_bins"))
    if bins is not None:
        parts.append(f"{int(bins)} bins")
    parts.append(f"$H = {fmt(h)}$")
    sigma = float(rep["std_height"].mean()) if "std_height" in rep else surface.get("rms_height")
    if sigma is not None and np.isfinite(sigma):
        parts.append(rf"rms height $\sigma$ = {float(sigma):.3g}")
    return ", ".join(parts)


def _rep_curves(ax, sub: xr.Dataset, ylabel: str, title: str) -> None:
    """Seed-mean eps against k_s, one curve per k_l, s.e.m. bars; log-log with the k_s as ticks."""
    for i, kl in enumerate(float(k) for k in sub["k_l"].values):
        row = sub.sel(k_l=kl)
        ok = ((row["n_seeds"] > 0) & np.isfinite(row["epsilon_mean"])).values
        if ok.any():
            ax.errorbar(row["k_s"].values[ok], row["epsilon_mean"].values[ok], yerr=row["epsilon_sem"].values[ok],
                        color=DATA_COLOURS[i % len(DATA_COLOURS)], marker=MARKERS[i % len(MARKERS)],
                        ls=LINESTYLES[i % len(LINESTYLES)], label=f"$k_l = {fmt(kl)}$")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ks = [float(k) for k in sub["k_s"].values]
    labelled = ks[:1]
    for k in ks[1:]:  # a label only 1.4x beyond the last one: 32 and 40 would collide
        if k / labelled[-1] >= 1.4:
            labelled.append(k)
    ax.set_xticks(ks, [fmt(k) if k in labelled else "" for k in ks])
    ax.xaxis.set_minor_formatter(NullFormatter())
    plain_log_labels(ax.yaxis)
    ax.set_xlabel(r"short cutoff $k_s = L/\lambda_s$ [1]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)


def _rep_grid(sub: xr.Dataset) -> tuple[list[float], list[float]]:
    """The k_l and k_s that have data (some finite seed mean) in ``sub`` (dims k_l, k_s)."""
    ok = (sub["n_seeds"] > 0) & np.isfinite(sub["epsilon_mean"])
    kls = [float(k) for k, a in zip(sub["k_l"].values, ok.any("k_s").values, strict=True) if a]
    kss = [float(k) for k, a in zip(sub["k_s"].values, ok.any("k_l").values, strict=True) if a]
    return kls, kss


def _rep_map(fig: Figure, ax, sub: xr.Dataset, symbol: str, unit: str) -> None:
    """The paper's Fig. 1a as a map: seed-mean eps as colour over k_l x k_s (categorical axes).

    ``sub``: statistics over ``(k_l, k_s)``; ``symbol``/``unit``: mathtext of the measure.
    Log colour scale; each cell carries its value; cells without data stay blank.
    """
    kls, kss = _rep_grid(sub)
    z = sub["epsilon_mean"].sel(k_l=kls, k_s=kss).transpose("k_l", "k_s").values
    z = np.where(np.isfinite(z) & (z > 0), z, np.nan)
    norm = mcolors.LogNorm(vmin=float(np.nanmin(z)), vmax=float(np.nanmax(z)))
    mesh = ax.pcolormesh(np.arange(len(kss) + 1) - 0.5, np.arange(len(kls) + 1) - 0.5, np.ma.masked_invalid(z),
                         norm=norm, cmap="cividis", edgecolors="white", linewidth=0.5)
    for (i, j), v in np.ndenumerate(z):
        if np.isfinite(v):
            dark = norm(v) < 0.55  # cividis is dark at the low end
            ax.text(j, i, f"{v:.2g}", ha="center", va="center", fontsize=5.5 if len(kss) <= 4 else 4.5,
                    color="white" if dark else "black")
    ax.set_xticks(range(len(kss)), [fmt(k) for k in kss])
    ax.set_yticks(range(len(kls)), [fmt(k) for k in kls])
    ax.set_xlabel(r"short cutoff $k_s$ [1]")
    ax.set_ylabel(r"long cutoff $k_l$ [1]")
    ax.set_title(rf"(c) {symbol} over $(k_l, k_s)$")
    ax.set_label("epsilon map")
    cb = fig.colorbar(mesh, ax=ax, shrink=0.9, pad=0.02)
    cb.set_label(f"{symbol} [{unit}]")
    plain_log_labels(cb.ax.yaxis)


def _rep_panels(rep: xr.Dataset, h: float) -> list[tuple[xr.Dataset, str, str, str]]:
    """``(statistics at H=h, symbol, unit, title)`` of the paper's eps and, when the per-case
    data allow it, of the scale-free eps (:func:`roughcontact.analysis.aggregate.seeds.scale_free_statistics`)."""
    units = unit_tex(number_unit(rep["epsilon_mean"].attrs))
    panels = [(rep.sel(H=h), r"$\bar\varepsilon$", units, r"(a) heights $h$ (paper's $\varepsilon$)")]
    free = scale_free_statistics(rep)
    if free is not None:
        panels.append((free.sel(H=h), r"$\bar\varepsilon_\sigma$", "1",
                       r"(b) normalised $(h-\bar h)/\sigma$: scale-free"))
    first = panels[0][0]
    if not np.isfinite(first["epsilon_mean"].where(first["n_seeds"] > 0)).any():
        raise ValueError(f"rep_stats has no finite epsilon_mean at H={h}")
    return panels


def fig_representativity(rep_stats: xr.Dataset, *, hurst: float | None = None) -> Figure:
    """Mean Gaussian L2 error of the height PDF versus ``k_s``, one curve per ``k_l``.

    The paper's Fig. 1a / appendix figure. Panel (a): eps of the heights ``h`` as the
    paper defines it [height unit^-1/2], which scales as ``sigma^(-1/2)`` with the rms
    height ``sigma``; panel (b), when ``rep_stats`` holds the per-case ``epsilon`` and
    ``std_height``: the scale-free eps of ``(h - hbar)/sigma`` [1], ``eps sqrt(sigma)``
    (:func:`roughcontact.statistics.representativity.scale_free_epsilon`). Log-log axes, error bars
    the standard error of the seed mean. Panel (c), when data exist for at least two
    ``k_l`` and two ``k_s``: the paper's Fig. 1a as a map, the seed-mean eps (scale-free
    where available) as colour over ``k_l x k_s``. The title states N, seeds, bins, H
    and the rms height.

    Parameters
    ----------
    rep_stats : xarray.Dataset
        :func:`roughcontact.analysis.aggregate.representativity_statistics` output: ``epsilon_mean``,
        ``epsilon_sem``, ``n_seeds`` over ``(k_l, k_s, H)``, optionally merged with the
        per-case ``epsilon`` and ``std_height`` over ``(k_l, k_s, H, seed)`` as in the
        workflow's ``aggregate/representativity.nc``.
    hurst : float, optional
        Which H to show; required when the dataset holds several.

    Returns
    -------
    matplotlib.figure.Figure
        7 in wide (:data:`~.style.FIGURE_WIDTH_IN`) with one to three panels, legend below.
    """
    require(rep_stats, "rep_stats", ("epsilon_mean", "epsilon_sem", "n_seeds"))
    h = _rep_hurst(rep_stats, hurst)
    panels = _rep_panels(rep_stats, h)
    kls, kss = _rep_grid(panels[-1][0])
    n = len(panels) + (len(kls) >= 2 and len(kss) >= 2)
    with matplotlib.rc_context(STYLE):
        fig = new_figure(2.9)
        axes = fig.subplots(1, n, squeeze=False, width_ratios=[1.0] * len(panels) + [1.15] * (n - len(panels)))[0]
        for ax, (sub, symbol, unit, title) in zip(axes, panels, strict=False):
            _rep_curves(ax, sub, f"mean $L_2$ error {symbol} [{unit}]", title if len(panels) > 1 else "")
        if n > len(panels):
            _rep_map(fig, axes[-1], *panels[-1][:3])
        fig.suptitle(_rep_summary(rep_stats, h) + "; bars: s.e.m. over seeds")
        handles, labels = axes[0].get_legend_handles_labels()
        note_series(fig, [f"k_l = {fmt(k)}" for k in _rep_grid(panels[0][0])[0]])
        if _recorded(rep_stats)[1].get("dimension") == 1:
            fig.set_gid(PROFILES_GID)
            note(fig, "profiles_heights")
        fig.legend(handles, labels, loc="outside lower center", ncols=len(handles),
                   title=r"long cutoff $k_l = L/\lambda_l$")
    return fig


def fig_surface_examples(examples: Sequence[tuple[np.ndarray, str]], *, length: float = 1.0,
                         bins: int = 60, shared_scale: bool = True) -> Figure:
    """Example surfaces (top) and their height PDFs against a Gaussian (bottom).

    The paper's Fig. 1 b-d. Lengths are shown in units of the domain side (``x/L``,
    ``h/L``). The Gaussian has the surface's own mean and standard deviation; the
    histogram is a density of ``h/L`` (``bins`` equal bins over the height range).

    Parameters
    ----------
    examples : sequence of (numpy.ndarray, str)
        ``(heights, label)``: a square ``(n, n)`` height field [u] (axis 0 = x) and a
        panel title (e.g. ``"(b) k_l = 1, k_s = 40"``); 1 to 6 of them.
    length : float
        Side ``L`` of the domain (> 0) [u].
    bins : int
        Histogram bins (>= 5).
    shared_scale : bool
        One colour scale and one height axis for all panels (default), so that the panels
        compare; ``False`` scales each panel to its own surface.

    Returns
    -------
    matplotlib.figure.Figure
        7 in wide (:data:`~.style.FIGURE_WIDTH_IN`; a single example sized for one column), two rows.
    """
    fields = _example_fields(examples, length, bins)
    n = len(fields)
    lo = min(float(h.min()) for h, _ in fields) / length
    hi = max(float(h.max()) for h, _ in fields) / length
    width = SINGLE_COLUMN_IN if n == 1 else DOUBLE_COLUMN_IN
    col_w = width / n
    with matplotlib.rc_context(STYLE):
        fig = new_figure(col_w * 0.95 + 1.7)
        axes = fig.subplots(2, n, squeeze=False, gridspec_kw={"height_ratios": [col_w * 0.95, 1.5]})
        for j, (h, label) in enumerate(fields):
            h = h / length
            vmin, vmax = (lo, hi) if shared_scale else (float(h.min()), float(h.max()))
            _example_map(fig, axes[0, j], h, label, vmin, vmax, first=j == 0)
            _example_pdf(axes[1, j], h, vmin, vmax, bins, first=j == 0)
        handles, labels = axes[1, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncols=2)
        note_series(fig, [label for _, label in fields])
    return fig


def _example_fields(examples: Sequence[tuple[np.ndarray, str]], length: float,
                    bins: int) -> list[tuple[np.ndarray, str]]:
    """The checked arguments of :func:`fig_surface_examples`: ``(heights, label)`` pairs, heights as
    finite square float arrays [u], labels as str; ``ValueError`` for a bad example, ``length`` or ``bins``."""
    examples = list(examples)
    if not 1 <= len(examples) <= 6:
        raise ValueError(f"examples must hold 1 to 6 (heights, label) pairs, got {len(examples)}")
    if not (np.isfinite(length) and length > 0):
        raise ValueError(f"length must be a finite number > 0, got {length!r}")
    if not isinstance(bins, (int, np.integer)) or bins < 5:
        raise ValueError(f"bins must be an integer >= 5, got {bins!r}")
    fields = []
    for i, item in enumerate(examples):
        if len(item) != 2:
            raise ValueError(f"examples[{i}] must be a (heights, label) pair")
        h = np.asarray(item[0], dtype=float)
        if h.ndim != 2 or h.shape[0] != h.shape[1] or not np.all(np.isfinite(h)):
            raise ValueError(f"examples[{i}] heights must be a finite square 2-D array, got shape {h.shape}")
        fields.append((h, str(item[1])))
    return fields


def _example_map(fig: Figure, ax, h: np.ndarray, label: str, vmin: float, vmax: float, first: bool) -> None:
    """Height map ``h/L`` (``h``: (n, n), axis 0 = x) on ``[0, 1]^2`` with colour scale ``[vmin, vmax]``
    and its colour bar; the y label only on the ``first`` panel."""
    im = ax.imshow(h.T, origin="lower", extent=(0, 1, 0, 1), interpolation="nearest", vmin=vmin, vmax=vmax)
    ax.set_title(label)
    ax.set_xlabel(r"$x/L$")
    if first:
        ax.set_ylabel(r"$y/L$")
    cb = fig.colorbar(im, ax=ax, shrink=0.8, pad=0.02)
    cb.ax.set_title(r"$h/L$", fontsize=7)


def _example_pdf(axh, h: np.ndarray, vmin: float, vmax: float, bins: int, first: bool) -> None:
    """Density histogram of ``h/L`` (``bins`` equal bins over ``[vmin, vmax]``) against the Gaussian of
    its own mean and standard deviation (none for a flat surface); the y label only on the ``first`` panel."""
    mean, std = float(h.mean()), float(h.std())
    axh.hist(h.ravel(), bins=bins, range=(vmin, vmax), density=True, color=DATA_COLOURS[1], alpha=0.6,
             label="surface")
    axh.set_xlim(vmin, vmax)
    grid = np.linspace(vmin, vmax, 200)
    if std > 0:
        axh.plot(grid, np.exp(-0.5 * ((grid - mean) / std) ** 2) / (np.sqrt(2 * np.pi) * std),
                 color=OKABE_ITO[0], label=r"Gaussian $G(h,\bar h,\sigma)$")
    axh.set_xlabel(r"height $h/L$")
    if first:
        axh.set_ylabel(r"PDF of $h/L$")
