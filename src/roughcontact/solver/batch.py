"""Many surfaces in one solve: the batched elastic iteration (issue 48).

:func:`solve_contact_batch` solves ``B`` surfaces of one grid under one load schedule together.
Every field carries a leading case axis, ``(B, nx, ny)``; every transform is one batched
``rfft2`` / ``irfft2`` over the last two axes (cuFFT or scipy.fft batches them); every reduction
runs along ``(-2, -1)`` and gives one number per case, kept as a ``(B, 1, 1)`` array so that it
broadcasts back onto the fields. The iteration is the default elastic one,
``"pk-fourier-f32"`` (:class:`~.elastic.PKIteration`): Polonsky & Keer's CG on the free set
``F``, the Fourier preconditioner ``M = |q| E* / 2`` with Polak-Ribiere's ``beta`` kept across
joins, the projection onto ``p >= 0`` with the mean restored by rescaling, float32 products in the
loop, float64 recomputations of ``w = K p - h`` below the residual levels 1e-5, 1e-9, ... and to
confirm convergence, the stall guard and the final check on a fresh displacement. It is written
with masks instead of index sets: ``F`` is a boolean field, ``p``, ``t`` and the gradients are
zero off ``F``, and what a case does in a round (iterate, wait for a float64 recomputation, stop)
is a per-case boolean, so a round is the same sequence of array operations for every case and
nothing in it needs the host.

Per case, the iteration is the single solve's: a converged case is frozen (its pressure, gap and
iteration count stop changing) while the others go on, and a case waiting for a float64
recomputation is frozen until the next *check*, where the host reads the per-case flags (one
small transfer: the only host synchronisation of the loop) and recomputes ``w`` for those cases.
The check comes every ``check_every`` rounds (:data:`CHECK_EVERY`), between the measure and the
move of a round; a waiting case idles until then, which costs rounds but never iterations: the
iteration counts do not depend on ``check_every``, and with ``check_every = 1`` the rounds are
the iterations of the slowest case. The transforms differ from the single solve's (batched scipy.fft or cuFFT
against pyFFTW's in-place plans, a projected step's change transformed by itself), so the
iterates agree to round-off of float32 products, not bit for bit: the same A/A0 to the
tolerance, iteration counts equal or within one or two per step (tests/test_batch.py).

Not batched: a step whose iteration stalls or breaks down moves on to the fallbacks of
:data:`~.workspace.FALLBACKS` on that case alone (a :class:`~.workspace.Workspace` of its own, the
single solve's code), and the following steps start on the batched iteration again (no
``STICKY``). Effects, the free boundary, the other elastic methods, flat surfaces, stored fields,
clusters and observers are refused with a ``ValueError``.

On CuPy the hot element-wise passes and per-case reductions are fused into a few
``ElementwiseKernel`` / ``ReductionKernel`` calls (:class:`_CupyKernels`, made only when CuPy is
importable; each is checked once against the plain array expressions and replaced by them if it
disagrees), cuFFT plans come from CuPy's plan cache (one shape, ``(B, nx, ny)``, for a whole solve),
and compiled kernels are cached on disk (``CUPY_CACHE_DIR``, :func:`roughcontact.core.backend.get_backend`).
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np
import xarray as xr

from ..core.backend import get_backend
from .box import box_solve
from .check import MEAN_RTOL
from .elastic import FR_AFTER_LOSS, pk_solve
from .halfspace import elastic_kernel
from .results import SOLVER_NAME, cell_attrs, solver_description, to_dataset
from .settings import SolverSettings
from .units import Units, cell_aspect, check_loads, internal_length
from .validation import validate_heights, validate_pressures
from .workspace import FALLBACKS, SOLVER_PATHS, STALL_WINDOW, Workspace

#: The only elastic iteration a batch runs (the package default).
BATCH_METHOD = "pk-fourier-f32"

#: Rounds between two reads of the per-case flags by the host, per array backend, when the caller
#: gives none. A read drains the GPU's queue of kernels, but a round of a batch of 1024² cases keeps
#: the GPU busy for milliseconds and the host needs only tens of microseconds to launch the next
#: kernel, while a case that asks for a float64 recomputation between two reads idles until the
#: next (15-30 % more rounds at 8): every round on both backends until measured otherwise
#: (benchmarks/gpu/run.sh measures 1 and 8).
CHECK_EVERY = {"numpy": 1, "cupy": 1}

#: Per-case variables of the batched dataset (dims ``case, step``).
PER_CASE = ("area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter", "iterations",
            "residual", "converged", "solver_path")


# --------------------------------------------------------------------------------------------
# transforms and kernels
# --------------------------------------------------------------------------------------------


class _BatchFFT:
    """Real 2-D transforms over the last two axes of a ``(B, nx, ny)`` batch.

    numpy backend: :mod:`scipy.fft` (``workers`` threads); CuPy: :mod:`cupyx.scipy.fft` (cuFFT,
    plans from CuPy's plan cache: the batch keeps one shape, so one plan per precision and
    direction serves the whole solve); a stand-in CuPy without ``cupyx`` (tests): the array
    module's ``fft``. The inverse is unnormalised (``norm="forward"``): the ``1 / (nx ny)`` sits in
    the multipliers.
    """

    def __init__(self, be, shape, threads: int = 1):
        self.shape = tuple(shape)
        self.kw, self.ikw = {}, {}
        mod = be.xp.fft  # no SciPy; the tests' stand-in CuPy (numpy's fft under CuPy's name)
        try:
            if be.name == "numpy":
                import scipy.fft as mod

                self.kw = {"workers": threads}
            elif hasattr(be.xp, "ElementwiseKernel"):  # the real CuPy
                import cupyx.scipy.fft as mod
            # the spectrum is not needed after the inverse: cuFFT's c2r may destroy it, no copy first
            if mod is not be.xp.fft:
                self.ikw = {**self.kw, "overwrite_x": True}
        except ImportError:
            mod = be.xp.fft
        self.mod = mod

    def rfft2(self, x):
        return self.mod.rfft2(x, axes=(-2, -1), **self.kw)

    def irfft2(self, spec):
        return self.mod.irfft2(spec, s=self.shape, axes=(-2, -1), norm="forward", **self.ikw)


class _Kernels:
    """The element-wise passes and per-case reductions of a round, as plain array expressions.

    Every argument is an array of the backend: fields ``(B, nx, ny)``, per-case numbers
    ``(B, 1, 1)``. Results of reductions are ``(B, 1, 1)`` float64 (or int64 for counts).
    :class:`_CupyKernels` replaces them by fused CUDA kernels (one pass over the fields each) with
    the same results up to the order of summation; the methods named "in place" must update their
    field arguments in place in both.
    """

    def __init__(self, xp):
        self.xp = xp

    def rsum(self, x):
        return self.xp.sum(x, axis=(-2, -1), keepdims=True, dtype=np.float64)

    def rcount(self, m):
        return self.xp.sum(m, axis=(-2, -1), keepdims=True, dtype=np.int64)

    def rmin(self, x):
        return self.xp.min(x, axis=(-2, -1), keepdims=True)

    def masked_sum(self, x, mask):
        """``sum(x where mask)`` per case."""
        return self.rsum(x * mask)

    def orth(self, P, w, gbar, F):
        """``sum_F p |w - gbar|`` per case (complementarity, unnormalised)."""
        return self.rsum(P * self.xp.abs(w - gbar) * F)

    def dot(self, a, b):
        return self.rsum(a * b)

    def to32(self, x, scale):
        """``float32(x * scale)``: the product in float64, rounded once (as ``SpectralProduct.load``)."""
        return (x * scale).astype(np.float32)

    def quadratic(self, spec, weights):
        """``sum(weights |spec|^2)`` per case over the half spectrum (float32 terms, float64 sum)."""
        re, im = spec.real, spec.imag
        return self.rsum(weights * (re * re + im * im))

    def scaled_into(self, R, factor, F):
        """``R * factor`` on ``F``, 0 off it, float64 (``R`` a float32 product)."""
        return R * factor * F

    def add_scaled(self, w, R, factor):
        """``w += R * factor`` in place (``R`` float32, ``w`` float64)."""
        w += R * factor
        return w

    def sub_masked(self, x, c, F):
        """``x -= c`` on ``F`` in place (``c`` per case)."""
        x -= c * F
        return x

    def join_gap(self, w, gbar, F, go):
        """The free set after the join (``F | w < gbar`` where ``go``) and the gap ``w - gbar`` on it, 0 off it."""
        Fn = self.xp.where(go, F | (w < gbar), F)
        return Fn, (w - gbar) * Fn

    def descent_dot(self, g, t, beta, a):
        """``g . (beta t + a)`` per case."""
        return self.rsum(g * (t * beta + a))

    def new_direction(self, t, a, g, beta, keep, go, g_prev):
        """In place: ``t = beta t + a`` where ``keep``, else ``a`` where ``go``; ``g_prev = g`` where ``go``."""
        xp = self.xp
        t[...] = xp.where(keep, t * beta + a, xp.where(go, a, t))
        g_prev[...] = xp.where(go, g, g_prev)

    def proj_any(self, P, t, tau, F):
        """Whether ``p - tau t <= 0`` at a node of ``F``, per case."""
        return self.xp.any(F & (P - tau * t <= 0.0), axis=(-2, -1), keepdims=True)

    def pos_sum(self, P, t, tau):
        """``sum(max(p - tau t, 0))`` per case."""
        return self.rsum(self.xp.maximum(P - tau * t, 0.0))

    def project(self, P, t, tau, go, scale, inv_sigma):
        """The step where ``go``: ``P`` (in place) becomes ``scale max(p - tau t, 0)``; returns the change, float32.

        ``scale`` is ``target / sum(max(trial, 0))`` for projected cases and 1 for the others. The
        change is ``max(-trial, 0) + (scale - 1) max(trial, 0) - tau t`` (the single solve's
        ``x - tau t`` of :meth:`~.elastic.PKIteration._project_single`; ``-tau t`` unprojected), 0
        where not ``go``, times ``inv_sigma`` and rounded to float32 for the transform.
        """
        xp = self.xp
        trial = P - tau * t
        tp = xp.maximum(trial, 0.0)
        change = (tp - trial) + (scale - 1.0) * tp - tau * t
        change *= go
        P[...] = xp.where(go, tp * scale, P)
        return (change * inv_sigma).astype(np.float32)

    def shrink(self, P, F, t, g_prev):
        """In place: nodes of ``F`` whose pressure is 0 leave it; ``t`` and ``g_prev`` are 0 off ``F``."""
        keep = P > 0.0
        F &= keep
        t *= keep
        g_prev *= keep


def _cupy_kernels(xp):
    """:class:`_CupyKernels` for the real CuPy, each kernel checked once; plain kernels otherwise."""
    if not hasattr(xp, "ElementwiseKernel"):  # numpy, or the tests' stand-in
        return _Kernels(xp)
    try:
        kernels = _CupyKernels(xp)
    except Exception as exc:  # noqa: BLE001 (any failure to build: run the plain expressions)
        warnings.warn(f"batched solve: fused CuPy kernels unavailable ({type(exc).__name__}: {exc}); "
                      "using plain array expressions", RuntimeWarning, stacklevel=2)
        return _Kernels(xp)
    kernels.self_check()
    return kernels


class _CupyKernels(_Kernels):
    """Fused CUDA kernels for the passes of a round (CuPy only).

    Each fuses what the plain expressions do in two to six passes (and their temporaries) into
    one pass over the fields; per-case numbers are ``(B, 1, 1)`` arrays broadcast onto them.
    Built only when CuPy is importable; :meth:`self_check` compares each with :class:`_Kernels` on
    a small random batch and falls back to the plain expression, with a warning, where they differ.
    """

    #: the methods :meth:`self_check` compares
    FUSED = ("masked_sum", "orth", "dot", "to32", "quadratic", "scaled_into", "add_scaled", "sub_masked",
             "join_gap", "descent_dot", "new_direction", "proj_any", "pos_sum", "project", "shrink")

    def __init__(self, cp):
        super().__init__(cp)
        self.cp = cp
        R, E = cp.ReductionKernel, cp.ElementwiseKernel
        self._orth = R("float64 p, float64 w, float64 gbar, bool f", "float64 y",
                       "f ? p * fabs(w - gbar) : 0.0", "a + b", "y = a", "0", "rc_batch_orth")
        self._msum = R("float64 x, bool f", "float64 y", "f ? x : 0.0", "a + b", "y = a", "0", "rc_batch_msum")
        # (inputs are not called a or b: those name the accumulators of the reduction)
        self._dot = R("float64 u, float64 v", "float64 y", "u * v", "a + b", "y = a", "0", "rc_batch_dot")
        self._quad = R("float32 re, float32 im, float32 wq", "float64 y", "(double)(wq * (re * re + im * im))",
                       "a + b", "y = a", "0", "rc_batch_quad")
        self._ddot = R("float64 g, float64 t, float64 beta, float64 z", "float64 y", "g * (t * beta + z)",
                       "a + b", "y = a", "0", "rc_batch_ddot")
        self._pany = R("float64 p, float64 t, float64 tau, bool f", "int32 y",
                       "(f && p - tau * t <= 0.0) ? 1 : 0", "max(a, b)", "y = a", "0", "rc_batch_pany")
        self._psum = R("float64 p, float64 t, float64 tau", "float64 y", "fmax(p - tau * t, 0.0)",
                       "a + b", "y = a", "0", "rc_batch_psum")
        self._to32 = E("float64 x, float64 s", "float32 y", "y = (float)(x * s)", "rc_batch_to32")
        self._scaled = E("float32 r, float64 c, bool f", "float64 y", "y = f ? (double)r * c : 0.0",
                         "rc_batch_scaled")
        self._add = E("float32 r, float64 c", "float64 w", "w += (double)r * c", "rc_batch_add")
        self._subm = E("float64 c, bool f", "float64 x", "if (f) x -= c", "rc_batch_subm")
        self._join = E("float64 w, float64 gbar, bool f, bool go", "bool fn, float64 g",
                       "fn = go ? (f || w < gbar) : f; g = fn ? w - gbar : 0.0", "rc_batch_join")
        self._newdir = E("float64 z, float64 g, float64 beta, bool keep, bool go", "float64 t, float64 gp",
                         "t = keep ? t * beta + z : (go ? z : t); if (go) gp = g", "rc_batch_newdir")
        self._project = E(
            "float64 t, float64 tau, bool go, float64 s, float64 isig", "float64 p, float32 d32",
            """
            double trial = p - tau * t;
            double tp = trial > 0.0 ? trial : 0.0;
            double d = go ? (tp - trial) + (s - 1.0) * tp - tau * t : 0.0;
            d32 = (float)(d * isig);
            if (go) p = tp * s;
            """, "rc_batch_project")
        self._shrink = E("float64 p", "bool f, float64 t, float64 gp",
                         "if (!(p > 0.0)) { f = false; t = 0.0; gp = 0.0; }", "rc_batch_shrink")
        self.fused = True

    def _reduce(self, kernel, *args):
        return kernel(*args, axis=(1, 2), keepdims=True)

    def masked_sum(self, x, mask):
        return self._reduce(self._msum, x, mask)

    def orth(self, P, w, gbar, F):
        return self._reduce(self._orth, P, w, gbar, F)

    def dot(self, a, b):
        return self._reduce(self._dot, a, b)

    def to32(self, x, scale):
        return self._to32(x, scale)

    def quadratic(self, spec, weights):
        return self._reduce(self._quad, spec.real, spec.imag, weights)

    def scaled_into(self, R, factor, F):
        return self._scaled(R, factor, F)

    def add_scaled(self, w, R, factor):
        self._add(R, factor, w)
        return w

    def sub_masked(self, x, c, F):
        self._subm(c, F, x)
        return x

    def join_gap(self, w, gbar, F, go):
        return self._join(w, gbar, F, go)

    def descent_dot(self, g, t, beta, a):
        return self._reduce(self._ddot, g, t, beta, a)

    def new_direction(self, t, a, g, beta, keep, go, g_prev):
        self._newdir(a, g, beta, keep, go, t, g_prev)

    def proj_any(self, P, t, tau, F):
        return self._reduce(self._pany, P, t, tau, F) > 0

    def pos_sum(self, P, t, tau):
        return self._reduce(self._psum, P, t, tau)

    def project(self, P, t, tau, go, scale, inv_sigma):
        d32 = self.cp.empty(P.shape, dtype=np.float32)
        self._project(t, tau, go, scale, inv_sigma, P, d32)
        return d32

    def shrink(self, P, F, t, g_prev):
        self._shrink(P, F, t, g_prev)

    def self_check(self) -> None:
        """Each fused kernel against :class:`_Kernels` on a random batch; the plain one where they differ."""
        cp = self.cp
        plain = _Kernels(cp)
        rng = np.random.default_rng(0)
        B, n = 3, 16

        def field():
            return cp.asarray(rng.standard_normal((B, n, n)))

        a, b, c = field(), field(), field()
        pos = cp.abs(field())
        pos[0, :2, :3] = 0.0  # nodes at p = 0: the projection and the shrink must see them
        f = cp.asarray(rng.random((B, n, n)) < 0.5)
        s = cp.asarray(rng.random((B, 1, 1)) + 0.5)
        go = cp.asarray(np.array([True, False, True]).reshape(B, 1, 1))
        keep = cp.asarray(np.array([True, False, False]).reshape(B, 1, 1))
        spec = cp.fft.rfft2(a.astype(np.float32), axes=(-2, -1))
        wq = cp.asarray(rng.random((n, n // 2 + 1)).astype(np.float32))
        r32 = a.astype(np.float32)
        calls = {
            "masked_sum": lambda k: k.masked_sum(a, f), "orth": lambda k: k.orth(pos, b, s, f),
            "dot": lambda k: k.dot(a, b), "to32": lambda k: k.to32(a, s), "quadratic": lambda k: k.quadratic(spec, wq),
            "scaled_into": lambda k: k.scaled_into(r32, s, f), "add_scaled": lambda k: k.add_scaled(a.copy(), r32, s),
            "sub_masked": lambda k: k.sub_masked(a.copy(), s, f), "join_gap": lambda k: k.join_gap(a, s * 0.1, f, go),
            "descent_dot": lambda k: k.descent_dot(a, b, s, c),
            "new_direction": lambda k: _inplace(lambda t, gp: k.new_direction(t, a, c, s, keep, go, gp), b, c * 2),
            "proj_any": lambda k: k.proj_any(pos, b, s * 0.1, f), "pos_sum": lambda k: k.pos_sum(pos, b, s * 0.1),
            "project": lambda k: _inplace(lambda p: (k.project(p, b, s * 0.1, go, s, 1.0 / s),), pos),
            "shrink": lambda k: _inplace(lambda p, ff, t, gp: k.shrink(p, ff, t, gp), pos - 0.5, f, a, b),
        }
        for name in self.FUSED:
            try:
                got, want = _as_tuple(calls[name](self)), _as_tuple(calls[name](plain))
                ok = len(got) == len(want) and all(
                    g.shape == wv.shape and g.dtype == wv.dtype
                    and bool(cp.allclose(g.astype(np.float64), wv.astype(np.float64), rtol=1e-5, atol=1e-6))
                    for g, wv in zip(got, want, strict=True))
                why = "results differ"
            except Exception as exc:  # noqa: BLE001
                ok, why = False, f"{type(exc).__name__}: {exc}"
            if not ok:
                warnings.warn(f"batched solve: fused kernel {name!r} failed its check ({why}); using the plain "
                              "expression", RuntimeWarning, stacklevel=2)
                setattr(self, name, getattr(plain, name))
                self.fused = False


def _inplace(fn, *fields):
    """Copies of ``fields``, ``fn``'s results on them, and the copies after ``fn`` (for in-place kernels)."""
    copies = [x.copy() for x in fields]
    out = fn(*copies)
    return (*_as_tuple(out), *copies)


