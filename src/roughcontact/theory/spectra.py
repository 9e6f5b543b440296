"""Spectral moments of the ideal isotropic power-law spectrum, and Nayak's bandwidth.

``C(k) ~ k^(-2(1+H))`` on ``k_l <= |k| <= k_s``, with wavenumbers ``k`` in cycles per ``L``: moments in
closed form (continuous integrals) and as the discrete sum over the integer modes of an ``n x n``
grid (what :func:`~roughcontact.surfaces.synthetic.generate_surface` actually draws), and Nayak's
bandwidth ``alpha = m0 m4 / m2^2``.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.fft import rfft_weights, wavenumbers
from .laws import positive_number

# Angular factors int_0^{2 pi} cos^n(theta) d theta for n = 0, 2, 4: they turn the
# radial integrals of an isotropic 2-D spectrum into moments of a 1-D cross-section.
_COS_INTEGRALS = {0: 2.0 * math.pi, 2: math.pi, 4: 3.0 * math.pi / 4.0}


# ------------------------------------------------------------------ spectral moments
def check_band(k_l, k_s, hurst) -> tuple[float, float, float]:
    """``(k_l, k_s, H)`` as floats, checked ``0 < k_l < k_s`` and ``0 <= H <= 1``; else a ValueError."""
    kl, ks, h = float(k_l), float(k_s), float(hurst)
    if not (np.isfinite(kl) and np.isfinite(ks)) or not (0.0 < kl < ks):
        raise ValueError(f"cutoffs must satisfy 0 < k_l < k_s, got k_l={k_l!r}, k_s={k_s!r}")
    if not np.isfinite(h) or not (0.0 <= h <= 1.0):
        raise ValueError(f"hurst (H) must lie in [0, 1], got {hurst!r}")
    return kl, ks, h


def _radial_integral(power: float, a: float, b: float) -> float:
    """``int_a^b k^power dk``, with the logarithm at ``power = -1`` (H = 0 or H = 1)."""
    if abs(power + 1.0) < 1e-12:
        return math.log(b / a)
    return (b ** (power + 1.0) - a ** (power + 1.0)) / (power + 1.0)


def _normalise(moments: dict[str, float], rms_slope, rms_height) -> dict[str, float]:
    if rms_slope is not None and rms_height is not None:
        raise ValueError("give at most one of rms_slope or rms_height")
    scale = 1.0
    if rms_slope is not None:
        scale = positive_number("rms_slope", rms_slope) ** 2 / (2.0 * moments["m2"])
    elif rms_height is not None:
        scale = positive_number("rms_height", rms_height) ** 2 / moments["m0"]
    m0, m2, m4 = (scale * moments[k] for k in ("m0", "m2", "m4"))
    return {
        "rms_height": math.sqrt(m0),
        "rms_slope": math.sqrt(2.0 * m2),
        "m0": m0,
        "m2": m2,
        "m4": m4,
        "alpha": nayak_alpha(m0, m2, m4),
    }


def power_law_moments(k_l: float, k_s: float, hurst: float, *, length: float = 1.0,
                      rms_slope: float | None = None,
                      rms_height: float | None = None) -> dict[str, float]:
    """Profile spectral moments of the ideal isotropic power-law spectrum, in closed form.

    The 2-D spectrum is ``C(k) = c |k|^(-2(1+H))`` for ``k_l <= |k| <= k_s`` and zero
    elsewhere, with the modes treated as a continuum of density one per unit area of
    the ``(k_x, k_y)`` mode-number plane. With ``q = 2 pi k / L`` and
    ``I_n = int_0^{2pi} cos^n(theta) d theta`` (``2 pi, pi, 3 pi / 4``):

    - ``m0 = <h^2>        = c I_0            int k^(-1-2H) dk``
    - ``m2 = <(dh/dx)^2>  = c I_2 (2pi/L)^2 int k^(1-2H)  dk``
    - ``m4 = <(h_xx)^2>   = c I_4 (2pi/L)^4 int k^(3-2H)  dk``

    (integrals from ``k_l`` to ``k_s``; a logarithm where the exponent is -1). These are
    moments of a 1-D cross-section (Nayak's ``m_i``), as returned by
    :func:`roughcontact.surfaces.synthetic.spectral_moments`; the rms slope is ``sqrt(2 m2)``.

    Parameters
    ----------
    k_l, k_s : float
        Cutoff mode numbers ``L / lambda``, ``0 < k_l < k_s``.
    hurst : float
        Hurst exponent H in [0, 1].
    length : float
        Side ``L`` of the domain (> 0) [u].
    rms_slope, rms_height : float, optional
        At most one: fixes ``c`` so that ``sqrt(2 m2)`` [-] or ``sqrt(m0)`` [u] takes this
        value. With neither, ``c = 1`` (power per mode ``|k|^(-2(1+H))`` [u^2]).

    Returns
    -------
    dict of str to float
        ``rms_height`` [u], ``rms_slope`` [-], ``m0`` [u^2], ``m2`` [-], ``m4`` [u^-2],
        ``alpha`` [-] (Nayak's ``m0 m4 / m2^2``, independent of ``c`` and ``L``).
    """
    kl, ks, h = check_band(k_l, k_s, hurst)
    q = 2.0 * math.pi / positive_number("length", length)
    raw = {
        "m0": _COS_INTEGRALS[0] * _radial_integral(-1.0 - 2.0 * h, kl, ks),
        "m2": _COS_INTEGRALS[2] * q**2 * _radial_integral(1.0 - 2.0 * h, kl, ks),
        "m4": _COS_INTEGRALS[4] * q**4 * _radial_integral(3.0 - 2.0 * h, kl, ks),
    }
    return _normalise(raw, rms_slope, rms_height)


def discrete_power_law_moments(n: int, k_l: float, k_s: float, hurst: float, *,
                               length: float = 1.0, rms_slope: float | None = None,
                               rms_height: float | None = None) -> dict[str, float]:
    """Profile spectral moments of the power-law spectrum summed over the grid's modes.

    Same spectrum as :func:`power_law_moments`, but summed over the integer modes
    ``(k_x, k_y)`` of an ``n x n`` periodic grid with ``k_l <= |k| <= k_s`` (the exact
    mode set of :func:`roughcontact.surfaces.synthetic.psd_filter`), and with the x/y-averaged
    derivatives of :func:`roughcontact.surfaces.synthetic.spectral_moments`. A surface whose Fourier
    amplitudes equal ``sqrt(C)`` mode by mode has these moments to round-off; a surface
    from :func:`~roughcontact.surfaces.synthetic.generate_surface` has them in expectation (its
    white noise gives each mode a random chi-square weight).

    Parameters
    ----------
    n : int
        Grid points per side (>= 4); ``k_s`` must be <= n/2.
    k_l, k_s : float
        Cutoff mode numbers, ``0 < k_l < k_s <= n/2``.
    hurst : float
        Hurst exponent H in [0, 1].
    length : float
        Side ``L`` (> 0) [u].
    rms_slope, rms_height : float, optional
        At most one, as in :func:`power_law_moments`.

    Returns
    -------
    dict of str to float
        Same keys and units as :func:`power_law_moments`.
    """
    if not isinstance(n, (int, np.integer)) or n < 4:
        raise ValueError(f"n (grid points per side) must be an integer >= 4, got {n!r}")
    kl, ks, h = check_band(k_l, k_s, hurst)
    if ks > n / 2:
        raise ValueError(f"k_s must be <= n/2 = {n / 2} (Nyquist), got k_s={k_s!r}")
    L = positive_number("length", length)
    # The band's modes all lie on a grid of m <= n points with |k| <= k_s < m/2 - 1 (no Nyquist mode): the
    # same terms, summed over m^2 instead of n^2 modes (issue 61: N = 4096 took seconds a call).
    m = 2 * (math.floor(ks) + 2)
    m = m if m <= n else n
    kx, ky = wavenumbers(m, 1.0)
    k = np.hypot(kx, ky)
    band = (k >= kl) & (k <= ks)
    if not band.any():
        raise ValueError(f"no integer mode has k_l={k_l} <= |k| <= k_s={k_s} on a {n}x{n} grid")
    with np.errstate(divide="ignore"):
        power = np.where(band, np.where(k > 0, k, 1.0) ** (-2.0 * (1.0 + h)), 0.0)
    power = rfft_weights(m) * power
    qx2 = (2.0 * math.pi * kx / L) ** 2
    qy2 = (2.0 * math.pi * ky / L) ** 2
    raw = {
        "m0": float(power.sum()),
        "m2": float(0.5 * ((qx2 + qy2) * power).sum()),
        "m4": float(0.5 * ((qx2**2 + qy2**2) * power).sum()),
    }
    return _normalise(raw, rms_slope, rms_height)


def nayak_alpha(m0, m2, m4):
    """Nayak's bandwidth parameter ``alpha = m0 m4 / m2^2`` [-].

    Use *profile* moments (those of a 1-D cross-section, Longuet-Higgins 1957, Nayak
    1971): ``alpha >= 1.5`` for an isotropic Gaussian surface. Feeding areal moments
    (``<h^2>, <|grad h|^2>, <(lap h)^2>``, see :func:`areal_moments`) gives ``2/3`` of it.

    Parameters
    ----------
    m0, m2, m4 : float or array_like (broadcastable)
        Moments (> 0) [u^2], [-], [u^-2].

    Returns
    -------
    float or numpy.ndarray
        ``alpha`` [-].
    """
    a0, a2, a4 = (np.asarray(v, dtype=float) for v in (m0, m2, m4))
    for name, v in (("m0", a0), ("m2", a2), ("m4", a4)):
        if not np.all(np.isfinite(v)) or np.any(v <= 0):
            raise ValueError(f"{name} must be finite and > 0, got {v!r}")
    out = a0 * a4 / a2**2
    return float(out) if out.ndim == 0 else out


def areal_moments(m0: float, m2: float, m4: float) -> tuple[float, float, float]:
    """Areal moments of an isotropic surface from its profile moments.

    ``M0 = <h^2> = m0``, ``M2 = <|grad h|^2> = 2 m2``, ``M4 = <(lap h)^2> = (8/3) m4``:
    the angular factors are ``int cos^2 = pi`` against ``2 pi`` and ``int cos^4 = 3 pi / 4``
    against ``2 pi``. Hence ``M0 M4 / M2^2 = (2/3) m0 m4 / m2^2``.

    Parameters
    ----------
    m0, m2, m4 : float
        Profile moments (> 0) [u^2], [-], [u^-2].

    Returns
    -------
    tuple of float
        ``(M0 [u^2], M2 [-], M4 [u^-2])``.
    """
    nayak_alpha(m0, m2, m4)  # same validation
    return float(m0), 2.0 * float(m2), 8.0 / 3.0 * float(m4)


def power_law_alpha(k_l: float, k_s: float, hurst: float, *, dimension: int = 2) -> float:
    """Nayak's ``alpha`` of the ideal continuous power-law spectrum (closed form) [-].

    Parameters
    ----------
    k_l, k_s : float
        Cutoff mode numbers, ``0 < k_l < k_s``.
    hurst : float
        Hurst exponent in [0, 1].
    dimension : {2, 1}
        2: a cross-section of the isotropic surface (:func:`power_law_moments`); 1: a profile whose
        own spectrum is the power law, ``C(k) ~ |k|^(-1-2H)`` with one mode per unit ``k``
        (:func:`roughcontact.surfaces.synthetic.generate_profile`). Both have the same radial
        integrals; the surface's moments carry the angular factors ``I_0, I_2, I_4`` and the
        profile's do not, so the profile's alpha is the surface's times ``I_2^2 / (I_0 I_4) = 2/3``.

    Returns
    -------
    float
        ``m0 m4 / m2^2``; depends on ``k_s / k_l`` and H only. A narrow band tends to 3/2 (surface)
        and 1 (profile: one sinusoid).

    Examples
    --------
    >>> round(power_law_alpha(16, 32, 0.8), 4), round(power_law_alpha(16, 32, 0.8, dimension=1), 4)
    (1.7552, 1.1701)
    """
    alpha = power_law_moments(k_l, k_s, hurst)["alpha"]
    if dimension == 2:
        return alpha
    if dimension == 1:
        return alpha * _COS_INTEGRALS[2] ** 2 / (_COS_INTEGRALS[0] * _COS_INTEGRALS[4])
    raise ValueError(f"dimension must be 1 (a profile) or 2 (a surface), got {dimension!r}")
