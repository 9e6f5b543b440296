"""Load steps whose contact the grid does not resolve, marked on the load-curve figures.

A step is *unresolved* when its largest contact patch holds fewer than 4 nodes (the contact file's
``contact_resolved``, :mod:`roughcontact.statistics.patches`): its A/A0 is the grid's, in stairs as the load rises.
The area-load and kappa figures (generated and measured) draw each such step of each case, where its case's
point is, as a hollow black circle above the data (:func:`mark_unresolved`, one call a panel); the legend counts
them (:func:`unresolved_handles`) and the caption says what they are, with their largest patch's node counts
(:func:`unresolved_note`, from the node counts the figure's record keeps: :func:`shown_nodes`), only when the
figure shows one. Aggregates without ``contact_resolved`` (files of older versions) get no mark.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..statistics.patches import MIN_PATCH_NODES

#: The gid of the marks (one line of markers a panel).
UNRESOLVED_GID = "unresolved_steps"
#: Hollow black circles around the step's point, above the data and its markers.
UNRESOLVED_STYLE = {"marker": "o", "mfc": "none", "mec": "black", "mew": 0.8, "ms": 7.0, "ls": "none", "zorder": 5}


def unresolved_steps(agg: xr.Dataset) -> xr.DataArray | None:
    """The unresolved steps of the present cases (bool, dims of ``agg.contact_resolved``); None where ``agg``
    has no ``contact_resolved``."""
    if "contact_resolved" not in agg:
        return None
    present = agg["case_present"].astype(bool) if "case_present" in agg else True
    return ~agg["contact_resolved"].astype(bool) & present


def mark_unresolved(ax, agg: xr.Dataset, x: xr.DataArray, y: xr.DataArray,
                    where: Mapping | None = None) -> Line2D | None:
    """Hollow circles at ``(x, y)`` of every unresolved step of ``agg``'s cases in ``where``.

    ``x``, ``y``: the panel's variables over ``agg``'s case dims and ``step`` (e.g. ``pressure / e_star``
    and ``area_fraction``); ``where``: a selection of the cases the panel draws (``{"k_s": 32.0, "k_l": [4.0,
    16.0], "H": [0.36]}``), all of them by default. The line (gid :data:`UNRESOLVED_GID`) keeps each mark's
    ``largest_patch_nodes`` in its attribute ``patch_nodes``, for :func:`unresolved_note`; None where nothing is
    unresolved.
    """
    bad = unresolved_steps(agg)
    if bad is None:
        return None
    where = dict(where or {})
    bad, x, y, nodes = (v.sel(where) for v in xr.broadcast(bad, x, y, agg["largest_patch_nodes"]))
    mask = bad.values.astype(bool)
    if not mask.any():
        return None
    (line,) = ax.plot(x.values[mask].astype(float), y.values[mask].astype(float), gid=UNRESOLVED_GID,
                      **UNRESOLVED_STYLE)
    line.patch_nodes = nodes.values[mask].astype(np.int64)
    return line


def shown_nodes(fig: Figure) -> np.ndarray:
    """The node counts of the marks ``fig`` shows inside its axes' limits, int64 (n,)."""
    nodes = [np.zeros(0, np.int64)]
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
        for line in ax.lines:
            if line.get_gid() != UNRESOLVED_GID or not line.get_visible():
                continue
            xy = np.asarray(line.get_xydata(), dtype=float).reshape(-1, 2)
            inside = np.isfinite(xy).all(axis=1) & (xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) \
                & (xy[:, 1] <= y1)
            nodes.append(line.patch_nodes[inside])
    return np.concatenate(nodes)


def _nodes_text(nodes: np.ndarray) -> str:
    lo, hi = int(nodes.min()), int(nodes.max())
    return f"{hi} node{'s' if hi != 1 else ''}" if lo == hi else f"{lo} to {hi} nodes"


def unresolved_handles(fig: Figure) -> list[Line2D]:
    """The legend entry of the unresolved steps ``fig`` shows (none when it shows none)."""
    nodes = shown_nodes(fig)
    if not nodes.size:
        return []
    n = nodes.size
    return [Line2D([], [], **{k: v for k, v in UNRESOLVED_STYLE.items() if k != "zorder"},
                   label=f"{n} unresolved load step{'s' if n != 1 else ''}: largest contact patch "
                         f"{_nodes_text(nodes)}, under {MIN_PATCH_NODES}")]


def unresolved_note(nodes) -> str:
    """The caption's sentence on the unresolved steps a figure shows, from their largest patch's node counts
    (``nodes``: :func:`shown_nodes`, as the figure's record keeps them; reStructuredText); empty for none."""
    nodes = np.asarray(nodes, dtype=np.int64).ravel()
    if not nodes.size:
        return ""
    steps = "one load step" if nodes.size == 1 else f"{nodes.size} load steps"
    return (f"\nHollow black circles: {steps} whose contact is unresolved: the grid does not resolve it, the "
            f"largest contact patch holding {_nodes_text(nodes)}, fewer than {MIN_PATCH_NODES}. Such a patch's size "
            "is known to a node "
            "only, a third of it or more, so A/A0 there is the grid's (held by few nodes, it climbs in stairs as the "
            "load rises). The contact files flag these steps (contact_resolved).\n")


def shown_cases(families) -> dict:
    """The :func:`mark_unresolved` selection of a generated scene's panel drawing ``families`` (``(k_l, k_s, H)``
    triples): every case of their ``k_l``, ``k_s`` and ``H`` values (those not drawn are absent cases)."""
    return {dim: sorted({f[i] for f in families}) for i, dim in enumerate(("k_l", "k_s", "H"))}
