"""Persson's contact theory beyond the area: pressure distribution, mean gap and contact stiffness.

The surface is given by its discrete spectrum: the angular wavenumbers ``q_k`` [rad / length] of
its nonzero Fourier modes and their powers ``c_k = |h_hat_k|^2`` [length^2] (``h_hat`` the DFT
divided by the number of nodes), so that ``sum c_k = <h^2>`` and ``sum q_k^2 c_k = h'^2``. A
continuous isotropic PSD ``C(q)`` maps onto it by ``2 pi int q C(q) dq -> sum_k c_k``.

- :func:`mode_spectrum`: the expected ``(q_k, c_k)`` of
  :func:`~roughcontact.surfaces.synthetic.generate_surface`.
- :func:`persson_pressure_distribution`: Persson's (2001) ``P(p)`` for a fully resolved spectrum.
- :func:`persson_mean_gap`: the mean interfacial separation ``u(p0)`` of Yang & Persson (2008),
  J. Phys.: Condens. Matter 20, 215214, and Persson (2007), PRL 99, 125502.
- :func:`persson_stiffness`: the normal contact stiffness ``K = -d p0 / d u`` of that ``u(p0)``.
- :func:`mode_weights`, :func:`power_law_terms`: the terms of those sums, on a discrete spectrum (where
  a shell's ``w(q)`` is read: :data:`W_RULES`) or as the continuum integral over an ideal power law.

Units: pressures and ``E*`` share one pressure unit, heights and lengths one length unit.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.special import erf, exp1, roots_legendre

from ..surfaces.synthetic import psd_filter
from .full_contact import wavenumbers
from .laws import nonnegative_array, positive_number
from .spectra import check_band

#: Range of ``s`` tabulated for the smooth part of ``J`` (:func:`_h_table`); outside it ``J`` is
#: given by its series (below) or by its asymptote (above), both exact to round-off there.
_S_TABLE = (1e-2, 6.0)

#: Modes x pressures evaluated at once by the mean gap and the stiffness (bounds the memory).
_CHUNK = 1 << 22

#: Relative difference below which two wavenumbers are one shell (round-off; lattice shells at
#: N = 8192 differ by > 1e-8 relative).
_SAME_Q = 1e-12


# ------------------------------------------------------------------------ spectrum
def mode_spectrum(n: int, k_l: float, k_s: float, hurst: float, *, rms_slope: float | None = None,
                  rms_height: float | None = None, length: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Expected discrete spectrum of :func:`~roughcontact.surfaces.synthetic.generate_surface`.

    ``c`` is proportional to the square of
    :func:`~roughcontact.surfaces.synthetic.psd_filter` (the generator's amplitude filter, which
    multiplies white noise of uniform expected power), over every mode of the full ``n x n`` grid.

    Parameters
    ----------
    n : int
        Grid points per side (>= 4).
    k_l, k_s : float
        Cutoff mode numbers (cycles per ``L``), ``0 < k_l < k_s <= n/2``.
    hurst : float
        Hurst exponent H in [0, 1]; ``c ~ k^(-2(1+H))`` in the band.
    rms_slope, rms_height : float
        Exactly one (> 0): normalises ``sum q^2 c = rms_slope^2`` [-] or ``sum c = rms_height^2``.
    length : float
        Side ``L`` (> 0) [length].

    Returns
    -------
    (q, c) : numpy.ndarray, float64, shapes (m,) and (m,)
        The ``m`` modes with nonzero power, ascending in ``q``: ``q = 2 pi |k| / L`` [rad / length]
        and ``c`` [length^2]; the zero mode is excluded.
    """
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 4:
        raise ValueError(f"n (grid points per side) must be an integer >= 4, got {n!r}")
    kl, ks, h = check_band(k_l, k_s, hurst)
    if ks > n / 2:
        raise ValueError(f"k_s must be <= n/2 = {n / 2} (Nyquist), got k_s={k_s!r}")
    if (rms_slope is None) == (rms_height is None):
        raise ValueError("give exactly one of rms_slope or rms_height")
    L = positive_number("length", length)
    half = psd_filter(n, kl, ks, h, length=L) ** 2
    # Columns past the rfft half are the Hermitian mirrors (-i, n - j) of stored ones.
    rows, cols = np.arange(n)[:, None], np.arange(n)[None, :]
    mirrored = cols > n // 2
    power = half[np.where(mirrored, -rows % n, rows), np.where(mirrored, n - cols, cols)]
    q = wavenumbers(n, L)
    keep = power > 0
    if not keep.any():
        raise ValueError(f"no integer mode has k_l={k_l} <= |k| <= k_s={k_s} on a {n}x{n} grid")
    q, c = q[keep], power[keep]
    order = np.argsort(q, kind="stable")
    q, c = q[order], c[order]
    if rms_slope is not None:
        c *= positive_number("rms_slope", rms_slope) ** 2 / float(np.sum(q * q * c))
    else:
        c *= positive_number("rms_height", rms_height) ** 2 / float(np.sum(c))
    return q, c


