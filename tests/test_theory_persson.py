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
from roughcontact.theory.persson import (
    W_RULES,
    mode_weights,
    persson_mean_gap_terms,
    persson_stiffness_terms,
    power_law_terms,
)

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
    """The whole power's w is sqrt(2)/h': the top shell read at its top; at its middle it holds less power."""
    q, c = spectrum
    _, w = mode_weights(q, c, "shell")
    h1 = math.sqrt(np.sum(q * q * c))
    assert w[-1] == pytest.approx(math.sqrt(2) / h1, rel=1e-12)
    assert np.all(np.diff(w) < 0)
    _, mid = mode_weights(q, c)
    assert np.all(mid > w) and np.all(np.diff(mid) < 0)


#: Each rule's W of the three distinct modes Q3 (one mode a shell: "mode" is "shell" here).
_W3 = {"shell": lambda q2c, i: (0.5 * np.sum(q2c[: i + 1])) ** -0.5,
       "midpoint": lambda q2c, i: (0.5 * (np.sum(q2c[:i]) + 0.5 * q2c[i])) ** -0.5,
       "mode": lambda q2c, i: (0.5 * np.sum(q2c[: i + 1])) ** -0.5}


@pytest.mark.parametrize("rule", W_RULES)
def test_mean_gap_against_direct_quadrature(rule):
    """u = (1/(2 sqrt pi)) sum_k q_k c_k w_k int_p0^inf dp/p [gamma + 3(1-gamma) P^2] exp(-(w p/E*)^2)."""
    e_star, gamma = 2.0, 0.42
    w = [_W3[rule](Q3**2 * C3, i) for i in range(3)]
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
        got = persson_mean_gap(p0, Q3[::-1], C3[::-1], e_star=e_star, gamma=gamma, rule=rule)  # any order
        assert float(got) == pytest.approx(ref, rel=1e-6)


@pytest.mark.parametrize("rule, expected", [("shell", [(0.5 * 1.0) ** -0.5, (0.5 * 9.0) ** -0.5]),
                                            ("midpoint", [(0.25 * 1.0) ** -0.5, (0.5 * 5.0) ** -0.5])])
def test_modes_of_one_wavenumber_count_together(rule, expected):
    """Ties in q share one W (the shell's power counted whole or half); splitting a mode changes nothing."""
    a, w = mode_weights([1.0, 2.0, 2.0], [1.0, 1.0, 1.0], rule)
    np.testing.assert_allclose(w, expected, rtol=1e-15)
    np.testing.assert_allclose(a, [w[0], 4.0 * w[1]], rtol=1e-15)
    split_q, split_c = np.r_[Q3, Q3[1]], np.r_[C3[0], 0.3 * C3[1], C3[2], 0.7 * C3[1]]
    p0 = np.array([1e-4, 0.02])
    np.testing.assert_allclose(persson_mean_gap(p0, split_q, split_c, e_star=1.0, rule=rule),
                               persson_mean_gap(p0, Q3, C3, e_star=1.0, rule=rule), rtol=1e-13)


@pytest.mark.parametrize("rule", ["shell", "midpoint"])
def test_a_shell_is_one_term_even_where_its_wavenumbers_differ_by_round_off(rule):
    """|k| = 5 is (3, 4) and (5, 0): hypot may round them apart; they are still one shell (issue 61)."""
    q, c = mode_spectrum(256, 4, 40, 0.5, rms_slope=0.1)
    k2 = np.rint((q / (2 * math.pi)) ** 2)
    a, w = mode_weights(q, c, rule)
    assert w.size == np.unique(k2).size < np.unique(q).size + 1
    shells, inverse = np.unique(k2, return_inverse=True)
    power = np.bincount(inverse, q * q * c)
    below = np.cumsum(power) - (0.5 * power if rule == "midpoint" else 0.0)
    np.testing.assert_allclose(w, (0.5 * below) ** -0.5, rtol=1e-12)
    np.testing.assert_allclose(a, np.bincount(inverse, q * c) * w, rtol=1e-12)
    _, wm = mode_weights(q * (1 + 1e-13 * (np.arange(q.size) % 3)), c, "mode")  # ties keep their given order
    order = np.lexsort((np.arange(q.size), k2))
    np.testing.assert_allclose(wm, (0.5 * np.cumsum((q * q * c)[order])) ** -0.5, rtol=1e-11)


def test_mode_by_mode_weights_follow_the_given_order_of_ties():
    a, w = mode_weights([2.0, 1.0, 2.0], [1.0, 1.0, 3.0], "mode")
    np.testing.assert_allclose(w, [(0.5 * 1.0) ** -0.5, (0.5 * 5.0) ** -0.5, (0.5 * 17.0) ** -0.5], rtol=1e-15)
    np.testing.assert_allclose(a, [w[0], 2.0 * w[1], 6.0 * w[2]], rtol=1e-15)


