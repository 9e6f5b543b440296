"""Combine per-case datasets into one grid, derive load-curve quantities, seed statistics.

Per-case datasets (one rough surface = one ``(k_l, k_s, H, seed)`` case) have the four
case dimensions ``k_l, k_s, H`` (float64 coordinates) and ``seed`` (int64), each of
length 1; contact datasets add the load-step dimension ``step`` (integer coordinate
1..n_steps). :func:`combine_cases` stacks them on the Cartesian grid of the case
coordinates; :func:`add_derived` adds ``kappa``, ``dpbar_dp0`` and ``n_unconverged``;
:func:`seed_statistics` and :func:`representativity_statistics` reduce over ``seed``;
:func:`windowed_load_slope` estimates ``d pbar / d p0`` by least squares over windows of
``log A/A0`` (:func:`log_window_edges`), a smoother alternative to the finite differences.

Every variable these functions create has ``units`` and ``long_name`` attributes.
Units propagate from the inputs, which must agree on them: :func:`combine_cases`
refuses a variable whose ``units`` (or ``reference_length_units``, the unit of a value written
as a number, :func:`roughcontact.quantities.per_reference_length`) differ between files; ``pressure`` and
``mean_contact_pressure`` share the unit of the global attribute ``e_star`` (its
``pressure_units`` where recorded, e.g. ``"MPa"``), so that ``kappa = E* h' / pbar``
and ``dpbar_dp0`` are dimensionless ("1"), as are area fractions and slopes; the
seed statistics ``<var>_mean/_std/_sem`` keep the ``units`` of ``<var>`` (and for
``epsilon`` its reference length).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence

import numpy as np
import xarray as xr

from .io import same_value
from .quantities import REFERENCE_ATTRS

#: The four case dimensions, in the order of every combined array.
CASE_DIMS = ("k_l", "k_s", "H", "seed")
#: The case dimension of measured surfaces: one name per topography file.
TOPOGRAPHY_DIM = "topography"
#: Variables a per-case contact dataset must hold.
CONTACT_REQUIRED = ("pressure", "area_fraction", "mean_contact_pressure", "converged", "rms_slope")
#: Variables a per-case representativity dataset must hold.
REPRESENTATIVITY_REQUIRED = ("epsilon",)
#: Quantities reduced over seeds by :func:`seed_statistics`.
SEED_STAT_VARIABLES = ("area_fraction", "kappa", "mean_contact_pressure", "dpbar_dp0")

_KINDS = {"contact": CONTACT_REQUIRED, "representativity": REPRESENTATIVITY_REQUIRED}


# ------------------------------------------------------------------------ combining
def _case_key(ds: xr.Dataset, name: str) -> tuple[float, float, float, int]:
    key = []
    for dim in CASE_DIMS:
        if dim not in ds.dims or dim not in ds.coords:
            raise ValueError(f"{name}: dataset has no dimension coordinate {dim!r}; "
                             f"per-case datasets need dims {CASE_DIMS}")
        if ds.sizes[dim] != 1:
            raise ValueError(f"{name}: dimension {dim!r} has length {ds.sizes[dim]}, expected 1 "
                             "(one case per dataset)")
        value = ds[dim].values[0]
        key.append(int(value) if dim == "seed" else float(value))
    return tuple(key)  # type: ignore[return-value]


def _fmt_case(key) -> str:
    return "(k_l={!r}, k_s={!r}, H={!r}, seed={!r})".format(*key)


def _normalise_expected(expected) -> set[tuple[float, float, float, int]]:
    out = set()
    for item in expected:
        if len(item) != 4:
            raise ValueError(f"expected must hold (k_l, k_s, H, seed) tuples, got {item!r}")
        kl, ks, h, s = item
        out.add((float(kl), float(ks), float(h), int(s)))
    return out


def _units_label(da: xr.DataArray) -> str | None:
    """``units``, with the reference length of a value written as a number: ``"1 (lengths in um)"``."""
    units, ref = da.attrs.get("units"), da.attrs.get("reference_length_units")
    return units if ref is None else f"{units} (lengths in {ref})"


def _check_like_first(ds: xr.Dataset, name: str, ref: xr.Dataset, ref_name: str, kind: str,
                      case_dims: Sequence[str]) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``ds`` can be stacked with the first case ``ref``.

    Same variables (the kind's required ones among them) with the same units, the same non-case
    dimensions and coordinates (exact join), and for contact data the same ``e_star``.
    """
    ref_vars = set(ref.data_vars)
    missing = [v for v in _KINDS[kind] if v not in ds.data_vars]
    if missing:
        raise ValueError(f"{name}: missing required variable(s) {missing} for kind={kind!r}")
    if set(ds.data_vars) != ref_vars:
        only_ref = sorted(ref_vars - set(ds.data_vars))
        only_here = sorted(set(ds.data_vars) - ref_vars)
        raise ValueError(f"{name}: variables differ from {ref_name}: missing {only_ref}, extra {only_here}")
    for var in sorted(ref_vars):
        got, want = _units_label(ds[var]), _units_label(ref[var])
        if got != want:
            raise ValueError(f"{name}: variable {var!r} has units {got!r}, but {ref_name} has "
                             f"{want!r} (cases of one study share its length and pressure units)")
    if kind == "contact" and "step" not in ds.dims:
        raise ValueError(f"{name}: contact datasets need a 'step' dimension")
    for dim in ds.dims:
        if dim in case_dims:
            continue
        if dim not in ref.dims or ds.sizes[dim] != ref.sizes[dim]:
            raise ValueError(f"{name}: dimension {dim!r} has size {ds.sizes.get(dim)}, "
                             f"but {ref_name} has {ref.sizes.get(dim)}")
        if (dim in ds.coords) != (dim in ref.coords) or (
                dim in ds.coords and not np.array_equal(ds[dim].values, ref[dim].values)):
            got = ds[dim].values if dim in ds.coords else None
            want = ref[dim].values if dim in ref.coords else None
            raise ValueError(f"{name}: {dim!r} coordinate {got!r} differs from {ref_name}'s "
                             f"{want!r} (exact join required)")
    if kind == "contact":
        if "e_star" not in ds.attrs:
            raise ValueError(f"{name}: global attribute 'e_star' is missing")
        if float(ds.attrs["e_star"]) != float(ref.attrs["e_star"]):
            raise ValueError(f"{name}: e_star={ds.attrs['e_star']!r} differs from "
                             f"{ref_name}'s e_star={ref.attrs['e_star']!r}")