# ------------------------------------------------------------ pressure distribution
def persson_pressure_distribution(p, p0: float, *, rms_slope: float, e_star: float) -> np.ndarray:
    """Persson's (2001) distribution of contact pressures for a fully resolved spectrum.

    ``P(p) = [exp(-(p - p0)^2 / 4G) - exp(-(p + p0)^2 / 4G)] / (2 sqrt(pi G))`` with
    ``G = E*^2 h'^2 / 8``: the diffusion of the pressure with magnification, absorbed at ``p = 0``.
    It is a density over the nominal area: ``int_0^inf P dp = erf(sqrt(2) p0 / (E* h'))``, the
    area fraction of :func:`~roughcontact.theory.laws.persson_area`.

    Parameters
    ----------
    p : array_like, any shape
        Local pressures (>= 0) [pressure unit of ``e_star``].
    p0 : float
        Applied mean pressure (>= 0) [pressure unit].
    rms_slope : float
        ``h'`` (> 0) [-].
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].

    Returns
    -------
    numpy.ndarray, shape of ``p``
        ``P(p)`` [1 / pressure unit].
    """
    x = nonnegative_array("p", p)
    if np.ndim(p0) != 0:
        raise ValueError(f"p0 must be a single number >= 0, got {p0!r}")
    m = float(nonnegative_array("p0", p0))
    four_g = 0.5 * (positive_number("e_star", e_star) * positive_number("rms_slope", rms_slope)) ** 2
    # exp(a) - exp(b) as exp(a) (1 - exp(b - a)) with b - a = -p p0 / G: no cancellation at p p0 -> 0.
    return np.exp(-((x - m) ** 2) / four_g) * -np.expm1(-4.0 * x * m / four_g) / math.sqrt(math.pi * four_g)


# ---------------------------------------------------------------- the J integral
def _integrand_h(s: np.ndarray) -> np.ndarray:
    """``erf(s)^2 exp(-s^2) / s``: the part of J's integrand that depends on the contact probability."""
    return erf(s) ** 2 * np.exp(-s * s) / s


def _e1_of_square(s: np.ndarray) -> np.ndarray:
    """``E1(s^2)`` without the underflow of ``s^2`` at tiny ``s`` (series ``-gamma_E - ln s^2 + s^2``)."""
    tiny = s < 1e-8
    safe = np.where(tiny, 1.0, s)
    return np.where(tiny, -np.euler_gamma - 2.0 * np.log(np.where(tiny, s, 1.0)) + s * s, exp1(safe * safe))


@functools.cache
def _h_table() -> CubicSpline:
    """Spline of ``ln H`` against ``ln s`` on :data:`_S_TABLE`, ``H(s0) = int_s0^inf erf^2 e^{-s^2} / s ds``.

    Built once: 800 intervals geometric in ``s``, each integrated by 12-point Gauss-Legendre
    (the integrand is smooth, so each piece is exact to round-off), summed from the top, where
    ``H(6) = E1(36) / 2`` to ``erfc(6) ~ 2e-17`` relative. ``ln H`` is smooth in ``ln s`` (it falls
    like ``-s^2`` at the top), so the spline keeps a relative accuracy of ~1e-10 everywhere.
    """
    s = np.geomspace(*_S_TABLE, 801)
    x, w = roots_legendre(12)
    a, b = s[:-1, None], s[1:, None]
    nodes = 0.5 * (b - a) * x[None, :] + 0.5 * (a + b)
    pieces = (0.5 * (b - a)[:, 0]) * (_integrand_h(nodes) @ w)
    top = 0.5 * float(exp1(_S_TABLE[1] ** 2))
    h = top + np.concatenate([np.cumsum(pieces[::-1])[::-1], [0.0]])
    return CubicSpline(np.log(s), np.log(h))


