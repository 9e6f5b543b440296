"""Labelled per-case datasets: arrays in, xarray out, no file I/O.

Every per-case dataset carries length-1 dimensions ``k_l, k_s, H, seed`` so that the
aggregate stage can join the cases with ``xarray.combine_by_coords``. The coordinate
values are the floats of the config strings (``float("0.36")``, identical on every
parse); file names use the strings themselves. A measured surface's case is its name
instead: one length-1 dimension ``topography`` with a string coordinate.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
import xarray as xr

from ..analysis.aggregate.combine import CASE_DIMS, TOPOGRAPHY_DIM
from ..core.cell import Cell
from ..core.quantities import cf_unit
from ..statistics.patches import resolved_variable
from ..statistics.representativity import epsilon_attrs
from ..surfaces.synthetic import (
    finite_difference_rms_slope,
    generate_profile,
    generate_surface,
    nonperiodic_moments,
    profile_moments,
    profile_spectral_moments,
    spectral_moments,
)
from ..theory.perimeter import PERIMETER_C, perimeter_corrected_area

_CASE_COORD_ATTRS = {
    "k_l": {"units": "1", "long_name": "long-wavelength cutoff L/lambda_l"},
    "k_s": {"units": "1", "long_name": "short-wavelength cutoff L/lambda_s"},
    "H": {"units": "1", "long_name": "Hurst roughness exponent"},
    "seed": {"units": "1", "long_name": "white-noise seed"},
}


def case_coords(k_l: str, k_s: str, hurst: str, seed: int) -> dict:
    """Length-1 case coordinates with units and long_name, from config strings."""
    values = {"k_l": float(k_l), "k_s": float(k_s), "H": float(hurst), "seed": int(seed)}
    return {
        name: xr.Variable((name,), np.array([value]), attrs=_CASE_COORD_ATTRS[name])
        for name, value in values.items()
    }


def expand_case(ds: xr.Dataset, k_l: str | None = None, k_s: str | None = None, hurst: str | None = None,
                seed: int | None = None, *, topography: str | None = None) -> xr.Dataset:
    """Add the length-1 case dimensions to every data variable of ``ds``.

    A generated case's ``k_l, k_s, H, seed``, or a measured one's ``topography`` name.
    """
    if topography is not None:
        dims = (TOPOGRAPHY_DIM,)
        coords = {TOPOGRAPHY_DIM: xr.Variable(dims, np.array([str(topography)], dtype=object),
                                              {"units": "1", "long_name": "name of the measured topography"})}
    else:
        dims, coords = CASE_DIMS, case_coords(k_l, k_s, hurst, seed)
    out = ds.expand_dims({name: 1 for name in dims}).assign_coords(coords)
    for name in out.data_vars:
        out[name] = out[name].transpose(*dims, *[d for d in out[name].dims if d not in dims])
        out[name].attrs = ds[name].attrs
    return out


def generated_heights(surface: dict, k_l: str, k_s: str, hurst: str, seed: int) -> np.ndarray:
    """The heights a generated study's ``surface`` block makes for one case: ``(N, N)``, or ``(N,)`` for a
    profile (``surface.dimension: 1``, :func:`roughcontact.surfaces.synthetic.generate_profile`)."""
    norm = {k: surface[k] for k in ("rms_slope", "rms_height") if k in surface}
    make = generate_profile if surface.get("dimension", 2) == 1 else generate_surface
    return make(surface["N"], float(k_l), float(k_s), float(hurst), int(seed), length=surface["L"],
                plateau=surface["plateau"], **norm)


def surface_dataset(heights: np.ndarray, *, k_l: str, k_s: str, hurst: str, seed: int,
                    length: float, normalisation: dict, length_unit: str = "1") -> xr.Dataset:
    """Dataset of one generated surface (a profile, ``heights`` of shape (n,): :func:`profile_surface_dataset`).

    ``heights`` is (n, n) [``length_unit``, the unit of ``length`` too, one of
    :data:`roughcontact.core.quantities.LENGTH_UNITS`; ``"1"``: nondimensional]; ``normalisation``
    is ``{"rms_slope": v}`` or ``{"rms_height": v}``, recorded as an attribute. Adds scalar
    statistics: rms height, spectral and finite-difference rms slope, profile moments
    (``m0`` [length^2], ``m2`` [1], ``m4`` [length^-2]) and Nayak's alpha. The global
    attribute ``length_units`` is the unit of the attribute ``length``.
    """
    if heights.ndim == 1:
        return profile_surface_dataset(heights, length=length, length_unit=length_unit, periodic=True,
                                       attrs={"normalisation": str(normalisation)}).pipe(
            expand_case, k_l, k_s, hurst, seed)
    n = heights.shape[0]
    stats = spectral_moments(heights, length)
    x = np.arange(n) * (length / n)
    u_len = cf_unit(length_unit, length_power=1)
    ds = xr.Dataset(
        {
            "heights": (("x", "y"), heights, {"units": u_len, "long_name": "surface height h(x, y)"}),
            "rms_height": ((), stats["rms_height"],
                           {"units": u_len, "long_name": "rms height (spectral)"}),
            "rms_slope": ((), stats["rms_slope"],
                          {"units": "1", "long_name": "rms slope sqrt(<|grad h|^2>) from the spectrum"}),
            "rms_slope_fd": ((), finite_difference_rms_slope(heights, length),
                             {"units": "1", "long_name": "rms slope from periodic central differences"}),
            "m0": ((), stats["m0"], {"units": cf_unit(length_unit, length_power=2),
                                     "long_name": "profile spectral moment m0"}),
            "m2": ((), stats["m2"], {"units": "1", "long_name": "profile spectral moment m2"}),
            "m4": ((), stats["m4"], {"units": cf_unit(length_unit, length_power=-2),
                                     "long_name": "profile spectral moment m4"}),
            "alpha": ((), stats["alpha"],
                      {"units": "1", "long_name": "Nayak bandwidth alpha = m0 m4 / m2^2 (profile moments)"}),
        },
        coords={
            "x": ("x", x, {"units": u_len, "long_name": "position along x"}),
            "y": ("y", x.copy(), {"units": u_len, "long_name": "position along y"}),
        },
        attrs={"length": float(length), "length_units": u_len, "n": int(n),
               "normalisation": str(normalisation)},
    )
    return expand_case(ds, k_l, k_s, hurst, seed)


def profile_surface_dataset(heights: np.ndarray, *, length: float, length_unit: str, periodic: bool,
                            attrs: dict) -> xr.Dataset:
    """Dataset of one profile (a 1-D surface: heights ``(n,)`` over ``x`` [length_unit], period or length ``length``).

    The statistics are the profile's (one slope, h' = sqrt(<(dh/dx)^2>), the h' of loads ``relative_to:
    rms_slope`` and of kappa): spectral with exact derivatives when ``periodic`` (a generated profile),
    else forward differences inside the profile (a measured one: its spectrum would count the jump between
    its ends as roughness). Global attributes: ``length``, ``n``, ``length_units``, ``surface_dimension`` = 1
    and ``attrs``. No case dimensions (the callers add them).
    """
    n = heights.size
    u_len = cf_unit(length_unit, length_power=1)
    stats = profile_spectral_moments(heights, length) if periodic else profile_moments(heights, length)
    how = "from the spectrum (exact derivative)" if periodic else "from forward differences inside the profile"
    variables = {
        "heights": (("x",), heights, {"units": u_len, "long_name": "profile height h(x)"}),
        "rms_height": ((), stats["rms_height"], {"units": u_len, "long_name": "rms height about the mean"}),
        "rms_slope": ((), stats["rms_slope"], {"units": "1", "long_name": f"rms slope sqrt(<(dh/dx)^2>) {how}"}),
        "m0": ((), stats["m0"], {"units": cf_unit(length_unit, length_power=2), "long_name": "profile moment m0"}),
        "m2": ((), stats["m2"], {"units": "1", "long_name": "profile moment m2 = <(dh/dx)^2>"}),
        "m4": ((), stats["m4"], {"units": cf_unit(length_unit, length_power=-2),
                                 "long_name": "profile moment m4 = <(d2h/dx2)^2>"}),
        "alpha": ((), stats["alpha"], {"units": "1", "long_name": "Nayak bandwidth alpha = m0 m4 / m2^2"}),
    }
    if periodic:
        dx = length / n
        slope = float(np.sqrt(np.mean(((np.roll(heights, -1) - np.roll(heights, 1)) / (2 * dx)) ** 2)))
        variables["rms_slope_fd"] = ((), slope, {"units": "1",
                                                 "long_name": "rms slope from periodic central differences"})
    return xr.Dataset(
        variables,
        coords={"x": ("x", np.arange(n) * (length / n), {"units": u_len, "long_name": "position along x"})},
        attrs={"length": float(length), "length_units": u_len, "n": int(n), "surface_dimension": 1, **attrs},
    )


def representativity_dataset(epsilon: float, heights: np.ndarray, *, n_bins: int, k_l: str | None = None,
                             k_s: str | None = None, hurst: str | None = None, seed: int | None = None,
                             topography: str | None = None, length_unit: str = "1") -> xr.Dataset:
    """Dataset of one surface's representativity: eps and the heights' mean and std.

    The case is a generated one's ``k_l, k_s, hurst, seed`` or a measured one's ``topography``.

    ``length_unit`` is the unit of the heights (:data:`roughcontact.core.quantities.LENGTH_UNITS`).
    eps, of unit length^-1/2, which no CF ``units`` string can write, is written as its number
    for heights in ``length_unit`` (``units`` ``"1"``, :func:`roughcontact.statistics.representativity.epsilon_attrs`).
    """
    u_len = cf_unit(length_unit, length_power=1)
    ds = xr.Dataset(
        {
            "epsilon": ((), float(epsilon), epsilon_attrs(length_unit)),
            "mean_height": ((), float(np.mean(heights)), {"units": u_len, "long_name": "mean height"}),
            "std_height": ((), float(np.std(heights)), {"units": u_len,
                                                        "long_name": "standard deviation of heights"}),
        },
        attrs={"n_bins": int(n_bins)},
    )
    return expand_case(ds, k_l, k_s, hurst, seed, topography=topography)


def contact_dataset(result: xr.Dataset, *, rms_slope: float, alpha: float, e_star: float,
                    k_l: str | None = None, k_s: str | None = None, hurst: str | None = None,
                    seed: int | None = None, topography: str | None = None) -> xr.Dataset:
    """Per-case contact dataset: the solver's result over ``step`` plus kappa and surface stats.

    The case is a generated one's ``k_l, k_s, hurst, seed`` or a measured one's ``topography``.
    kappa = E* h' / pbar [1] with h' the surface's rms slope (spectral for a generated
    surface, finite differences inside the patch for a measured one), the paper's
    normalised inverse mean contact pressure (its Fig. 3). The solver's ``wall_time``
    is dropped: result files must be byte-identical across reruns, so timings go to the
    job's log and Snakemake benchmark file instead. Units: those of ``result`` (the
    ``length_unit``/``pressure_unit`` given to :func:`roughcontact.solver.solve_contact`;
    ``e_star`` in its ``pressure_units``); what this adds is dimensionless. A profile's solve
    (``surface_dimension`` 1) gets no ``area_fraction_corrected``: Yastrebov et al.'s (2017)
    perimeter correction is derived for a map's pixel boundaries, not a profile's interval ends.
    ``contact_resolved`` flags each step whose largest contact patch (the solver's ``largest_patch_nodes``)
    holds at least 4 nodes (:mod:`roughcontact.statistics.patches`); an unresolved step's A/A0 is the grid's.
    """
    ds = result.drop_vars("wall_time", errors="ignore")
    ds["contact_resolved"] = resolved_variable(ds["largest_patch_nodes"])
    if result.attrs.get("surface_dimension") != 1:  # the perimeter correction is derived for maps' pixels only
        _add_corrected_area(ds, Cell.from_attrs(result.attrs, (int(result.attrs["nx"]), int(result.attrs["ny"]))))
    ds["kappa"] = (e_star * rms_slope / ds["mean_contact_pressure"]).assign_attrs(
        units="1", long_name="kappa = E* h' / mean contact pressure")
    ds["rms_slope"] = xr.DataArray(float(rms_slope), attrs={
        "units": "1", "long_name": "rms slope h' of the surface (its surface file's rms_slope)"})
    ds["alpha"] = xr.DataArray(float(alpha), attrs={
        "units": "1", "long_name": "Nayak bandwidth alpha of the surface (profile moments)"})
    ds.attrs["e_star"] = float(e_star)
    return expand_case(ds, k_l, k_s, hurst, seed, topography=topography)


def _add_corrected_area(ds: xr.Dataset, cell: Cell) -> None:
    """``area_fraction_corrected`` of a map's contact (Yastrebov et al. 2017's perimeter correction)."""
    ds["area_fraction_corrected"] = xr.DataArray(
        perimeter_corrected_area(ds["area_fraction"].values, ds["contact_perimeter"].values, cell.pixel_scale),
        dims=("step",),
        attrs={"units": "1",
               # one text for every cell, so that square and rectangular cases aggregate
               "long_name": f"perimeter-corrected contact area fraction A_pix/A0 - c P dx, c = {PERIMETER_C:.4f}, "
                            "dx = sqrt(dx dy) the pixel side"},
    )


def measured_surface_dataset(measured, *, name: str) -> xr.Dataset:
    """Dataset of one measured surface (a :class:`roughcontact.surfaces.topography.MeasuredSurface`).

    ``heights`` (nx, ny) and ``x``, ``y`` in the study's length unit ``measured.unit``; the
    statistics come from differences inside the patch (:func:`roughcontact.surfaces.synthetic.nonperiodic_moments`:
    a measured patch is not periodic, and its spectrum would count the jump between opposite
    edges as roughness). Global attributes (:meth:`~.core.cell.Cell.surface_attrs`): ``length`` and ``n`` for a square
    cell with square pixels, else ``length_x``, ``length_y``, ``nx`` and ``ny``; ``length_units``
    and ``source`` (the reader's provenance as JSON: file, sha256, reader, units and sizes before
    conversion, undefined points, detrending, cropping). A line scan: :func:`profile_surface_dataset`.
    """
    h, unit = measured.heights, measured.unit
    if h.ndim == 1:
        ds = profile_surface_dataset(h, length=measured.lengths[0], length_unit=unit, periodic=False,
                                     attrs={"source": json.dumps(measured.info, sort_keys=True)})
        ds["undefined_fraction"] = xr.DataArray(float(measured.info.get("undefined_fraction", 0.0)), attrs={
            "units": "1", "long_name": "fraction of the file's points not measured (filled before contact)"})
        return expand_case(ds, topography=name)
    stats = nonperiodic_moments(h, measured.lengths)
    u_len = cf_unit(unit, length_power=1)
    (nx, ny), (lx, ly) = h.shape, measured.lengths
    ds = xr.Dataset(
        {
            "heights": (("x", "y"), h, {"units": u_len, "long_name": "surface height h(x, y)"}),
            "rms_height": ((), stats["rms_height"], {"units": u_len, "long_name": "rms height about the mean"}),
            "rms_slope": ((), stats["rms_slope"], {"units": "1", "long_name": (
                "rms slope sqrt(<|grad h|^2>) from forward differences inside the patch")}),
            "m0": ((), stats["m0"], {"units": cf_unit(unit, length_power=2), "long_name": "profile moment m0"}),
            "m2": ((), stats["m2"], {"units": "1", "long_name": "profile moment m2 = <(dh/dx)^2>, differences"}),
            "m4": ((), stats["m4"], {"units": cf_unit(unit, length_power=-2),
                                     "long_name": "profile moment m4 = <(d2h/dx2)^2>, differences"}),
            "alpha": ((), stats["alpha"], {"units": "1", "long_name": "Nayak bandwidth alpha = m0 m4 / m2^2"}),
            "undefined_fraction": ((), float(measured.info.get("undefined_fraction", 0.0)), {
                "units": "1", "long_name": "fraction of the file's points not measured (filled before contact)"}),
        },
        coords={
            "x": ("x", np.arange(nx) * (lx / nx), {"units": u_len, "long_name": "position along x"}),
            "y": ("y", np.arange(ny) * (ly / ny), {"units": u_len, "long_name": "position along y"}),
        },
        attrs={**Cell.of(h.shape, measured.length).surface_attrs(), "length_units": u_len,
               "source": json.dumps(measured.info, sort_keys=True)},
    )
    return expand_case(ds, topography=name)


def surface_heights(ds: xr.Dataset, source):
    """The ``(nx, ny)`` heights and the solver's ``length`` (L, or (Lx, Ly)) of a surface dataset, checked; a
    profile's (global attribute ``surface_dimension`` 1) ``(n,)`` heights and its length ``L``.

    ``source`` names the file in messages. Raises ``ValueError`` when the heights are
    missing, not a 2-D field of at least 4 x 4 points over ``x, y``, not real numbers, or not all
    finite, or when the cell's sides (:meth:`~.core.cell.Cell.from_attrs`) are missing or not positive numbers.
    Reads the whole field; :func:`surface_grid` checks a file without it.
    """
    da = heights_field(ds, source)
    heights = np.asarray(da.values, dtype=float)
    _require_finite(heights, source)
    return heights, Cell.from_attrs(ds.attrs, heights.shape, source).length


#: Rows of heights (points of a profile) that :func:`surface_grid` reads to check their values, spread evenly
#: over x from the first row to the last: 8 rows are 4 MiB at ny = 65536, against 34 GB for the field.
SAMPLE_ROWS = 8


def surface_grid(ds: xr.Dataset, source, sample_rows: int = SAMPLE_ROWS):
    """The grid ``(nx, ny)`` (a profile's ``(n,)``) and the solver's ``length`` of a surface dataset, checked from
    its header and a sample of its heights: :func:`surface_heights` without reading the whole field.

    Parameters
    ----------
    ds : xarray.Dataset
        A surface file's dataset, best opened lazily (:func:`~.io.lazy_dataset`): then only the rows sampled are
        read from the file, each as one hyperslab of ``ny`` values.
    source : str or path
        The file, named in messages.
    sample_rows : int
        How many rows along x (``x`` indices ``round(linspace(0, nx - 1, sample_rows))``, the first and the last
        included) must hold finite heights: ``sample_rows * ny`` values read, 8 bytes each.

    Returns
    -------
    shape : tuple of int
        ``(nx, ny)``, or ``(n,)`` for a profile.
    length : float or (float, float)
        ``L``, or ``(Lx, Ly)`` for a rectangular cell [the file's length unit].

    Raises
    ------
    ValueError
        Naming ``source``, with :func:`surface_heights`' messages for what the header shows (the variable
        missing, its dimensions or shape, a type that is not real numbers, the cell's sides) and for a NaN or
        infinite height in the rows sampled. A NaN or infinite height in another row is not seen here: the MPI
        ranks find it, each checking the rows it reads (:func:`roughcontact.solver.mpi.program.read_rows`), and
        every rank ends with one line naming the file and its rows (exit status 2).
    """
    da = heights_field(ds, source)
    rows = np.unique(np.round(np.linspace(0, da.shape[0] - 1, max(1, min(sample_rows, da.shape[0])))).astype(int))
    # one row at a time: each a hyperslab read of its own, whatever the backend makes of a list of indices
    sample = np.stack([np.asarray(da.isel(x=int(i)).values, dtype=float) for i in rows])
    _require_finite(sample, source, f" in the {rows.size} rows checked (x = {', '.join(map(str, rows))})")
    return tuple(da.shape), Cell.from_attrs(ds.attrs, da.shape, source).length


def heights_field(ds: xr.Dataset, source) -> xr.DataArray:
    """The heights of a surface dataset without its length-1 case dimensions, checked from the header alone (no
    value read): a 2-D field over ``(x, y)`` of at least 4 x 4 points (a profile: over ``(x,)``, at least 4), of
    real numbers. ``ValueError`` naming ``source`` otherwise."""
    if "heights" not in ds:
        raise ValueError(f"{source}: lacks the variable 'heights'")
    da = ds["heights"].squeeze([d for d in (*CASE_DIMS, TOPOGRAPHY_DIM) if d in ds["heights"].dims])
    if ds.attrs.get("surface_dimension") == 1:  # a profile: (n,) over x (Cell.from_attrs: its one 'length')
        if da.dims != ("x",) or da.size < 4:
            raise ValueError(f"{source}: 'heights' of a profile (surface_dimension 1) must be a field over (x,) of "
                             f"at least 4 points, got dims {da.dims} and shape {da.shape}")
    elif da.dims != ("x", "y") or min(da.shape) < 4:
        raise ValueError(f"{source}: 'heights' must be a 2-D field over (x, y) of at least 4 x 4 points, "
                         f"got dims {da.dims} and shape {da.shape}")
    if da.dtype.kind not in "iuf":
        raise ValueError(f"{source}: 'heights' must hold real numbers, got the type {da.dtype}; remove the file "
                         "(or rerun with -f) to remake it")
    return da


def _require_finite(heights: np.ndarray, source, where: str = "") -> None:
    """``ValueError`` naming ``source`` if ``heights`` (all of them, or those read ``where``) hold NaN or inf."""
    if not np.all(np.isfinite(heights)):
        raise ValueError(f"{source}: 'heights' holds {int(np.sum(~np.isfinite(heights)))} NaN or infinite "
                         f"value(s){where}; every height must be finite")


def representativity_batch(surface: dict, *, k_l: str, k_s: Sequence[str], hurst: str, seeds: int,
                           n_bins: int, length_unit: str | None = None) -> xr.Dataset:
    """eps of every ``k_s`` and seeds ``0 .. seeds-1`` of one ``(k_l, H)``, surfaces made in memory.

    One job of the representativity study. At N = 1024 a surface and its eps take
    ~0.1 s of CPU and a job's Python start-up ~1.1 s, so one job computes a whole k_l
    (the paper's: 6 k_s x 30 seeds, ~20 s) to keep the start-up under 10 % of the work.
    ``surface`` is the study's surface block (``N``, ``L``, ``plateau`` and
    ``rms_height`` or ``rms_slope``, optionally ``unit``). ``length_unit`` is the unit of
    the heights; ``None`` (default): ``surface["unit"]``, ``"1"`` without one. Returns the
    per-case datasets of :func:`representativity_dataset` combined (dims ``k_l, H`` of
    length 1, ``k_s`` in the given order, ``seed`` of length ``seeds``); one case is
    ``ds.isel(k_s=[i], seed=[s])``, see :func:`split_cases`.
    """
    from ..statistics.representativity import gaussian_l2_error

    unit = surface.get("unit", "1") if length_unit is None else length_unit
    rows = []
    for ks in k_s:
        parts = []
        for seed in range(seeds):
            h = generated_heights(surface, k_l, ks, hurst, seed)
            parts.append(representativity_dataset(gaussian_l2_error(h, n_bins), h, n_bins=n_bins, k_l=k_l,
                                                  k_s=ks, hurst=hurst, seed=seed, length_unit=unit))
        rows.append(xr.concat(parts, dim="seed", combine_attrs="override"))
    return xr.concat(rows, dim="k_s", combine_attrs="override")


def split_cases(ds: xr.Dataset) -> list[xr.Dataset]:
    """The per-case datasets of a batch (each with length-1 ``k_s`` and ``seed`` dimensions), k_s-major."""
    return [ds.isel(k_s=[i], seed=[j]) for i in range(ds.sizes["k_s"]) for j in range(ds.sizes["seed"])]
