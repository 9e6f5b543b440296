"""Finite-load asperity theories: Bush-Gibson-Thomas (1975) and Greenwood (2006).

Both models sum non-interacting Hertz contacts over the summits of an isotropic Gaussian
surface pressed by a rigid flat, with summit heights and principal curvatures drawn from
the exact Longuet-Higgins / Nayak (1971) statistics. They differ only in the Hertz law of
one summit:

- ``"bgt"`` (Bush, Gibson & Thomas 1975): the summit is an elliptic paraboloid and its
  contact is the exact *elliptic* Hertz solution (Johnson 1985, ch. 4);
- ``"greenwood"`` (Greenwood 2006, "simplified elliptic model"): the same summit replaced
  by the sphere of geometric-mean radius ``R_g = (kappa_1 kappa_2)^(-1/2)``.

The formulas, conventions and reference values are those of the project note
``shared/reference/bgt-greenwood.md`` (section numbers below refer to it).

Variables and units
-------------------
- ``m0, m2, m4``: *profile* spectral moments (those of a 1-D cross-section, as in
  :func:`roughcontact.theory.power_law_moments`), units [u^2], [-], [u^-2].
- ``alpha = m0 m4 / m2^2`` [-]: Nayak's bandwidth, ``>= 3/2`` (= 3/2 for a ring spectrum).
- ``xi_d = d / sqrt(m0)`` [-]: separation between the flat and the mean plane of the
  heights (not of the summits), in units of the rms height.
- ``pbar = p0 / (E* h')`` [-]: reduced mean pressure, with ``h' = sqrt(<|grad h|^2>) =
  sqrt(2 m2)`` the rms slope and ``E*`` the Hertz contact modulus
  (``F = 4/3 E* R^(1/2) delta^(3/2)``; ``E/(1-nu^2)`` for a rigid rough body).
- ``A/A0`` [-]: real contact-area fraction. Not clipped: without interaction or
  coalescence the models exceed 1 at large loads (use them for ``A/A0 <~ 0.3``).
- ``kappa = (A/A0) / pbar`` [-]: secant proportionality constant, ``A = kappa F/(E* h')``;
  both models tend to ``sqrt(2 pi)`` as ``xi_d -> inf``, slowly:
  ``1 - kappa/sqrt(2 pi) ~ c alpha / xi_d^2``, ``c ~ 0.175`` (BGT), ``0.085`` (Greenwood).

In reduced form both curves depend on ``alpha`` only (no Hurst exponent, no length).

How the curves are computed
---------------------------
With ``xi = z/sqrt(m0)`` the summit height and ``t`` its mean curvature in units of
``sqrt(m4/3)``, ``(xi, t)`` is bivariate normal (``var xi = 1``, ``var t = 2``,
``cov = sqrt(3/alpha)``), restricted to ``t > 0`` (section 2.3). The curvature difference
``s = t y`` integrates out into shape functions ``W_A(t), W_F(t)`` (section 4.2;
closed form with Kummer's function for Greenwood, Gauss-Legendre over ``y`` with the
elliptic Hertz factors for BGT). Then, using ``t | xi ~ N(sqrt(3/alpha) xi, 2 - 3/alpha)``,

    A/A0 = 1/2 sqrt(alpha/3)               int phi(xi) (xi - xi_d)_+       G_A(xi) dxi,
    pbar = sqrt(2) 3^(1/4) alpha^(3/4)/(9 pi) int phi(xi) (xi - xi_d)_+^(3/2) G_F(xi) dxi,

with ``G_A(xi) = E[t^3 W_A(t) 1(t>0) | xi]`` and ``G_F(xi) = E[t^(7/2) W_F(t) 1(t>0) | xi]``,
``phi`` the standard normal pdf. ``G_A, G_F`` do not depend on ``xi_d``: they are
tabulated once per ``(alpha, model)`` (Gauss-Legendre in ``t`` over +-9 conditional
standard deviations, a cubic spline in ``xi`` on a 0.02 grid; cached) and the outer
integral is done per ``xi_d`` by Gauss-Legendre in ``w`` with ``xi = xi_d + w^2`` (which
removes the endpoint singularity), split at ``xi = 0``. As ``alpha -> 3/2`` the
conditional variance of ``t`` vanishes and ``G(xi)`` tends continuously to its value at
``t = sqrt(2) xi`` (section 2.6), which is used at ``alpha = 3/2`` exactly, so no
degenerate Gaussian is ever integrated. Curves at given load are obtained by Newton's
method in ``xi_d`` on ``ln pbar`` (or ``ln A/A0``), started from a 0.05-step table, with
the exact derivatives ``d A/d xi_d`` and ``d pbar/d xi_d``.

Accuracy: numerical error <~ 1e-9 relative on ``A/A0`` and ``pbar`` (every node count and
step doubled or halved; a brute-force triple integral of Nayak's pdf agrees to 1e-10). The
note's reference tables (two other quadrature routes, confirmed by Monte Carlo) are
reproduced to their last printed digit at ``alpha`` = 1.5, 1.75, 2, 10, 100.

Cost: building the tables of a new ``(alpha, model)`` takes ~0.05 s (plus ~0.1 s once per
process for ``W``); a 200-point curve then takes ~0.01 s.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.special import hyp1f1, roots_legendre

from .summits import SQRT_2PI, checked_alpha, checked_model, hertz_elliptic_factors, positive_scalar, real_array

#: Range of reduced separations ``xi_d = d / sqrt(m0)`` the curves are evaluated on [-].
#: At ``xi_d = -10`` every model has ``A/A0 > 1`` (meaningless without interaction);
#: at ``xi_d = 35``, ``pbar ~ 1e-270`` (near the smallest double).
XI_D_RANGE = (-10.0, 35.0)


# Numerical parameters (accuracy measured against the note's tables and against doubled
# node counts: every one of them is good to ~1e-9 relative or better).
_N_Y = 400  # Gauss-Legendre nodes in theta, y = sin(theta), for the BGT shape functions


_T_MAX = 70.0  # t-table [0, _T_MAX] of W_A, W_F (max t needed: sqrt(2)*37 + 9*sqrt(2) = 65)


_T_STEP = 0.02


_N_T = 64  # Gauss-Legendre nodes for E[. | xi] over +-_T_SIGMAS conditional sd


_T_SIGMAS = 9.0


_XI_STEP = 0.02  # xi-grid of G_A, G_F: [_XI_LO, _XI_HI]


_XI_LO = XI_D_RANGE[0]


_XI_HI = 37.0


_TAIL = 80.0  # outer integral up to xi_max with xi_max^2 - max(xi_d, 0)^2 = _TAIL (e^-40)


_N_W = 64  # Gauss-Legendre nodes per panel of the outer integral (two panels)


_XI_D_STEP = 0.05  # table in xi_d used to start Newton's method


_CHUNK = 4096  # xi_d values per vectorised block


# --------------------------------------------------------- shape functions W(t)
@lru_cache(maxsize=1)
def _shape_splines() -> dict[str, tuple[CubicSpline, CubicSpline]]:
    """Cubic splines of ``W_A(t), W_F(t)`` on ``[0, _T_MAX]`` for both models (section 4.2).

    Greenwood: ``W_A = M(1, 5/2, -t^2/2)/3``, ``W_F = 2/7 M(1, 11/4, -t^2/2)``. BGT: the
    same plus ``int_0^1 (1-y^2)^(1/2 or 3/4) y exp(-t^2 y^2/2) (Phi - 1) dy`` by
    Gauss-Legendre in ``theta`` (``y = sin theta``), which keeps the (small) elliptic
    correction exact where it matters and makes large-``t`` errors negligible.
    """
    t = np.arange(0, round(_T_MAX / _T_STEP) + 1) * _T_STEP
    x = -0.5 * t * t
    wa_g = hyp1f1(1.0, 2.5, x) / 3.0
    wf_g = 2.0 / 7.0 * hyp1f1(1.0, 2.75, x)
    nodes, weights = roots_legendre(_N_Y)
    theta = 0.25 * math.pi * (nodes + 1.0)
    wts = 0.25 * math.pi * weights
    y = np.sin(theta)
    one_minus_y = 2.0 * np.sin(0.5 * (0.5 * math.pi - theta)) ** 2  # 1 - sin(theta), no cancellation
    phi_a, phi_f = hertz_elliptic_factors((1.0 + y) / one_minus_y)
    cos = np.cos(theta)
    gauss = np.exp(-0.5 * np.outer(t * t, y * y))  # (n_t, n_y)
    base = wts * y * cos  # dy = cos(theta) d theta
    wa_b = wa_g + gauss @ (base * cos * (phi_a - 1.0))
    wf_b = wf_g + gauss @ (base * cos**1.5 * (phi_f - 1.0))
    return {
        "greenwood": (CubicSpline(t, wa_g), CubicSpline(t, wf_g)),
        "bgt": (CubicSpline(t, wa_b), CubicSpline(t, wf_b)),
    }


# ------------------------------------------------- conditional moments G_A, G_F
def _xi_grid() -> np.ndarray:
    k0 = round(_XI_LO / _XI_STEP)
    k1 = round(_XI_HI / _XI_STEP)
    return np.arange(k0, k1 + 1) * _XI_STEP  # contains xi = 0 exactly


@lru_cache(maxsize=64)
def _g_splines(alpha: float, model: str) -> tuple[CubicSpline, CubicSpline]:
    """Splines in ``xi`` of ``G_A = E[t^3 W_A 1(t>0) | xi]`` and ``G_F = E[t^3.5 W_F 1(t>0) | xi]``."""
    w_a, w_f = _shape_splines()[model]
    xi = _xi_grid()
    mean = math.sqrt(3.0 / alpha) * xi
    sd = math.sqrt(max(2.0 - 3.0 / alpha, 0.0))

    def h_a(t):
        return t**3 * w_a(t)

    def h_f(t):
        return t**3.5 * w_f(t)

    if sd == 0.0:  # alpha = 3/2: t = sqrt(2) xi deterministically (section 2.6)
        tp = np.maximum(mean, 0.0)
        return CubicSpline(xi, h_a(tp)), CubicSpline(xi, h_f(tp))
    nodes, weights = roots_legendre(_N_T)
    lo = np.maximum(mean - _T_SIGMAS * sd, 0.0)
    hi = np.maximum(mean + _T_SIGMAS * sd, 0.0)
    half = 0.5 * (hi - lo)
    tn = lo[:, None] + half[:, None] * (nodes + 1.0)  # (n_xi, _N_T)
    dens = np.exp(-0.5 * ((tn - mean[:, None]) / sd) ** 2) / (sd * SQRT_2PI)
    wq = half[:, None] * weights * dens
    flat = tn.ravel()
    g_a = np.sum(wq * h_a(flat).reshape(tn.shape), axis=1)
    g_f = np.sum(wq * h_f(flat).reshape(tn.shape), axis=1)
    return CubicSpline(xi, g_a), CubicSpline(xi, g_f)


def _prefactors(alpha: float) -> tuple[float, float]:
    c_a = 0.5 * math.sqrt(alpha / 3.0)
    c_f = math.sqrt(2.0) * 3.0**0.25 / (9.0 * math.pi) * alpha**0.75
    return c_a, c_f


@lru_cache(maxsize=1)
def _outer_rule() -> tuple[np.ndarray, np.ndarray]:
    nodes, weights = roots_legendre(_N_W)
    return 0.5 * (nodes + 1.0), 0.5 * weights  # on [0, 1]


def _integrals(xi_d: np.ndarray, alpha: float, model: str) -> tuple[np.ndarray, ...]:
    """``(A/A0, pbar, dA/dxi_d, dpbar/dxi_d)`` at 1-D ``xi_d`` (within XI_D_RANGE)."""
    g_a, g_f = _g_splines(alpha, model)
    c_a, c_f = _prefactors(alpha)
    u, wu = _outer_rule()
    out = [np.empty_like(xi_d) for _ in range(4)]
    for start in range(0, xi_d.size, _CHUNK):
        xd = xi_d[start:start + _CHUNK, None]
        x0 = np.maximum(xd, 0.0)
        w_max = np.sqrt(np.sqrt(x0 * x0 + _TAIL) - xd)
        w_mid = np.where(xd < 0.0, np.sqrt(np.maximum(-xd, 0.0)), 0.5 * w_max)  # split at xi = 0
        w = np.concatenate([w_mid * u, w_mid + (w_max - w_mid) * u], axis=1)
        jac = np.concatenate([w_mid * wu, (w_max - w_mid) * wu], axis=1) * 2.0 * w  # dxi = 2 w dw
        xi = xd + w * w
        base = jac * np.exp(-0.5 * xi * xi) / SQRT_2PI
        ga = g_a(xi.ravel()).reshape(xi.shape) * base
        gf = g_f(xi.ravel()).reshape(xi.shape) * base
        sl = slice(start, start + _CHUNK)
        out[0][sl] = c_a * np.sum(ga * w * w, axis=1)
        out[1][sl] = c_f * np.sum(gf * w**3, axis=1)
        out[2][sl] = -c_a * np.sum(ga, axis=1)
        out[3][sl] = -1.5 * c_f * np.sum(gf * w, axis=1)
    return tuple(out)


@lru_cache(maxsize=64)
def _xi_d_table(alpha: float, model: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``xi_d`` grid (step 0.05 over XI_D_RANGE) with ``ln A/A0`` and ``ln pbar`` on it."""
    k0, k1 = (round(v / _XI_D_STEP) for v in XI_D_RANGE)
    grid = np.arange(k0, k1 + 1) * _XI_D_STEP
    area, pbar, _, _ = _integrals(grid, alpha, model)
    return grid, np.log(area), np.log(pbar)


