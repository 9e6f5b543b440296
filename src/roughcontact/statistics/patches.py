"""Contact patches of one load step: how many nodes hold the contact, how many its largest patch holds, and
whether the grid resolves it.

A *patch* is a connected set of contact nodes: along a profile a run of consecutive contact nodes, on a map
a 4-connected cluster (edge neighbours; :mod:`.clusters` says why). Where the solver's half-space is periodic
(``boundary="periodic"``, the generated surfaces and the MPI and batched solves) a patch that leaves the cell
through one edge and re-enters through the opposite one is one patch; on a free patch (``boundary="free"``,
the measured surfaces: the contact file's global attribute ``boundary``) nothing connects opposite edges.
Every solver reports per load step ``contact_nodes`` (nodes in contact) and ``largest_patch_nodes`` (nodes of
its largest patch, :func:`contact_patches`); the contact file adds the flag ``contact_resolved``
(:func:`resolved_variable`).

**The resolution rule.** A load step's contact is *unresolved* when its largest patch holds fewer than
:data:`MIN_PATCH_NODES` = 4 nodes: the whole contact hangs on specks of 1 to 3 nodes. Why 4: a patch's size is known
to a node only (each of its edges lies somewhere between its last contact node and the first free one), and it grows
by whole nodes: by a third of itself or more per node below 4. The load curve then climbs in stairs, A/A0 flat while
the load rises until the next node touches: one patch of 3 nodes over six steps of SurfaceTopography's 132-point
line scan ``xy-1.txt``, patches of 3, 3 and 1 nodes over ten steps of its ``nonuniform.asc`` while the load doubles
(30 steps to p0/(E* h') = 0.05, tests/test_patches.py). One count for profiles and maps: a map's patch grows through
the free nodes all around it, so at a given count its area follows the load at least as smoothly as a profile's run,
and a speck of 1 to 3 nodes (at most 3 along, 2 across) is unresolved in either. Why the largest patch and not every
patch nor the node count: at small loads a rough surface's contact is many small spots, most of 1 to 3 nodes (the
paper's thousands at A/A0 ~ 0.005), and as long as one of them holds 4 nodes or more the contact moves with the load
(nodes touch somewhere at every step); a step with fewer than 4 contact nodes in all has no patch of 4, so the rule
flags it too. Where that leaves the paper's and the shipped scenes' steps (every one resolved): at the first step
(A/A0 ~ 0.005) the largest patch holds 79 to 134 nodes in three of the paper's cases at N = 1024 (k_s = 128 and 512,
lambda_s down to 2 nodes; H = 0.2 and 0.84), 10 or more in the demo's twelve (N = 256), 6 or more in the lines
scene's sixteen profiles (n = 4096). What the small spots' pixel boundaries add to A/A0 is the perimeter
correction's business (:mod:`roughcontact.theory.perimeter`), not this flag's.

Pure functions, no I/O; :func:`slab_patches` and :func:`merge_slabs` give the largest patch of a grid split in
slabs of rows (the MPI solver's) from each slab's edges, without gathering the grid.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr
from numba import njit
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

#: Nodes the largest contact patch of a resolved load step holds at least (module docstring).
MIN_PATCH_NODES = 4

#: Edge-neighbour (4-connectivity) structuring element of a 2-D grid.
EDGE_NEIGHBOURS = ndimage.generate_binary_structure(2, 1)

#: The solvers' per-step patch variables: name -> long_name (units "1", int64 over ``step``).
PATCH_LONG_NAMES = {
    "contact_nodes": "number of nodes in contact (p > 0)",
    "largest_patch_nodes": "number of nodes of the largest contact patch (a run of contact nodes along a profile, "
                           "a 4-connected cluster on a map; periodic where the half-space is)",
}

#: ``flag_meanings`` of ``contact_resolved``, in the order of its ``flag_values`` 0, 1.
RESOLVED_MEANINGS = ("unresolved", "resolved")


def merge_across_edges(raw: np.ndarray, n_raw: int, periodic_x: bool, periodic_y: bool) -> tuple[int, np.ndarray]:
    """``(n_comp, comp)``: the components of the raw labels ``0..n_raw`` of a 2-D grid (``comp``, shape
    ``(n_raw + 1,)``, each label's component) once the labels facing each other across the x edges (axis 0:
    first and last rows) are joined where ``periodic_x``, and across the y edges (axis 1) where ``periodic_y``.
    Vertex 0 (no contact) stays on its own."""
    a, b = [], []
    if periodic_x:
        a.append(raw[0, :])
        b.append(raw[-1, :])
    if periodic_y:
        a.append(raw[:, 0])
        b.append(raw[:, -1])
    a = np.concatenate(a) if a else np.zeros(0, dtype=raw.dtype)
    b = np.concatenate(b) if b else np.zeros(0, dtype=raw.dtype)
    both = (a > 0) & (b > 0)
    a, b = a[both], b[both]
    # The graph is tiny (<= nx + ny edges) but csgraph keeps the merge O(n_raw) without a Python loop.
    graph = coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n_raw + 1, n_raw + 1))
    return connected_components(graph, directed=False)


def _grid(mask) -> np.ndarray:
    """``mask`` as a 2-D bool grid: a profile ``(n,)`` as ``(n, 1)``; a ValueError for another shape or dtype."""
    m = np.asarray(mask)
    if m.dtype != np.bool_:
        raise ValueError(f"mask must have dtype bool, got {m.dtype}; pass e.g. `pressure > 0`")
    if m.ndim == 1:
        m = m[:, None]
    if m.ndim != 2 or m.size == 0:
        raise ValueError(f"mask must be a profile (n,) or a map (nx, ny) with n, nx, ny >= 1, got shape {m.shape}")
    return m


@njit(cache=True, nogil=True)
def _label_sizes(raw, comp, n_comp):
    """Node count of each component ``comp[label]`` of the labels ``raw`` (label 0: no contact, not counted).

    One pass and no grid-sized temporary. A field of patch ids (``comp[raw]``), or ``np.bincount`` of the labels
    (which first copies them to int64), costs more through its fresh pages than the counting itself: 41-258 ms
    and 86-232 ms a step at 2048² inside a solve on a 2-core VM, against 9-55 for the labelling (2026-12-02)."""
    sizes = np.zeros(n_comp, dtype=np.int64)
    for v in raw.ravel():
        if v:
            sizes[comp[v]] += 1
    return sizes


def _components(m: np.ndarray, periodic_x: bool, periodic_y: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(raw, comp, sizes)`` of a 2-D bool grid: its raw labels (0 off contact), each raw label's patch id
    (``comp[0]`` a patch of no node) and each patch's node count. A node's patch id is ``comp[raw]`` where
    ``m``; no field of ids is made (:func:`_label_sizes`)."""
    raw, n_raw = ndimage.label(m, structure=EDGE_NEIGHBOURS)
    n_comp, comp = merge_across_edges(raw, n_raw, periodic_x, periodic_y)
    return raw, comp, _label_sizes(raw, comp, n_comp)


