"""Labelled per-case datasets: arrays in, xarray out, no file I/O.

Every per-case dataset carries length-1 dimensions ``k_l, k_s, H, seed`` so that the
aggregate stage can join the cases with ``xarray.combine_by_coords``. The coordinate
values are the floats of the config strings (``float("0.36")``, identical on every
parse); file names use the strings themselves.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .accuracy import PERIMETER_C, perimeter_corrected_area
from .surface import finite_difference_rms_slope, spectral_moments

CASE_DIMS = ("k_l", "k_s", "H", "seed")

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


def expand_case(ds: xr.Dataset, k_l: str, k_s: str, hurst: str, seed: int) -> xr.Dataset:
    """Add the length-1 case dimensions to every data variable of ``ds``."""
    coords = case_coords(k_l, k_s, hurst, seed)
    out = ds.expand_dims({name: 1 for name in CASE_DIMS}).assign_coords(coords)
    for name in out.data_vars:
        out[name] = out[name].transpose(*CASE_DIMS, *[d for d in out[name].dims if d not in CASE_DIMS])
        out[name].attrs = ds[name].attrs
    return out


def surface_dataset(heights: np.ndarray, *, k_l: str, k_s: str, hurst: str, seed: int,
                    length: float, normalisation: dict) -> xr.Dataset:
    """Dataset of one generated surface.

    ``heights`` is (n, n) [length unit]; ``normalisation`` is ``{"rms_slope": v}`` or
    ``{"rms_height": v}``, recorded as an attribute. Adds scalar statistics: rms height,
    spectral and finite-difference rms slope, profile moments and Nayak's alpha.
    """
    n = heights.shape[0]
    stats = spectral_moments(heights, length)
    x = np.arange(n) * (length / n)
    ds = xr.Dataset(
        {
            "heights": (("x", "y"), heights, {"units": "length unit of L", "long_name": "surface height h(x, y)"}),
            "rms_height": ((), stats["rms_height"],
                           {"units": "length unit of L", "long_name": "rms height (spectral)"}),
            "rms_slope": ((), stats["rms_slope"],
                          {"units": "1", "long_name": "rms slope sqrt(<|grad h|^2>) from the spectrum"}),
            "rms_slope_fd": ((), finite_difference_rms_slope(heights, length),
                             {"units": "1", "long_name": "rms slope from periodic central differences"}),
            "m0": ((), stats["m0"], {"units": "length unit^2", "long_name": "profile spectral moment m0"}),
            "m2": ((), stats["m2"], {"units": "1", "long_name": "profile spectral moment m2"}),
            "m4": ((), stats["m4"], {"units": "length unit^-2", "long_name": "profile spectral moment m4"}),
            "alpha": ((), stats["alpha"],
                      {"units": "1", "long_name": "Nayak bandwidth alpha = m0 m4 / m2^2 (profile moments)"}),
        },
        coords={
            "x": ("x", x, {"units": "length unit of L", "long_name": "position along x"}),
            "y": ("y", x.copy(), {"units": "length unit of L", "long_name": "position along y"}),
        },
        attrs={"length": float(length), "n": int(n), "normalisation": str(normalisation)},
    )
    return expand_case(ds, k_l, k_s, hurst, seed)


def representativity_dataset(epsilon: float, heights: np.ndarray, *, n_bins: int, k_l: str, k_s: str,
                             hurst: str, seed: int) -> xr.Dataset:
    """Dataset of one surface's representativity: eps and the heights' mean and std."""
    ds = xr.Dataset(
        {
            "epsilon": ((), float(epsilon), {"units": "length unit^-1/2",
                                            "long_name": "L2 error between the heights PDF and its Gaussian"}),
            "mean_height": ((), float(np.mean(heights)), {"units": "length unit of L", "long_name": "mean height"}),
            "std_height": ((), float(np.std(heights)), {"units": "length unit of L",
                                                        "long_name": "standard deviation of heights"}),
        },
        attrs={"n_bins": int(n_bins)},
    )
    return expand_case(ds, k_l, k_s, hurst, seed)


def contact_dataset(result: xr.Dataset, *, rms_slope: float, alpha: float, e_star: float,
                    k_l: str, k_s: str, hurst: str, seed: int) -> xr.Dataset:
    """Per-case contact dataset: the solver's result over ``step`` plus kappa and surface stats.

    kappa = E* h' / pbar [1] with h' the surface's spectral rms slope, the paper's
    normalised inverse mean contact pressure (its Fig. 3). The solver's ``wall_time``
    is dropped: result files must be byte-identical across reruns, so timings go to the
    job's log and Snakemake benchmark file instead.
    """
    ds = result.drop_vars("wall_time", errors="ignore")
    dx = float(result.attrs["length"]) / int(result.attrs["n"])
    ds["area_fraction_corrected"] = xr.DataArray(
        perimeter_corrected_area(ds["area_fraction"].values, ds["contact_perimeter"].values, dx),
        dims=("step",),
        attrs={"units": "1",
               "long_name": f"perimeter-corrected contact area fraction A_pix/A0 - c P dx, c = {PERIMETER_C:.4f}"},
    )
    ds["kappa"] = (e_star * rms_slope / ds["mean_contact_pressure"]).assign_attrs(
        units="1", long_name="kappa = E* h' / mean contact pressure")
    ds["rms_slope"] = xr.DataArray(float(rms_slope), attrs={
        "units": "1", "long_name": "spectral rms slope h' of the surface"})
    ds["alpha"] = xr.DataArray(float(alpha), attrs={
        "units": "1", "long_name": "Nayak bandwidth alpha of the surface (profile moments)"})
    ds.attrs["e_star"] = float(e_star)
    return expand_case(ds, k_l, k_s, hurst, seed)


def surface_heights(ds: xr.Dataset, source) -> tuple[np.ndarray, float]:
    """The ``(n, n)`` heights and the cell side ``L`` of a surface dataset, checked.

    ``source`` names the file in messages. Raises ``ValueError`` when the heights are
    missing, not a square 2-D field of at least 4 x 4 points over ``x, y``, or not all
    finite, or when the global attribute ``length`` is missing or not a positive number.
    """
    if "heights" not in ds:
        raise ValueError(f"{source}: lacks the variable 'heights'")
    da = ds["heights"].squeeze([d for d in CASE_DIMS if d in ds["heights"].dims])
    if da.dims != ("x", "y") or da.shape[0] != da.shape[1] or da.shape[0] < 4:
        raise ValueError(f"{source}: 'heights' must be a square 2-D field over (x, y) of at least 4 x 4 points, "
                         f"got dims {da.dims} and shape {da.shape}")
    heights = np.asarray(da.values, dtype=float)
    if not np.all(np.isfinite(heights)):
        raise ValueError(f"{source}: 'heights' holds {int(np.sum(~np.isfinite(heights)))} NaN or infinite "
                         "value(s); every height must be finite")
    length = ds.attrs.get("length")
    try:
        length = float(length)
    except (TypeError, ValueError):
        raise ValueError(f"{source}: the global attribute 'length' (side of the cell) is missing or not a "
                         f"number: {length!r}") from None
    if not (np.isfinite(length) and length > 0):
        raise ValueError(f"{source}: the global attribute 'length' must be a finite number > 0, got {length!r}")
    return heights, length


def representativity_batch(surface: dict, *, k_l: str, k_s: str, hurst: str, seeds: int,
                           n_bins: int) -> xr.Dataset:
    """eps of seeds ``0 .. seeds-1`` of one ``(k_l, k_s, H)``, each surface made in memory.

    One job of the representativity study: at N = 1024 a surface and its eps take
    ~0.3 s, less than a job's start-up, so the seeds of a grid point run together.
    ``surface`` is the study's surface block (``N``, ``L``, ``plateau`` and
    ``rms_height`` or ``rms_slope``). Returns the per-seed datasets of
    :func:`representativity_dataset` concatenated along ``seed`` (dims
    ``k_l, k_s, H`` of length 1 and ``seed`` of length ``seeds``); one seed is
    ``ds.sel(seed=[s])``.
    """
    from .representativity import gaussian_l2_error
    from .surface import generate_surface

    norm = {k: surface[k] for k in ("rms_slope", "rms_height") if k in surface}
    parts = []
    for seed in range(seeds):
        h = generate_surface(surface["N"], float(k_l), float(k_s), float(hurst), seed,
                             length=surface["L"], plateau=surface["plateau"], **norm)
        eps = gaussian_l2_error(h, n_bins)
        parts.append(representativity_dataset(eps, h, n_bins=n_bins, k_l=k_l, k_s=k_s, hurst=hurst,
                                              seed=seed))
    return xr.concat(parts, dim="seed", combine_attrs="override")


def split_seeds(ds: xr.Dataset) -> list[xr.Dataset]:
    """The per-seed datasets of a batch (each with a length-1 ``seed`` dimension)."""
    return [ds.isel(seed=[i]) for i in range(ds.sizes["seed"])]
