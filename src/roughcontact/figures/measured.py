"""Figures of measured scenes: the topographies, ``A/A0`` against load and ``kappa`` against ``A/A0``.

A measured scene's cases are topography files named by strings (dim ``topography``) rather
than the generator's ``(k_l, k_s, H, seed)`` grid, and its CEL fit pools them all
(:func:`roughcontact.analysis.fit.fit_topographies`). These figures follow the conventions of
:mod:`roughcontact.figures` (Okabe-Ito colours, legend below the panels, theory in black and grey,
Persson in reddish purple) and reuse its helpers and theory lines; they are built without pyplot
and saved byte-reproducibly by :func:`roughcontact.figures.style.save_figure`.

One colour and marker per topography (the marker changes after the seven data colours, so no
two of the first 49 topographies look alike). The load axis of the area figure is
``p0/(E* h')`` with each topography's own rms slope ``h'``: the BGT and Persson asymptotes and
the CEL are then single curves for all topographies, whatever their slopes.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..analysis.aggregate import is_profiles
from ..analysis.aggregate.combine import TOPOGRAPHY_DIM as _DIM
from ..theory.laws import KAPPA_BGT, cel_area, cel_area_limit, cel_kappa
from . import load_curves
from .area_load import area_load_theory, area_load_theory_handles
from .captions import PROFILES_GID, ROUTE_LEGEND
from .kappa import kappa_theory
from .load_curves import (
    asperity_alphas,
    asperity_handles,
    constrained_constants,
    e_star_of,
    masked_points,
    n_outside,
    reference_style,
    unconverged_handles,
)
from .record import note, note_series
from .style import (
    DATA_COLOURS,
    DOUBLE_COLUMN_IN,
    MAP_PIXELS,
    MARKERS,
    SINGLE_COLUMN_IN,
    STYLE,
    block_mean,
    legend_below,
    new_figure,
    plain_log_labels,
    require,
    unit_tex,
)
from .unresolved import mark_unresolved, unresolved_handles

#: Style of the fitted CEL (as in :mod:`roughcontact.figures`: thick translucent grey).
_FIT_STYLE = reference_style("cel_fit")


# ----------------------------------------------------------------------- helpers
def _names(agg: xr.Dataset) -> list[str]:
    if _DIM not in agg.dims:
        raise ValueError(f"agg must have a {_DIM!r} dimension (a measured scene's aggregate), got {tuple(agg.dims)}")
    return [str(t) for t in agg[_DIM].values]


def _style(i: int) -> dict:
    """Colour and marker of the ``i``-th topography."""
    return {"color": DATA_COLOURS[i % len(DATA_COLOURS)],
            "marker": MARKERS[(i // len(DATA_COLOURS)) % len(MARKERS)]}


def _in_fit(agg: xr.Dataset, fit: xr.Dataset | None) -> np.ndarray:
    """Per topography, whether it entered the fit (``fit.in_fit``, else ``agg.case_present``)."""
    names = _names(agg)
    if fit is not None and "in_fit" in fit:
        used = {str(t): bool(v) for t, v in zip(fit[_DIM].values, fit["in_fit"].values, strict=True)}
        return np.array([used.get(n, False) for n in names])
    if "case_present" in agg:
        return agg["case_present"].transpose(_DIM).values.astype(bool)
    return np.ones(len(names), bool)


def _fitted(fit: xr.Dataset | None, estimator: str):
    """``((kappa, mu, beta), constrained)`` of the pooled fit, or ``(None, False)`` where absent/NaN."""
    if fit is None:
        return None, False
    require(fit, "fit", ("value",))
    if estimator not in [str(e) for e in fit["estimator"].values]:
        raise ValueError(f"estimator={estimator!r} is not in fit (has {list(fit['estimator'].values)})")
    v = fit["value"].sel(estimator=estimator)
    consts = tuple(float(v.sel(constant=c)) for c in ("kappa", "mu", "beta"))
    if not np.all(np.isfinite(consts)):
        return None, False
    return consts, all(constrained_constants(fit, {}, estimator, ("kappa", "mu", "beta")).values())


def _fit_label(fit: xr.Dataset, estimator: str, constrained: bool, n: int) -> str:
    """The legend entry of the pooled fit of ``n`` topographies: its route and its constants rounded to their
    intervals (:func:`~.load_curves.constant_text`), or why there are none."""
    text = (f"CEL fitted to the {'single topography' if n == 1 else f'{n} topographies'} "
            f"({ROUTE_LEGEND[estimator]})")
    if not constrained:
        return text + ": no bootstrap interval" if n < 2 else text + ": not constrained by the data"
    estimates = load_curves.fit_estimates(fit, {}, estimator)
    return text + ": " + ", ".join(load_curves.constant_text(c, estimates[c]) for c in load_curves.CEL_CONSTANTS)


def _note_fit(fig, fit: xr.Dataset, estimator: str, label: str) -> None:
    """Record the pooled fit's curves (gid ``cel_fit``) with their route, legend entry and window."""
    load_curves.note_fit_curves(fig, "cel_fit", estimator, label, lambda ax: "all topographies pooled", fit)


