"""The distribution of the contact pressure, ``P(p)``, per load step.

Persson's theory predicts ``P(p)``, the density of the contact pressure over the nominal area
(its integral over ``p > 0`` is the contact-area fraction), and the paper names it the natural
next observable. Pressures are binned in the reduced pressure ``p / (E* h')`` (``h'`` the surface's
rms slope), the scale on which Persson's ``P`` depends on nothing else, so that the bins are the
same for every surface of a scene and the aggregate can stack them.

:class:`PressureDistribution` is an observer of a solve (``solve_contact(..., observers=[...])``):
it reads each step's pressure field and gives its variables at the end. All else is pure.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

#: ``units`` of the reduced pressure ``p / (E* h')`` and of the density per unit of it.
DIMENSIONLESS = "1"


def pressure_bins(n_bins: int, max_pbar: float) -> np.ndarray:
    """Edges of ``n_bins`` equal bins of ``p / (E* h')`` on ``[0, max_pbar]``, shape ``(n_bins + 1,)``."""
    if isinstance(n_bins, bool) or not isinstance(n_bins, (int, np.integer)) or n_bins < 1:
        raise ValueError(f"pressure_distribution bins must be a whole number >= 1, got {n_bins!r}")
    top = float(max_pbar)
    if not np.isfinite(top) or top <= 0.0:
        raise ValueError(f"pressure_distribution max must be a finite number > 0 (p / (E* h')), got {max_pbar!r}")
    return np.linspace(0.0, top, int(n_bins) + 1)


def pressure_density(pressure: np.ndarray, edges: np.ndarray, scale: float) -> tuple[np.ndarray, float]:
    """Density of ``p / scale`` over the nominal area in the bins ``edges``, and the area beyond them.

    Parameters
    ----------
    pressure : numpy.ndarray, shape (nx, ny)
        Nodal contact pressure [pressure]; nodes with ``p > 0`` are in contact.
    edges : numpy.ndarray, shape (n_bins + 1,)
        Increasing bin edges of ``p / scale`` [-] (:func:`pressure_bins`).
    scale : float
        ``E* h'`` [pressure].

    Returns
    -------
    density : numpy.ndarray, shape (n_bins,)
        Fraction of the nominal area with ``p > 0`` and ``p / scale`` in each bin, per unit of
        ``p / scale`` [-]: ``sum(density * widths)`` plus the overflow is the area fraction.
    overflow : float
        Fraction of the nominal area with ``p / scale`` at or above the last edge [-] (nothing is
        dropped silently: a range too short for the load shows here).
    """
    reduced = np.asarray(pressure, dtype=np.float64).ravel() / float(scale)
    contact = reduced[reduced > 0.0]
    counts, _ = np.histogram(contact, bins=edges)
    # np.histogram puts a value equal to the last edge into the last bin: count it as overflow
    top = np.count_nonzero(contact >= edges[-1])
    counts[-1] -= np.count_nonzero(contact == edges[-1])
    n = reduced.size
    return counts / (n * np.diff(edges)), top / n


class PressureDistribution:
    """Observer of a solve: :func:`pressure_density` of every load step, then its dataset.

    ``edges`` are bin edges of ``p / (E* h')`` (:func:`pressure_bins`), ``scale`` is ``E* h'``
    [pressure] of the surface solved.
    """

    def __init__(self, edges: np.ndarray, scale: float):
        self.edges = np.asarray(edges, dtype=np.float64)
        if self.edges.ndim != 1 or self.edges.size < 2 or not np.all(np.diff(self.edges) > 0):
            raise ValueError("pressure_distribution edges must be a 1-D increasing array of >= 2 values")
        self.scale = float(scale)
        if not np.isfinite(self.scale) or self.scale <= 0.0:
            raise ValueError(f"pressure_distribution scale E* h' must be finite and > 0, got {scale!r}")
        self.densities: list[np.ndarray] = []
        self.overflow: list[float] = []

    def observe(self, step) -> None:
        """Record one load step's pressure field (``step.pressure``: host array, shape ``(nx, ny)``;
        ``step`` a :class:`roughcontact.solver.solve.StepView`)."""
        density, over = pressure_density(step.pressure, self.edges, self.scale)
        self.densities.append(density)
        self.overflow.append(over)

    def dataset(self, steps) -> xr.Dataset:
        """``pressure_distribution(step, pressure_bin)`` and ``pressure_distribution_overflow(step)``."""
        return pressure_distribution_dataset(np.array(self.densities), np.array(self.overflow), steps,
                                             self.edges)


def pressure_distribution_dataset(densities: np.ndarray, overflow: np.ndarray, steps, edges) -> xr.Dataset:
    """The per-step densities ``(n_steps, n_bins)`` and overflows ``(n_steps,)`` as CF variables.

    Coordinates: ``pressure_bin`` (bin centres of ``p / (E* h')``), ``pressure_bin_low`` and
    ``pressure_bin_high`` (its edges), ``step``.
    """
    edges = np.asarray(edges, dtype=np.float64)
    lo, hi = edges[:-1], edges[1:]
    name = "reduced contact pressure p/(E* h')"
    coords = {
        "step": ("step", np.asarray(steps)),
        "pressure_bin": ("pressure_bin", 0.5 * (lo + hi),
                         {"units": DIMENSIONLESS, "long_name": f"{name}, bin centre"}),
        "pressure_bin_low": ("pressure_bin", lo,
                             {"units": DIMENSIONLESS, "long_name": f"{name}, lower bin edge"}),
        "pressure_bin_high": ("pressure_bin", hi,
                              {"units": DIMENSIONLESS, "long_name": f"{name}, upper bin edge"}),
    }
    data = {
        "pressure_distribution": (("step", "pressure_bin"), densities, {
            "units": DIMENSIONLESS,
            "long_name": "contact pressure distribution P(p): fraction of the nominal area in contact "
                         "per unit of p/(E* h')"}),
        "pressure_distribution_overflow": ("step", overflow, {
            "units": DIMENSIONLESS,
            "long_name": "fraction of the nominal area with p/(E* h') above the last pressure bin"}),
    }
    return xr.Dataset(data, coords=coords)
