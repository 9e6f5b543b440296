"""Contact-cluster statistics on the periodic cell.

A *cluster* (contact spot) is a connected component of the contact set
``p > 0`` on the ``(n, n)`` node grid of the periodic cell, or the ``(nx, ny)``
grid of a rectangular cell of sides ``(Lx, Ly)`` (pixels ``dx = Lx / nx`` by
``dy = Ly / ny``; a float ``length`` means a square cell, a pair ``(Lx, Ly)`` a
rectangular one, as for the solver). Two conventions fix what "connected" means
here, and both are deliberate:

* **Periodic.** The cell is a torus (the solver uses a periodic half-space), so
  a spot that leaves the cell through one edge and re-enters through the
  opposite one is a single spot. Labelling the raw array would split it in two
  (or four, at a corner) and bias the statistics towards many small spots.
  For a free patch (the solver's ``boundary="free"``), ``periodic=False``
  labels the open square instead.
* **4-connectivity** (edge neighbours only). Two contact nodes that touch only
  at a corner share no pixel edge, so no contact area joins them: on a pixel
  grid they are two spots whose contact zones are separated by gap along both
  axes. This is also the connectivity under which the solver's
  ``contact_perimeter`` (edges between contact and non-contact nodes) is the
  perimeter of the clusters counted here. 8-connectivity would merge checkerboard
  patterns, which are a discretisation artefact, into one large spot.

All functions are pure (no I/O). Areas are fractions of the nominal area
``A0 = L**2`` (``Lx * Ly``) unless the key/variable name says otherwise; one node
has area ``1 / n**2`` (``1 / (nx * ny)``) of it, the pixel area ``dx * dy``.
"""
from __future__ import annotations

import numbers
from collections.abc import Iterable

import numpy as np
import xarray as xr
from scipy import ndimage

from ..core.cell import Cell, check_length
from ..core.quantities import cf_unit
from .patches import EDGE_NEIGHBOURS, merge_across_edges
from .wrapping import CONNECTIVITIES, wrapping_variable

#: ``units`` attribute of dimensionless quantities (fractions of A0, counts).
DIMENSIONLESS_UNITS = "1"

#: Number of logarithmic bins of the default histogram.
DEFAULT_N_BINS = 24


# --------------------------------------------------------------------------- validation
def _check_mask(mask, square: bool = True) -> np.ndarray:
    if not isinstance(mask, np.ndarray):
        raise ValueError(f"mask must be a numpy.ndarray of bool, got {type(mask).__name__}")
    if mask.ndim != 2:
        raise ValueError(f"mask must be 2-D (n, n) or (nx, ny), got {mask.ndim}-D array of shape {mask.shape}")
    if square and mask.shape[0] != mask.shape[1]:
        raise ValueError(f"mask must be square (n, n) for a square cell (a float length), got shape {mask.shape}; "
                         "a rectangular cell needs length=(Lx, Ly)")
    if min(mask.shape) < 1:
        raise ValueError(f"mask must have n >= 1 (nx, ny >= 1), got shape {mask.shape}")
    if mask.dtype != np.bool_:
        raise ValueError(
            f"mask must have dtype bool, got dtype {mask.dtype}; "
            "pass e.g. `pressure > 0` for a contact pressure field")
    return mask


def _check_edges(bins) -> np.ndarray:
    edges = np.asarray(bins, dtype=float)
    if edges.ndim != 1 or edges.size < 2:
        raise ValueError(f"bins must be a 1-D array of at least 2 edges, got shape {edges.shape}")
    if not np.all(np.isfinite(edges)):
        raise ValueError(f"bins must be finite, got {edges!r}")
    if edges[0] <= 0:
        raise ValueError("bin edges must be > 0 (logarithmic bins in units of A0), "
                         f"got first edge {edges[0]!r}")
    if np.any(np.diff(edges) <= 0):
        raise ValueError(f"bin edges must be strictly increasing, got {edges!r}")
    return edges


