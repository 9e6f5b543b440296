"""NetCDF at the edges: labels enforced, atomic and deterministic writes, bad files named."""
import os

import numpy as np
import pytest
import xarray as xr

from roughcontact import generate_surface
from roughcontact.datasets import surface_dataset
from roughcontact.io import InputFileError, config_hash, read_dataset, write_dataset

PARAMS = {"surface": {"N": 16}, "seeds": 1}


def _surface_ds():
    h = generate_surface(16, 1, 4, 0.5, 0, rms_slope=0.1)
    return surface_dataset(h, k_l="1", k_s="4", hurst="0.5", seed=0, length=1.0, normalisation={"rms_slope": 0.1})


def _write(path):
    return write_dataset(_surface_ds(), path, stage="surface", scene="t", scene_parameters=PARAMS)


def test_roundtrip_and_provenance(tmp_path):
    p = _write(tmp_path / "s.nc")
    ds = read_dataset(p, stage="surface", variables=["heights"])
    assert ds.attrs["config_hash"] == config_hash(PARAMS)
    assert ds.attrs["roughcontact_stage"] == "surface" and ds.attrs["scene"] == "t"
    assert '"N":16' in ds.attrs["scene_parameters"]
    assert ds.heights.shape == (1, 1, 1, 1, 16, 16)


def test_byte_identical_rewrites(tmp_path):
    a, b = _write(tmp_path / "a.nc"), _write(tmp_path / "b.nc")
    assert a.read_bytes() == b.read_bytes()


def test_unlabelled_or_nan_variables_refused(tmp_path):
    ds = _surface_ds()
    ds["extra"] = xr.DataArray(1.0)
    with pytest.raises(ValueError, match="extra"):
        write_dataset(ds, tmp_path / "x.nc", stage="surface", scene="t", scene_parameters=PARAMS)
    ds = _surface_ds()
    ds["rms_slope"] = ds["rms_slope"] * np.nan
    with pytest.raises(ValueError, match="NaN"):
        write_dataset(ds, tmp_path / "x.nc", stage="surface", scene="t", scene_parameters=PARAMS)
    assert not list(tmp_path.iterdir()), "a refused write leaves nothing behind"


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", boom)
    with pytest.raises(OSError):
        _write(tmp_path / "s.nc")
    assert not list(tmp_path.iterdir())


def test_truncated_file_named(tmp_path):
    p = _write(tmp_path / "s.nc")
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 3])
    with pytest.raises(InputFileError, match=r"s\.nc: not a readable NetCDF"):
        read_dataset(p, stage="surface")


def test_foreign_and_wrong_stage_files_named(tmp_path):
    foreign = tmp_path / "f.nc"
    xr.Dataset({"a": ("x", [1.0, 2.0])}).to_netcdf(foreign)
    with pytest.raises(InputFileError, match=r"f\.nc: not written by roughcontact"):
        read_dataset(foreign, stage="surface")
    p = _write(tmp_path / "s.nc")
    with pytest.raises(InputFileError, match="holds stage 'surface', expected 'contact'"):
        read_dataset(p, stage="contact")
    with pytest.raises(InputFileError, match="lacks required variable"):
        read_dataset(p, stage="surface", variables=["pressure"])
    with pytest.raises(InputFileError, match="does not exist"):
        read_dataset(tmp_path / "none.nc", stage="surface")
    text = tmp_path / "t.nc"
    text.write_text("hello")
    with pytest.raises(InputFileError, match="not a readable NetCDF"):
        read_dataset(text, stage="surface")
    assert os.path.exists(p)
