"""Geometric representativity: how far a surface's height distribution is from a Gaussian.

The paper's measure (its appendix) is the L2 distance between the normalised height
histogram P of the surface and the Gaussian G with the surface's own mean and standard
deviation::

    eps(S, N_bins) = sqrt( integral |G(h; hbar, sigma) - P(h)|^2 dh )

P is piecewise constant on ``n_bins`` equal bins spanning [min h, max h] and zero
outside. The integral is evaluated exactly for that piecewise-constant P (bin integrals
of G and G^2 through erf), including the Gaussian tails outside the histogram's range,
so the only approximation left is the histogram itself. eps has units of
1/sqrt(height unit), which UDUNITS-2, and so CF, cannot write (integer powers only,
:mod:`roughcontact.core.quantities`). Files therefore hold eps as the number it is for heights
in the study's length unit ``ell`` (``"um"``, or ``"1"`` for nondimensional heights):
eps of the dimensionless heights ``h / (1 ell)``, which is ``eps(h) sqrt(1 ell)``, with
``units: "1"`` and the attributes ``reference_length_units`` (``ell``) and
``reference_length_power`` (``"-1/2"``) that restore the dimension: ``epsilon`` 0.8 with
``"um"`` is 0.8 um^-1/2 (:func:`epsilon_attrs`). In a nondimensional study, as in the
paper (lengths in units of the side L = 1), this is eps itself.

eps depends on the height scale: heights ``c h`` give ``eps / sqrt(c)`` (the histogram
and G are densities in h, and the bins follow [min, max]). The scale-free measure is eps
of the normalised heights ``z = (h - hbar) / sigma``, dimensionless and the same for
every rms height: ``eps_z = eps sqrt(sigma)`` exactly (:func:`scale_free_epsilon`), so at
the paper's rms height 0.1 it is ``sqrt(0.1) = 0.316`` times eps.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy.special import erf, erfc

from ..core.quantities import per_reference_length

#: What the ``comment`` of ``epsilon`` says (the same for every length unit).
EPSILON_COMMENT = ("eps = sqrt(int (G - P)^2 dz) of the heights as numbers z = h / ell in units of ell = 1 "
                   "reference_length_units: eps of h in reference_length_units^reference_length_power "
                   "(UDUNITS-2, and so CF, has no fractional powers); epsilon sqrt(std_height) is the "
                   "scale-free eps of (h - mean height) / std_height")


def _gauss_cdf(z: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + erf(z / np.sqrt(2.0)))


def gaussian_l2_error(heights: np.ndarray, n_bins: int = 500) -> float:
    """L2 error between the heights' histogram PDF and their Gaussian, eps [height^-1/2].

    Parameters
    ----------
    heights : array_like, any shape
        Surface heights [height unit]; must be finite and not all equal.
    n_bins : int
        Number of equal histogram bins over [min, max] (paper: 500), >= 2.

    Returns
    -------
    float
        eps = sqrt(int (G - P)^2 dh) with G the normal PDF of mean and standard
        deviation (population, ddof=0) of ``heights``.
    """
    h = np.asarray(heights, dtype=float).ravel()
    if not isinstance(n_bins, (int, np.integer)) or n_bins < 2:
        raise ValueError(f"n_bins must be an integer >= 2, got {n_bins!r}")
    if h.size < 2 or not np.all(np.isfinite(h)):
        raise ValueError("heights must hold at least two finite values")
    mean, sigma = float(h.mean()), float(h.std())
    if not sigma > 0:
        raise ValueError("heights are all equal: the Gaussian of a flat surface is undefined")
    counts, edges = np.histogram(h, bins=n_bins)
    width = edges[1] - edges[0]
    pdf = counts / (h.size * width)
    z = (edges - mean) / sigma
    # int_bin G dh and int_bin G^2 dh; G^2 is a Gaussian of std sigma/sqrt(2) scaled by
    # 1/(2 sigma sqrt(pi)).
    g1 = np.diff(_gauss_cdf(z))
    g2 = np.diff(_gauss_cdf(z * np.sqrt(2.0))) / (2.0 * sigma * np.sqrt(np.pi))
    inside = float(np.sum(g2 - 2.0 * pdf * g1 + pdf**2 * width))
    tails = (0.5 * erfc(-z[0]) + 0.5 * erfc(z[-1])) / (2.0 * sigma * np.sqrt(np.pi))
    # Mathematically >= 0; a tiny negative value can only be roundoff.
    return float(np.sqrt(max(inside + tails, 0.0)))


def epsilon_attrs(length_unit: str) -> dict:
    """CF attributes of eps (:func:`gaussian_l2_error`) of heights in ``length_unit``.

    ``units`` ``"1"``: eps is written as its number for heights in ``length_unit`` (one of
    :data:`roughcontact.core.quantities.LENGTH_UNITS`), i.e. eps of the dimensionless heights
    ``h / (1 length_unit)``; ``reference_length_units`` (``length_unit``) and
    ``reference_length_power`` (``"-1/2"``) give its dimension back
    (:func:`roughcontact.core.quantities.per_reference_length`), ``comment`` says so in words.
    """
    return {**per_reference_length(length_unit, Fraction(-1, 2)),
            "long_name": "L2 error between the heights PDF and its Gaussian", "comment": EPSILON_COMMENT}


def binning_noise_floor(n_samples: int, n_bins: int, range_in_sigma: float,
                        sigma: float = 1.0) -> float:
    """Expected eps for ``n_samples`` independent draws from an exact Gaussian.

    Two terms add in eps^2: the multinomial noise of the bin counts, sum_i p_i /
    (n dh) = 1 / (n dh), and the within-bin variation of G that a piecewise-constant P
    cannot follow, dh^2/12 * int G'^2 dh = dh^2 / (48 sqrt(pi) sigma^3), with the bin
    width dh = range_in_sigma * sigma / n_bins. Returns sqrt of their sum
    [height^-1/2]. Correlated samples (real surfaces) have fewer independent draws and
    so a higher floor.
    """
    if n_samples < 1 or n_bins < 1 or not range_in_sigma > 0 or not sigma > 0:
        raise ValueError("n_samples, n_bins, range_in_sigma and sigma must be positive")
    dh = range_in_sigma * sigma / n_bins
    noise = 1.0 / (n_samples * dh)
    shape = dh**2 / (48.0 * np.sqrt(np.pi) * sigma**3)
    return float(np.sqrt(noise + shape))


def scale_free_epsilon(epsilon, sigma):
    """eps of the normalised heights ``(h - hbar) / sigma`` from eps of the heights [1].

    Under ``z = (h - hbar) / sigma`` the equal bins over [min, max] map onto equal bins
    over the new range, every density gains a factor ``sigma`` and ``dh = sigma dz``, so
    ``int (G_z - P_z)^2 dz = sigma int (G - P)^2 dh``: ``eps_z = eps sqrt(sigma)``.

    Parameters
    ----------
    epsilon : array_like, any shape
        :func:`gaussian_l2_error` of the heights [height unit^-1/2].
    sigma : array_like, broadcastable to ``epsilon``
        Population standard deviation of the same heights (> 0) [height unit].

    Returns
    -------
    numpy.ndarray or xarray.DataArray, the broadcast shape
        Dimensionless eps of the normalised heights [1].
    """
    if np.any(np.asarray(sigma) <= 0):
        raise ValueError("sigma must be > 0")
    return epsilon * np.sqrt(sigma)


def scale_free_l2_error(heights: np.ndarray, n_bins: int = 500) -> float:
    """eps of the normalised heights ``(h - hbar) / sigma`` [1]: invariant to the height scale.

    Parameters as in :func:`gaussian_l2_error`; equals
    ``scale_free_epsilon(gaussian_l2_error(h, n_bins), h.std())`` up to roundoff.
    """
    h = np.asarray(heights, dtype=float)
    sigma = float(h.std()) if h.size and np.all(np.isfinite(h)) else 0.0
    if not sigma > 0:
        return gaussian_l2_error(h, n_bins)  # raises with the reason
    return gaussian_l2_error((h - h.mean()) / sigma, n_bins)
