"""Percolation of the contact area on the periodic cell: does a contact cluster wrap around the torus?

On a periodic cell a cluster *wraps* when it connects a node to one of the node's periodic images:
walking through contact nodes only, one arrives at the same node shifted by a whole number of
cells. The shifts a cluster realises form a lattice of winding vectors ``(wx, wy)`` (in cells);
the cluster wraps in x when one of them has ``wx != 0``, in y when one has ``wy != 0``, and in both
directions when two of them are linearly independent (the cluster spans the torus: its complement
holds no band around the cell). This is the wrapping criterion of percolation on a torus (Newman &
Ziff 2001, Phys. Rev. E 64, 016706): unlike a largest-cluster share, it does not depend on a
threshold.

Two connectivities are offered: 4 (edge neighbours: the contact set's own, as in
:mod:`.clusters`) and 8 (corner neighbours too: the dual lattice's, where the gap percolates
exactly when the contact area does not).

Algorithm: :func:`scipy.ndimage.label` labels the open rectangle; every pair of contact nodes
that are neighbours across the cell's edges joins two labels with a shift of ``(±1, 0)``,
``(0, ±1)`` or a corner's ``(±1, ±1)`` cells; a union-find that carries each label's offset from its
root then finds every cycle of the label graph, and a cycle's total shift is a winding vector
(Hoshen–Kopelman with periodic offsets, as Machta et al. 1996). Pure functions, no I/O.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import xarray as xr
from scipy import ndimage

#: Connectivities :func:`wrapping` accepts: 4 (edge neighbours) or 8 (corner neighbours too).
CONNECTIVITIES = (4, 8)
#: Bits of :func:`wrapping_code` (CF ``flag_masks``): wraps in x, in y, in both directions.
WRAPS_X, WRAPS_Y, WRAPS_BOTH = 1, 2, 4
#: The ``flag_meanings`` of those bits, in their order.
WRAPPING_MEANINGS = ("wraps_x", "wraps_y", "wraps_both")


def _structure(connectivity: int) -> np.ndarray:
    if connectivity not in CONNECTIVITIES:
        raise ValueError(f"connectivity must be one of {CONNECTIVITIES}, got {connectivity!r}")
    return ndimage.generate_binary_structure(2, 1 if connectivity == 4 else 2)


def _crossing_edges(raw: np.ndarray, connectivity: int) -> list[tuple[int, int, int, int]]:
    """``(a, b, sx, sy)`` for every pair of contact nodes that are neighbours across the cell's edges.

    ``a`` is the raw label of a node, ``b`` that of its neighbour, ``(sx, sy)`` the shift in cells of
    the image the neighbour lies in. Only the forward offsets ``(1, 0), (0, 1)`` (and ``(1, 1)``,
    ``(1, -1)`` for 8-connectivity) are walked, so each neighbour pair appears once.
    """
    nx, ny = raw.shape
    offsets = [(1, 0), (0, 1)] + ([(1, 1), (1, -1)] if connectivity == 8 else [])
    edges = []
    i, j = np.nonzero(raw)
    for di, dj in offsets:
        ti, tj = i + di, j + dj
        sx, sy = np.floor_divide(ti, nx), np.floor_divide(tj, ny)
        cross = (sx != 0) | (sy != 0)
        a = raw[i[cross], j[cross]]
        b = raw[np.mod(ti[cross], nx), np.mod(tj[cross], ny)]
        keep = b > 0
        edges += zip(a[keep].tolist(), b[keep].tolist(), sx[cross][keep].tolist(), sy[cross][keep].tolist(),
                     strict=True)
    return edges


def winding_vectors(mask: np.ndarray, connectivity: int = 4) -> dict[int, list[tuple[int, int]]]:
    """The winding vectors of each cluster of a periodic contact set that wraps.

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (nx, ny)
        The contact set on the periodic cell, axis 0 = x.
    connectivity : {4, 8}
        Which neighbours connect (module docstring).

    Returns
    -------
    dict
        For each raw label (of :func:`scipy.ndimage.label`, the smallest of its periodic cluster)
        whose cluster wraps: the nonzero winding vectors ``(wx, wy)`` [cells] found, one per
        independent cycle of the label graph. An empty dict: no cluster wraps.

    Examples
    --------
    >>> band = np.zeros((4, 4), dtype=bool); band[1, :] = True   # a band along y
    >>> winding_vectors(band)
    {1: [(0, 1)]}
    """
    mask = np.asarray(mask)
    if mask.ndim != 2 or mask.dtype != bool or mask.size == 0:
        raise ValueError(f"mask must be a non-empty 2-D boolean array, got {mask.dtype} of shape {mask.shape}")
    raw, n = ndimage.label(mask, structure=_structure(connectivity))
    parent = np.arange(n + 1)
    offset = np.zeros((n + 1, 2), dtype=np.int64)  # a label's position relative to its parent, in cells

    def find(x: int) -> tuple[int, np.ndarray]:
        """The root of label ``x`` and ``x``'s position relative to it; the path is compressed."""
        path = []
        while parent[x] != x:
            path.append(x)
            x = parent[x]
        acc = np.zeros(2, dtype=np.int64)
        for node in reversed(path):  # from the root down: each offset becomes relative to the root
            acc = acc + offset[node]
            offset[node], parent[node] = acc, x
        return x, (offset[path[0]].copy() if path else np.zeros(2, dtype=np.int64))

    cycles: list[tuple[int, tuple[int, int]]] = []
    for a, b, sx, sy in _crossing_edges(raw, connectivity):
        ra, oa = find(a)
        rb, ob = find(b)
        shift = oa + np.array([sx, sy]) - ob  # where b's root sits relative to a's root, by this edge
        if ra == rb:
            if shift.any():
                cycles.append((ra, (int(shift[0]), int(shift[1]))))
        else:
            parent[rb], offset[rb] = ra, shift
    out: dict[int, list[tuple[int, int]]] = {}
    for root, vector in cycles:
        out.setdefault(find(root)[0], []).append(vector)
    return out