def _power_law_shells(m, k_l=4.0, k_s=8.0, hurst=0.84, slope=0.1):
    """``m`` shells of equal width in q over [q_l, q_s], each with the continuum's power 2 pi q C dq (midpoints)."""
    edges = 2 * math.pi * np.linspace(k_l, k_s, m + 1)
    q = 0.5 * (edges[1:] + edges[:-1])
    c = 2 * math.pi * q * q ** (-2 * (1 + hurst)) * np.diff(edges)
    return q, c * slope**2 / np.sum(q * q * c)


def test_the_midpoint_rule_converges_to_the_continuum_and_the_whole_shell_does_not_as_fast():
    """issue 61: the whole-shell W put the k_l = 4 cells 8-10 % off the continuum; the midpoint rule converges."""
    p0 = np.array([2e-3, 2e-2])
    a, w = power_law_terms(4.0, 8.0, 0.84, rms_slope=0.1)
    exact = persson_mean_gap_terms(p0, a, w, e_star=1.0)
    err = {rule: [np.max(np.abs(persson_mean_gap(p0, *_power_law_shells(m), e_star=1.0, rule=rule) / exact - 1))
                  for m in (8, 32)] for rule in ("midpoint", "shell")}
    assert err["midpoint"][1] < 0.01 and err["midpoint"][1] < err["midpoint"][0] / 3
    assert err["shell"][0] > 0.05 and err["shell"][1] > 5 * err["midpoint"][1]


@pytest.mark.parametrize("hurst", [0.36, 1.0])
def test_the_continuum_terms_against_direct_quadrature(hurst):
    """u = sqrt(pi) int q^2 C w J(w p0/E*) dq, w = (pi int_ql^q q'^3 C)^(-1/2), by adaptive quadrature."""
    kl, ks, slope, length, e_star = 3.0, 12.0, 0.2, 2.0, 1.5
    ql, qs = 2 * math.pi * kl / length, 2 * math.pi * ks / length
    m3 = quad(lambda q: q**3 * q ** (-2 * (1 + hurst)), ql, qs, epsabs=0, epsrel=1e-13)[0]
    c0 = slope**2 / (2 * math.pi * m3)

    def w(q):  # the power below q in closed form (checked against quad at the top: m3)
        below = math.log(q / ql) if hurst == 1.0 else (q ** (2 - 2 * hurst) - ql ** (2 - 2 * hurst)) / (2 - 2 * hurst)
        return (math.pi * c0 * below) ** -0.5

    assert w(qs) == pytest.approx(math.sqrt(2) / slope, rel=1e-12)

    a, ww = power_law_terms(kl, ks, hurst, rms_slope=slope, length=length)
    np.testing.assert_allclose(persson_mean_gap_terms([1e-3, 0.03], *power_law_terms(
        kl, ks, hurst, rms_slope=slope, length=length, nodes=4096), e_star=e_star),
        persson_mean_gap_terms([1e-3, 0.03], a, ww, e_star=e_star), rtol=1e-9)  # converged
    for p0 in (1e-3, 0.03):
        ref = math.sqrt(math.pi) * quad(lambda q, p0=p0: q * q * c0 * q ** (-2 * (1 + hurst)) * w(q)
                                        * float(persson_j(w(q) * p0 / e_star)), ql, qs, epsabs=0, epsrel=1e-10,
                                        limit=200)[0]
        assert float(persson_mean_gap_terms(p0, a, ww, e_star=e_star)) == pytest.approx(ref, rel=1e-6)
    assert np.sum(a / ww) == pytest.approx(2 * math.pi * c0 * quad(lambda q: q**2 * q ** (-2 * (1 + hurst)), ql,
                                                                   qs, epsabs=0, epsrel=1e-13)[0], rel=1e-9)
    r = 1e-4
    p0 = np.array([1e-3, 0.03])
    fd = -(2 * r * p0) / (persson_mean_gap_terms(p0 * (1 + r), a, ww, e_star=e_star)
                          - persson_mean_gap_terms(p0 * (1 - r), a, ww, e_star=e_star))
    np.testing.assert_allclose(persson_stiffness_terms(p0, a, ww, e_star=e_star), fd, rtol=1e-5)


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
    (lambda: persson_mean_gap(0.1, Q3, C3, e_star=1.0, rule="top"), "rule"),
    (lambda: power_law_terms(4, 2, 0.5, rms_slope=0.1), "k_l"),
    (lambda: power_law_terms(2, 4, 0.5, rms_slope=0.0), "rms_slope"),
    (lambda: power_law_terms(2, 4, 0.5, rms_slope=0.1, nodes=4), "nodes"),
])
def test_bad_inputs(call, name):
    with pytest.raises(ValueError, match=name):
        call()
