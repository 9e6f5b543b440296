"""The interaction laws of adhesion, the resolution of their process zone, and the pull-off's statuses.

Each law is an energy ``phi(g)`` per unit area of the gap ``g >= 0`` with ``phi(0) = -w``
(``w`` the work of adhesion [pressure x length]) and range ``rho`` [length]; its tension
``d phi / d g >= 0`` pulls the surfaces together (package docstring). :func:`zone_cells` says
whether a grid resolves the law's process zone ``E* rho^2 / w``.
"""

from __future__ import annotations

import math

import numpy as np

from ...core.cell import Cell

#: Fewest grid cells the process zone ``E* rho^2 / w`` must span for a step to count as converged
#: (:func:`zone_cells`). Measured on a sphere's pull-off (exponential law, L = R / 2; docs/solver.md,
#: "Adhesion"): at Tabor parameter 4, 0.37 cells read 2.32 pi w R, 0.74 cells 1.62, 1.49 cells 1.541;
#: at Tabor parameter 2, 1.49 cells read 1.605, 2.97 cells 1.587, 5.94 cells 1.584 (1.3 % and 0.2 % above
#: the finest). Below this the error grows past a few per cent and, at a tenth of a cell, past any bound.
MIN_ZONE_CELLS = 1.5
#: Below this many cells (and at least :data:`MIN_ZONE_CELLS`) a solve warns: the pull-off may still be
#: about 1 % above its grid-converged value.
WARN_ZONE_CELLS = 3.0


