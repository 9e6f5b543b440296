"""Analytical references for the contact of rough surfaces: asymptotes, Persson, the CEL.

Everything here is a pure function of its arguments (no I/O). Conventions follow
:mod:`roughcontact.surface`: wavenumbers ``k`` are mode numbers in cycles per ``L``
(``k = L / lambda``), angular wavenumbers are ``q = 2 pi k / L``, heights and ``L``
share one length unit ``u``; pressures ``p0`` and the contact modulus ``E*`` share one
pressure unit; ``h'`` is the rms slope ``sqrt(<|grad h|^2>)`` [-]; ``a = A/A0`` is the
real contact-area fraction [-].

Contents
--------
- Small-load asymptotes ``A/A0 = kappa p0 / (h' E*)`` with ``kappa_BGT = sqrt(2 pi)``
  (Bush, Gibson & Thomas 1975, also Greenwood 2006 and Nayak-Thomas in the limit
  ``A/A0 -> 0``) and ``kappa_P = sqrt(8 / pi)`` (Persson 2001).
- Persson's full curve ``A/A0 = erf(sqrt(2) p0 / (E* h'))``.
- The contact evolution law (CEL) of Yastrebov, Anciaux & Molinari (2012), its inverse,
  the effective ``kappa(A/A0)`` it implies and the power law for ``d pbar / d p0``.
- Spectral moments of the ideal isotropic power-law spectrum ``C(k) ~ k^(-2(1+H))`` on
  ``k_l <= |k| <= k_s``: in closed form (continuous integrals) and as the discrete sum
  over the integer modes of an ``n x n`` grid (what :func:`~roughcontact.surface.generate_surface`
  actually draws), and Nayak's bandwidth ``alpha = m0 m4 / m2^2``.

Finite-load BGT and Greenwood curves
------------------------------------
The paper's Fig. 2 (``fig:5`` in its source) compares with the curves of Bush, Gibson & Thomas (1975,
exact elliptic Hertz per summit) and of Greenwood (2006, "simplified elliptic model":
geometric-mean-radius sphere per summit) for ``alpha = 2``, both built on Nayak's (1971)
summit statistics. They live in :mod:`roughcontact.asperity` and are re-exported here:
:func:`asperity_model` (``A/A0`` and ``pbar = p0/(E* h')`` at a reduced separation
``xi_d = d/sqrt(m0)``), :func:`asperity_reduced_area` / :func:`asperity_reduced_pressure`
(one at given other), :func:`asperity_area` (dimensional, like :func:`persson_area`),
:func:`asperity_kappa`, the summit statistics :func:`nayak_summit_pdf`,
:func:`nayak_summit_pdf_xi_t`, :func:`nayak_summit_density` and the elliptic Hertz factors
:func:`hertz_elliptic_factors`. Their small-load limit is :data:`KAPPA_BGT`, reached only
slowly (``1 - kappa/sqrt(2 pi) ~ c alpha / xi_d^2``).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import erf

from .asperity import (  # noqa: F401  (re-exported: the finite-load asperity theories)
    ASPERITY_MODELS,
    NAYAK_ALPHA_MIN,
    XI_D_RANGE,
    asperity_area,
    asperity_kappa,
    asperity_max_load,
    asperity_model,
    asperity_reduced_area,
    asperity_reduced_pressure,
    hertz_elliptic_factors,
    nayak_summit_density,
    nayak_summit_pdf,
    nayak_summit_pdf_xi_t,
)
from .fft import rfft_weights, wavenumbers

#: Small-load slope of asperity models (BGT 1975, Greenwood 2006), ``sqrt(2 pi)`` [-].
KAPPA_BGT = math.sqrt(2.0 * math.pi)
#: Small-load slope of Persson's theory (2001), ``sqrt(8 / pi)`` [-].
KAPPA_PERSSON = math.sqrt(8.0 / math.pi)

# Angular factors int_0^{2 pi} cos^n(theta) d theta for n = 0, 2, 4: they turn the
# radial integrals of an isotropic 2-D spectrum into moments of a 1-D cross-section.
_COS_INTEGRALS = {0: 2.0 * math.pi, 2: math.pi, 4: 3.0 * math.pi / 4.0}


# --------------------------------------------------------------------------- checks
def _positive(name: str, value) -> float:
    v = float(value)
    if not np.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def _cel_constants(kappa, mu, beta) -> tuple[float, float, float]:
    k = _positive("kappa", kappa)
    m = float(mu)
    if not np.isfinite(m) or not (0.0 < m < 1.0):
        raise ValueError(f"mu must lie in the open interval (0, 1), got {mu!r}")
    b = _positive("beta", beta)
    return k, m, b


def _nonnegative_array(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ValueError(f"{name} must be finite and >= 0 everywhere, got {value!r}")
    return arr


def _area_fraction_array(name: str, value, upper: float = 1.0) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0) or np.any(arr >= upper):
        raise ValueError(
            f"{name} must be finite and lie in the open interval (0, {upper:.6g}), got {value!r}"
        )
    return arr


# ------------------------------------------------------------------ linear asymptotes
def linear_area(p0, *, kappa: float, rms_slope: float, e_star: float) -> np.ndarray:
    """Small-load asymptote ``A/A0 = kappa p0 / (h' E*)``.

    Parameters
    ----------
    p0 : array_like, any shape
        Applied mean pressure ``F / A0`` (>= 0) [pressure unit of ``e_star``].
    kappa : float
        Proportionality constant (> 0) [-], e.g. :data:`KAPPA_BGT` or :data:`KAPPA_PERSSON`.
    rms_slope : float
        ``h' = sqrt(<|grad h|^2>)`` (> 0) [-].
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        Area fraction ``A/A0`` [-]; not clipped at 1 (it is an asymptote).
    """
    p = _nonnegative_array("p0", p0)
    return _positive("kappa", kappa) * p / (_positive("rms_slope", rms_slope) * _positive("e_star", e_star))


def persson_area(p0, *, rms_slope: float, e_star: float) -> np.ndarray:
    """Persson's (2001) area fraction ``A/A0 = erf(sqrt(2) p0 / (E* h'))``.

    From ``P = erf(p0 / (2 sqrt(G)))`` with ``G = (E*/p0)^2 <|grad h|^2> / 8`` for a
    surface whose whole spectrum is resolved; its small-load slope is
    ``2 sqrt(2) / sqrt(pi) = sqrt(8/pi)`` = :data:`KAPPA_PERSSON`.

    Parameters
    ----------
    p0 : array_like, any shape
        Applied mean pressure (>= 0) [pressure unit of ``e_star``].
    rms_slope : float
        ``h'`` (> 0) [-].
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        ``A/A0`` in [0, 1) [-].
    """
    p = _nonnegative_array("p0", p0)
    return erf(math.sqrt(2.0) * p / (_positive("e_star", e_star) * _positive("rms_slope", rms_slope)))


# ------------------------------------------------------------ contact evolution law
def cel_area(p0, *, kappa: float, mu: float, beta: float, rms_slope: float, e_star: float) -> np.ndarray:
    """Contact evolution law ``A/A0 = (beta + [kappa p0 / (h' E*)]^(mu-1))^(1/(mu-1))``.

    Yastrebov, Anciaux & Molinari (2012), Eq. (2). It integrates
    ``d pbar / d p0 = beta (A0/A)^mu`` from the linear law ``A/A0 = kappa p0/(h' E*)``
    at ``p0 -> 0``; at large ``p0`` it saturates at ``beta^(-1/(1-mu))``
    (:func:`cel_area_limit`), so it is meant for moderate loads only.

    Parameters
    ----------
    p0 : array_like, any shape
        Applied mean pressure (>= 0) [pressure unit of ``e_star``].
    kappa : float
        Small-load constant (> 0) [-].
    mu : float
        Exponent in (0, 1) [-].
    beta : float
        Prefactor (> 0) [-].
    rms_slope : float
        ``h'`` (> 0) [-].
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        ``A/A0`` [-]; exactly 0 where ``p0 = 0``.
    """
    k, m, b = _cel_constants(kappa, mu, beta)
    p = _nonnegative_array("p0", p0)
    x = k * p / (_positive("rms_slope", rms_slope) * _positive("e_star", e_star))
    out = np.zeros_like(x)
    pos = x > 0
    # Written as x (1 + b x^(1-m))^(-1/(1-m)) so that small loads keep full precision.
    xp = x[pos]
    out[pos] = xp * (1.0 + b * xp ** (1.0 - m)) ** (-1.0 / (1.0 - m))
    return out


def cel_pressure(area_fraction, *, kappa: float, mu: float, beta: float, rms_slope: float,
                 e_star: float) -> np.ndarray:
    """Inverse of :func:`cel_area`: ``p0 = (h' E* / kappa) ((A/A0)^(mu-1) - beta)^(1/(mu-1))``.

    Parameters
    ----------
    area_fraction : array_like, any shape
        ``a = A/A0`` in ``(0, beta^(-1/(1-mu)))`` [-], the range the CEL reaches.
    kappa, mu, beta : float
        CEL constants (kappa > 0, 0 < mu < 1, beta > 0) [-].
    rms_slope : float
        ``h'`` (> 0) [-].
    e_star : float
        Contact modulus (> 0) [pressure unit].

    Returns
    -------
    numpy.ndarray, shape of ``area_fraction``
        Applied pressure ``p0`` [pressure unit of ``e_star``].
    """
    k, m, b = _cel_constants(kappa, mu, beta)
    a = _area_fraction_array("area_fraction", area_fraction, upper=cel_area_limit(m, b))
    scale = _positive("rms_slope", rms_slope) * _positive("e_star", e_star) / k
    return scale * a * (1.0 - b * a ** (1.0 - m)) ** (-1.0 / (1.0 - m))


def cel_area_limit(mu: float, beta: float) -> float:
    """Saturation ``lim_{p0 -> inf} A/A0 = beta^(-1/(1-mu))`` of the CEL [-] (often > 1)."""
    _, m, b = _cel_constants(1.0, mu, beta)
    return b ** (-1.0 / (1.0 - m))


def cel_kappa(area_fraction, *, kappa: float, mu: float, beta: float) -> np.ndarray:
    """Effective ``kappa(a) = E* h' / pbar = h' E* a / p0`` implied by the CEL.

    Substituting :func:`cel_pressure` into ``h' E* a / p0`` gives
    ``kappa(a) = kappa a (a^(mu-1) - beta)^(1/(1-mu)) = kappa (1 - beta a^(1-mu))^(1/(1-mu))``,
    which tends to ``kappa`` as ``a -> 0`` like ``kappa (1 - beta a^(1-mu) / (1-mu))``.

    Parameters
    ----------
    area_fraction : array_like, any shape
        ``a = A/A0`` in ``[0, beta^(-1/(1-mu)))`` [-].
    kappa, mu, beta : float
        CEL constants [-].

    Returns
    -------
    numpy.ndarray, shape of ``area_fraction``
        ``kappa(a)`` [-].
    """
    k, m, b = _cel_constants(kappa, mu, beta)
    a = np.asarray(area_fraction, dtype=float)
    upper = cel_area_limit(m, b)
    if not np.all(np.isfinite(a)) or np.any(a < 0) or np.any(a >= upper):
        raise ValueError(
            f"area_fraction must be finite and lie in [0, {upper:.6g}), got {area_fraction!r}"
        )
    return k * (1.0 - b * a ** (1.0 - m)) ** (1.0 / (1.0 - m))


def cel_dpbar_dp0(area_fraction, *, mu: float, beta: float) -> np.ndarray:
    """Power law ``d pbar / d p0 = beta (A0/A)^mu`` behind the CEL [-].

    Parameters
    ----------
    area_fraction : array_like, any shape
        ``a = A/A0`` in (0, 1] [-].
    mu : float
        Exponent in (0, 1) [-].
    beta : float
        Prefactor (> 0) [-].

    Returns
    -------
    numpy.ndarray, shape of ``area_fraction``
        ``d pbar / d p0`` [-].
    """
    _, m, b = _cel_constants(1.0, mu, beta)
    a = np.asarray(area_fraction, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a <= 0) or np.any(a > 1):
        raise ValueError(f"area_fraction must be finite and lie in (0, 1], got {area_fraction!r}")
    return b * a ** (-m)


# ------------------------------------------------------------------ spectral moments
def _check_band(k_l, k_s, hurst) -> tuple[float, float, float]:
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
        scale = _positive("rms_slope", rms_slope) ** 2 / (2.0 * moments["m2"])
    elif rms_height is not None:
        scale = _positive("rms_height", rms_height) ** 2 / moments["m0"]
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
    :func:`roughcontact.surface.spectral_moments`; the rms slope is ``sqrt(2 m2)``.

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
    kl, ks, h = _check_band(k_l, k_s, hurst)
    q = 2.0 * math.pi / _positive("length", length)
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
    mode set of :func:`roughcontact.surface.psd_filter`), and with the x/y-averaged
    derivatives of :func:`roughcontact.surface.spectral_moments`. A surface whose Fourier
    amplitudes equal ``sqrt(C)`` mode by mode has these moments to round-off; a surface
    from :func:`~roughcontact.surface.generate_surface` has them in expectation (its
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
    kl, ks, h = _check_band(k_l, k_s, hurst)
    if ks > n / 2:
        raise ValueError(f"k_s must be <= n/2 = {n / 2} (Nyquist), got k_s={k_s!r}")
    L = _positive("length", length)
    kx, ky = wavenumbers(n, 1.0)
    k = np.hypot(kx, ky)
    band = (k >= kl) & (k <= ks)
    if not band.any():
        raise ValueError(f"no integer mode has k_l={k_l} <= |k| <= k_s={k_s} on a {n}x{n} grid")
    with np.errstate(divide="ignore"):
        power = np.where(band, np.where(k > 0, k, 1.0) ** (-2.0 * (1.0 + h)), 0.0)
    power = rfft_weights(n) * power
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


def power_law_alpha(k_l: float, k_s: float, hurst: float) -> float:
    """Nayak's ``alpha`` of the ideal continuous power-law spectrum (closed form) [-].

    Parameters
    ----------
    k_l, k_s : float
        Cutoff mode numbers, ``0 < k_l < k_s``.
    hurst : float
        Hurst exponent in [0, 1].

    Returns
    -------
    float
        ``m0 m4 / m2^2`` from :func:`power_law_moments`; depends on ``k_s / k_l`` and H only.
    """
    return power_law_moments(k_l, k_s, hurst)["alpha"]
