"""The interaction laws of adhesion, the resolution of their process zone, and the pull-off's statuses.

Each law is an energy ``phi(g)`` per unit area of the gap ``g >= 0`` with ``phi(0) = -w``
(``w`` the work of adhesion [pressure x length]) and range ``rho`` [length]; its tension
``d phi / d g >= 0`` pulls the surfaces together (:mod:`roughcontact.solver.adhesion`). :func:`zone_cells` says
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

#: Largest :func:`attraction_across_cell` (at the pull-off, a fraction of ``w / rho``) for a trusted pull-off.
#: For a body centred in the cell it is the tension at the cell's edge; with the exponential law on a
#: paraboloid, exp(-a^2 / (2 R rho)) is both the tension at radius ``a`` over ``w / rho`` and the share of
#: Derjaguin's force ``2 pi w R`` beyond ``a``, so the edge cuts off at most this share of a rigid sphere's
#: pull-off. Measured (sphere, w = 1e-4 E* R; docs/solver.md, "Adhesion"), the pull-off at L = R / 2 against
#: L = 2 R and this fraction at L = R / 2: mu_T = 0.05: -40 % at 0.483; 0.1: -16 % at 0.230; 0.2: -3.3 % at
#: 0.052; 0.3: -1.1 % at 0.012; 0.5: +0.9 % at 6e-4 (the grids' own difference): the pull-off moves by 0.6-1.0
#: times the fraction, so below 0.05 by less than 5 %. The adhesion scene's rough surfaces (rms height 1.3-1.9
#: rho) read 0.002-0.022.
MAX_ATTRACTION_ACROSS_CELL = 0.05

#: What a pull-off's status code means (index = code); only ``trusted`` carries a number. New codes are
#: appended, so that a stored code keeps its meaning.
PULL_OFF_STATUS = ("trusted", "adhesive_zone_unresolved", "last_load_step_not_converged", "not_separated",
                   "unconverged_step_beside_minimum", "refinement_not_converged", "attraction_spans_cell")
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
    "attraction_spans_cell": f"at the pull-off the law still pulls at {MAX_ATTRACTION_ACROSS_CELL:g} of w / rho or "
                             "more all along a row or column of the cell (attraction_across_cell): the cell's edge "
                             "cuts the body's attraction off and the periodic images' surfaces lie within its "
                             "range, so the pull-off depends on the cell's size (a sphere at L = R / 2, mu_T = 0.1: "
                             "1.64 pi w R against 1.95 at L = 2 R); enlarge the cell until the attraction dies out "
                             "inside it (for a sphere L^2 / (8 R rho) >= 3), or shorten the range",
}
#: Why no unloading step counts as converged when the pull-off is not trusted (``unload_converged``'s comment).
UNTRUSTED_TRACE_STEPS = (
    "The unloading trace is one measurement: each step starts from the one before and the pull-off is their "
    "minimum. When pull_off_status is not trusted no step of the trace is reported converged: an unresolved "
    "adhesive zone (below 1.5 cells no step counts as converged) or an attraction that spans the cell makes every "
    "step wrong, a trace from an unconverged load step may follow another branch throughout, and a trace that did "
    "not separate, whose minimum is not bracketed or whose refinement did not settle is no complete branch. A step "
    "that met its own residual keeps its finite unload_mean_pressure.")


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
    >>> round(process_zone_length(Exponential(1e-5, 1e-3), 1.0), 12)  # E* rho^2 / w = 1e-6 / 1e-5
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


def attraction_across_cell(law, gap) -> float:
    """The strongest attraction held all along a grid line across the cell, over the law's largest ``w / rho``.

    For each row and each column of ``gap`` (each axis with more than one node), the weakest tension
    ``tension(g)`` along it; the largest of these, divided by ``law.max_tension`` [-], in [0, 1]. For a
    body centred in the cell (a sphere) the line through its centre is weakest at the cell's edge: this is
    the attraction there, the share of the body's attraction the edge cuts off (:data:`MAX_ATTRACTION_ACROSS_CELL`).
    On a periodic rough surface a line meets deep valleys, unless an attracting band wraps the cell.

    Parameters
    ----------
    law : Exponential or MaugisDugdale
        The interaction law (``tension`` [pressure], ``max_tension = w / rho``).
    gap : ndarray, shape (nx, ny)
        The gap [length], ``>= 0``.

    Examples
    --------
    >>> g = np.array([[0.0, 1.0], [1.0, 2.0]]) * 1e-3
    >>> round(attraction_across_cell(Exponential(1e-5, 1e-3), g), 4)  # the line [0, 1] rho: exp(-1)
    0.3679
    """
    t = law.tension(gap)
    lines = [t.min(axis=axis) for axis in (0, 1) if t.shape[axis] > 1]
    return float(max(line.max() for line in lines) / law.max_tension)


def unresolved_zone_message(cells: float, law, e_star: float, dx_name: str = "the cell") -> str:
    """Why a grid cannot resolve ``law``, and the remedies (shared by the solver and the config check)."""
    return (f"the adhesive process zone E* rho^2 / w spans {cells:.3g} grid cells of {dx_name}, fewer than "
            f"{MIN_ZONE_CELLS:g} (w = {law.w:.3g}, rho = {law.rho:.3g}, E* = {e_star:.3g}): the grid cannot resolve "
            "the law and the pull-off comes out too large; refine the grid, lengthen the range or lower the work")