def patch_sizes(mask, periodic: bool = True) -> np.ndarray:
    """Node counts of the contact patches of one step, largest first.

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (n,) (a profile) or (nx, ny) (a map)
        The contact set (``p > 0``); a profile may also come as ``(n, 1)``.
    periodic : bool
        ``True``: the cell wraps around (patches join across opposite edges); ``False``: a free patch.

    Returns
    -------
    numpy.ndarray of int64, shape (n_patches,)
        Sorted descending; they sum to the number of contact nodes. Empty without contact.

    Examples
    --------
    >>> patch_sizes(np.array([1, 1, 0, 1, 0, 1, 1, 1], bool)).tolist()  # the ends join around the period
    [5, 1]
    >>> patch_sizes(np.array([1, 1, 0, 1, 0, 1, 1, 1], bool), periodic=False).tolist()
    [3, 2, 1]
    """
    m = _grid(mask)
    if not m.any():
        return np.zeros(0, dtype=np.int64)
    sizes = _components(m, periodic, periodic)[2]
    return np.sort(sizes[sizes > 0])[::-1]


def contact_patches(mask, periodic: bool = True) -> tuple[int, int]:
    """``(contact_nodes, largest_patch_nodes)`` of one step's contact set (:func:`patch_sizes`; 0, 0 without
    contact)."""
    sizes = patch_sizes(mask, periodic)
    return int(sizes.sum()), int(sizes[0]) if sizes.size else 0


def resolved(largest_patch_nodes) -> np.ndarray:
    """Whether each step's contact is resolved: its largest patch holds at least :data:`MIN_PATCH_NODES` nodes
    (the module docstring's rule). ``largest_patch_nodes``: array_like of int, any shape.

    >>> resolved([0, 1, 3, 4, 40]).tolist()
    [False, False, False, True, True]
    """
    return np.asarray(largest_patch_nodes) >= MIN_PATCH_NODES


def patch_variables(contact_nodes, largest_patch_nodes) -> dict[str, tuple[np.ndarray, str, str]]:
    """The solvers' per-step patch columns as ``name -> (values int64 (n_steps,), units, long_name)``."""
    values = {"contact_nodes": contact_nodes, "largest_patch_nodes": largest_patch_nodes}
    return {name: (np.asarray(values[name], dtype=np.int64), "1", long_name)
            for name, long_name in PATCH_LONG_NAMES.items()}


