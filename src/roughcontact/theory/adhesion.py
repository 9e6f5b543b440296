"""Analytical references for adhesive contact: JKR, DMT, Maugis-Dugdale, Johnson's wavy surface.

Pure functions of their arguments. Conventions as :mod:`roughcontact.solver.adhesion`:
``E*`` the plane-strain (contact) modulus [pressure], ``w`` the work of adhesion
[energy / area], forces compressive positive (a pull-off force is returned as a
positive magnitude), ``R`` the sphere radius [length]. Johnson's ``K = 4 E* / 3``.

Contents
--------
- :func:`jkr_pull_off` ``1.5 pi w R`` and :func:`dmt_pull_off` ``2 pi w R``; the JKR force
  and approach against the contact radius (:func:`jkr_force`, :func:`jkr_approach`).
- :func:`tabor_parameter` ``mu_T = (R w^2 / (E*^2 z0^3))^(1/3)`` and
  :func:`maugis_parameter` ``lambda = 2 sigma0 (R / (pi w K^2))^(1/3)``.
- The Maugis-Dugdale transition: :func:`maugis_curve` (force, contact radius and approach
  against ``m = c / a``) and :func:`maugis_pull_off` (the load-controlled pull-off between
  the JKR (``lambda -> inf``: 1.5) and DMT (``lambda -> 0``: 2) limits).
- Johnson (1995), the JKR-type adhesion of a 1-D wavy surface ``h = Delta cos(2 pi x / lam)``:
  :func:`johnson_wavy_alpha`, :func:`johnson_wavy_pressure` (mean pressure against the
  contact half-width ``a``), :func:`johnson_wavy_pull_off` and :func:`johnson_wavy_jump_in`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar


def _positive(name: str, value) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def jkr_pull_off(w: float, radius: float) -> float:
    """JKR pull-off force of a sphere under load control, ``1.5 pi w R`` [force].

    Johnson, Kendall & Roberts (1971), Proc. R. Soc. Lond. A 324, 301-313. Under
    displacement control it is the most tensile force met on the force-approach curve.
    """
    return 1.5 * math.pi * _positive("w", w) * _positive("radius", radius)


def dmt_pull_off(w: float, radius: float) -> float:
    """DMT (Derjaguin) pull-off force of a sphere, ``2 pi w R`` [force].

    Derjaguin, Muller & Toporov (1975), J. Colloid Interface Sci. 53, 314-326: the
    attraction of a rigid sphere touching a flat, whatever the law's shape.
    """
    return 2.0 * math.pi * _positive("w", w) * _positive("radius", radius)


def jkr_force(a, *, radius: float, w: float, e_star: float):
    """JKR load against contact radius ``a`` [length]: ``4 E* a^3 / (3 R) - sqrt(8 pi w E* a^3)``.

    Johnson (1985), Contact Mechanics, section 5.5; compressive positive [force].
    """
    a = np.asarray(a, dtype=float)
    return 4.0 * e_star * a ** 3 / (3.0 * radius) - np.sqrt(8.0 * math.pi * w * e_star * a ** 3)


def jkr_approach(a, *, radius: float, w: float, e_star: float):
    """JKR approach against contact radius: ``a^2 / R - sqrt(2 pi w a / E*)`` [length]."""
    a = np.asarray(a, dtype=float)
    return a ** 2 / radius - np.sqrt(2.0 * math.pi * w * a / e_star)


def tabor_parameter(radius: float, w: float, e_star: float, z0: float) -> float:
    """Tabor's parameter ``mu_T = (R w^2 / (E*^2 z0^3))^(1/3)`` [-].

    Tabor (1977), J. Colloid Interface Sci. 58, 2-13 (with ``E*`` the contact modulus, as
    Greenwood 1997): ``z0`` is the range of the law (the equilibrium spacing, ``rho`` here).
    Large: JKR; small: DMT. For a Maugis-Dugdale law ``lambda = 1.16 mu_T`` with
    ``sigma0 = 1.03 w / z0``; with ``sigma0 = w / z0`` exactly, ``lambda = 1.12 mu_T``.
    """
    r, w, e, z = (_positive(k, v) for k, v in (("radius", radius), ("w", w), ("e_star", e_star), ("z0", z0)))
    return (r * w * w / (e * e * z ** 3)) ** (1.0 / 3.0)


def maugis_parameter(radius: float, w: float, e_star: float, sigma0: float) -> float:
    """Maugis' transition parameter ``lambda = 2 sigma0 (R / (pi w K^2))^(1/3)``, ``K = 4 E*/3`` [-].

    Maugis (1992), J. Colloid Interface Sci. 150, 243-269; Johnson & Greenwood (1997),
    J. Colloid Interface Sci. 192, 326-333, eq. (3). ``sigma0`` the Dugdale stress.
    """
    k = 4.0 * _positive("e_star", e_star) / 3.0
    r, w, s0 = _positive("radius", radius), _positive("w", w), _positive("sigma0", sigma0)
    return 2.0 * s0 * (r / (math.pi * w * k * k)) ** (1.0 / 3.0)


def maugis_curve(lam: float, m):
    """Maugis-Dugdale sphere in reduced units against ``m = c / a > 1`` (``c`` the cohesive-zone edge).

    Maugis (1992), as written by Johnson & Greenwood (1997):

        lam A^2 / 2 [s + (m^2 - 2) atan s] + 4 lam^2 A / 3 [s atan s - m + 1] = 1,  s = sqrt(m^2 - 1)
        P = A^3 - lam A^2 [s + m^2 atan s],           D = A^2 - 4 A lam s / 3

    with ``A = a (K / (pi w R^2))^(1/3)``, ``P = load / (pi w R)``, ``D = approach
    (K^2 / (pi^2 w^2 R))^(1/3)``. Returns ``(A, P, D)`` arrays like ``m``. ``lam -> inf``
    gives JKR (``P = A^3 - sqrt(6 A^3)``), ``lam -> 0`` DMT.
    """
    lam = _positive("lam", lam)
    m = np.asarray(m, dtype=float)
    s = np.sqrt(m * m - 1.0)
    at = np.arctan(s)
    c2 = 0.5 * lam * (s + (m * m - 2.0) * at)
    c1 = 4.0 * lam * lam / 3.0 * (s * at - m + 1.0)
    # positive root of c2 A^2 + c1 A - 1 = 0 (c2, c1 >= 0), written without cancellation
    a = 2.0 / (c1 + np.sqrt(c1 * c1 + 4.0 * c2))
    p = a ** 3 - lam * a * a * (s + m * m * at)
    d = a * a - 4.0 * a * lam * s / 3.0
    return a, p, d


def maugis_pull_off(lam: float) -> float:
    """Load-controlled pull-off of the Maugis-Dugdale sphere, ``-min P`` in units of ``pi w R`` [-].

    Between 1.5 (JKR, ``lam -> inf``) and 2 (DMT, ``lam -> 0``); Maugis (1992), fig. 4.
    Found by minimising :func:`maugis_curve`'s ``P`` over ``log(m - 1)``.
    """
    lam = _positive("lam", lam)
    grid = np.logspace(-8, 4, 2001)
    p = maugis_curve(lam, 1.0 + grid)[1]
    k = int(np.argmin(p))
    lo, hi = math.log(grid[max(k - 1, 0)]), math.log(grid[min(k + 1, grid.size - 1)])
    res = minimize_scalar(lambda x: float(maugis_curve(lam, 1.0 + math.exp(x))[1]), bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-12})
    return -float(min(res.fun, p[k]))


def johnson_wavy_alpha(w: float, wavelength: float, amplitude: float, e_star: float) -> float:
    """Johnson's (1995) adhesion parameter ``alpha = sqrt(2 lam w / (pi^2 E* Delta^2))`` [-].

    For ``alpha > 0.57`` a wavy surface jumps into full contact under zero load.
    """
    lam, w = _positive("wavelength", wavelength), _positive("w", w)
    d, e = _positive("amplitude", amplitude), _positive("e_star", e_star)
    return math.sqrt(2.0 * lam * w / (math.pi ** 2 * e * d * d))


def johnson_wavy_pressure(a, *, wavelength: float, amplitude: float, w: float, e_star: float):
    """Mean pressure of the JKR-type adhesive contact of ``h = Delta cos(2 pi x / lam)`` [pressure].

    Johnson (1995), Int. J. Solids Struct. 32(3/4), 423-430: contact on
    ``|x| < a`` of each period, plane strain,

        pbar = p* sin^2(pi a / lam) - sqrt(2 E* w tan(pi a / lam) / lam),   p* = pi E* Delta / lam

    i.e. ``pbar / p* = sin^2 psi - alpha sqrt(tan psi)``. Westergaard's (1939) non-adhesive
    curve plus the periodic flat-punch load whose edge stress intensity ``K`` meets
    Griffith's ``K^2 / (2 E*) = w``; for ``a << lam`` it is the JKR cylinder,
    ``pi E* a^2 / (4 R) - sqrt(2 pi w E* a)`` per period, ``R = lam^2 / (4 pi^2 Delta)``.
    """
    lam = _positive("wavelength", wavelength)
    psi = math.pi * np.asarray(a, dtype=float) / lam
    p_star = math.pi * e_star * amplitude / lam
    return p_star * np.sin(psi) ** 2 - np.sqrt(2.0 * e_star * w * np.tan(psi) / lam)


#: Largest ``alpha`` with a stable partial contact: ``max 4 sin^1.5 cos^2.5`` (at ``tan^2 psi = 3/5``).
WAVY_ALPHA_MAX = 4.0 * 0.6 ** 0.75 * 0.4 ** 1.25
#: ``alpha`` above which the surface jumps into full contact under zero load, ``3^(3/4) / 4``.
WAVY_ALPHA_SPONTANEOUS = 3.0 ** 0.75 / 4.0


def _wavy_critical(alpha: float, upper: bool) -> tuple[float, float] | None:
    """Critical point of ``f = sin^2 psi - alpha sqrt(tan psi)``: the minimum (``upper=False``) or maximum.

    ``f' = 0`` is ``4 sin^1.5 psi cos^2.5 psi = alpha``; its left side rises to
    :data:`WAVY_ALPHA_MAX` at ``tan^2 psi = 3/5`` and falls back to 0, so there are two roots
    (a local minimum below, a local maximum above) when ``alpha < WAVY_ALPHA_MAX``, else none.
    """
    alpha = _positive("alpha", alpha)
    if alpha >= WAVY_ALPHA_MAX:
        return None
    top = math.atan(math.sqrt(0.6))
    lhs = lambda x: 4.0 * math.sin(x) ** 1.5 * math.cos(x) ** 2.5 - alpha  # noqa: E731
    psi = brentq(lhs, top, math.pi / 2, xtol=1e-15) if upper else brentq(lhs, 0.0, top, xtol=1e-15)
    return psi, math.sin(psi) ** 2 - alpha * math.sqrt(math.tan(psi))


def johnson_wavy_pull_off(alpha: float) -> tuple[float, float] | None:
    """Load-controlled pull-off of the wavy surface: ``(psi, pbar / p*)`` at the curve's local minimum.

    ``psi = pi a / lam`` there; ``pbar / p*`` is negative (tensile). ``None`` for
    ``alpha >= WAVY_ALPHA_MAX`` (no stable partial contact). Johnson (1995), Fig. 3.
    """
    return _wavy_critical(alpha, False)


def johnson_wavy_jump_in(alpha: float) -> tuple[float, float] | None:
    """Load above which a load-controlled contact jumps to full contact: ``(psi, pbar / p*)`` at the local maximum.

    The curve falls to ``-inf`` as ``psi -> pi/2`` (the adhesive term diverges); when this
    maximum is negative (``alpha > WAVY_ALPHA_SPONTANEOUS = 3^(3/4)/4 ~ 0.57``) the surface jumps
    into full contact under zero load. ``None`` for ``alpha >= WAVY_ALPHA_MAX``. Johnson (1995).
    """
    return _wavy_critical(alpha, True)
