"""Contact maps: the contact patches and the pressure inside them at the stored load steps, over the heights.

A scene that lists load steps under ``contact.outputs.fields`` stores, in each case's contact file, the
nodal ``contact_pressure`` and ``gap`` at those steps (dims ``field_step``, or ``step`` when every step
is stored, then ``x`` and, for a 2-D map, ``y``). :func:`fig_contact_maps` draws them beside the
surface's heights:

- **2-D maps** (heights ``(x, y)``): the heights as a grey-scale image, and over it the contact pressure
  ``p/E*`` as a colour map only where ``p > 0``, i.e. on the contact patches; everything out of contact
  stays grey. One colour bar of the heights per case, one of the pressure for the whole figure (one
  scale, so that steps and cases compare).
- **1-D profiles** (heights ``(x,)``, a line scan): the profile ``h(x)``, the deformed surface
  ``d - g(x)`` (:func:`deformed_surface`, which touches the rigid flat at ``z = d`` where the gap is 0)
  and the flat itself above, the pressure ``p/E*`` along ``x`` in a panel below.

Which is drawn follows the data: heights with a ``y`` dimension are maps, without one profiles.

**One figure per scene, a few chosen cases in it, not one figure per case.** Rows are cases (for a
generated scene the first seed of each ``(k_l, k_s, H)``, for a patch source each file, at most
:data:`MAP_CASES`), columns the stored steps (at most :data:`MAP_STEPS`, spread over them when more are
stored: :func:`shown_steps`). The figure rule is one generic rule per registered figure, writing
``figures/{figure}.png``: a figure per case would need a case wildcard in it (or a rule of its own) and
would put a thousand maps into the paper scene's report. The seeds of one ``(k_l, k_s, H)`` are
samples of one statistics, so the first shows what its patches look like; the fixed maxima keep the
figure, and the report, readable whatever the grid.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator

from .captions import PROFILES_GID
from .record import note, note_series
from .style import (
    DOUBLE_COLUMN_IN,
    MAP_PIXELS,
    OKABE_ITO,
    STYLE,
    block_mean,
    fmt,
    new_figure,
    require,
    unit_tex,
)

#: Most cases (rows) a contact-map figure draws.
MAP_CASES = 4
#: Most stored steps (columns) a contact-map figure draws.
MAP_STEPS = 4
#: Variables :func:`fig_contact_maps` reads from each case's contact dataset.
CONTACT_MAP_VARIABLES = ("contact_pressure", "gap", "pressure", "area_fraction")
#: Colour map of the heights (grey scale: the pressure's colours stand out over it) and of the pressure.
HEIGHT_CMAP, PRESSURE_CMAP = "gray", "plasma"
#: Dimensions of a stored field that are not the case's (those are length 1 and dropped).
_FIELD_DIMS = ("step", "field_step", "x", "y")


# ----------------------------------------------------------------------- data
def stored_steps(contact: xr.Dataset) -> list[int]:
    """The load-step numbers (1-based) whose fields ``contact`` stores, in their stored order.

    Parameters
    ----------
    contact : xarray.Dataset
        A case's contact dataset with ``contact_pressure`` along ``field_step`` (the steps listed by
        ``outputs.fields``) or ``step`` (every step stored).

    Returns
    -------
    list of int
    """
    require(contact, "contact", ("contact_pressure",))
    dim = "field_step" if "field_step" in contact["contact_pressure"].dims else "step"
    return [int(s) for s in contact[dim].values]


def shown_steps(steps: Sequence[int], most: int = MAP_STEPS) -> list[int]:
    """At most ``most`` of ``steps``: all of them, or ``most`` spread evenly from the first to the last."""
    steps = list(steps)
    if len(steps) <= most:
        return steps
    return [steps[int(i)] for i in np.round(np.linspace(0, len(steps) - 1, most))]


def case_values(da: xr.DataArray, step: int | None = None) -> np.ndarray:
    """The values of one case's variable without its length-1 case dimensions, at a stored ``step``.

    Parameters
    ----------
    da : xarray.DataArray
        ``heights`` (case dims, ``x`` [, ``y``]), a stored field (case dims, ``field_step`` or
        ``step``, ``x`` [, ``y``]) or a per-step variable (case dims, ``step``).
    step : int, optional
        The load step (1-based) of a field; None for the heights.

    Returns
    -------
    numpy.ndarray
        Float, shape ``(nx, ny)`` or ``(nx,)``, axis 0 along ``x`` (shape ``()`` for a per-step variable).
    """
    extra = [d for d in da.dims if d not in _FIELD_DIMS]
    if any(da.sizes[d] != 1 for d in extra):
        raise ValueError(f"{da.name}: holds more than one case (dims {dict(da.sizes)}); give one case's file")
    da = da.isel({d: 0 for d in extra})
    if step is not None:
        dim = "field_step" if "field_step" in da.dims else "step"
        if step not in da[dim].values:
            raise ValueError(f"{da.name}: step {step} is not stored (stored: {da[dim].values.tolist()})")
        da = da.sel({dim: step})
    return np.asarray(da.transpose(*[d for d in ("x", "y") if d in da.dims]).values, dtype=float)


def is_profile(surface: xr.Dataset) -> bool:
    """Whether a surface's heights are a 1-D profile (no ``y`` dimension) rather than a 2-D map."""
    require(surface, "surface", ("heights",))
    return "y" not in surface["heights"].dims


