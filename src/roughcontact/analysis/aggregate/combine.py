"""Combine per-case datasets into one grid (generated scenes) or one topography axis (measured ones).

Per-case datasets (one rough surface = one ``(k_l, k_s, H, seed)`` case) have the four
case dimensions ``k_l, k_s, H`` (float64 coordinates) and ``seed`` (int64), each of
length 1; contact datasets add the load-step dimension ``step`` (integer coordinate
1..n_steps). :func:`combine_cases` stacks them on the Cartesian grid of the case
coordinates. Units propagate from the inputs, which must agree on them: :func:`combine_cases`
refuses a variable whose ``units`` (or ``reference_length_units``, the unit of a value written
as a number, :func:`roughcontact.core.quantities.per_reference_length`) differ between files.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence

import numpy as np
import xarray as xr

from ...core.values import same_value

#: The four case dimensions, in the order of every combined array.
CASE_DIMS = ("k_l", "k_s", "H", "seed")


#: The case dimension of measured surfaces: one name per topography file.
TOPOGRAPHY_DIM = "topography"


#: Variables a per-case contact dataset must hold.
CONTACT_REQUIRED = ("pressure", "area_fraction", "mean_contact_pressure", "converged", "rms_slope")


#: Variables a per-case representativity dataset must hold.
REPRESENTATIVITY_REQUIRED = ("epsilon",)


_KINDS = {"contact": CONTACT_REQUIRED, "representativity": REPRESENTATIVITY_REQUIRED}


# ------------------------------------------------------------------------ combining
def is_profiles(agg: xr.Dataset) -> bool:
    """Whether a combined dataset's cases are profiles (1-D surfaces in plane strain).

    The solver marks a profile's result with the global attribute ``surface_dimension = 1``
    (:func:`roughcontact.solver.solve_contact`); :func:`combine_cases` keeps the attributes its cases
    share. A dataset without the attribute holds 2-D maps.

    Examples
    --------
    >>> is_profiles(xr.Dataset(attrs={"surface_dimension": 1})), is_profiles(xr.Dataset())
    (True, False)
    """
    return int(agg.attrs.get("surface_dimension", 2)) == 1


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


#: Relative tolerance on the positions of two measured maps' points stacked on one grid (pressure fields):
#: sizes of one map converted from different units differ in their last digits.
GRID_RTOL = 1e-9


def _same_coordinate(got: np.ndarray, want: np.ndarray, rtol: float) -> bool:
    if got.shape != want.shape:
        return False
    if rtol and got.dtype.kind == "f" and want.dtype.kind == "f":
        return bool(np.allclose(got, want, rtol=rtol, atol=rtol * float(np.max(np.abs(want), initial=0.0))))
    return bool(np.array_equal(got, want))


def _coordinate_text(values) -> str:
    """A coordinate in a few words: its length and ends (a field's x or y has hundreds of values)."""
    if values is None:
        return "none"
    values = np.asarray(values)
    if values.size <= 4:
        return repr(values.tolist())
    return f"{values.size} values {values[0]!r} .. {values[-1]!r}"


def _check_like_first(ds: xr.Dataset, name: str, ref: xr.Dataset, ref_name: str, kind: str,
                      case_dims: Sequence[str], coord_rtol: float = 0.0) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``ds`` can be stacked with the first case ``ref``.

    Same variables (the kind's required ones among them) with the same units, the same non-case
    dimensions and coordinates (exact join; float coordinates within ``coord_rtol`` if given), and
    for contact data the same ``e_star``.
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
                dim in ds.coords and not _same_coordinate(ds[dim].values, ref[dim].values, coord_rtol)):
            got = ds[dim].values if dim in ds.coords else None
            want = ref[dim].values if dim in ref.coords else None
            raise ValueError(f"{name}: {dim!r} coordinate differs from {ref_name}'s ({_coordinate_text(got)} "
                             f"against {_coordinate_text(want)}): cases are stacked on one coordinate")
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
    datasets, names = _checked_inputs(datasets, names, kind)
    keys = _case_keys(datasets, names, kind)
    expected_set = _expected_cases(keys, names, expected)
    axes, positions, present_mask = _grid_layout(keys, expected_set)
    ref = datasets[0]
    coords = _grid_coords(axes, ref)
    has_holes = not present_mask.all()
    data_vars = {var: _stack_variable(var, datasets, names, positions, present_mask.shape, has_holes)
                 for var in sorted(set(ref.data_vars))}
    data_vars["case_present"] = xr.Variable(CASE_DIMS, present_mask, attrs={
        "units": "1", "long_name": "a dataset exists for this case (False: grid hole, not expected)"})
    attrs = _shared_attrs(datasets)
    attrs["n_cases"] = len(datasets)
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _checked_inputs(datasets: Sequence[xr.Dataset], names: Sequence[str],
                    kind: str) -> tuple[list[xr.Dataset], list[str]]:
    """``datasets`` and ``names`` (as str) as lists, after checking ``kind`` and that they pair up, non-empty."""
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {sorted(_KINDS)}, got {kind!r}")
    datasets = list(datasets)
    names = [str(n) for n in names]
    if len(datasets) != len(names):
        raise ValueError(f"datasets and names must have the same length, got {len(datasets)} "
                         f"and {len(names)}")
    if not datasets:
        raise ValueError("datasets is empty: nothing to combine")
    return datasets, names


def _grid_layout(keys: Sequence[tuple], expected_set: set[tuple]) -> tuple[list[list], list[tuple], np.ndarray]:
    """The case grid: its ``axes``, each key's grid index and the bool mask of the cases present.

    The grid spans the expected cases too, so that a hole stays visible as one: ``axes`` holds
    the sorted values of ``k_l, k_s, H, seed`` over ``keys`` and ``expected_set``;
    ``positions[i]`` is the index of ``keys[i]``; the mask has shape ``(len(ax) for ax in axes)``.
    """
    axes = [sorted({k[i] for k in set(keys) | expected_set}) for i in range(4)]
    index = [{v: j for j, v in enumerate(ax)} for ax in axes]
    positions = [tuple(index[i][key[i]] for i in range(4)) for key in keys]
    present_mask = np.zeros(tuple(len(ax) for ax in axes), dtype=bool)
    for pos in positions:
        present_mask[pos] = True
    return axes, positions, present_mask


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
        _check_like_first(ds, name, datasets[0], names[0], kind, (TOPOGRAPHY_DIM,), coord_rtol=GRID_RTOL)
        # a field's x, y within round-off of the first map's: stacked on the first's
        grid = {dim: datasets[0][dim] for dim in ("x", "y") if dim in ds.coords and dim in datasets[0].coords}
        by_case[case] = (ds.assign_coords(grid), name)
    missing = [e for e in expected if e not in by_case]
    if missing:
        raise ValueError(f"{len(missing)} expected topography case(s) have no dataset: {', '.join(missing)}")
    ordered = [by_case[e][0] for e in expected]
    out = xr.concat(ordered, dim=TOPOGRAPHY_DIM, data_vars="minimal", coords="minimal", compat="equals",
                    combine_attrs="drop_conflicts")
    out.attrs["n_cases"] = len(ordered)
    return out


# ------------------------------------------------------------------- derived values
def first_bad_case(bad: xr.DataArray) -> str:
    """The coordinates of the first True element of ``bad`` as ``'dim=value, ...'`` (for error messages)."""
    idx = np.argwhere(bad.values)[0]
    parts = [f"{d}={bad[d].values[i]!r}" for d, i in zip(bad.dims, idx, strict=True)]
    return ", ".join(parts)
