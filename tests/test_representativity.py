"""Representativity measure eps: exactness for a known histogram, noise floor, the paper's trend."""
import numpy as np
import pytest
from scipy import integrate
from scipy.stats import norm

from roughcontact import generate_surface
from roughcontact.representativity import binning_noise_floor, gaussian_l2_error


def test_matches_direct_quadrature():
    # The closed form (erf bin integrals + tails) against brute-force quadrature.
    rng = np.random.default_rng(0)
    h = rng.gamma(3.0, size=5000)
    n_bins = 20
    counts, edges = np.histogram(h, bins=n_bins)
    pdf = counts / (h.size * (edges[1] - edges[0]))
    g = norm(h.mean(), h.std())

    def sq(x):
        i = np.searchsorted(edges, x, side="right") - 1
        p = pdf[i] if 0 <= i < n_bins else 0.0
        return (g.pdf(x) - p) ** 2

    pts = list(edges)
    total = integrate.quad(sq, edges[0] - 20, edges[-1] + 20, points=pts, limit=500)[0]
    assert gaussian_l2_error(h, n_bins) == pytest.approx(np.sqrt(total), rel=1e-6)


def test_exact_gaussian_sample_within_binning_noise():
    # For independent Gaussian draws eps is set by binning noise alone; 1.5x the expected
    # floor bounds it (eps^2 is a sum of ~500 independent terms: relative scatter ~ 5 %).
    rng = np.random.default_rng(42)
    for n in (10_000, 65_536, 262_144):
        x = rng.normal(0.3, 0.1, n)
        floor = binning_noise_floor(n, 500, (x.max() - x.min()) / x.std(), sigma=x.std())
        eps = gaussian_l2_error(x, 500)
        assert 0.5 * floor < eps < 1.5 * floor


def test_paper_trend_larger_k_l_is_more_gaussian():
    # The paper's finding (Fig. 1a) at N=256, k_s=64: mean eps over 10 seeds drops with k_l.
    def mean_eps(k_l):
        return np.mean([gaussian_l2_error(generate_surface(256, k_l, 64, 0.8, s, rms_height=0.1)) for s in range(10)])

    assert mean_eps(16) < mean_eps(1)


def test_bad_input():
    with pytest.raises(ValueError, match="all equal"):
        gaussian_l2_error(np.ones(100))
    with pytest.raises(ValueError, match="finite"):
        gaussian_l2_error(np.array([1.0, np.nan, 2.0]))
    with pytest.raises(ValueError, match="n_bins"):
        gaussian_l2_error(np.arange(10.0), 1)