def in_contact(pressure: np.ndarray) -> np.ma.MaskedArray:
    """``pressure`` masked where it is not positive: what remains is the contact patches' pressure."""
    pressure = np.asarray(pressure, dtype=float)
    return np.ma.masked_where(~(pressure > 0), pressure)


def deformed_surface(heights: np.ndarray, gap: np.ndarray) -> tuple[np.ndarray, float]:
    """The deformed surface of a profile and the height of the rigid flat on it.

    The gap is ``g = d - z`` with ``z = h - u`` the deformed surface (``u`` the elastic displacement
    into the body) and ``d`` the rigid flat's height, so ``z = d - g`` touches the flat where ``g = 0``.
    The fields fix ``d`` only up to the displacement's mean, which the periodic half-space leaves free
    (its solver sets it to zero): ``d`` is the one for which ``<u> = 0``, i.e. ``d = <h> + <g>``, and the
    deformed surface keeps the profile's mean height.

    Parameters
    ----------
    heights, gap : numpy.ndarray
        Shape ``(nx,)``, both [length]; ``gap >= 0``.

    Returns
    -------
    (numpy.ndarray, float)
        ``z = d - g`` (shape ``(nx,)``) [length] and ``d`` [length].
    """
    heights, gap = np.asarray(heights, dtype=float), np.asarray(gap, dtype=float)
    if heights.shape != gap.shape:
        raise ValueError(f"heights {heights.shape} and gap {gap.shape} must have one shape")
    plane = float(heights.mean() + gap.mean())
    return plane - gap, plane


def step_title(contact: xr.Dataset, step: int) -> str:
    """``step k: A/A0 = .., p0/E* = ..`` of a stored ``step`` (mathtext), from the per-step variables."""
    e_star = float(contact.attrs.get("e_star", 1.0))
    area = float(case_values(contact["area_fraction"], step))
    load = float(case_values(contact["pressure"], step)) / e_star
    return rf"step {step}: $A/A_0$ = {area:.3g}, $p_0/E^*$ = {load:.3g}"


def case_label(contact: xr.Dataset) -> str:
    """A case's name for a row: a patch's ``topography`` name, or a generated case's cutoffs, H and seed."""
    if "topography" in contact.coords:
        return str(contact["topography"].values.ravel()[0])
    if all(d in contact.coords for d in ("k_l", "k_s", "H", "seed")):
        v = {d: contact[d].values.ravel()[0] for d in ("k_l", "k_s", "H", "seed")}
        return rf"$k_l$ = {fmt(v['k_l'])}, $k_s$ = {fmt(v['k_s'])}, $H$ = {fmt(v['H'])}, seed {int(v['seed'])}"
    return str(contact.attrs.get("source_file", "case"))


