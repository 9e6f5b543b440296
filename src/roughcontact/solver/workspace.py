"""Grid-level state of one surface reused across load steps: operator, fields, buffers."""

from __future__ import annotations

import math

import numpy as np
from numba.extending import register_jitable

from ..core.backend import get_backend
from ..core.cell import Cell
from .halfspace import half_space
from .units import rms_about_mean

#: Iterations of the elastic path (docs/solver.md, "Algorithm"): ``"pk"``, Polonsky & Keer's
#: CG as in Tamaas' ``PolonskyKeerRey`` (the reference); ``"pk-fourier"``, the same
#: iteration with the Fourier preconditioner and an extrapolated warm start;
#: ``"pk-fourier-f32"``, the latter with single-precision transforms in the loop.
ELASTIC_METHODS = ("pk", "pk-fourier", "pk-fourier-f32")

#: The iterations a stalled step moves on to, in turn, from its pressure when it stalled (each
#: more robust and slower): single-precision products -> float64 products -> the monotone gradient
#: projection ``"box"`` (Moré & Toraldo; every move lowers the energy, so it cannot cycle).
FALLBACKS = {"pk-fourier-f32": ("pk-fourier", "box"), "pk-fourier": ("box",), "pk": ("box",), "box": ()}

#: Whether a step that needed a fallback makes the method that converged it the start of the
#: following steps of the same surface (contact.ContactSolver._iterate).
STICKY = True

#: Every way a step can end (the per-step ``solver_path`` codes): the exact answer of a flat
#: surface, one of the elastic iterations, or the bounded (hardness) iteration.
SOLVER_PATHS = ("exact", *ELASTIC_METHODS, "box")


#: A step that does not halve its best residual within this many iterations is
#: declared stalled (round-off floor or breakdown); when it progresses, the CG
#: halves the residual every ~5-20 iterations on the paper case (n <= 1024).
STALL_WINDOW = 300


#: After a projection that takes at least this fraction of ``F`` out of contact, the next ``beta``
#: is Fletcher-Reeves' (as after a full projection) instead of Polak-Ribiere's. Measured: on
#: frt-2's plateau (SurfaceTopography's file) Polak-Ribiere's kept history cycles with period 2
#: (~11 000 nodes join, ~4 400 leave) until the stall guard; Fletcher-Reeves' converges the step in
#: 16 iterations. On synthetic surfaces a projection clips ~10 of ~17 000 nodes: the rule rarely
#: applies there, and it changed the iterations by less than 1 % (4 cases at N = 512).
FR_AFTER_LOSS = 0.1


@register_jitable
def stall_rule(residual: float, it: int, max_iter: int, best: float, at: int,
               window: int = STALL_WINDOW) -> tuple[bool, float, int]:
    """The stop rule of every iteration: ``(stop, best, at)`` at iteration ``it`` with this ``residual``.

    A step ends unconverged at a non-finite residual, at ``max_iter``, or when its best residual ``best``
    (reached at iteration ``at``) has not been halved within ``window`` iterations; a residual below half
    the best becomes the new best. :func:`loop_head` applies it.
    """
    if not math.isfinite(residual) or it >= max_iter:
        return True, best, at
    if residual < 0.5 * best:
        best, at = residual, it
    return it - at >= window, best, at  # (a window of 0 stops at once)


#: The decisions of :func:`loop_head`: the case iterates, has converged, waits for ``w`` recomputed in float64,
#: or stops unconverged.
GO, CONVERGED, WAIT, STOP = 0, 1, 2, 3


@register_jitable
def loop_head(residual: float, tol: float, fresh: bool, level: float, levels: bool, it: int, max_iter: int,
              best: float, at: int, window: int) -> tuple[int, float, float, int]:
    """The elastic iteration's loop head for a case that is neither done nor waiting: ``(decision, level, best, at)``.

    With ``residual <= tol`` the case has converged where ``w`` is fresh (``K P - h`` recomputed in float64 since
    the last step), and waits for that recomputation otherwise: incremental updates may have drifted. With
    ``levels`` (the float32 iteration) a residual below ``level`` on a stale ``w`` waits for it too, and the level
    falls by four decades until it is below the residual (``w`` recomputed below 1e-5 and after every further four
    decades). Otherwise the stall guard (:func:`stall_rule`) stops the case or lets it iterate (:data:`GO`).

    Written once: the single solve's kernels (:mod:`.compressed`) call it, and numba compiles it into the batched
    CPU kernels (``register_jitable``). The array kernels (:class:`~.batch.kernels.ArrayKernels`, numpy or CuPy)
    and the CUDA kernels write it over their per-case arrays, with at most six lowerings of the level a call;
    tests/test_batch.py holds the host's forms to this one (the CUDA kernel runs on a GPU only).
    """
    if residual <= tol:
        return (CONVERGED if fresh else WAIT), level, best, at
    if levels and residual < level and not fresh:
        while level > residual:
            level *= 1e-4
        return WAIT, level, best, at
    stop, best, at = stall_rule(residual, it, max_iter, best, at, window)
    return (STOP if stop else GO), level, best, at


