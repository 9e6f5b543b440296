"""Pressure-controlled FFT-BEM normal contact solver (Polonsky & Keer 1999).

Problem
-------
A rigid rough surface with heights ``h(x, y)`` (highest points touch first; the
same convention as Tamaas, where ``h`` is the combined roughness) is pressed onto
a periodic elastic half-space of plane-strain modulus ``E*`` over a square cell of
side ``L`` sampled on ``n x n`` nodes (spacing ``dx = L / n``, node ``i`` at
``x = i * dx``, axis 0 = x, axis 1 = y). With ``p >= 0`` the nodal contact
pressure, the surface displacement into the half-space is, in Fourier space,

    u(q) = 2 p(q) / (E* |q|)   for q != 0,      u(q = 0) = 0,

``|q| = 2 pi |k| / L`` in rad per length. Fixing ``u(0) = 0`` makes ``u`` the
displacement relative to its mean; the rigid-body approach is the Lagrange
multiplier of the mean-pressure constraint ``mean(p) = p0``. The gap is

    g = u - h + d,     d = rigid-body offset,

so that ``mean(g) = d - mean(h)`` is the mean separation between the rigid
surface and the deformed half-space (the ``mean_gap`` output). The discrete
problem: ``p >= 0``, ``g >= 0``, ``p * g = 0``, ``mean(p) = p0``. With a
``hardness`` ``H`` (perfect plasticity of the interface, as in Tamaas'
``KatoSaturated``) the pressure is also capped, ``p <= H``, nodes at the cap
may interpenetrate (``g <= 0`` there) and nodes strictly between the bounds
have ``g = 0``; a mean ``p0 >= H`` cannot be carried and is refused. Each load
step is solved for the current load alone (no plastic history carried between
steps). Both problems are the optimality conditions of the convex quadratic
program ``min 1/2 p.Kp - h.p`` over ``{0 <= p (<= H), mean(p) = p0}``, ``d``
being the multiplier of the mean constraint; the solution is unique.

Units
-----
Internally the solver works in units where ``E* = L = 1`` and lengths are
counted in ``c``, the power of two just above the rms height ``s`` of ``h``
(so the internal heights have rms in [0.5, 1) and are an exact copy of ``h``);
pressures are counted in ``E* c / L``. Every load then enters through the
dimensionless ``p0 L / (E* s)``, which must lie in :data:`LOAD_RANGE` (as must
``hardness L / (E* s)``): outside it float64 cannot represent the contact
(squares of pressures or gaps overflow or underflow) and the load is refused
with a ``ValueError`` naming the argument. When ``|mean(h)| > s`` the mean is
subtracted first (a rigid shift absorbed by ``d``). A perfectly flat surface
(all heights equal) has the exact solution ``p = p0`` everywhere, ``g = 0``;
it is returned directly, with ``iterations = 0``. For the default
``E* = L = 1`` the unit changes are exact (powers of two), so the iterates are
bit for bit those of the unscaled problem.

Algorithm
---------
*Elastic* (no hardness): constrained conjugate gradient on the contact set
``F = {p > 0}`` with the mean-pressure constraint, projection onto ``p >= 0``
and Polonsky-Keer's active-set rules: nodes out of contact with a negative gap
join ``F`` and the CG restarts; a step that would take nodes below 0 is
projected, the mean restored by rescaling, and the CG continues on the reduced
set. Implementation details:

* the Fourier kernel and the pyFFTW plans are made once per grid
  (:func:`roughcontact.fft.get_fft`), all buffers are preallocated and the
  inner loop calls no BLAS routine (OpenBLAS' thread wake-up interleaved with
  FFTW costs more than the transform at these sizes);
* the search direction ``t`` is kept zero-mean on ``F``, so a step
  ``p <- p - tau t`` keeps ``mean(p)`` and, since ``u`` is linear in ``p``, the
  displacement is updated as ``u <- u - tau K t`` from the response ``K t`` that
  the step length needs anyway: such an iteration costs one FFT pair. Joining
  nodes are folded into the search direction (they start at ``p = 0``), so
  joins keep this exact update too. Only a projection (nodes leaving the
  contact set) recomputes ``u = K p`` with a second FFT pair, and so does
  the confirmation of a small residual before the final check;
* reductions run on compressed arrays over ``F`` only;
* each load step starts from the previous step's pressure scaled to the new
  ``p0`` (for the elastic problem ``u`` scales with it, so no FFT is needed).

That is the reference iteration, :data:`ELASTIC_METHOD` ``= "pk"`` (the
iteration of Tamaas' ``PolonskyKeerRey``, with the same iteration count). The
default, ``"pk-fourier"``, keeps its projections, active-set rules, stall
guard and final check, and changes two things (a third is opt-in):

* *Fourier preconditioner*: the search direction is built from
  ``z = P_F M P_F g`` with ``M = |q| E* / 2`` (the exact inverse of the
  elastic operator when ``F`` is the whole cell; 0 at ``q = 0``), ``P_F`` the
  restriction to ``F``, and ``z``'s mean over ``F`` removed; ``t = z + beta t``
  with ``beta = (g.z) / (g_old.z_old)``. At iterations where nodes join ``F``
  the gradient is re-centred on the enlarged ``F`` (a shift of ``d``) and the
  CG restarts from the preconditioned direction. One more FFT pair per
  iteration; on the paper case the iterations drop 2-3x and grow more slowly
  with ``n`` (``benchmarks/README.md``);
* *extrapolated warm start*: from the third step on, the start is the linear
  extrapolation in ``p0`` of the last two solutions, clipped at 0 and rescaled
  to the mean (one FFT pair to get ``u``), instead of the scaled last one;
* *single-precision transforms*, ``"pk-fourier-f32"``, not the default
  (``float32`` pyFFTW plans, ``FFTW_ESTIMATE`` as the double ones): the
  products ``K t`` and ``M P_F g`` of the loop are computed in ``float32``
  while ``p``, the gap, every reduction and the mean removal of the direction
  stay in ``float64``. The incremental update
  ``u <- u - tau K t`` then drifts from ``K p`` by ~1e-7 of the steps taken,
  so ``u = K p`` is recomputed in ``float64`` after every projection, when the
  residual first falls below 1e-5 and after each further four decades, and
  before the final check (which always uses a fresh ``float64`` product).
  Same iterations and answers to the tolerance, tolerances down to 1e-13
  reachable, deterministic; but float32 rounding is not a smooth function of
  the input, so problems that differ only by round-off (exact rescalings of
  heights and ``E*``) end at solutions that differ by O(``tol``) instead of
  O(1e-16): off by default for that reason (``tests/test_solver_hard_cases.py``).

*With a hardness*: the bound-constrained problem is solved by a monotone
gradient-projection / conjugate-gradient scheme (Moré & Toraldo 1991, with
Dostál's proportioning test), every step of which lowers the energy and keeps
``0 <= p <= H`` and ``mean(p) = p0``:

* the feasible set's projection is ``P(y) = clip(y - lam, 0, H)`` with the
  offset ``lam`` found by a 1-D search (Newton steps on the piecewise linear
  ``sum(clip(y - lam, 0, H))``, safeguarded by bisection): it is the exact
  projection onto ``{0 <= p <= H, mean(p) = p0}``, so the load carried by the
  capped nodes never has to be rescaled away (the free set's share
  ``p0 n^2 - H |capped|`` may be tiny or the capped set too large; the
  projection releases nodes from the cap as needed);
* with ``d`` chosen so that ``g`` has zero mean on the free set
  ``F = {0 < p < H}``, the *free gradient* is ``g`` on ``F`` and the
  *chopped gradient* the sign violations at the bounds (``g < 0`` at ``p = 0``,
  ``g > 0`` at ``p = H``); while the chopped part is not larger than the free
  part (2-norms), a CG step minimises the energy on the current face
  (direction zero-mean on ``F``); a step that would leave the box is replaced
  by the projection of the CG trial point onto the face (exact line search on
  the segment, or the full projected point when it lowers the energy), and the
  CG restarts;
* otherwise a gradient-projection step ``P(p - alpha g)`` (Barzilai-Borwein
  ``alpha``, exact line search on the segment) changes the active sets, many
  nodes at a time.

In the rigid-plastic limit (``H`` far below ``E* s / L``) this finds the
bearing-area solution in one or two steps; for a cap that is never reached it
is a CG on the contact set with gradient-projection steps for the joins, about
as many iterations as the elastic path (each one dearer: full-grid passes).

Convergence criterion
---------------------
Let ``s`` be the gap scale: the rms height of ``h`` about its mean, see
:func:`gap_scale`; ``d`` is taken so that ``g`` has zero mean on
``F = {0 < p < H}`` (``H = inf`` without hardness; when ``F`` is empty, the
offset in the middle of the admissible interval). The solver forms

    e_orth = sum_F(p |g|) / (n^2 p0 * s)      (complementarity, pressure-weighted:
                                               g ~ 0 on the elastic contact set;
                                               pointwise |g| <= ~6 tol s measured)
    e_pen  = max(0, -min g over all nodes below the cap) / s   (gap sign)
    e_cap  = max(0, max g over nodes at the cap) / s           (hardness only)

and ``residual = max(e_orth, e_pen, e_cap)``. All three terms are ratios of
gaps to ``s`` and do not depend on ``n``. A step is converged only when a final
check on ``u = K p`` recomputed by FFT from the returned pressure finds

* every value finite, ``0 <= p`` (``<= H``), ``|mean(p) - p0| <= MEAN_RTOL p0``
  (:data:`MEAN_RTOL`, 1e-10), and
* ``residual <= tol`` as defined above, hence ``g >= -tol * s`` wherever
  ``p < H`` and ``g <= tol * s`` wherever ``p = H``;

a step that fails any of these is ``converged = False``, whatever the iteration
said, and its ``residual`` is the one of the check. In floating point the gap
carries a round-off error of order ``1e-16 * max|h - mean(h)| / s`` (about
``1e-15`` for Gaussian surfaces) plus ``1e-16 * p0 L / (E* s)``, so any
``tol >= 1e-13`` is reachable at moderate loads; far past full contact
(``p0 L / (E* s)`` above roughly ``tol * 1e16``) the pressure field itself cannot
resolve the gap to ``tol`` and the step ends ``converged = False``. Should the
iteration stall (no halving of the residual within :data:`STALL_WINDOW`
iterations, or a breakdown of the step length), the step ends with
``converged = False`` and finite fields instead of running to ``max_iter``.

The FFT plans and buffers are shared per grid size within a process, so two
solves of the same size must not run concurrently in threads of one process
(separate processes, as under Snakemake, are fine).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import xarray as xr

from .fft import get_fft, wavenumbers

#: ``units`` attribute of pressures: they carry whatever unit ``e_star`` has.
PRESSURE_UNITS = "same as e_star"
#: ``units`` attribute of lengths: the unit of ``heights`` and ``length``.
LENGTH_UNITS = "same as heights"
#: ``units`` attribute of lengths per unit area.
INVERSE_LENGTH_UNITS = "1/(same as heights)"
#: ``units`` attribute of dimensionless fractions.
FRACTION_UNITS = "1"

SOLVER_NAME = "roughcontact.solver.pk_pressure"
SOLVER_DESCRIPTION = (
    "Pressure-controlled constrained conjugate gradient (Polonsky & Keer 1999) on a "
    "periodic FFT-BEM elastic half-space, u(q) = 2 p(q) / (E* |q|), Fourier-preconditioned "
    "(|q| E*/2 on the contact set) with an extrapolated warm start by default (attribute "
    "elastic_method; 'pk' is the plain iteration); with a hardness, "
    "monotone gradient-projection/CG on {0 <= p <= H, mean p = p0}; converged when "
    "max(sum_F(p|g|)/(sum(p) s), max(0,-min g below cap)/s, max(0,max g at cap)/s) <= tol "
    "with s the rms height, mean(p) = p0 to 1e-10 and 0 <= p (<= H), checked on a freshly "
    "recomputed displacement"
)

#: Default iteration cap per load step.
DEFAULT_MAX_ITER = 10000
#: A step that does not halve its best residual within this many iterations is
#: declared stalled (round-off floor or breakdown); when it progresses, the CG
#: halves the residual every ~5-20 iterations on the paper case (n <= 1024).
STALL_WINDOW = 300
#: Allowed range of the dimensionless loads ``p0 * L / (E* * s)`` and
#: ``hardness * L / (E* * s)`` (``s`` the rms height): beyond it squares of the
#: pressures or gaps leave the float64 range.
LOAD_RANGE = (1e-100, 1e100)
#: Relative tolerance of the final check ``|mean(p) - p0| <= MEAN_RTOL * p0``.
MEAN_RTOL = 1e-10
#: Largest float64 with some head room: a single node may carry ``n^2 p0``.
_FLOAT_CEILING = 1e300
#: Iterations of the elastic path (module docstring): ``"pk"``, Polonsky & Keer's
#: CG as in Tamaas' ``PolonskyKeerRey`` (the reference); ``"pk-fourier"``, the same
#: iteration with the Fourier preconditioner and an extrapolated warm start;
#: ``"pk-fourier-f32"``, the latter with single-precision transforms in the loop.
ELASTIC_METHODS = ("pk", "pk-fourier", "pk-fourier-f32")
#: Elastic iteration used by :func:`solve_contact` and :func:`solve_step`.
ELASTIC_METHOD = "pk-fourier"


@dataclass
class StepResult:
    """Outcome of one load step of :func:`solve_step`.

    Attributes
    ----------
    p0 : float
        Applied mean pressure [pressure].
    pressure : numpy.ndarray, shape (n, n)
        Nodal contact pressure ``0 <= p (<= hardness)`` [pressure].
    gap : numpy.ndarray, shape (n, n)
        Gap ``g = u - h + d`` [length]; zero (to ``tol``) on the elastic contact set.
    area_fraction : float
        Fraction of nodes with ``p > 0`` [-].
    mean_gap : float
        Mean of ``gap`` over the cell [length].
    contact_perimeter : float
        Contact-set boundary length per unit nominal area [1/length].
    iterations : int
        Iterations (CG or gradient-projection steps).
    residual : float
        Residual of the final check (module docstring) [-].
    converged : bool
        The final check on a freshly recomputed displacement passed.
    wall_time : float
        Wall-clock seconds spent in the step.
    plastic_area_fraction, plastic_load_fraction : float or None
        Fraction of nodes at the hardness cap and share of the load they carry;
        ``None`` when no hardness is given.
    """

    p0: float
    pressure: np.ndarray
    gap: np.ndarray
    area_fraction: float
    mean_gap: float
    contact_perimeter: float
    iterations: int
    residual: float
    converged: bool
    wall_time: float
    plastic_area_fraction: float | None = None
    plastic_load_fraction: float | None = None


# --------------------------------------------------------------------------- kernels
def elastic_kernel(n: int, e_star: float = 1.0, length: float = 1.0) -> np.ndarray:
    """Fourier multiplier from pressure to displacement on the rfft2 grid.

    Parameters
    ----------
    n : int
        Grid points per side.
    e_star : float
        Plane-strain modulus E* [pressure].
    length : float
        Side L of the periodic cell [length].

    Returns
    -------
    numpy.ndarray, float64, shape (n, n//2+1)
        ``2 / (E* |q|)`` [length / pressure] with ``|q| = 2 pi |k| / L``; the
        ``q = 0`` entry is 0 (the mean displacement is absorbed by the rigid-body
        approach).
    """
    kx, ky = wavenumbers(n, length)
    q = 2.0 * np.pi * np.hypot(kx, ky)
    out = np.zeros_like(q)
    np.divide(2.0 / e_star, q, out=out, where=q > 0)
    return out


def displacement(pressure: np.ndarray, *, e_star: float = 1.0, length: float = 1.0,
                 threads: int = 1) -> np.ndarray:
    """Surface displacement of the periodic half-space under a pressure field.

    Parameters
    ----------
    pressure : array_like, shape (n, n)
        Nodal pressure [pressure].
    e_star, length, threads
        As in :func:`solve_contact`.

    Returns
    -------
    numpy.ndarray, float64, shape (n, n)
        Displacement ``u`` into the half-space [length], zero mean.

    Raises
    ------
    ValueError
        For invalid input, or when ``u`` is not representable in float64.
    """
    p = _validate_heights(pressure, name="pressure")
    e_star = _check_positive("e_star", e_star)
    length = _check_positive("length", length)
    n = p.shape[0]
    fft = _plans(n, _validate_threads(threads))
    # u = (L / E*) K_1 p with K_1 the kernel for E* = L = 1; the factor is applied
    # as mantissa and exponent so that no intermediate overflows.
    pm = float(np.max(np.abs(p))) if p.size else 0.0
    if pm == 0.0:
        return np.zeros_like(p)
    ep = math.frexp(pm)[1]
    u = fft.backward(fft.forward(np.ldexp(p, -ep)) * elastic_kernel(n)).copy()
    fm, fe = _frexp_ratio((length,), (e_star,))
    with np.errstate(over="ignore", under="ignore"):
        u = np.ldexp(u * fm, fe + ep)
    if not np.all(np.isfinite(u)):
        raise ValueError("displacement: u = K p overflows float64 for this pressure, e_star and length "
                         f"(max |p| * length / e_star must stay below ~1e300; got max |p| = {pm!r}, "
                         f"e_star = {e_star!r}, length = {length!r})")
    return u


def _rms_about_mean(h: np.ndarray) -> tuple[float, float]:
    """``(mean, rms about the mean)`` of ``h`` without overflow or underflow.

    The squares are taken of ``h`` scaled by a power of two (exact) so that the
    largest entry is in [0.5, 1): for ordinary inputs the result is bit for bit
    ``sqrt(mean((h - mean(h))**2))``.
    """
    hmax = max(float(h.max()), -float(h.min()))
    if hmax == 0.0:
        return 0.0, 0.0
    e = math.frexp(hmax)[1]
    hs = np.ldexp(h, -e)
    mu = hs.mean()
    hs -= mu
    return math.ldexp(float(mu), e), math.ldexp(float(np.sqrt(np.mean(hs * hs))), e)


def gap_scale(heights: np.ndarray, p0: float, e_star: float = 1.0, length: float = 1.0) -> float:
    """Gap scale ``s`` of the convergence criterion [length].

    The rms height of ``heights`` about its mean (computed without overflow);
    for a perfectly flat surface, where that is 0, the displacement scale
    ``p0 * L / E*`` instead.
    """
    h = np.asarray(heights, dtype=float)
    rms = _rms_about_mean(h)[1] if h.size and h.max() > h.min() else 0.0
    return rms if rms > 0 else float(p0) * float(length) / float(e_star)


def contact_perimeter(mask: np.ndarray, length: float = 1.0) -> float:
    """Length of the contact-set boundary per unit nominal area [1/length].

    Counts pixel edges between a contact and a non-contact node, with periodic
    wrap in both directions, times ``dx = L / n``, divided by ``L**2``.

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (n, n)
        Contact set.
    length : float
        Side L of the cell [length].
    """
    m = np.asarray(mask, dtype=bool)
    n = m.shape[0]
    edges = np.count_nonzero(m != np.roll(m, 1, axis=0)) + np.count_nonzero(m != np.roll(m, 1, axis=1))
    return float(edges) * (length / n) / length**2


# --------------------------------------------------------------------------- validation
def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """Inner product of 1-D float arrays without BLAS.

    OpenBLAS wakes its thread pool for ``ddot``/``daxpy`` on vectors of this
    size; interleaved with FFTW calls the wake-up costs more than the FFT pair
    (measured 0.4 ms per call at 3e4 entries on 2 cores). einsum stays in numpy.
    """
    return float(np.einsum("i,i->", a, b))


def _real_scalar(name: str, value, expected: str) -> float:
    """``float(value)`` for a real number; strings, bools and the like are refused."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or (
            isinstance(value, np.ndarray) and (value.ndim != 0 or value.dtype.kind not in "iuf")):
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__} {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__} {value!r}") from None