def _as_tuple(x):
    return () if x is None else (x if isinstance(x, tuple) else (x,))


class BatchOperator:
    """The periodic half-space's products on a ``(B, nx, ny)`` batch, internal units (``E* = Lx = 1``).

    ``K`` (float64 and float32) and the preconditioner ``M = |q| E* / 2`` (float32), multipliers of
    shape ``(nx, ny // 2 + 1)`` carrying the inverse transform's ``1 / (nx ny)``, and Parseval's
    weights for ``x . K x``. float32 inputs are divided by each case's ``sigma`` (its internal rms
    height, ``(B, 1, 1)``) before the cast, as the single solve's products.
    """

    def __init__(self, be, shape, aspect: float, threads: int, kernels: _Kernels):
        self.be, self.xp, self.k = be, be.xp, kernels
        nx, ny = self.shape = tuple(shape)
        self.fft = _BatchFFT(be, shape, threads)
        if be.name == "cupy":
            # one plan per shape, precision and direction: the batch's and the float64 refreshes'
            # power-of-two subsets (<= 2 log2(B) + 6 plans) stay in CuPy's plan cache (default 16)
            try:
                cache = be.xp.fft.config.get_plan_cache()
                cache.set_size(max(cache.get_size(), 64))
            except AttributeError:  # the tests' stand-in
                pass
        kern = elastic_kernel(self.shape, 1.0, internal_length(aspect))
        minv = np.zeros_like(kern)
        np.divide(1.0, kern, out=minv, where=kern > 0)
        norm = 1.0 / (nx * ny)
        herm = np.full(ny // 2 + 1, 2.0)  # columns standing for their Hermitian mirror count twice
        herm[0] = 1.0
        if ny % 2 == 0:
            herm[-1] = 1.0
        self.kmult64 = be.asarray(kern * norm)
        self.kmult32 = be.asarray((kern * norm).astype(np.float32))
        self.mmult32 = be.asarray((minv * norm).astype(np.float32))
        self.kquad32 = be.asarray((kern * herm[None, :] * norm).astype(np.float32))

    def spectrum32(self, x, inv_sigma):
        """float32 spectrum of ``x * inv_sigma`` (one batched forward transform)."""
        return self.fft.rfft2(self.k.to32(x, inv_sigma))

    def quadratic32(self, spec):
        """``x . (K x) / sigma^2`` per case from :meth:`spectrum32`'s spectrum, ``(B, 1, 1)`` float64."""
        return self.k.quadratic(spec, self.kquad32)

    def inverse32(self, spec, mult):
        """``F^-1[mult spec]``: float32 ``(B, nx, ny)`` (the spectrum is overwritten)."""
        spec *= mult
        return self.fft.irfft2(spec)

    def apply64(self, P):
        """``K P`` in float64, ``(B, nx, ny)``."""
        spec = self.fft.rfft2(P)
        spec *= self.kmult64
        return self.fft.irfft2(spec)


# --------------------------------------------------------------------------------------------
# the batched iteration of one load step
# --------------------------------------------------------------------------------------------


class BatchIteration:
    """:class:`~.elastic.PKIteration` (``pk-fourier-f32``) on ``B`` cases at once, with masks.

    State per case (fields ``(B, nx, ny)``, numbers ``(B, 1, 1)``): ``P`` (the solver's, zero off
    ``F``) and ``w = K P - h`` (the solver's, updated in place), ``F`` the free set, ``t`` the
    direction and ``g_prev`` the last direction's gradient (zero off ``F``), ``g_old``, ``delta``,
    whether ``g_prev`` is valid, the iteration count, the stall guard's best residual and its
    iteration, ``next_sync``, and the round's flags: ``done`` (converged or stopped), ``waiting``
    (for a float64 recomputation at the next check), ``fresh`` (``w`` recomputed since the last
    step). ``fresh0`` per case is the single solve's ``fresh`` argument as an int: 1 True, 0 False
    (recomputed first), -1 None.
    """

    def __init__(self, solver: BatchSolver, p_int, fresh0, max_iter):
        self.s, xp = solver, solver.xp
        self.xp, self.k, self.op = xp, solver.kernels, solver.op
        B = solver.batch
        self.tol = solver.tol
        self.p_int = p_int  # (B, 1, 1) float64 on the device
        self.target = p_int * solver.size
        self.scale = solver.h_rms  # (B, 1, 1)
        self.inv_norm = 1.0 / (self.target * self.scale)
        self.sigma, self.inv_sigma = solver.h_rms, 1.0 / solver.h_rms
        self.max_iter = max_iter  # (B,) host ints
        must = np.flatnonzero(fresh0 == 0)
        if must.size:
            solver.refresh(must)
        self.fresh = xp.asarray((fresh0 >= 0).reshape(B, 1, 1))  # refreshed ones are fresh now
        self.F = solver.P > 0.0
        self.nF = self.k.rcount(self.F)
        self.t = xp.zeros_like(solver.P)
        self.g_prev = xp.zeros_like(solver.P)
        self.gprev_ok = xp.zeros((B, 1, 1), dtype=bool)
        self.delta = xp.zeros((B, 1, 1))
        self.g_old = xp.ones((B, 1, 1))
        self.it = xp.zeros((B, 1, 1), dtype=np.int64)
        self.best = xp.full((B, 1, 1), math.inf)
        self.at = xp.zeros((B, 1, 1), dtype=np.int64)
        self.next_sync = xp.full((B, 1, 1), 1e-5)
        self.done = xp.zeros((B, 1, 1), dtype=bool)
        self.converged = xp.zeros((B, 1, 1), dtype=bool)
        self.waiting = xp.zeros((B, 1, 1), dtype=bool)
        self.max_iter_d = xp.asarray(np.asarray(max_iter, dtype=np.int64).reshape(B, 1, 1))
        self.rounds = 0

    def run(self, check_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Iterate every case to convergence or a stop; ``(iterations, converged)`` per case (host).

        A round measures every case, then moves those that iterate. Every ``check_every``-th round
        the host reads the per-case flags between the two (the only host synchronisation of the
        loop: a few bytes per case), recomputes ``w`` in float64 for the cases waiting for it and
        lets them measure again, as the single solve's loop does after its recomputations, so that
        they move in that same round. With ``check_every = 1`` no case ever waits; with more, a case
        that asks for a recomputation idles until the next check.
        """
        s = self.s
        while True:
            for j in range(check_every):
                self.measure()
                if j == check_every - 1 and self.check():
                    break
                self.act()
                self.rounds += 1
            else:
                continue
            break
        self.finish()
        return (s.be.to_host(self.it).reshape(-1).astype(np.int64),
                s.be.to_host(self.converged).reshape(-1).astype(bool))

    def _flags(self):
        s = self.s
        flags = s.be.to_host(self.xp.concatenate([self.done.reshape(-1), self.waiting.reshape(-1)]))
        return flags[: s.batch], flags[s.batch:]

    def check(self) -> bool:
        """The host's check after a measure: recomputations for the waiting cases; True when all are done."""
        done, waiting = self._flags()
        sync = np.flatnonzero(waiting)
        if sync.size:
            self.resync(sync)
            idx = self.s.xp.asarray(sync)
            self.fresh[idx] = True
            self.waiting[idx] = False
            self.measure()  # the others' decisions stand (measuring an unchanged case again changes nothing)
            done, _ = self._flags()
        return bool(done.all())

    def resync(self, cases: np.ndarray) -> None:
        """Pressure brought to the exact mean and ``w`` recomputed in float64 for ``cases`` (host ints)."""
        s = self.s
        idx = s.xp.asarray(cases)
        P = s.P[idx]
        tot = self.k.rsum(P)
        tgt = self.target[idx]
        P *= self.xp.where(tot > 0, tgt / self.xp.where(tot > 0, tot, 1.0), 1.0)
        s.P[idx] = P
        s.refresh(cases)

    def finish(self) -> None:
        """``w`` fresh for every case (the final check needs it)."""
        stale = np.flatnonzero(~self.s.be.to_host(self.fresh).reshape(-1))
        if stale.size:
            self.resync(stale)
            self.fresh[self.s.xp.asarray(stale)] = True

    def measure(self) -> None:
        """The first half of :meth:`~.elastic.PKIteration.run`'s loop for every case: residual and decisions.

        Converged, waiting and stopped cases are flagged; ``self.go`` says which iterate in
        :meth:`act`. Measuring again a case whose state has not changed decides the same (the stall
        guard's and ``next_sync``'s updates are idempotent).
        """
        xp, k, s = self.xp, self.k, self.s
        P, w = s.P, s.w
        active = ~(self.done | self.waiting)
        # gap on F (zero mean there), sign violations off F, the residual
        nF = self.nF
        has_f = nF > 0
        gbar = xp.where(has_f, k.masked_sum(w, self.F) / xp.where(has_f, nF, 1), 0.0)
        pen = xp.maximum(gbar - k.rmin(w), 0.0)  # min over F of g and over the candidates off F
        orth = k.orth(P, w, gbar, self.F) * self.inv_norm
        r = xp.maximum(xp.maximum(orth, pen / self.scale), 0.0)
        r = xp.where(xp.isfinite(orth) & xp.isfinite(pen), r, math.inf)
        below = r <= self.tol
        conv = active & below & self.fresh
        sync_level = ~below & (r < self.next_sync)
        want = active & ~self.fresh & (below | sync_level)
        lower = want & sync_level
        for _ in range(6):  # next_sync below r: every four decades (at most ~4 steps from 1e-5 to tol)
            self.next_sync = xp.where(lower & (self.next_sync > r), self.next_sync * 1e-4, self.next_sync)
        rest = active & ~conv & ~want
        # the stall guard (workspace.StallGuard) on the cases that reach it
        better = rest & (r < 0.5 * self.best)
        self.best = xp.where(better, r, self.best)
        self.at = xp.where(better, self.it, self.at)
        stop = rest & (~xp.isfinite(r) | (self.it >= self.max_iter_d) | (self.it - self.at >= STALL_WINDOW))
        self.go = rest & ~stop
        self.gbar = gbar
        self.converged |= conv
        self.waiting |= want
        self.done |= conv | stop

    def act(self) -> None:
        """The second half of the loop for the cases that iterate: join, direction, step."""
        xp, k, s = self.xp, self.k, self.s
        go, nF = self.go, self.nF
        self.it += go
        # join: violating nodes (w < gbar off F) enter F; their p, t and g_prev are 0 there already
        F, g = k.join_gap(s.w, self.gbar, self.F, go)
        nF_new = k.rcount(F)
        joined = go & (nF_new > nF)
        empty = go & (nF_new == 0)
        self.done |= empty
        go &= ~empty
        self.F, self.nF = F, nF_new
        nf = xp.where(nF_new > 0, nF_new, 1)
        k.sub_masked(g, xp.where(joined, k.rsum(g) / nf, 0.0), F)  # re-centred on the enlarged F (shifts d)
        go = self._direction(g, go, nf)
        self._step(g, go)

    def _direction(self, g, go, nf):
        """``t = z + beta t`` (``t = z`` at a restart or where that is no descent); returns ``go`` less breakdowns."""
        xp, k, op = self.xp, self.k, self.op
        R = op.inverse32(op.spectrum32(g, self.inv_sigma), op.mmult32)  # M g / sigma
        a = k.scaled_into(R, self.sigma, self.F)
        k.sub_masked(a, k.rsum(a) / nf, self.F)  # zero mean on F
        G = k.dot(g, a)
        ok = (G > 0.0) & xp.isfinite(G)
        self.done |= go & ~ok
        go = go & ok
        restart = ~((self.delta > 0.0) & (self.g_old > 0.0))
        g_old = xp.where(self.g_old != 0.0, self.g_old, 1.0)
        beta_pr = xp.maximum(0.0, (G - k.dot(self.g_prev, a)) / g_old)
        beta = xp.where(self.gprev_ok, beta_pr, G / g_old)
        beta = xp.where(restart | ~go, 0.0, beta)
        descent = k.descent_dot(g, self.t, beta, a) > 0.0
        keep = go & (restart | descent)
        k.new_direction(self.t, a, g, beta, keep, go, self.g_prev)
        self.gprev_ok |= go
        self.g_old = xp.where(go, G, self.g_old)
        self.delta = xp.where(go, 1.0, self.delta)
        return go

    def _step(self, g, go) -> None:
        """Exact line search along ``-t``, the projection onto ``p >= 0``, ``w`` moved by ``K`` of the change."""
        xp, k, op, s = self.xp, self.k, self.op, self.s
        t, F = self.t, self.F
        spec = op.spectrum32(t, self.inv_sigma)
        rt = op.quadratic32(spec) * self.sigma ** 2
        gt = k.dot(g, t)
        tau = xp.where(rt > 0.0, gt / xp.where(rt > 0.0, rt, 1.0), math.nan)
        ok = xp.isfinite(tau) & (tau > 0.0)
        self.done |= go & ~ok
        go = go & ok
        tau = xp.where(go, tau, 0.0)
        proj = go & k.proj_any(s.P, t, tau, F)
        total = k.pos_sum(s.P, t, tau)
        bad = proj & ~(total > 0.0)  # nothing left to carry the load (the single solve restarts uniformly)
        self.done |= bad
        go &= ~bad
        proj &= ~bad
        tau = xp.where(go, tau, 0.0)
        pscale = xp.where(proj, self.target / xp.where(total > 0.0, total, 1.0), 1.0)
        d32 = k.project(s.P, t, tau, go, pscale, self.inv_sigma)
        # w <- w + K (p_new - p): one forward and one inverse float32 transform (every case)
        R = op.inverse32(op.fft.rfft2(d32), op.kmult32)
        k.add_scaled(s.w, R, self.sigma)
        nF_old = self.nF
        k.shrink(s.P, F, t, self.g_prev)  # a projected case's F loses the nodes at p = 0
        nF_new = self.nF = k.rcount(F)
        # Polak-Ribiere's history off after a projection that took a large part of F away
        self.gprev_ok &= ~(proj & ((nF_old - nF_new) >= FR_AFTER_LOSS * nF_old))
        nf_new = xp.where(nF_new > 0, nF_new, 1)
        k.sub_masked(t, xp.where(proj, k.rsum(t) / nf_new, 0.0), F)  # zero mean on the reduced F
        self.fresh &= ~go


# --------------------------------------------------------------------------------------------
# the solver of a batch: units, warm starts, steps
# --------------------------------------------------------------------------------------------


class BatchSolver:
    """``B`` validated surfaces of one grid: units per case, fields on the backend, warm starts.

    ``h`` (B, nx, ny) validated host heights [length]; ``settings`` checked for ``(nx, ny)``.
    """

    def __init__(self, h: np.ndarray, settings: SolverSettings, check_every: int | None = None):
        self.settings = settings
        self.batch = B = h.shape[0]
        self.shape = tuple(h.shape[1:])
        self.size = self.shape[0] * self.shape[1]
        self.tol, self.max_iter = settings.tol, settings.max_iter
        self.length, self.threads = settings.length, settings.threads
        self.method = BATCH_METHOD
        self.periodic = True
        self.array_backend = settings.array_backend
        self.be = get_backend(self.array_backend)
        self.xp = xp = self.be.xp
        self.check_every = CHECK_EVERY.get(self.be.name, 1) if check_every is None else int(check_every)
        if self.check_every < 1:
            raise ValueError(f"check_every must be an int >= 1, got {check_every!r}")
        self.units = [Units(h[b], settings.e_star, settings.length) for b in range(B)]
        flat = [b for b, u in enumerate(self.units) if u.flat]
        if flat:
            raise ValueError(f"heights: case(s) {flat} are flat (all heights equal); a batch takes rough surfaces "
                             "only (solve a flat surface alone with solve_contact)")
        hin = np.stack([u.heights for u in self.units])
        from .units import rms_about_mean

        rms = np.array([rms_about_mean(u.heights)[1] for u in self.units])
        self.h_rms = xp.asarray(rms.reshape(B, 1, 1))
        self.h_rms_host = rms
        self.kernels = _cupy_kernels(xp) if self.be.name == "cupy" else _Kernels(xp)
        self.op = BatchOperator(self.be, self.shape, cell_aspect(self.length), self.threads, self.kernels)
        self.h = self.be.asarray(hin)
        self.h_host = hin
        self.P = xp.zeros(h.shape)
        self.w = xp.empty(h.shape)
        self.prev = None  # (B,) host internal p0 of the last step
        self._older = None  # (p_int (B,), P, w, w_ok (B,)) of the step before the last
        self._last = None  # (P, w, w_ok (B,)) of the last step
        self._ws = {}  # single-case workspaces of the fallbacks, by case
        self.paths = SOLVER_PATHS

    @property
    def backend(self) -> str:
        return self.be.fft_name()

    def check_loads(self, p: np.ndarray, name: str) -> None:
        for u in self.units:
            check_loads(u, p, self.shape, name)

    def refresh(self, cases: np.ndarray) -> None:
        """``w = K P - h`` in float64 for ``cases`` (host ints): a gather of those cases, one product, a scatter.

        The gathered batch is padded to a power of two (repeating the first case) so that the
        transforms see at most ``log2(B) + 1`` shapes, whose plans the backend caches.
        """
        xp = self.xp
        m = cases.size
        if m == self.batch:
            self.w[...] = self.op.apply64(self.P)
            self.w -= self.h
            return
        size = 1 << (m - 1).bit_length()
        sel = np.concatenate([cases, np.full(size - m, cases[0])]) if size > m else cases
        idx = xp.asarray(sel)
        u = self.op.apply64(self.P[idx])[:m]
        dst = xp.asarray(cases)
        self.w[dst] = u - self.h[dst]

    def start(self, p_int: np.ndarray) -> np.ndarray:
        """The starting pressure (and ``w``) of every case for internal loads ``p_int`` (B,); per-case ``fresh``.

        As :meth:`~.contact.ContactSolver.start` for the float32 iteration without a cap: the uniform
        load at the first step; the scaled last solution (``w`` scaled with it: fresh) while there is
        one; from the third step the extrapolation through the last two, clipped at 0, with ``w``
        from their gaps and one float32 product of the clipped part (fresh = -1: not recomputed).
        """
        xp, B = self.xp, self.batch
        target = p_int * self.size
        fresh = np.zeros(B, dtype=np.int8)
        if self.prev is None:
            self.P[...] = xp.asarray(p_int.reshape(B, 1, 1))
            return fresh
        s = p_int / self.prev
        c = np.zeros(B)
        if self._older is not None:
            op0 = self._older[0]
            with np.errstate(divide="ignore", invalid="ignore"):
                cc = (p_int - self.prev) / (self.prev - op0)
            c = np.where((op0 != self.prev) & (cc > 0.0) & (cc <= 2.0), cc, 0.0)
        lin = (c > 0) & self._last[2] & self._older[3] if self._older is not None else np.zeros(B, bool)
        extra = (c > 0) & ~lin
        sd = xp.asarray(s.reshape(B, 1, 1))
        # the scaled start (c = 0): p and u = K p scale together, so w follows without a transform
        plain = xp.asarray((c == 0).reshape(B, 1, 1))
        w_scaled = self.w * sd + (sd - 1.0) * self.h
        self.w[...] = xp.where(plain, w_scaled, self.w)
        self.P[...] = xp.where(plain, self.P * sd, self.P)
        fresh[c == 0] = 1
        if (c > 0).any():
            cd = xp.asarray(c.reshape(B, 1, 1))
            Pl, wl = self._last[0], self._last[1]
            Po, wo = self._older[1], self._older[2]
            P = (Pl - Po) * cd + Pl
            clipped = xp.maximum(P, 0.0)
            ext = xp.asarray((c > 0).reshape(B, 1, 1))
            if lin.any():
                # w = (1 + c) w_last - c w_older exactly, plus K of the clipped part (float32)
                wlin = (wl - wo) * cd + wl
                x = clipped - P
                R = self.op.inverse32(self.op.spectrum32(x, 1.0 / self.h_rms), self.op.kmult32)
                wlin = self.kernels.add_scaled(wlin, R, self.h_rms)
                tot = self.kernels.rsum(clipped)
                sc = xp.asarray(target.reshape(B, 1, 1)) / tot
                ld = xp.asarray(lin.reshape(B, 1, 1))
                self.w[...] = xp.where(ld, wlin * sc + (sc - 1.0) * self.h, self.w)
                fresh[lin] = -1
            tot = self.kernels.rsum(clipped)
            sc = xp.asarray(target.reshape(B, 1, 1)) / xp.where(tot > 0, tot, 1.0)
            newP = xp.where(tot > 0, clipped * sc, xp.asarray(p_int.reshape(B, 1, 1)))
            self.P[...] = xp.where(ext, newP, self.P)
            fresh[extra] = 0
        return fresh

    def fallback(self, b: int, p_int: float, its: int) -> tuple[int, str, bool]:
        """The single solve's fallbacks (:data:`FALLBACKS`) on case ``b`` alone, from its pressure.

        ``its`` iterations are spent; returns ``(iterations in all, path, converged)`` with the
        batch's ``P`` and ``w`` of the case replaced by the fallback's (fresh).
        """
        ws = self._ws.get(b)
        if ws is None:
            ws = self._ws[b] = Workspace(self.h_host[b], self.length, self.threads, "pk-fourier", "periodic",
                                         backend=self.array_backend)
        ws.P[...] = self.P[b]
        ws.w[...] = self.w[b]
        path, ok = BATCH_METHOD, False
        for method in FALLBACKS[BATCH_METHOD]:
            if ok or its >= self.max_iter:
                break
            path = method
            if method == "box":
                ws.method = "pk-fourier"
                more, ok = box_solve(ws, p_int, self.tol, self.max_iter - its, 2.0 * p_int * ws.size, True)
            else:
                ws.method = method
                more, ok = pk_solve(ws, p_int, self.tol, self.max_iter - its, True)
            its += more
        ws.method = "pk-fourier"
        self.P[b] = ws.P
        self.w[b] = ws.w
        return its, path, ok

    def final_check(self, p_int: np.ndarray):
        """The single solve's :func:`~.check.final_check` per case (no cap).

        Host arrays (B,): ``(ok, residual, gbar, w_sum, nf)``.
        """
        xp, k, B = self.xp, self.kernels, self.batch
        P, w = self.P, self.w
        target = xp.asarray((p_int * self.size).reshape(B, 1, 1))
        p_sum, w_sum = k.rsum(P), k.rsum(w)
        pos = P > 0.0
        nf = k.rcount(pos)
        gbar = k.masked_sum(w, pos) / xp.where(nf > 0, nf, 1)
        e_orth = k.orth(P, w, gbar, pos) / (target * self.h_rms)
        e_pen = xp.maximum(0.0, gbar - k.rmin(w)) / self.h_rms
        pmin = k.rmin(P)
        out = xp.concatenate([a.reshape(-1).astype(np.float64) for a in
                              (p_sum, w_sum, nf, gbar, e_orth, e_pen, pmin)])
        p_sum, w_sum, nf, gbar, e_orth, e_pen, pmin = self.be.to_host(out).reshape(7, B)
        t_host = p_int * self.size
        finite = np.isfinite(p_sum) & np.isfinite(w_sum)
        residual = np.where(finite, np.maximum(e_orth, e_pen), math.inf)
        ok = finite & (pmin >= 0.0) & (np.abs(p_sum - t_host) <= MEAN_RTOL * t_host) & (residual <= self.tol) & (nf > 0)
        return ok, residual, gbar, w_sum, nf.astype(np.int64)

    def perimeter(self) -> np.ndarray:
        """Contact perimeter per unit area of every case (periodic; :func:`~.results.contact_perimeter`), host (B,)."""
        xp = self.xp
        m = self.P > 0.0
        ex = xp.sum(m != xp.roll(m, 1, axis=1), axis=(1, 2), dtype=np.int64)
        ey = xp.sum(m != xp.roll(m, 1, axis=2), axis=(1, 2), dtype=np.int64)
        ex, ey = (self.be.to_host(v).astype(np.float64) for v in (ex, ey))
        nx, ny = self.shape
        length = self.length
        if np.ndim(length) == 1 and nx == ny and length[0] == length[1]:
            length = float(length[0])
        if np.ndim(length) == 0:
            return (ex + ey) * (length / nx) / length ** 2
        lx, ly = length
        return (ex * (ly / ny) + ey * (lx / nx)) / (lx * ly)

    def solve(self, p0: float):
        """Solve one load step of every case; per-case host columns."""
        B = self.batch
        p_int = np.array([u.to_internal(p0) for u in self.units])
        fresh0 = self.start(p_int)
        it = BatchIteration(self, self.xp.asarray(p_int.reshape(B, 1, 1)), fresh0, np.full(B, self.max_iter))
        its, conv = it.run(self.check_every)
        paths = [BATCH_METHOD] * B
        w_ok = np.ones(B, dtype=bool)
        for b in np.flatnonzero(~conv & (its < self.max_iter)):
            its[b], paths[b], _ = self.fallback(int(b), float(p_int[b]), int(its[b]))
            w_ok[b] = paths[b] == BATCH_METHOD
        ok, residual, gbar, w_sum, nf = self.final_check(p_int)
        if (nf == 0).any():
            raise RuntimeError(f"no contact node at p0={p0!r} in case(s) {np.flatnonzero(nf == 0).tolist()}: the "
                               "solver lost the load (bug)")
        # warm starts: keep the last two solutions (buffers recycled)
        recycled = self._older
        if self._last is not None:
            self._older = (self.prev, self._last[0], self._last[1], self._last[2])
        Pk = self.P.copy() if recycled is None else _copy_into(recycled[1], self.P)
        wk = self.w.copy() if recycled is None else _copy_into(recycled[2], self.w)
        self._last = (Pk, wk, w_ok)
        self.prev = p_int
        area = nf / self.size
        mean_gap = np.array([math.ldexp(w_sum[b] / self.size - gbar[b], self.units[b].e_len) for b in range(B)])
        if not np.all(np.isfinite(mean_gap)):
            raise ValueError(f"pressures: the gap at p0={p0!r} overflows float64 in the units of heights; reduce "
                             "p0 * length / e_star or the heights")
        return {"area_fraction": area, "mean_contact_pressure": p0 / area, "mean_gap": mean_gap,
                "contact_perimeter": self.perimeter(), "residual": residual, "iterations": its,
                "converged": ok, "solver_path": np.array([SOLVER_PATHS.index(p) for p in paths], dtype=np.int8),
                "rounds": it.rounds}


def _copy_into(dst, src):
    dst[...] = src
    return dst


# --------------------------------------------------------------------------------------------
# the entry point
# --------------------------------------------------------------------------------------------


def validate_batch(heights) -> np.ndarray:
    """``heights`` as a C-contiguous float64 ``(B, nx, ny)`` array, each case checked as :func:`validate_heights`."""
    if isinstance(heights, (str, bytes)):
        raise ValueError(f"heights must be a real numeric array, got the string {heights!r}")
    a = np.asarray(heights)
    if a.ndim != 3 or a.shape[0] < 1:
        raise ValueError(f"heights of a batch must have shape (B, nx, ny) with B >= 1, got {a.shape}")
    return np.stack([validate_heights(a[b], name=f"heights[{b}]", square=False) for b in range(a.shape[0])])


def solve_contact_batch(heights, pressures, settings: SolverSettings | None = None, *, check_every: int | None = None,
                        progress=None, **options) -> xr.Dataset:
    """Solve ``B`` surfaces of one grid under one load schedule together (issue 48).

    Parameters
    ----------
    heights : array_like, shape (B, nx, ny)
        ``B`` rigid surfaces [length] on one periodic cell, each as :func:`~.solve.solve_contact`'s
        ``heights`` (axis 1 = x); none flat.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures [pressure], the same schedule for every case (as for
        :func:`~.solve.solve_contact`, checked against each case's rms height).
    settings : SolverSettings, optional
        As for :func:`~.solve.solve_contact`; the batch runs the periodic elastic iteration
        ``"pk-fourier-f32"`` without effects, on either array backend.
    check_every : int, optional
        Rounds between two host reads of the per-case flags (:data:`CHECK_EVERY` by backend).
    progress : callable, optional
        Called after each load step as ``progress(step, p0, area_fraction, iterations, converged,
        seconds)`` with per-case arrays of shape (B,).
    **options
        Fields of :class:`SolverSettings` replacing those of ``settings``.

    Returns
    -------
    xarray.Dataset
        :func:`~.solve.solve_contact`'s dataset with a leading dimension ``case`` (0..B-1) on the
        per-case variables (``area_fraction``, ``mean_contact_pressure``, ``mean_gap``,
        ``contact_perimeter``, ``iterations``, ``residual``, ``converged``, ``solver_path``:
        dims ``case, step``); ``pressure`` and ``wall_time`` (the whole batch's step) over ``step``;
        attributes as there, plus ``batch_size`` and ``check_every``.

    Raises
    ------
    ValueError
        For invalid input, or what a batch does not run (effects, ``boundary="free"``, another
        elastic method, a flat surface), naming it.
    """
    p = validate_pressures(pressures)
    h = validate_batch(heights)
    checked = SolverSettings.from_options(settings, **options).checked(h.shape[1:])
    if checked.effects:
        names = ", ".join(type(e).__name__ for e in checked.effects)
        raise ValueError(f"a batch of surfaces runs the elastic solver only, not the effects ({names}); "
                         "solve each case with solve_contact")
    if checked.boundary != "periodic":
        raise ValueError(f"a batch of surfaces runs the periodic half-space only, got boundary={checked.boundary!r}; "
                         "solve each case with solve_contact")
    if checked.method != BATCH_METHOD:
        raise ValueError(f"a batch of surfaces runs the elastic method {BATCH_METHOD!r} only, got "
                         f"{checked.method!r}; solve each case with solve_contact")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be a callable or None, got {type(progress).__name__} {progress!r}")
    solver = BatchSolver(h, checked, check_every)
    solver.check_loads(p, "pressures")
    B, n_steps = solver.batch, p.size
    cols = {k: np.empty((B, n_steps)) for k in ("area_fraction", "mean_contact_pressure", "mean_gap",
                                                 "contact_perimeter", "residual")}
    iters = np.empty((B, n_steps), dtype=np.int64)
    conv = np.empty((B, n_steps), dtype=bool)
    paths = np.empty((B, n_steps), dtype=np.int8)
    wall = np.empty(n_steps)
    rounds = np.empty(n_steps, dtype=np.int64)
    for k, p0 in enumerate(p):
        t0 = time.perf_counter()
        out = solver.solve(float(p0))
        wall[k] = time.perf_counter() - t0
        for name in cols:
            cols[name][:, k] = out[name]
        iters[:, k], conv[:, k], paths[:, k] = out["iterations"], out["converged"], out["solver_path"]
        rounds[k] = out["rounds"]
        if progress is not None:
            progress(k + 1, float(p0), out["area_fraction"], out["iterations"], out["converged"], wall[k])
    return _batch_dataset(solver, p, cols, iters, conv, paths, wall, rounds)


def _batch_dataset(solver: BatchSolver, p, cols, iters, conv, paths, wall, rounds) -> xr.Dataset:
    """The batch's dataset: case 0's single-solve layout, the per-case variables stacked over ``case``."""
    s = solver.settings
    sides, grid = cell_attrs(solver.shape, s.length)
    attrs = {"e_star": s.e_star, **sides, "tol": s.tol, "max_iter": s.max_iter, "threads": s.threads,
             "fft_backend": solver.backend, **grid, "solver": SOLVER_NAME,
             "solver_description": solver_description(True, np.ndim(s.length) == 0),
             "batch_size": solver.batch, "check_every": solver.check_every}
    first = {name: col[0] for name, col in cols.items()}
    first["wall_time"] = wall
    ds = to_dataset(p, first, iters[0], conv[0], ([], [], []), False, solver.shape, attrs, (), paths=paths[0],
                    length_unit=s.length_unit, pressure_unit=s.pressure_unit)
    stacked = {**cols, "iterations": iters, "converged": conv, "solver_path": paths}
    for name in PER_CASE:
        var = ds[name].variable
        ds[name] = xr.Variable(("case", "step"), stacked[name], var.attrs)
    ds["wall_time"].attrs["long_name"] = "wall-clock time of the load step (the whole batch's)"
    ds["rounds"] = xr.Variable(("step",), rounds, {"units": "1", "long_name": "rounds of the batched iteration "
                                                   "(iterations of the slowest case plus waits for checks)"})
    ds = ds.assign_coords(case=xr.Variable(("case",), np.arange(solver.batch),
                                           {"units": "1", "long_name": "case of the batch (0-based)"}))
    ds.attrs["elastic_method"] = solver.method
    ds.attrs["boundary"] = "periodic"
    return ds
