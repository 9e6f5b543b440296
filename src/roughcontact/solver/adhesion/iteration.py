"""The gap iteration of adhesive contact: :func:`solve_adhesive` and its :class:`AdhesiveIteration`.

Polonsky & Keer's constrained conjugate gradient on the gap (:mod:`roughcontact.solver.adhesion`, "Algorithm"),
under displacement control, wrapped by :func:`pressure_control` for an imposed mean pressure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.cell import Cell
from ...core.fft import get_fft
from ..halfspace import inverse_kernel
from ..workspace import dot
from .laws import LAWS, MIN_ZONE_CELLS, positive, zone_cells

#: Default iteration cap of :func:`solve_adhesive` (all inner iterations of one call).
DEFAULT_MAX_ITER = 20000
#: Relative tolerance on the imposed mean gap in the final check.
MEAN_GAP_RTOL = 1e-12

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
    """``heights`` as float64 ``(nx, ny)`` and ``length`` checked: the float ``L`` or ``(Lx, Ly)`` of its
    :meth:`~roughcontact.core.cell.Cell.canonical` cell (the same sides, so the same kernel, bit for bit)."""
    h = np.ascontiguousarray(heights, dtype=np.float64)
    if h.ndim != 2 or h.shape[0] < 4 or h.size < 4:
        raise ValueError(f"heights must be a 2-D array (nx, ny) with nx >= 4 (ny = 1 for a 1-D profile), "
                         f"got shape {h.shape}")
    if not np.all(np.isfinite(h)):
        raise ValueError("heights must contain only finite values (found NaN or inf)")
    return h, Cell.canonical(h.shape, length, "heights").length


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
        mean_gap = positive("mean_gap", mean_gap)
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
    e_star, tol = positive("e_star", e_star), positive("tol", tol)
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
