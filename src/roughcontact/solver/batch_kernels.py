"""Transforms and kernels of the batched solve (:mod:`.batch`): plain array expressions and fused CUDA ones.

:class:`BatchOperator` holds the periodic half-space's products on a ``(B, nx, ny)`` batch, batched
``rfft2`` / ``irfft2`` over the last two axes (:class:`_BatchFFT`: scipy.fft on the host, cuFFT
through ``cupyx.scipy.fft`` with CuPy's plan cache on a GPU). :class:`_Kernels` are the element-wise
passes and per-case reductions of a round as array expressions (any backend); :class:`_CupyKernels`
fuse each into one ``ElementwiseKernel`` / ``ReductionKernel`` pass, made only when CuPy is
importable and each checked once against its plain form (:func:`_cupy_kernels`).
"""

from __future__ import annotations

import warnings

import numpy as np

from .halfspace import elastic_kernel
from .units import internal_length


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


#: The fused reductions of :class:`_CupyKernels`: attribute -> ``cupy.ReductionKernel``'s ``(in_params,
#: out_params, map_expr, reduce_expr, post_map_expr, identity)``; each reduces over axes (1, 2) of
#: ``(B, nx, ny)`` inputs (per-case ``(B, 1, 1)`` inputs broadcast). No input is called ``a`` or
#: ``b``: those name the accumulators of the reduction. Module constants, so that the tests can
#: run the same C code on the host (tests/test_batch_kernels.py).
REDUCTIONS = {
    "_orth": ("float64 p, float64 w, float64 gbar, bool f", "float64 y", "f ? p * fabs(w - gbar) : 0.0",
              "a + b", "y = a", "0"),
    "_msum": ("float64 x, bool f", "float64 y", "f ? x : 0.0", "a + b", "y = a", "0"),
    "_dot": ("float64 u, float64 v", "float64 y", "u * v", "a + b", "y = a", "0"),
    "_quad": ("float32 re, float32 im, float32 wq", "float64 y", "(double)(wq * (re * re + im * im))",
              "a + b", "y = a", "0"),
    "_ddot": ("float64 g, float64 t, float64 beta, float64 z", "float64 y", "g * (t * beta + z)",
              "a + b", "y = a", "0"),
    "_pany": ("float64 p, float64 t, float64 tau, bool f", "int32 y", "(f && p - tau * t <= 0.0) ? 1 : 0",
              "max(a, b)", "y = a", "0"),
    "_psum": ("float64 p, float64 t, float64 tau", "float64 y", "fmax(p - tau * t, 0.0)", "a + b", "y = a", "0"),
}

#: The fused element-wise passes of :class:`_CupyKernels`: attribute -> ``cupy.ElementwiseKernel``'s
#: ``(in_params, out_params, operation)``; outputs that are read too are updated in place.
ELEMENTWISE = {
    "_to32": ("float64 x, float64 s", "float32 y", "y = (float)(x * s)"),
    "_scaled": ("float32 r, float64 c, bool f", "float64 y", "y = f ? (double)r * c : 0.0"),
    "_add": ("float32 r, float64 c", "float64 w", "w += (double)r * c"),
    "_subm": ("float64 c, bool f", "float64 x", "if (f) x -= c"),
    "_join": ("float64 w, float64 gbar, bool f, bool go", "bool fn, float64 g",
              "fn = go ? (f || w < gbar) : f; g = fn ? w - gbar : 0.0"),
    "_newdir": ("float64 z, float64 g, float64 beta, bool keep, bool go", "float64 t, float64 gp",
                "t = keep ? t * beta + z : (go ? z : t); if (go) gp = g"),
    "_project": ("float64 t, float64 tau, bool go, float64 s, float64 isig", "float64 p, float32 d32",
                 "double trial = p - tau * t; double tp = trial > 0.0 ? trial : 0.0; "
                 "double d = go ? (tp - trial) + (s - 1.0) * tp - tau * t : 0.0; "
                 "d32 = (float)(d * isig); if (go) p = tp * s"),
    "_shrink": ("float64 p", "bool f, float64 t, float64 gp", "if (!(p > 0.0)) { f = false; t = 0.0; gp = 0.0; }"),
}


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
        for attr, spec in REDUCTIONS.items():
            setattr(self, attr, cp.ReductionKernel(*spec, name="rc_batch" + attr))
        for attr, spec in ELEMENTWISE.items():
            setattr(self, attr, cp.ElementwiseKernel(*spec, name="rc_batch" + attr))
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
