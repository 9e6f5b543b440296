"""Measured topography files (written by SurfaceTopography's own writers) read into square height arrays."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from SurfaceTopography import Topography

from compare_outputs import assert_heights_close
from roughcontact.surfaces.topography import (
    LENGTH_UNITS,
    MeasuredSurface,
    TopographyError,
    check_header,
    read_topography,
)

INFO_KEYS = {"file", "sha256", "reader", "channel", "file_unit", "unit_from", "physical_size_from", "original_shape",
             "original_physical_size", "n_undefined", "undefined", "detrend", "crop", "periodic"}


def _noise(shape, seed=0, scale=1.0):
    return scale * np.random.default_rng(seed).standard_normal(shape)


def _netcdf(tmp_path, heights, size, unit="um", name="t.nc", periodic=False):
    """Write ``heights`` (masked where undefined) of physical ``size`` in ``unit`` as a NetCDF file."""
    fn = tmp_path / name
    Topography(heights, size, unit=unit, periodic=periodic).to_netcdf(str(fn))
    return fn


def _fit_residual(h, degree):
    """``h`` (nx, ny) minus its least-squares polynomial of ``degree`` (1: plane, 2: quadric) in the grid indices."""
    i, j = np.meshgrid(np.arange(h.shape[0], dtype=float), np.arange(h.shape[1], dtype=float), indexing="ij")
    columns = [np.ones_like(i), i, j] + ([i * i, j * j, i * j] if degree == 2 else [])
    design = np.stack([c.ravel() for c in columns], axis=1)
    coeffs = np.linalg.lstsq(design, h.ravel(), rcond=None)[0]
    return h - (design @ coeffs).reshape(h.shape)


def test_x3p_in_metres_is_read_in_micrometres(tmp_path):
    h = _noise((16, 16), scale=1e-7)  # metres
    fn = tmp_path / "scan.x3p"
    Topography(h, (16e-6, 16e-6), unit="m").to_x3p(str(fn))
    surface = read_topography(fn, unit="um")
    assert isinstance(surface, MeasuredSurface) and surface.unit == "um"
    assert surface.heights.dtype == np.float64 and surface.heights.flags.c_contiguous
    np.testing.assert_allclose(surface.heights, h * 1e6, rtol=1e-12)
    assert surface.length == pytest.approx(16.0, rel=1e-12)
    info = surface.info
    assert info["reader"] == "X3PReader" and info["file_unit"] == "m" and info["crop"] is None
    assert info["unit_from"] == "file" and info["physical_size_from"] == "file" and info["ignored"] == []
    assert info["original_shape"] == [16, 16] and info["original_physical_size"] == pytest.approx([16.0, 16.0])


def test_file_metadata_wins_over_the_scene(tmp_path):
    fn = tmp_path / "scan.x3p"
    Topography(_noise((8, 8), scale=1e-7), (8e-6, 8e-6), unit="m").to_x3p(str(fn))
    surface = read_topography(fn, unit="nm", file_unit="mm", physical_size=(1.0, 1.0))
    assert surface.length == pytest.approx(8000.0, rel=1e-12)
    assert surface.info["ignored"] == ["file_unit", "physical_size"] and surface.info["unit_from"] == "file"


def test_info_is_json_with_the_file_hash(tmp_path):
    fn = _netcdf(tmp_path, _noise((8, 8)), (4.0, 4.0), unit="nm", periodic=True)
    info = read_topography(str(fn), unit="um").info
    assert INFO_KEYS <= set(info)
    assert info["sha256"] == hashlib.sha256(fn.read_bytes()).hexdigest()
    assert info["file"] == str(fn) and info["reader"] == "NCReader" and info["periodic"] is True
    assert json.loads(json.dumps(info)) == info


# Isolated interior points, so that the harmonic fill is the mean of the four neighbours.
HOLES = ((3, 4), (5, 8), (8, 2))


@pytest.fixture
def holey(tmp_path):
    h = _noise((12, 12), seed=1)
    mask = np.zeros(h.shape, dtype=bool)
    mask[tuple(np.array(HOLES).T)] = True
    return _netcdf(tmp_path, np.ma.masked_array(h, mask=mask), (12.0, 12.0)), h, mask


def test_undefined_points_are_rejected_by_default(holey):
    fn, _, _ = holey
    with pytest.raises(TopographyError) as err:
        read_topography(fn, unit="um")
    msg = str(err.value)
    assert msg.startswith(f"{fn}: ") and "3 of 144 points" in msg and "topography.undefined" in msg, msg


def test_undefined_points_filled_with_the_mean(holey):
    fn, h, mask = holey
    surface = read_topography(fn, unit="um", undefined="mean")
    np.testing.assert_array_equal(surface.heights[~mask], h[~mask])
    np.testing.assert_allclose(surface.heights[mask], h[~mask].mean(), rtol=1e-12)
    assert surface.info["n_undefined"] == 3 and surface.info["undefined"] == "mean"


def test_undefined_points_filled_harmonically(holey):
    fn, h, mask = holey
    heights = read_topography(fn, unit="um", undefined="harmonic").heights
    assert np.isfinite(heights).all()
    np.testing.assert_array_equal(heights[~mask], h[~mask])
    for i, j in HOLES:
        neighbours = h[[i - 1, i + 1, i, i], [j, j, j - 1, j + 1]]
        assert neighbours.min() <= heights[i, j] <= neighbours.max()
        assert heights[i, j] == pytest.approx(neighbours.mean(), rel=1e-12)


def test_mean_fill_after_detrend_lies_on_the_trend(tmp_path):
    # Detrending first fits the plane to measured points only; the hole is then filled on the plane (0),
    # not with the tilted scan's global mean.
    i, j = np.meshgrid(np.arange(16.0), np.arange(16.0), indexing="ij")
    h = np.ma.masked_array(5.0 + 2.0 * i - 0.5 * j, mask=(i == 12) & (j == 3))
    surface = read_topography(_netcdf(tmp_path, h, (16.0, 16.0)), unit="um", undefined="mean", detrend="height")
    np.testing.assert_allclose(surface.heights, 0.0, atol=1e-10)


@pytest.mark.parametrize("shape, crop", [((48, 32), [8, 0, 32]), ((32, 48), [0, 8, 32]), ((33, 30), [1, 0, 30])])
def test_non_square_map_kept_cropped_or_rejected(tmp_path, shape, crop):
    h = _noise(shape, seed=2)
    fn = _netcdf(tmp_path, h, (shape[0] * 0.5, shape[1] * 0.5))
    whole = read_topography(fn, unit="um")  # the default: the whole map, sides (Lx, Ly)
    np.testing.assert_array_equal(whole.heights, h)
    assert not whole.square and whole.lengths == pytest.approx((shape[0] * 0.5, shape[1] * 0.5), rel=1e-12)
    assert whole.length == whole.lengths and whole.info["crop"] is None
    with pytest.raises(TopographyError) as err:
        read_topography(fn, unit="um", non_square="reject")
    msg = str(err.value)
    assert msg.startswith(f"{fn}: ") and f"{shape[0]} x {shape[1]}" in msg and "set it to keep" in msg
    surface = read_topography(fn, unit="um", non_square="crop")
    i0, j0, n = crop
    np.testing.assert_array_equal(surface.heights, h[i0:i0 + n, j0:j0 + n])
    assert surface.heights.flags.c_contiguous and surface.length == pytest.approx(n * 0.5, rel=1e-12)
    assert surface.info["crop"] == crop and surface.info["original_shape"] == list(shape)


def test_file_without_unit_or_size_needs_the_scene(tmp_path):
    h = _noise((10, 10), seed=3)
    fn = tmp_path / "raw.npy"
    np.save(fn, h)
    with pytest.raises(TopographyError, match="no length unit; give topography.file_unit") as err:
        read_topography(fn, unit="um", physical_size=(200.0, 200.0))
    assert str(err.value).startswith(f"{fn}: ")
    with pytest.raises(TopographyError, match="no physical size; give topography.physical_size"):
        read_topography(fn, unit="um", file_unit="nm")
    surface = read_topography(fn, unit="um", file_unit="nm", physical_size=(200.0, 200.0))
    np.testing.assert_allclose(surface.heights, h * 1e-3, rtol=1e-12)
    assert surface.length == pytest.approx(0.2, rel=1e-12)
    assert surface.info["unit_from"] == "scene" and surface.info["physical_size_from"] == "scene"
    assert surface.info["reader"] == "NPYReader" and surface.info["file_unit"] == "nm"


def test_non_square_pixels_are_kept(tmp_path):
    h = _noise((16, 16))
    surface = read_topography(_netcdf(tmp_path, h, (16.0, 8.0)), unit="um")
    np.testing.assert_array_equal(surface.heights, h)
    assert not surface.square and surface.length == (16.0, 8.0)  # dx = 1 um, dy = 0.5 um
    # Within the tolerance |dx/dy - 1| <= 1e-6 the pixels count as square: one side, as for a generated surface.
    almost = read_topography(_netcdf(tmp_path, h, (16.0, 16.0 * (1 + 1e-7)), name="almost.nc"), unit="um")
    assert almost.square and almost.length == 16.0


def test_detrend_modes(tmp_path):
    i, j = np.meshgrid(np.arange(16.0), np.arange(16.0), indexing="ij")
    noise = _noise((16, 16), seed=4, scale=0.01)
    plane = 3.0 + 0.2 * i - 0.7 * j
    quadric = plane + 0.05 * i * i - 0.02 * j * j + 0.03 * i * j
    fn_plane = _netcdf(tmp_path, plane + noise, (8.0, 8.0), name="plane.nc")
    fn_quadric = _netcdf(tmp_path, quadric + noise, (8.0, 8.0), name="quadric.nc")

    def read(fn, mode):
        return read_topography(fn, unit="um", detrend=mode).heights

    np.testing.assert_array_equal(read(fn_plane, "none"), plane + noise)
    np.testing.assert_allclose(read(fn_plane, "center"), plane + noise - (plane + noise).mean(), atol=1e-12)
    np.testing.assert_allclose(read(fn_plane, "height"), _fit_residual(noise, 1), atol=1e-10)
    np.testing.assert_allclose(read(fn_quadric, "curvature"), _fit_residual(noise, 2), atol=1e-10)


def test_channel_selection(tmp_path):
    fn = tmp_path / "two.npz"
    first, second = _noise((8, 8), seed=5), _noise((8, 8), seed=6)
    np.savez(fn, height=first, retrace=second)
    kw = dict(unit="um", file_unit="um", physical_size=(8.0, 8.0))
    surface = read_topography(fn, channel=1, **kw)
    np.testing.assert_array_equal(surface.heights, second)
    assert surface.info["channel"] == "retrace"
    with pytest.raises(TopographyError, match=r"channel 2 is out of range.*0: 'height', 1: 'retrace'"):
        read_topography(fn, channel=2, **kw)


def _gzip(tmp_path, inner):
    import gzip

    fn = tmp_path / (inner.name + ".gz")
    fn.write_bytes(gzip.compress(inner.read_bytes()))
    return fn


def _zip(tmp_path, inner, container):
    import zipfile

    fn = tmp_path / ("container.zip" if container else "plain.zip")
    with zipfile.ZipFile(fn, "w") as archive:
        archive.write(inner, inner.name)
        if container:  # SurfaceTopography's container: a meta.yml and the data files
            archive.writestr("meta.yml", "surfaces: []\n")
            archive.writestr("LICENSE-ccby-4.0.txt", "licence")
    return fn


@pytest.mark.parametrize("pack, message", [
    (_gzip, r"the file is gzip-compressed; decompress it \(gunzip\) and name the decompressed file$"),
    (lambda tmp, inner: _zip(tmp, inner, True), r"a SurfaceTopography container \(meta\.yml\) of several "
                                                r"measurements, not one topography file; unzip it and name the data "
                                                r"file you want in topography\.files \(its files: t\.nc\)$"),
    (lambda tmp, inner: _zip(tmp, inner, False), r"a zip archive, not one topography file; unzip it .*\(its files: "
                                                 r"t\.nc\)$"),
])
def test_compressed_files_and_archives_say_what_to_do(tmp_path, pack, message):
    """SurfaceTopography's examples matrix-4.txt.gz and container-2.zip: no reader takes them, and the message
    said only "unknown or unsupported format, or a damaged file"."""
    inner = _netcdf(tmp_path, _noise((8, 8)), (8.0, 8.0))
    assert read_topography(inner, unit="um").heights.shape == (8, 8)
    fn = pack(tmp_path, inner)
    for read in (read_topography, check_header):
        with pytest.raises(TopographyError, match=message) as err:
            read(fn, unit="um")
        assert str(err.value).startswith(f"{fn}: ")


@pytest.mark.parametrize("content", [{}, {"note": "no heights here"}])
def test_file_without_channels_rejected(tmp_path, content):
    """A file some reader accepts but that holds no data channel: named, with the reader and the remedy.

    SurfaceTopography's example nms-2.nms is read as MATLAB data with no channel; once the message
    ended in an empty list ("the file's channels are ").
    """
    import scipy.io

    fn = tmp_path / "empty.mat"
    scipy.io.savemat(fn, content)
    with pytest.raises(TopographyError, match=r"reads it as 'mat' data \(MatReader\) but finds no data "
                                              r"channel in it.*topography\.format$") as err:
        read_topography(fn, unit="um", file_unit="um", physical_size=(1.0, 1.0))
    assert str(err.value).startswith(f"{fn}: ")


def test_line_scan_is_read_as_a_profile(tmp_path):
    """A 1-D array is a uniform line scan (issue 49): read as a profile, its size one length [L]."""
    fn = tmp_path / "line.npy"
    np.save(fn, _noise(32))
    surface = read_topography(fn, unit="um", file_unit="um", physical_size=(2.0,))
    assert surface.heights.shape == (32,) and surface.lengths == (2.0,) and surface.length == 2.0
    assert surface.dimension == 1 and surface.info["line_scan"] == "uniform" and "resampled" not in surface.info
    with pytest.raises(TopographyError, match=r"physical_size \[1.0, 1.0\] has 2 value\(s\), but channel .* is a "
                                              r"line scan: give \[L\], its length") as err:
        read_topography(fn, unit="um", file_unit="um", physical_size=(1.0, 1.0))
    assert str(err.value).startswith(f"{fn}: ")


def test_unknown_and_missing_files(tmp_path):
    junk = tmp_path / "junk.dat"
    junk.write_bytes(np.random.default_rng(7).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    with pytest.raises(TopographyError, match="not a topography file SurfaceTopography can read") as err:
        read_topography(junk, unit="um")
    assert str(err.value).startswith(f"{junk}: ") and "x3p" in str(err.value)
    missing = tmp_path / "nowhere.x3p"
    with pytest.raises(TopographyError, match="does not exist") as err:
        read_topography(missing, unit="um")
    assert str(err.value).startswith(f"{missing}: ")


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(unit="cm"), "topography.unit 'cm' is not allowed; use one of m, mm, um, nm"),
        (dict(unit="µm"), "topography.unit 'µm' is not allowed"),
        (dict(file_unit="inch"), "topography.file_unit 'inch' is not allowed"),
        (dict(undefined="zero"), "topography.undefined 'zero' is not allowed; use one of reject, mean, harmonic"),
        (dict(detrend="plane"), "use one of none, center, height, curvature"),
        (dict(non_square="pad"), "topography.non_square 'pad' is not allowed; use one of keep, crop, reject"),
        (dict(physical_size=(1.0, -1.0)), "topography.physical_size (1.0, -1.0) is not allowed"),
        (dict(physical_size=(1.0, 2.0, 3.0)), "use two finite numbers > 0"),
        (dict(channel=-1), "topography.channel -1 is not allowed"),
    ],
)
def test_bad_arguments_are_named(tmp_path, kwargs, words):
    fn = _netcdf(tmp_path, _noise((4, 4)), (1.0, 1.0))
    with pytest.raises(TopographyError) as err:
        read_topography(fn, **{"unit": "um", **kwargs})
    assert str(err.value).startswith(f"{fn}: ") and words in str(err.value), str(err.value)
    assert isinstance(err.value, ValueError) and LENGTH_UNITS == ("m", "mm", "um", "nm")


def test_shipped_example_files_hold_what_the_examples_module_writes(tmp_path):
    """data/measured/ (the `measured` scene's inputs) equals a fresh `python -m roughcontact.pipeline.examples`.

    The shipped files were generated on another machine: heights agree to FFT rounding
    (tests/compare_outputs.py), sizes and undefined points exactly.
    """
    from roughcontact.pipeline.examples import write_examples

    repo = Path(__file__).resolve().parents[1] / "data" / "measured"
    fresh = write_examples(tmp_path)
    settings = {"ground-a": {}, "ground-b": {"undefined": "harmonic"},
                "ground-c": {"file_unit": "nm", "physical_size": (100000.0, 125000.0), "non_square": "crop"}}
    for name, path in fresh.items():
        a = read_topography(repo / path.name, unit="um", **settings[name])
        b = read_topography(path, unit="um", **settings[name])
        assert_heights_close(b.heights, a.heights, what=str(repo / path.name))
        assert a.length == b.length and a.info["n_undefined"] == b.info["n_undefined"]


def test_mostly_undefined_maps_are_refused_and_the_fraction_recorded(tmp_path):
    # A map 60 % undefined would be mostly the fill's invention: refused above topography.max_undefined
    # (default 0.5), naming the file, the fraction and the remedy; accepted when the scene allows it,
    # with the fraction in the provenance and in the surface file.
    from roughcontact.pipeline.datasets import measured_surface_dataset

    h = _noise((20, 20), seed=4)
    mask = np.zeros(h.shape, dtype=bool)
    mask[:12] = True  # 240 of 400 points
    fn = _netcdf(tmp_path, np.ma.masked_array(h, mask=mask), (20.0, 20.0))
    with pytest.raises(TopographyError) as err:
        read_topography(fn, unit="um", undefined="mean")
    msg = str(err.value)
    assert msg.startswith(f"{fn}: 240 of 400 points (60.0%) are undefined") and "topography.max_undefined = 0.5" in msg
    surface = read_topography(fn, unit="um", undefined="mean", max_undefined=0.7)
    assert surface.info["undefined_fraction"] == 0.6
    assert float(measured_surface_dataset(surface, name="m")["undefined_fraction"].squeeze()) == 0.6
    with pytest.raises(TopographyError, match=r"topography.max_undefined 1.5 is not allowed; use a number in \[0, 1\]"):
        read_topography(fn, unit="um", max_undefined=1.5)


@pytest.mark.parametrize("name", ["a.x3p", "a.txt", "a.bin"])
def test_random_bytes_are_not_a_height_map(tmp_path, name):
    # SurfaceTopography's HGT reader takes any file whose size is a square number of 16-bit values:
    # 5000 random bytes were once read as a 50 x 50 map with rms slope 19 140 and solved. A format
    # found by size alone must agree with the extension, unless the scene names the format.
    fn = tmp_path / name
    fn.write_bytes(np.random.default_rng(0).bytes(5000))
    with pytest.raises(TopographyError) as err:
        read_topography(fn, unit="um", file_unit="nm", physical_size=(1.0, 1.0))
    msg = str(err.value)
    assert msg.startswith(f"{fn}: SurfaceTopography reads it only as 'hgt' data") and "topography.format" in msg
    named = read_topography(fn, unit="um", file_unit="nm", physical_size=(1.0, 1.0), format="hgt")
    assert named.heights.shape == (50, 50)
    with pytest.raises(TopographyError, match="topography.format 'x3' is not allowed; use one of al3d"):
        read_topography(fn, unit="um", format="x3")


def test_empty_tiny_and_flat_maps_are_named(tmp_path):
    empty = tmp_path / "e.x3p"
    empty.write_bytes(b"")
    with pytest.raises(TopographyError, match=r"e.x3p: the file is empty \(0 bytes\)"):
        read_topography(empty, unit="um")
    tiny = _netcdf(tmp_path, _noise((3, 7)), (3.0, 7.0), name="tiny.nc")
    with pytest.raises(TopographyError, match=r"tiny.nc: the map is 3 x 7 points; the contact solver needs at least"):
        read_topography(tiny, unit="um")
    flat = _netcdf(tmp_path, np.full((8, 8), 2.5), (8.0, 8.0), name="flat.nc")
    with pytest.raises(TopographyError, match=r"flat.nc: the map is flat \(every height equal after detrend 'none'\)"):
        read_topography(flat, unit="um")