# -------------------------------------------------------------------- public API
def asperity_model(xi_d, *, alpha: float, model: str) -> tuple[np.ndarray, np.ndarray]:
    """Area fraction and reduced pressure of the BGT or Greenwood model at a separation.

    Parameters
    ----------
    xi_d : array_like, any shape
        Reduced separation ``d / sqrt(m0)`` between the flat and the mean plane of the
        heights, within :data:`XI_D_RANGE` = [-10, 35] [-].
    alpha : float
        Nayak's bandwidth ``m0 m4 / m2^2`` (profile moments), ``>= 3/2`` [-].
    model : {"bgt", "greenwood"}
        Exact elliptic Hertz per summit (BGT 1975) or the geometric-mean sphere
        (Greenwood 2006).

    Returns
    -------
    (area_fraction, pbar) : tuple of numpy.ndarray, shape of ``xi_d``
        ``A/A0`` [-] (not clipped at 1) and ``p0 / (E* h')`` [-]; both decrease with ``xi_d``.
    """
    a, m = checked_alpha(alpha), checked_model(model)
    xd = real_array("xi_d", xi_d, *XI_D_RANGE)
    area, pbar, _, _ = _integrals(xd.ravel(), a, m)
    return area.reshape(xd.shape), pbar.reshape(xd.shape)