def default_area_bins(n_total_pixels: int, n_bins: int = DEFAULT_N_BINS) -> np.ndarray:
    """Logarithmic bin edges from one node to the whole cell.

    Parameters
    ----------
    n_total_pixels : int
        Number of nodes of the cell, ``n**2`` or ``nx * ny`` (>= 1).
    n_bins : int
        Number of bins (>= 1).

    Returns
    -------
    numpy.ndarray, float64, shape (n_bins + 1,)
        Edges in units of A0, from ``1 / n_total_pixels`` to ``1``, equally spaced
        in ``log10``. For a single-node cell (``n_total_pixels == 1``) the range
        is empty, so the edges are ``2**-n_bins, ..., 1/2, 1`` instead (the only
        possible cluster lands in the last bin).
    """
    if isinstance(n_total_pixels, bool) or not isinstance(n_total_pixels, numbers.Integral) \
            or n_total_pixels < 1:
        raise ValueError(f"n_total_pixels must be an integer >= 1, got {n_total_pixels!r}")
    if isinstance(n_bins, bool) or not isinstance(n_bins, numbers.Integral) or n_bins < 1:
        raise ValueError(f"n_bins must be an integer >= 1, got {n_bins!r}")
    lo = 1.0 / int(n_total_pixels)
    if lo == 1.0:
        # A one-node cell has no range from 1/n**2 to 1 to span; keep strictly
        # increasing edges that still end at A0.
        edges = 2.0 ** np.arange(-int(n_bins), 1, dtype=float)
    else:
        edges = np.logspace(np.log10(lo), 0.0, int(n_bins) + 1)
    # logspace round-trips through log10; pin the ends so a one-node cluster and
    # a cell-filling cluster are never lost to a last-ulp miss.
    edges[0] = min(edges[0], lo)
    edges[-1] = 1.0
    return edges


# --------------------------------------------------------------------------- labelling
def label_clusters(mask: np.ndarray, periodic: bool = True, *, square: bool = True) -> tuple[np.ndarray, int]:
    """Label the contact clusters of a periodic cell (4-connectivity).

    ``scipy.ndimage.label`` labels the open square; labels facing each other
    across the x (axis 0) and y (axis 1) boundaries are then merged with a
    connected-components pass over the graph of those label pairs, so a
    cluster that wraps around the torus is one cluster. Why 4-connectivity:
    see the module docstring (corner contacts share no edge, hence no area).

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (n, n), or (nx, ny) with ``square=False``
        Contact set (``True`` where the node is in contact), axis 0 = x,
        axis 1 = y, on a periodic square cell; any ``n >= 1``, odd or even.
    periodic : bool
        ``False``: a free patch, no merge across its edges.
    square : bool
        ``True`` (default): the cell is square and ``mask`` must be ``(n, n)``.
        ``False``: a rectangular cell, any ``(nx, ny)``; labelled the same way (the
        x edges wrap onto each other, and the y edges; pixel sizes do not matter).

    Returns
    -------
    labels : numpy.ndarray of int32, shape of ``mask``
        0 for non-contact nodes, ``1..n_clusters`` for contact nodes. Numbering
        is deterministic: clusters are ordered by their first node in C
        (row-major) order, so cluster 1 holds the contact node with the
        smallest flat index.
    n_clusters : int
        Number of clusters (0 for an empty mask).

    Raises
    ------
    ValueError
        If ``mask`` is not a 2-D, square (with ``square=True``), non-empty numpy
        array of dtype bool.
    """
    mask = _check_mask(mask, square)
    raw, n_raw = ndimage.label(mask, structure=EDGE_NEIGHBOURS)
    if n_raw == 0:
        return np.zeros(mask.shape, dtype=np.int32), 0
    n_comp, comp = merge_across_edges(raw, n_raw, periodic, periodic)
    return _number_by_first_node(raw, n_raw, n_comp, comp)