def _check_positive(name: str, value) -> float:
    v = _real_scalar(name, value, "a finite real number > 0")
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a finite real number > 0, got {value!r}")
    return v


def _validate_heights(heights, name: str = "heights") -> np.ndarray:
    if isinstance(heights, (str, bytes)):
        raise ValueError(f"{name} must be a real numeric array, got the string {heights!r}")
    try:
        a = np.asarray(heights)
    except Exception as exc:  # ragged lists and the like
        raise ValueError(f"{name} must be a real 2-D square array of finite numbers: {exc}") from None
    if a.dtype == object or a.dtype.kind not in "iuf":
        if a.dtype.kind == "c":
            raise ValueError(f"{name} must be real, got complex dtype {a.dtype}")
        raise ValueError(f"{name} must be a real numeric array, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a 2-D square array (n, n), got shape {a.shape}")
    if a.shape[0] < 4:
        raise ValueError(f"{name} must be at least 4 x 4, got shape {a.shape}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must contain only finite values (found NaN or inf)")
    return a


def _validate_pressures(pressures) -> np.ndarray:
    if isinstance(pressures, (str, bytes)):
        raise ValueError(
            f"pressures must be a 1-D sequence of finite numbers > 0, got the string {pressures!r}")
    try:
        raw = np.asarray(pressures)
    except (TypeError, ValueError):
        raise ValueError(
            f"pressures must be a 1-D sequence of finite numbers > 0, got {pressures!r}"
        ) from None
    if raw.dtype == object or raw.dtype.kind not in "iuf":
        # strings, bools, complex numbers, ragged or mixed sequences
        raise ValueError(
            f"pressures must be a 1-D sequence of finite real numbers > 0, got {pressures!r} "
            f"(dtype {raw.dtype})"
        )
    p = raw.astype(np.float64)
    if p.ndim == 0:
        raise ValueError(
            f"pressures must be a non-empty 1-D sequence of mean pressures p0 > 0, got the scalar {pressures!r}"
        )
    if p.ndim != 1 or p.size == 0:
        raise ValueError(
            f"pressures must be a non-empty 1-D sequence of mean pressures p0 > 0, got shape {p.shape}"
        )
    if not np.all(np.isfinite(p)) or np.any(p <= 0):
        raise ValueError(f"pressures must all be finite and > 0, got {p.tolist()}")
    return p