def _case_keys(datasets: Sequence[xr.Dataset], names: Sequence[str], kind: str) -> list[tuple]:
    """The ``(k_l, k_s, H, seed)`` key of each dataset, in input order, after checking each one.

    Raises ``ValueError`` naming the file for a case given twice or a dataset that cannot be
    stacked with the first one (:func:`_check_like_first`); files are checked in input order,
    so the first bad file is the one named.
    """
    keys: list[tuple] = []
    seen: dict[tuple, str] = {}
    ref = datasets[0]
    for ds, name in zip(datasets, names, strict=True):
        key = _case_key(ds, name)
        if key in seen:
            raise ValueError(f"{name}: case {_fmt_case(key)} already given by {seen[key]}")
        seen[key] = name
        keys.append(key)
        _check_like_first(ds, name, ref, names[0], kind, CASE_DIMS)
    return keys


def _expected_cases(keys: Sequence[tuple], names: Sequence[str],
                    expected: Iterable[tuple] | None) -> set[tuple[float, float, float, int]]:
    """The expected case keys, checked against the given ones (``keys``, one per file in ``names``).

    Default: every point of the Cartesian product of the keys' coordinates with ``k_l < k_s``.
    Raises ``ValueError`` naming the cases for expected cases without a dataset (first, so that
    a missing file is reported as such), then naming the file for a case that is not expected.
    """
    present = set(keys)
    if expected is None:
        axes = [sorted({k[i] for k in keys}) for i in range(4)]
        expected_set = {c for c in itertools.product(*axes) if c[0] < c[1]}
    else:
        expected_set = _normalise_expected(expected)
    missing_cases = sorted(expected_set - present)
    if missing_cases:
        shown = ", ".join(_fmt_case(c) for c in missing_cases[:10])
        more = f" and {len(missing_cases) - 10} more" if len(missing_cases) > 10 else ""
        raise ValueError(f"{len(missing_cases)} expected case(s) have no dataset: {shown}{more}")
    for key, name in zip(keys, names, strict=True):
        if key not in expected_set:
            raise ValueError(f"{name}: case {_fmt_case(key)} is not among the expected cases")
    return expected_set


def _grid_coords(axes: Sequence[Sequence], ref: xr.Dataset) -> dict[str, xr.Variable]:
    """Coordinates of the combined grid: the four case axes (with ``ref``'s attrs), then ``ref``'s others.

    ``axes`` holds the sorted values of ``k_l, k_s, H`` (float64) and ``seed`` (int64). Of
    ``ref``'s other coordinates, those along no case dimension (e.g. ``step``) are kept as they are.
    """
    coords: dict[str, xr.Variable | np.ndarray] = {
        "k_l": np.asarray(axes[0], dtype=np.float64),
        "k_s": np.asarray(axes[1], dtype=np.float64),
        "H": np.asarray(axes[2], dtype=np.float64),
        "seed": np.asarray(axes[3], dtype=np.int64),
    }
    for dim in CASE_DIMS:
        coords[dim] = xr.Variable(dim, coords[dim], attrs=dict(ref[dim].attrs))
    for name_c, coord in ref.coords.items():
        if name_c not in CASE_DIMS and not (set(coord.dims) & set(CASE_DIMS)):
            coords[name_c] = coord.variable
    return coords


