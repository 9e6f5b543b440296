"""Theory for profiles (issue 49): Persson's 1-D law, the exact full-contact pressure of a periodic profile."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import erf

from roughcontact.surfaces.synthetic import generate_profile, profile_spectral_moments
from roughcontact.theory.profiles import (
    KAPPA_PERSSON_PROFILE,
    NOT_FOR_PROFILES,
    full_contact_load_profile,
    full_contact_pressure_profile,
    persson_area_profile,
)


def test_persson_profile_is_erf_of_p0_over_sqrt2_sigma():
    """sigma_p = (E*/2) h' with h' the profile slope; small-load slope sqrt(8/pi)."""
    e_star, slope = 2.5, 0.07
    p0 = np.array([0.0, 1e-6, 0.01, 0.1])
    sigma = 0.5 * e_star * slope
    np.testing.assert_allclose(persson_area_profile(p0, rms_slope=slope, e_star=e_star),
                               erf(p0 / (math.sqrt(2) * sigma)), rtol=1e-15)
    small = persson_area_profile(1e-9, rms_slope=slope, e_star=e_star) / (1e-9 / (e_star * slope))
    assert small == pytest.approx(KAPPA_PERSSON_PROFILE, rel=1e-9)
    with pytest.raises(ValueError, match="rms_slope must be a finite number > 0"):
        persson_area_profile(0.1, rms_slope=0.0, e_star=1.0)


def test_full_contact_pressure_of_a_sine_is_westergaards():
    """h = a cos(q x): p = p0 + (E*/2) a q cos(q x) (Westergaard; Johnson 1985, section 13.2), so the last
    point touches at p0 = E* a q / 2 = pi E* a / lambda."""
    n, length, a, k, e_star = 256, 3.0, 0.02, 4, 2.0
    x = np.arange(n) * length / n
    q = 2 * math.pi * k / length
    p = full_contact_pressure_profile(a * np.cos(q * x), 0.5, e_star, length)
    np.testing.assert_allclose(p, 0.5 + 0.5 * e_star * a * q * np.cos(q * x), atol=1e-13)
    assert full_contact_load_profile(a * np.cos(q * x), e_star, length) == pytest.approx(0.5 * e_star * a * q)


def test_full_contact_pressure_variance_is_e_star_h_prime_over_2():
    """The Hilbert transform keeps the variance: std(p) = (E*/2) h' exactly, for a rough profile too."""
    h = generate_profile(2048, 2, 128, 0.6, 1, rms_slope=0.2, length=2.0)
    slope = profile_spectral_moments(h, 2.0)["rms_slope"]
    p = full_contact_pressure_profile(h, 1.0, 3.0, 2.0)
    assert np.std(p) == pytest.approx(0.5 * 3.0 * slope, rel=1e-12) and np.mean(p) == pytest.approx(1.0)


def test_the_2d_laws_are_named_as_not_for_profiles():
    assert set(NOT_FOR_PROFILES) == {"cel", "bgt", "greenwood", "perimeter_correction"}
