"""Figures of the study (Yastrebov, Anciaux & Molinari 2012, Figs. 1-4 and appendix).

Each ``fig_*`` function takes datasets and returns a :class:`matplotlib.figure.Figure`
built without pyplot (no global figure registry, no GUI backend); :func:`save_figure`
writes it as PNG and PDF with byte-identical output on every rerun.

Conventions: single-column figures are 3.4 in wide, multi-panel ones 7 in; legends sit
outside the axes; colours are the Okabe-Ito palette (distinguishable with the common
colour-vision deficiencies), one colour per Hurst exponent; the long cutoff
``lambda_l = L / k_l`` is told apart by marker and line style. Theory curves are black
or grey. Symbols: ``p0`` applied mean pressure, ``E*`` contact modulus, ``h'`` rms
slope, ``A/A0`` contact-area fraction, ``pbar`` mean contact pressure,
``kappa = E* h' / pbar``.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FormatStrFormatter, NullFormatter, ScalarFormatter

from .io import atomic_output
from .theory import (
    KAPPA_BGT,
    KAPPA_PERSSON,
    NAYAK_ALPHA_MIN,
    asperity_area,
    asperity_kappa,
    cel_area,
    cel_dpbar_dp0,
    cel_kappa,
    linear_area,
    persson_area,
)

#: Okabe & Ito (2008) colour-blind-safe palette, black first (reserved for theory).
OKABE_ITO = ("#000000", "#E69F00", "#56B4E9", "#009E73", "#D55E00", "#0072B2", "#CC79A7", "#F0E442")
#: Data colours: the palette without black, yellow last (weak on white).
DATA_COLOURS = OKABE_ITO[1:]
_MARKERS = ("o", "s", "^", "D", "v", "P", "X")
_LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1)), (0, (1, 1)))
#: Width of a single-column and of a two-column figure [in].
SINGLE_COLUMN_IN = 3.4
DOUBLE_COLUMN_IN = 7.0

_STYLE = {
    "font.size": 8,
    "axes.labelsize": 8,
    "axes.titlesize": 8,
    "legend.fontsize": 7,
    "legend.title_fontsize": 7,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "lines.linewidth": 1.0,
    "lines.markersize": 3.0,
    "axes.linewidth": 0.6,
    "errorbar.capsize": 1.5,
    "legend.frameon": False,
    "image.cmap": "cividis",
    "pdf.fonttype": 42,
    "svg.hashsalt": "roughcontact",
}

_PNG_DPI = 300


# ------------------------------------------------------------------------ saving
def save_figure(fig: Figure, path: str | os.PathLike) -> list[Path]:
    """Write ``fig`` as ``<path>.png`` (300 dpi) and ``<path>.pdf``, byte-reproducibly.

    A ``.png`` or ``.pdf`` suffix on ``path`` is replaced, so either output name may be
    passed. Reproducibility: PNG drops the ``Software`` text chunk; PDF drops
    ``CreationDate``, ``Creator`` and ``Producer`` (dates and versions are the only
    varying bytes; Agg rasterisation and PDF object numbering are deterministic, and
    TrueType embedding (``pdf.fonttype`` 42) subsets fonts deterministically).
    Each file is written atomically (:func:`roughcontact.io.atomic_output`): an
    interrupted save leaves the previous complete file or none, never a truncated one,
    and the files get the mode the umask gives.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        Output path without extension, or with ``.png`` / ``.pdf``; parent folders are
        created.

    Returns
    -------
    list of pathlib.Path
        ``[png_path, pdf_path]``.
    """
    if not isinstance(fig, Figure):
        raise ValueError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    base = Path(path)
    if base.suffix.lower() in (".png", ".pdf"):
        base = base.with_suffix("")
    if not base.name:
        raise ValueError(f"path must name a file, got {path!r}")
    base.parent.mkdir(parents=True, exist_ok=True)
    png, pdf = base.with_suffix(".png"), base.with_suffix(".pdf")
    # Subsetting DejaVu's display-size glyphs (big radicals) makes fontTools warn about
    # the font's zero timestamps; the output is unaffected, so keep the logs clean.
    ft_log = logging.getLogger("fontTools")
    level = ft_log.level
    ft_log.setLevel(logging.ERROR)
    try:
        with matplotlib.rc_context({"pdf.fonttype": 42, "svg.hashsalt": "roughcontact"}):
            with atomic_output(png) as tmp:
                fig.savefig(tmp, format="png", dpi=_PNG_DPI, metadata={"Software": None})
            with atomic_output(pdf) as tmp:
                fig.savefig(tmp, format="pdf",
                            metadata={"CreationDate": None, "Creator": None, "Producer": None})
    finally:
        ft_log.setLevel(level)
    return [png, pdf]


# ----------------------------------------------------------------------- helpers
def _new_figure(width: float, height: float) -> Figure:
    return Figure(figsize=(width, height), layout="constrained")


def _require(ds: xr.Dataset, name: str, variables: Sequence[str]) -> None:
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"{name} must be an xarray.Dataset, got {type(ds).__name__}")
    missing = [v for v in variables if v not in ds]
    if missing:
        raise ValueError(f"{name} lacks variable(s) {missing}")


def _pick(values: np.ndarray, wanted, name: str) -> list[float]:
    have = [float(v) for v in values]
    if wanted is None:
        return have
    out = []
    for w in np.atleast_1d(wanted):
        matches = [h for h in have if np.isclose(h, float(w), rtol=1e-9, atol=0)]
        if not matches:
            raise ValueError(f"{name}={float(w)!r} is not in the data; available: {have}")
        out.append(matches[0])
    return out


def _unit_tex(units: str) -> str:
    """A CF-style unit string as mathtext: ``"length unit^-1/2"`` -> ``$(\\mathrm{length\\ unit})^{-1/2}$``."""
    if units in ("", "1"):
        return "1"
    base, _, power = units.partition("^")
    tex = r"\mathrm{" + base.strip().replace(" ", r"\ ") + "}"
    if " " in base.strip() and power:
        tex = f"({tex})"
    return f"${tex}^{{{power}}}$" if power else f"${tex}$"


def _fmt(v: float) -> str:
    return f"{float(v):g}"


def _lambda_label(k: float, which: str) -> str:
    return rf"$\lambda_{which} = L/{_fmt(k)}$"


def _run_summary(agg: xr.Dataset, stats: xr.Dataset) -> str:
    """What a contact figure shows, for its title: grid N, seeds per family, load range."""
    parts = []
    try:
        recorded = json.loads(agg.attrs.get("scene_parameters", "{}"))
    except ValueError:
        recorded = {}
    n = recorded.get("surface", {}).get("N") if isinstance(recorded, dict) else None
    if n is not None:
        parts.append(f"$N = {int(n)}$")
    seeds = stats["n_seeds"].values[stats["n_seeds"].values > 0] if "n_seeds" in stats else np.array([])
    if seeds.size:
        lo, hi = int(seeds.min()), int(seeds.max())
        parts.append(f"{lo} seeds" if lo == hi else f"{lo}-{hi} seeds")
    if "pressure" in agg and "e_star" in agg.attrs:
        p = agg["pressure"].values / float(agg.attrs["e_star"])
        if np.isfinite(p).any():
            parts.append(f"$p_0/E^*$ = {np.nanmin(p):.3g}-{np.nanmax(p):.3g}")
    return ", ".join(parts)


def _legend_below(fig: Figure, handles: list, title: str) -> None:
    """A two-column legend under the panels; the figure grows by its height, the panels keep theirs."""
    rows = int(np.ceil(len(handles) / 2)) + 1
    width, height = fig.get_size_inches()
    fig.set_size_inches(max(width, DOUBLE_COLUMN_IN), height + 0.19 * rows + 0.2)
    fig.legend(handles=handles, loc="outside lower center", ncols=2, title=title)


def _panel_grid(n: int) -> tuple[int, int, float, float]:
    ncols = 1 if n == 1 else min(n, 3)
    nrows = int(np.ceil(n / ncols))
    width = SINGLE_COLUMN_IN if n == 1 else DOUBLE_COLUMN_IN
    panel_w = (width - (1.3 if n == 1 else 1.4)) / ncols
    height = nrows * max(1.9, 0.85 * panel_w) + 0.3
    return nrows, ncols, width + (1.3 if n == 1 else 0.0), height


def _family_styles(k_ls: Sequence[float], hs: Sequence[float]):
    colour = {h: DATA_COLOURS[i % len(DATA_COLOURS)] for i, h in enumerate(hs)}
    marker = {k: _MARKERS[i % len(_MARKERS)] for i, k in enumerate(k_ls)}
    style = {k: _LINESTYLES[i % len(_LINESTYLES)] for i, k in enumerate(k_ls)}
    return colour, marker, style


def _family_handles(k_ls, hs, colour, marker, style) -> list[Line2D]:
    handles = [Line2D([], [], color=colour[h], lw=1.5, label=f"$H = {_fmt(h)}$") for h in hs]
    handles += [Line2D([], [], color="0.35", marker=marker[k], ls=style[k], label=_lambda_label(k, "l"))
                for k in k_ls]
    return handles


def _fit_constants(fit: xr.Dataset | None, k_l: float, k_s: float, estimator: str):
    """(kappa, mu, beta) of the H-pooled fit, or None where absent/NaN."""
    if fit is None:
        return None
    _require(fit, "fit", ("value",))
    if estimator not in list(fit["estimator"].values):
        raise ValueError(f"estimator={estimator!r} is not in fit (has {list(fit['estimator'].values)})")
    try:
        v = fit["value"].sel({"k_l": k_l, "k_s": k_s, "H_group": "pooled", "estimator": estimator})
    except KeyError:
        return None
    vals = [float(v.sel(constant=c)) for c in ("kappa", "mu", "beta")]
    return tuple(vals) if np.all(np.isfinite(vals)) else None


def _present(stats: xr.Dataset, k_l: float, k_s: float, h: float) -> bool:
    return int(stats["n_seeds"].sel(k_l=k_l, k_s=k_s, H=h)) > 0


def _e_star(agg: xr.Dataset) -> float:
    if "e_star" not in agg.attrs:
        raise ValueError("agg lacks the global attribute 'e_star'")
    e = float(agg.attrs["e_star"])
    if not (np.isfinite(e) and e > 0):
        raise ValueError(f"agg.attrs['e_star'] must be finite and > 0, got {agg.attrs['e_star']!r}")
    return e


#: Finite-load asperity models drawn in the area-load and kappa figures: line style per model.
ASPERITY_STYLES = {"bgt": ("-", "BGT"), "greenwood": ("-.", "Greenwood (2006)")}
#: The paper's contact evolution law (Yastrebov et al. 2012): kappa, mu, beta.
PAPER_CONSTANTS = {"kappa": 1.145 * KAPPA_BGT, "mu": 0.55, "beta": 0.21}
PAPER_CEL_LABEL = r"CEL, paper: $\kappa/\sqrt{2\pi}$ = 1.145, $\mu$ = 0.55, $\beta$ = 0.21"
BGT_LIMIT_LABEL = r"BGT small-load limit, $\kappa=\sqrt{2\pi}$"
#: Nayak's bandwidth of the paper's Fig. 5 comparison (Carbone & Bottiglione 2008).
PAPER_ALPHA = 2.0


def _asperity_alphas(agg: xr.Dataset) -> list[tuple[float, str, str]]:
    """``(alpha, colour, label)`` of the asperity curves: the paper's alpha = 2 and, when the
    surfaces carry it and it differs, their own mean Nayak bandwidth (profile moments)."""
    out = [(PAPER_ALPHA, "0.15", r"$\alpha = 2$ (paper)")]
    if "alpha" in agg:
        present = agg["case_present"] if "case_present" in agg else True
        alpha = float(agg["alpha"].where(present).mean(skipna=True))
        if np.isfinite(alpha) and alpha >= NAYAK_ALPHA_MIN and abs(alpha - PAPER_ALPHA) > 0.005:
            out.append((alpha, "0.6", rf"$\alpha = {alpha:.2f}$ (these surfaces)"))
    return out


def _asperity_handles(alphas) -> list[Line2D]:
    return [Line2D([], [], color=colour, lw=1.1, ls=ls, label=f"{name}, {label}")
            for alpha, colour, label in alphas for ls, name in ASPERITY_STYLES.values()]


def _mean_slope(stats: xr.Dataset) -> float:
    # All cases of a study share the target rms slope; its mean sets the theory lines.
    hp = stats["rms_slope_mean"].where(stats["n_seeds"] > 0)
    v = float(hp.mean(skipna=True))
    if not (np.isfinite(v) and v > 0):
        raise ValueError("stats has no finite positive rms_slope_mean")
    return v


def _selection(stats, k_l, k_s, hurst):
    ks_list = _pick(stats["k_s"].values, k_s, "k_s")
    kl_list = _pick(stats["k_l"].values, k_l, "k_l")
    h_list = _pick(stats["H"].values, hurst, "hurst")
    ks_list = [ks for ks in ks_list
               if any(_present(stats, kl, ks, h) for kl in kl_list for h in h_list)]
    if not ks_list:
        raise ValueError("no (k_l, k_s, H) family with data in the selection")
    return kl_list, ks_list, h_list


# ---------------------------------------------------------------------- figures
def _family_panels(stats, k_l, k_s, hurst, fit_k_l):
    """Selection, styles, the k_l of the drawn CEL, and one panel per k_s (Figs. 2-4)."""
    kl_list, ks_list, h_list = _selection(stats, k_l, k_s, hurst)
    colour, marker, style = _family_styles(kl_list, h_list)
    cel_kl = kl_list[-1] if fit_k_l is None else _pick(stats["k_l"].values, fit_k_l, "fit_k_l")[0]
    nrows, ncols, width, height = _panel_grid(len(ks_list))
    with matplotlib.rc_context(_STYLE):
        fig = _new_figure(width, height)
        axes = fig.subplots(nrows, ncols, squeeze=False)
    return kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes


def fig_representativity(rep_stats: xr.Dataset, *, hurst: float | None = None) -> Figure:
    """Mean Gaussian L2 error of the height PDF versus ``k_s``, one curve per ``k_l``.

    The paper's Fig. 1a / appendix figure: log-log axes, error bars are the standard
    error of the seed mean.

    Parameters
    ----------
    rep_stats : xarray.Dataset
        :func:`roughcontact.aggregate.representativity_statistics` output: ``epsilon_mean``,
        ``epsilon_sem``, ``n_seeds`` over ``(k_l, k_s, H)``.
    hurst : float, optional
        Which H to show; required when the dataset holds several.

    Returns
    -------
    matplotlib.figure.Figure
        3.4 in wide (plus the legend column).
    """
    _require(rep_stats, "rep_stats", ("epsilon_mean", "epsilon_sem", "n_seeds"))
    hs = [float(h) for h in rep_stats["H"].values]
    if hurst is None:
        if len(hs) != 1:
            raise ValueError(f"rep_stats holds several H {hs}; pass hurst= one of them")
        h = hs[0]
    else:
        h = _pick(rep_stats["H"].values, hurst, "hurst")[0]
    sub = rep_stats.sel(H=h)
    units = str(rep_stats["epsilon_mean"].attrs.get("units", "1"))
    with matplotlib.rc_context(_STYLE):
        fig = _new_figure(SINGLE_COLUMN_IN + 1.0, 2.6)
        ax = fig.add_subplot()
        k_ls = [float(k) for k in sub["k_l"].values]
        drawn = 0
        for i, kl in enumerate(k_ls):
            row = sub.sel(k_l=kl)
            ok = (row["n_seeds"] > 0) & np.isfinite(row["epsilon_mean"])
            if not bool(ok.any()):
                continue
            x = row["k_s"].values[ok.values]
            ax.errorbar(x, row["epsilon_mean"].values[ok.values], yerr=row["epsilon_sem"].values[ok.values],
                        color=DATA_COLOURS[i % len(DATA_COLOURS)], marker=_MARKERS[i % len(_MARKERS)],
                        ls=_LINESTYLES[i % len(_LINESTYLES)], label=f"$k_l = {_fmt(kl)}$")
            drawn += 1
        if drawn == 0:
            raise ValueError(f"rep_stats has no finite epsilon_mean at H={h}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ks_vals = sub["k_s"].values
        ax.set_xticks(ks_vals)
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(r"short cutoff $k_s = L/\lambda_s$ [1]")
        ax.set_ylabel(rf"mean $L_2$ error $\bar\varepsilon$ [{_unit_tex(units)}]")
        ax.set_title(rf"$H = {_fmt(h)}$, error bars: s.e.m. over seeds")
        fig.legend(loc="outside right upper", title=r"$k_l = L/\lambda_l$")
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
        7 in wide (3.4 in for a single example), two rows.
    """
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
    n = len(fields)
    lo = min(float(h.min()) for h, _ in fields) / length
    hi = max(float(h.max()) for h, _ in fields) / length
    width = SINGLE_COLUMN_IN if n == 1 else DOUBLE_COLUMN_IN
    col_w = width / n
    with matplotlib.rc_context(_STYLE):
        fig = _new_figure(width, col_w * 0.95 + 1.7)
        axes = fig.subplots(2, n, squeeze=False, gridspec_kw={"height_ratios": [col_w * 0.95, 1.5]})
        for j, (h, label) in enumerate(fields):
            h = h / length
            vmin, vmax = (lo, hi) if shared_scale else (float(h.min()), float(h.max()))
            ax = axes[0, j]
            im = ax.imshow(h.T, origin="lower", extent=(0, 1, 0, 1), interpolation="nearest", vmin=vmin, vmax=vmax)
            ax.set_title(label)
            ax.set_xlabel(r"$x/L$")
            if j == 0:
                ax.set_ylabel(r"$y/L$")
            cb = fig.colorbar(im, ax=ax, shrink=0.8, pad=0.02)
            cb.ax.set_title(r"$h/L$", fontsize=7)
            mean, std = float(h.mean()), float(h.std())
            axh = axes[1, j]
            axh.hist(h.ravel(), bins=bins, range=(vmin, vmax), density=True, color=DATA_COLOURS[1], alpha=0.6,
                     label="surface")
            axh.set_xlim(vmin, vmax)
            grid = np.linspace(vmin, vmax, 200)
            if std > 0:
                axh.plot(grid, np.exp(-0.5 * ((grid - mean) / std) ** 2) / (np.sqrt(2 * np.pi) * std),
                         color=OKABE_ITO[0], label=r"Gaussian $G(h,\bar h,\sigma)$")
            axh.set_xlabel(r"height $h/L$")
            if j == 0:
                axh.set_ylabel(r"PDF of $h/L$")
        handles, labels = axes[1, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncols=2)
    return fig