def _invert(target: np.ndarray, alpha: float, model: str, which: int) -> tuple[np.ndarray, np.ndarray]:
    """``(A/A0, pbar)`` where quantity ``which`` (0: area, 1: pbar) equals ``target`` (> 0)."""
    grid, ln_a, ln_p = _xi_d_table(alpha, model)
    ln_q = (ln_a, ln_p)[which]
    ln_t = np.log(target)
    xd = np.interp(-ln_t, -ln_q, grid)  # ln q decreases with xi_d
    for _ in range(8):
        vals = _integrals(xd, alpha, model)
        q, dq = vals[which], vals[which + 2]
        step = (np.log(q) - ln_t) / (dq / q)
        xd = np.clip(xd - step, *XI_D_RANGE)
        if np.max(np.abs(step)) < 1e-12:
            break
    area, pbar, _, _ = _integrals(xd, alpha, model)
    return area, pbar


def _at_load(values: np.ndarray, alpha: float, model: str, which: int) -> tuple[np.ndarray, np.ndarray]:
    """``(A/A0, pbar)`` at given area (``which = 0``) or pbar (1); tiny values use kappa(35)."""
    grid, ln_a, ln_p = _xi_d_table(alpha, model)
    ln_q = (ln_a, ln_p)[which]
    flat = values.ravel()
    area, pbar = np.zeros_like(flat), np.zeros_like(flat)
    pos = flat > 0
    tiny = pos & (flat < math.exp(ln_q[-1]))
    regular = pos & ~tiny
    if regular.any():
        area[regular], pbar[regular] = _invert(flat[regular], alpha, model, which)
    if tiny.any():
        # below pbar(xi_d = 35) ~ 1e-270: the curve is linear, A = kappa(35) pbar.
        kappa_end = math.exp(ln_a[-1] - ln_p[-1])
        if which == 0:
            area[tiny], pbar[tiny] = flat[tiny], flat[tiny] / kappa_end
        else:
            area[tiny], pbar[tiny] = kappa_end * flat[tiny], flat[tiny]
    return area.reshape(values.shape), pbar.reshape(values.shape)