def _h_of(s0: np.ndarray) -> np.ndarray:
    """``H(s0) = int_s0^inf erf(s)^2 exp(-s^2) / s ds`` for ``s0 >= 0`` (any shape)."""
    lo, hi = _S_TABLE
    inside = np.clip(s0, lo, hi)
    out = np.exp(_h_table()(np.log(inside)))
    # Below the table: H(lo) + int_s0^lo of the series (4/pi)(s - 5 s^3 / 3), error O(lo^6).
    sb = np.minimum(s0, lo)
    below = (2.0 / math.pi) * (lo**2 - sb**2) - (5.0 / (3.0 * math.pi)) * (lo**4 - sb**4)
    out = np.where(s0 < lo, out + below, out)
    # Above it erf(s)^2 = 1 - O(erfc(6)) and H = E1(s0^2) / 2.
    return np.where(s0 > hi, 0.5 * _e1_of_square(np.maximum(s0, hi)), out)


def persson_j(s0, gamma: float = 0.45) -> np.ndarray:
    """``J(s0) = int_s0^inf [gamma + 3 (1 - gamma) erf(s)^2] exp(-s^2) / s ds`` [-].

    Split as ``(gamma / 2) E1(s0^2) + 3 (1 - gamma) H(s0)``: the exponential integral carries
    the logarithm ``J ~ gamma ln(1/s0) - gamma gamma_E / 2 + 3 (1 - gamma) H(0)`` of small
    ``s0`` exactly, and the smooth ``H`` is tabulated once (:func:`_h_table`).

    Parameters
    ----------
    s0 : array_like, any shape
        Lower limit (> 0) [-].
    gamma : float
        Persson's ``gamma`` in [0, 1] [-].

    Returns
    -------
    numpy.ndarray, shape of ``s0``
        ``J(s0)`` [-], relative accuracy ~1e-9.
    """
    s = np.asarray(s0, dtype=float)
    if np.any(np.isnan(s)) or np.any(s <= 0):
        raise ValueError(f"s0 must be > 0 everywhere, got {s0!r}")
    g = _gamma(gamma)
    return 0.5 * g * _e1_of_square(s) + 3.0 * (1.0 - g) * _h_of(s)


def _f(s: np.ndarray, gamma: float) -> np.ndarray:
    """``f(s) = [gamma + 3 (1 - gamma) erf(s)^2] exp(-s^2)``, so that ``dJ/ds0 = -f(s0) / s0``."""
    return (gamma + 3.0 * (1.0 - gamma) * erf(s) ** 2) * np.exp(-s * s)


def _gamma(gamma) -> float:
    g = float(gamma)
    if not math.isfinite(g) or not 0.0 <= g <= 1.0:
        raise ValueError(f"gamma must lie in [0, 1], got {gamma!r}")
    return g


# ------------------------------------------------------------ mean gap, stiffness
#: How :func:`mode_weights` places Persson's ``w(q)`` on a discrete spectrum (its ``rule``).
W_RULES = ("midpoint", "shell", "mode")