def fig_area_load(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
                  k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
                  hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
                  estimator: str = "joint") -> Figure:
    """Contact-area fraction versus ``p0/E*`` (the paper's Fig. 2), one panel per ``k_s``.

    Each ``(lambda_l, lambda_s, H)`` family is its seed-mean curve with a +-1 standard
    deviation band. Black lines: BGT (``kappa = sqrt(2 pi)``) and Persson
    (``sqrt(8/pi)``) asymptotes ``A/A0 = kappa p0 / (h' E*)``; grey dotted: Persson's
    full ``erf`` curve; with ``fit``, the H-pooled CEL of ``fit_k_l`` (default: the
    largest ``k_l`` shown, the most representative surfaces) as a thick grey line.
    Theory lines use the mean rms slope of the shown cases.

    Parameters
    ----------
    agg : xarray.Dataset
        Combined contact dataset (for ``e_star``).
    stats : xarray.Dataset
        :func:`roughcontact.aggregate.seed_statistics` output.
    fit : xarray.Dataset, optional
        :func:`roughcontact.fit.fit_cel` output.
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
    _require(stats, "stats", ("area_fraction_mean", "area_fraction_std", "pressure_mean",
                              "rms_slope_mean", "n_seeds"))
    e_star = _e_star(agg)
    hp = _mean_slope(stats)
    alphas = _asperity_alphas(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = _family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(_STYLE):
        xmax = ymax = 0.0
        drew_fit = False
        for idx, ks in enumerate(ks_list):
            ax = axes.flat[idx]
            for kl in kl_list:
                for h in h_list:
                    if not _present(stats, kl, ks, h):
                        continue
                    s = stats.sel(k_l=kl, k_s=ks, H=h)
                    x = s["pressure_mean"].values / e_star
                    y, sd = s["area_fraction_mean"].values, s["area_fraction_std"].values
                    ax.fill_between(x, y - sd, y + sd, color=colour[h], alpha=0.2, lw=0)
                    ax.plot(x, y, color=colour[h], marker=marker[kl], ls=style[kl], markevery=3)
                    xmax = max(xmax, float(np.nanmax(x)))
                    ymax = max(ymax, float(np.nanmax(y + sd)))
            ax.set_title(_lambda_label(ks, "s"))
        for idx, ks in enumerate(ks_list):
            # Second pass: theory over the common load range of all panels.
            ax = axes.flat[idx]
            p = np.linspace(0, xmax * e_star, 200)
            consts = _fit_constants(fit, cel_kl, ks, estimator)
            if consts is not None:
                ax.plot(p / e_star, cel_area(p, kappa=consts[0], mu=consts[1], beta=consts[2],
                                             rms_slope=hp, e_star=e_star),
                        color="0.45", lw=2.2, alpha=0.8, zorder=1)
                drew_fit = True
            ax.plot(p / e_star, linear_area(p, kappa=KAPPA_BGT, rms_slope=hp, e_star=e_star),
                    color=OKABE_ITO[0], lw=0.9, ls="-", zorder=3)
            ax.plot(p / e_star, linear_area(p, kappa=KAPPA_PERSSON, rms_slope=hp, e_star=e_star),
                    color=OKABE_ITO[0], lw=0.9, ls="--", zorder=3)
            ax.plot(p / e_star, persson_area(p, rms_slope=hp, e_star=e_star),
                    color="0.5", lw=0.9, ls=":", zorder=3)
            for alpha, shade, _ in alphas:
                for model, (ls, _name) in ASPERITY_STYLES.items():
                    ax.plot(p / e_star, asperity_area(p, alpha=alpha, rms_slope=hp, e_star=e_star, model=model),
                            color=shade, lw=1.1, ls=ls, zorder=3)
            ax.set_xlim(0, xmax)
            ax.set_ylim(0, ymax * 1.05)
            ax.set_xlabel(r"$p_0/E^*$ [1]")
            ax.set_ylabel(r"$A/A_0$ [1]")
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = _family_handles(kl_list, h_list, colour, marker, style)
        handles += [Line2D([], [], color=OKABE_ITO[0], lw=0.9, label=BGT_LIMIT_LABEL),
                    Line2D([], [], color=OKABE_ITO[0], lw=0.9, ls="--",
                           label=r"Persson small-load limit, $\kappa=\sqrt{8/\pi}$"),
                    Line2D([], [], color="0.5", lw=0.9, ls=":", label=r"Persson, erf")]
        handles += _asperity_handles(alphas)
        if drew_fit:
            handles.append(Line2D([], [], color="0.45", lw=2.2, alpha=0.8,
                                  label=f"CEL fit ({estimator}), " + _lambda_label(cel_kl, "l")))
        fig.suptitle(_run_summary(agg, stats))
        _legend_below(fig, handles, f"$h' = {hp:.3g}$; bands: $\\pm 1$ s.d.")
    return fig


def fig_kappa(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
              k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
              hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
              estimator: str = "paper") -> Figure:
    """``kappa = E* h' / pbar`` versus ``A/A0`` (the paper's Fig. 3), one panel per ``k_s``.

    Seed means with standard-error bars per ``(lambda_l, H)``; the BGT limit
    ``sqrt(2 pi)`` (Persson's ``sqrt(8/pi) ~ 1.60`` lies below the usual range and is
    only drawn if inside it); with ``fit``, the CEL's ``kappa(a) = kappa (1 - beta
    a^(1-mu))^(1/(1-mu))`` of ``fit_k_l`` and the fit window (shaded).

    Parameters
    ----------
    agg, stats, fit, k_l, k_s, hurst, fit_k_l, estimator
        As in :func:`fig_area_load`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require(stats, "stats", ("kappa_mean", "kappa_sem", "area_fraction_mean", "n_seeds"))
    _e_star(agg)
    alphas = _asperity_alphas(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = _family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(_STYLE):
        drew_fit = False
        for idx, ks in enumerate(ks_list):
            ax = axes.flat[idx]
            amax, ylo, yhi = 0.0, np.inf, -np.inf
            for kl in kl_list:
                for h in h_list:
                    if not _present(stats, kl, ks, h):
                        continue
                    s = stats.sel(k_l=kl, k_s=ks, H=h)
                    x, y, e = (s[v].values for v in ("area_fraction_mean", "kappa_mean", "kappa_sem"))
                    ax.errorbar(x, y, yerr=e, color=colour[h], marker=marker[kl], ls=style[kl],
                                markevery=2, errorevery=2, elinewidth=0.6)
                    amax = max(amax, float(np.nanmax(x)))
                    ylo, yhi = min(ylo, float(np.nanmin(y - e))), max(yhi, float(np.nanmax(y + e)))
            consts = _fit_constants(fit, cel_kl, ks, estimator)
            if consts is not None:
                a = np.linspace(0, amax, 200)
                ax.plot(a, cel_kappa(a, kappa=consts[0], mu=consts[1], beta=consts[2]),
                        color="0.45", lw=2.2, alpha=0.8, zorder=1)
                ax.axvspan(float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan)),
                           color="0.9", zorder=0, lw=0)
                ylo, yhi = min(ylo, consts[0]), max(yhi, consts[0])
                drew_fit = True
            ax.axhline(KAPPA_BGT, color=OKABE_ITO[0], lw=0.9)
            ylo, yhi = min(ylo, KAPPA_BGT), max(yhi, KAPPA_BGT)
            a = np.linspace(0, amax, 200)
            ax.plot(a, cel_kappa(a, **PAPER_CONSTANTS), color=OKABE_ITO[0], lw=1.4, ls=":", zorder=4)
            a = np.linspace(0, amax, 120)
            for alpha, shade, _ in alphas:
                for model, (ls, _name) in ASPERITY_STYLES.items():
                    # Below the small-load limit sqrt(2 pi): they set the lower bound of the axis.
                    k = asperity_kappa(a, alpha=alpha, model=model)
                    ax.plot(a, k, color=shade, lw=1.1, ls=ls, zorder=2)
                    ylo = min(ylo, float(np.min(k)))
            pad = 0.05 * (yhi - ylo)
            persson_shown = ylo - pad <= KAPPA_PERSSON <= yhi + pad
            if persson_shown:
                ax.axhline(KAPPA_PERSSON, color=OKABE_ITO[0], lw=0.9, ls="--")
            ax.set_ylim(ylo - pad, yhi + pad)
            ax.set_xlim(0, amax * 1.02)
            ax.set_title(_lambda_label(ks, "s"))
            ax.set_xlabel(r"$A/A_0$ [1]")
            ax.set_ylabel(r"$\kappa = E^* h'/\bar p$ [1]")
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = _family_handles(kl_list, h_list, colour, marker, style)
        handles.append(Line2D([], [], color=OKABE_ITO[0], lw=0.9, label=BGT_LIMIT_LABEL))
        handles.append(Line2D([], [], color=OKABE_ITO[0], lw=0.9, ls="--", label=(
            r"Persson small-load limit, $\kappa=\sqrt{8/\pi}$" if persson_shown
            else rf"Persson, $\kappa=\sqrt{{8/\pi}}$ = {KAPPA_PERSSON:.2f}: below the axis")))
        handles += _asperity_handles(alphas)
        handles.append(Line2D([], [], color=OKABE_ITO[0], lw=1.4, ls=":", label=PAPER_CEL_LABEL))
        if drew_fit:
            handles.append(Line2D([], [], color="0.45", lw=2.2, alpha=0.8, label=_fit_label(
                "this run", estimator, cel_kl, _fit_constants(fit, cel_kl, ks_list[0], estimator)
                if len(ks_list) == 1 else None, _fit_constrained(fit, cel_kl, ks_list[0], estimator))))
            handles.append(Patch(facecolor="0.9", edgecolor="none", label=(
                f"fit window $A/A_0 \\in$ [{float(fit.attrs.get('window_low', np.nan)):g}, "
                f"{float(fit.attrs.get('window_high', np.nan)):g}]")))
        fig.suptitle(_run_summary(agg, stats))
        _legend_below(fig, handles, "error bars: s.e.m.")
    return fig