def resolved_variable(largest_patch_nodes: xr.DataArray) -> xr.DataArray:
    """``contact_resolved``: bool over the dims of ``largest_patch_nodes`` (:func:`resolved`), a CF flag
    (``flag_values`` 0 1, ``flag_meanings`` :data:`RESOLVED_MEANINGS`) whose long name states the rule and
    whose attribute ``min_patch_nodes`` its threshold."""
    return xr.DataArray(resolved(largest_patch_nodes.values), dims=largest_patch_nodes.dims, attrs={
        "units": "1",
        "long_name": f"contact resolved by the grid: its largest contact patch holds at least {MIN_PATCH_NODES} "
                     f"nodes (unresolved: every patch a speck of 1 to {MIN_PATCH_NODES - 1} nodes)",
        "flag_values": np.array([0, 1], dtype=np.int8),
        "flag_meanings": " ".join(RESOLVED_MEANINGS),
        "min_patch_nodes": np.int64(MIN_PATCH_NODES)})


# ----------------------------------------------------------------------------------------- slabs of rows
@dataclass(frozen=True)
class SlabPatches:
    """What :func:`merge_slabs` needs of one slab of rows: its contact nodes, its largest patch touching neither
    edge row, and the patches on its edge rows (ids ``1..k`` local to the slab, 0 off contact).

    Attributes
    ----------
    nodes : int
        Contact nodes of the slab.
    interior : int
        Node count of its largest patch that touches neither its first nor its last row (0: none).
    first, last : numpy.ndarray of int64, shape (ny,)
        The edge patch id of each node of the first and last row.
    sizes : numpy.ndarray of int64, shape (k + 1,)
        Node count (within the slab) of each edge patch id; ``sizes[0] = 0``.
    """

    nodes: int
    interior: int
    first: np.ndarray
    last: np.ndarray
    sizes: np.ndarray


def slab_patches(mask: np.ndarray, periodic: bool = True) -> SlabPatches:
    """:class:`SlabPatches` of one slab of rows ``mask`` (bool ``(rows, ny)``) of a grid split along x (axis 0),
    patches joined across the y edges where ``periodic``."""
    m = _grid(mask)
    raw, comp, sizes = _components(m, False, periodic)
    ids = [np.where(m[r], comp[raw[r]], -1) for r in (0, -1)]  # the edge rows' patch ids (-1 off contact)
    edge = np.unique(np.concatenate(ids))
    edge = edge[edge >= 0]
    inner = np.ones(sizes.size, bool)
    inner[edge] = False
    local = np.zeros(sizes.size + 1, dtype=np.int64)  # patch id + 1 -> edge id (0: not an edge patch)
    local[edge + 1] = np.arange(1, edge.size + 1)
    return SlabPatches(nodes=int(m.sum()), interior=int(sizes[inner].max(initial=0)),
                       first=local[ids[0] + 1], last=local[ids[1] + 1],
                       sizes=np.concatenate([[0], sizes[edge]]).astype(np.int64))


def merge_slabs(parts: Sequence[SlabPatches], periodic: bool = True) -> tuple[int, int]:
    """``(contact_nodes, largest_patch_nodes)`` of a grid from its slabs' :class:`SlabPatches`, in the order of
    their rows: the edge patches of neighbouring slabs (the last slab's and the first's too, where ``periodic``)
    joined where their facing rows are both in contact. Equal to :func:`contact_patches` of the whole grid."""
    offsets = np.cumsum([0] + [p.sizes.size for p in parts])
    a, b = [], []
    pairs = list(zip(parts[:-1], parts[1:], offsets[:-2], offsets[1:-1], strict=True))
    if periodic:
        pairs.append((parts[-1], parts[0], offsets[-2], offsets[0]))
    for upper, lower, off_u, off_l in pairs:
        both = (upper.last > 0) & (lower.first > 0)
        a.append(upper.last[both] + off_u)
        b.append(lower.first[both] + off_l)
    a, b = np.concatenate(a or [np.zeros(0, np.int64)]), np.concatenate(b or [np.zeros(0, np.int64)])
    graph = coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(offsets[-1], offsets[-1]))
    comp = connected_components(graph, directed=False)[1]
    joined = np.bincount(comp, weights=np.concatenate([p.sizes for p in parts]))
    largest = max(int(joined.max(initial=0)), max(p.interior for p in parts))
    return sum(p.nodes for p in parts), largest


__all__ = [
    "EDGE_NEIGHBOURS",
    "MIN_PATCH_NODES",
    "PATCH_LONG_NAMES",
    "RESOLVED_MEANINGS",
    "SlabPatches",
    "contact_patches",
    "merge_across_edges",
    "merge_slabs",
    "patch_sizes",
    "patch_variables",
    "resolved",
    "resolved_variable",
    "slab_patches",
]