def _stack_variable(var: str, datasets: Sequence[xr.Dataset], names: Sequence[str],
                    positions: Sequence[tuple[int, int, int, int]], grid_shape: tuple[int, ...],
                    has_holes: bool) -> xr.Variable:
    """Variable ``var`` of every dataset placed at its case's grid position, dims ``CASE_DIMS + rest``.

    ``positions[i]`` is the grid index of ``datasets[i]`` on a grid of ``grid_shape`` (the
    four case axes); ``rest`` are the variable's non-case dims in the first dataset's order.
    Holes are NaN (float), ``False`` (bool); an integer variable becomes float64 only if
    ``has_holes``, so that a complete grid keeps its integers. Attrs are the first dataset's.
    """
    ref = datasets[0]
    template = ref[var]
    rest = tuple(d for d in template.dims if d not in CASE_DIMS)
    order = CASE_DIMS + rest
    rest_shape = tuple(ref.sizes[d] for d in rest)
    dtype = template.dtype
    if np.issubdtype(dtype, np.bool_):
        fill, out_dtype = False, np.bool_
    elif np.issubdtype(dtype, np.integer):
        fill, out_dtype = (np.nan, np.float64) if has_holes else (0, dtype)
    elif np.issubdtype(dtype, np.floating) or np.issubdtype(dtype, np.complexfloating):
        fill, out_dtype = np.nan, dtype
    else:
        raise ValueError(f"{names[0]}: variable {var!r} has dtype {dtype}, which cannot be "
                         "stacked (numeric or boolean only)")
    arr = np.full(grid_shape + rest_shape, fill, dtype=out_dtype)
    for ds, name, pos in zip(datasets, names, positions, strict=True):
        v = ds[var]
        # A variable need not span every case dim (constant along the others): add them, length 1.
        extra = [d for d in CASE_DIMS if d not in v.dims]
        if extra:
            v = v.expand_dims({d: ds[d].values for d in extra})
        if set(v.dims) != set(order):
            raise ValueError(f"{name}: variable {var!r} has dims {v.dims}, but {names[0]} has "
                             f"{template.dims}")
        arr[pos] = v.transpose(*order).values[0, 0, 0, 0]
    return xr.Variable(order, arr, attrs=dict(template.attrs))


def _shared_attrs(datasets: Sequence[xr.Dataset]) -> dict:
    """The first dataset's global attrs that every dataset has with an equal value, in its order."""
    ref = datasets[0]
    attrs = {}
    for key_a, val in ref.attrs.items():
        if all(key_a in ds.attrs and same_value(ds.attrs[key_a], val) for ds in datasets):
            attrs[key_a] = val
    return attrs


def combine_cases(datasets: Sequence[xr.Dataset], names: Sequence[str], *,
                  expected: Iterable[tuple] | None = None, kind: str = "contact") -> xr.Dataset:
    """Stack per-case datasets on the grid of their case coordinates, strictly.

    The result has dims ``(k_l, k_s, H, seed)`` plus any non-case dims of the inputs
    (``step`` for contact data), each variable transposed to that order. The grid is the
    sorted union of the inputs' and ``expected``'s coordinate values. Grid points that
    are not expected (e.g. ``k_l >= k_s``, which a scene's grid drops) are left as
    holes: NaN in float variables, ``False`` in boolean ones; integer variables become
    float64 with NaN only if there is such a hole. The boolean variable ``case_present``
    marks the cases that exist.

    Parameters
    ----------
    datasets : sequence of xarray.Dataset
        One per case, each with dims ``k_l, k_s, H, seed`` of length 1 (and ``step`` for
        contact data, integer coordinate identical in every dataset).
    names : sequence of str
        Same length: the file each dataset came from, used in error messages.
    expected : iterable of (k_l, k_s, H, seed), optional
        The cases the caller expects. Default: every point of the Cartesian product of
        the inputs' coordinates with ``k_l < k_s``.
    kind : {"contact", "representativity"}
        Which variables are required: :data:`CONTACT_REQUIRED` (and the global
        attribute ``e_star``, identical in all datasets) or
        :data:`REPRESENTATIVITY_REQUIRED`.

    Returns
    -------
    xarray.Dataset
        Dims ``(k_l, k_s, H, seed[, step])``; the inputs' variables with their attrs,
        ``case_present(k_l, k_s, H, seed)`` (bool), global attrs that all inputs share
        plus ``n_cases``.

    Raises
    ------
    ValueError
        Naming the file: a required variable is missing, a variable present in other
        files is missing, the step coordinate (or any other non-case coordinate) differs,
        a variable's ``units`` differ, ``e_star`` differs, a case appears twice or is not
        expected. Naming the case: an expected case has no dataset. Never fills a missing
        expected case with NaN.
    """
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {sorted(_KINDS)}, got {kind!r}")
    datasets = list(datasets)
    names = [str(n) for n in names]
    if len(datasets) != len(names):
        raise ValueError(f"datasets and names must have the same length, got {len(datasets)} "
                         f"and {len(names)}")
    if not datasets:
        raise ValueError("datasets is empty: nothing to combine")

    keys = _case_keys(datasets, names, kind)
    present = set(keys)
    expected_set = _expected_cases(keys, names, expected)

    # The grid spans the expected cases too, so that a hole stays visible as one.
    axes = [sorted({k[i] for k in present | expected_set}) for i in range(4)]
    index = [{v: j for j, v in enumerate(ax)} for ax in axes]
    grid_shape = tuple(len(ax) for ax in axes)
    positions = [tuple(index[i][key[i]] for i in range(4)) for key in keys]
    has_holes = len(present) < int(np.prod(grid_shape))

    present_mask = np.zeros(grid_shape, dtype=bool)
    for pos in positions:
        present_mask[pos] = True

    ref = datasets[0]
    coords = _grid_coords(axes, ref)
    data_vars = {var: _stack_variable(var, datasets, names, positions, grid_shape, has_holes)
                 for var in sorted(set(ref.data_vars))}
    data_vars["case_present"] = xr.Variable(CASE_DIMS, present_mask, attrs={
        "units": "1", "long_name": "a dataset exists for this case (False: grid hole, not expected)"})

    attrs = _shared_attrs(datasets)
    attrs["n_cases"] = len(datasets)
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def combine_topographies(datasets: Sequence[xr.Dataset], names: Sequence[str], *, expected: Sequence[str],
                         kind: str = "contact") -> xr.Dataset:
    """Stack per-case datasets of measured surfaces along ``topography``, strictly.

    Like :func:`combine_cases` for cases named by their topography file: each dataset has a
    length-1 dimension ``topography``; the result holds exactly the ``expected`` names, in that
    order, with every input variable and its attrs, and the global attrs all inputs share plus
    ``n_cases``. Raises ``ValueError`` naming the file for a duplicate or unexpected name, a
    missing or extra variable, different units, steps or ``e_star``, and naming the case for
    an expected name without a dataset.
    """
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {sorted(_KINDS)}, got {kind!r}")
    datasets, names, expected = list(datasets), [str(n) for n in names], [str(e) for e in expected]
    if not datasets or len(datasets) != len(names):
        raise ValueError(f"need one name per dataset and at least one, got {len(datasets)} and {len(names)}")
    by_case: dict[str, tuple[xr.Dataset, str]] = {}
    for ds, name in zip(datasets, names, strict=True):
        if TOPOGRAPHY_DIM not in ds.coords or ds.sizes.get(TOPOGRAPHY_DIM) != 1:
            raise ValueError(f"{name}: needs a length-1 dimension coordinate {TOPOGRAPHY_DIM!r} (one measured case)")
        case = str(ds[TOPOGRAPHY_DIM].values[0])
        if case in by_case:
            raise ValueError(f"{name}: topography {case!r} already given by {by_case[case][1]}")
        if case not in expected:
            raise ValueError(f"{name}: topography {case!r} is not among the expected {expected}")
        _check_like_first(ds, name, datasets[0], names[0], kind, (TOPOGRAPHY_DIM,))
        by_case[case] = (ds, name)
    missing = [e for e in expected if e not in by_case]
    if missing:
        raise ValueError(f"{len(missing)} expected topography case(s) have no dataset: {', '.join(missing)}")
    ordered = [by_case[e][0] for e in expected]
    out = xr.concat(ordered, dim=TOPOGRAPHY_DIM, data_vars="minimal", coords="minimal", compat="equals",
                    combine_attrs="drop_conflicts")
    out.attrs["n_cases"] = len(ordered)
    return out