def _recorded(ds: xr.Dataset) -> dict:
    try:
        recorded = json.loads(ds.attrs.get("scene_parameters", "{}"))
    except ValueError:
        return {}
    return recorded if isinstance(recorded, dict) else {}


def grid_text(sizes: Mapping[str, tuple[int, int]]) -> str:
    """The grids of the files: ``N = 256``, ``N = 150-480`` when all are square, else the smallest and largest;
    line scans' ``n = 132-134 points`` (shapes ``(n,)``)."""
    if all(len(shape) == 1 for shape in sizes.values()):
        lo, hi = min(s[0] for s in sizes.values()), max(s[0] for s in sizes.values())
        return f"$n = {lo}$ points" if lo == hi else f"$n$ = {lo}-{hi} points"
    shapes = sorted(set(sizes.values()), key=lambda s: (s[0] * s[1], s))
    if all(nx == ny for nx, ny in shapes):
        lo, hi = shapes[0][0], shapes[-1][0]
        return f"$N = {lo}$" if lo == hi else f"$N$ = {lo}-{hi}"
    (ax, ay), (bx, by) = shapes[0], shapes[-1]
    return rf"grid ${ax} \times {ay}$" if len(shapes) == 1 else rf"grids ${ax} \times {ay}$ to ${bx} \times {by}$"


def _title(fig, agg: xr.Dataset, sizes) -> None:
    """The figure's title (:func:`_summary`) and its data series (the topographies); line scans' figures are
    tagged as profiles (:func:`~.load_curves.mark_profiles`: their captions say which references are 2-D laws)."""
    note_series(fig, _names(agg))
    if is_profiles(agg):
        load_curves.mark_profiles(fig, load_curves.NO_ASPERITY)
        fig.suptitle("profiles (1-D, plane strain), " + _summary(agg, sizes))
        return
    fig.suptitle(_summary(agg, sizes))


def _summary(agg: xr.Dataset, sizes: Mapping[str, tuple[int, int]] | None) -> str:
    """Title: number of topographies, grids, boundary of the half-space, load range ``p0/E*``."""
    n = len(_names(agg))
    parts = [f"{n} topograph{'y' if n == 1 else 'ies'}"]
    if sizes:
        parts.append(grid_text(sizes))
    solver = _recorded(agg).get("solver", {})
    boundary = agg.attrs.get("boundary", solver.get("boundary") if isinstance(solver, dict) else None)
    if boundary:
        parts.append(f"{boundary} boundary")
    p = agg["pressure"].values / e_star_of(agg)
    if np.isfinite(p).any():
        parts.append(f"$p_0/E^*$ = {np.nanmin(p):.3g}-{np.nanmax(p):.3g}")
    return ", ".join(parts)


def _unconverged(agg: xr.Dataset) -> xr.DataArray:
    """The unconverged steps, ``(topography, step)`` (:func:`roughcontact.figures.load_curves.unconverged_steps`), of
    every topography: each is drawn, whether or not it entered the fit."""
    bad = load_curves.unconverged_steps(agg, present=True)
    return xr.zeros_like(agg["area_fraction"], dtype=bool) if bad is None else bad.transpose(_DIM, "step")


def _load(agg: xr.Dataset) -> xr.DataArray:
    """``p0/(E* h')`` [1] of every step, each topography over its own rms slope ``h'``, dims of ``area_fraction``."""
    return agg["pressure"].broadcast_like(agg["area_fraction"]) / (e_star_of(agg) * agg["rms_slope"])