def _load_range(alpha: float, model: str, which: int) -> float:
    grid, ln_a, ln_p = _xi_d_table(alpha, model)
    return math.exp((ln_a, ln_p)[which][0])


def asperity_reduced_area(pbar, *, alpha: float, model: str) -> np.ndarray:
    """``A/A0`` of the BGT or Greenwood model at a given reduced pressure ``p0 / (E* h')``.

    ``xi_d`` is eliminated by Newton's method on ``ln pbar(xi_d)`` (exact derivative),
    started from a 0.05-step table; converged to ~1e-12 in ``xi_d``.

    Parameters
    ----------
    pbar : array_like, any shape
        ``p0 / (E* h')``, ``>= 0`` and at most ``pbar(xi_d = -10)`` (where ``A/A0 > 1``) [-].
    alpha : float
        Nayak's bandwidth (profile moments), ``>= 3/2`` [-].
    model : {"bgt", "greenwood"}
        See :func:`asperity_model`.

    Returns
    -------
    numpy.ndarray, shape of ``pbar``
        ``A/A0`` [-]; 0 where ``pbar = 0``.
    """
    a, m = checked_alpha(alpha), checked_model(model)
    p = real_array("pbar", pbar, 0.0, _load_range(a, m, 1), " (= p0/(E* h'))")
    return _at_load(p, a, m, 1)[0]


