"""Persson's theory beyond the area (roughcontact.theory.persson): the pressure distribution, the
generator's mode spectrum, the mean gap of Yang & Persson (2008) and the contact stiffness."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import erf

from roughcontact.theory import (
    discrete_power_law_moments,
    mode_spectrum,
    persson_area,
    persson_j,
    persson_mean_gap,
    persson_pressure_distribution,
    persson_stiffness,
)
from roughcontact.theory.persson import mode_weights

#: A small spectrum of three modes [rad / length], [length^2].
Q3, C3 = np.array([3.0, 10.0, 25.0]), np.array([4e-4, 5e-5, 2e-6])


@pytest.fixture(scope="module")
def spectrum():
    return mode_spectrum(64, 2, 32, 0.7, rms_slope=0.2, length=2.0)


# ------------------------------------------------------------ pressure distribution
@pytest.mark.parametrize("p0", [1e-3, 0.02, 0.1, 0.5])
def test_pressure_distribution_integrates_to_persson_area(p0):
    h1, e_star = 0.3, 2.0
    scale = e_star * h1  # P's width: sqrt(2 G) = E* h' / 2
    total, _ = quad(lambda p: persson_pressure_distribution(p, p0, rms_slope=h1, e_star=e_star),
                    0.0, p0 + 20 * scale, epsabs=0, epsrel=1e-12, limit=200, points=[p0])
    assert total == pytest.approx(float(persson_area(p0, rms_slope=h1, e_star=e_star)), rel=1e-6)
    mean, _ = quad(lambda p: p * persson_pressure_distribution(p, p0, rms_slope=h1, e_star=e_star),
                   0.0, p0 + 20 * scale, epsabs=0, epsrel=1e-12, limit=200, points=[p0])
    assert mean == pytest.approx(p0, rel=1e-6)  # the absorbing wall at p = 0 keeps the load


def test_pressure_distribution_shape_and_zero():
    p = np.linspace(0.0, 1.0, 12).reshape(3, 4)
    out = persson_pressure_distribution(p, 0.2, rms_slope=0.5, e_star=1.0)
    assert out.shape == (3, 4) and out[0, 0] == 0.0 and np.all(out[p > 0] > 0)


# ------------------------------------------------------------------------ spectrum
def test_mode_spectrum_normalisation():
    n, kl, ks, hurst, length = 32, 2.0, 12.0, 0.6, 3.0
    q, c = mode_spectrum(n, kl, ks, hurst, rms_slope=0.15, length=length)
    assert np.sum(q * q * c) == pytest.approx(0.15**2, rel=1e-13)
    ref = discrete_power_law_moments(n, kl, ks, hurst, length=length, rms_slope=0.15)
    assert np.sum(c) == pytest.approx(ref["m0"], rel=1e-12)
    qh, ch = mode_spectrum(n, kl, ks, hurst, rms_height=0.01, length=length)
    assert np.sum(ch) == pytest.approx(1e-4, rel=1e-13)
    np.testing.assert_allclose(qh, q)
    np.testing.assert_allclose(ch / c, ch[0] / c[0], rtol=1e-12)


@pytest.mark.parametrize("n", [16, 17])
def test_mode_spectrum_covers_the_full_grid(n):
    """Every mode of the full n x n grid in the band, with c ~ |k|^(-2(1+H)) (odd n too)."""
    kl, ks, hurst = 1.5, n / 2, 0.8
    m = np.fft.fftfreq(n, 1.0 / n)
    k = np.hypot(m[:, None], m[None, :]).ravel()
    k = np.sort(k[(k >= kl) & (k <= ks)])
    q, c = mode_spectrum(n, kl, ks, hurst, rms_height=1.0)
    np.testing.assert_allclose(q, 2 * math.pi * k, rtol=1e-14)
    assert np.all(np.diff(q) >= 0)
    expected = k ** (-2 * (1 + hurst))
    np.testing.assert_allclose(c, expected / expected.sum(), rtol=1e-12)


# ---------------------------------------------------------------------- the J integral
@pytest.mark.parametrize("gamma", [0.0, 0.45, 1.0])
@pytest.mark.parametrize("s0", [1e-7, 3e-3, 0.05, 0.7, 2.0, 4.5, 6.5])
def test_j_against_quad(s0, gamma):
    def f(s):
        return (gamma + 3 * (1 - gamma) * erf(s) ** 2) * math.exp(-s * s) / s

    mid = max(s0, 1.0)
    ref = quad(f, s0, mid, epsabs=0, epsrel=1e-13, limit=200)[0] + quad(f, mid, mid + 30, epsabs=0, epsrel=1e-13)[0]
    assert float(persson_j(s0, gamma)) == pytest.approx(ref, rel=1e-6)


def test_j_small_argument_asymptote():
    """J(s0) = gamma ln(1/s0) + const + O(s0^2): the constant is reached below the table too."""
    s = np.array([1e-5, 1e-7, 1e-9, 1e-30])
    offset = persson_j(s, 0.45) - 0.45 * np.log(1 / s)
    np.testing.assert_allclose(offset, offset[-1], rtol=1e-9)


# --------------------------------------------------------------------- mean gap
def test_w_at_the_largest_q_gives_persson_area(spectrum):
    q, c = spectrum
    _, w = mode_weights(q, c)
    h1 = math.sqrt(np.sum(q * q * c))
    assert w[-1] == pytest.approx(math.sqrt(2) / h1, rel=1e-12)
    assert np.all(np.diff(w) < 0)


def test_mean_gap_against_direct_quadrature():
    """u = (1/(2 sqrt pi)) sum_k q_k c_k w_k int_p0^inf dp/p [gamma + 3(1-gamma) P^2] exp(-(w p/E*)^2)."""
    e_star, gamma = 2.0, 0.42
    w = [(0.5 * np.sum((Q3**2 * C3)[: i + 1])) ** -0.5 for i in range(3)]
    for p0 in (1e-4, 3e-3, 0.05):
        total = 0.0
        for qk, ck, wk in zip(Q3, C3, w, strict=True):
            def inner(p, wk=wk):
                s = wk * p / e_star
                return (gamma + 3 * (1 - gamma) * erf(s) ** 2) * math.exp(-s * s) / p

            top = 40 * e_star / wk
            pts = [x for x in (e_star / wk,) if p0 < x < top]
            total += qk * ck * wk * quad(inner, p0, top, epsabs=0, epsrel=1e-12, limit=400, points=pts)[0]
        ref = total / (2 * math.sqrt(math.pi))
        got = persson_mean_gap(p0, Q3[::-1], C3[::-1], e_star=e_star, gamma=gamma)  # any order of modes
        assert float(got) == pytest.approx(ref, rel=1e-6)


def test_modes_of_one_wavenumber_count_together():
    """Ties in q share one W (the sum over q_j <= q_k includes them all); splitting a mode changes nothing."""
    a, w = mode_weights([1.0, 2.0, 2.0], [1.0, 1.0, 1.0])
    np.testing.assert_allclose(w, [(0.5 * 1.0) ** -0.5, (0.5 * 9.0) ** -0.5], rtol=1e-15)
    np.testing.assert_allclose(a, [w[0], 4.0 * w[1]], rtol=1e-15)
    split_q, split_c = np.r_[Q3, Q3[1]], np.r_[C3[0], 0.3 * C3[1], C3[2], 0.7 * C3[1]]
    p0 = np.array([1e-4, 0.02])
    np.testing.assert_allclose(persson_mean_gap(p0, split_q, split_c, e_star=1.0),
                               persson_mean_gap(p0, Q3, C3, e_star=1.0), rtol=1e-13)


def test_mean_gap_decreasing_and_shaped(spectrum):
    q, c = spectrum
    p0 = np.geomspace(1e-6, 0.3, 40)
    u = persson_mean_gap(p0, q, c, e_star=1.0)
    assert u.shape == p0.shape and np.all(u > 0) and np.all(np.diff(u) < 0)
    grid = persson_mean_gap(p0.reshape(5, 8), q, c, e_star=1.0)
    np.testing.assert_allclose(grid.ravel(), u, rtol=1e-14)
    assert np.ndim(persson_mean_gap(0.01, q, c, e_star=1.0)) == 0


def test_mean_gap_logarithmic_at_small_load(spectrum):
    """u ~ -gamma' ln p0 with gamma' = (gamma / (2 sqrt pi)) sum_k q_k c_k W_k."""
    q, c = spectrum
    a, _ = mode_weights(q, c)
    slope = -0.45 * np.sum(a) / (2 * math.sqrt(math.pi))
    p0, r = 1e-9, 1.01
    u = persson_mean_gap(np.array([p0 / r, p0 * r]), q, c, e_star=1.0, gamma=0.45)
    assert (u[1] - u[0]) / (2 * math.log(r)) == pytest.approx(slope, rel=1e-6)


# ------------------------------------------------------------------------- stiffness
@pytest.mark.parametrize("gamma", [0.3, 0.45])
def test_stiffness_is_minus_dp0_du(spectrum, gamma):
    q, c = spectrum
    e_star = 1.5
    p0 = np.geomspace(1e-5, 0.2, 7)
    r = 1e-3
    u_plus = persson_mean_gap(p0 * (1 + r), q, c, e_star=e_star, gamma=gamma)
    u_minus = persson_mean_gap(p0 * (1 - r), q, c, e_star=e_star, gamma=gamma)
    fd = -(2 * r * p0) / (u_plus - u_minus)
    np.testing.assert_allclose(persson_stiffness(p0, q, c, e_star=e_star, gamma=gamma), fd, rtol=1e-4)


def test_stiffness_at_zero_load(spectrum):
    q, c = spectrum
    assert float(persson_stiffness(0.0, q, c, e_star=1.0)) == 0.0
    assert persson_stiffness(np.zeros((2, 1)), q, c, e_star=1.0).shape == (2, 1)


# ------------------------------------------------------------------------- input checks
@pytest.mark.parametrize("call, name", [
    (lambda: persson_pressure_distribution(-1.0, 0.1, rms_slope=0.1, e_star=1.0), "p"),
    (lambda: persson_pressure_distribution(1.0, -0.1, rms_slope=0.1, e_star=1.0), "p0"),
    (lambda: persson_pressure_distribution(1.0, [0.1, 0.2], rms_slope=0.1, e_star=1.0), "p0"),
    (lambda: persson_pressure_distribution(1.0, 0.1, rms_slope=0.0, e_star=1.0), "rms_slope"),
    (lambda: persson_pressure_distribution(1.0, 0.1, rms_slope=0.1, e_star=np.nan), "e_star"),
    (lambda: mode_spectrum(3, 1, 1.5, 0.8, rms_slope=0.1), "n"),
    (lambda: mode_spectrum(16, 1, 9, 0.8, rms_slope=0.1), "k_s"),
    (lambda: mode_spectrum(16, 4, 2, 0.8, rms_slope=0.1), "k_l"),
    (lambda: mode_spectrum(16, 1, 8, 1.5, rms_slope=0.1), "hurst"),
    (lambda: mode_spectrum(16, 1, 8, 0.8), "rms_slope"),
    (lambda: mode_spectrum(16, 1, 8, 0.8, rms_slope=0.1, rms_height=1.0), "rms_height"),
    (lambda: mode_spectrum(16, 1, 8, 0.8, rms_slope=-0.1), "rms_slope"),
    (lambda: mode_spectrum(16, 1, 8, 0.8, rms_slope=0.1, length=0), "length"),
    (lambda: mode_spectrum(16, 1.1, 1.2, 0.8, rms_slope=0.1), "no integer mode"),
    (lambda: persson_mean_gap(0.0, Q3, C3, e_star=1.0), "p0"),
    (lambda: persson_mean_gap([0.1, np.nan], Q3, C3, e_star=1.0), "p0"),
    (lambda: persson_mean_gap(0.1, Q3, C3, e_star=0.0), "e_star"),
    (lambda: persson_mean_gap(0.1, Q3, C3, e_star=1.0, gamma=1.2), "gamma"),
    (lambda: persson_mean_gap(0.1, -Q3, C3, e_star=1.0), "q"),
    (lambda: persson_mean_gap(0.1, Q3.reshape(3, 1), C3, e_star=1.0), "q"),
    (lambda: persson_mean_gap(0.1, Q3, C3[:2], e_star=1.0), "c"),
    (lambda: persson_mean_gap(0.1, Q3, -C3, e_star=1.0), "c"),
    (lambda: persson_mean_gap(0.1, Q3, 0 * C3, e_star=1.0), "c"),
    (lambda: persson_stiffness(-0.1, Q3, C3, e_star=1.0), "p0"),
    (lambda: persson_stiffness(0.1, Q3, C3, e_star=1.0, gamma=-0.1), "gamma"),
    (lambda: persson_j(0.0), "s0"),
])
def test_bad_inputs(call, name):
    with pytest.raises(ValueError, match=name):
        call()