def mode_weights(q, c, rule: str = "midpoint") -> tuple[np.ndarray, np.ndarray]:
    """Terms ``(a, W)`` of Persson's sum over a discrete spectrum: ``u = (1 / (2 sqrt pi)) sum a J(W p0 / E*)``.

    Persson's ``w(q) = (pi int_q0^q q'^3 C dq')^(-1/2)`` holds the power below ``q``: infinite at the
    lowest wavenumber, ``sqrt(2) / h'`` at the highest. On a discrete spectrum the modes come in shells
    of one ``|q|``, and where inside its own shell a term's ``W`` is read is a choice (``rule``):

    - ``"midpoint"`` (default): each shell at the middle of its own power, ``W = (sum_{q_j < q} q_j^2
      c_j / 2 + sum_{q_j = q} q_j^2 c_j / 4)^(-1/2)``: the midpoint rule of the continuum integral
      across the shell, so the sum tends to the continuum one shell by shell (issue 61).
    - ``"shell"``: each shell at its top, with all of its own power, ``W = (sum_{q_j <= q} q_j^2 c_j /
      2)^(-1/2)``. The lowest shells then carry a finite ``W`` where the continuum's is infinite, and
      with few modes between q0 and q1 the mean gap comes out several percent too small.
    - ``"mode"``: mode by mode in ascending ``q`` (a shell's modes in their given order), each with the
      power up to and including itself: per shell, the average of ``W`` over its own power.

    Wavenumbers within a relative 1e-12 of each other are one shell (round-off).

    Parameters
    ----------
    q, c : array_like, shape (m,)
        Wavenumbers (> 0) [rad / length] and powers (>= 0, not all 0) [length^2] of the modes.
    rule : {"midpoint", "shell", "mode"}
        Where a shell's ``W`` is read (above).

    Returns
    -------
    (a, W) : numpy.ndarray, shapes (k,)
        One term per shell (per mode with ``"mode"``), ascending in ``q``: ``W`` [-] and ``a = W sum
        q_k c_k`` over the term's modes [length].
    """
    qa, ca = np.asarray(q, dtype=float), np.asarray(c, dtype=float)
    if qa.ndim != 1 or qa.size == 0 or not np.all(np.isfinite(qa)) or np.any(qa <= 0):
        raise ValueError(f"q must be a non-empty 1-D array of finite wavenumbers > 0, got shape {qa.shape}")
    if ca.shape != qa.shape or not np.all(np.isfinite(ca)) or np.any(ca < 0) or not np.any(ca > 0):
        raise ValueError(f"c must be a 1-D array of finite powers >= 0, not all 0, of the shape of q {qa.shape}")
    if rule not in W_RULES:
        raise ValueError(f"rule must be one of {W_RULES}, got {rule!r}")
    keep = ca > 0  # modes without power add nothing, and would give 0 * inf where they come first
    qa, ca = qa[keep], ca[keep]
    # A shell: the modes of one |q|, equal up to round-off (hypot(3, 4) and hypot(5, 0) may differ in the last bit).
    order = np.argsort(qa, kind="stable")
    shell = np.empty(qa.size, dtype=np.int64)
    shell[order] = np.cumsum(np.r_[True, qa[order][1:] > qa[order][:-1] * (1.0 + _SAME_Q)]) - 1
    order = np.lexsort((np.arange(qa.size), shell))  # by shell, the modes of a shell in their given order
    qa, ca, shell = qa[order], ca[order], shell[order]
    if rule == "mode":
        w = (0.5 * np.cumsum(qa * qa * ca)) ** -0.5
        return qa * ca * w, w
    # Modes of one |q| share W: summing them first shortens every later sum (~10x on a square grid).
    starts = np.flatnonzero(np.r_[True, shell[1:] > shell[:-1]])
    qc, q2c = np.add.reduceat(qa * ca, starts), np.add.reduceat(qa * qa * ca, starts)
    below = np.cumsum(q2c) - (0.5 * q2c if rule == "midpoint" else 0.0)
    w = (0.5 * below) ** -0.5
    return qc * w, w


