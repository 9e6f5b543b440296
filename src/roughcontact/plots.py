"""Figures of the study (Yastrebov, Anciaux & Molinari 2012, Figs. 1-4 and appendix).

Each ``fig_*`` function takes datasets and returns a :class:`matplotlib.figure.Figure`
built without pyplot (no global figure registry, no GUI backend); :func:`save_figure`
writes it as PNG and PDF with byte-identical output on every rerun.

Conventions: single-column figures are 3.4 in wide, multi-panel ones 7 in; legends sit
outside the axes; colours are the Okabe-Ito palette (distinguishable with the common
colour-vision deficiencies), one colour per Hurst exponent; the long cutoff
``lambda_l = L / k_l`` is told apart by marker and line style. Theory curves are black
or grey, except Persson's, in reddish purple (:data:`PERSSON_COLOUR`). Load steps whose solve
did not converge are left out of every line and seed mean, drawn as grey crosses
(:data:`UNCONVERGED_STYLE`) and counted in the legend. Symbols: ``p0``
applied mean pressure, ``E*`` contact modulus, ``h'`` rms slope, ``A/A0`` contact-area
fraction, ``pbar`` mean contact pressure, ``kappa = E* h' / pbar``.
"""

from __future__ import annotations

import json
import logging
import os
import re
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib
import matplotlib.colors as mcolors
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FormatStrFormatter, FuncFormatter, NullFormatter

