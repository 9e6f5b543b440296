"""Analytic references for profiles: contact of a 1-D rough surface (plane strain, a line scan or a generated
profile) with an elastic half-plane.

What carries over from the maps, and what does not:

- **Persson's theory applies.** It follows the variance of the contact pressure as roughness is added and
  treats ``p = 0`` as an absorbing boundary (Persson 2001, J. Chem. Phys. 115, 3840); neither step depends
  on the dimension. In full contact the plane-strain pressure of a periodic profile is exactly
  ``p(x) = p0 + (E*/2) F^-1[|q| h_hat](x)`` (the half-plane's surface compliance ``2 / (E* |q|)``, as in
  the 2-D cell of :mod:`roughcontact.theory.full_contact`), a Hilbert transform of the slope, which keeps its
  variance: ``sigma_p^2 = (E*/2)^2 <(dh/dx)^2>``. Persson's
  ``A/A0 = erf(p0 / (sqrt(2) sigma_p)) = erf(sqrt(2) p0 / (E* h'))`` then holds with ``h'`` the
  *profile's* rms slope sqrt(<(dh/dx)^2>) (:func:`persson_area_profile`); its small-load slope is
  ``sqrt(8 / pi)`` (:data:`KAPPA_PERSSON_PROFILE`), the 2-D value with the 1-D slope.
- **No constant kappa is known for line contacts.** Van Dokkum, Khajeh Salehani, Irani & Nicola (2018,
  Tribol. Lett. 66, 115; Green's function molecular dynamics) find that for line contacts kappa =
  (A/A0) / (p0 / (E* h')) is not a constant as A/A0 -> 0: it depends on the load and on H; only with the
  rms slope measured over the contact itself does linearity return, with a line/surface ratio of about 0.9.
  So no asymptote is given here: the pipeline compares a profile's kappa with Persson's numerically.
  Measured (the ``lines`` scene, 2026-11-28: N = 4096, k_s = 128, k_l in {4, 16}, H in {0.36, 0.84}, 4 seeds,
  periodic): the seed-mean kappa falls with load over A/A0 in [0.01, 0.11], from 3.4-4.2 to 2.5-3.0, well
  above Persson's sqrt(8/pi) = 1.60 and not constant, as van Dokkum et al. report.
- **The paper's CEL constants, BGT and Greenwood do not apply.** Yastrebov, Anciaux & Molinari (2012) fit
  their contact evolution law to 2-D surfaces; Bush, Gibson & Thomas (1975) and Greenwood (2006) are
  asperity models of a 2-D surface's summits (their kappa = sqrt(2 pi) comes from the areal summit
  statistics of Nayak 1973). A profile has peaks, not summits, and its contact spots are intervals; none
  of their constants is a prediction for a profile (:data:`NOT_FOR_PROFILES`).
- **The perimeter correction** (Yastrebov et al. 2017) is derived for a map's pixel boundaries; a profile's
  contact has interval ends, whose pixel bias is not derived here: profiles get no corrected area.

Units: pressures and ``E*`` share one unit; heights and lengths one length unit; ``h'`` is dimensionless.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import erf

from .laws import nonnegative_array, positive_number

#: Small-load slope of Persson's theory for a profile, kappa = sqrt(8 / pi) [-], with h' the profile's rms slope.
KAPPA_PERSSON_PROFILE = math.sqrt(8.0 / math.pi)

#: The 2-D laws that make no prediction for a profile, each with why (shown in figure captions and the docs).
NOT_FOR_PROFILES = {
    "cel": "the CEL's constants (kappa, mu, beta) were fitted by Yastrebov et al. (2012) to 2-D surfaces",
    "bgt": "Bush, Gibson & Thomas's kappa = sqrt(2 pi) comes from a 2-D surface's summit statistics",
    "greenwood": "Greenwood's (2006) asperity model is one of a 2-D surface's summits",
    "perimeter_correction": "the perimeter correction (Yastrebov et al. 2017) is derived for a map's pixels",
}


def persson_area_profile(p0, *, rms_slope: float, e_star: float) -> np.ndarray:
    """Persson's contact length fraction of a profile, ``A/A0 = erf(p0 / (sqrt(2) sigma_p))``.

    ``sigma_p = (E*/2) h'`` is the rms pressure of full contact of a profile of rms slope
    ``h' = sqrt(<(dh/dx)^2>)`` (module docstring), so ``A/A0 = erf(sqrt(2) p0 / (E* h'))``: the 2-D
    formula (:func:`roughcontact.theory.laws.persson_area`) with the profile's slope in place of
    ``sqrt(<|grad h|^2>)``.

    Parameters
    ----------
    p0 : array_like, any shape
        Applied mean pressure per unit length of the profile (>= 0) [pressure unit of ``e_star``].
    rms_slope : float
        The profile's rms slope ``h'`` (> 0) [-].
    e_star : float
        Plane-strain modulus ``E*`` (> 0) [pressure unit].

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        The contact length fraction in [0, 1) [-].
    """
    sigma = 0.5 * positive_number("e_star", e_star) * positive_number("rms_slope", rms_slope)
    return erf(nonnegative_array("p0", p0) / (math.sqrt(2.0) * sigma))


def full_contact_pressure_profile(h, p0: float, e_star: float = 1.0, length: float = 1.0) -> np.ndarray:
    """The exact plane-strain pressure of a periodic profile in full contact, ``p0 + (E*/2) F^-1[|q| h_hat]``.

    Parameters
    ----------
    h : array_like, shape (n,)
        Heights of the rigid profile [length] at ``x = i length / n``; its mean does not matter.
    p0 : float
        Applied mean pressure [pressure unit of ``e_star``].
    e_star : float
        Plane-strain modulus ``E*`` (> 0) [pressure unit].
    length : float
        Period ``L`` (> 0) [length].

    Returns
    -------
    numpy.ndarray, float64, shape (n,)
        Pressure [pressure unit], mean ``p0``: the contact solution wherever it is > 0 everywhere.
    """
    arr = np.asarray(h, dtype=np.float64)
    if arr.ndim != 1 or arr.size < 2 or not np.all(np.isfinite(arr)):
        raise ValueError(f"h must be a 1-D profile of at least 2 finite heights, got shape {arr.shape}")
    if not math.isfinite(float(p0)):
        raise ValueError(f"p0 must be a finite number, got {p0!r}")
    n = arr.size
    q = 2.0 * math.pi * np.abs(np.fft.rfftfreq(n, 1.0 / n)) / positive_number("length", length)
    return float(p0) + np.fft.irfft(np.fft.rfft(arr) * (0.5 * positive_number("e_star", e_star) * q), n)


def full_contact_load_profile(h, e_star: float = 1.0, length: float = 1.0) -> float:
    """The mean pressure at which the last point of a periodic profile touches, ``-min (E*/2) F^-1[|q| h_hat]``
    [pressure unit] (>= 0; 0 for a flat profile): :func:`full_contact_pressure_profile` at ``p0 = 0``."""
    return max(0.0, -float(full_contact_pressure_profile(h, 0.0, e_star, length).min()))