# ------------------------------------------------------------------- derived values
def _first_bad_case(bad: xr.DataArray) -> str:
    idx = np.argwhere(bad.values)[0]
    parts = [f"{d}={bad[d].values[i]!r}" for d, i in zip(bad.dims, idx, strict=True)]
    return ", ".join(parts)


def fd_weights(x0: float, x: np.ndarray) -> np.ndarray:
    """Finite-difference weights of the first derivative at ``x0`` from nodes ``x``.

    Fornberg's (1988) recursion: ``f'(x0) ~ w @ f(x)`` exactly for polynomials of degree
    ``len(x) - 1``, for any distinct, not necessarily uniform, nodes.

    Parameters
    ----------
    x0 : float
        Where the derivative is wanted.
    x : numpy.ndarray, shape (m,)
        Distinct nodes, m >= 2.

    Returns
    -------
    numpy.ndarray, shape (m,)
        Weights [1 / unit of x].
    """
    x = np.asarray(x, dtype=float)
    m = x.size
    c = np.zeros((m, 2))
    c[0, 0] = 1.0
    c1, c4 = 1.0, x[0] - x0
    for i in range(1, m):
        mn = min(i, 1)
        c2, c5, c4 = 1.0, c4, x[i] - x0
        for j in range(i):
            c3 = x[i] - x[j]
            c2 *= c3
            if j == i - 1:
                for k in range(mn, 0, -1):
                    c[i, k] = c1 * (k * c[i - 1, k - 1] - c5 * c[i - 1, k]) / c2
                c[i, 0] = -c1 * c5 * c[i - 1, 0] / c2
            for k in range(mn, 0, -1):
                c[j, k] = (c4 * c[j, k] - k * c[j, k - 1]) / c3
            c[j, 0] = c4 * c[j, 0] / c3
        c1 = c2
    return c[:, 1]


#: Variables in which :func:`load_derivative` may difference.
DERIVATIVE_VARIABLES = ("log_p0", "p0")