def asperity_reduced_pressure(area_fraction, *, alpha: float, model: str) -> np.ndarray:
    """Inverse of :func:`asperity_reduced_area`: ``p0 / (E* h')`` at a given ``A/A0``.

    Parameters
    ----------
    area_fraction : array_like, any shape
        ``A/A0``, ``>= 0`` and at most its value at ``xi_d = -10`` (> 1) [-].
    alpha : float
        Nayak's bandwidth (profile moments), ``>= 3/2`` [-].
    model : {"bgt", "greenwood"}
        See :func:`asperity_model`.

    Returns
    -------
    numpy.ndarray, shape of ``area_fraction``
        ``pbar`` [-]; 0 where ``A/A0 = 0``.
    """
    a, m = checked_alpha(alpha), checked_model(model)
    af = real_array("area_fraction", area_fraction, 0.0, _load_range(a, m, 0))
    return _at_load(af, a, m, 0)[1]


def asperity_max_load(*, alpha: float, rms_slope: float, e_star: float, model: str) -> float:
    """The largest mean pressure ``p0`` [pressure unit of ``e_star``] the BGT / Greenwood model covers.

    Its table ends at ``xi_d = -10`` (the separation at which ``A/A0`` reaches 1): above this load
    the model has no answer, and :func:`asperity_area` refuses the load.
    """
    a, m = checked_alpha(alpha), checked_model(model)
    return _load_range(a, m, 1) * positive_scalar("rms_slope", rms_slope) * positive_scalar("e_star", e_star)