def _validate_threads(threads) -> int:
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
        raise ValueError(f"threads must be an integer >= 1, got {threads!r}")
    return int(threads)


def _validate_solver_args(e_star, length, tol, max_iter, hardness, threads):
    e_star = _check_positive("e_star", e_star)
    length = _check_positive("length", length)
    tol_f = _real_scalar("tol", tol, "a number in the open interval (0, 1)")
    if not (0.0 < tol_f < 1.0):
        raise ValueError(f"tol must be a number in the open interval (0, 1), got {tol!r}")
    if isinstance(max_iter, (bool, np.bool_)) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    if hardness is not None:
        hardness = _check_positive("hardness", hardness)
    return e_star, length, tol_f, int(max_iter), hardness, _validate_threads(threads)


def _validate_store(store_fields, n_steps: int) -> set[int]:
    if isinstance(store_fields, (bool, np.bool_)):
        return set(range(1, n_steps + 1)) if store_fields else set()
    if isinstance(store_fields, Iterable) and not isinstance(store_fields, (str, bytes)):
        steps = set()
        for s in store_fields:
            if isinstance(s, (bool, np.bool_)) or not isinstance(s, (int, np.integer)) or not 1 <= s <= n_steps:
                raise ValueError(
                    f"store_fields must be a bool or an iterable of step numbers in 1..{n_steps}, got {s!r}"
                )
            steps.add(int(s))
        return steps
    raise ValueError(
        f"store_fields must be a bool or an iterable of step numbers in 1..{n_steps}, got {store_fields!r}"
    )


def _validate_flag(name: str, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)


# --------------------------------------------------------------------------- units
def _frexp_ratio(num, den) -> tuple[float, int]:
    """``prod(num) / prod(den)`` as ``(mantissa, exponent)``, without overflow."""
    m, e = 1.0, 0
    for x in num:
        fm, fe = math.frexp(x)
        m, e = m * fm, e + fe
    for x in den:
        fm, fe = math.frexp(x)
        m, e = m / fm, e - fe
    fm, fe = math.frexp(m)
    return fm, e + fe


