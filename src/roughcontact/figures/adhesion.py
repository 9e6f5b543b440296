"""The figures of an adhesive scene: the load cycle with its hysteresis, and the pull-off per case.

An adhesive scene (``contact.effects.adhesion``) draws these instead of the contact figures of a
non-adhesive one: the contact evolution law and the theories of Fig. 2 (BGT, Persson, Greenwood)
describe contact without adhesion, so neither the CEL fit nor those curves are drawn for it.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib
import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .record import note_series
from .style import OKABE_ITO, STYLE, new_figure, require

#: Variables :func:`fig_hysteresis` reads from each case's contact dataset.
HYSTERESIS_VARIABLES = ("pressure", "area_fraction", "mean_gap", "converged", "unload_mean_gap",
                        "unload_mean_pressure", "unload_area_fraction", "unload_converged", "pull_off_pressure")
#: Variables :func:`fig_pull_off` reads from the contact aggregate.
PULL_OFF_VARIABLES = ("pull_off_pressure", "pull_off_status")


def _scalar(da: xr.DataArray) -> float:
    """The one value of a per-case scalar (stored with the case's length-1 dimensions)."""
    return float(np.asarray(da.values).ravel()[0])


def fig_hysteresis(cases: Sequence[tuple[str, xr.Dataset]]) -> Figure:
    """The load cycle of each case against the mean gap: loading solid, unloading dashed.

    Left: the contact area fraction A/A0; right: the mean pressure p0/E*, with each case's
    pull-off (the most tensile unloading pressure, when trusted) marked by a star. The gap
    between a case's two branches is the adhesion hysteresis: loading steps are solved under
    pressure control from the previous step's gap, unloading under displacement control from
    the last load step. Unconverged steps are left out of the lines and drawn as grey crosses.

    Parameters
    ----------
    cases : sequence of (str, xarray.Dataset)
        A label and a case's contact dataset each (:data:`HYSTERESIS_VARIABLES`, attribute
        ``e_star``; the length unit from ``mean_gap``'s ``units``).
    """
    if not cases:
        raise ValueError("cases is empty: no adhesive case to draw")
    for label, ds in cases:
        require(ds, f"case {label}", HYSTERESIS_VARIABLES)
    with matplotlib.rc_context(STYLE):
        fig = new_figure(2.8)
        ax_a, ax_p = fig.subplots(1, 2)
        for i, (label, ds) in enumerate(cases):
            colour = OKABE_ITO[1 + i % (len(OKABE_ITO) - 1)]
            e_star = float(ds.attrs["e_star"])
            _branch(ax_a, ax_p, ds["mean_gap"], ds["area_fraction"], ds["pressure"] / e_star,
                    ds["converged"], colour, "-", label)
            _branch(ax_a, ax_p, ds["unload_mean_gap"], ds["unload_area_fraction"], ds["unload_mean_pressure"] / e_star,
                    ds["unload_converged"], colour, "--", None)
            pull = _scalar(ds["pull_off_pressure"])
            if np.isfinite(pull):
                p = ds["unload_mean_pressure"].values.ravel()
                k = int(np.nanargmin(p))
                ax_p.plot(ds["unload_mean_gap"].values.ravel()[k], -pull / e_star, "*", color=colour, ms=7, mec="k",
                          mew=0.4)
        unit = cases[0][1]["mean_gap"].attrs.get("units", "1")
        for ax in (ax_a, ax_p):
            ax.set_xlabel("mean gap" + ("" if unit == "1" else f" [{unit}]"))
        ax_a.set_ylabel(r"$A/A_0$")
        ax_p.set_ylabel(r"$p_0/E^*$")
        ax_p.axhline(0.0, color="0.6", lw=0.5)
        ax_a.plot([], [], "k-", label="loading (pressure control)")
        ax_a.plot([], [], "k--", label="unloading (displacement control)")
        ax_p.plot([], [], "*", color="w", mec="k", mew=0.4, ms=7, ls="none", label="pull-off (trusted)")
        ax_a.legend(loc="upper right")
        ax_p.legend(loc="lower right")
        fig.suptitle("Adhesive load cycle: loading and unloading against the mean gap")
        note_series(fig, [label for label, _ in cases])
    return fig


def _branch(ax_a, ax_p, gap, area, load, converged, colour, style, label) -> None:
    """One branch on both panels: converged steps as a line, the others as grey crosses."""
    gap, area, load = (np.asarray(v.values, dtype=float).ravel() for v in (gap, area, load))
    ok = np.asarray(converged.values).astype(bool).ravel() & np.isfinite(load)
    ax_a.plot(gap[ok], area[ok], style, color=colour, label=label)
    ax_p.plot(gap[ok], load[ok], style, color=colour)
    if (~ok).any():
        ax_a.plot(gap[~ok], area[~ok], "x", color="0.5")


def fig_pull_off(agg: xr.Dataset, case_dims: Sequence[str]) -> Figure:
    """The pull-off pressure over E* of every case, with its spread over seeds or surfaces.

    One point per case whose pull-off can be trusted (``pull_off_status`` 0); per group (the
    cases that differ only in ``seed``: a generated scene's ``(k_l, k_s, H)``; a measured scene
    has one group per topography) its mean with +-1 standard deviation. The title counts the
    cases left out and says why, from the status flag.

    Parameters
    ----------
    agg : xarray.Dataset
        The contact aggregate (:data:`PULL_OFF_VARIABLES`, attribute ``e_star``).
    case_dims : sequence of str
        Its case dimensions: ``("k_l", "k_s", "H", "seed")`` or ``("topography",)``.
    """
    require(agg, "agg", PULL_OFF_VARIABLES)
    e_star = float(agg.attrs["e_star"])
    status = agg["pull_off_status"]
    meanings = status.attrs["flag_meanings"].split()
    present = agg["case_present"] if "case_present" in agg else xr.ones_like(status, dtype=bool)
    pull = (agg["pull_off_pressure"] / e_star).where(present)
    groups = [d for d in case_dims if d != "seed"]
    stacked = pull.stack(group=groups) if len(groups) > 1 else pull.rename({groups[0]: "group"})
    with matplotlib.rc_context(STYLE):
        fig = new_figure(2.8)
        ax = fig.subplots()
        labels = []
        for i in range(stacked.sizes["group"]):
            values = np.asarray(stacked.isel(group=i).values, dtype=float).ravel()
            values = values[np.isfinite(values)]
            labels.append(_group_label(stacked, i, groups))
            if values.size:
                ax.plot(np.full(values.size, i), values, "o", color=OKABE_ITO[1], ms=3, alpha=0.7)
                ax.errorbar(i + 0.15, values.mean(), yerr=values.std(ddof=1) if values.size > 1 else 0, fmt="s",
                            color="k", ms=4)
        ax.set_xticks(range(len(labels)), labels, rotation=30 if len(labels) > 4 else 0, ha="right"
                      if len(labels) > 4 else "center")
        ax.plot([], [], "o", color=OKABE_ITO[1], ms=3, label="one case (seed or file)")
        ax.errorbar([], [], yerr=[], fmt="s", color="k", ms=4, label="mean ± s.d.")
        ax.legend(loc="best")
        ax.set_ylabel(r"pull-off pressure $\bar p_{\rm off}/E^*$")
        ax.set_xlim(-0.5, len(labels) - 0.5)
        ax.set_title(_left_out(status.where(present), meanings))
        note_series(fig, labels)
    return fig


#: The case dimensions' symbols (mathtext) in a tick label.
_SYMBOLS = {"k_l": "$k_l$", "k_s": "$k_s$", "H": "$H$"}


def _group_label(stacked: xr.DataArray, i: int, groups: Sequence[str]) -> str:
    """A group's tick label: ``k_l, k_s, H`` values (``$k_l$ = 4, $k_s$ = 32, $H$ = 0.36``) or the topography's
    name."""
    if len(groups) == 1:
        return str(stacked["group"].values[i])
    values = stacked["group"].values[i]
    return ", ".join(f"{_SYMBOLS.get(d, d)} = {v:g}" for d, v in zip(groups, values, strict=True))


def _left_out(status: xr.DataArray, meanings: Sequence[str]) -> str:
    """The title: every case trusted, or how many are left out and why."""
    codes = np.asarray(status.values, dtype=float).ravel()
    codes = codes[np.isfinite(codes)].astype(int)
    bad = {meanings[c]: int((codes == c).sum()) for c in sorted(set(codes.tolist())) if c != 0}
    if not bad:
        return f"pull-off of all {codes.size} cases (trusted)"
    why = ", ".join(f"{n} {name.replace('_', ' ')}" for name, n in bad.items())
    return f"{codes.size - sum(bad.values())} of {codes.size} cases trusted; left out: {why}"