def power_law_terms(k_l: float, k_s: float, hurst: float, *, rms_slope: float, length: float = 1.0,
                    nodes: int = 2048) -> tuple[np.ndarray, np.ndarray]:
    """Terms ``(a, W)`` of Persson's continuum integral over the ideal power-law spectrum (quadrature).

    ``C(q) = C0 q^(-2(1+H))`` for ``q_l <= q <= q_s`` (``q = 2 pi k / L``), normalised so that
    ``2 pi int q^3 C dq = rms_slope^2``; ``w(q) = (pi int_q_l^q q'^3 C dq')^(-1/2)`` in closed form.
    ``u = sqrt(pi) int q^2 C w J(w p0 / E*) dq`` is taken by Gauss-Legendre in ``t`` with
    ``q = q_l + (q_s - q_l) t^2`` (``w`` diverges as ``(q - q_l)^(-1/2)`` at ``q_l``): ``a = 2 pi q^2 C
    w dq`` at the nodes, so that :func:`persson_mean_gap_terms` sums it like a discrete spectrum.

    Parameters
    ----------
    k_l, k_s : float
        Cutoff mode numbers (cycles per ``L``), ``0 < k_l < k_s``.
    hurst : float
        Hurst exponent H in [0, 1].
    rms_slope : float
        ``h'`` (> 0) [-].
    length : float
        Side ``L`` (> 0) [length].
    nodes : int
        Quadrature nodes (>= 16); 2048 give the mean gap to ~1e-6 relative.

    Returns
    -------
    (a, W) : numpy.ndarray, shapes (nodes,)
        ``a`` [length] and ``W`` [-] at the nodes, ascending in ``q``.
    """
    kl, ks, h = check_band(k_l, k_s, hurst)
    if isinstance(nodes, (bool, np.bool_)) or not isinstance(nodes, (int, np.integer)) or nodes < 16:
        raise ValueError(f"nodes must be an integer >= 16, got {nodes!r}")
    L = positive_number("length", length)
    slope = positive_number("rms_slope", rms_slope)
    ql, qs = 2.0 * math.pi * kl / L, 2.0 * math.pi * ks / L
    x, wt = roots_legendre(int(nodes))
    t, wt = 0.5 * (x + 1.0), 0.5 * wt
    q = ql + (qs - ql) * t * t
    dq = 2.0 * (qs - ql) * t * wt

    def moment3(t):  # int_ql^q(t) x^3 x^(-2(1+H)) dx, the logarithm at H = 1; no cancellation at q -> ql
        p, lg = 2.0 - 2.0 * h, np.log1p((qs - ql) / ql * t * t)
        return lg if abs(p) < 1e-12 else ql**p * np.expm1(p * lg) / p

    c0 = slope**2 / (2.0 * math.pi * float(moment3(1.0)))
    w = (math.pi * c0 * moment3(t)) ** -0.5
    return 2.0 * math.pi * q * q * c0 * q ** (-2.0 * (1.0 + h)) * w * dq, w


def _pressures(p0, *, positive: bool) -> np.ndarray:
    arr = np.asarray(p0, dtype=float)
    bad = np.any(arr <= 0) if positive else np.any(arr < 0)
    if not np.all(np.isfinite(arr)) or bad:
        raise ValueError(f"p0 must be finite and {'>' if positive else '>='} 0 everywhere, got {p0!r}")
    return arr