def asperity_area(p0, *, alpha: float, rms_slope: float, e_star: float, model: str) -> np.ndarray:
    """BGT / Greenwood ``A/A0`` at applied pressure ``p0`` (cf. :func:`~roughcontact.theory.persson_area`).

    Parameters
    ----------
    p0 : array_like, any shape
        Mean pressure ``F / A0`` (>= 0) [pressure unit of ``e_star``].
    alpha : float
        Nayak's bandwidth (profile moments), ``>= 3/2`` [-].
    rms_slope : float
        ``h' = sqrt(<|grad h|^2>) = sqrt(2 m2)`` (> 0) [-].
    e_star : float
        Hertz contact modulus ``E*`` (> 0) [pressure unit].
    model : {"bgt", "greenwood"}
        See :func:`asperity_model`.

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        ``A/A0`` [-].
    """
    a, m = checked_alpha(alpha), checked_model(model)
    scale = positive_scalar("rms_slope", rms_slope) * positive_scalar("e_star", e_star)
    pmax = _load_range(a, m, 1) * scale
    p = real_array("p0", p0, 0.0, pmax, f" (= E* h' pbar; alpha={a:.6g}, model={m!r})")
    return _at_load(p / scale, a, m, 1)[0]


def asperity_kappa(area_fraction=None, *, pbar=None, alpha: float, model: str) -> np.ndarray:
    """Secant ``kappa = (A/A0) / pbar = A E* h' / F`` of the BGT or Greenwood model.

    Give exactly one of ``area_fraction`` (as in :func:`~roughcontact.theory.cel_kappa`) or
    ``pbar``. ``kappa`` increases to ``sqrt(2 pi)`` as the load vanishes (the value returned
    at zero load), slowly: ``1 - kappa / sqrt(2 pi) ~ c alpha / xi_d^2``.

    Parameters
    ----------
    area_fraction : array_like, optional
        ``A/A0`` (>= 0, as in :func:`asperity_reduced_pressure`) [-].
    pbar : array_like, optional, keyword
        ``p0 / (E* h')`` (>= 0, as in :func:`asperity_reduced_area`) [-].
    alpha : float
        Nayak's bandwidth (profile moments), ``>= 3/2`` [-].
    model : {"bgt", "greenwood"}
        See :func:`asperity_model`.

    Returns
    -------
    numpy.ndarray, shape of the given load
        ``kappa`` [-].
    """
    if (area_fraction is None) == (pbar is None):
        raise ValueError("give exactly one of area_fraction or pbar")
    a, m = checked_alpha(alpha), checked_model(model)
    if pbar is None:
        load = real_array("area_fraction", area_fraction, 0.0, _load_range(a, m, 0))
        area, p = _at_load(load, a, m, 0)
    else:
        load = real_array("pbar", pbar, 0.0, _load_range(a, m, 1), " (= p0/(E* h'))")
        area, p = _at_load(load, a, m, 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(load > 0, area / np.where(p > 0, p, 1.0), SQRT_2PI)