from .aggregate import log_window_edges, seed_reduce, windowed_load_slope
from .fit import at_bound
from .io import atomic_output
from .quantities import LENGTH_UNITS, PRESSURE_UNITS
from .representativity import scale_free_statistics
from .theory import (
    KAPPA_BGT,
    KAPPA_PERSSON,
    NAYAK_ALPHA_MIN,
    asperity_area,
    asperity_kappa,
    asperity_max_load,
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


#: One factor of a unit string of :func:`roughcontact.quantities.cf_unit` (``um``, ``um^-2``), of
#: :func:`_number_unit` (``um^(-1/2)``) or of files of older versions (``um**-2``, ``um^-0.5``).
_UNIT_FACTOR = re.compile(r"^([A-Za-z]+)(?:(?:\^|\*\*)\(?([-+]?\d+(?:/\d+|\.\d+)?)\)?)?$")
_UNIT_SYMBOLS = frozenset(LENGTH_UNITS + PRESSURE_UNITS + ("s",)) - {"1"}


def _unit_tex(units: str) -> str:
    """A unit string as mathtext, upright, factors separated by a thin space.

    The strings of :func:`roughcontact.quantities.cf_unit` and :func:`_number_unit`: ``"um^(-1/2)"``
    -> ``$\\mathrm{\\mu m}^{-1/2}$``, ``"MPa um^-1"`` -> ``$\\mathrm{MPa}\\,\\mathrm{\\mu m}^{-1}$``,
    ``"1"`` -> ``"1"``. Other strings (files of older versions) as one upright word with
    its power: ``"length unit^-1/2"`` -> ``$(\\mathrm{length\\ unit})^{-1/2}$``.
    """
    units = units.strip()
    if units in ("", "1"):
        return "1"
    factors = [_UNIT_FACTOR.match(f) for f in units.split()]
    if all(m is not None and m.group(1) in _UNIT_SYMBOLS for m in factors):
        parts = []
        for m in factors:
            base, power = m.groups()
            tex = r"\mathrm{" + (r"\mu m" if base == "um" else base) + "}"
            parts.append(f"{tex}^{{{power}}}" if power else tex)
        return "$" + r"\,".join(parts) + "$"
    base, _, power = units.partition("^")
    tex = r"\mathrm{" + base.strip().replace(" ", r"\ ") + "}"
    if " " in base.strip() and power:
        tex = f"({tex})"
    return f"${tex}^{{{power}}}$" if power else f"${tex}$"


def _number_unit(attrs) -> str:
    """The unit a variable's number is in, for a label: its ``units``, or for a value written for lengths in
    a reference unit (:func:`roughcontact.quantities.per_reference_length`) that unit to its power, e.g.
    ``"um^(-1/2)"`` for ``epsilon`` (``units`` ``"1"``, ``reference_length_units`` ``"um"``, power ``"-1/2"``)."""
    ref, power = attrs.get("reference_length_units"), attrs.get("reference_length_power")
    if ref is None or power is None or ref == "1":
        return str(attrs.get("units", "1"))
    return f"{ref}^({power})"


def _fmt(v: float) -> str:
    return f"{float(v):g}"


def _lambda_label(k: float, which: str) -> str:
    """``lambda = L/k`` as the paper writes it: ``L`` itself for ``k = 1``."""
    return rf"$\lambda_{which} = L$" if float(k) == 1.0 else rf"$\lambda_{which} = L/{_fmt(k)}$"


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


# -------------------------------------------------------------- unconverged steps
#: Load steps whose solve did not converge: small grey crosses under the data, out of the means.
UNCONVERGED_STYLE = {"color": "0.5", "marker": "x", "ls": "none", "ms": 3.0, "mew": 0.7}


def _unconverged(ds: xr.Dataset, present: xr.DataArray | bool | None = None) -> xr.DataArray | None:
    """The load steps that did not converge: boolean, dims of ``ds.converged`` (``(k_l, k_s, H,
    seed, step)`` or ``(topography, step)``); None where ``ds`` has no ``converged`` (files of
    older versions: every step is taken as converged).

    Only the steps of cases in ``present`` count (default ``ds.case_present``: a grid hole, whose
    ``converged`` is False, has no steps); ``True`` counts every case.
    """
    if "converged" not in ds:
        return None
    if present is None:
        present = ds["case_present"].astype(bool) if "case_present" in ds else True
    return ~ds["converged"].astype(bool) & present


def _converged_family(agg: xr.Dataset, stats: xr.Dataset, bad: xr.DataArray | None, family: Mapping,
                      names: Sequence[str]) -> dict[str, np.ndarray]:
    """Seed statistics of one family over its converged steps, by name, shape ``(n_steps,)`` each.

    ``family``: ``{"k_l": .., "k_s": .., "H": ..}``; ``names``: statistics of
    :func:`roughcontact.aggregate.seed_statistics` (``"kappa_mean"``, ``"area_fraction_std"``,
    ``"pressure_mean"`` ...), in the units of their variable; ``bad``: :func:`_unconverged` of
    ``agg``. Taken from ``stats`` where every step of the family converged (or ``bad`` is None),
    else recomputed from ``agg`` by :func:`roughcontact.aggregate.seed_statistics`' reduction
    with the unconverged ``(seed, step)`` left out (a step none of whose seeds converged is NaN,
    and so is the s.d. of a step with one converged seed).
    """
    fam_bad = None if bad is None else bad.sel(family)
    if fam_bad is None or not bool(fam_bad.any()):
        return {name: stats[name].sel(family).values for name in names}
    case = agg.sel(family)
    ok = ~fam_bad & (case["case_present"].astype(bool) if "case_present" in case else True)
    n_ok = ok.sum("seed")
    out = {}
    for name in names:
        var, stat = name.rsplit("_", 1)
        out[name] = seed_reduce(case[var], ok, n_ok, var, "1")[stat].transpose("step").values
    return out


def _masked_points(x: xr.DataArray, y: xr.DataArray, mask: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """``x`` and ``y`` where ``mask`` is True, broadcast against each other, flattened: shape ``(n,)`` each."""
    x, y, mask = (v.transpose(*mask.dims) for v in xr.broadcast(x, y, mask))
    m = mask.values.astype(bool)
    return x.values[m].astype(float), y.values[m].astype(float)


def _family_unconverged(agg: xr.Dataset, bad: xr.DataArray | None, family: Mapping, x: str,
                        y: str) -> tuple[np.ndarray, np.ndarray]:
    """Values of the variables ``x`` and ``y`` at the unconverged steps (``bad``, :func:`_unconverged`)
    of one family, shape ``(n,)`` each."""
    mask = None if bad is None else bad.sel(family)
    if mask is None or not bool(mask.any()):
        return np.array([]), np.array([])
    case = agg.sel(family)
    return _masked_points(case[x], case[y], mask)


def _draw_unconverged(ax, x: np.ndarray, y: np.ndarray) -> None:
    """The unconverged steps ``(x, y)``, shape ``(n,)`` each, as crosses (nothing for ``n = 0``)."""
    if x.size:
        ax.plot(x, y, zorder=1.5, **UNCONVERGED_STYLE)


def _n_outside(ax, x: np.ndarray, y: np.ndarray) -> int:
    """How many points ``(x, y)`` the axes do not show at their current limits (non-finite ones,
    and non-positive ones on a log axis, included)."""
    inside = np.isfinite(x) & np.isfinite(y)
    with np.errstate(invalid="ignore"):
        for v, (lo, hi), scale in ((x, ax.get_xlim(), ax.get_xscale()), (y, ax.get_ylim(), ax.get_yscale())):
            inside &= (v >= min(lo, hi)) & (v <= max(lo, hi)) & ((v > 0) if scale == "log" else True)
    return int(x.size - inside.sum())


def _unconverged_handles(n: int, n_off: int, left_out_of: str = "lines and means") -> list[Line2D]:
    """Legend entry of ``n`` unconverged steps, ``n_off`` of them outside the axes; none for ``n = 0``."""
    if not n:
        return []
    off = f"; {n_off} outside the axes" if n_off else ""
    return [Line2D([], [], **UNCONVERGED_STYLE,
                   label=f"{n} unconverged load step{'s' if n != 1 else ''}, left out of the {left_out_of}{off}")]


#: Finite-load asperity models drawn in the area-load and kappa figures: line style per model.
ASPERITY_STYLES = {"bgt": ("-", "BGT"), "greenwood": ("-.", "Greenwood (2006)")}
#: The paper's contact evolution law (Yastrebov et al. 2012): kappa, mu, beta.
PAPER_CONSTANTS = {"kappa": 1.145 * KAPPA_BGT, "mu": 0.55, "beta": 0.21}
PAPER_CEL_LABEL = r"CEL, paper: $\kappa/\sqrt{2\pi}$ = 1.145, $\mu$ = 0.55, $\beta$ = 0.21"
BGT_LIMIT_LABEL = r"BGT small-load limit, $\kappa=\sqrt{2\pi}$"
#: Nayak's bandwidth of the paper's Fig. 5 comparison (Carbone & Bottiglione 2008).
PAPER_ALPHA = 2.0


#: Largest relative spread of the cases' Nayak alpha for which one "these surfaces" curve is drawn.
ALPHA_SPREAD_MAX = 0.1


def _asperity_alphas(agg: xr.Dataset) -> list[tuple[float, str, str]]:
    """``(alpha, colour, label)`` of the asperity curves: the paper's alpha = 2 and, when the
    surfaces carry it, it differs and the cases share it (relative spread of the means per
    (k_l, k_s) family at most :data:`ALPHA_SPREAD_MAX`), their own mean Nayak bandwidth
    (profile moments).

    Families of different bandwidth (k_s / k_l from 2 to 128 gives alpha from ~1.5 to ~30)
    have no common alpha: their mean would be a curve that describes none of them.
    """
    out = [(PAPER_ALPHA, "0.15", r"$\alpha = 2$ (paper)")]
    if "alpha" in agg:
        present = agg["case_present"] if "case_present" in agg else True
        alphas = agg["alpha"].where(present)
        family = alphas.mean([d for d in alphas.dims if d not in ("k_l", "k_s")], skipna=True)
        alpha = float(alphas.mean(skipna=True))
        spread = (float(family.max(skipna=True)) - float(family.min(skipna=True))) / alpha if family.size else 0.0
        if (np.isfinite(alpha) and alpha >= NAYAK_ALPHA_MIN and abs(alpha - PAPER_ALPHA) > 0.005
                and spread <= ALPHA_SPREAD_MAX):
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


def _rep_hurst(rep: xr.Dataset, hurst: float | None) -> float:
    hs = [float(h) for h in rep["H"].values]
    if hurst is None:
        if len(hs) != 1:
            raise ValueError(f"rep_stats holds several H {hs}; pass hurst= one of them")
        return hs[0]
    return _pick(rep["H"].values, hurst, "hurst")[0]


def _rep_summary(rep: xr.Dataset, h: float) -> str:
    """What a representativity figure shows: grid N, seeds, histogram bins, H, rms height."""
    try:
        recorded = json.loads(rep.attrs.get("scene_parameters", "{}"))
    except ValueError:
        recorded = {}
    recorded = recorded if isinstance(recorded, dict) else {}
    surface = recorded.get("surface", {}) if isinstance(recorded.get("surface"), dict) else {}
    parts = [f"$N = {int(surface['N'])}$"] if "N" in surface else []
    seeds = rep["n_seeds"].values[rep["n_seeds"].values > 0]
    if seeds.size:
        lo, hi = int(seeds.min()), int(seeds.max())
        parts.append(f"{lo} seeds" if lo == hi else f"{lo}-{hi} seeds")
    bins = rep.attrs.get("n_bins", recorded.get("n_bins"))
    if bins is not None:
        parts.append(f"{int(bins)} bins")
    parts.append(f"$H = {_fmt(h)}$")
    sigma = float(rep["std_height"].mean()) if "std_height" in rep else surface.get("rms_height")
    if sigma is not None and np.isfinite(sigma):
        parts.append(rf"rms height $\sigma$ = {float(sigma):.3g}")
    return ", ".join(parts)


def _plain_log_labels(axis) -> None:
    """Plain decimals on a log axis (0.3, not 3x10^-1): the decades, and 2, 3, 5 times them
    where the axis spans less than two decades (decided when drawn, from its limits)."""
    def minor(v, _pos):
        lo, hi = sorted(axis.get_view_interval())
        mantissa = v / 10.0 ** np.floor(np.log10(v) + 1e-9)
        return f"{v:g}" if hi / lo < 100 and any(np.isclose(mantissa, (2, 3, 5))) else ""

    axis.set_major_formatter(FormatStrFormatter("%g"))
    axis.set_minor_formatter(FuncFormatter(minor))


def _rep_curves(ax, sub: xr.Dataset, ylabel: str, title: str) -> None:
    """Seed-mean eps against k_s, one curve per k_l, s.e.m. bars; log-log with the k_s as ticks."""
    for i, kl in enumerate(float(k) for k in sub["k_l"].values):
        row = sub.sel(k_l=kl)
        ok = ((row["n_seeds"] > 0) & np.isfinite(row["epsilon_mean"])).values
        if ok.any():
            ax.errorbar(row["k_s"].values[ok], row["epsilon_mean"].values[ok], yerr=row["epsilon_sem"].values[ok],
                        color=DATA_COLOURS[i % len(DATA_COLOURS)], marker=_MARKERS[i % len(_MARKERS)],
                        ls=_LINESTYLES[i % len(_LINESTYLES)], label=f"$k_l = {_fmt(kl)}$")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ks = [float(k) for k in sub["k_s"].values]
    labelled = ks[:1]
    for k in ks[1:]:  # a label only 1.4x beyond the last one: 32 and 40 would collide
        if k / labelled[-1] >= 1.4:
            labelled.append(k)
    ax.set_xticks(ks, [_fmt(k) if k in labelled else "" for k in ks])
    ax.xaxis.set_minor_formatter(NullFormatter())
    _plain_log_labels(ax.yaxis)
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
    ax.set_xticks(range(len(kss)), [_fmt(k) for k in kss])
    ax.set_yticks(range(len(kls)), [_fmt(k) for k in kls])
    ax.set_xlabel(r"short cutoff $k_s$ [1]")
    ax.set_ylabel(r"long cutoff $k_l$ [1]")
    ax.set_title(rf"(c) {symbol} over $(k_l, k_s)$")
    ax.set_label("epsilon map")
    cb = fig.colorbar(mesh, ax=ax, shrink=0.9, pad=0.02)
    cb.set_label(f"{symbol} [{unit}]")
    _plain_log_labels(cb.ax.yaxis)


def _rep_panels(rep: xr.Dataset, h: float) -> list[tuple[xr.Dataset, str, str, str]]:
    """``(statistics at H=h, symbol, unit, title)`` of the paper's eps and, when the per-case
    data allow it, of the scale-free eps (:func:`roughcontact.representativity.scale_free_statistics`)."""
    units = _unit_tex(_number_unit(rep["epsilon_mean"].attrs))
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
    (:func:`roughcontact.representativity.scale_free_epsilon`). Log-log axes, error bars
    the standard error of the seed mean. Panel (c), when data exist for at least two
    ``k_l`` and two ``k_s``: the paper's Fig. 1a as a map, the seed-mean eps (scale-free
    where available) as colour over ``k_l x k_s``. The title states N, seeds, bins, H
    and the rms height.

    Parameters
    ----------
    rep_stats : xarray.Dataset
        :func:`roughcontact.aggregate.representativity_statistics` output: ``epsilon_mean``,
        ``epsilon_sem``, ``n_seeds`` over ``(k_l, k_s, H)``, optionally merged with the
        per-case ``epsilon`` and ``std_height`` over ``(k_l, k_s, H, seed)`` as in the
        workflow's ``aggregate/representativity.nc``.
    hurst : float, optional
        Which H to show; required when the dataset holds several.

    Returns
    -------
    matplotlib.figure.Figure
        7 in wide with two or three panels (4.4 in with one), legend below.
    """
    _require(rep_stats, "rep_stats", ("epsilon_mean", "epsilon_sem", "n_seeds"))
    h = _rep_hurst(rep_stats, hurst)
    panels = _rep_panels(rep_stats, h)
    kls, kss = _rep_grid(panels[-1][0])
    n = len(panels) + (len(kls) >= 2 and len(kss) >= 2)
    with matplotlib.rc_context(_STYLE):
        fig = _new_figure(DOUBLE_COLUMN_IN if n > 1 else SINGLE_COLUMN_IN + 1.0, 2.9)
        axes = fig.subplots(1, n, squeeze=False, width_ratios=[1.0] * len(panels) + [1.15] * (n - len(panels)))[0]
        for ax, (sub, symbol, unit, title) in zip(axes, panels, strict=False):
            _rep_curves(ax, sub, f"mean $L_2$ error {symbol} [{unit}]", title if len(panels) > 1 else "")
        if n > len(panels):
            _rep_map(fig, axes[-1], *panels[-1][:3])
        fig.suptitle(_rep_summary(rep_stats, h) + "; bars: s.e.m. over seeds")
        handles, labels = axes[0].get_legend_handles_labels()
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
        :func:`roughcontact.aggregate.seed_statistics` output (the workflow passes the
        aggregate, which holds both).
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
    alphas, bad = _asperity_alphas(agg), _unconverged(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = _family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(_STYLE):
        extent, crosses = np.zeros(3), []  # largest p0/E*, A/A0 + s.d., s.d.
        for idx, ks in enumerate(ks_list):
            families = [(kl, ks, h) for kl in kl_list for h in h_list if _present(stats, kl, ks, h)]
            panel_extent, panel_crosses = _area_load_panel(axes.flat[idx], agg, stats, bad, families, e_star,
                                                           colour, marker, style)
            extent = np.fmax(extent, panel_extent)
            crosses.append(panel_crosses)
            axes.flat[idx].set_title(_lambda_label(ks, "s"))
        xmax, ymax, sdmax = (float(v) for v in extent)
        drew_fit = False
        for idx, ks in enumerate(ks_list):
            # Second pass: theory over the common load range of all panels.
            consts = _fit_constants(fit, cel_kl, ks, estimator)
            _area_load_axes(axes.flat[idx], consts, xmax, ymax, e_star, hp, alphas)
            drew_fit = drew_fit or consts is not None
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = _family_handles(kl_list, h_list, colour, marker, style) + _area_load_theory_handles(sdmax)
        n_off = sum(_n_outside(ax, *c) for ax, c in zip(axes.flat, crosses, strict=False))  # hidden axes last
        handles += _asperity_handles(alphas) + _unconverged_handles(sum(x.size for x, _ in crosses), n_off)
        if drew_fit:
            handles.append(Line2D([], [], color="0.45", lw=2.2, alpha=0.8,
                                  label=f"CEL fit ({estimator}), " + _lambda_label(cel_kl, "l")))
        fig.suptitle(_run_summary(agg, stats))
        _legend_below(fig, handles, f"$h' = {hp:.3g}$")
    return fig


#: The +-1 s.d. bands of the area-load figure: face and edge opacity, edge width [pt].
_BAND_ALPHA, _BAND_EDGE_ALPHA, _BAND_EDGE_LW = 0.3, 0.8, 0.6
#: Persson's (2001) two curves: one colour, told apart by style (they coincide at small load).
PERSSON_COLOUR = OKABE_ITO[6]
_PERSSON_LIMIT_STYLE = {"color": PERSSON_COLOUR, "lw": 1.0, "ls": (0, (4, 2))}
_PERSSON_ERF_STYLE = {"color": PERSSON_COLOUR, "lw": 2.6, "ls": "-", "alpha": 0.45}


def _area_load_family(ax, s: Mapping[str, np.ndarray], e_star: float, colour, marker, style) -> np.ndarray:
    """Seed-mean ``A/A0(p0/E*)`` of one family with its ``+-1`` s.d. band (edged, so it shows
    when thin). ``s``: ``pressure_mean`` [unit of e_star], ``area_fraction_mean`` and ``_std``
    [1], shape ``(n_steps,)`` each. Returns ``[max p0/E*, max A/A0 + s.d., max s.d.]`` [1]
    (NaN where no step has a value)."""
    x = s["pressure_mean"] / e_star
    y, sd = s["area_fraction_mean"], s["area_fraction_std"]
    face, edge = mcolors.to_rgba(colour, _BAND_ALPHA), mcolors.to_rgba(colour, _BAND_EDGE_ALPHA)
    ax.fill_between(x, y - sd, y + sd, facecolor=face, edgecolor=edge, lw=_BAND_EDGE_LW, zorder=2)
    ax.plot(x, y, color=colour, marker=marker, ls=style, markevery=3, zorder=2.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a family none of whose steps converged
        return np.array([np.nanmax(x), np.nanmax(y + sd), np.nanmax(sd)])


def _area_load_panel(ax, agg, stats, bad, families, e_star: float, colour, marker, style):
    """The families ``(kl, ks, h)`` of one area-load panel over their converged steps
    (:func:`_converged_family`), and their unconverged steps as crosses.

    Returns ``(extent, (x, y))``: ``[max p0/E*, max A/A0 + s.d., max s.d.]`` [1] (NaN ignored)
    and ``p0/E*``, ``A/A0`` [1] of the unconverged steps, shape ``(n,)`` each.
    """
    extent, crosses = np.zeros(3), [(np.array([]), np.array([]))]
    for kl, ks, h in families:
        family = {"k_l": kl, "k_s": ks, "H": h}
        v = _converged_family(agg, stats, bad, family, ("pressure_mean", "area_fraction_mean", "area_fraction_std"))
        extent = np.fmax(extent, _area_load_family(ax, v, e_star, colour[h], marker[kl], style[kl]))
        p, a = _family_unconverged(agg, bad, family, "pressure", "area_fraction")
        crosses.append((p / e_star, a))
    x, y = (np.concatenate(v) for v in zip(*crosses, strict=True))
    _draw_unconverged(ax, x, y)
    return extent, (x, y)


def _area_load_axes(ax, consts, xmax: float, ymax: float, e_star: float, hp: float, alphas) -> None:
    """The fitted CEL (``consts``: ``(kappa, mu, beta)``, or None) and the theory of one area-load
    panel over ``p0/E*`` in ``[0, xmax]``; limits (``A/A0`` up to ``1.05 ymax``) and labels."""
    p = np.linspace(0, xmax * e_star, 200)
    if consts is not None:
        ax.plot(p / e_star, cel_area(p, kappa=consts[0], mu=consts[1], beta=consts[2], rms_slope=hp, e_star=e_star),
                color="0.45", lw=2.2, alpha=0.8, zorder=1)
    _area_load_theory(ax, p, e_star, hp, alphas)
    ax.set_xlim(0, xmax)
    ax.set_ylim(0, ymax * 1.05)
    ax.set_xlabel(r"$p_0/E^*$ [1]")
    ax.set_ylabel(r"$A/A_0$ [1]")


def _area_load_theory(ax, p: np.ndarray, e_star: float, hp: float, alphas) -> bool:
    """BGT and Persson small-load limits, Persson's erf curve and the asperity models at loads ``p``.

    An asperity model is drawn only up to the largest load it covers (its A/A0 = 1,
    :func:`~roughcontact.asperity.asperity_max_load`); returns whether one was cut there, for a note.
    """
    x = p / e_star
    ax.plot(x, linear_area(p, kappa=KAPPA_BGT, rms_slope=hp, e_star=e_star),
            color=OKABE_ITO[0], lw=0.9, ls="-", zorder=3)
    ax.plot(x, persson_area(p, rms_slope=hp, e_star=e_star), **_PERSSON_ERF_STYLE, zorder=3)
    ax.plot(x, linear_area(p, kappa=KAPPA_PERSSON, rms_slope=hp, e_star=e_star), **_PERSSON_LIMIT_STYLE,
            zorder=4)
    cut = False
    for alpha, shade, _ in alphas:
        for model, (ls, _name) in ASPERITY_STYLES.items():
            inside = p <= asperity_max_load(alpha=alpha, rms_slope=hp, e_star=e_star, model=model)
            cut |= not inside.all()
            ax.plot(x[inside], asperity_area(p[inside], alpha=alpha, rms_slope=hp, e_star=e_star, model=model),
                    color=shade, lw=1.1, ls=ls, zorder=3)
    return cut


def _area_load_theory_handles(sdmax: float) -> list:
    """Legend entries of the s.d. band (``sdmax``: its largest half-width [1]) and of the
    BGT and Persson curves."""
    grey = np.array([0.5, 0.5, 0.5])
    return [Patch(facecolor=(*grey, _BAND_ALPHA), edgecolor=(*grey, _BAND_EDGE_ALPHA), lw=_BAND_EDGE_LW,
                  label=f"$\\pm 1$ s.d. over seeds (largest: {sdmax:.2g})"),
            Line2D([], [], color=OKABE_ITO[0], lw=0.9, label=BGT_LIMIT_LABEL),
            Line2D([], [], **_PERSSON_LIMIT_STYLE,
                   label=r"Persson, small-load limit $A/A_0 = \sqrt{8/\pi}\,p_0/(h'E^*)$"),
            Line2D([], [], **_PERSSON_ERF_STYLE,
                   label=r"Persson, full: $A/A_0 = \mathrm{erf}(\sqrt{2}\,p_0/(h'E^*))$")]


def _kappa_theory(ax, amax: float, alphas, ylo: float, yhi: float) -> list:
    """BGT and Persson limits, the paper's CEL and the asperity models on ``[0, amax]``; sets the y
    limits from ``[ylo, yhi]`` (data) and the asperity curves; returns the legend entries."""
    ax.axhline(KAPPA_BGT, color=OKABE_ITO[0], lw=0.9)
    a = np.linspace(0, amax, 200)
    ax.plot(a, cel_kappa(a, **PAPER_CONSTANTS), color=OKABE_ITO[0], lw=1.4, ls=":", zorder=4)
    a = np.linspace(0, amax, 120)
    for alpha, shade, _ in alphas:
        for model, (ls, _name) in ASPERITY_STYLES.items():
            k = asperity_kappa(a, alpha=alpha, model=model)
            ax.plot(a, k, color=shade, lw=1.1, ls=ls, zorder=2)
            ylo = min(ylo, float(np.min(k)))
    pad = 0.05 * (yhi - ylo)
    shown = ylo - pad <= KAPPA_PERSSON <= yhi + pad
    if shown:
        ax.axhline(KAPPA_PERSSON, **_PERSSON_LIMIT_STYLE)
    ax.set_ylim(ylo - pad, yhi + pad)
    return [Line2D([], [], color=OKABE_ITO[0], lw=0.9, label=BGT_LIMIT_LABEL),
            Line2D([], [], **_PERSSON_LIMIT_STYLE, label=(
                r"Persson small-load limit, $\kappa=\sqrt{8/\pi}$" if shown
                else rf"Persson, $\kappa=\sqrt{{8/\pi}}$ = {KAPPA_PERSSON:.2f}: below the axis")),
            *_asperity_handles(alphas),
            Line2D([], [], color=OKABE_ITO[0], lw=1.4, ls=":", label=PAPER_CEL_LABEL)]


def _kappa_panel(ax, agg, stats, bad, families, colour, marker, style):
    """Seed-mean ``kappa(A/A0)`` with s.e.m. bars of each family ``(kl, ks, h)`` of one panel over
    its converged steps (:func:`_converged_family`), and its unconverged steps as crosses.

    Returns ``(amax, ylo, yhi, (x, y))``: the largest mean ``A/A0`` [1], the range of mean -+ s.e.m.
    [1], and ``A/A0``, ``kappa`` [1] of the unconverged steps, shape ``(n,)`` each.
    """
    amax, ylo, yhi, crosses = 0.0, np.inf, -np.inf, [(np.array([]), np.array([]))]
    for kl, ks, h in families:
        family = {"k_l": kl, "k_s": ks, "H": h}
        v = _converged_family(agg, stats, bad, family, ("area_fraction_mean", "kappa_mean", "kappa_sem"))
        x, y, e = v["area_fraction_mean"], v["kappa_mean"], v["kappa_sem"]
        ax.errorbar(x, y, yerr=e, color=colour[h], marker=marker[kl], ls=style[kl],
                    markevery=2, errorevery=2, elinewidth=0.6)
        if np.isfinite(x).any():  # else every step of the family failed
            amax = max(amax, float(np.nanmax(x)))
            ylo, yhi = min(ylo, float(np.nanmin(y - e))), max(yhi, float(np.nanmax(y + e)))
        crosses.append(_family_unconverged(agg, bad, family, "area_fraction", "kappa"))
    x, y = (np.concatenate(v) for v in zip(*crosses, strict=True))
    _draw_unconverged(ax, x, y)
    return amax, ylo, yhi, (x, y)


def _kappa_fit_handles(fit, ks_list, cel_kl, estimator) -> list:
    """Legend entries of the fitted CEL (its constants for one panel, or where it is not constrained) and its window."""
    loose = [ks for ks in ks_list if not _fit_constrained(fit, cel_kl, ks, estimator)]
    return [Line2D([], [], color="0.45", lw=2.2, alpha=0.8, label=_fit_label(
                "this run", estimator, cel_kl, _fit_constants(fit, cel_kl, ks_list[0], estimator)
                if len(ks_list) == 1 else None, not loose,
                where=", ".join(_lambda_label(ks, "s") for ks in loose) if len(ks_list) > 1 else "")),
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
    _require(stats, "stats", ("kappa_mean", "kappa_sem", "area_fraction_mean", "n_seeds"))
    _e_star(agg)
    alphas, bad = _asperity_alphas(agg), _unconverged(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = _family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    with matplotlib.rc_context(_STYLE):
        drew_fit, n_bad, n_off = False, 0, 0
        for idx, ks in enumerate(ks_list):
            ax = axes.flat[idx]
            families = [(kl, ks, h) for kl in kl_list for h in h_list if _present(stats, kl, ks, h)]
            amax, ylo, yhi, crosses = _kappa_panel(ax, agg, stats, bad, families, colour, marker, style)
            consts = _fit_constants(fit, cel_kl, ks, estimator)
            if consts is not None:
                a = np.linspace(0, amax, 200)
                ax.plot(a, cel_kappa(a, kappa=consts[0], mu=consts[1], beta=consts[2]),
                        color="0.45", lw=2.2, alpha=0.8, zorder=1)
                ax.axvspan(float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan)),
                           color="0.9", zorder=0, lw=0)
                ylo, yhi = min(ylo, consts[0]), max(yhi, consts[0])
                drew_fit = True
            theory = _kappa_theory(ax, amax, alphas, min(ylo, KAPPA_BGT), max(yhi, KAPPA_BGT))
            ax.set_xlim(0, amax * 1.02)
            ax.set_title(_lambda_label(ks, "s"))
            ax.set_xlabel(r"$A/A_0$ [1]")
            ax.set_ylabel(r"$\kappa = E^* h'/\bar p$ [1]")
            n_bad, n_off = n_bad + crosses[0].size, n_off + _n_outside(ax, *crosses)
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = _family_handles(kl_list, h_list, colour, marker, style) + theory
        handles += _unconverged_handles(n_bad, n_off)
        if drew_fit:
            handles += _kappa_fit_handles(fit, ks_list, cel_kl, estimator)
        fig.suptitle(_run_summary(agg, stats))
        _legend_below(fig, handles, "error bars: s.e.m.")
    return fig


def _constrained_constants(fit: xr.Dataset, where: Mapping, estimator: str,
                           constants: Sequence[str]) -> dict[str, bool]:
    """Per constant, whether the data constrain it: the fit's ``constrained`` flag (95 % interval
    narrower than the value, :func:`roughcontact.fit.constrained_flags`; True for files without
    the flag) and not sitting on a bound of the fit (:func:`roughcontact.fit.at_bound`; the flag
    of fits made before that check was part of it does not say so).

    ``where``: the fit's group, e.g. ``{"k_l": 16.0, "k_s": 32.0, "H_group": "pooled"}`` (empty
    for a fit of measured topographies).
    """
    sub = fit.sel({**where, "estimator": estimator})
    out = {}
    for c in constants:
        flag = bool(sub["constrained"].sel(constant=c)) if "constrained" in sub else True
        out[c] = flag and not at_bound(estimator, c, float(sub["value"].sel(constant=c)))
    return out


def _fit_constrained(fit: xr.Dataset, k_l: float, k_s: float, estimator: str,
                     constants: Sequence[str] = ("kappa", "mu", "beta")) -> bool:
    """Whether ``constants`` of the H-pooled fit are all constrained by the data (:func:`_constrained_constants`)."""
    where = {"k_l": k_l, "k_s": k_s, "H_group": "pooled"}
    return all(_constrained_constants(fit, where, estimator, constants).values())


def _fit_label(who: str, estimator: str, k_l: float, consts, constrained: bool = True, where: str = "") -> str:
    """Legend text of a fitted CEL curve, with its constants when one curve is drawn and the
    data constrain them (else "not constrained": an interval wider than the value is no number;
    ``where`` names the panels where they are not, when there are several)."""
    text = f"CEL, {who} ({estimator}), " + _lambda_label(k_l, "l")
    if not constrained:
        return text + ": not constrained by the data" + (f" at {where}" if where else "")
    if consts is not None:
        text += rf": $\kappa/\sqrt{{2\pi}}$ = {consts[0] / KAPPA_BGT:.3f}, $\mu$ = {consts[1]:.2f}, " \
                rf"$\beta$ = {consts[2]:.2f}"
    return text


#: Windows per decade of ``A/A0`` of the windowed ``d pbar / d p0`` (see aggregate.windowed_load_slope).
DPBAR_PER_DECADE = 6
#: Style of the paper's power law and of this run's fit in the d pbar / d p0 figure.
_PAPER_LAW_STYLE = {"color": OKABE_ITO[0], "lw": 1.0, "ls": (0, (4, 2)), "zorder": 5}
_FIT_LAW_STYLE = {"color": "0.55", "lw": 2.6, "alpha": 0.6, "ls": "-", "zorder": 1}


def _windowed_dpbar(agg: xr.Dataset, kl: float, ks: float, h: float, per_decade: int,
                    bad: xr.DataArray | None = None):
    """Seed mean and s.e.m. of the windowed ``d pbar / d p0`` of one family.

    Windows: :func:`roughcontact.aggregate.log_window_edges` of the seed-mean load curve;
    slopes per seed by :func:`roughcontact.aggregate.windowed_load_slope`, the unconverged
    steps (``bad``, :func:`_unconverged` of ``agg``) left out of both. Returns
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

    ``family``: ``{"k_l": .., "k_s": .., "H": ..}``; ``bad``: :func:`_unconverged` of ``agg``.
    Returns ``(x_raw, y_raw, bar_lo, bar_hi, x_bad, y_bad)`` [1] of what was drawn, 1-D each, for
    the axis limits and the count of unconverged steps.
    """
    s = _converged_family(agg, stats, bad, family, ("area_fraction_mean", "dpbar_dp0_mean"))
    xr_, yr_ = s["area_fraction_mean"], s["dpbar_dp0_mean"]
    raw = np.isfinite(xr_) & np.isfinite(yr_) & (xr_ > 0) & (yr_ > 0)
    ax.plot(xr_[raw], yr_[raw], ls="none", marker=marker, ms=1.6, color=colour, alpha=0.35, mew=0, zorder=2)
    x, y, sem = _windowed_dpbar(agg, family["k_l"], family["k_s"], family["H"], per_decade, bad)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    bars = _log_bars(y[ok], sem[ok])
    ax.errorbar(x[ok], y[ok], yerr=bars, color=colour, marker=marker, ls=style, ms=3.5,
                elinewidth=0.8, capsize=2.0, zorder=3)
    x_bad, y_bad = _family_unconverged(agg, bad, family, "area_fraction", "dpbar_dp0")
    _draw_unconverged(ax, x_bad, y_bad)
    return xr_[raw], yr_[raw], y[ok] - bars[0], y[ok] + bars[1], x_bad, y_bad


#: The constants of the power law ``beta (A0/A)^mu``: name, mathtext, index in ``(kappa, mu, beta)``.
_LAW_CONSTANTS = (("beta", r"$\beta$", 2), ("mu", r"$\mu$", 1))


def _fit_law_label(consts, ks: float, many: bool, estimator: str, cel_kl: float,
                   constrained: Mapping[str, bool] | None = None) -> str:
    """Legend text of this run's fitted power law: the value of each of beta and mu that the data
    constrain, and "not constrained by the data" for the others (an interval wider than the value
    is no number), e.g. ``mu = 0.537, beta not constrained by the data``.

    ``consts``: ``(kappa, mu, beta)``; ``constrained``: per name (default: all constrained).
    """
    where = _lambda_label(cel_kl, "l") + (", " + _lambda_label(ks, "s") if many else "")
    constrained = constrained or {}
    parts = [f"{tex} = {consts[i]:.3f}" for name, tex, i in _LAW_CONSTANTS if constrained.get(name, True)]
    loose = [tex for name, tex, _ in _LAW_CONSTANTS if not constrained.get(name, True)]
    if loose:
        parts.append(", ".join(loose) + " not constrained by the data")
    return rf"this run (fit: {estimator}), {where}: " + ", ".join(parts)


def fig_dpbar(agg: xr.Dataset, stats: xr.Dataset, fit: xr.Dataset | None = None, *,
              k_l: Sequence[float] | None = None, k_s: Sequence[float] | None = None,
              hurst: Sequence[float] | None = None, fit_k_l: float | None = None,
              estimator: str = "paper", per_decade: int = DPBAR_PER_DECADE) -> Figure:
    """``d pbar / d p0`` versus ``A/A0`` on log-log axes (the paper's Fig. 4).

    Large markers: per seed, the least-squares slope of ``pbar`` against ``p0`` over
    windows of equal width ``1/per_decade`` decade in ``A/A0`` (merged where the load
    steps are sparse; :func:`roughcontact.aggregate.windowed_load_slope`), averaged over
    seeds, with ``+-1`` s.e.m. bars drawn in log space (``y e^(+-sem/y)``, always above
    zero); non-positive values cannot be drawn on the log axis and are left out. Small
    faint markers: the seed mean of the pointwise finite differences
    (``dpbar_dp0_mean``); those outside the axis range are counted in the legend. Steps
    whose solve did not converge (``agg.converged`` False) are left out of both and drawn
    as grey crosses, counted in the legend. Lines: the paper's ``0.21 (A0/A)^0.55``
    (black dashed) and, with ``fit``, the fitted ``beta (A0/A)^mu`` of ``fit_k_l`` (thick
    grey); the legend gives the value of each of mu and beta that the data constrain and
    says "not constrained" of the others (:func:`_constrained_constants`).

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
    _require(stats, "stats", ("dpbar_dp0_mean", "area_fraction_mean", "n_seeds"))
    _require(agg, "agg", ("pressure", "mean_contact_pressure", "area_fraction"))
    _e_star(agg)
    bad = _unconverged(agg)
    kl_list, ks_list, h_list, colour, marker, style, cel_kl, fig, axes = _family_panels(
        stats, k_l, k_s, hurst, fit_k_l)
    fit_handles, n_off, n_bad, n_bad_off = [], 0, 0, 0
    with matplotlib.rc_context(_STYLE):
        for idx, ks in enumerate(ks_list):
            ax = axes.flat[idx]
            drawn = [_dpbar_family(ax, agg, stats, bad, {"k_l": kl, "k_s": ks, "H": h}, colour[h], marker[kl],
                                   style[kl], per_decade)
                     for kl in kl_list for h in h_list if _present(stats, kl, ks, h)]
            x_raw, y_raw, lo, hi, x_bad, y_bad = (np.concatenate(v) for v in zip(*drawn, strict=True))
            n_bad += x_bad.size
            if x_raw.size == 0 or lo.size == 0:
                n_bad_off += x_bad.size
                continue  # nothing drawable on log axes in this panel
            label = _dpbar_panel(ax, fit, cel_kl, ks, estimator, len(ks_list) > 1, x_raw, lo, hi)
            fit_handles += [Line2D([], [], **{k: v for k, v in _FIT_LAW_STYLE.items() if k != "zorder"},
                                   label=label)] if label else []
            n_off += int(np.sum((y_raw < ax.get_ylim()[0]) | (y_raw > ax.get_ylim()[1])))
            n_bad_off += _n_outside(ax, x_bad, y_bad)
        for ax in list(axes.flat)[len(ks_list):]:
            ax.set_visible(False)
        handles = _family_handles(kl_list, h_list, colour, marker, style)
        handles += _dpbar_handles(per_decade, n_off) + _unconverged_handles(n_bad, n_bad_off) + fit_handles
        fig.suptitle(_run_summary(agg, stats))
        _legend_below(fig, handles, r"bars: $\pm 1$ s.e.m. over seeds, in log space ($y\,e^{\pm s/y}$)")
    return fig


def _dpbar_panel(ax, fit, cel_kl: float, ks: float, estimator: str, many: bool, x_raw, lo, hi) -> str:
    """The paper's and the fitted power law of one panel, its limits and labels.

    ``x_raw``: the drawn ``A/A0`` [1]; ``lo``, ``hi``: ends of the drawn bars [1], 1-D each.
    Returns the fitted law's legend text (:func:`_fit_law_label`), "" without a fit.
    """
    a = np.geomspace(float(x_raw.min()), float(x_raw.max()), 100)
    lines = [cel_dpbar_dp0(a, mu=PAPER_CONSTANTS["mu"], beta=PAPER_CONSTANTS["beta"])]
    ax.plot(a, lines[0], **_PAPER_LAW_STYLE)
    consts, label = _fit_constants(fit, cel_kl, ks, estimator), ""
    if consts is not None:
        lines.append(cel_dpbar_dp0(a, mu=consts[1], beta=consts[2]))
        ax.plot(a, lines[-1], **_FIT_LAW_STYLE)
        constrained = _constrained_constants(fit, {"k_l": cel_kl, "k_s": ks, "H_group": "pooled"},
                                             estimator, ("mu", "beta"))
        label = _fit_law_label(consts, ks, many, estimator, cel_kl, constrained)
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
    """Log axes with plain decimal labels, title and labels of a d pbar / d p0 panel."""
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