def _mode_sum(values: np.ndarray, a: np.ndarray, w: np.ndarray, e_star: float, term) -> np.ndarray:
    """``sum_k a_k term(W_k p0 / E*)`` for each ``p0`` of ``values`` (flat), in chunks of modes x pressures."""
    out = np.empty(values.size)
    step = max(1, _CHUNK // w.size)
    for i in range(0, values.size, step):
        s = values[i:i + step, None] * (w[None, :] / e_star)
        out[i:i + step] = term(s) @ a
    return out


def persson_mean_gap_terms(p0, a, w, *, e_star: float, gamma: float = 0.45) -> np.ndarray:
    """Persson's mean gap ``u = (1 / (2 sqrt pi)) sum_k a_k J(W_k p0 / E*)`` from its terms ``(a, W)``.

    The terms of a discrete spectrum come from :func:`mode_weights`, those of the continuum power
    law from :func:`power_law_terms`; :func:`persson_mean_gap` documents the theory and units.
    """
    values = _pressures(p0, positive=True)
    g, es = _gamma(gamma), positive_number("e_star", e_star)
    total = _mode_sum(values.ravel(), np.asarray(a, float), np.asarray(w, float), es, lambda s: persson_j(s, g))
    return (total / (2.0 * math.sqrt(math.pi))).reshape(values.shape)


def persson_stiffness_terms(p0, a, w, *, e_star: float, gamma: float = 0.45) -> np.ndarray:
    """``K = -d p0 / d u`` of :func:`persson_mean_gap_terms` (:func:`persson_stiffness` documents it)."""
    values = _pressures(p0, positive=False)
    g, es = _gamma(gamma), positive_number("e_star", e_star)
    total = _mode_sum(values.ravel(), np.asarray(a, float), np.asarray(w, float), es,
                      lambda s: _f(s, g)) / (2.0 * math.sqrt(math.pi))
    flat = values.ravel()
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(flat > 0, flat / total, 0.0 if g > 0 else math.inf)
    return k.reshape(values.shape)


def persson_mean_gap(p0, q, c, *, e_star: float, gamma: float = 0.45, rule: str = "midpoint") -> np.ndarray:
    """Persson's mean interfacial separation ``u(p0)`` (Yang & Persson 2008; Persson 2007).

    ``u = sqrt(pi) int dq q^2 C(q) w(q) int_p0^inf dp'/p' [gamma + 3 (1 - gamma) P(q, p')^2]
    exp(-(w(q) p' / E*)^2)`` with ``w(q) = (pi int_q0^q q'^3 C dq')^(-1/2)`` and
    ``P(q, p) = erf(w(q) p / E*)``. For the discrete spectrum (``2 pi q C dq -> c_k``) it reads
    ``u = (1 / (2 sqrt(pi))) sum_k q_k c_k W_k J(W_k p0 / E*)`` (:func:`persson_j`), with ``W_k`` the
    ``w`` of shell ``k`` read by ``rule`` (:func:`mode_weights`: by default at the middle of the
    shell's own power, the continuum-consistent choice). The total power's ``w`` is ``sqrt(2) / h'``,
    so that ``P = erf(sqrt(2) p0 / (E* h'))`` at the top of the spectrum is
    :func:`~roughcontact.theory.laws.persson_area`. At small ``p0``, ``u ~ -(gamma / (2 sqrt(pi)))
    sum_k q_k c_k W_k ln p0``.

    Parameters
    ----------
    p0 : array_like, any shape
        Applied mean pressure (> 0) [pressure unit of ``e_star``].
    q : array_like, shape (m,)
        Angular wavenumbers of the modes (> 0, any order) [rad / length].
    c : array_like, shape (m,)
        Their powers ``|h_hat|^2`` (>= 0), ``sum c = <h^2>`` [length^2], e.g. from :func:`mode_spectrum`.
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].
    gamma : float
        Persson's correction for the elastic energy stored in the non-contact area, in [0, 1]
        (0.4 to 0.5 in Yang & Persson 2008) [-].
    rule : {"midpoint", "shell", "mode"}
        Where each shell's ``w`` is read (:func:`mode_weights`).

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        Mean gap ``u`` [length] (from the mean plane of the deformed body to that of the surface).
    """
    a, w = mode_weights(q, c, rule)
    return persson_mean_gap_terms(p0, a, w, e_star=e_star, gamma=gamma)


def persson_stiffness(p0, q, c, *, e_star: float, gamma: float = 0.45, rule: str = "midpoint") -> np.ndarray:
    """Normal contact stiffness per unit nominal area ``K = -d p0 / d u`` of :func:`persson_mean_gap`.

    Since ``dJ/ds0 = -f(s0) / s0`` with ``f(s) = [gamma + 3 (1 - gamma) erf(s)^2] exp(-s^2)``,
    ``du/dp0 = -(1 / (2 sqrt(pi) p0)) sum_k q_k c_k W_k f(W_k p0 / E*)``, in closed form:
    ``K = p0 / [(1 / (2 sqrt(pi))) sum_k q_k c_k W_k f(W_k p0 / E*)]``, linear in ``p0`` at small load
    (``gamma > 0``).

    Parameters
    ----------
    p0 : array_like, any shape
        Applied mean pressure (>= 0) [pressure unit of ``e_star``].
    q, c : array_like, shape (m,)
        The discrete spectrum, as in :func:`persson_mean_gap` [rad / length], [length^2].
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].
    gamma : float
        Persson's ``gamma`` in [0, 1] [-]; with ``gamma = 0``, ``K ~ 1 / p0`` at small load.
    rule : {"midpoint", "shell", "mode"}
        Where each shell's ``w`` is read (:func:`mode_weights`).

    Returns
    -------
    numpy.ndarray, shape of ``p0``
        ``K`` [pressure unit / length]; at ``p0 = 0``, 0 when ``gamma > 0`` and inf when ``gamma = 0``.
    """
    a, w = mode_weights(q, c, rule)
    return persson_stiffness_terms(p0, a, w, e_star=e_star, gamma=gamma)
