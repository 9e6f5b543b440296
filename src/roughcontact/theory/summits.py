"""Nayak's (1971) summit statistics of a Gaussian isotropic surface, and the elliptic Hertz factors of a summit.

The building blocks of the finite-load asperity theories (:mod:`roughcontact.theory.asperity`):
summit density, the joint density of summit height and curvatures, and the factors of the
exact elliptic Hertz contact of one summit (Bush, Gibson & Thomas 1975).
"""

from __future__ import annotations

import math
import numbers

import numpy as np
from scipy.special import elliprd, elliprf

#: Smallest Nayak bandwidth of an isotropic Gaussian surface (a ring spectrum) [-].
NAYAK_ALPHA_MIN = 1.5


#: The two asperity models: exact elliptic Hertz (BGT 1975), geometric-mean sphere (Greenwood 2006).
ASPERITY_MODELS = ("bgt", "greenwood")


SQRT_2PI = math.sqrt(2.0 * math.pi)


# --------------------------------------------------------------------------- checks
def checked_alpha(alpha, *, strict: bool = False) -> float:
    """Nayak's alpha as a float, >= 3/2 (> 3/2 when ``strict``), else a ValueError."""
    bound = f"{'>' if strict else '>='} {NAYAK_ALPHA_MIN}"
    msg = (f"alpha (Nayak's bandwidth m0 m4 / m2^2 of profile moments) must be a finite real number "
           f"{bound}")
    if not isinstance(alpha, numbers.Real) or isinstance(alpha, (bool, np.bool_)):
        raise ValueError(f"{msg}, got {alpha!r}")
    a = float(alpha)
    if not math.isfinite(a) or a < NAYAK_ALPHA_MIN or (strict and a == NAYAK_ALPHA_MIN):
        raise ValueError(f"{msg}, got {alpha!r}")
    return a


def checked_model(model) -> str:
    """An asperity model's name, lower-cased and one of :data:`ASPERITY_MODELS`; else a ValueError."""
    m = model.lower() if isinstance(model, str) else model
    if m not in ASPERITY_MODELS:
        raise ValueError(f"model must be one of {ASPERITY_MODELS}, got {model!r}")
    return m


def real_array(name: str, value, lo: float, hi: float, note: str = "") -> np.ndarray:
    """``value`` as a float array, finite and within ``[lo, hi]``; else a ValueError naming ``name`` (and ``note``)."""
    msg = f"{name}{note} must be finite and lie in [{lo:.6g}, {hi:.6g}], got {value!r}"
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(msg) from None
    if not np.all(np.isfinite(arr)) or np.any(arr < lo) or np.any(arr > hi):
        raise ValueError(msg)
    return arr