class _Units:
    """Internal units of one surface (module docstring, "Units").

    Lengths are counted in ``c = 2**e_len`` (``s / c`` in [0.5, 1) with ``s`` the
    rms height), pressures in ``E* c / L = pm * 2**pe``; ``heights`` holds the
    internal (exactly scaled) heights. ``flat`` marks a surface whose heights
    are all equal.
    """

    def __init__(self, h: np.ndarray, e_star: float, length: float):
        self.e_star, self.length = e_star, length
        self.flat = not bool(h.max() > h.min())
        if self.flat:
            self.rms = 0.0
            self.heights = None
            return
        mean, rms = _rms_about_mean(h)
        self.rms = rms
        self.e_len = math.frexp(rms)[1]
        if abs(mean) > rms:
            # a rigid offset larger than the roughness: remove it (absorbed by d)
            # so that the round-off of the gap is relative to the roughness.
            h = h - mean
        self.heights = np.ldexp(h, -self.e_len)
        pm, pe = _frexp_ratio((e_star,), (length,))
        self.pm, self.pe = pm, pe + self.e_len

    def ratio_log10(self, p: float) -> float:
        """``log10(p * L / (E* s))``, the dimensionless load (no overflow)."""
        return math.log10(p) + math.log10(self.length) - math.log10(self.e_star) - math.log10(self.rms)

    def to_internal(self, p: float) -> float:
        return math.ldexp(p, -self.pe) / self.pm

    def pressure(self, p_int: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        if -1000 < self.pe < 1000:
            # one multiply by a normal float (exact for E* = L = 1: a power of two)
            return np.multiply(p_int, math.ldexp(self.pm, self.pe), out=out)
        out = np.multiply(p_int, self.pm, out=out)
        return np.ldexp(out, self.pe, out=out)

    def length_field(self, g_int):
        return np.ldexp(g_int, self.e_len)


def _check_loads(units: _Units, p: np.ndarray, hardness, n: int, name: str) -> None:
    """Refuse loads the cap cannot carry and loads outside float64's reach."""
    label = "p0" if name == "p0" else "every p0"
    if hardness is not None and np.any(p >= hardness):
        bad = float(p.max())
        raise ValueError(
            f"{name}: {label} must be in the open interval (0, hardness) = (0, {hardness!r}): a pressure "
            f"capped at the hardness cannot carry a mean load >= hardness (every applied mean pressure "
            f"must be < hardness); got {name if name == 'p0' else 'max p0'} = {bad!r}")
    top = float(p.max())
    if top * float(n) * float(n) > _FLOAT_CEILING:
        raise ValueError(
            f"{name}: {label} must be <= {_FLOAT_CEILING:g} / n**2 = {_FLOAT_CEILING / n / n:.3g} (a single "
            f"node may carry the whole load n**2 p0); got {top!r}")
    if units.flat:
        return
    lo, hi = LOAD_RANGE
    checks = [(name, label, float(x)) for x in (p.min(), p.max())]
    if hardness is not None:
        checks.append(("hardness", "hardness", hardness))
    for arg, what, value in checks:
        r = units.ratio_log10(value)
        if not (math.log10(lo) <= r <= math.log10(hi)):
            raise ValueError(
                f"{arg}: {what} * length / (e_star * s) must be in [{lo:g}, {hi:g}] with s = "
                f"{units.rms:.6g} the rms height of heights (outside it float64 cannot represent the "
                f"contact); got {what.split()[-1]} = {value!r}, i.e. 10**{r:.1f}")


# --------------------------------------------------------------------------- workspace
def _plans(n: int, threads: int):
    """The cached FFT pair for an ``n x n`` grid.

    ``get_fft`` is an ``lru_cache`` keyed on the literal arguments; for one
    thread this is the same call as :func:`roughcontact.surface.generate_surface`
    makes, so both share one set of plans and buffers (33 MB at n = 1024).
    """
    if threads == 1:
        return get_fft((n, n), backend=None)
    return get_fft((n, n), threads=threads)


class _Workspace:
    """Grid-level state reused across load steps: plans, kernel, buffers, fields.

    Everything here is in the solver's internal units (``E* = L = 1``, lengths
    in ``units.e_len`` powers of two); ``length`` is the physical cell side.
    """

    def __init__(self, heights: np.ndarray, length: float, threads: int):
        n = heights.shape[0]
        self.n = n
        self.size = n * n
        self.length = length
        self.fft = _plans(n, threads)
        kern = elastic_kernel(n)
        # Interleaved (re, im) copy so that the kernel product is a float64 ufunc
        # call on the complex buffer, with no complex temporary.
        self.kern2 = np.repeat(kern[..., None], 2, axis=-1)
        self.h = heights
        self.hf = heights.ravel()
        self.h_rms = _rms_about_mean(heights)[1]
        self.w = np.empty((n, n))  # u - h (gap without the rigid-body offset)
        self.wf = self.w.ravel()
        self.P = np.zeros((n, n))  # pressure, full field
        self.Pf = self.P.ravel()
        self.T = np.zeros((n, n))  # conjugate direction, zero off the free set
        self.Tf = self.T.ravel()
        self.mask = np.zeros((n, n), dtype=bool)
        self.bbuf = np.empty((n, n), dtype=bool)
        #: elastic iteration, one of :data:`ELASTIC_METHODS`
        if ELASTIC_METHOD not in ELASTIC_METHODS:
            raise ValueError(f"ELASTIC_METHOD must be one of {ELASTIC_METHODS}, got {ELASTIC_METHOD!r}")
        self.method = ELASTIC_METHOD
        self._minv2 = None  # preconditioner multiplier |q| E*/2, made on first use
        self.Z = None  # preconditioner input, zero off the free set
        self.fft32 = None  # single-precision plans (method "pk-fourier-f32")

    def _setup_method(self) -> None:
        """Preconditioner multiplier, its buffer and, for ``-f32``, the single plans."""
        if self.method == "pk" or self.Z is not None and (
                self.method != "pk-fourier-f32" or self.fft32 is not None):
            return
        if self.Z is None:
            kern = self.kern2[..., 0]
            minv = np.zeros_like(kern)
            np.divide(1.0, kern, out=minv, where=kern > 0)
            self._minv2 = np.repeat(minv[..., None], 2, axis=-1)
            self.Z = np.zeros((self.n, self.n))
        if self.method == "pk-fourier-f32" and self.fft32 is None:
            self.fft32 = get_fft((self.n, self.n), threads=self.fft.threads, backend=self.fft.backend,
                                 dtype=np.float32)
            self.kern2_32 = self.kern2.astype(np.float32)
            self.minv2_32 = self._minv2.astype(np.float32)

    def _product(self, field: np.ndarray, mult: np.ndarray, fft) -> np.ndarray:
        spec = fft.forward(field)
        if spec.dtype.itemsize != 2 * mult.dtype.itemsize:  # numpy.fft < 2 computes in double
            spec = spec * mult[..., 0]
        else:
            view = spec.view(mult.dtype).reshape(mult.shape)
            np.multiply(view, mult, out=view)
        return fft.backward(spec)

    def apply_m(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with ``M = |q| E* / 2`` (``K``'s inverse off ``q = 0``; 0 at ``q = 0``).

        Returns an FFT buffer that the next transform overwrites.
        """
        return self._product(field, self._minv2, self.fft)

    def apply_k32(self, field: np.ndarray) -> np.ndarray:
        """``K field`` with single-precision transforms (``float32`` buffer)."""
        return self._product(field, self.kern2_32, self.fft32)

    def apply_m32(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with single-precision transforms (``float32`` buffer)."""
        return self._product(field, self.minv2_32, self.fft32)

    def apply_k(self, field: np.ndarray) -> np.ndarray:
        """``K field`` in an FFT buffer that the next transform overwrites."""
        spec = self.fft.forward(field)
        view = spec.view(np.float64).reshape(self.kern2.shape)
        np.multiply(view, self.kern2, out=view)
        return self.fft.backward(spec)

    def refresh(self) -> None:
        """Recompute ``w = K P - h`` from the full pressure field (one FFT pair)."""
        np.subtract(self.apply_k(self.P), self.h, out=self.w)

    def scale(self, p0: float) -> float:
        return self.h_rms


def _project(y: np.ndarray, total: float, cap: float) -> np.ndarray:
    """Euclidean projection of ``y`` onto ``{0 <= x <= cap, sum(x) = total}``.

    The projection is ``x = clip(y - lam, 0, cap)`` with the offset ``lam`` such
    that ``sum(x) = total`` (requires ``0 < total < cap * y.size``):
    ``phi(lam) = sum(clip(y - lam, 0, cap)) - total`` is piecewise linear and
    non-increasing, so Newton steps (slope minus the number of nodes strictly
    inside the box) inside a bisection bracket find it, exactly once the nodes
    inside stop changing. The last rounding error of the sum is spread over
    the nodes inside the box; when the cap is below the resolution of ``y``
    (the bracket shrinks to adjacent floats with no node inside), ``x``
    interpolates between the two sides of the jump.
    """
    size = y.size
    if total >= cap * size:  # only reachable through round-off of p0 -> hardness
        return np.full_like(y, cap)
    lo = float(y.min()) - cap  # phi(lo) = size * cap - total > 0
    hi = float(y.max())  # phi(hi) = -total < 0
    lam = float(y.mean()) - total / size  # exact when nothing is clipped
    if not lo < lam < hi:
        lam = 0.5 * (lo + hi)
    z = np.empty_like(y)
    inside = np.empty(size, dtype=bool)
    for k in range(400):
        np.subtract(y, lam, out=z)
        np.greater(z, 0.0, out=inside)
        inside &= z < cap
        np.clip(z, 0.0, cap, out=z)
        phi = float(z.sum()) - total
        if abs(phi) <= 1e-14 * total:
            break
        if phi > 0:
            lo = lam
        else:
            hi = lam
        m = np.count_nonzero(inside)
        new = lam + phi / m if m and k < 100 else 0.5 * (lo + hi)
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
            if not lo < new < hi:
                # bracket collapsed onto a jump of phi: interpolate across it
                zl = np.clip(y - lo, 0.0, cap)
                zh = np.clip(y - hi, 0.0, cap)
                sl, sh = float(zl.sum()), float(zh.sum())
                theta = (total - sh) / (sl - sh) if sl > sh else 0.0
                zl -= zh
                zl *= min(max(theta, 0.0), 1.0)
                zh += zl
                return zh
        lam = new
    err = total - float(z.sum())
    if err:
        np.greater(z, 0.0, out=inside)
        inside &= z < cap
        m = np.count_nonzero(inside)
        if m:
            z[inside] += err / m
            np.clip(z, 0.0, cap, out=z)
    return z


def _enforce_mean(P: np.ndarray, target: float, hardness: float | None) -> None:
    """Make ``P.sum() == target`` in place, keeping ``0 <= P <= hardness``.

    Without a cap this is a plain rescale (uniform field if ``P`` is 0). With a
    cap, the nodes already loaded are projected onto ``{0 <= p <= H, sum = target}``
    (:func:`_project`, a common shift of their pressures) when they can carry
    ``target``; otherwise the whole field is.
    """
    if hardness is None:
        s = P.sum()
        if s > 0:
            P *= target / s
        else:
            P.fill(target / P.size)
        return
    flat = P.reshape(-1)
    np.clip(flat, 0.0, hardness, out=flat)
    pos = np.flatnonzero(flat > 0)
    if hardness * pos.size > target * (1.0 + 1e-12):
        flat[pos] = _project(flat[pos], target, hardness)
    else:
        flat[...] = _project(flat, target, hardness)


def _active_set(ws: _Workspace) -> np.ndarray:
    np.greater(ws.P, 0.0, out=ws.mask)
    return np.flatnonzero(ws.mask)


# --------------------------------------------------------------------------- elastic loop
def _pk_solve(ws: _Workspace, p0: float, tol: float, max_iter: int, fresh: bool):
    """Solve one elastic load step in place on ``ws`` from the pressure in ``ws.P``.

    ``ws.P`` must be >= 0 with mean ``p0``; ``fresh`` says whether ``ws.w``
    already equals ``K P - h``. Returns ``(iterations, converged)`` with ``ws.P``
    and ``ws.w`` consistent (``ws.w`` freshly recomputed) on exit.
    """
    target = p0 * ws.size
    scale = ws.scale(p0)
    inv_norm = 1.0 / (target * scale)
    w, wf, Pf, T, Tf, mask, bbuf = ws.w, ws.wf, ws.Pf, ws.T, ws.Tf, ws.mask, ws.bbuf
    maskf = mask.ravel()

    precond = ws.method != "pk"
    single = ws.method == "pk-fourier-f32"
    ws._setup_method()
    if precond:
        Zf = ws.Z.ravel()
    apply_m = ws.apply_m32 if single else ws.apply_m
    apply_k = ws.apply_k32 if single else ws.apply_k
    # single precision: w drifts from K p - h by ~1e-7 of the steps taken; it is
    # recomputed in float64 when the residual falls below each of these levels
    next_sync = 1e-5
    if not fresh:
        ws.refresh()
    idx = _active_set(ws)
    p_c = Pf[idx]
    t_c = np.zeros_like(p_c)
    g_c, a_c = np.empty_like(p_c), np.empty_like(p_c)
    T.fill(0.0)
    fresh = True
    delta = 0.0
    g_old = 1.0
    it = 0
    ref, it_ref = math.inf, 0
    converged = False
    gbar = 0.0
    residual = math.inf
    joined_after = 0  # > 0: nodes from this index on joined F this iteration

    while True:
        nf = idx.size
        # ---- gap on the free set, offset chosen so that it has zero mean there
        if nf:
            np.take(wf, idx, out=g_c)
            gbar = g_c.sum() / nf
            g_c -= gbar
        # ---- sign violations: out-of-contact nodes with g < 0
        np.less(w, gbar, out=bbuf)
        np.greater(bbuf, mask, out=bbuf)  # (w < gbar) & ~mask, for booleans
        ncand = np.count_nonzero(bbuf)
        pen = 0.0
        if ncand:
            cand = np.flatnonzero(bbuf)
            g_cand = wf[cand] - gbar
            pen = -float(g_cand.min())
        orth = 0.0
        if nf:
            pen = max(pen, -float(g_c.min()))
            np.abs(g_c, out=a_c)
            orth = _dot(p_c, a_c) * inv_norm
        residual = max(orth, pen / scale, 0.0)

        if residual <= tol:
            if fresh:
                converged = True
                break
            # Incremental updates may have drifted: confirm on a fresh K p.
            _sync_pressure(ws, idx, p_c, target)
            ws.refresh()
            fresh = True
            continue
        if single and residual < next_sync and not fresh:
            # float64 gap below 1e-5 and after every further four decades
            while next_sync > residual:
                next_sync *= 1e-4
            _sync_pressure(ws, idx, p_c, target)
            ws.refresh()
            fresh = True
            continue
        if not math.isfinite(residual) or it >= max_iter:
            break
        if residual < 0.5 * ref:
            ref, it_ref = residual, it
        elif it - it_ref >= STALL_WINDOW:
            break
        it += 1

        # ---- violating nodes join the free set and the CG restarts (PK's rule):
        # folding them into the search direction keeps the update of u exact.
        if ncand:
            joined_after = nf
            idx = np.concatenate([idx, cand])
            p_c = np.concatenate([p_c, np.zeros(ncand)])
            g_c = np.concatenate([g_c, g_cand])
            a_c = np.empty_like(p_c)
            t_c = np.empty_like(p_c)
            maskf[cand] = True
            delta = 0.0
            nf = idx.size
        if nf == 0:
            break

        # ---- conjugate direction (zero mean on F, so mean(p) is kept) and step
        if precond:
            if joined_after:
                # gradient on the enlarged set: zero mean on F (shifts d only)
                g_c -= g_c.sum() / nf
                joined_after = 0
            # z = P_F M P_F g, zero mean on F; beta = g.z / g_old.z_old
            Zf[idx] = g_c
            _take(apply_m(ws.Z).ravel(), idx, a_c)
            Zf[idx] = 0.0
            a_c -= a_c.sum() / nf
            G = _dot(g_c, a_c)
            if not (G > 0.0 and math.isfinite(G)):
                break  # breakdown at round-off level: the final check decides
            if delta > 0.0 and g_old > 0.0:
                t_c *= G / g_old
                t_c += a_c
            else:
                t_c[...] = a_c
        else:
            G = _dot(g_c, g_c)
            if delta > 0.0 and g_old > 0.0:
                t_c *= delta * G / g_old
                t_c += g_c
            else:
                t_c[...] = g_c
                if joined_after:
                    # Restore zero mean on the nodes already in contact only: each
                    # joining node keeps t = g (< 0), so the step moves it into the
                    # contact set as PK's rule does instead of clipping it at once.
                    # g.t = |g|^2 still holds because g has zero mean on the old
                    # free set.
                    t_c[:joined_after] -= t_c.sum() / joined_after
                joined_after = 0
        g_old = G
        delta = 1.0
        Tf[idx] = t_c
        Rf = apply_k(T).ravel()
        _take(Rf, idx, a_c)
        rt = _dot(a_c, t_c)
        tau = _dot(g_c, t_c) / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tau) and tau > 0.0):
            break  # null direction: nothing can move, report as not converged
        # trial pressure in a_c
        np.multiply(t_c, -tau, out=a_c)
        a_c += p_c
        n_out = np.count_nonzero(a_c <= 0.0)
        if n_out == 0:
            p_c, a_c = a_c, p_c
            np.multiply(Rf, Rf.dtype.type(tau), out=Rf)
            wf -= Rf  # u <- u - tau K t: exact, no FFT pair for p
            fresh = False
            continue

        # ---- Polonsky-Keer projection onto p >= 0, exact mean, fresh K p
        np.maximum(a_c, 0.0, out=a_c)
        Pf[idx] = a_c
        _enforce_mean(ws.P, target, None)
        idx = _active_set(ws)
        t_c = Tf[idx]
        if t_c.size:
            t_c -= t_c.mean()
        T.fill(0.0)
        p_c = Pf[idx]
        g_c, a_c = np.empty_like(p_c), np.empty_like(p_c)
        ws.refresh()
        fresh = True

    Pf[idx] = p_c
    if not fresh:
        _sync_pressure(ws, idx, p_c, target)
        ws.refresh()
    # An early exit right after nodes joined leaves them flagged with p = 0.
    np.greater(ws.P, 0.0, out=mask)
    return it, converged


def _take(src: np.ndarray, idx: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = src[idx]``, converting a float32 ``src`` to float64."""
    if src.dtype == out.dtype:
        np.take(src, idx, out=out)
    else:
        out[...] = src[idx]


def _sync_pressure(ws, idx, p_c, target):
    """Write the contact-set pressure back to the full field with the exact mean.

    Between full rebuilds the mean drifts only by round-off; the rescale is
    ``1 + O(1e-16)`` and keeps ``mean(p) = p0`` to machine precision.
    """
    if not p_c.size:
        return
    s = p_c.sum()
    if s > 0 and target > 0:
        p_c *= target / s
    ws.Pf[idx] = p_c


# --------------------------------------------------------------------------- capped loop
def _offset_no_free(w, zero, capd) -> float:
    """``gbar = -d`` when no node is strictly between the bounds.

    Any ``d`` in ``[max(-w) over p = 0, min(-w) over p = H]`` satisfies the sign
    conditions; the middle of that interval is taken (or of the violated one,
    which minimises the largest violation).
    """
    lo = float((-w[zero]).max()) if zero.any() else -math.inf
    hi = float((-w[capd]).min()) if capd.any() else math.inf
    if math.isfinite(lo) and math.isfinite(hi):
        d = 0.5 * (lo + hi)
    elif math.isfinite(lo):
        d = lo
    elif math.isfinite(hi):
        d = hi
    else:
        d = 0.0
    return -d


def _box_solve(ws: _Workspace, p0: float, tol: float, max_iter: int, cap: float, fresh: bool):
    """Solve one capped load step in place on ``ws`` from the pressure in ``ws.P``.

    ``ws.P`` must satisfy ``0 <= P <= cap`` with mean ``p0``. Gradient
    projection / CG with proportioning (module docstring); every step lowers
    the energy ``1/2 p.Kp - h.p`` and keeps the bounds and the mean. Returns
    ``(iterations, converged)`` with ``ws.w`` freshly recomputed on exit.

    The sets ``p = 0``, ``p = H`` and the free set (index array ``idx``) change
    only in projection steps; a CG step inside the face touches the full grid
    only for the transform, the update of ``w`` and two sign tests.
    """
    n2 = ws.size
    target = p0 * n2
    scale = ws.scale(p0)
    inv_norm = 1.0 / (target * scale)
    P, w = ws.Pf, ws.wf
    shape = ws.P.shape
    if not fresh:
        ws.refresh()
    fresh = True
    zero_m = np.empty(n2, dtype=bool)
    cap_m = np.empty(n2, dtype=bool)
    b1 = np.empty(n2, dtype=bool)
    t = np.zeros(n2)  # CG direction, zero off the free set
    kt = np.empty(n2)

    def active_sets():
        np.less_equal(P, 0.0, out=zero_m)
        np.greater_equal(P, cap, out=cap_m)
        np.logical_or(zero_m, cap_m, out=b1)
        np.logical_not(b1, out=b1)
        return np.flatnonzero(b1)

    idx = active_sets()
    g_old = 0.0
    restart = True
    alpha = 0.0  # gradient-projection step length; 0 = not known yet
    it = 0
    ref, it_ref = math.inf, 0
    converged = False
    residual = math.inf

    while True:
        nf = idx.size
        p_f = P[idx]
        g_f = w[idx]
        if nf:
            gbar = float(g_f.sum()) / nf
            g_f -= gbar
        else:
            gbar = _offset_no_free(w, zero_m, cap_m)
        # sign violations: g < 0 at p = 0, g > 0 at p = H
        np.less(w, gbar, out=b1)
        b1 &= zero_m
        vz = np.flatnonzero(b1)
        g_z = w[vz] - gbar
        np.greater(w, gbar, out=b1)
        b1 &= cap_m
        vc = np.flatnonzero(b1)
        g_c = w[vc] - gbar
        pen = max(0.0, -float(g_z.min()) if vz.size else 0.0, -float(g_f.min()) if nf else 0.0)
        e_cap = float(g_c.max()) if vc.size else 0.0
        orth = _dot(p_f, np.abs(g_f)) * inv_norm if nf else 0.0
        residual = max(orth, pen / scale, e_cap / scale)

        if residual <= tol:
            if fresh:
                converged = True
                break
            ws.refresh()
            fresh = True
            continue
        if not math.isfinite(residual) or it >= max_iter:
            break
        if residual < 0.5 * ref:
            ref, it_ref = residual, it
        elif it - it_ref >= STALL_WINDOW:
            break
        it += 1

        # ---- proportioning: sign violations at the bounds vs gradient on the face
        chopped = _dot(g_z, g_z) + _dot(g_c, g_c)
        G = _dot(g_f, g_f)
        if nf == 0 or chopped > G:
            # ---- gradient projection: P(p - alpha g), exact line search on the segment
            g = w - gbar
            if not alpha > 0.0:
                r = np.zeros(n2)  # projected gradient: free part and violations
                r[idx] = g_f
                r[vz] = g_z
                r[vc] = g_c
                act = np.concatenate([idx, vz, vc])
                r[act] -= r[act].mean()
                kr = ws.apply_k(r.reshape(shape)).ravel()
                rkr = _dot(r, kr)
                alpha = _dot(r, r) / rkr if rkr > 0.0 else 1.0
            step = _project(P - alpha * g, target, cap)
            step -= P
            ks = ws.apply_k(step.reshape(shape)).ravel()
            sks, gs = _dot(step, ks), _dot(g, step)
            if not (sks > 0.0 and gs < 0.0 and math.isfinite(sks)):
                break  # no descent left at this precision: report as not converged
            theta = min(1.0, -gs / sks)
            alpha = _dot(step, step) / sks  # Barzilai-Borwein, for the next projection
            if theta < 1.0:
                step *= theta
                ks *= theta
            P += step
            np.clip(P, 0.0, cap, out=P)
            w += ks
            idx = active_sets()
            restart = True
            fresh = False
            continue

        # ---- conjugate gradient on the face {0 < p < H}, direction zero-mean there
        if restart or g_old <= 0.0:
            t.fill(0.0)
            t_f = g_f
        else:
            t_f = t[idx]
            t_f *= G / g_old
            t_f += g_f
        t[idx] = t_f
        g_old = G
        restart = False
        np.copyto(kt, ws.apply_k(t.reshape(shape)).ravel())
        tkt, rt = _dot(t_f, kt[idx]), _dot(g_f, t_f)
        if not (tkt > 0.0 and rt > 0.0 and math.isfinite(tkt)):
            break  # null direction: report as not converged
        tau = rt / tkt
        alpha = tau
        y_f = p_f - tau * t_f
        if y_f.min() > 0.0 and y_f.max() < cap:
            P[idx] = y_f
            kt *= tau
            w -= kt
            fresh = False
            continue
        # the CG step leaves the box: project the trial point onto the face
        # {0 <= p_F <= H, sum p_F fixed} and search on the segment to it
        x_f = _project(y_f, float(p_f.sum()), cap)
        s_f = x_f - p_f
        step = np.zeros(n2)
        step[idx] = s_f
        ks = ws.apply_k(step.reshape(shape)).ravel()
        sks, gs = _dot(s_f, ks[idx]), _dot(g_f, s_f)
        if sks > 0.0 and gs < 0.0:
            theta = 1.0 if gs + 0.5 * sks < 0.0 else -gs / sks  # the projected point if it lowers the energy
            if theta >= 1.0:
                P[idx] = x_f
            else:
                P[idx] = np.clip(p_f + theta * s_f, 0.0, cap)
                ks *= theta
            w += ks
        else:
            # truncated CG step: up to the first bound met along -t
            with np.errstate(divide="ignore", invalid="ignore"):
                lim = np.where(t_f > 0.0, p_f / t_f, np.where(t_f < 0.0, (p_f - cap) / t_f, np.inf))
            j = int(np.argmin(lim))
            tmax = float(lim[j])
            if not (math.isfinite(tmax) and tmax >= 0.0):
                break  # no bound ahead although the trial left the box: round-off, give up
            new = np.clip(p_f - tmax * t_f, 0.0, cap)
            new[j] = 0.0 if t_f[j] > 0.0 else cap
            P[idx] = new
            kt *= tmax
            w -= kt
        idx = active_sets()
        restart = True
        fresh = False

    if not fresh:
        ws.refresh()
    np.greater(ws.P, 0.0, out=ws.mask)
    return it, converged


# --------------------------------------------------------------------------- final check
def _final_check(ws: _Workspace, p0: float, tol: float, cap: float | None):
    """The invariants of the module docstring on ``ws.P`` and a fresh ``ws.w``.

    Returns ``(ok, residual, gbar, w_sum)``: ``gbar`` is ``-d``, the offset that
    makes the gap zero-mean on the free set, ``w_sum`` the sum of ``ws.w``. A NaN
    or inf anywhere makes a sum non-finite, so finiteness is read off the sums.
    """
    P, w = ws.Pf, ws.wf
    target = p0 * ws.size
    scale = ws.scale(p0)
    p_sum, w_sum = float(P.sum()), float(w.sum())
    if not (math.isfinite(p_sum) and math.isfinite(w_sum)):
        return False, math.inf, 0.0, w_sum
    bounds = float(P.min()) >= 0.0 and (cap is None or float(P.max()) <= cap)
    mean_ok = abs(p_sum - target) <= MEAN_RTOL * target
    pos = ws.mask.ravel()
    np.greater(P, 0.0, out=pos)
    if cap is None:
        free = pos
        capd = None
    else:
        capd = P >= cap
        free = pos & ~capd
    w_f = w[free]
    nf = w_f.size
    if nf:
        gbar = float(w_f.mean())
        w_f -= gbar
        e_orth = _dot(P[free], np.abs(w_f)) / (target * scale)
    else:
        gbar = _offset_no_free(w, ~pos, capd if capd is not None else np.zeros_like(pos))
        e_orth = 0.0
    if capd is None:
        e_pen = max(0.0, gbar - float(w.min())) / scale
        e_cap = 0.0
    else:
        below = ~capd
        e_pen = max(0.0, gbar - float(w[below].min())) / scale if below.any() else 0.0
        e_cap = max(0.0, float(w[capd].max()) - gbar) / scale if capd.any() else 0.0
    residual = max(e_orth, e_pen, e_cap)
    ok = bounds and mean_ok and residual <= tol
    return ok, residual, gbar, w_sum


# --------------------------------------------------------------------------- public API
@dataclass
class _Step:
    """Physical outputs of one solved load step (internal)."""

    pressure: np.ndarray
    mask: np.ndarray
    area: float
    mean_gap: float
    perimeter: float
    iterations: int
    residual: float
    converged: bool
    n_sat: int
    gbar: float


class _Solver:
    """Validated problem of one surface: units, workspace and the step loop."""

    def __init__(self, h, e_star, length, tol, max_iter, hardness, threads):
        self.n = h.shape[0]
        self.length = length
        self.tol, self.max_iter, self.hardness = tol, max_iter, hardness
        self.units = _Units(h, e_star, length)
        self.threads = threads
        self.ws = None if self.units.flat else _Workspace(self.units.heights, length, threads)
        self.cap = None
        if hardness is not None and not self.units.flat:
            self.cap = self.units.to_internal(hardness)
        self.prev = None  # internal p0 of the last solved step
        self._older = None  # (p0, pressure) of the step before the last
        self._last = None  # pressure of the last step
        self._pbuf = np.empty((self.n, self.n))

    @property
    def backend(self) -> str:
        return (self.ws.fft if self.ws is not None else _plans(self.n, self.threads)).backend

    def start(self, p0: float, initial=None) -> bool:
        """Put the starting pressure for ``p0`` in the workspace; returns ``fresh``."""
        ws, cap = self.ws, self.cap
        p_int = self.units.to_internal(p0)
        target = p_int * ws.size
        if initial is not None:
            np.maximum(initial, 0.0, out=ws.P)
            if cap is None:
                top = float(ws.P.max())
                if top > 0:
                    ws.P /= top
            else:
                np.minimum(ws.P, self.hardness, out=ws.P)
                ws.P *= cap / self.hardness
            _enforce_mean(ws.P, target, cap)
            return False
        if cap is not None and p_int >= cap:
            # p0 within an ulp of the hardness: every node at the cap
            ws.P.fill(cap)
            return False
        if self.prev is None:
            ws.P.fill(p_int)
            return False
        s = p_int / self.prev
        c = 0.0
        if cap is None and ws.method != "pk" and self._older is not None and self._older[0] != self.prev:
            c = (p_int - self.prev) / (self.prev - self._older[0])
        if 0.0 < c <= 2.0:
            # Extrapolated warm start, linear in the load through the last two
            # solutions (loads moving on in the same direction, by at most twice
            # the last increment); otherwise the scaled last solution below.
            P_old = self._older[1]
            ws.P -= P_old
            ws.P *= c
            ws.P += self._last
            np.maximum(ws.P, 0.0, out=ws.P)
            _enforce_mean(ws.P, target, None)
            return False
        if cap is None:
            # Warm start: p and u = K p scale together, so w = K p - h follows
            # without a transform.
            ws.w *= s
            ws.w += (s - 1.0) * ws.h
            ws.P *= s
            return True
        ws.P *= s
        _enforce_mean(ws.P, target, cap)
        return False

    def solve(self, p0: float, initial=None, keep_gap: bool = False):
        """Solve the step for the physical mean pressure ``p0``; returns ``(_Step, gap)``."""
        n2 = self.n * self.n
        if self.units.flat:
            # exact solution: u = K p0 = 0, so g = 0 with d = h
            p = np.full((self.n, self.n), p0)
            mean_ok = abs(float(p.sum()) - p0 * n2) <= MEAN_RTOL * p0 * n2
            gap = np.zeros((self.n, self.n)) if keep_gap else None
            return _Step(p, p > 0, 1.0, 0.0, 0.0, 0, 0.0, mean_ok, 0, 0.0), gap
        ws, units, cap = self.ws, self.units, self.cap
        fresh = self.start(p0, initial)
        p_int = units.to_internal(p0)
        if cap is None:
            its, _ = _pk_solve(ws, p_int, self.tol, self.max_iter, fresh)
        else:
            its, _ = _box_solve(ws, p_int, self.tol, self.max_iter, cap, fresh)
        ok, residual, gbar, w_sum = _final_check(ws, p_int, self.tol, cap)
        if cap is None and ws.method != "pk":
            self._older = None if self.prev is None else (self.prev, self._last)
            self._last = ws.P.copy()
        self.prev = p_int
        p = units.pressure(ws.P, out=self._pbuf)
        n_sat = 0
        if cap is not None:
            p[ws.P >= cap] = self.hardness  # exactly the cap in physical units too
            np.minimum(p, self.hardness, out=p)
            n_sat = int(np.count_nonzero(p >= self.hardness))
        mask = p > 0
        area = np.count_nonzero(mask) / n2
        if area <= 0:
            raise RuntimeError(f"no contact node at p0={p0!r}: the solver lost the load (bug)")
        mean_gap = math.ldexp(w_sum / n2 - gbar, units.e_len)
        gap = None
        if keep_gap:
            gap = units.length_field(ws.w - gbar)
        if not (math.isfinite(mean_gap) and (gap is None or np.all(np.isfinite(gap)))):
            raise ValueError(
                f"pressures: the gap at p0={p0!r} overflows float64 in the units of heights; reduce "
                "p0 * length / e_star or the heights")
        step = _Step(p, mask, area, mean_gap, contact_perimeter(mask, self.length), its,
                     float(residual), bool(ok), n_sat, gbar)
        return step, gap


def _plastic_stats(hardness, n_sat, p0, n2):
    if hardness is None:
        return None, None
    return n_sat / n2, hardness * n_sat / (p0 * n2)


def solve_step(heights, p0: float, *, e_star: float = 1.0, length: float = 1.0,
               tol: float = 1e-8, max_iter: int = DEFAULT_MAX_ITER, threads: int = 1,
               hardness: float | None = None, initial_pressure=None) -> StepResult:
    """Solve the contact for one mean pressure.

    Parameters
    ----------
    heights : array_like, shape (n, n)
        Rigid surface heights [length]; the highest points touch first.
    p0 : float
        Applied mean pressure [pressure]: ``0 < p0``, ``p0 < hardness`` if a
        hardness is given, and ``p0 * length / (e_star * s)`` in
        :data:`LOAD_RANGE` (``s`` the rms height).
    e_star, length, tol, max_iter, threads, hardness
        As in :func:`solve_contact`.
    initial_pressure : array_like, shape (n, n), optional
        Starting pressure (clipped to ``[0, hardness]`` and brought to mean
        ``p0``); uniform ``p0`` when omitted.

    Returns
    -------
    StepResult
        Fields are fresh arrays owned by the caller.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    h = _validate_heights(heights)
    p0_f = _real_scalar("p0", p0, "a finite number > 0")
    if not (math.isfinite(p0_f) and p0_f > 0):
        raise ValueError(f"p0 must be a finite number > 0, got {p0!r}")
    e_star, length, tol, max_iter, hardness, threads = _validate_solver_args(
        e_star, length, tol, max_iter, hardness, threads)
    init = None
    if initial_pressure is not None:
        init = _validate_heights(initial_pressure, name="initial_pressure")
        if init.shape != h.shape:
            raise ValueError(f"initial_pressure must have shape {h.shape}, got {init.shape}")
    solver = _Solver(h, e_star, length, tol, max_iter, hardness, threads)
    _check_loads(solver.units, np.array([p0_f]), hardness, h.shape[0], "p0")
    t0 = time.perf_counter()
    st, gap = solver.solve(p0_f, initial=init, keep_gap=True)
    wall = time.perf_counter() - t0
    pa, pl = _plastic_stats(hardness, st.n_sat, p0_f, h.size)
    return StepResult(p0_f, st.pressure.copy(), gap, st.area, st.mean_gap, st.perimeter,
                      st.iterations, st.residual, st.converged, wall, pa, pl)


def solve_contact(heights, pressures, *, e_star: float = 1.0, length: float = 1.0,
                  tol: float = 1e-8, max_iter: int = DEFAULT_MAX_ITER, store_fields=False,
                  threads: int = 1, hardness: float | None = None,
                  clusters: bool = False) -> xr.Dataset:
    """Solve the normal contact of a rigid rough surface on a periodic half-space.

    Parameters
    ----------
    heights : array_like, shape (n, n)
        Rigid surface heights [length] on the square periodic cell, axis 0 = x,
        axis 1 = y; the highest points touch first. Any ``n >= 4``, odd or not.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures ``p0 > 0``, one load step each [pressure, same unit
        as ``e_star``], each with ``p0 * length / (e_star * s)`` in
        :data:`LOAD_RANGE` (``s`` the rms height of ``heights``) and, with a
        hardness, ``p0 < hardness``. Any order is accepted; each step
        warm-starts from the previous one, which pays off most for increasing
        loads.
    e_star : float
        Plane-strain modulus ``E* = E / (1 - nu**2)`` of the half-space, > 0.
    length : float
        Side ``L`` of the periodic cell [length], > 0.
    tol : float
        Convergence tolerance in (0, 1) on the scale-free residual of the module
        docstring.
    max_iter : int
        Iteration cap per step, >= 1.
    store_fields : bool or iterable of int
        ``True`` stores ``contact_pressure`` and ``gap`` for every step (dims
        ``step, x, y``); an iterable of 1-based step numbers stores only those
        (dims ``field_step, x, y``, coordinate ``field_step`` = step numbers).
    threads : int
        FFTW threads (default 1).
    hardness : float, optional
        Cap on the pressure (perfectly plastic interface) [pressure], > every p0,
        with ``hardness * length / (e_star * s)`` in :data:`LOAD_RANGE`.
    clusters : bool
        Add contact-cluster statistics per step (periodic 4-connected labelling, see
        :mod:`roughcontact.clusters`): ``cluster_count``, ``cluster_mean_area``,
        ``cluster_max_area`` and ``cluster_area_histogram``. Off: no labelling work.

    Returns
    -------
    xarray.Dataset
        Dimension ``step`` (coordinate 1..n_steps) with ``pressure``,
        ``area_fraction``, ``mean_contact_pressure``, ``mean_gap``,
        ``contact_perimeter``, ``iterations``, ``residual``, ``converged``,
        ``wall_time`` and, with a hardness, ``plastic_area_fraction`` and
        ``plastic_load_fraction``; fields and ``x``/``y`` coordinates only when
        stored. Every variable carries ``units`` and ``long_name``.
        ``converged`` is True only when the final check of the module docstring
        passed on a freshly recomputed displacement.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    h = _validate_heights(heights)
    p = _validate_pressures(pressures)
    e_star, length, tol, max_iter, hardness, threads = _validate_solver_args(
        e_star, length, tol, max_iter, hardness, threads)
    store = _validate_store(store_fields, p.size)
    clusters = _validate_flag("clusters", clusters)
    n = h.shape[0]
    solver = _Solver(h, e_star, length, tol, max_iter, hardness, threads)
    _check_loads(solver.units, p, hardness, n, "pressures")

    n_steps = p.size
    cols = {k: np.empty(n_steps) for k in
            ("area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter",
             "residual", "wall_time", "plastic_area_fraction", "plastic_load_fraction")}
    iters = np.empty(n_steps, dtype=np.int64)
    conv = np.empty(n_steps, dtype=bool)
    fields_p, fields_g, field_steps = [], [], []
    masks = [] if clusters else None
    for k, p0 in enumerate(p):
        p0 = float(p0)
        t0 = time.perf_counter()
        st, gap = solver.solve(p0, keep_gap=k + 1 in store)
        pa, pl = _plastic_stats(hardness, st.n_sat, p0, n * n)
        cols["wall_time"][k] = time.perf_counter() - t0
        cols["area_fraction"][k] = st.area
        cols["mean_contact_pressure"][k] = p0 / st.area
        cols["mean_gap"][k] = st.mean_gap
        cols["contact_perimeter"][k] = st.perimeter
        cols["residual"][k] = st.residual
        cols["plastic_area_fraction"][k] = pa if pa is not None else 0.0
        cols["plastic_load_fraction"][k] = pl if pl is not None else 0.0
        iters[k] = st.iterations
        conv[k] = st.converged
        if k + 1 in store:
            fields_p.append(st.pressure.copy())
            fields_g.append(gap)
            field_steps.append(k + 1)
        if masks is not None:
            masks.append(st.mask.copy())

    ds = _to_dataset(p, cols, iters, conv, fields_p, fields_g, field_steps, store_fields,
                     n, e_star, length, tol, max_iter, hardness, threads, solver.backend)
    ds.attrs["elastic_method"] = solver.ws.method if solver.ws is not None else ELASTIC_METHOD
    if masks is not None:
        from .clusters import cluster_dataset

        stats = cluster_dataset(masks, ds["step"].values, length)
        ds = ds.merge(stats.drop_vars("step"), combine_attrs="override")
    return ds


def _to_dataset(p, cols, iters, conv, fields_p, fields_g, field_steps, store_fields, n,
                e_star, length, tol, max_iter, hardness, threads, backend) -> xr.Dataset:
    steps = np.arange(1, p.size + 1)
    meta = {
        "pressure": (p, PRESSURE_UNITS, "applied mean pressure p0 = F / A0"),
        "area_fraction": (cols["area_fraction"], FRACTION_UNITS,
                          "real contact area fraction A / A0 (fraction of nodes with p > 0)"),
        "mean_contact_pressure": (cols["mean_contact_pressure"], PRESSURE_UNITS,
                                  "mean contact pressure F / A = p0 / (A / A0)"),
        "mean_gap": (cols["mean_gap"], LENGTH_UNITS,
                     "mean gap between the rigid surface and the deformed half-space"),
        "contact_perimeter": (cols["contact_perimeter"], INVERSE_LENGTH_UNITS,
                              "contact-set boundary length (pixel edges x dx) per unit nominal area"),
        "iterations": (iters, FRACTION_UNITS, "solver iterations (CG or gradient-projection steps)"),
        "residual": (cols["residual"], FRACTION_UNITS,
                     "final scale-free residual max(sum_F(p|g|)/(sum(p) s), max(0,-min g below cap)/s, "
                     "max(0,max g at cap)/s) on a freshly recomputed displacement"),
        "converged": (conv, FRACTION_UNITS,
                      "residual <= tol, mean(p) = p0 to 1e-10 and 0 <= p (<= hardness) on a freshly "
                      "recomputed displacement"),
        "wall_time": (cols["wall_time"], "s", "wall-clock time of the load step"),
    }
    if hardness is not None:
        meta["plastic_area_fraction"] = (cols["plastic_area_fraction"], FRACTION_UNITS,
                                         "fraction of nodes at the hardness cap")
        meta["plastic_load_fraction"] = (cols["plastic_load_fraction"], FRACTION_UNITS,
                                         "share of the load carried by nodes at the hardness cap")
    data_vars = {name: xr.Variable(("step",), val, {"units": u, "long_name": ln})
                 for name, (val, u, ln) in meta.items()}
    coords = {"step": xr.Variable(("step",), steps, {"units": FRACTION_UNITS,
                                                      "long_name": "load step number (1-based)"})}
    if field_steps:
        dim = "step" if (isinstance(store_fields, (bool, np.bool_)) and store_fields) else "field_step"
        dims = (dim, "x", "y")
        xs = np.arange(n) * (length / n)
        coords["x"] = xr.Variable(("x",), xs, {"units": LENGTH_UNITS, "long_name": "node position along axis 0"})
        coords["y"] = xr.Variable(("y",), xs.copy(), {"units": LENGTH_UNITS, "long_name": "node position along axis 1"})
        if dim == "field_step":
            coords["field_step"] = xr.Variable(("field_step",), np.array(field_steps),
                                               {"units": FRACTION_UNITS,
                                                "long_name": "load step number of the stored fields"})
        data_vars["contact_pressure"] = xr.Variable(
            dims, np.stack(fields_p), {"units": PRESSURE_UNITS, "long_name": "nodal contact pressure"})
        data_vars["gap"] = xr.Variable(
            dims, np.stack(fields_g), {"units": LENGTH_UNITS,
                                       "long_name": "gap between the rigid surface and the half-space"})
    attrs = {
        "e_star": e_star,
        "length": length,
        "tol": tol,
        "max_iter": max_iter,
        "threads": threads,
        "fft_backend": backend,
        "n": n,
        "solver": SOLVER_NAME,
        "solver_description": SOLVER_DESCRIPTION,
        "pressure_units": PRESSURE_UNITS,
    }
    if hardness is not None:
        attrs["hardness"] = hardness
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


__all__ = [
    "DEFAULT_MAX_ITER",
    "ELASTIC_METHOD",
    "ELASTIC_METHODS",
    "FRACTION_UNITS",
    "INVERSE_LENGTH_UNITS",
    "LENGTH_UNITS",
    "LOAD_RANGE",
    "MEAN_RTOL",
    "PRESSURE_UNITS",
    "STALL_WINDOW",
    "StepResult",
    "contact_perimeter",
    "displacement",
    "elastic_kernel",
    "gap_scale",
    "solve_contact",
    "solve_step",
]