def wrapping(mask: np.ndarray, connectivity: int = 4) -> tuple[bool, bool, bool]:
    """``(wraps_x, wraps_y, wraps_both)`` of a periodic contact set (module docstring).

    ``wraps_both`` is True when one cluster has two linearly independent winding vectors; a
    cluster along a diagonal, ``(1, 1)``, wraps in x and in y but not in both.

    Examples
    --------
    >>> cross = np.zeros((5, 5), dtype=bool); cross[2, :] = cross[:, 2] = True
    >>> wrapping(cross)
    (True, True, True)
    """
    x = y = both = False
    for vectors in winding_vectors(mask, connectivity).values():
        v = np.array(vectors)
        x |= bool(v[:, 0].any())
        y |= bool(v[:, 1].any())
        both |= bool(np.linalg.matrix_rank(v) == 2)
    return x, y, both


def wrapping_code(mask: np.ndarray, connectivity: int = 4) -> int:
    """:func:`wrapping` as CF flag bits: :data:`WRAPS_X` | :data:`WRAPS_Y` | :data:`WRAPS_BOTH`."""
    x, y, both = wrapping(mask, connectivity)
    return WRAPS_X * x + WRAPS_Y * y + WRAPS_BOTH * both


def wrapping_variable(masks: Iterable[np.ndarray], connectivities: Sequence[int] = CONNECTIVITIES) -> xr.Variable:
    """The per-step ``cluster_wrapping`` variable: flag bits over ``(step, connectivity)``.

    ``masks``: the contact set of each load step, in order (periodic cell). CF ``flag_masks``
    :data:`WRAPS_X`, :data:`WRAPS_Y`, :data:`WRAPS_BOTH` with ``flag_meanings``
    :data:`WRAPPING_MEANINGS`.
    """
    codes = np.array([[wrapping_code(m, c) for c in connectivities] for m in masks], dtype=np.int8)
    return xr.Variable(("step", "connectivity"), codes.reshape(-1, len(connectivities)), {
        "units": "1", "long_name": "whether a contact cluster connects the periodic cell to its image (bits)",
        "flag_masks": np.array([WRAPS_X, WRAPS_Y, WRAPS_BOTH], dtype=np.int8),
        "flag_meanings": " ".join(WRAPPING_MEANINGS)})


def first_wrapping(codes: np.ndarray, area: np.ndarray, bit: int = WRAPS_BOTH) -> tuple[float, float]:
    """The A/A0 bracket ``(below, at)`` of the first load step whose contact set wraps (``bit``).

    ``codes`` and ``area`` over the load steps, in order (A/A0 increasing). ``below`` is the last
    step's A/A0 before the first wrapping one (NaN when the first step already wraps), ``at`` the
    first wrapping step's (NaN when none wraps): the threshold lies in ``(below, at]``, and the
    step spacing bounds how well it is known.
    """
    codes, area = np.asarray(codes), np.asarray(area, dtype=float)
    hit = np.flatnonzero(codes & bit)
    if not hit.size:
        return float(area[-1]), float("nan")
    k = int(hit[0])
    return (float(area[k - 1]) if k > 0 else float("nan")), float(area[k])