def _number_by_first_node(raw: np.ndarray, n_raw: int, n_comp: int, comp: np.ndarray) -> tuple[np.ndarray, int]:
    """``(labels, count)``: int32 labels ``1..count`` (0 off contact, shape of ``raw``) of the components
    ``comp`` of ``raw``, ordered by their first node in C order, whatever ndimage's or csgraph's numbering."""
    flat = raw.ravel()
    nz = np.flatnonzero(flat)
    first_of_raw = np.full(n_raw + 1, flat.size, dtype=np.int64)
    np.minimum.at(first_of_raw, flat[nz], nz)
    first_of_comp = np.full(n_comp, flat.size, dtype=np.int64)
    np.minimum.at(first_of_comp, comp[1:], first_of_raw[1:])
    present = np.unique(comp[1:])
    ordered = present[np.argsort(first_of_comp[present], kind="stable")]
    new_id = np.zeros(n_comp, dtype=np.int32)
    new_id[ordered] = np.arange(1, ordered.size + 1, dtype=np.int32)
    out = np.zeros(raw.shape, dtype=np.int32)
    out.ravel()[nz] = new_id[comp[flat[nz]]]
    return out, int(ordered.size)


# --------------------------------------------------------------------------- statistics
def cluster_area_histogram(areas_in_pixels, n_total_pixels: int, bins=None) -> np.ndarray:
    """Histogram of cluster areas on fixed bins given in units of A0.

    Parameters
    ----------
    areas_in_pixels : array_like of int, shape (n_clusters,)
        Cluster areas as node counts (>= 1 each); any order.
    n_total_pixels : int
        Nodes in the cell, ``n**2`` (``nx * ny``); converts node counts to fractions of A0.
    bins : array_like of float, shape (n_bins + 1,), optional
        Strictly increasing, positive bin edges in units of A0. Bins are
        ``[e_i, e_{i+1})`` except the last, which also includes its right edge
        (``numpy.histogram`` convention). Default:
        ``default_area_bins(n_total_pixels)``, 24 log-spaced bins from one node
        (``1 / n**2``) to the whole cell (1), which catch every possible cluster.

    Returns
    -------
    numpy.ndarray of int64, shape (n_bins,)
        Number of clusters per bin. With the default bins the counts sum to
        ``n_clusters``; clusters outside custom ``[bins[0], bins[-1]]`` are not
        counted.

    Raises
    ------
    ValueError
        For non-integer or non-positive areas, areas above ``n_total_pixels``,
        or malformed ``bins``.
    """
    if isinstance(n_total_pixels, bool) or not isinstance(n_total_pixels, numbers.Integral) \
            or n_total_pixels < 1:
        raise ValueError(f"n_total_pixels must be an integer >= 1, got {n_total_pixels!r}")
    n_total = int(n_total_pixels)
    px = np.asarray(areas_in_pixels)
    if px.ndim != 1:
        raise ValueError(f"areas_in_pixels must be 1-D, got shape {px.shape}")
    if px.size and not np.issubdtype(px.dtype, np.integer):
        if not (np.issubdtype(px.dtype, np.floating) and np.all(np.isfinite(px))
                and np.all(px == np.round(px))):
            raise ValueError(f"areas_in_pixels must be whole node counts, got dtype {px.dtype}: {px!r}")
    px = px.astype(np.int64)
    if px.size and (px.min() < 1 or px.max() > n_total):
        raise ValueError(
            f"areas_in_pixels must lie in [1, n_total_pixels={n_total}], "
            f"got min {px.min()} and max {px.max()}")
    edges = default_area_bins(n_total) if bins is None else _check_edges(bins)
    counts, _ = np.histogram(px / n_total, bins=edges)
    return counts.astype(np.int64)


