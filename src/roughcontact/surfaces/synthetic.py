"""Self-affine periodic rough surfaces by FFT filtering of white noise (Hu & Tonder 1992).

Conventions: a square periodic domain of side ``length`` (L) sampled on ``n x n``
points, spacing ``dx = L / n``. Wavenumbers ``k`` are mode numbers in cycles per L
(``k = L / lambda``), as in the paper; angular wavenumbers are ``q = 2 pi k / L``.
Heights are in the same length unit as ``length``.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np

from ..core.cell import Cell
from ..core.fft import get_fft, rfft_weights, wavenumbers

#: Allowed ranges of the scale arguments: wide, but far enough from float64's limits that
#: heights, their squares and the spectral moments m2 ~ h^2/L^2 and m4 ~ h^2/L^4 stay finite.
LENGTH_RANGE = (1e-50, 1e50)
RMS_HEIGHT_RANGE = (1e-100, 1e100)
RMS_SLOPE_RANGE = (0.0, 1e3)


def _real(name: str, value, lo: float, hi: float, *, lo_open: bool = False, hi_open: bool = False) -> float:
    """``value`` as a float if it is a real number in the range, else a ValueError naming ``name``."""
    left, right = "(" if lo_open else "[", ")" if hi_open else "]"
    allowed = f"a finite real number in {left}{lo:g}, {hi:g}{right}"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be {allowed}, got {value!r} of type {type(value).__name__}")
    x = float(value)
    inside = (lo < x if lo_open else lo <= x) and (x < hi if hi_open else x <= hi)
    if not math.isfinite(x) or not inside:
        raise ValueError(f"{name} must be {allowed}, got {value!r}")
    return x


def _check_params(n, k_l, k_s, hurst, rms_slope, rms_height, length):
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 4:
        raise ValueError(f"n (grid points per side) must be an integer >= 4, got {n!r}")
    k_l = _real("k_l", k_l, 0.0, n / 2, lo_open=True)
    k_s = _real("k_s", k_s, 0.0, math.inf, lo_open=True, hi_open=True)
    if not k_l < k_s:
        raise ValueError(f"cutoffs must satisfy 0 < k_l < k_s, got k_l={k_l!r}, k_s={k_s!r}")
    if k_s > n / 2:
        raise ValueError(f"k_s must be <= n/2 = {n / 2} (Nyquist), got k_s={k_s!r}")
    _real("hurst (H)", hurst, 0.0, 1.0, lo_open=True, hi_open=True)
    if (rms_slope is None) == (rms_height is None):
        raise ValueError("give exactly one of rms_slope or rms_height")
    if rms_slope is not None:
        _real("rms_slope", rms_slope, *RMS_SLOPE_RANGE, lo_open=True)
    else:
        _real("rms_height", rms_height, *RMS_HEIGHT_RANGE)
    _real("length (L)", length, *LENGTH_RANGE)


def case_seed(seed: int, k_l: float, k_s: float, hurst: float) -> np.random.SeedSequence:
    """Seed sequence for one case: the user's ``seed`` plus a digest of the cutoffs and H.

    Different cases with the same ``seed`` thus draw independent noise, and the same
    arguments always give the same noise, on any platform.
    """
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    key = f"{float(k_l)!r}|{float(k_s)!r}|{float(hurst)!r}".encode()
    digest = int.from_bytes(hashlib.sha256(key).digest()[:8], "little")
    return np.random.SeedSequence(entropy=int(seed), spawn_key=(digest,))


def psd_filter(n: int, k_l: float, k_s: float, hurst: float, *, length: float = 1.0,
               plateau: bool = False) -> np.ndarray:
    """Amplitude filter sqrt(C(k)) on the rfft2 grid, shape ``(n, n//2+1)``.

    C(k) is proportional to ``|k|^(-2(1+H))`` for ``k_l <= |k| <= k_s`` (k in cycles per
    L) and zero elsewhere, or constant at C(k_l) for ``0 < |k| < k_l`` when ``plateau``.
    The mean (k = 0) is always zero. The overall scale is arbitrary: callers normalise.
    """
    kx, ky = wavenumbers(n, 1.0)
    k = np.hypot(kx, ky)
    with np.errstate(divide="ignore"):
        amp = np.where(k > 0, k, np.inf) ** (-(1.0 + hurst))
    band = (k >= k_l) & (k <= k_s)
    out = np.where(band, amp, 0.0)
    if plateau:
        out = np.where((k > 0) & (k < k_l), float(k_l) ** (-(1.0 + hurst)), out)
    out[0, 0] = 0.0
    return out


def spectral_moments(heights: np.ndarray, length: float = 1.0) -> dict[str, float]:
    """Spectral statistics of a periodic ``(n, n)`` height field, from its own spectrum.

    Returns a dict (units: length unit ``u`` of ``heights`` and ``length``):

    - ``rms_height``: sqrt(<h^2>) about the mean [u]
    - ``rms_slope``: sqrt(<|grad h|^2>) with the exact spectral derivative [-]
    - ``m0``, ``m2``, ``m4``: *profile* moments, averaged over the x and y directions:
      <h^2> [u^2], <(dh/dx)^2> [-], <(d2h/dx2)^2> [u^-2]
    - ``alpha``: Nayak's bandwidth m0*m4/m2^2 [-] from the profile moments (areal
      moments would give 2/3 of this for an isotropic surface)
    """
    h = np.asarray(heights, dtype=float)
    n = h.shape[0]
    if h.ndim != 2 or h.shape[0] != h.shape[1]:
        raise ValueError(f"heights must be a square 2-D array, got shape {h.shape}")
    spec = np.fft.rfft2(h)
    power = rfft_weights(n) * np.abs(spec) ** 2 / float(n) ** 4
    power[0, 0] = 0.0
    # Moments on the unit cell (q in rad per L), scaled by L afterwards: q^4 of a cell of
    # side 1e50 would underflow, and alpha is scale-free anyway.
    kx, ky = wavenumbers(n, 1.0)
    qx2 = (2 * np.pi * kx) ** 2
    qy2 = (2 * np.pi * ky) ** 2
    m0 = float(power.sum())
    m2 = float(0.5 * ((qx2 + qy2) * power).sum())
    m4 = float(0.5 * ((qx2**2 + qy2**2) * power).sum())
    return {
        "rms_height": float(np.sqrt(m0)),
        "rms_slope": float(np.sqrt(2.0 * m2)) / length,
        "m0": m0,
        "m2": m2 / length**2,
        "m4": m4 / length**4,
        "alpha": float(m0 * m4 / m2**2) if m2 > 0 else float("nan"),
    }


def finite_difference_rms_slope(heights: np.ndarray, length: float = 1.0) -> float:
    """rms slope from periodic central differences [-]; biased low against the spectral one."""
    h = np.asarray(heights, dtype=float)
    dx = length / h.shape[0]
    gx = (np.roll(h, -1, 0) - np.roll(h, 1, 0)) / (2 * dx)
    gy = (np.roll(h, -1, 1) - np.roll(h, 1, 1)) / (2 * dx)
    return float(np.sqrt(np.mean(gx**2 + gy**2)))


def nonperiodic_moments(heights: np.ndarray, length=1.0) -> dict[str, float]:
    """Statistics of a measured ``(nx, ny)`` patch (not periodic), from finite differences.

    A 1-D ``heights`` of shape (n,) is a profile: :func:`profile_moments`.

    ``length`` is the side L of a square patch or its sides ``(Lx, Ly)``; pixels
    ``dx = Lx / nx``, ``dy = Ly / ny``. A measured patch's spectrum would count the jump
    between opposite edges as roughness, so its moments come from differences taken inside
    the patch only: forward first and second differences along x and along y, averaged over
    both directions. Same keys and units as :func:`spectral_moments` (``rms_slope`` =
    sqrt(<|grad h|^2>) = sqrt(2 m2)); differences are biased low against the spectral
    derivative at the pixel scale, as :func:`finite_difference_rms_slope` is.
    """
    h = np.asarray(heights, dtype=float)
    if h.ndim == 1:
        return profile_moments(h, length)
    if h.ndim != 2 or min(h.shape) < 3:
        raise ValueError(f"heights must be a 2-D array of at least 3 x 3 (or a profile of at least 3 points), "
                         f"got shape {h.shape}")
    lx, ly = Cell.of(h.shape, length).sides
    dx, dy = lx / h.shape[0], ly / h.shape[1]
    m0 = float(np.mean((h - h.mean()) ** 2))
    d1 = float(np.mean(np.diff(h, axis=0) ** 2)), float(np.mean(np.diff(h, axis=1) ** 2))
    d2 = float(np.mean(np.diff(h, 2, axis=0) ** 2)), float(np.mean(np.diff(h, 2, axis=1) ** 2))
    if dx == dy:  # the square pixel's expressions, bit for bit those of earlier releases
        m2, m4 = 0.5 * (d1[0] + d1[1]) / dx**2, 0.5 * (d2[0] + d2[1]) / dx**4
    else:
        m2, m4 = 0.5 * (d1[0] / dx**2 + d1[1] / dy**2), 0.5 * (d2[0] / dx**4 + d2[1] / dy**4)
    return {
        "rms_height": float(np.sqrt(m0)),
        "rms_slope": float(np.sqrt(2.0 * m2)),
        "m0": m0,
        "m2": m2,
        "m4": m4,
        "alpha": float(m0 * m4 / m2**2) if m2 > 0 else float("nan"),
    }


def base_grid(n: int, k_s: float) -> int:
    """Side of the grid on which the white noise is drawn: the smallest even M > 2 k_s, or n.

    Every mode of the band (|k| <= k_s) lies strictly inside the M x M spectrum, so the
    filtered noise is a trigonometric polynomial independent of the output grid: the
    same seed gives the *same continuous surface* sampled at any n >= M, which makes
    resolution studies measure discretisation error alone. When n < M (k_s near the
    Nyquist mode of n) the noise is drawn on the n x n grid itself.
    """
    m = 2 * (int(np.floor(k_s)) + 1)
    return m if m <= n else n


def _embed_spectrum(spec_m: np.ndarray, m: int, n: int) -> np.ndarray:
    """Place an (m, m//2+1) rfft2 spectrum into an (n, n//2+1) one, zero elsewhere (n >= m)."""
    if m == n:
        return spec_m
    out = np.zeros((n, n // 2 + 1), dtype=complex)
    rows = np.fft.fftfreq(m, 1.0 / m).astype(int)
    # The mode m/2 (row and column) lies outside the band by construction of m: skip it,
    # as its Hermitian partner would be ambiguous on the larger grid.
    keep = np.abs(rows) < m // 2
    out[np.mod(rows[keep], n), : m // 2] = spec_m[keep, : m // 2]
    return out


def generate_surface(n: int, k_l: float, k_s: float, hurst: float, seed: int, *,
                     rms_slope: float | None = None, rms_height: float | None = None,
                     length: float = 1.0, plateau: bool = False,
                     backend: str | None = None) -> np.ndarray:
    """Periodic self-affine Gaussian rough surface, shape ``(n, n)``, zero mean.

    Parameters
    ----------
    n : int
        Grid points per side (any integer >= 4; odd sizes allowed).
    k_l, k_s : float
        Long- and short-wavelength cutoffs as mode numbers ``L / lambda``, 0 < k_l < k_s <= n/2.
    hurst : float
        Hurst exponent H in (0, 1); the PSD decays as ``k^(-2(1+H))``.
    seed : int
        Seed of the white noise (>= 0); the case's cutoffs and H are mixed in, so
        different cases never share noise. The noise is drawn on the smallest grid that
        holds the band (:func:`base_grid`), so the same arguments with another ``n``
        sample the same continuous surface.
    rms_slope, rms_height : float
        Exactly one: the target rms slope sqrt(<|grad h|^2>) [-], computed from the
        spectrum with exact derivatives, or the rms height [length unit].
    length : float
        Side L of the periodic domain [length unit].
    plateau : bool
        Keep C constant at C(k_l) below k_l instead of cutting it (off in the paper).
    backend : {"pyfftw", "numpy"} or None
        FFT backend; both give the same array to ~1e-12 relative.

    Returns
    -------
    numpy.ndarray, float64, shape (n, n)
        Heights h(x, y) [length unit], axis 0 = x, axis 1 = y, spacing ``length / n``.
    """
    _check_params(n, k_l, k_s, hurst, rms_slope, rms_height, length)
    rng = np.random.default_rng(case_seed(seed, k_l, k_s, hurst))
    m = base_grid(n, k_s)
    noise = rng.standard_normal((m, m))
    spec_m = np.fft.rfft2(noise) * psd_filter(m, k_l, k_s, hurst, length=length, plateau=plateau)
    fft = get_fft((n, n), backend=backend)
    h = fft.backward(_embed_spectrum(spec_m, m, n)).copy()
    # Normalise on the unit cell (the rms slope there is rms_slope * L), so that no
    # intermediate carries a power of L.
    stats = spectral_moments(h, 1.0)
    current = stats["rms_slope"] if rms_slope is not None else stats["rms_height"]
    if not current > 0:
        raise ValueError(
            f"no spectral power between k_l={k_l} and k_s={k_s} on a {n}x{n} grid; widen the band"
        )
    h -= h.mean()
    h *= (float(rms_slope) * float(length) if rms_slope is not None else float(rms_height)) / current
    rms = float(np.sqrt(np.mean(h * h))) if np.all(np.isfinite(h)) else math.inf
    if not RMS_HEIGHT_RANGE[0] <= rms <= RMS_HEIGHT_RANGE[1]:
        raise ValueError(
            f"rms_slope={rms_slope!r} on length={length!r} gives an rms height of {rms:.3g}, outside the "
            f"representable range [{RMS_HEIGHT_RANGE[0]:g}, {RMS_HEIGHT_RANGE[1]:g}]; choose a smaller product"
        )
    return h


# ---------------------------------------------------------------------------------------------------------------
# Profiles (1-D surfaces, plane strain): the honest 1-D analogue of the maps above.
# ---------------------------------------------------------------------------------------------------------------


def profile_psd_filter(n: int, k_l: float, k_s: float, hurst: float, *, plateau: bool = False) -> np.ndarray:
    """Amplitude filter sqrt(C(k)) of a profile on the rfft grid, shape ``(n//2+1,)``.

    The 1-D self-affine spectrum: C(q) proportional to ``q^(-1-2H)`` for ``k_l <= k <= k_s`` (k in
    cycles per L), zero elsewhere, or constant at C(k_l) for ``0 < k < k_l`` when ``plateau``: the
    convention of :func:`psd_filter`, whose 2-D isotropic C(q) ~ q^(-2-2H) is this one times the
    1/q of the radial measure. The mean (k = 0) is zero; the scale is arbitrary (callers normalise).
    """
    k = np.arange(n // 2 + 1, dtype=float)
    with np.errstate(divide="ignore"):
        amp = np.where(k > 0, k, np.inf) ** (-(0.5 + hurst))
    out = np.where((k >= k_l) & (k <= k_s), amp, 0.0)
    if plateau:
        out = np.where((k > 0) & (k < k_l), float(k_l) ** (-(0.5 + hurst)), out)
    out[0] = 0.0
    return out


def profile_spectral_moments(heights: np.ndarray, length: float = 1.0) -> dict[str, float]:
    """Spectral statistics of a periodic profile ``(n,)`` of period ``length`` (length unit ``u``).

    Returns ``rms_height`` [u]; ``rms_slope`` = sqrt(<(dh/dx)^2>) with the exact spectral derivative [-]
    (a profile has one slope: no factor 2 as in the areal <|grad h|^2> = 2 m2); the moments ``m0`` [u^2],
    ``m2`` [-], ``m4`` [u^-2]; Nayak's ``alpha`` = m0 m4 / m2^2 [-]. Same keys as :func:`spectral_moments`.
    """
    h = np.asarray(heights, dtype=float)
    if h.ndim != 1 or h.size < 4:
        raise ValueError(f"heights must be a 1-D profile of at least 4 points, got shape {h.shape}")
    n = h.size
    weights = np.full(n // 2 + 1, 2.0)
    weights[0] = 1.0
    if n % 2 == 0:
        weights[-1] = 1.0  # the Nyquist bin has no conjugate partner
    power = weights * np.abs(np.fft.rfft(h)) ** 2 / float(n) ** 2
    power[0] = 0.0
    q2 = (2 * np.pi * np.arange(n // 2 + 1)) ** 2  # on the unit period; scaled by L below (see spectral_moments)
    m0, m2, m4 = float(power.sum()), float((q2 * power).sum()), float((q2**2 * power).sum())
    return {"rms_height": float(np.sqrt(m0)), "rms_slope": float(np.sqrt(m2)) / length, "m0": m0,
            "m2": m2 / length**2, "m4": m4 / length**4,
            "alpha": float(m0 * m4 / m2**2) if m2 > 0 else float("nan")}


def profile_moments(heights: np.ndarray, length: float = 1.0) -> dict[str, float]:
    """Statistics of a measured profile ``(n,)`` of length ``length`` (not periodic), from forward differences.

    Pixel ``dx = length / n``. The profile analogue of :func:`nonperiodic_moments` (differences inside the
    profile only, biased low against the spectral derivative at the pixel scale); ``rms_slope`` is the
    profile's sqrt(<(dh/dx)^2>) = sqrt(m2), the h' that loads are relative to (``load.relative_to``).
    """
    h = np.asarray(heights, dtype=float)
    if h.ndim != 1 or h.size < 3:
        raise ValueError(f"heights must be a 1-D profile of at least 3 points, got shape {h.shape}")
    dx = float(length) / h.size
    m0 = float(np.mean((h - h.mean()) ** 2))
    m2 = float(np.mean(np.diff(h) ** 2)) / dx**2
    m4 = float(np.mean(np.diff(h, 2) ** 2)) / dx**4
    return {"rms_height": float(np.sqrt(m0)), "rms_slope": float(np.sqrt(m2)), "m0": m0, "m2": m2, "m4": m4,
            "alpha": float(m0 * m4 / m2**2) if m2 > 0 else float("nan")}


def generate_profile(n: int, k_l: float, k_s: float, hurst: float, seed: int, *,
                     rms_slope: float | None = None, rms_height: float | None = None,
                     length: float = 1.0, plateau: bool = False) -> np.ndarray:
    """Periodic self-affine Gaussian profile, shape ``(n,)``, zero mean: the 1-D :func:`generate_surface`.

    Parameters
    ----------
    n : int
        Points along the profile (>= 4).
    k_l, k_s : float
        Cutoffs as mode numbers ``L / lambda``, 0 < k_l < k_s <= n/2.
    hurst : float
        Hurst exponent H in (0, 1); the 1-D PSD decays as ``q^(-1-2H)`` (:func:`profile_psd_filter`).
    seed : int
        Seed of the white noise (>= 0), mixed with the cutoffs and H as in :func:`case_seed`. The noise is
        drawn on :func:`base_grid`'s points, so another ``n`` samples the same continuous profile.
    rms_slope, rms_height : float
        Exactly one: the profile's spectral rms slope sqrt(<(dh/dx)^2>) [-] or rms height [length unit].
    length : float
        Period L of the profile [length unit]; spacing ``length / n``.
    plateau : bool
        Keep C constant at C(k_l) below k_l instead of cutting it.

    Returns
    -------
    numpy.ndarray, float64, shape (n,)
        Heights h(x) [length unit] at ``x = i length / n``.
    """
    _check_params(n, k_l, k_s, hurst, rms_slope, rms_height, length)
    rng = np.random.default_rng(case_seed(seed, k_l, k_s, hurst))
    m = base_grid(n, k_s)
    spec_m = np.fft.rfft(rng.standard_normal(m)) * profile_psd_filter(m, k_l, k_s, hurst, plateau=plateau)
    spec = np.zeros(n // 2 + 1, dtype=complex)
    keep = m // 2 if m < n else m // 2 + 1  # the mode m/2 lies outside the band when m < n (base_grid)
    spec[:keep] = spec_m[:keep]
    h = np.fft.irfft(spec, n)
    stats = profile_spectral_moments(h, 1.0)
    current = stats["rms_slope"] if rms_slope is not None else stats["rms_height"]
    if not current > 0:
        raise ValueError(f"no spectral power between k_l={k_l} and k_s={k_s} on a profile of {n} points; "
                         "widen the band")
    h -= h.mean()
    h *= (float(rms_slope) * float(length) if rms_slope is not None else float(rms_height)) / current
    rms = float(np.sqrt(np.mean(h * h))) if np.all(np.isfinite(h)) else math.inf
    if not RMS_HEIGHT_RANGE[0] <= rms <= RMS_HEIGHT_RANGE[1]:
        raise ValueError(f"rms_slope={rms_slope!r} on length={length!r} gives an rms height of {rms:.3g}, outside the "
                         f"representable range [{RMS_HEIGHT_RANGE[0]:g}, {RMS_HEIGHT_RANGE[1]:g}]; choose a smaller "
                         "product")
    return h
