"""A surface file with bad heights or attributes is named, never a raw KeyError or a NaN solve; the check of a file
from its header and a sample of rows (``surface_grid``, the MPI job's) gives the same messages."""
import numpy as np
import pytest

from roughcontact.pipeline.datasets import surface_dataset, surface_grid, surface_heights


def _surface(n=8):
    h = np.random.default_rng(0).standard_normal((n, n))
    return surface_dataset(h - h.mean(), k_l="1", k_s="4", hurst="0.8", seed=0, length=1.0,
                           normalisation={"rms_slope": 0.1}).assign_attrs(length=1.0)


def test_good_surface():
    heights, length = surface_heights(_surface(), "s.nc")
    assert heights.shape == (8, 8) and length == 1.0


def test_rectangular_surface_gives_both_sides():
    ds = _surface().isel(y=slice(0, 6))
    ds.attrs = {"length_x": 1.0, "length_y": 0.5, "nx": 8, "ny": 6}
    heights, length = surface_heights(ds, "s.nc")
    assert heights.shape == (8, 6) and length == (1.0, 0.5)


@pytest.mark.parametrize(
    "spoil, words",
    [
        (lambda ds: ds.isel(y=slice(0, 6)), "is 8 x 6 but the file gives one side 'length'; a rectangular cell "
                                            "needs the attributes 'length_x' and 'length_y'"),
        (lambda ds: ds.isel(y=0), "must be a 2-D field over (x, y)"),
        (lambda ds: ds.assign_attrs(length_x=1.0, length_y=0.0), "'length_y' must be a finite number > 0, got 0.0"),
        (lambda ds: ds.isel(x=slice(0, 2), y=slice(0, 2)), "at least 4 x 4"),
        (lambda ds: ds.assign(heights=ds.heights.where(ds.x > 0)), "holds 8 NaN or infinite value(s)"),
        (lambda ds: ds.drop_vars("heights"), "lacks the variable 'heights'"),
        (lambda ds: ds.drop_attrs(deep=False), "global attribute 'length' (side of the cell) is missing"),
        (lambda ds: ds.assign_attrs(length="wide"), "is missing or not a number: 'wide'"),
        (lambda ds: ds.assign_attrs(length=-1.0), "must be a finite number > 0, got -1.0"),
        (lambda ds: ds.assign(heights=ds.heights.astype(str)), "'heights' must hold real numbers, got the type <U"),
    ],
)
# on 8 x 8 points the sample is every row: surface_grid sees every fault surface_heights sees
@pytest.mark.parametrize("check", [surface_heights, surface_grid])
def test_bad_surface_file_is_named(spoil, words, check):
    with pytest.raises(ValueError) as info:
        check(spoil(_surface()), "results/x/surfaces/s.nc")
    assert str(info.value).startswith("results/x/surfaces/s.nc: ") and words in str(info.value), str(info.value)


def test_the_sample_is_spread_rows_and_gives_the_grid():
    ds = _surface(64)
    assert surface_grid(ds, "s.nc") == ((64, 64), 1.0)
    # rows 0, 9, 18, 27, 36, 45, 54, 63: a NaN in row 40 is left to the ranks that read it
    assert surface_grid(ds.assign(heights=ds.heights.where(ds.x != ds.x[40])), "s.nc") == ((64, 64), 1.0)
    with pytest.raises(ValueError, match=r"^s.nc: 'heights' holds 64 NaN or infinite value\(s\) in the 8 rows "
                                         r"checked \(x = 0, 9, 18, 27, 36, 45, 54, 63\); every height must be finite$"):
        surface_grid(ds.assign(heights=ds.heights.where(ds.x != ds.x[45])), "s.nc")
    assert surface_grid(ds, "s.nc", sample_rows=100) == ((64, 64), 1.0)  # at most every row