def cluster_statistics(mask: np.ndarray, length=1.0, periodic: bool = True) -> dict:
    """Count and areas of the contact clusters of one periodic contact mask.

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (n, n), or (nx, ny) for a pair ``length``
        Contact set, as for :func:`label_clusters`.
    length : float or (float, float)
        Side ``L`` of the square cell, or sides ``(Lx, Ly)`` of a rectangular one
        [length], > 0; only enters ``areas_physical``.
    periodic : bool
        As for :func:`label_clusters`.

    Returns
    -------
    dict
        ``count`` : int
            Number of clusters (periodic, 4-connected).
        ``areas`` : numpy.ndarray of float64, shape (count,)
            Cluster areas as fractions of A0 [-], sorted descending; they sum
            to the contact area fraction ``mask.mean()``.
        ``areas_pixels`` : numpy.ndarray of int64, shape (count,)
            The same areas as node counts, same order.
        ``areas_physical`` : numpy.ndarray of float64, shape (count,)
            The same areas in [length**2], ``areas * L**2`` (a rectangle:
            ``areas_pixels * dx * dy``).
        ``mean_area``, ``max_area`` : float
            Mean and largest cluster area as fractions of A0 [-]; 0.0 (not
            NaN) when there is no cluster.
        ``n_total_pixels`` : int
            ``n**2`` (``nx * ny``), to feed :func:`cluster_area_histogram`.

    Raises
    ------
    ValueError
        For a bad mask (see :func:`label_clusters`), a bad length or a float length for a mask that is
        not square (:meth:`roughcontact.core.cell.Cell.canonical`).
    """
    cell = Cell.canonical(_check_mask(mask, square=False).shape, length, "mask")
    labels, count = label_clusters(mask, periodic, square=cell.square)
    n_total = labels.size
    # bincount over labels gives every cluster's node count in one pass.
    px = np.bincount(labels.ravel(), minlength=count + 1)[1:].astype(np.int64)
    px = np.sort(px)[::-1]
    areas = px / n_total
    return {
        "count": int(count),
        "areas": areas,
        "areas_pixels": px,
        "areas_physical": cell.areas(areas, px),
        "mean_area": float(areas.mean()) if count else 0.0,
        "max_area": float(areas[0]) if count else 0.0,
        "n_total_pixels": int(n_total),
    }


def _to_mask(field, index: int) -> np.ndarray:
    arr = np.asarray(field)
    if arr.ndim != 2:
        raise ValueError(f"field {index} must be a 2-D array (n, n) (or (nx, ny) with length=(Lx, Ly)), "
                         f"got shape {arr.shape}")
    if arr.dtype == np.bool_:
        return arr
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise ValueError(
            f"field {index} must be a bool contact mask or a real pressure field, got dtype {arr.dtype}")
    if not np.all(np.isfinite(arr)):
        # A NaN pressure means a failed solve; reading it as "no contact" would hide that.
        raise ValueError(f"pressure field {index} contains non-finite values")
    return arr > 0


def cluster_dataset(masks_or_pressures: Iterable, steps, length, bins=None,
                    periodic: bool = True, *, length_unit: str = "1") -> xr.Dataset:
    """Per-step cluster statistics as an xarray.Dataset.

    Parameters
    ----------
    masks_or_pressures : iterable of array_like, each shape (n, n) or (nx, ny)
        One field per load step: a bool contact mask, or a real contact
        pressure field (contact where ``p > 0``). A 3-D array or DataArray
        ``(step, x, y)`` (e.g. ``solve_contact(...).contact_pressure``) works as
        it iterates over its first axis. All fields share one shape; ``(nx, ny)``
        with ``nx != ny`` needs a pair ``length``.
    steps : array_like, shape (n_steps,)
        Step coordinate values (e.g. the solver's 1-based step numbers).
    length : float or (float, float)
        Side ``L`` of the square cell, or sides ``(Lx, Ly)`` of a rectangular one
        [length], > 0; stored as attributes (every area here is a fraction of
        A0 = L**2 or Lx * Ly): ``length`` and ``n`` for a square cell,
        ``length_x`` and ``length_y`` for a rectangle, and ``nx``, ``ny`` always.
    bins : array_like of float, shape (n_bins + 1,), optional
        Histogram bin edges in units of A0 (see :func:`cluster_area_histogram`);
        default ``default_area_bins(nx * ny)``.
    periodic : bool
        As for :func:`label_clusters` (``False`` for a free patch).
    length_unit : str
        Unit of ``length`` (:data:`roughcontact.core.quantities.LENGTH_UNITS`, default ``"1"``),
        the global attribute ``length_units``; every variable is dimensionless.

    Returns
    -------
    xarray.Dataset
        Dimensions ``step`` (n_steps) and ``area_bin`` (n_bins), with

        * ``cluster_count(step)`` int64 — number of clusters;
        * ``cluster_mean_area(step)``, ``cluster_max_area(step)`` float64 —
          fractions of A0 (0.0 at a step without contact);
        * ``cluster_area_histogram(step, area_bin)`` int64 — clusters per bin;
        * periodic: ``cluster_wrapping(step, connectivity)`` int8, :mod:`.wrapping`'s bits;
        * coordinates ``step``, ``area_bin`` (bin centre, geometric mean of the edges),
          ``area_bin_low`` and ``area_bin_high`` (edges), in units of A0 except ``step``.

        Every variable and coordinate carries ``units`` and ``long_name``.

    Raises
    ------
    ValueError
        For fields that are not 2-D bool/real arrays (square for a float ``length``),
        fields of different sizes, non-finite pressures, a ``steps`` length that does not
        match the number of fields, no field at all, or bad ``length``/``bins``.
    """
    length_units = cf_unit(length_unit, length_power=1)
    masks, steps = _fields_and_steps(masks_or_pressures, steps)
    cell = Cell.canonical(masks[0].shape, length, "each field")
    n_total = masks[0].size
    edges = default_area_bins(n_total) if bins is None else _check_edges(bins)
    variables, coords = _cluster_variables(masks, cell.length, periodic, edges), _cluster_coords(steps, edges)
    if periodic:  # a free patch has no periodic image to connect to
        _add_wrapping(variables, coords, masks)
    return xr.Dataset(variables, coords=coords, attrs=_cluster_attrs(cell, length_units, periodic))


