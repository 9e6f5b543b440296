"""Surface generation: spectrum shape, normalisation, reproducibility, FFT backends."""
import numpy as np
import pytest

from roughcontact import generate_surface
from roughcontact.core.fft import wavenumbers
from roughcontact.surfaces.synthetic import finite_difference_rms_slope, spectral_moments


def radial_psd(h):
    """Azimuthally averaged |h(k)|^2 on integer |k| shells (k in cycles per L)."""
    n = h.shape[0]
    power = np.abs(np.fft.fft2(h)) ** 2
    kx = np.fft.fftfreq(n, 1.0 / n)
    k = np.hypot(kx[:, None], kx[None, :])
    shell = np.rint(k).astype(int)
    sums = np.bincount(shell.ravel(), power.ravel())
    counts = np.bincount(shell.ravel())
    return np.arange(len(sums)), sums / np.maximum(counts, 1), k, power


@pytest.mark.parametrize("hurst", [0.2, 0.5, 0.8])
def test_psd_slope_between_cutoffs(hurst):
    # Averaging a few seeds beats down the chi-squared scatter of each shell; +-0.05 on
    # the exponent is the acceptance band.
    k_l, k_s, n = 4, 64, 256
    psd = np.mean([radial_psd(generate_surface(n, k_l, k_s, hurst, s, rms_slope=0.1))[1] for s in range(4)], axis=0)
    k = np.arange(len(psd))
    sel = (k >= k_l + 1) & (k <= k_s - 1)
    slope = np.polyfit(np.log(k[sel]), np.log(psd[sel]), 1)[0]
    assert slope == pytest.approx(-2 * (1 + hurst), abs=0.05)


def test_no_power_outside_band():
    n, k_l, k_s = 128, 8, 32
    h = generate_surface(n, k_l, k_s, 0.7, 3, rms_slope=0.1)
    _, _, k, power = radial_psd(h)
    outside = (k < k_l) | (k > k_s)
    assert power[outside].max() < 1e-20 * power.max()


def test_plateau_adds_power_below_k_l_only():
    n, k_l, k_s = 128, 8, 32
    h = generate_surface(n, k_l, k_s, 0.7, 3, rms_slope=0.1, plateau=True)
    _, _, k, power = radial_psd(h)
    assert power[(k > 0) & (k < k_l)].max() > 0
    assert power[k > k_s].max() < 1e-20 * power.max()


@pytest.mark.parametrize("n", [64, 63, 100])
def test_normalisation_exact(n):
    h = generate_surface(n, 2, 16, 0.8, 0, rms_slope=0.1)
    assert spectral_moments(h)["rms_slope"] == pytest.approx(0.1, rel=1e-6)
    assert abs(h.mean()) < 1e-14
    h = generate_surface(n, 2, 16, 0.8, 0, rms_height=0.1, length=2.0)
    assert spectral_moments(h, 2.0)["rms_height"] == pytest.approx(0.1, rel=1e-6)
    assert np.std(h) == pytest.approx(0.1, rel=1e-6)


def test_spectral_slope_matches_exact_derivative_of_a_sinusoid():
    n, length, amp = 64, 2.0, 0.3
    x = np.arange(n) * length / n
    h = amp * np.sin(2 * np.pi * 3 * x / length)[:, None] * np.ones(n)[None, :]
    exact = amp * 2 * np.pi * 3 / length / np.sqrt(2)
    assert spectral_moments(h, length)["rms_slope"] == pytest.approx(exact, rel=1e-12)
    # Central differences underestimate it: the reason the paper uses the spectrum.
    assert finite_difference_rms_slope(h, length) < exact


def test_same_seed_same_array_and_independent_cases():
    a = generate_surface(64, 2, 16, 0.8, 5, rms_slope=0.1)
    assert np.array_equal(a, generate_surface(64, 2, 16, 0.8, 5, rms_slope=0.1))
    others = [
        generate_surface(64, 2, 16, 0.8, 6, rms_slope=0.1),
        generate_surface(64, 2, 16, 0.7, 5, rms_slope=0.1),
        generate_surface(64, 4, 16, 0.8, 5, rms_slope=0.1),
    ]
    for b in others:
        assert abs(np.corrcoef(a.ravel(), b.ravel())[0, 1]) < 0.5


def test_backends_agree():
    pytest.importorskip("pyfftw")
    a = generate_surface(128, 4, 32, 0.6, 1, rms_slope=0.1, backend="pyfftw")
    b = generate_surface(128, 4, 32, 0.6, 1, rms_slope=0.1, backend="numpy")
    assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))


def test_wavenumbers_grid():
    kx, ky = wavenumbers(8)
    assert kx.shape == (8, 1) and ky.shape == (1, 5)
    assert kx[:, 0].tolist() == [0, 1, 2, 3, -4, -3, -2, -1]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(n=64, k_l=16, k_s=16, hurst=0.8, seed=0, rms_slope=0.1), "k_l < k_s"),
        (dict(n=64, k_l=1, k_s=33, hurst=0.8, seed=0, rms_slope=0.1), "n/2"),
        (dict(n=64, k_l=1, k_s=16, hurst=1.0, seed=0, rms_slope=0.1), r"\(0, 1\)"),
        (dict(n=64, k_l=1, k_s=16, hurst=0.5, seed=-1, rms_slope=0.1), "seed"),
        (dict(n=64, k_l=1, k_s=16, hurst=0.5, seed=0, rms_slope=-0.1), "rms_slope"),
        (dict(n=64, k_l=1, k_s=16, hurst=0.5, seed=0), "exactly one"),
        (dict(n=64, k_l=1, k_s=16, hurst=0.5, seed=0, rms_slope=0.1, rms_height=0.1), "exactly one"),
        (dict(n=64, k_l=1, k_s=16, hurst=float("nan"), seed=0, rms_slope=0.1), "hurst"),
    ],
)
def test_bad_arguments_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        generate_surface(**kwargs)