def _curve(agg: xr.Dataset, name: str, bad: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """``(p0/(E* h'), A/A0)`` of one topography at its converged steps (``bad``: :func:`_unconverged`)
    with positive values, [1] each, shape ``(n,)``."""
    sel = {_DIM: name}
    a = agg["area_fraction"].sel(sel).transpose("step").values.astype(float)
    x = _load(agg).sel(sel).transpose("step").values.astype(float)
    ok = ~bad.sel(sel).values & np.isfinite(x) & np.isfinite(a) & (x > 0) & (a > 0)
    return x[ok], a[ok]


def _draw_unconverged(ax, x: xr.DataArray, y: xr.DataArray, bad: xr.DataArray,
                      agg: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """The unconverged steps as crosses at ``(x, y)`` (dims ``(topography, step)``), and ``agg``'s unresolved
    steps circled (:func:`~.unresolved.mark_unresolved`); returns the crosses' ``(x, y)``, shape ``(n,)`` each,
    to count those outside the axes once the limits are set."""
    points = masked_points(x, y, bad)
    load_curves.draw_unconverged(ax, *points)
    mark_unresolved(ax, agg, x, y)
    return points


def _topography_handles(names: Sequence[str], used: np.ndarray, ls: str) -> list[Line2D]:
    return [Line2D([], [], ls=ls, mfc=None if u else "none", **_style(i),
                   label=name + ("" if u else " (not in the fit)"))
            for i, (name, u) in enumerate(zip(names, used, strict=True))]


def _window_patch(fit: xr.Dataset) -> Patch:
    return Patch(facecolor="0.9", edgecolor="none", label=(
        f"fit window $A/A_0 \\in$ [{float(fit.attrs.get('window_low', np.nan)):g}, "
        f"{float(fit.attrs.get('window_high', np.nan)):g}]"))


def _cell_label(ds: xr.Dataset, shape: tuple[int, int], utex: str) -> tuple[tuple[float, float], str]:
    """The sides (Lx, Ly) of a surface file's cell and its title text (``L``, ``N`` or both sides)."""
    if "length_x" in ds.attrs:
        lx, ly = float(ds.attrs["length_x"]), float(ds.attrs["length_y"])
        # four significant digits, never an exponent (30000, not 3e+04)
        sides = r" \times ".join(np.format_float_positional(v, precision=4, fractional=False, trim="-")
                                  for v in (lx, ly))
        return (lx, ly), rf"${sides}$ {utex}, ${shape[0]} \times {shape[1]}$"
    length = float(ds.attrs.get("length", shape[0]))
    return (length, length), f"$L$ = {length:.3g} {utex}, $N$ = {int(ds.attrs.get('n', shape[0]))}"


def _draw_map(fig, ax, ds: xr.Dataset, utex: str, text: list[str]) -> None:
    """One map panel of :func:`fig_topographies`: the heights to scale, its title (``text``: name, sigma, slope)
    and a colour bar below."""
    name, sigma, slope = text
    h = np.asarray(ds["heights"].transpose(..., "x", "y").values, dtype=float).squeeze()
    if h.ndim != 2:
        raise ValueError(f"heights must be a 2-D map, got shape {h.shape}")
    (lx, ly), cell = _cell_label(ds, h.shape, utex)
    note(fig, "height_maps", *(["block_averaged"] if max(h.shape) > MAP_PIXELS else []))
    im = ax.imshow(block_mean(h, MAP_PIXELS).T, origin="lower", extent=(0, lx, 0, ly), interpolation="nearest")
    # a rectangle's two sizes fill the line: its sigma goes to the next one
    lines = [cell, f"{sigma}, {slope}"] if "length_x" in ds.attrs else [f"{cell}, {sigma}", slope]
    ax.set_title("\n".join([name, *lines]), fontsize=7)
    ax.set_xlabel(f"$x$ [{utex}]")
    ax.set_ylabel(f"$y$ [{utex}]")
    # Below the map: a colour bar at the side would sit under the (wider) title.
    fig.colorbar(im, ax=ax, location="bottom", shrink=0.8, pad=0.02, aspect=30).set_label(f"height $h$ [{utex}]")


def _draw_profile(ax, ds: xr.Dataset, utex: str, text: list[str]) -> None:
    """One line-scan panel of :func:`fig_topographies`: h(x) [unit] on its uniform grid, its title as a map's."""
    name, sigma, slope = text
    note(ax.figure, "line_scans")
    h = np.asarray(ds["heights"].values, dtype=float).ravel()
    length = float(ds.attrs.get("length", h.size))
    ax.plot(np.arange(h.size) * (length / h.size), h, lw=0.6, color="0.2")
    ax.set_title("\n".join([name, f"profile: $L$ = {length:.4g} {utex}, $n$ = {h.size}, {sigma}", slope]),
                 fontsize=7)
    ax.set_xlabel(f"$x$ [{utex}]")
    ax.set_ylabel(f"height $h$ [{utex}]")


def _scalar(ds: xr.Dataset, name: str) -> float:
    return float(ds[name].values.squeeze()) if name in ds else float("nan")


# ---------------------------------------------------------------------- figures
def fig_topographies(surfaces: Sequence[xr.Dataset]) -> Figure:
    """Height map of each measured topography, with its size and statistics in the panel title.

    Parameters
    ----------
    surfaces : sequence of xarray.Dataset
        One per topography (``results/{scene}/surfaces/{name}.nc``): ``heights(x, y)``,
        ``(nx, ny)`` [unit] (a line scan's ``heights(x)``, drawn as a profile); ``rms_height``,
        ``rms_slope`` [1] and ``alpha`` [1] (Nayak bandwidth), each scalar or along a length-1
        ``topography`` dim whose label is the name; global attrs ``length`` (side ``L``) [unit] and
        ``n`` for a square cell, or ``length_x``, ``length_y``, ``nx``, ``ny``
        (:meth:`roughcontact.core.cell.Cell.surface_attrs`), and ``length_units``. Each map is drawn to scale.

    Returns
    -------
    matplotlib.figure.Figure
        Up to three panels per row, each with its own colour scale and colour bar (below) [unit];
        maps larger than :data:`MAP_PIXELS` are block-averaged for display.
    """
    if not surfaces:
        raise ValueError("surfaces must hold at least one dataset")
    for i, ds in enumerate(surfaces):
        require(ds, f"surfaces[{i}]", ("heights",))
    ncols = min(len(surfaces), 3)
    nrows = -(-len(surfaces) // ncols)
    width = SINGLE_COLUMN_IN if ncols == 1 else DOUBLE_COLUMN_IN
    # Per row: the square map (~0.75 of the column) plus its three-line title, x label and colour bar.
    row = 0.75 * width / ncols + 1.3
    with matplotlib.rc_context(STYLE):
        fig = new_figure(nrows * row + 0.3)
        axes = fig.subplots(nrows, ncols, squeeze=False)
        names = []
        for ax, ds in zip(axes.flat, surfaces, strict=False):
            utex = unit_tex(str(ds.attrs.get("length_units", "1")))
            name = str(ds[_DIM].values.ravel()[0]) if _DIM in ds.coords else str(ds.attrs.get("source_file", ""))
            names.append(name)
            sigma = rf"$\sigma$ = {_scalar(ds, 'rms_height'):.3g} {utex}"
            slope = rf"$h'$ = {_scalar(ds, 'rms_slope'):.3g}, $\alpha$ = {_scalar(ds, 'alpha'):.3g}"
            if "y" in ds["heights"].dims:
                _draw_map(fig, ax, ds, utex, [name, sigma, slope])
            else:  # a line scan (profile): its heights along x
                _draw_profile(ax, ds, utex, [name, sigma, slope])
        for ax in list(axes.flat)[len(surfaces):]:
            ax.set_visible(False)
        note_series(fig, names)
        if all("y" not in ds["heights"].dims for ds in surfaces):  # line scans only: profiles
            fig.set_gid(PROFILES_GID)
        n = len(surfaces)
        # One column is too narrow for the title on one line.
        fig.suptitle(f"{n} measured topograph{'y' if n == 1 else 'ies'}" + ("\n" if ncols == 1 else "; ")
                     + r"$\sigma$: rms height, $h'$: rms slope, $\alpha$: Nayak bandwidth")
    return fig


def _prepare(agg: xr.Dataset, fit: xr.Dataset | None, estimator: str, required):
    """Checked inputs of a contact figure: names, asperity alphas, fitted constants, which cases were fitted."""
    require(agg, "agg", required)
    consts, constrained = _fitted(fit, estimator)
    return _names(agg), asperity_alphas(agg), consts, constrained, _in_fit(agg, fit)


def fig_measured_area_load(agg: xr.Dataset, fit: xr.Dataset | None = None, *, estimator: str = "joint",
                           sizes: Mapping[str, tuple[int, int]] | None = None) -> Figure:
    """``A/A0`` against ``p0/(E* h')`` per topography, log-log (cf. the paper's Fig. 2).

    Markers and thin lines: each topography's converged steps, its load normalised by its own
    rms slope ``h'``; grey crosses: the unconverged steps, counted in the legend. Theory as in
    :func:`roughcontact.figures.area_load.fig_area_load`: the BGT asymptote
    ``A/A0 = sqrt(2 pi) p0/(E* h')`` (black), Persson's small-load asymptote (purple dashed)
    and full erf curve (thick translucent purple), the finite-load BGT and Greenwood asperity
    models at ``alpha = 2`` and at the topographies' mean ``alpha``; with ``fit``, the pooled
    CEL (thick grey) and its ``A/A0`` window (shaded band).

    Parameters
    ----------
    agg : xarray.Dataset
        Contact aggregate of a measured scene, dims ``(topography, step)``: ``area_fraction``
        [1], ``pressure`` [unit of the attr ``e_star``], ``rms_slope(topography)`` [1],
        optionally ``converged``, ``alpha(topography)``, ``case_present(topography)``.
    fit : xarray.Dataset, optional
        :func:`roughcontact.analysis.fit.fit_topographies` output.
    estimator : str
        Which estimator of ``fit`` to draw.
    sizes : mapping of str to (int, int), optional
        Grid ``(nx, ny)`` per topography, for the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    names, alphas, consts, constrained, used = _prepare(agg, fit, estimator, ("area_fraction", "pressure",
                                                                              "rms_slope"))
    with matplotlib.rc_context(STYLE):
        fig = new_figure(3.0)
        ax = fig.subplots()
        bad = _unconverged(agg)
        xs, ys = _draw_area_curves(ax, agg, names, used, bad)
        crosses = _draw_unconverged(ax, _load(agg), agg["area_fraction"], bad, agg)
        grid = np.geomspace(xs.min() / 1.2, xs.max() * 1.2, 200)
        # Loads normalised by E* h': the theory takes p0 = x with E* = h' = 1.
        cut = area_load_theory(ax, grid, 1.0, 1.0, alphas)
        handles = _topography_handles(names, used, "-") + area_load_theory_handles(0.0)[1:]
        handles += asperity_handles(alphas)
        if cut:
            handles.append(Line2D([], [], ls="none", label="BGT, Greenwood: drawn up to their full contact"))
        if consts is not None:
            handles += _draw_area_fit(ax, grid, fit, estimator, consts, constrained, used)
        _area_load_log_axes(ax, grid, ys)
        handles += unconverged_handles(crosses[0].size, n_outside(ax, *crosses), "lines") + unresolved_handles(fig)
        _title(fig, agg, sizes)
        legend_below(fig, handles, r"each topography's load over its own $E^* h'$")
    return fig


def _draw_area_curves(ax, agg: xr.Dataset, names: Sequence[str], used: np.ndarray,
                      bad: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """Each topography's converged ``A/A0(p0/(E* h'))`` (:func:`_curve`) as markers and a thin line,
    open markers for those not in the fit (``used`` False); returns all drawn ``(x, y)`` [1], 1-D each.

    Raises ``ValueError`` when no step has a positive load and contact area.
    """
    curves = [_curve(agg, name, bad) for name in names]
    for i, ((x, y), u) in enumerate(zip(curves, used, strict=True)):
        ax.plot(x, y, ls="-", lw=0.7, mfc=None if u else "none", zorder=4, **_style(i))
    xs = np.concatenate([x for x, _ in curves])
    ys = np.concatenate([y for _, y in curves])
    if xs.size == 0:
        raise ValueError("agg has no converged step with a positive load and contact area")
    return xs, ys


def _draw_area_fit(ax, grid: np.ndarray, fit: xr.Dataset, estimator: str, consts, constrained: bool,
                   used: np.ndarray) -> list:
    """The pooled CEL ``A/A0`` over the loads ``grid`` (``p0/(E* h')`` [1]; ``consts``:
    ``(kappa, mu, beta)``) and its ``A/A0`` window as a shaded band; returns their legend entries."""
    ax.plot(grid, cel_area(grid, kappa=consts[0], mu=consts[1], beta=consts[2], rms_slope=1.0, e_star=1.0),
            zorder=4.5, gid="cel_fit", **_FIT_STYLE)
    ax.axhspan(float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan)),
               color="0.9", lw=0, zorder=0, gid="fit_window")
    label = _fit_label(fit, estimator, constrained, int(fit.get("n_topographies", used.sum())))
    _note_fit(ax.figure, fit, estimator, label)
    return [Line2D([], [], **_FIT_STYLE, label=label), _window_patch(fit)]


def _area_load_log_axes(ax, grid: np.ndarray, ys: np.ndarray) -> None:
    """Log-log axes with plain labels over the loads ``grid`` and the drawn ``A/A0`` ``ys`` (capped at 1)."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        plain_log_labels(axis)
    ax.set_xlim(grid[0], grid[-1])
    ax.set_ylim(ys.min() / 1.5, min(1.0, ys.max() * 1.5))
    ax.set_xlabel(r"$p_0/(E^* h')$ [1]")
    ax.set_ylabel(r"$A/A_0$ [1]")


def fig_measured_kappa(agg: xr.Dataset, fit: xr.Dataset | None = None, *, estimator: str = "paper",
                       sizes: Mapping[str, tuple[int, int]] | None = None) -> Figure:
    """``kappa = E* h'/pbar`` against ``A/A0`` per topography (cf. the paper's Fig. 3).

    Markers and thin lines: each topography's converged steps; grey crosses: the unconverged
    steps, counted in the legend. The BGT limit ``sqrt(2 pi)``
    (black), Persson's ``sqrt(8/pi)`` (purple dashed, or named in the legend when below the
    axis), the paper's CEL (black dotted), the finite-load BGT and Greenwood asperity models
    as in :func:`roughcontact.figures.kappa.fig_kappa`; with ``fit``, the pooled CEL's
    ``kappa(A/A0) = kappa (1 - beta a^(1-mu))^(1/(1-mu))`` (thick grey) and its window (shaded).

    Parameters
    ----------
    agg : xarray.Dataset
        As in :func:`fig_measured_area_load`, with ``kappa(topography, step)`` [1].
    fit, estimator, sizes
        As in :func:`fig_measured_area_load`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    names, alphas, consts, constrained, used = _prepare(agg, fit, estimator, ("area_fraction", "pressure",
                                                                              "rms_slope", "kappa"))
    with matplotlib.rc_context(STYLE):
        fig = new_figure(3.0)
        ax = fig.subplots()
        amax, ylo, yhi, bad = 0.0, KAPPA_BGT, KAPPA_BGT, _unconverged(agg)
        for i, (name, u) in enumerate(zip(names, used, strict=True)):
            case = agg.sel({_DIM: name})
            a, k = (case[v].transpose("step").values.astype(float) for v in ("area_fraction", "kappa"))
            ok = np.isfinite(a) & np.isfinite(k) & (a > 0) & ~bad.sel({_DIM: name}).values
            ax.plot(a[ok], k[ok], ls="-", lw=0.7, mfc=None if u else "none", zorder=4, **_style(i))
            if ok.any():
                amax, ylo, yhi = max(amax, a[ok].max()), min(ylo, k[ok].min()), max(yhi, k[ok].max())
        if amax == 0.0:
            raise ValueError("agg has no converged step with a positive contact area")
        crosses = _draw_unconverged(ax, agg["area_fraction"], agg["kappa"], bad, agg)
        handles = _topography_handles(names, used, "-")
        if consts is not None:
            a = np.linspace(0.0, min(amax, 0.99 * cel_area_limit(consts[1], consts[2])), 200)
            ax.plot(a, cel_kappa(a, kappa=consts[0], mu=consts[1], beta=consts[2]),
                    zorder=4.5, gid="cel_fit", **_FIT_STYLE)
            ax.axvspan(float(fit.attrs.get("window_low", np.nan)), float(fit.attrs.get("window_high", np.nan)),
                       color="0.9", lw=0, zorder=0, gid="fit_window")
            ylo, yhi = min(ylo, consts[0]), max(yhi, consts[0])
            label = _fit_label(fit, estimator, constrained, int(fit.get("n_topographies", used.sum())))
            _note_fit(fig, fit, estimator, label)
            handles += [Line2D([], [], **_FIT_STYLE, label=label), _window_patch(fit)]
        handles += kappa_theory(ax, amax, alphas, ylo, yhi)
        ax.set_xlim(0, amax * 1.02)
        handles += unconverged_handles(crosses[0].size, n_outside(ax, *crosses), "lines") + unresolved_handles(fig)
        ax.set_xlabel(r"$A/A_0$ [1]")
        ax.set_ylabel(r"$\kappa = E^* h'/\bar p$ [1]")
        _title(fig, agg, sizes)
        legend_below(fig, handles, "")
    return fig

