"""Profiles (issue 49): the 1-D self-affine generator, profile statistics, and line scans read from files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from roughcontact.surfaces.linescan import MIN_PROFILE_POINTS, RESAMPLING, uniform_profile
from roughcontact.surfaces.synthetic import (
    generate_profile,
    nonperiodic_moments,
    profile_moments,
    profile_psd_filter,
    profile_spectral_moments,
)
from roughcontact.surfaces.topography import TopographyError, check_header, read_topography

DATA = Path(__file__).parent / "data" / "linescans"


def _xy(tmp_path, x, z, name="scan.txt"):
    """A two-column text line scan (x, z), read by SurfaceTopography's XYZ reader (no unit: give file_unit)."""
    fn = tmp_path / name
    np.savetxt(fn, np.c_[x, z])
    return fn


# --- the generator -------------------------------------------------------------------------------------------

def test_profile_psd_slope_band_and_normalisation():
    """C(q) ~ q^(-1-2H) inside [k_l, k_s] (slope fitted on the seed-averaged periodogram), nothing outside,
    and the rms slope exactly the one asked for."""
    n, k_l, k_s, hurst = 4096, 4, 256, 0.7
    power = np.zeros(n // 2 + 1)
    for seed in range(40):
        h = generate_profile(n, k_l, k_s, hurst, seed, rms_slope=0.1)
        assert profile_spectral_moments(h)["rms_slope"] == pytest.approx(0.1, rel=1e-12)
        power += np.abs(np.fft.rfft(h)) ** 2
    k = np.arange(n // 2 + 1)
    band = (k >= k_l) & (k <= k_s)
    assert np.all(power[~band] < 1e-20 * power[band].max())
    slope = np.polyfit(np.log(k[band]), np.log(power[band]), 1)[0]
    assert slope == pytest.approx(-1 - 2 * hurst, abs=0.05)


def test_profile_is_deterministic_and_one_continuous_profile_at_any_n():
    a = generate_profile(512, 2, 32, 0.5, 3, rms_height=1.0)
    assert np.array_equal(a, generate_profile(512, 2, 32, 0.5, 3, rms_height=1.0))
    assert not np.allclose(a, generate_profile(512, 2, 32, 0.5, 4, rms_height=1.0))
    fine = generate_profile(1024, 2, 32, 0.5, 3, rms_height=1.0)
    np.testing.assert_allclose(fine[::2], a, atol=1e-12)
    assert np.std(a) == pytest.approx(1.0, rel=1e-12) and abs(a.mean()) < 1e-12


def test_profile_filter_plateau_and_bad_arguments():
    amp = profile_psd_filter(64, 4, 16, 0.5, plateau=True)
    assert amp[0] == 0 and np.all(amp[1:4] == amp[4]) and np.all(amp[17:] == 0)
    with pytest.raises(ValueError, match=r"k_s must be <= n/2 = 32.0"):
        generate_profile(64, 4, 40, 0.5, 0, rms_slope=0.1)
    with pytest.raises(ValueError, match="exactly one of rms_slope or rms_height"):
        generate_profile(64, 4, 16, 0.5, 0)


def test_profile_moments_against_a_sine():
    """A sine of amplitude a and wavenumber q: m0 = a^2/2, m2 = (a q)^2/2, m4 = (a q^2)^2/2; alpha = 1."""
    n, length, a, k = 1024, 2.0, 0.3, 5
    x = np.arange(n) * length / n
    q = 2 * np.pi * k / length
    h = a * np.sin(q * x)
    spec = profile_spectral_moments(h, length)
    assert spec["m0"] == pytest.approx(a**2 / 2) and spec["m2"] == pytest.approx((a * q) ** 2 / 2)
    assert spec["m4"] == pytest.approx((a * q**2) ** 2 / 2) and spec["alpha"] == pytest.approx(1.0)
    assert spec["rms_slope"] == pytest.approx(a * q / np.sqrt(2))
    diff = profile_moments(h, length)
    assert diff["rms_slope"] == pytest.approx(spec["rms_slope"], rel=1e-3)  # differences: O((q dx)^2) low
    assert nonperiodic_moments(h, length) == diff


# --- line scans read from files --------------------------------------------------------------------------------

def test_nonuniform_scan_is_resampled_and_recorded():
    """SurfaceTopography's nonuniform.asc (134 points, spacings 1.2 to 19.7): n points at the mean spacing,
    every height between two measured ones, the method recorded."""
    path = DATA / "nonuniform.asc"
    surface = read_topography(path, unit="um", file_unit="um")
    raw = np.loadtxt(path)
    x, z = raw[:, 0] - raw[0, 0], raw[:, 1]
    dx = (x[-1] - x[0]) / (x.size - 1)
    assert surface.heights.shape == (134,) and surface.lengths[0] == pytest.approx(134 * dx, rel=1e-12)
    record = surface.info["resampled"]
    assert record["method"] == RESAMPLING and record["original_points"] == 134
    assert record["spacing"] == pytest.approx(dx, rel=1e-12)
    assert record["original_spacing_min"] == pytest.approx(1.1586, rel=1e-4)
    assert surface.info["line_scan"] == "nonuniform"
    assert surface.heights[0] == z[0] and surface.heights[-1] == pytest.approx(z[-1], rel=1e-12)
    np.testing.assert_allclose(surface.heights, np.interp(np.arange(134) * dx, x, z), rtol=1e-12)
    json.dumps(surface.info)
    assert check_header(path, unit="um", file_unit="um") == ((134,), (pytest.approx(dx, rel=1e-12),))


def test_uniform_profile_keeps_the_point_count_and_the_ends():
    x = np.array([0.0, 0.1, 0.3, 0.4, 0.6, 0.7, 0.9, 1.0])
    info = {}
    h, length = uniform_profile(x, x**2, info)
    assert h.size == 8 and length == pytest.approx(8 / 7) and h[0] == 0 and h[-1] == 1
    assert np.all(np.diff(h) > 0) and info["resampled"]["original_spacing_median"] == pytest.approx(0.1)


def test_too_short_scan_refused_at_the_header():
    path = DATA / "csv-2.csv"
    for check in (check_header, read_topography):
        with pytest.raises(TopographyError, match=rf"the line scan has 8 points; a profile needs at least "
                                                  rf"{MIN_PROFILE_POINTS}.*measure a longer or denser scan") as err:
            check(path, unit="um", file_unit="um")
        assert str(err.value).startswith(f"{path}: ")


def test_non_monotonic_positions_refused(tmp_path):
    x = np.arange(20.0)
    x[7] = 5.5
    fn = _xy(tmp_path, x, np.sin(x))
    with pytest.raises(TopographyError, match=r"positions do not increase strictly: x\[6\] = 6 is followed by "
                                              r"x\[7\] = 5.5; .* sort the points by x and remove repeated") as err:
        read_topography(fn, unit="um", file_unit="um")
    assert str(err.value).startswith(f"{fn}: ")
    x[7] = 6.0  # a repeated position: two heights at one x
    with pytest.raises(TopographyError, match=r"x\[6\] = 6 is followed by x\[7\] = 6"):
        read_topography(_xy(tmp_path, x, np.sin(x), "repeat.txt"), unit="um", file_unit="um")


def test_nan_heights_follow_the_maps_undefined_policy(tmp_path):
    """NaN heights are undefined points: rejected by default, filled with the mean or linearly (harmonic in 1-D)."""
    x = np.arange(24.0)
    z = np.sin(x)
    z[[5, 6]] = np.nan
    fn = _xy(tmp_path, x, z)
    with pytest.raises(TopographyError, match=r"2 of 24 points \(8.333%\) are undefined \(not measured, or NaN\); "
                                              r"set topography.undefined to mean or harmonic") as err:
        read_topography(fn, unit="um", file_unit="um")
    assert str(err.value).startswith(f"{fn}: ")
    mean = read_topography(fn, unit="um", file_unit="um", undefined="mean")
    assert mean.heights[5] == mean.heights[6] == pytest.approx(np.nanmean(z))
    harmonic = read_topography(fn, unit="um", file_unit="um", undefined="harmonic")
    np.testing.assert_allclose(harmonic.heights[5:7], z[4] + (z[7] - z[4]) * np.array([1, 2]) / 3)
    assert harmonic.info["n_undefined"] == 2 and np.all(np.isfinite(harmonic.heights))
    with pytest.raises(TopographyError, match="more than topography.max_undefined = 0.05"):
        read_topography(fn, unit="um", file_unit="um", undefined="mean", max_undefined=0.05)


def test_detrend_on_a_profile(tmp_path):
    x = np.linspace(0.0, 10.0, 40)
    rough = 0.01 * np.sin(7 * x)
    fn = _xy(tmp_path, x, 3.0 + 0.5 * x + 0.2 * x**2 + rough)
    flat = read_topography(fn, unit="um", file_unit="um", detrend="curvature")
    assert np.ptp(flat.heights - (rough - np.polyval(np.polyfit(x, rough, 2), x))) < 1e-9
    line = read_topography(fn, unit="um", file_unit="um", detrend="height")
    assert abs(np.polyfit(x, line.heights, 1)[0]) < 1e-9
    with pytest.raises(TopographyError, match=r"the profile is flat .* no roughness"):
        read_topography(_xy(tmp_path, x, np.full(x.size, 2.5), "level.txt"), unit="um", file_unit="um")