class ClusterObserver:
    """The per-step cluster statistics of a solve, as an observer of its steps.

    Keeps each step's contact mask (a copy: ``nx * ny`` bools a step) and, when the solve ends,
    labels them with :func:`cluster_dataset`. Pass it to :func:`roughcontact.solver.solve_contact`
    (``observers=[...]``); :func:`roughcontact.case.run_case` adds one when a case's
    outputs ask for ``clusters``.

    Parameters
    ----------
    length : float or (float, float)
        The solve's ``length`` [length]: ``L`` of a square cell or ``(Lx, Ly)``.
    periodic : bool
        ``True`` for the periodic cell, ``False`` for a free patch (``boundary="free"``).
    length_unit : str
        Unit of ``length`` (the solve's ``length_unit``).

    Examples
    --------
    >>> from roughcontact.solver import solve_contact
    >>> from roughcontact.surfaces.synthetic import generate_surface
    >>> h = generate_surface(64, 2, 16, 0.8, seed=0, rms_slope=0.1)
    >>> ds = solve_contact(h, [0.001, 0.004], observers=[ClusterObserver(1.0)])
    >>> ds.cluster_count.dims
    ('step',)
    """

    needs_gap = False
    #: Clusters are a map's (labelled with 2-D connectivity, wrapping along x and y): a profile's solve
    #: refuses this observer (:func:`roughcontact.solver.solve_contact`).
    profiles = False

    def __init__(self, length, periodic: bool = True, *, length_unit: str = "1"):
        self.length, self.periodic, self.length_unit = check_length(length), bool(periodic), length_unit
        self._masks: list[np.ndarray] = []

    def observe(self, step) -> None:
        """Keep ``step.mask`` (a :class:`roughcontact.solver.solve.StepView`)."""
        self._masks.append(np.array(step.mask, dtype=bool, copy=True))

    def dataset(self, steps) -> xr.Dataset:
        """:func:`cluster_dataset` of the masks seen, on the solve's ``steps``."""
        return cluster_dataset(self._masks, steps, self.length, periodic=self.periodic, length_unit=self.length_unit)


def _add_wrapping(variables: dict, coords: dict, masks: list[np.ndarray]) -> None:
    """``cluster_wrapping`` over ``(step, connectivity)`` and its ``connectivity`` coordinate (4 and 8)."""
    variables["cluster_wrapping"] = wrapping_variable(masks, CONNECTIVITIES)
    coords["connectivity"] = xr.Variable(("connectivity",), np.array(CONNECTIVITIES, dtype=np.int64), {
        "units": "1", "long_name": "neighbours that connect a cluster's nodes (4: edges, 8: edges and corners)"})


