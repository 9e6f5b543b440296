"""Representativity measure eps: exactness for a known histogram, noise floor, the paper's trend."""
import numpy as np
import pytest
from scipy import integrate
from scipy.stats import norm

from roughcontact import generate_surface
from roughcontact.analysis.aggregate.seeds import scale_free_statistics
from roughcontact.statistics.representativity import (
    binning_noise_floor,
    gaussian_l2_error,
    scale_free_epsilon,
    scale_free_l2_error,
)


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


def test_scale_free_epsilon_is_invariant_and_the_dimensional_one_scales():
    """eps(c h) = eps(h)/sqrt(c); eps of (h - hbar)/sigma is the same for every c and equals eps sqrt(sigma)."""
    h = generate_surface(64, 1, 32, 0.8, 3, rms_height=0.1)
    eps, free = gaussian_l2_error(h), scale_free_l2_error(h)
    for c in (1e-3, 0.1, 7.0, 1e4):
        assert gaussian_l2_error(c * h) == pytest.approx(eps / np.sqrt(c), rel=1e-9)
        assert scale_free_l2_error(c * h + 5.0) == pytest.approx(free, rel=1e-9)
    assert free == pytest.approx(scale_free_epsilon(eps, h.std()), rel=1e-9)
    # At the paper's rms height 0.1 the two differ by sqrt(0.1).
    assert free == pytest.approx(eps * np.sqrt(0.1), rel=1e-9)
    with pytest.raises(ValueError, match="sigma"):
        scale_free_epsilon(eps, 0.0)
    with pytest.raises(ValueError, match="all equal"):
        scale_free_l2_error(np.ones(10))


def test_scale_free_statistics_from_per_case_values():
    import xarray as xr

    dims = ("k_l", "k_s", "H", "seed")
    rng = np.random.default_rng(0)
    eps, sigma = rng.uniform(0.1, 0.5, (2, 1, 1, 3)), rng.uniform(0.05, 0.2, (2, 1, 1, 3))
    coords = {"k_l": [1.0, 4.0], "k_s": [32.0], "H": [0.8], "seed": np.arange(3)}
    rep = xr.Dataset({"epsilon": (dims, eps), "std_height": (dims, sigma)}, coords=coords)
    st = scale_free_statistics(rep)
    np.testing.assert_allclose(st["epsilon_mean"].values, (eps * np.sqrt(sigma)).mean(axis=-1))
    assert st["epsilon_mean"].attrs["units"] == "1" and st["n_seeds"].values.min() == 3
    assert scale_free_statistics(rep.drop_vars("std_height")) is None


def test_a_batch_holds_every_k_s_and_seed_each_as_computed_alone():
    """One representativity job's file: each (k_s, seed) equals that surface's eps computed on its own."""
    from roughcontact.analysis import aggregate
    from roughcontact.pipeline.datasets import representativity_batch, split_cases

    surface = {"N": 32, "L": 1.0, "plateau": False, "rms_height": 0.1}
    batch = representativity_batch(surface, k_l="2", k_s=["8", "12"], hurst="0.8", seeds=3, n_bins=20)
    assert dict(batch.sizes) == {"k_l": 1, "k_s": 2, "H": 1, "seed": 3}
    for ks in ("8", "12"):
        for seed in range(3):
            h = generate_surface(32, 2.0, float(ks), 0.8, seed, rms_height=0.1)
            assert batch.epsilon.sel(k_s=float(ks), seed=seed).item() == gaussian_l2_error(h, 20)
    parts = split_cases(batch)
    assert [(p.k_s.item(), p.seed.item()) for p in parts] == [(8.0, 0), (8.0, 1), (8.0, 2),
                                                              (12.0, 0), (12.0, 1), (12.0, 2)]
    expected = [(2.0, ks, 0.8, s) for ks in (8.0, 12.0) for s in range(3)]
    combined = aggregate.combine_cases(parts, [f"case {i}" for i in range(6)], expected=expected,
                                       kind="representativity")
    assert combined.epsilon.equals(batch.epsilon)