class StallGuard:
    """:func:`stall_rule` with its state, for an iteration of its own (the capped one, :mod:`.box`)."""

    def __init__(self, max_iter: int):
        self.max_iter = max_iter
        self.best, self.at = math.inf, 0

    def stop(self, residual: float, it: int) -> bool:
        """Whether iteration ``it`` with this ``residual`` ends the step (unconverged)."""
        stop, self.best, self.at = stall_rule(residual, it, self.max_iter, self.best, self.at, STALL_WINDOW)
        return stop


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """Inner product of 1-D float arrays without BLAS.

    OpenBLAS wakes its thread pool for ``ddot``/``daxpy`` on vectors of this
    size; interleaved with FFTW calls the wake-up costs more than the FFT pair
    (measured 0.4 ms per call at 3e4 entries on 2 cores). einsum stays in numpy.
    """
    return float(np.einsum("i,i->", a, b))


class Workspace:
    """Fields of one surface in internal units (``E* = Lx = 1``, lengths in powers of two).

    The fields have the heights' shape ``(nx, ny)`` (``shape``; ``size = nx * ny`` nodes);
    ``length`` is the cell's, a float ``L`` or a pair ``(Lx, Ly)``, of which the operator
    takes the aspect ``Ly / Lx``. ``P`` the pressure, ``w = K P - h`` the gap without the rigid-body offset,
    ``T`` the search direction (zero off the free set), ``mask`` the contact
    set; ``op`` the elastic operator (:func:`~.halfspace.half_space` for
    ``boundary``) and ``method`` the elastic iteration, one of
    :data:`ELASTIC_METHODS`. The ``apply_*`` methods are the operator's
    products (one FFT pair each; the benchmark counts them here). ``scale``
    replaces the rms height of ``heights`` as the gap scale (a flat punch,
    whose heights have none). ``backend`` names the array backend the fields live on
    (:mod:`roughcontact.core.backend`; ``xp`` is its array module): ``heights`` are host
    numpy, everything here is the backend's.
    """

    def __init__(self, heights: np.ndarray, length: float, threads: int, method: str,
                 boundary: str = "periodic", scale: float | None = None, backend: str = "numpy"):
        if method not in ELASTIC_METHODS:
            raise ValueError(f"method must be one of {ELASTIC_METHODS}, got {method!r}")
        shape = self.shape = heights.shape
        self.size = shape[0] * shape[1]
        self.length = length
        self.method = method
        self.boundary = boundary
        self.be = get_backend(backend)
        xp = self.xp = self.be.xp
        self.op = half_space(boundary, shape, threads, Cell.of(shape, length).aspect, self.be)
        self.h_rms = rms_about_mean(heights)[1] if scale is None else scale
        self.h = self.be.asarray(heights)
        self.hf = self.h.ravel()
        self.w = xp.empty(shape)
        self.wf = self.w.ravel()
        self.P = xp.zeros(shape)
        self.Pf = self.P.ravel()
        self.T = xp.zeros(shape)
        self.Tf = self.T.ravel()
        self.mask = xp.zeros(shape, dtype=bool)
        self.bbuf = xp.empty(shape, dtype=bool)
        self.Z = None  # preconditioner input, zero off the free set
        self._nodes = (None, None)  # (flat indices, their (rows, columns)): see nodes()

    @property
    def backend(self) -> str:
        return self.op.backend

    @property
    def sigma(self) -> float:
        """Scale of the float32 products: their results are divided by it."""
        return self.op.sigma

    def setup_method(self) -> None:
        """Preconditioner buffer and, for ``-f32``, the single-precision products."""
        if self.method != "pk" and self.Z is None:
            self.Z = self.xp.zeros(self.shape)
        if self.method == "pk-fourier-f32":
            self.op.single(self.h_rms)

    def apply_k(self, field: np.ndarray) -> np.ndarray:
        """``K field`` in an FFT buffer that the next transform overwrites."""
        return self.op.apply(field)

    def apply_m(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with ``M = |q| E* / 2`` (``K``'s inverse off ``q = 0`` when periodic)."""
        return self.op.apply_inverse(field)

    def apply_k32(self, field: np.ndarray) -> np.ndarray:
        """``K field / sigma`` with single-precision transforms (``float32`` buffer)."""
        return self.op.apply32(field)

    def refresh(self) -> None:
        """Recompute ``w = K P - h`` from the full pressure field (one FFT pair)."""
        np.subtract(self.apply_k(self.P), self.h, out=self.w)

    def scale(self, p0: float) -> float:
        """Gap scale ``s`` of the convergence criterion, internal units."""
        return self.h_rms

    def nodes(self, idx: np.ndarray):
        """``(rows, columns)`` of the flat indices ``idx``, to read a product's 2-D result at them.

        A float64 product may be a strided view of its buffer (rows padded in place), where a flat
        read would copy the whole grid first. Cached for the same array: the iterations pass one
        array while their set does not change.
        """
        if self._nodes[0] is not idx:
            self._nodes = (idx, np.divmod(idx, self.shape[1]))
        return self._nodes[1]

    def active_set(self) -> np.ndarray:
        """Flat indices of ``P > 0`` (and ``mask`` set to them)."""
        np.greater(self.P, 0.0, out=self.mask)
        return np.flatnonzero(self.mask)