def positive(name: str, value) -> float:
    """``float(value)``, finite and > 0; else a ``ValueError`` naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}") from None
    if isinstance(value, (bool, np.bool_)) or not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


class Exponential:
    """Exponential law: ``phi(g) = -w exp(-g / rho)``, tension ``(w / rho) exp(-g / rho)``.

    Parameters
    ----------
    w : float
        Work of adhesion [energy / area = pressure x length], > 0.
    rho : float
        Range [length], > 0. The largest tension is ``w / rho`` (at contact).

    Tamaas' ``ExponentialAdhesionFunctional`` with ``surface_energy = w``, ``rho = rho``.
    """

    name = "exponential"

    def __init__(self, w, rho):
        self.w, self.rho = positive("w", w), positive("rho", rho)

    @property
    def max_tension(self) -> float:
        return self.w / self.rho

    def energy(self, g):
        """``phi(g)`` [energy / area], array like ``g`` (``g >= 0`` [length])."""
        return -self.w * np.exp(-np.asarray(g, dtype=float) / self.rho)

    def tension(self, g):
        """Tensile stress ``d phi / d g >= 0`` [pressure], array like ``g``."""
        return (self.w / self.rho) * np.exp(-np.asarray(g, dtype=float) / self.rho)

    def curvature(self, g):
        """``d^2 phi / d g^2 <= 0`` [pressure / length]: the law is concave."""
        return -(self.w / self.rho ** 2) * np.exp(-np.asarray(g, dtype=float) / self.rho)


class MaugisDugdale:
    """Maugis-Dugdale (cohesive zone) law: constant tension ``sigma0 = w / rho`` for ``g <= rho``.

    ``phi(g) = -w + sigma0 g`` for ``0 <= g <= rho``, 0 beyond (concave, kink at ``rho``);
    ``tension(g) = sigma0`` for ``g <= rho`` (at contact too: a contact node carries
    ``p + sigma0 >= 0``), 0 beyond. Maugis (1992), J. Colloid Interface Sci. 150, 243.

    Parameters
    ----------
    w : float
        Work of adhesion [energy / area], > 0.
    rho : float
        Range ``h0`` of the cohesive zone [length], > 0.

    Tamaas' ``MaugisAdhesionFunctional`` with ``surface_energy = w``, ``rho = rho``.
    """

    name = "maugis-dugdale"

    def __init__(self, w, rho):
        self.w, self.rho = positive("w", w), positive("rho", rho)

    @property
    def sigma0(self) -> float:
        return self.w / self.rho

    max_tension = sigma0

    def energy(self, g):
        """``phi(g)`` [energy / area], array like ``g``."""
        g = np.asarray(g, dtype=float)
        return np.where(g <= self.rho, self.sigma0 * g - self.w, 0.0)

    def tension(self, g):
        """Tensile stress [pressure]: ``sigma0`` where ``g <= rho``, else 0."""
        g = np.asarray(g, dtype=float)
        return np.where(g <= self.rho, self.sigma0, 0.0)

    def curvature(self, g):
        """``d^2 phi / d g^2`` off the kink: 0 (the kink at ``rho`` is concave)."""
        return np.zeros_like(np.asarray(g, dtype=float))


LAWS = (Exponential, MaugisDugdale)

#: What a pull-off's status code means (index = code); only ``trusted`` carries a number.
PULL_OFF_STATUS = ("trusted", "adhesive_zone_unresolved", "last_load_step_not_converged", "not_separated",
                   "unconverged_step_beside_minimum", "refinement_not_converged")
#: Why each status other than ``trusted`` leaves the pull-off NaN, and what to do.
PULL_OFF_REASONS = {
    "adhesive_zone_unresolved": "the grid does not resolve the adhesive process zone (zone_cells): refine the "
                                "grid, lengthen the range or lower the work",
    "last_load_step_not_converged": "unloading started from a load step that did not converge",
    "not_separated": "the surfaces still touched after the last unloading step: allow more steps or a longer step",
    "unconverged_step_beside_minimum": "a step next to the most tensile one did not converge, so the minimum "
                                       "is not bracketed: raise max_iter",
    "refinement_not_converged": "halving the unloading step near the minimum still moved the pull-off by more "
                                "than its tolerance",
}


def process_zone_length(law, e_star: float) -> float:
    """The length scale ``E* rho^2 / w`` [length] of the adhesive process zone (module docstring).

    Parameters
    ----------
    law : Exponential or MaugisDugdale
        Its work ``w`` [pressure x length] and range ``rho`` [length].
    e_star : float
        Plane-strain modulus ``E*`` [pressure].

    Examples
    --------
    >>> process_zone_length(Exponential(1e-5, 1e-3), 1.0)
    0.1
    """
    return float(e_star) * law.rho ** 2 / law.w


def zone_cells(law, e_star: float, length, shape) -> float:
    """How many grid cells the process zone spans: ``E* rho^2 / w / dx`` (module docstring).

    ``dx`` is the larger pixel side, ``Lx / nx`` or ``Ly / ny`` (``Lx / nx`` alone for a 1-D profile,
    ``ny = 1``); ``length`` a float ``L`` (square cell) or ``(Lx, Ly)`` [length], ``shape``
    ``(nx, ny)``. A step counts as converged only when this is at least :data:`MIN_ZONE_CELLS`.

    Examples
    --------
    >>> zone_cells(Exponential(1e-5, 1e-3), 1.0, 1.0, (128, 128))  # the adhesion scene: 12.8 cells
    12.8
    """
    nx, ny = shape
    lx, ly = Cell.of(shape, length).sides
    dx = lx / nx if ny == 1 else max(lx / nx, ly / ny)
    return round(process_zone_length(law, e_star) / dx, 12)


def unresolved_zone_message(cells: float, law, e_star: float, dx_name: str = "the cell") -> str:
    """Why a grid cannot resolve ``law``, and the remedies (shared by the solver and the config check)."""
    return (f"the adhesive process zone E* rho^2 / w spans {cells:.3g} grid cells of {dx_name}, fewer than "
            f"{MIN_ZONE_CELLS:g} (w = {law.w:.3g}, rho = {law.rho:.3g}, E* = {e_star:.3g}): the grid cannot resolve "
            "the law and the pull-off comes out too large; refine the grid, lengthen the range or lower the work")