def _cluster_attrs(cell: Cell, length_units: str, periodic: bool) -> dict:
    """Global attributes of :func:`cluster_dataset`: the cell (sides, grid) and how clusters were labelled."""
    sides, grid = cell.solver_attrs()
    return {**sides, "length_units": length_units, **grid, "cluster_connectivity": 4,
            "cluster_boundary": "periodic" if periodic else "free"}


def _fields_and_steps(masks_or_pressures: Iterable, steps) -> tuple[list[np.ndarray], np.ndarray]:
    """Contact masks (one per field, one shared shape) and the matching 1-D ``steps``."""
    masks = [_to_mask(f, i) for i, f in enumerate(masks_or_pressures)]
    if not masks:
        raise ValueError("masks_or_pressures is empty: need at least one (n, n) field")
    shapes = {m.shape for m in masks}
    if len(shapes) != 1:
        raise ValueError(f"all fields must share one shape (n, n) or (nx, ny), got {sorted(shapes)}")
    steps = np.asarray(steps)
    if steps.ndim != 1 or steps.size != len(masks):
        raise ValueError(
            f"steps must be 1-D with one entry per field ({len(masks)}), got shape {steps.shape}")
    return masks, steps


def _cluster_variables(masks: list[np.ndarray], length, periodic: bool,
                       edges: np.ndarray) -> dict[str, xr.Variable]:
    """Count, mean and largest area, and area histogram of each mask's clusters."""
    n_total = masks[0].size
    count = np.zeros(len(masks), dtype=np.int64)
    mean_area = np.zeros(len(masks))
    max_area = np.zeros(len(masks))
    hist = np.zeros((len(masks), edges.size - 1), dtype=np.int64)
    for k, m in enumerate(masks):
        st = cluster_statistics(m, length, periodic)
        count[k] = st["count"]
        mean_area[k] = st["mean_area"]
        max_area[k] = st["max_area"]
        hist[k] = cluster_area_histogram(st["areas_pixels"], n_total, edges)
    u = DIMENSIONLESS_UNITS
    boundary = "periodic" if periodic else "free"
    return {
        "cluster_count": xr.Variable(("step",), count, {
            "units": u, "long_name": f"number of contact clusters ({boundary}, 4-connected)"}),
        "cluster_mean_area": xr.Variable(("step",), mean_area, {
            "units": u, "long_name": "mean contact cluster area / A0 (0 without contact)"}),
        "cluster_max_area": xr.Variable(("step",), max_area, {
            "units": u, "long_name": "largest contact cluster area / A0 (0 without contact)"}),
        "cluster_area_histogram": xr.Variable(("step", "area_bin"), hist, {
            "units": u, "long_name": "number of contact clusters per area bin"}),
    }


def _cluster_coords(steps: np.ndarray, edges: np.ndarray) -> dict[str, xr.Variable]:
    """``step`` and the area bins (geometric centre and edges, units of A0)."""
    u = DIMENSIONLESS_UNITS
    return {
        "step": xr.Variable(("step",), steps, {"units": u, "long_name": "load step number"}),
        "area_bin": xr.Variable(("area_bin",), np.sqrt(edges[:-1] * edges[1:]), {
            "units": u, "long_name": "cluster area bin centre (geometric mean of edges) / A0"}),
        "area_bin_low": xr.Variable(("area_bin",), edges[:-1].copy(), {
            "units": u, "long_name": "cluster area bin lower edge / A0 (inclusive)"}),
        "area_bin_high": xr.Variable(("area_bin",), edges[1:].copy(), {
            "units": u,
            "long_name": "cluster area bin upper edge / A0 (exclusive, inclusive for the last bin)"}),
    }

__all__ = [
    "DEFAULT_N_BINS",
    "DIMENSIONLESS_UNITS",
    "cluster_area_histogram",
    "cluster_dataset",
    "cluster_statistics",
    "default_area_bins",
    "label_clusters",
]
