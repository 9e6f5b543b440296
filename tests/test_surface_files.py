"""A surface file with bad heights or attributes is named, never a raw KeyError or a NaN solve."""
import numpy as np
import pytest

from roughcontact.pipeline.datasets import surface_dataset, surface_heights


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
    ],
)
def test_bad_surface_file_is_named(spoil, words):
    with pytest.raises(ValueError) as info:
        surface_heights(spoil(_surface()), "results/x/surfaces/s.nc")
    assert str(info.value).startswith("results/x/surfaces/s.nc: ") and words in str(info.value), str(info.value)