def load_derivative(values: np.ndarray, p0: np.ndarray, *, order: int = 2,
                    variable: str = "log_p0") -> np.ndarray:
    """``d values / d p0`` along the last axis by finite differences of order 2 or 4.

    Stencil: centred ``order + 1``-point Fornberg weights on the actual (non-uniform)
    nodes, shifted to one-sided ``order + 1`` points at the two ends, so the error is
    ``O(h^order)`` everywhere; for ``order=2`` this is exactly
    ``numpy.gradient(..., edge_order=2)``.

    ``variable="log_p0"`` (default) differences in ``ln p0`` and applies the chain rule
    ``d/d p0 = (1/p0) d/d ln p0``. Why: at small loads ``pbar`` carries a singular
    ``p0^(1-mu)`` term (the CEL's ``pbar = (h'E*/kappa)(1 + beta x^(1-mu))^(1/(1-mu))``,
    ``x ~ p0``), which is smooth in ``ln p0`` but not in ``p0``. On 30 uniform load
    steps reaching ``A/A0 = 0.15``, the second-order error at the second step falls from
    4 % (in ``p0``) to 1 % (in ``ln p0``), and the bias this puts into a log-log fit of
    ``mu`` over ``A/A0 in [0.01, 0.11]`` from +0.011 to +0.003; ``order=4`` removes it
    (< 1e-4) at the cost of about 1.3x (interior) to 3x (end points) more noise
    amplification. ``variable="p0"`` differences ``p0`` directly. A NaN only spoils the
    derivatives whose stencil contains it.

    Parameters
    ----------
    values : numpy.ndarray, shape (..., n_steps)
        Quantity along the load steps (e.g. ``pbar``) [any unit].
    p0 : numpy.ndarray, shape (..., n_steps) or (n_steps,)
        Applied pressure at each step, > 0 and strictly increasing along the last axis;
        all-NaN rows (grid holes) give all-NaN derivatives.
    order : {2, 4}
        Order of accuracy; needs at least ``order + 1`` steps.
    variable : {"log_p0", "p0"}
        Variable the differences are taken in.

    Returns
    -------
    numpy.ndarray, shape of ``values``
        Derivative [unit of values / unit of p0].
    """
    if order not in (2, 4):
        raise ValueError(f"order must be 2 or 4, got {order!r}")
    if variable not in DERIVATIVE_VARIABLES:
        raise ValueError(f"variable must be one of {DERIVATIVE_VARIABLES}, got {variable!r}")
    v = np.asarray(values, dtype=float)
    p = np.broadcast_to(np.asarray(p0, dtype=float), v.shape)
    n = v.shape[-1]
    width = order + 1
    if n < width:
        raise ValueError(f"need >= {width} load steps for order-{order} differences, got {n}")
    flat_v = v.reshape(-1, n)
    flat_p = p.reshape(-1, n)
    out = np.full_like(flat_v, np.nan)
    cache: dict[bytes, np.ndarray] = {}
    for i in range(flat_v.shape[0]):
        pi = flat_p[i]
        if np.all(np.isnan(pi)):
            continue
        if not (np.all(np.isfinite(pi)) and np.all(np.diff(pi) > 0)):
            raise ValueError(f"p0 must be finite and strictly increasing along the load steps, got {pi!r}")
        if variable == "log_p0" and pi[0] <= 0:
            raise ValueError(f"p0 must be > 0 to difference in ln p0, got {pi!r}")
        key = pi.tobytes()
        if key not in cache:
            # One weight matrix per load schedule: cases usually share theirs.
            x = np.log(pi) if variable == "log_p0" else pi
            W = np.zeros((n, n))
            half = order // 2
            for j in range(n):
                lo = min(max(j - half, 0), n - width)
                W[j, lo:lo + width] = fd_weights(x[j], x[lo:lo + width])
            if variable == "log_p0":
                W /= pi[:, None]
            cache[key] = W
        out[i] = cache[key] @ flat_v[i]
    return out.reshape(v.shape)


def log_window_edges(area: np.ndarray, per_decade: int = 6, min_points: int = 2) -> np.ndarray:
    """Edges of windows of equal width ``1/per_decade`` decade in ``A/A0``, each holding steps.

    The edges sit on the fixed grid ``10^(k / per_decade)`` (integer ``k``) and cover the
    range of ``area``, so curves of different range get the same windows. Where the load
    steps are sparse in ``log A/A0`` (small loads on an equally spaced load schedule) a
    window holding fewer than ``min_points`` values of ``area`` is merged with the next
    one (the last with the previous one): those windows are wider, a whole number of
    grid windows.

    Parameters
    ----------
    area : numpy.ndarray, shape (n,)
        Reference area fractions ``A/A0`` [1] (e.g. a seed-mean load curve); non-finite
        and non-positive values are ignored; at least ``min_points`` must remain.
    per_decade : int
        Grid windows per decade (>= 1).
    min_points : int
        Fewest values of ``area`` a window must hold (>= 1).

    Returns
    -------
    numpy.ndarray, shape (n_windows + 1,)
        Increasing edges [1], the first <= ``min(area)``, the last > ``max(area)``.
    """
    for name, v in (("per_decade", per_decade), ("min_points", min_points)):
        if not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
    a = np.asarray(area, dtype=float).ravel()
    a = np.sort(a[np.isfinite(a) & (a > 0)])
    if a.size < min_points:
        raise ValueError(f"area holds {a.size} finite positive value(s); min_points={min_points}")
    k = np.floor(np.log10(a) * per_decade + 1e-9)
    grid = 10.0 ** (np.arange(k[0], k[-1] + 2) / per_decade)
    counts = np.histogram(a, bins=grid)[0]
    keep, held = [grid[0]], 0
    for j, c in enumerate(counts):
        held += c
        if held >= min_points:
            keep.append(grid[j + 1])
            held = 0
    if held:
        keep[-1] = grid[-1]
    return np.asarray(keep)