def test_empty_band_is_reported():
    # 0.2 < |k| < 0.9 holds no integer mode: no power to normalise.
    with pytest.raises(ValueError, match="no spectral power"):
        generate_surface(16, 0.2, 0.9, 0.5, 0, rms_slope=0.1)


def test_same_continuous_surface_at_any_resolution():
    # The noise is drawn on the smallest grid holding the band, so N=128 and N=2048 sample
    # one trigonometric polynomial: resolution studies see discretisation error only.
    coarse = generate_surface(128, 16, 32, 0.8, 0, rms_slope=0.1)
    for n in (256, 2048):
        fine = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
        step = n // 128
        assert np.max(np.abs(fine[::step, ::step] - coarse)) <= 1e-12 * np.max(np.abs(coarse))


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"k_l": "4"}, "k_l must be a finite real number in (0, 32], got '4' of type str"),
        ({"hurst": "0.8"}, "hurst (H) must be a finite real number in (0, 1)"),
        ({"hurst": True}, "hurst (H) must be a finite real number"),
        ({"rms_slope": "0.1"}, "rms_slope must be a finite real number in (0, 1000]"),
        ({"rms_slope": 1e308}, "rms_slope must be a finite real number in (0, 1000], got 1e+308"),
        ({"length": "1"}, "length (L) must be a finite real number in [1e-50, 1e+50]"),
        ({"length": 1e-300}, "length (L) must be a finite real number in [1e-50, 1e+50], got 1e-300"),
        ({"length": 1e300}, "length (L) must be a finite real number in [1e-50, 1e+50], got 1e+300"),
        ({"rms_slope": None, "rms_height": 1e308}, "rms_height must be a finite real number in [1e-100, 1e+100]"),
        ({"n": 64.0}, "n (grid points per side) must be an integer >= 4"),
        ({"length": 1e-50, "rms_slope": 1e-300}, "outside the representable range"),
    ],
)
def test_library_arguments_are_named_with_their_range(kwargs, words):
    args = {"n": 64, "k_l": 4, "k_s": 16, "hurst": 0.8, "seed": 0, "rms_slope": 0.1}
    args.update(kwargs)
    with pytest.raises(ValueError) as info:
        generate_surface(args.pop("n"), args.pop("k_l"), args.pop("k_s"), args.pop("hurst"), args.pop("seed"),
                         **args)
    assert words in str(info.value), str(info.value)


@pytest.mark.parametrize("length", [1e-40, 1e-3, 1.0, 1e3, 1e40])
def test_extreme_lengths_scale_exactly(length):
    """The same surface on any cell size: heights scale with L at a fixed rms slope, alpha does not move."""
    ref = generate_surface(64, 4, 16, 0.8, 0, rms_slope=0.1)
    h = generate_surface(64, 4, 16, 0.8, 0, rms_slope=0.1, length=length)
    assert np.allclose(h / length, ref, rtol=1e-12, atol=1e-15 * np.abs(ref).max())
    stats, ref_stats = spectral_moments(h, length), spectral_moments(ref, 1.0)
    assert stats["rms_slope"] == pytest.approx(0.1, rel=1e-12)
    assert stats["alpha"] == pytest.approx(ref_stats["alpha"], rel=1e-12)
    big = generate_surface(64, 4, 16, 0.8, 0, rms_height=1e90)
    assert np.all(np.isfinite(big)) and np.sqrt(np.mean(big**2)) == pytest.approx(1e90, rel=1e-12)


def test_nonperiodic_moments_agree_with_the_spectrum_and_ignore_the_edge_jump():
    from roughcontact.surfaces.synthetic import nonperiodic_moments, spectral_moments

    # k_s = N/16: finite differences are biased O((q dx)^2 / 12) ~ 1 % at the shortest wavelength
    h = generate_surface(256, 2.0, 16.0, 0.7, 3, length=2.0, rms_slope=0.1)
    fd, sp = nonperiodic_moments(h, 2.0), spectral_moments(h, 2.0)
    assert fd["rms_height"] == pytest.approx(sp["rms_height"], rel=1e-12)
    assert fd["rms_slope"] == pytest.approx(sp["rms_slope"], rel=0.01)
    assert fd["m4"] == pytest.approx(sp["m4"], rel=0.03) and fd["alpha"] == pytest.approx(sp["alpha"], rel=0.03)
    # a tilted plane is smooth inside the patch: slope exactly s, no curvature, whatever the edges
    x = np.arange(64) * (3.0 / 64)
    plane = np.outer(0.2 * x, np.ones(64))
    tilt = nonperiodic_moments(plane, 3.0)
    assert tilt["rms_slope"] == pytest.approx(0.2, rel=1e-12) and tilt["m4"] == pytest.approx(0.0, abs=1e-20)
    assert spectral_moments(plane, 3.0)["rms_slope"] > 1.0  # the periodic spectrum sees the jump
