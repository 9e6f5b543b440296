"""Adhesive normal contact: interaction laws and a gap-based FFT-BEM solver.

Problem
-------
The conventions of :mod:`roughcontact.solver`: a rigid surface of heights ``h`` [length]
(highest points touch first) on a periodic elastic half-space of plane-strain modulus
``E*`` [pressure], cell ``Lx x Ly`` on ``nx x ny`` nodes (``length`` a float ``L`` means a
square cell; ``ny = 1`` is a plane-strain 1-D problem, ``h`` independent of y). ``p`` is
the net surface pressure [pressure], compressive positive, tensile negative, and

    u(q) = 2 p(q) / (E* |q|),  u(q = 0) = 0,     g = u - h + d,   mean(g) = d - mean(h).

The surfaces attract each other through an interaction law of energy ``phi(g)`` per unit
area (:class:`Exponential`, :class:`MaugisDugdale`), ``phi(0) = -w`` with ``w`` the work of
adhesion, ``phi(inf) = 0``, whose tensile stress ``tension(g) = d phi / d g >= 0`` pulls the
surfaces together. (The tension is ``+d phi/d g``: ``phi`` rises from ``-w`` to 0 as the
gap opens, and the stress it exerts is tensile, ``p = -tension(g)`` in the gap.)
The discrete adhesive problem (the invariants that a converged step satisfies):

* ``g >= 0`` everywhere (exactly: the projection sets it);
* where ``g > 0``: ``p = -tension(g)``;
* where ``g = 0``: ``p + tension(0) >= 0`` (the repulsive part of the pressure is >= 0);
* displacement control: ``mean(g)`` equals the imposed mean gap; pressure control:
  ``mean(p) = p0`` (``p0 < 0`` is a tensile load).

These are the stationarity conditions of the total energy (Rey, Anciaux & Molinari 2017,
Comput. Mech. 60, 69-81), written with the gap as primal variable:

    E(g) = 1/2 <(g + h), M (g + h)> + sum phi(g)    over {g >= 0, mean(g) = gbar},

``M = E* |q| / 2`` (0 at ``q = 0``) the inverse of the elastic operator, so that
``p = M (g + h) - lam``, ``lam`` the multiplier of the mean-gap constraint and
``mean(p) = -lam``. Both laws are concave in ``g``, so the elastic quadratic is an upper
bound of ``E`` along any line: a step length computed from ``M`` alone lowers the energy.

Algorithm (:class:`AdhesiveIteration`)
--------------------------------------
Polonsky & Keer's constrained conjugate gradient with the roles of pressure and gap
exchanged, as Rey et al. (2017) and Tamaas' ``PolonskyKeerRey(model, h, tol, gap, gap)``
with an adhesion functional term: the gradient is ``r = M (g + h) + tension(g)``; the free
set ``F`` is ``{g > 0}`` plus the contact nodes where ``r < lam`` (they want to open, PK's
join rule, restarting the CG); the search direction is conjugate on ``F`` and zero-mean
there (``mean(g)`` is kept); the step length is the elastic one,
``tau = <z, t> / <t, M t>``; a step that takes nodes below 0 is clipped at 0, the mean
restored by rescaling the gaps (Tamaas' rule) and the CG restarts. One FFT pair per
iteration (``M t``); ``M (g + h)`` is updated incrementally and recomputed after each
projection and before the final check. Pressure control wraps displacement control: the
mean gap is found by a bracketing secant (Illinois) search on the load-stable branch
(mean pressure decreasing with the mean gap), each evaluation warm-started.

Convergence criterion
---------------------
With ``p_ref`` the rms of ``M h`` (the rms pressure that flattens ``h`` completely,
``p* / sqrt 2`` for a sinusoid of amplitude ``Delta``: ``p* = pi E* Delta / lambda``; the
law's ``tension(0)`` when ``h`` is flat), the residual is

    max( max_{g > 0} |p + tension(g)|,  max(0, -min_{g = 0} (p + tension(0))) ) / p_ref

(and, under pressure control, ``|mean(p) - p0| / p_ref`` too). A step is ``converged`` only
when this residual, recomputed from the returned gap with a fresh FFT, is ``<= tol``, every
value is finite, ``g >= 0`` and the mean gap is the imposed one to 1e-12 relative. The
contact area fraction is the fraction of nodes with ``g == 0`` exactly.

Resolution of the adhesive zone
-------------------------------
Where the surfaces part, the tension acts over a process zone of length of order
``l_a = E* rho^2 / w`` (:func:`process_zone_length`: the length over which the largest tension
``w / rho`` opens the gap by ``rho`` elastically; a Dugdale zone is ``pi/8`` of it). A grid whose
cell ``dx`` is not small against ``l_a`` cannot represent the law: nodes jump in and out of
contact as a whole and the tension they carry is too large (measured on a sphere, Tabor
parameter ``mu_T`` 8 at 64 nodes: a pull-off of 7 pi w R, 3.5 times the largest physically
possible, every step meeting the residual). :func:`zone_cells` is ``l_a / dx``; below
:data:`MIN_ZONE_CELLS` no step is reported converged, whatever its residual.

The energy is not convex when ``w / rho^2`` exceeds ``pi E* / L`` (the smallest eigenvalue
of ``M`` on zero-mean fields): equilibria then depend on the start (hysteresis), and a
converged step is *an* equilibrium, not necessarily the one another solver finds. With
the Maugis-Dugdale law each node's tension jumps at ``g = rho``; unless the cohesive zone
spans many nodes the discrete system is trapped in many states (measured on the 1-D wavy
surface: loading and unloading curves 0.04 p* apart where the exponential law's agree).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.fft import get_fft
from .halfspace import inverse_kernel
from .workspace import dot

#: Default iteration cap of :func:`solve_adhesive` (all inner iterations of one call).
DEFAULT_MAX_ITER = 20000
#: Relative tolerance on the imposed mean gap in the final check.
MEAN_GAP_RTOL = 1e-12
#: Fewest grid cells the process zone ``E* rho^2 / w`` must span for a step to count as converged
#: (:func:`zone_cells`). Measured on a sphere's pull-off (exponential law, L = R / 2; docs/solver.md,
#: "Adhesion"): at Tabor parameter 4, 0.37 cells read 2.32 pi w R, 0.74 cells 1.62, 1.49 cells 1.541;
#: at Tabor parameter 2, 1.49 cells read 1.605, 2.97 cells 1.587, 5.94 cells 1.584 (1.3 % and 0.2 % above
#: the finest). Below this the error grows past a few per cent and, at a tenth of a cell, past any bound.
MIN_ZONE_CELLS = 1.5
#: Below this many cells (and at least :data:`MIN_ZONE_CELLS`) a solve warns: the pull-off may still be
#: about 1 % above its grid-converged value.
WARN_ZONE_CELLS = 3.0


def _positive(name: str, value) -> float:
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
        self.w, self.rho = _positive("w", w), _positive("rho", rho)

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
        self.w, self.rho = _positive("w", w), _positive("rho", rho)

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
    lx, ly = (length, length) if np.ndim(length) == 0 else length
    dx = float(lx) / nx if ny == 1 else max(float(lx) / nx, float(ly) / ny)
    return round(process_zone_length(law, e_star) / dx, 12)


def unresolved_zone_message(cells: float, law, e_star: float, dx_name: str = "the cell") -> str:
    """Why a grid cannot resolve ``law``, and the remedies (shared by the solver and the config check)."""
    return (f"the adhesive process zone E* rho^2 / w spans {cells:.3g} grid cells of {dx_name}, fewer than "
            f"{MIN_ZONE_CELLS:g} (w = {law.w:.3g}, rho = {law.rho:.3g}, E* = {e_star:.3g}): the grid cannot resolve "
            "the law and the pull-off comes out too large; refine the grid, lengthen the range or lower the work")


@dataclass
class AdhesiveResult:
    """One solved step of :func:`solve_adhesive` (fields shape ``(nx, ny)``).

    pressure [pressure] (compressive > 0, tensile < 0), gap [length] (``>= 0``),
    area_fraction (nodes with ``gap == 0`` over all nodes), mean_pressure [pressure],
    mean_gap [length], offset ``d = mean_gap + mean(h)`` [length], iterations (all inner
    iterations), residual (module docstring), converged, control ("gap" or "pressure").
    """

    pressure: np.ndarray
    gap: np.ndarray
    area_fraction: float
    mean_pressure: float
    mean_gap: float
    offset: float
    iterations: int
    residual: float
    converged: bool
    control: str
    zone_cells: float = math.inf


def elastic_product(field, mult) -> np.ndarray:
    """``F^-1[mult F[field]]`` for a real ``(nx, ny)`` field and multiplier ``(nx, ny // 2 + 1)``: a new array.

    The transforms are the cached float64 pair of :func:`roughcontact.core.fft.get_fft` (FFTW with the
    shipped plans: 0.7x the CPU of numpy.fft for the adhesion scene's solves at N = 128, measured),
    numpy.fft for a 1-D problem (``ny = 1``), which that pair does not plan.
    """
    if min(field.shape) < 2:
        return np.fft.irfft2(np.fft.rfft2(field) * mult, s=field.shape)
    fft = get_fft(field.shape)
    spec = fft.forward(field)  # the pair's own buffers: multiplied in place, the result copied out
    np.multiply(spec, mult, out=spec)
    return fft.backward(spec).copy()


def adhesive_state(heights, gap, law, mult):
    """Pressure, mean pressure and the two residual parts of a gap field.

    ``mult`` is :func:`inverse_kernel`. Returns ``(p, mean_p, e_free, e_contact)``: ``p`` the
    pressure with ``p = -tension(g)`` on average over ``{g > 0}``, ``e_free = max |p + tension|``
    over ``g > 0`` and ``e_contact = max(0, -min(p + tension(0)))`` over ``g == 0`` [pressure].
    """
    r = elastic_product(gap + heights, mult) + law.tension(gap)
    free = gap > 0
    lam = float(r[free].mean()) if free.any() else float(r.min())
    dev = r - lam
    e_free = float(np.abs(dev[free]).max()) if free.any() else 0.0
    e_cont = float(max(0.0, -dev[~free].min())) if (~free).any() else 0.0
    return dev - law.tension(gap), -lam, e_free, e_cont


class AdhesiveIteration:
    """Polonsky-Keer-type CG on the gap for one surface, law and half-space (module docstring).

    Buffers (float64, shape ``(nx, ny)``): ``g`` the gap, ``mgh = M (g + h)``, ``t`` the
    search direction, ``z`` the projected gradient. ``mult`` is :func:`inverse_kernel`;
    ``p_ref`` the pressure scale of the residual. :meth:`solve` runs one displacement-
    controlled step from the current ``g``.
    """

    def __init__(self, heights, law, e_star, length):
        self.h, self.law = heights, law
        self.mult = inverse_kernel(heights.shape, e_star, length)
        mh = self._m(heights)
        rms = float(np.sqrt(np.mean(mh * mh)))
        self.p_ref = rms if rms > 0 else law.max_tension
        self.g = np.zeros_like(heights)
        self.mgh = np.zeros_like(heights)
        self.iterations = 0

    def _m(self, field):
        return elastic_product(field, self.mult)

    def start(self, gap, mean_gap):
        """Warm start: ``gap`` clipped at 0 and rescaled to ``mean_gap`` (zeros stay zeros)."""
        g = np.maximum(gap, 0.0)
        m = g.mean()
        self.g = g * (mean_gap / m) if m > 0 else np.full_like(g, mean_gap)
        self.mgh = self._m(self.g + self.h)

    def measure(self):
        """``(lam, residual, free, joiners)`` of the current state (incremental ``mgh``)."""
        r = self.mgh + self.law.tension(self.g)
        pos = self.g > 0
        lam = float(r[pos].mean())
        join = (~pos) & (r < lam)
        free = pos | join
        e_free = float(np.abs(r[pos] - lam).max())
        e_cont = float(max(0.0, lam - r[~pos].min())) if (~pos).any() else 0.0
        self.r = r
        return lam, max(e_free, e_cont) / self.p_ref, free, bool(join.any())

    def solve(self, mean_gap, tol, max_iter):
        """Iterate from ``self.g`` (mean ``mean_gap``) to ``residual <= tol`` or ``max_iter``.

        Returns ``(iterations, residual)`` of the final check on a fresh FFT.
        """
        t = np.zeros_like(self.g)
        zz_old, it, fresh = 0.0, 0, True
        while True:
            lam, res, free, joined = self.measure()
            if res <= tol:
                if fresh:
                    break
                self.mgh, fresh = self._m(self.g + self.h), True
                continue
            if it >= max_iter:
                break
            it += 1
            lam = float(self.r[free].mean())
            z = np.where(free, self.r - lam, 0.0)
            zz = dot(z.ravel(), z.ravel())
            if joined or zz_old == 0.0:
                t = z
            else:
                t = z + (zz / zz_old) * t
            zt = dot(z.ravel(), t.ravel())
            if zt <= 0.0:  # not a descent direction: restart
                t, zt = z, zz
            mt = self._m(t)
            curv = dot(t.ravel(), mt.ravel())  # no BLAS (workspace.dot)
            if not (curv > 0.0 and math.isfinite(curv)):
                break
            tau = zt / curv
            trial = self.g - tau * t
            if trial.min() < 0.0:
                self.start(trial, mean_gap)  # clip, rescale the mean, fresh M (g + h)
                zz_old, fresh = 0.0, True
            else:
                self.g = trial
                self.mgh -= tau * mt
                zz_old, fresh = zz, False
        self.iterations += it
        return it, self.check(mean_gap)[1]

    def check(self, mean_gap):
        """Final check on a fresh FFT: ``(pressure, residual, mean_pressure)``."""
        p, mean_p, e_free, e_cont = adhesive_state(self.h, self.g, self.law, self.mult)
        res = max(e_free, e_cont) / self.p_ref
        bad_mean = abs(self.g.mean() - mean_gap) > MEAN_GAP_RTOL * mean_gap
        if bad_mean or not (np.all(np.isfinite(p)) and self.g.min() >= 0.0):
            res = math.inf
        return p, res, mean_p


def _heights(heights, length):
    """``heights`` as float64 ``(nx, ny)`` and ``length`` checked (float ``L`` or ``(Lx, Ly)``)."""
    h = np.ascontiguousarray(heights, dtype=np.float64)
    if h.ndim != 2 or h.shape[0] < 4 or h.size < 4:
        raise ValueError(f"heights must be a 2-D array (nx, ny) with nx >= 4 (ny = 1 for a 1-D profile), "
                         f"got shape {h.shape}")
    if not np.all(np.isfinite(h)):
        raise ValueError("heights must contain only finite values (found NaN or inf)")
    if np.ndim(length) == 0:
        if h.shape[0] != h.shape[1]:
            raise ValueError(f"a float length needs square heights; give length=(Lx, Ly) for shape {h.shape}")
        return h, _positive("length", length)
    lx, ly = length
    return h, (_positive("length[0]", lx), _positive("length[1]", ly))


def _finish(it, mean_gap, control, iterations, p0=None):
    """Assemble an :class:`AdhesiveResult` from the final check of ``it`` at ``mean_gap``."""
    p, res, mean_p = it.check(mean_gap)
    if p0 is not None:
        res = max(res, abs(mean_p - p0) / it.p_ref)
    return res, AdhesiveResult(p, it.g.copy(), float(np.count_nonzero(it.g == 0.0)) / it.g.size, mean_p,
                               float(it.g.mean()), float(it.g.mean() + it.h.mean()), iterations, res,
                               False, control)


def solve_adhesive(heights, *, law, e_star=1.0, length=1.0, mean_gap=None, p0=None, initial_gap=None,
                   tol=1e-8, max_iter=DEFAULT_MAX_ITER) -> AdhesiveResult:
    """Solve one adhesive contact step on the periodic half-space (module docstring).

    Parameters
    ----------
    heights : array_like, shape (nx, ny)
        Rigid surface heights [length], highest points touch first; ``ny = 1`` (with
        ``length=(Lx, Ly)``) is a plane-strain profile.
    law : Exponential or MaugisDugdale
        Interaction law (work of adhesion ``w`` [pressure x length], range ``rho`` [length]).
    e_star : float
        Plane-strain modulus ``E*`` [pressure].
    length : float or (float, float)
        Cell side ``L`` (square heights) or sides ``(Lx, Ly)`` [length].
    mean_gap : float, optional
        Displacement control: imposed ``mean(g) = d - mean(h) > 0`` [length].
    p0 : float, optional
        Pressure control: imposed ``mean(p)`` [pressure], negative for a tensile load;
        exactly one of ``mean_gap`` and ``p0``. Solved on the load-stable branch met first
        from the start (mean pressure decreasing with the mean gap).
    initial_gap : array_like, shape (nx, ny), optional
        Warm start [length], e.g. the previous step's ``gap``: clipped at 0 and rescaled to
        the mean gap (its contact set is kept). Default: ``max(h) - h`` (the rigid surface
        touching at its highest node).
    tol : float
        Tolerance in (0, 1) on the scale-free residual (module docstring).
    max_iter : int
        Cap on all inner iterations of the call, >= 1.

    Returns
    -------
    AdhesiveResult
        ``converged`` only when the final check (fresh FFT) passes and the grid resolves the
        process zone (:func:`zone_cells` >= :data:`MIN_ZONE_CELLS`).
    """
    h, length = _heights(heights, length)
    e_star, tol = _check_args(e_star, tol, law, max_iter, mean_gap, p0)
    start = _start_gap(h, initial_gap)
    it = AdhesiveIteration(h, law, e_star, length)
    if mean_gap is not None:
        mean_gap = _positive("mean_gap", mean_gap)
        it.start(start, mean_gap)
        it.solve(mean_gap, tol, int(max_iter))
        res, out = _finish(it, mean_gap, "gap", it.iterations)
    else:
        res, out = pressure_control(it, _finite("p0", p0), start, tol, int(max_iter))
    out.zone_cells = zone_cells(law, e_star, length, h.shape)
    out.converged = bool(res <= tol) and out.zone_cells >= MIN_ZONE_CELLS
    return out


def _check_args(e_star, tol, law, max_iter, mean_gap, p0) -> tuple[float, float]:
    """``(e_star, tol)`` checked, with the law, ``max_iter`` and the control; ``ValueError`` naming each."""
    e_star, tol = _positive("e_star", e_star), _positive("tol", tol)
    if tol >= 1:
        raise ValueError(f"tol must be in (0, 1), got {tol!r}")
    if not isinstance(law, LAWS):
        raise ValueError(f"law must be an Exponential or MaugisDugdale instance, got {type(law).__name__}")
    if isinstance(max_iter, (bool, np.bool_)) or int(max_iter) != max_iter or max_iter < 1:
        raise ValueError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    if (mean_gap is None) == (p0 is None):
        raise ValueError("give exactly one of mean_gap (displacement control) and p0 (pressure control)")
    return e_star, tol


def _start_gap(h: np.ndarray, initial_gap) -> np.ndarray:
    """The starting gap: ``initial_gap`` checked, else ``max(h) - h`` (touching at the highest node)."""
    if initial_gap is None:
        return h.max() - h
    start = np.asarray(initial_gap, dtype=np.float64)
    if start.shape != h.shape or not np.all(np.isfinite(start)) or start.max() <= 0:
        raise ValueError(f"initial_gap must be finite, of shape {h.shape}, with a positive value somewhere")
    return start


def _finite(name: str, value) -> float:
    """``float(value)``, finite; else a ``ValueError`` naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return v


#: Cap on the mean-gap evaluations of the pressure control.
MAX_OUTER = 100


def _expand(cur, prev, step):
    """Next mean gap before the root is bracketed: a secant step with a negative slope (at most 4x
    the previous step), else a doubling step towards the root; never below half the current gap."""
    gbar, f = cur[0], cur[1]
    slope = (f - prev[1]) / (gbar - prev[0]) if prev is not None and gbar != prev[0] else 0.0
    new = gbar - f / slope if slope < 0 else gbar + math.copysign(2 * abs(step), f)
    if abs(new - gbar) > 4 * abs(step):
        new = gbar + math.copysign(4 * abs(step), new - gbar)
    return gbar / 2 if new <= 0 else new


def pressure_control(it, p0, start, tol, max_iter):
    """Mean gap with ``mean(p) = p0``: secant search, then Illinois regula falsi once bracketed.

    ``f(gbar) = mean_p - p0`` decreases with ``gbar`` on the load-stable branch. Until a sign
    change is found, secant steps with a negative slope are taken (at most 4x the previous
    step), else steps doubling towards the root; each evaluation starts from the gap of
    the nearest evaluated mean gap. Returns ``(residual, AdhesiveResult)``.
    """
    def evaluate(gbar, warm):
        it.start(warm, gbar)
        it.solve(gbar, tol, max(1, max_iter - it.iterations))
        res, out = _finish(it, gbar, "pressure", it.iterations, p0)
        return [gbar, out.mean_pressure - p0, it.g.copy(), res, out]

    g0 = float(start.mean())
    cur = evaluate(g0, start)
    prev, lo, hi, side, step = None, None, None, 0, 0.01 * g0
    for _ in range(MAX_OUTER):
        gbar, f, gap, res, out = cur
        if res <= tol or it.iterations >= max_iter:
            break
        # lo: the latest evaluation with f > 0, hi: with f <= 0. Illinois: an end kept twice in a
        # row has its stored f halved (persistently), so regula falsi cannot stall on one side.
        if f > 0:
            if side == 1 and hi is not None:
                hi[1] /= 2
            lo, side = cur, 1
        else:
            if side == -1 and lo is not None:
                lo[1] /= 2
            hi, side = cur, -1
        if lo is not None and hi is not None:
            if abs(lo[0] - hi[0]) <= 1e-14 * max(lo[0], hi[0]):
                break  # a jump of the mean pressure: no equilibrium at p0 on this branch
            new = (lo[0] * hi[1] - hi[0] * lo[1]) / (hi[1] - lo[1])
        else:
            new = _expand(cur, prev, step)
            if out.area_fraction == 0 and f > 0 and gbar > g0 + 1e3 * it.law.rho:
                break  # separated: the load is beyond the pull-off
        step, prev = new - gbar, cur
        near = min((c for c in (lo, hi, cur) if c is not None), key=lambda c: abs(c[0] - new))
        cur = evaluate(new, near[2])
    it.g = cur[2]
    return cur[3], cur[4]