def windowed_load_slope(pbar: np.ndarray, p0: np.ndarray, area: np.ndarray, edges: np.ndarray, *,
                        min_points: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """``d pbar / d p0`` as the least-squares slope of ``pbar`` against ``p0`` per window of ``A/A0``.

    The load steps whose area fraction lies in ``[edges[j], edges[j+1])`` form window
    ``j``; a straight line ``pbar = a + b p0`` is fitted to them and ``b`` is returned with
    the steps' mean ``A/A0``. The slope is exact for a linear ``pbar(p0)``, and for a
    quadratic one on equally spaced loads it is exactly ``pbar'`` at the steps' mean
    ``p0`` (the odd moments of the loads about their mean vanish); in general its error is
    ``O(d^2 pbar''')`` for a window of half-width ``d`` in ``p0``. With windows of equal
    width in ``log A/A0`` (:func:`log_window_edges`) the estimate averages over many steps
    at large ``A/A0``, where finite differences are noisiest on a log axis, and reduces to
    the secant of two steps where steps are sparse. Non-finite values are left out.

    Parameters
    ----------
    pbar : numpy.ndarray, shape (..., n_steps)
        Mean contact pressure ``F/A`` [pressure unit].
    p0 : numpy.ndarray, shape (..., n_steps) or (n_steps,)
        Applied mean pressure ``F/A0`` [same pressure unit].
    area : numpy.ndarray, shape (..., n_steps)
        Area fraction ``A/A0`` [1] that assigns the steps to windows.
    edges : numpy.ndarray, shape (n_windows + 1,)
        Increasing window edges in ``A/A0`` [1].
    min_points : int
        Fewest steps a window needs (>= 2); fewer give NaN.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., n_windows)
        Mean ``A/A0`` of the window's steps [1] and the slope ``d pbar / d p0`` [1].
    """
    if not isinstance(min_points, (int, np.integer)) or min_points < 2:
        raise ValueError(f"min_points must be an integer >= 2, got {min_points!r}")
    y = np.asarray(pbar, dtype=float)
    x = np.broadcast_to(np.asarray(p0, dtype=float), y.shape)
    a = np.broadcast_to(np.asarray(area, dtype=float), y.shape)
    e = np.asarray(edges, dtype=float)
    if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0):
        raise ValueError("edges must be a 1-D increasing array of at least two values")
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(a)
    a_mean = np.full(y.shape[:-1] + (e.size - 1,), np.nan)
    slope = np.full_like(a_mean, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        for j in range(e.size - 1):
            m = ok & (a >= e[j]) & (a < e[j + 1])
            n = m.sum(axis=-1)
            xm = np.where(m, x, 0.0).sum(axis=-1) / n
            ym = np.where(m, y, 0.0).sum(axis=-1) / n
            dx = np.where(m, x - xm[..., None], 0.0)
            sxx = (dx * dx).sum(axis=-1)
            b = (dx * np.where(m, y - ym[..., None], 0.0)).sum(axis=-1) / sxx
            good = (n >= min_points) & (sxx > 0)
            slope[..., j] = np.where(good, b, np.nan)
            a_mean[..., j] = np.where(good, np.where(m, a, 0.0).sum(axis=-1) / n, np.nan)
    return a_mean, slope


def add_derived(ds: xr.Dataset, *, kappa_rtol: float = 1e-6, derivative_order: int = 2,
                derivative_variable: str = "log_p0") -> xr.Dataset:
    """Add ``kappa``, ``dpbar_dp0`` and ``n_unconverged`` to a combined contact dataset.

    - ``kappa = E* h' / pbar`` [1], recomputed from ``e_star`` (global attr),
      ``rms_slope`` and ``mean_contact_pressure``. If the input already has ``kappa``,
      it must agree to ``kappa_rtol`` wherever both are finite, and ``pbar`` must equal
      ``p0 / (A/A0)`` to the same tolerance at converged steps; else ValueError.
    - ``dpbar_dp0`` [1]: ``d pbar / d p0`` per case along the load steps by
      :func:`load_derivative` (default: second-order non-uniform finite differences in
      ``ln p0``, see there for why). Unconverged steps stay in the stencils (the load
      curve has no other value there); the fits drop the unconverged steps themselves.
    - ``n_unconverged(k_l, k_s, H, seed)``: number of steps with ``converged == False``;
      float64 so that grid holes (``case_present == False``) can be NaN.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`combine_cases` with ``kind="contact"``.
    kappa_rtol : float
        Relative tolerance of the consistency checks (> 0).
    derivative_order : {2, 4}
        Order of the finite differences for ``dpbar_dp0``.
    derivative_variable : {"log_p0", "p0"}
        Variable the differences are taken in.

    Returns
    -------
    xarray.Dataset
        A copy of ``ds`` with the three variables added (``kappa`` replaced by the
        recomputed values).
    """
    e_star = _check_derived_inputs(ds, kappa_rtol)
    out = ds.copy()
    present = ds["case_present"] if "case_present" in ds else xr.ones_like(ds["rms_slope"], dtype=bool)
    converged = ds["converged"].astype(bool)

    out["kappa"] = _checked_kappa(ds, e_star, converged, present, kappa_rtol)
    out["kappa"].attrs = {"units": "1", "long_name": "kappa = E* h' / pbar (normalised inverse mean contact pressure)"}
    out["dpbar_dp0"] = _dpbar_dp0(ds, present, derivative_order, derivative_variable)
    out["n_unconverged"] = _n_unconverged(converged, present)
    out["n_unconverged"].attrs = {"units": "1", "long_name": "number of unconverged load steps (NaN: no such case)"}
    return out


def _check_derived_inputs(ds: xr.Dataset, kappa_rtol: float) -> float:
    """The contact modulus ``e_star`` [pressure unit] of ``ds``, after checking :func:`add_derived`'s inputs.

    ``ValueError`` for a bad ``kappa_rtol``, a missing required variable or ``e_star``, an
    ``e_star`` that is not finite and positive, or pressures in different units.
    """
    if not (np.isfinite(kappa_rtol) and kappa_rtol > 0):
        raise ValueError(f"kappa_rtol must be a finite number > 0, got {kappa_rtol!r}")
    missing = [v for v in CONTACT_REQUIRED if v not in ds.data_vars]
    if missing:
        raise ValueError(f"ds lacks variable(s) {missing}; pass the output of combine_cases")
    if "e_star" not in ds.attrs:
        raise ValueError("ds lacks the global attribute 'e_star' (contact modulus)")
    e_star = float(ds.attrs["e_star"])
    if not (np.isfinite(e_star) and e_star > 0):
        raise ValueError(f"e_star must be a finite number > 0, got {ds.attrs['e_star']!r}")
    _check_pressure_units(ds)
    return e_star


def _checked_kappa(ds: xr.Dataset, e_star: float, converged: xr.DataArray, present: xr.DataArray,
                   kappa_rtol: float) -> xr.DataArray:
    """``kappa = E* h' / pbar`` [1] over the dims of ``mean_contact_pressure``, NaN where ``pbar <= 0``.

    Checked first: ``pbar == p0 / (A/A0)`` to ``kappa_rtol`` at the converged steps of present
    cases with ``A/A0 > 0``, then a stored ``kappa`` against the recomputed one wherever both
    are finite; ``ValueError`` naming the first offending case and step otherwise.
    ``converged`` and ``present`` are boolean masks broadcastable to ``pbar``.
    """
    pbar = ds["mean_contact_pressure"]
    a = ds["area_fraction"]
    p0 = ds["pressure"]
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = e_star * ds["rms_slope"] / pbar
        pbar_check = p0 / a
    kappa = kappa.where(np.isfinite(kappa) & (pbar > 0))
    usable = converged & (a > 0) & np.isfinite(pbar) & present
    bad = usable & ~(abs(pbar - pbar_check) <= kappa_rtol * abs(pbar_check))
    if bool(bad.any()):
        raise ValueError("mean_contact_pressure differs from pressure / area_fraction beyond "
                         f"rtol={kappa_rtol} at {_first_bad_case(bad)}")
    if "kappa" in ds:
        both = np.isfinite(ds["kappa"]) & np.isfinite(kappa)
        bad = both & ~(abs(ds["kappa"] - kappa) <= kappa_rtol * abs(kappa))
        if bool(bad.any()):
            raise ValueError("stored kappa differs from e_star * rms_slope / mean_contact_pressure "
                             f"beyond rtol={kappa_rtol} at {_first_bad_case(bad)}")
    return kappa.transpose(*pbar.dims)


def _dpbar_dp0(ds: xr.Dataset, present: xr.DataArray, order: int, variable: str) -> xr.Variable:
    """``d pbar / d p0`` [1] by :func:`load_derivative`, dims of ``mean_contact_pressure`` (``step`` last).

    ``ValueError`` if ``step`` is not the last dimension, or (prefixed "pressure / derivative
    settings") if :func:`load_derivative` rejects the load schedule or the settings.
    """
    pbar = ds["mean_contact_pressure"]
    p0 = ds["pressure"]
    dims = pbar.dims
    if dims[-1] != "step":
        raise ValueError(f"mean_contact_pressure must have 'step' as last dimension, got {dims}")
    # Holes carry no load schedule; NaN there keeps the monotonicity check to real cases.
    p0_arr = np.where(present.broadcast_like(pbar).transpose(*dims).values,
                      p0.broadcast_like(pbar).transpose(*dims).values, np.nan)
    try:
        deriv = load_derivative(pbar.values, p0_arr, order=order, variable=variable)
    except ValueError as err:
        raise ValueError(f"pressure / derivative settings: {err}") from None
    return xr.Variable(dims, deriv, attrs={
        "units": "1",
        "long_name": "d pbar / d p0 (finite differences along the load steps)",
        "stencil": f"order-{order} Fornberg differences in {variable}"})


def _n_unconverged(converged: xr.DataArray, present: xr.DataArray) -> xr.DataArray:
    """Unconverged steps per case (float64; NaN where ``present`` is False), case dims in canonical order."""
    n_unc = (~converged).sum("step").where(present).astype(np.float64)
    return n_unc.transpose(*[d for d in (*CASE_DIMS, TOPOGRAPHY_DIM) if d in n_unc.dims])


def _check_pressure_units(ds: xr.Dataset) -> None:
    """``pressure``, ``mean_contact_pressure`` and ``e_star`` share one unit (kappa, dpbar_dp0 [1]).

    Only the units that are recorded are compared (a variable without ``units`` passes).
    """
    units = {v: ds[v].attrs["units"] for v in ("pressure", "mean_contact_pressure") if "units" in ds[v].attrs}
    if "pressure_units" in ds.attrs:
        units["e_star (attribute pressure_units)"] = ds.attrs["pressure_units"]
    if len(set(units.values())) > 1:
        raise ValueError(f"pressures must share one unit for kappa = E* h' / pbar and d pbar / d p0 to be "
                         f"dimensionless, got units {units}")


def aggregate_contact(datasets: Sequence[xr.Dataset], names: Sequence[str], *,
                      expected: Iterable[tuple] | None = None) -> xr.Dataset:
    """:func:`combine_cases` (``kind="contact"``) followed by :func:`add_derived`."""
    return add_derived(combine_cases(datasets, names, expected=expected, kind="contact"))


# ---------------------------------------------------------------- seed statistics
def seed_reduce(da: xr.DataArray, present: xr.DataArray, n: xr.DataArray, label: str,
                 units: str) -> dict[str, xr.DataArray]:
    """Mean, std (ddof=1) and sem over ``seed`` of the present cases; data NaNs propagate."""
    vals = da.where(present)
    data_nan = (da.isnull() & present).any("seed")
    mean = (vals.sum("seed", skipna=True) / n).where(~data_nan & (n > 0))
    dev2 = ((vals - mean) ** 2).sum("seed", skipna=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.sqrt(dev2 / (n - 1)).where(~data_nan & (n > 1))
        sem = std / np.sqrt(n)
    mean.attrs = {"units": units, "long_name": f"mean over seeds of {label}"}
    std.attrs = {"units": units, "long_name": f"standard deviation (ddof=1) over seeds of {label}"}
    sem.attrs = {"units": units, "long_name": f"standard error of the seed mean of {label}"}
    return {"mean": mean, "std": std, "sem": sem}


def _n_seeds(present: xr.DataArray, min_seeds: int, what: str) -> xr.DataArray:
    if not isinstance(min_seeds, (int, np.integer)) or min_seeds < 1:
        raise ValueError(f"min_seeds must be an integer >= 1, got {min_seeds!r}")
    n = present.sum("seed").astype(np.int64)
    few = (n > 0) & (n < min_seeds)
    if bool(few.any()):
        raise ValueError(f"{what}: only {int(n.where(few).min())} seed(s) at "
                         f"{_first_bad_case(few)}; min_seeds={min_seeds} (set min_seeds=1 to "
                         "accept NaN standard deviations)")
    n.attrs = {"units": "1", "long_name": "number of seeds (0: no such case)"}
    return n


def seed_statistics(ds: xr.Dataset, *, variables: Sequence[str] = SEED_STAT_VARIABLES,
                    min_seeds: int = 2) -> xr.Dataset:
    """Mean, standard deviation and standard error over seeds per ``(k_l, k_s, H)``.

    Only cases with ``case_present`` enter; a NaN in a present case's data makes that
    statistic NaN (it is not skipped). ``std`` uses ``ddof=1``, ``sem = std / sqrt(n)``.

    Parameters
    ----------
    ds : xarray.Dataset
        Combined contact dataset; ``kappa``/``dpbar_dp0`` are derived by
        :func:`add_derived` if absent.
    variables : sequence of str
        Variables to reduce (default :data:`SEED_STAT_VARIABLES`).
    min_seeds : int
        Smallest accepted seed count for a present ``(k_l, k_s, H)`` (>= 1).

    Returns
    -------
    xarray.Dataset
        Dims ``(k_l, k_s, H[, step])``: ``<var>_mean``, ``<var>_std``, ``<var>_sem`` for each
        variable with the ``units`` of the variable, ``pressure_mean`` [unit of e_star],
        ``rms_slope_mean`` [1] and ``n_seeds(k_l, k_s, H)``; attrs of ``ds`` kept.
    """
    if "dpbar_dp0" not in ds or "kappa" not in ds:
        ds = add_derived(ds)
    present = ds["case_present"] if "case_present" in ds else xr.ones_like(ds["rms_slope"], dtype=bool)
    n = _n_seeds(present, min_seeds, "seed_statistics")
    out = xr.Dataset(attrs=dict(ds.attrs))
    for var in list(variables) + ["pressure", "rms_slope"]:
        if var not in ds:
            raise ValueError(f"variables: {var!r} is not in the dataset (has {sorted(ds.data_vars)})")
        units = str(ds[var].attrs.get("units", "1"))
        label = str(ds[var].attrs.get("long_name", var))
        stats = seed_reduce(ds[var], present, n, label, units)
        if var in ("pressure", "rms_slope") and var not in variables:
            out[f"{var}_mean"] = stats["mean"]
            continue
        for k, v in stats.items():
            out[f"{var}_{k}"] = v
    out["n_seeds"] = n
    return out


def representativity_statistics(ds: xr.Dataset, *, min_seeds: int = 2) -> xr.Dataset:
    """Mean, std and sem over seeds of the Gaussian L2 error ``epsilon`` per ``(k_l, k_s, H)``.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`combine_cases` with ``kind="representativity"``: ``epsilon``
        (and optionally ``rms_height``, ``rms_slope``) over ``(k_l, k_s, H, seed)``.
    min_seeds : int
        Smallest accepted seed count for a present ``(k_l, k_s, H)`` (>= 1).

    Returns
    -------
    xarray.Dataset
        Dims ``(k_l, k_s, H)``: ``epsilon_mean``, ``epsilon_std``, ``epsilon_sem`` [unit and
        reference length of epsilon], ``rms_height_mean``/``rms_slope_mean`` where available, ``n_seeds``.
    """
    if "epsilon" not in ds:
        raise ValueError("ds lacks variable 'epsilon'; pass combine_cases(..., kind='representativity')")
    present = ds["case_present"] if "case_present" in ds else xr.ones_like(ds["epsilon"], dtype=bool)
    n = _n_seeds(present, min_seeds, "representativity_statistics")
    out = xr.Dataset(attrs=dict(ds.attrs))
    eps = ds["epsilon"]
    stats = seed_reduce(eps, present, n, str(eps.attrs.get("long_name", "epsilon")),
                         str(eps.attrs.get("units", "1")))
    for k, v in stats.items():
        out[f"epsilon_{k}"] = v.assign_attrs({a: eps.attrs[a] for a in REFERENCE_ATTRS if a in eps.attrs})
    for var in ("rms_height", "rms_slope"):
        if var in ds:
            st = seed_reduce(ds[var], present, n, str(ds[var].attrs.get("long_name", var)),
                              str(ds[var].attrs.get("units", "1")))
            out[f"{var}_mean"] = st["mean"]
    out["n_seeds"] = n
    return out
