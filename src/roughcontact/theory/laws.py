"""Analytical laws of rough contact: the small-load asymptotes, Persson's curve and the contact evolution law (CEL).

Everything here is a pure function of its arguments (no I/O). Pressures ``p0`` and the contact
modulus ``E*`` share one pressure unit; ``h'`` is the rms slope ``sqrt(<|grad h|^2>)`` [-]; ``a = A/A0``
is the real contact-area fraction [-].

- Small-load asymptotes ``A/A0 = kappa p0 / (h' E*)`` with ``kappa_BGT = sqrt(2 pi)``
  (Bush, Gibson & Thomas 1975, also Greenwood 2006 and Nayak-Thomas in the limit
  ``A/A0 -> 0``) and ``kappa_P = sqrt(8 / pi)`` (Persson 2001).
- Persson's full curve ``A/A0 = erf(sqrt(2) p0 / (E* h'))``.
- The CEL of Yastrebov, Anciaux & Molinari (2012), its inverse, the effective ``kappa(A/A0)``
  it implies and the power law for ``d pbar / d p0``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import erf

#: Small-load slope of asperity models (BGT 1975, Greenwood 2006), ``sqrt(2 pi)`` [-].
KAPPA_BGT = math.sqrt(2.0 * math.pi)


#: Small-load slope of Persson's theory (2001), ``sqrt(8 / pi)`` [-].
KAPPA_PERSSON = math.sqrt(8.0 / math.pi)


# --------------------------------------------------------------------------- checks
def positive_number(name: str, value) -> float:
    """``float(value)``, finite and > 0; else a ValueError naming ``name``."""
    v = float(value)
    if not np.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def _cel_constants(kappa, mu, beta) -> tuple[float, float, float]:
    k = positive_number("kappa", kappa)
    m = float(mu)
    if not np.isfinite(m) or not (0.0 < m < 1.0):
        raise ValueError(f"mu must lie in the open interval (0, 1), got {mu!r}")
    b = positive_number("beta", beta)
    return k, m, b


def nonnegative_array(name: str, value) -> np.ndarray:
    """``value`` as a float array, finite and >= 0 everywhere; else a ValueError naming ``name``."""
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
    p = nonnegative_array("p0", p0)
    scale = positive_number("rms_slope", rms_slope) * positive_number("e_star", e_star)
    return positive_number("kappa", kappa) * p / scale


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
    p = nonnegative_array("p0", p0)
    return erf(math.sqrt(2.0) * p / (positive_number("e_star", e_star) * positive_number("rms_slope", rms_slope)))


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
    p = nonnegative_array("p0", p0)
    x = k * p / (positive_number("rms_slope", rms_slope) * positive_number("e_star", e_star))
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
    scale = positive_number("rms_slope", rms_slope) * positive_number("e_star", e_star) / k
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