def _fit_constrained(fit: xr.Dataset, k_l: float, k_s: float, estimator: str) -> bool:
    """Whether every constant of the H-pooled fit is constrained by the data (see fit.constrained_flags)."""
    if "constrained" not in fit:
        return True
    sel = {"k_l": k_l, "k_s": k_s, "H_group": "pooled", "estimator": estimator}
    return bool(fit["constrained"].sel(sel).all())


def _fit_label(who: str, estimator: str, k_l: float, consts, constrained: bool = True) -> str:
    """Legend text of a fitted CEL curve, with its constants when one curve is drawn and the
    data constrain them (else "not constrained": an interval wider than the value is no number)."""
    text = f"CEL, {who} ({estimator}), " + _lambda_label(k_l, "l")
    if not constrained:
        return text + ": not constrained by the data"
    if consts is not None:
        text += rf": $\kappa/\sqrt{{2\pi}}$ = {consts[0] / KAPPA_BGT:.3f}, $\mu$ = {consts[1]:.2f}, " \
                rf"$\beta$ = {consts[2]:.2f}"
    return text


def fig_dpbar(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
              k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
              hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
              estimator: str = "paper") -> Figure:
    """``d pbar / d p0`` versus ``A/A0`` on log-log axes (the paper's Fig. 4).

    Seed means with standard-error bars (non-positive means are not drawn on the log
    axis); the paper's power law ``0.21 (A0/A)^0.55`` (grey dotted) and, with ``fit``,
    the fitted ``beta (A0/A)^mu`` of ``fit_k_l``.

    Parameters
    ----------
    agg, stats, fit, k_l, k_s, hurst, fit_k_l, estimator
        As in :func:`fig_area_load`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _require(stats, "stats", ("dpbar_dp0_mean", "dpbar_dp0_sem", "area_fraction_mean", "n_seeds"))
    _e_star(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = _family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(_STYLE):
        drew_fit = False
        for idx, ks in enumerate(ks_list):
            ax = axes.flat[idx]
            amin, amax = np.inf, 0.0
            for kl in kl_list:
                for h in h_list:
                    if not _present(stats, kl, ks, h):
                        continue
                    s = stats.sel(k_l=kl, k_s=ks, H=h)
                    x, y, e = (s[v].values for v in ("area_fraction_mean", "dpbar_dp0_mean", "dpbar_dp0_sem"))
                    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
                    if not ok.any():
                        continue
                    # Clip the lower error bar so it stays on the positive log axis.
                    lower = np.minimum(e[ok], 0.95 * y[ok])
                    ax.errorbar(x[ok], y[ok], yerr=[lower, e[ok]], color=colour[h], marker=marker[kl],
                                ls=style[kl], elinewidth=0.6)
                    amin, amax = min(amin, float(x[ok].min())), max(amax, float(x[ok].max()))
            if not np.isfinite(amin):
                continue
            a = np.geomspace(amin, amax, 100)
            ax.plot(a, cel_dpbar_dp0(a, mu=0.55, beta=0.21), color="0.5", lw=0.9, ls=":", zorder=3)
            consts = _fit_constants(fit, cel_kl, ks, estimator)
            if consts is not None:
                ax.plot(a, cel_dpbar_dp0(a, mu=consts[1], beta=consts[2]), color="0.45", lw=2.2,
                        alpha=0.8, zorder=1)
                drew_fit = True
            ax.set_xscale("log")
            ax.set_yscale("log")
            # Plain decimals: the data span about one decade, where 4x10^0 reads badly.
            for axis in (ax.xaxis, ax.yaxis):
                axis.set_major_formatter(FormatStrFormatter("%g"))
            # Minor labels help within a decade but collide once the axis spans more.
            lo, hi = ax.get_ylim()
            ax.yaxis.set_minor_formatter(FormatStrFormatter("%g") if hi / lo < 12 else NullFormatter())
            ax.set_title(_lambda_label(ks, "s"))
            ax.set_xlabel(r"$A/A_0$ [1]")
            ax.set_ylabel(r"$\partial\bar p/\partial p_0$ [1]")
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = _family_handles(kl_list, h_list, colour, marker, style)
        handles.append(Line2D([], [], color="0.5", lw=0.9, ls=":",
                              label=r"paper: $0.21\,(A_0/A)^{0.55}$"))
        if drew_fit:
            handles.append(Line2D([], [], color="0.45", lw=2.2, alpha=0.8,
                                  label=rf"fit $\beta(A_0/A)^\mu$ ({estimator}), " + _lambda_label(cel_kl, "l")))
        fig.suptitle(_run_summary(agg, stats))
        fig.legend(handles=handles, loc="outside right upper", title="error bars: s.e.m.")
    return fig


def fig_accuracy(summary: xr.Dataset) -> Figure:
    """What accuracy costs: relative error against wall time per surface, log-log.

    Two panels: kappa at A/A0 = ``summary.attrs['kappa_at']`` and A/A0 at p_max. One
    series per axis varied (N, tol, n_steps, seeds), each point labelled with its value;
    the N axis is drawn twice, pixel-counted (solid) and perimeter-corrected (dashed);
    the shipped defaults are marked with a star. Zero errors (the reference itself)
    are not drawn on log axes.
    """
    _require(summary, "summary", ["time_per_case", "err_kappa", "err_area", "axis", "value"])
    with matplotlib.rc_context(_STYLE):
        return _draw_accuracy(summary)


def _draw_accuracy(summary: xr.Dataset) -> Figure:
    fig = _new_figure(7.0, 3.2)
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
            t = summary["time_per_case"].values[sel]
            order = np.argsort(t)
            for variant, style, label in ((metric, "-", names[name]),
                                          (f"{metric}_corrected", "--", "N, perimeter-corrected")):
                if variant.endswith("corrected") and name != "N":
                    continue
                e = summary[f"err_{variant}"].values[sel][order]
                ok = np.isfinite(e) & (e > 0)
                ax.plot(t[order][ok], e[ok], style, marker="o", ms=3, color=colour, label=label)
                if style == "-":
                    for ti, ei, v in zip(t[order][ok], e[ok], summary["value"].values[sel][order][ok], strict=True):
                        ax.annotate(str(v), (ti, ei), textcoords="offset points", xytext=(3, 3), fontsize=6,
                                    color=colour)
        d = np.flatnonzero(axis_of == "defaults")
        if d.size:
            e = summary[f"err_{metric}"].values[d]
            if np.all(e > 0):
                ax.plot(summary["time_per_case"].values[d], e, "*", ms=10, color="black", label="defaults")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time [s] (per surface; seeds: all k seeds)")
        ax.set_ylabel("relative error [1]")
        ax.set_title(title, fontsize=9)
    handles, labels = axes[0].get_legend_handles_labels()
    uniq = dict(zip(labels, handles, strict=True))
    fig.legend(uniq.values(), uniq.keys(), loc="outside right center", fontsize=7, frameon=False)
    return fig