def positive_scalar(name: str, value) -> float:
    """``float(value)``, finite and > 0; else a ValueError naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


# ------------------------------------------------------------- summit statistics
def nayak_summit_density(m2, m4) -> float:
    """Number of summits per unit area ``D = m4 / (6 pi sqrt(3) m2)`` (Nayak 1971) [u^-2].

    Parameters
    ----------
    m2, m4 : float
        Profile moments ``<(dh/dx)^2>`` [-] and ``<(d2h/dx2)^2>`` [u^-2] (> 0).

    Returns
    -------
    float
        Summit density [u^-2]; ``alpha / (6 pi sqrt(3))`` in units ``m0 = m2 = 1``.
    """
    return positive_scalar("m4", m4) / (6.0 * math.pi * math.sqrt(3.0) * positive_scalar("m2", m2))


def nayak_summit_pdf(xi, t, s, alpha) -> np.ndarray:
    """Joint pdf of summit height, mean curvature and curvature difference (note, section 2.3).

    ``f(xi, t, s) = sqrt(3) (t^2 - s^2) s exp(-s^2/2) phi_2(xi, t)`` on ``0 <= s < t``, zero
    elsewhere, where ``phi_2`` is the bivariate normal density with ``var xi = 1``,
    ``var t = 2``, ``cov = sqrt(3/alpha)``. Normalised to 1 over summits.

    Parameters
    ----------
    xi : array_like
        Summit height over the mean plane of heights, in units of ``sqrt(m0)`` [-].
    t, s : array_like
        ``(kappa_1 + kappa_2)/2`` and ``(kappa_1 - kappa_2)/2`` in units of
        ``sqrt(m4/3)`` [-] (``kappa_i`` principal curvatures of ``-h``).
    alpha : float
        Nayak's bandwidth, ``> 3/2`` (at 3/2 the density is singular: ``t = sqrt(2) xi``).

    Returns
    -------
    numpy.ndarray, broadcast shape of the inputs
        Probability density [-].
    """
    a = checked_alpha(alpha, strict=True)
    xi, t, s = (np.asarray(v, dtype=float) for v in (xi, t, s))
    inside = (s >= 0) & (s < t)
    shape = math.sqrt(3.0) * (t * t - s * s) * s * np.exp(-0.5 * s * s)
    return np.where(inside, shape * _phi2(xi, t, a), 0.0)


def nayak_summit_pdf_xi_t(xi, t, alpha) -> np.ndarray:
    """Nayak's (1971) joint pdf of summit height and mean curvature (note, section 2.3).

    ``f(xi, t) = sqrt(3)/(2 pi) sqrt(C1) (t^2 - 2 + 2 exp(-t^2/2))
    exp(-C1 (xi^2 - sqrt(3/alpha) xi t + t^2/2))`` for ``t > 0`` (zero otherwise), with
    ``C1 = alpha / (2 alpha - 3)``: :func:`nayak_summit_pdf` integrated over ``s``.

    Parameters
    ----------
    xi, t : array_like
        Reduced summit height and mean curvature, as in :func:`nayak_summit_pdf` [-].
    alpha : float
        Nayak's bandwidth, ``> 3/2``.

    Returns
    -------
    numpy.ndarray, broadcast shape of the inputs
        Probability density [-].
    """
    a = checked_alpha(alpha, strict=True)
    xi, t = (np.asarray(v, dtype=float) for v in (xi, t))
    c1 = a / (2.0 * a - 3.0)
    tt = np.where(t > 0, t, 0.0)
    shape = tt * tt - 2.0 + 2.0 * np.exp(-0.5 * tt * tt)  # -> t^4/4 at small t
    small = tt < 1e-3
    shape = np.where(small, tt**4 / 4.0 - tt**6 / 24.0, shape)
    dens = math.sqrt(3.0) / (2.0 * math.pi) * math.sqrt(c1) * shape \
        * np.exp(-c1 * (xi * xi - math.sqrt(3.0 / a) * xi * t + 0.5 * t * t))
    return np.where(t > 0, dens, 0.0)


def _phi2(xi, t, a):
    det = 2.0 - 3.0 / a
    q = (2.0 * xi * xi - 2.0 * math.sqrt(3.0 / a) * xi * t + t * t) / det
    return np.exp(-0.5 * q) / (2.0 * math.pi * math.sqrt(det))


# ------------------------------------------------------------------ Hertz factors
def _kprime(lam: np.ndarray) -> np.ndarray:
    """Axis ratio ``k' = b/a`` of the elliptic Hertz contact for curvature ratio ``lam >= 1``.

    Solves ``lam = R_D(0, 1, k'^2) / R_D(0, k'^2, 1)`` by bisection in ``ln k'`` on
    ``[ln(1/(2 lam)), 0]`` (``lam`` decreases monotonically in ``k'``; ``k' ~ lam^(-2/3)``
    at moderate and ``> 1/(2 lam)`` at any ellipticity).
    """
    lo = np.log(0.5 / lam)
    hi = np.zeros_like(lam)
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        k2 = np.exp(2.0 * mid)
        too_round = elliprd(0.0, 1.0, k2) / elliprd(0.0, k2, 1.0) < lam  # k' too large
        hi = np.where(too_round, mid, hi)
        lo = np.where(too_round, lo, mid)
    return np.exp(0.5 * (lo + hi))


def hertz_elliptic_factors(lam) -> tuple[np.ndarray, np.ndarray]:
    """Area and load of an elliptic Hertz contact relative to the geometric-mean sphere.

    A rigid flat pressed by ``delta`` into an elastic summit of principal curvatures
    ``kappa_1 >= kappa_2 > 0`` makes a contact of area ``pi delta Phi_A / sqrt(kappa_1 kappa_2)``
    carrying ``F = 4/3 E* delta^(3/2) (kappa_1 kappa_2)^(-1/4) Phi_F`` (note, section 3.1;
    Johnson 1985, ch. 4), with the Carlson forms
    ``Phi_A = 2 sqrt(lam) k' R_D(0, k'^2, 1) / (3 K)`` and
    ``Phi_F = pi/sqrt(2) lam^(1/4) [R_D(0, k'^2, 1)/(3 K)]^(1/2) / K``, ``K = R_F(0, k'^2, 1)``,
    where ``k' = b/a`` solves ``lam = R_D(0, 1, k'^2)/R_D(0, k'^2, 1)``. ``Phi = 1`` is the
    geometric-mean sphere (Greenwood 2006).

    Parameters
    ----------
    lam : array_like
        Curvature ratio ``kappa_1 / kappa_2 >= 1`` [-].

    Returns
    -------
    (phi_A, phi_F) : tuple of numpy.ndarray, shape of ``lam``
        Area and load factors [-] (``phi_A <= 1 <= phi_F``).
    """
    lam = np.asarray(lam, dtype=float)
    if not np.all(np.isfinite(lam)) or np.any(lam < 1.0):
        raise ValueError(f"lam (curvature ratio kappa_1/kappa_2) must be finite and >= 1, got {lam!r}")
    kp = _kprime(np.atleast_1d(lam))
    k2 = kp * kp
    rd = elliprd(0.0, k2, 1.0)
    big_k = elliprf(0.0, k2, 1.0)
    lam1 = np.atleast_1d(lam)
    phi_a = 2.0 * np.sqrt(lam1) * kp * rd / (3.0 * big_k)
    phi_f = math.pi / math.sqrt(2.0) * lam1**0.25 * np.sqrt(rd / (3.0 * big_k)) / big_k
    return phi_a.reshape(lam.shape), phi_f.reshape(lam.shape)