def _length_tex(contact: xr.Dataset) -> str:
    units = contact["x"].attrs.get("units") if "x" in contact.coords else None
    return unit_tex(str(units or contact.attrs.get("length_units", "1")))


# ----------------------------------------------------------------------- drawing
def draw_map(ax, heights: np.ndarray, pressure: np.ndarray, extent: tuple[float, float, float, float],
             norm: Normalize):
    """One 2-D panel: the heights in grey, the pressure in colour on the contact patches only.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    heights : numpy.ndarray
        Shape ``(nx, ny)`` [length], axis 0 along ``x``.
    pressure : numpy.ndarray
        ``p/E*``, shape ``(nx, ny)`` [1]; drawn where ``> 0`` (:func:`in_contact`).
    extent : tuple of float
        ``(0, Lx, 0, Ly)`` [length].
    norm : matplotlib.colors.Normalize
        The pressure's colour scale (one for the figure).

    Returns
    -------
    (matplotlib.image.AxesImage, matplotlib.image.AxesImage)
        The heights' image and the pressure's. Maps over :data:`MAP_PIXELS` a side are block-averaged:
        a block shows contact where any of its nodes does, coloured by the block's mean pressure.
    """
    if heights.shape != pressure.shape or heights.ndim != 2:
        raise ValueError(f"heights {heights.shape} and pressure {pressure.shape} must be maps of one shape")
    shown = block_mean(heights, MAP_PIXELS)
    f = max(1, -(-max(heights.shape) // MAP_PIXELS))  # block_mean's block side: the extent drops its cropped edge
    extent = (extent[0], extent[0] + (extent[1] - extent[0]) * shown.shape[0] * f / heights.shape[0],
              extent[2], extent[2] + (extent[3] - extent[2]) * shown.shape[1] * f / heights.shape[1])
    kw = {"origin": "lower", "extent": extent, "interpolation": "nearest"}
    h_img = ax.imshow(shown.T, cmap=HEIGHT_CMAP, **kw)
    p_img = ax.imshow(in_contact(block_mean(pressure, MAP_PIXELS)).T, cmap=PRESSURE_CMAP, norm=norm, **kw)
    return h_img, p_img


def draw_profile(ax_h, ax_p, x: np.ndarray, heights: np.ndarray, gap: np.ndarray, pressure: np.ndarray) -> None:
    """One 1-D panel pair: profile, deformed surface and rigid flat (``ax_h``), pressure along ``x`` (``ax_p``).

    Parameters
    ----------
    ax_h, ax_p : matplotlib.axes.Axes
        The profile's axes and the pressure's (below it).
    x : numpy.ndarray
        Node positions, shape ``(nx,)`` [length].
    heights, gap : numpy.ndarray
        Shape ``(nx,)`` [length].
    pressure : numpy.ndarray
        ``p/E*``, shape ``(nx,)`` [1]; zero out of contact.
    """
    z, plane = deformed_surface(heights, gap)
    ax_h.plot(x, heights, color="0.55", lw=0.8, label="profile $h(x)$")
    ax_h.plot(x, z, color=OKABE_ITO[5], lw=0.9, label="deformed surface $d - g(x)$")
    ax_h.axhline(plane, color="black", lw=0.6, ls="--", label="rigid flat $z = d$")
    touching = np.where(pressure > 0, z, np.nan)
    ax_h.plot(x, touching, color=OKABE_ITO[4], lw=2.0, solid_capstyle="butt", label="in contact ($p > 0$)")
    ax_p.fill_between(x, 0.0, np.where(pressure > 0, pressure, 0.0), step="mid", color=OKABE_ITO[4], lw=0)
    ax_p.set_ylim(bottom=0.0)


# ----------------------------------------------------------------------- the figure
def fig_contact_maps(cases: Sequence[tuple[xr.Dataset, xr.Dataset]]) -> Figure:
    """Contact patches and pressure at the stored steps of a few cases, over their heights.

    Rows: the cases, in order (at most :data:`MAP_CASES`); columns: their stored steps (at most
    :data:`MAP_STEPS`, :func:`shown_steps`), each panel titled with its step, ``A/A0`` and ``p0/E*``.
    2-D maps or 1-D profiles after the heights' dimensions (:func:`is_profile`); see the module.

    Parameters
    ----------
    cases : sequence of (xarray.Dataset, xarray.Dataset)
        ``(surface, contact)`` per case: the surface file's ``heights`` (case dims, ``x`` [, ``y``])
        [length] and the contact file's :data:`CONTACT_MAP_VARIABLES` (fields on the heights' grid,
        ``pressure`` and ``area_fraction`` along ``step``; attribute ``e_star``; coordinate ``x`` [, ``y``]
        with its ``units``). All cases 2-D or all 1-D, with the same stored steps.

    Returns
    -------
    matplotlib.figure.Figure
    """
    cases = list(cases)[:MAP_CASES]
    if not cases:
        raise ValueError("cases is empty: no case with stored fields to draw")
    for i, (surface, contact) in enumerate(cases):
        require(surface, f"surface {i}", ("heights",))
        require(contact, f"contact {i}", CONTACT_MAP_VARIABLES)
    profiles = {is_profile(s) for s, _ in cases}
    if len(profiles) != 1:
        raise ValueError("cases mix 1-D profiles and 2-D maps: draw them in separate figures")
    steps = shown_steps(stored_steps(cases[0][1]))
    for _, contact in cases[1:]:
        if stored_steps(contact) != stored_steps(cases[0][1]):
            raise ValueError(f"cases store different steps: {stored_steps(contact)} and {stored_steps(cases[0][1])}")
    with matplotlib.rc_context(STYLE):
        fig = (_fig_profiles if profiles.pop() else _fig_maps)(cases, steps)
    note_series(fig, [case_label(contact) for _, contact in cases])
    return fig


def _pressure_norm(cases, steps) -> Normalize:
    """One pressure scale ``p/E*`` from 0 to the largest drawn nodal pressure (1 where none is positive)."""
    top = max(float(case_values(c["contact_pressure"], k).max()) / float(c.attrs.get("e_star", 1.0))
              for _, c in cases for k in steps)
    return Normalize(0.0, top if top > 0 else 1.0)


def _fig_maps(cases, steps) -> Figure:
    """The 2-D figure of :func:`fig_contact_maps`: a row of maps per case (its height colour bar at the right),
    or with one stored step the cases side by side (each its colour bar below), so that the figure stays wide."""
    across = len(steps) == 1
    nrows, ncols = (1, len(cases)) if across else (len(cases), len(steps))
    panel = min(2.0, (DOUBLE_COLUMN_IN - 1.2) / ncols)
    fig = new_figure(nrows * (panel + 0.45) + 0.9)
    axes = fig.subplots(nrows, ncols, squeeze=False)
    norm = _pressure_norm(cases, steps)
    note(fig, "side_by_side" if across else "rows_of_steps", "maps")
    if any(max(case_values(s["heights"]).shape) > MAP_PIXELS for s, _ in cases):
        note(fig, "block_averaged_pressure")
    for i, (surface, contact) in enumerate(cases):
        row, utex = (axes[0, i:i + 1] if across else axes[i]), _length_tex(contact)
        x, y = (np.asarray(contact[d].values, dtype=float) for d in ("x", "y"))
        extent = (0.0, x[-1] + (x[1] - x[0]), 0.0, y[-1] + (y[1] - y[0]))
        e_star = float(contact.attrs.get("e_star", 1.0))
        for j, (ax, k) in enumerate(zip(row, steps, strict=True)):
            h_img, p_img = draw_map(ax, case_values(surface["heights"]),
                                    case_values(contact["contact_pressure"], k) / e_star, extent, norm)
            ax.set_title(_map_title(contact, k, across), fontsize=6.5 if across else 7)
            ax.set_xlabel(f"$x$ [{utex}]")
            if j == 0 and not (across and i):  # side by side, the cells' y axis is labelled once
                ax.set_ylabel(f"$y$ [{utex}]" if across else f"{case_label(contact)}\n$y$ [{utex}]")
        htex = unit_tex(str(surface["heights"].attrs.get("units", "1")))
        bar = fig.colorbar(h_img, ax=list(row), location="bottom" if across else "right", shrink=0.9, aspect=20)
        bar.set_label(f"height $h$ [{htex}]")
        # a narrow bar below a map: few short labels (0.0025, not 0.0025 and 0.0000), none overlapping
        bar.locator = MaxNLocator(3 if across else 5)
        bar.formatter = FuncFormatter(lambda v, _: f"{v:g}".replace("-", "\N{MINUS SIGN}"))
        bar.update_ticks()
    # the pressure's bar spans the figure on the side the heights' bars leave free
    fig.colorbar(p_img, ax=axes.ravel().tolist(), location="right" if across else "bottom", shrink=0.8,
                 aspect=25 if across else 40).set_label(
        r"contact pressure $p/E^*$ [1]" + ("\n" if across else " ") + r"(where $p > 0$: the contact patches)")
    fig.suptitle("Contact maps: heights (grey), pressure on the contact patches (colour)")
    return fig


def _positions(surface: xr.Dataset, contact: xr.Dataset, n: int) -> np.ndarray:
    """Node positions along ``x`` [length]: the contact file's ``x``, else the surface file's, else the node
    numbers (a 1-D file written without coordinates still draws)."""
    for ds in (contact, surface):
        if "x" in ds.coords and ds["x"].size == n:
            return np.asarray(ds["x"].values, dtype=float)
    return np.arange(n, dtype=float)


def _map_title(contact: xr.Dataset, step: int, with_case: bool) -> str:
    """A map's title: its step, ``A/A0`` and ``p0/E*`` on two lines, under its case's name ``with_case``."""
    title = step_title(contact, step).replace(": ", ":\n")
    if not with_case:
        return title
    case = case_label(contact).replace(", seed", "\nseed")  # a narrow panel: the seed on the step's line
    return f"{case}, {title.replace(':' + chr(10), chr(10))}"


def _fig_profiles(cases, steps) -> Figure:
    """The 1-D figure of :func:`fig_contact_maps`: per case a row of profiles over a row of pressures."""
    nrows, ncols = len(cases), len(steps)
    fig = new_figure(nrows * 2.3 + 0.7)
    axes = fig.subplots(2 * nrows, ncols, squeeze=False, sharex="col",
                        gridspec_kw={"height_ratios": [2.0, 1.0] * nrows})
    fig.set_gid(PROFILES_GID)
    note(fig, "profiles_layout", "profiles_contact")
    for i, (surface, contact) in enumerate(cases):
        heights, utex = case_values(surface["heights"]), _length_tex(contact)
        htex = unit_tex(str(surface["heights"].attrs.get("units", "1")))
        x = _positions(surface, contact, heights.size)
        e_star = float(contact.attrs.get("e_star", 1.0))
        for j, k in enumerate(steps):
            ax_h, ax_p = axes[2 * i, j], axes[2 * i + 1, j]
            draw_profile(ax_h, ax_p, x, heights, case_values(contact["gap"], k),
                         case_values(contact["contact_pressure"], k) / e_star)
            ax_h.set_title(step_title(contact, k), fontsize=7)
            ax_p.set_xlabel(f"$x$ [{utex}]")
            if j == 0:
                ax_h.set_ylabel(f"{case_label(contact)}\nheight [{htex}]")
                ax_p.set_ylabel(r"$p/E^*$ [1]")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center", ncols=4)
    fig.suptitle("Contact along the profiles: heights, deformed surface and pressure")
    return fig
