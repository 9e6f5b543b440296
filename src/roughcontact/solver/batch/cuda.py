"""The fused CUDA kernels of the batched solve (:mod:`roughcontact.solver.batch`), made only when CuPy is importable.

:class:`CupyKernels` replaces each method of :class:`~.kernels.ArrayKernels` by one
``cupy.ElementwiseKernel`` or ``cupy.ReductionKernel`` (specs :data:`REDUCTIONS` and
:data:`ELEMENTWISE`, module constants so that tests/test_batch_kernels.py can run the same C code
on the host); :func:`fused_kernels` builds them and checks each once against the plain expression,
which replaces any that fails, with a warning.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np

from .kernels import ArrayKernels


@functools.cache
def fused_kernels(xp):
    """:class:`CupyKernels` for the real CuPy, each kernel checked once; plain kernels otherwise.

    Made once per array module and process: a solve's kernels are the last solve's (the self-check
    runs ~50 launches, a cost that a warm batch of one case would otherwise pay each time).
    """
    if not hasattr(xp, "ElementwiseKernel"):  # numpy, or the tests' stand-in
        return ArrayKernels(xp)
    try:
        kernels = CupyKernels(xp)
    except Exception as exc:  # noqa: BLE001 (any failure to build: run the plain expressions)
        warnings.warn(f"batched solve: fused CuPy kernels unavailable ({type(exc).__name__}: {exc}); "
                      "using plain array expressions", RuntimeWarning, stacklevel=2)
        return ArrayKernels(xp)
    kernels.self_check()
    return kernels


#: The fused reductions of :class:`CupyKernels`: attribute -> ``cupy.ReductionKernel``'s ``(in_params,
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

#: The fused element-wise passes of :class:`CupyKernels`: attribute -> ``cupy.ElementwiseKernel``'s
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
    # per-case decisions on (B, 1, 1) arrays: one launch each instead of 10-40 small ones
    "_gbar": ("float64 s, int64 n", "float64 gbar", "gbar = n > 0 ? s / (double)n : 0.0"),
    "_decide": (
        "float64 orth, float64 wmin, float64 gbar, float64 inv_norm, float64 scale, float64 tol, int64 stall, "
        "float64 big, int64 it, int64 max_iter, bool fresh",
        "float64 next_sync, float64 best, int64 at, bool done, bool waiting, bool converged, bool go",
        "double pr = gbar - wmin; double pen = (pr > 0.0 || pr != pr) ? pr : 0.0; double o = orth * inv_norm; "
        "double r = (isfinite(o) && isfinite(pen)) ? fmax(fmax(o, pen / scale), 0.0) : big; "
        "bool active = !(done || waiting); bool below = r <= tol; bool conv = active && below && fresh; "
        "bool sync_level = !below && r < next_sync; bool want = active && !fresh && (below || sync_level); "
        "for (int j = 0; j < 6; ++j) { if (want && sync_level && next_sync > r) next_sync *= 1e-4; } "
        "bool rest = active && !conv && !want; "
        "if (rest && r < 0.5 * best && it < max_iter) { best = r; at = it; } "
        "bool stop = rest && (!isfinite(r) || it >= max_iter || it - at >= stall); "
        "go = rest && !stop; converged = converged || conv; waiting = waiting || want; "
        "done = done || conv || stop"),
    "_joinfix": ("int64 nnew, int64 nold, float64 gsum", "bool go, bool done, float64 c, float64 nf",
                 "bool joined = go && nnew > nold; bool empty = go && nnew == 0; done = done || empty; "
                 "go = go && !empty; nf = nnew > 0 ? (double)nnew : 1.0; c = joined ? gsum / nf : 0.0"),
    "_beta": ("float64 G, float64 gpa, float64 g_old, float64 delta, bool gprev_ok",
              "bool go, bool done, float64 beta, bool restart",
              "bool ok = G > 0.0 && isfinite(G); done = done || (go && !ok); go = go && ok; "
              "restart = !(delta > 0.0 && g_old > 0.0); double d = g_old != 0.0 ? g_old : 1.0; "
              "double bpr = (G - gpa) / d; bpr = (bpr > 0.0 || bpr != bpr) ? bpr : 0.0; "
              "double bb = gprev_ok ? bpr : G / d; beta = (restart || !go) ? 0.0 : bb"),
    "_dirdone": ("float64 dd, bool restart, float64 G, bool go",
                 "bool gprev_ok, float64 g_old, float64 delta, bool keep",
                 "keep = go && (restart || dd > 0.0); if (go) { gprev_ok = true; g_old = G; delta = 1.0; }"),
    "_tau": ("float64 quad, float64 sigma, float64 gt, float64 qnan", "bool go, bool done, float64 tau",
             "double rt = quad * (sigma * sigma); double tt = rt > 0.0 ? gt / rt : qnan; "
             "bool ok = isfinite(tt) && tt > 0.0; done = done || (go && !ok); go = go && ok; tau = go ? tt : 0.0"),
    "_pscale": ("bool pany, float64 total, float64 target", "bool go, bool done, float64 tau, bool proj, float64 ps",
                "bool pj = go && pany; bool bad = pj && !(total > 0.0); done = done || bad; go = go && !bad; "
                "proj = pj && !bad; tau = go ? tau : 0.0; ps = proj ? target / (total > 0.0 ? total : 1.0) : 1.0"),
    "_shrinkfix": ("int64 nold, int64 nnew, float64 tsum, float64 frac, bool proj, bool go",
                   "bool gprev_ok, bool fresh, float64 c",
                   "if (proj && (double)(nold - nnew) >= frac * (double)nold) gprev_ok = false; "
                   "fresh = fresh && !go; c = proj ? tsum / (nnew > 0 ? (double)nnew : 1.0) : 0.0"),
}


#: How a reduction's ``reduce_expr`` is carried out over each case's values (an array module's function).
_REDUCERS = {"a + b": "sum", "max(a, b)": "max"}


class CupyKernels(ArrayKernels):
    """Fused CUDA kernels for the passes of a round (CuPy only).

    Each fuses what the plain expressions do in two to six passes (and their temporaries) into
    one pass over the fields; per-case numbers are ``(B, 1, 1)`` arrays broadcast onto them.
    Built only when CuPy is importable; :meth:`self_check` compares each with :class:`ArrayKernels` on
    a small random batch and falls back to the plain expression, with a warning, where they differ.
    """

    #: the methods :meth:`self_check` compares
    FUSED = ("rsum", "rcount", "rmin", "masked_sum", "orth", "dot", "to32", "quadratic", "scaled_into",
             "add_scaled", "sub_masked",
             "join_gap", "descent_dot", "new_direction", "proj_any", "pos_sum", "project", "shrink",
             "gbar", "decide", "join_fix", "beta", "direction_done", "step_length", "projection_scale", "shrink_fix")

    def __init__(self, cp):
        super().__init__(cp)
        self.cp = cp
        # A reduction is its map as an element-wise kernel, then CuPy's sum or max over each case's
        # contiguous nx * ny values (CUB's segmented reduction). Measured on an H200 (2026-11-27, N = 1024):
        # a cupy.ReductionKernel over axes (1, 2) with (B, 1, 1) inputs broadcast took 5.6 ms a call at
        # B = 16 (12-14 ms for the four with per-case inputs), 90 % of a round; xp.sum over the same axes
        # 0.26 ms.
        for attr, (params, out, mapped, reduce_expr, post, _identity) in REDUCTIONS.items():
            if post != "y = a" or reduce_expr not in _REDUCERS:
                raise ValueError(f"reduction {attr}: only 'a + b' or 'max(a, b)' with 'y = a' are built")
            setattr(self, attr, (cp.ElementwiseKernel(params, out, f"y = {mapped}", name="rc_batch" + attr),
                                 _REDUCERS[reduce_expr]))
        for attr, spec in ELEMENTWISE.items():
            setattr(self, attr, cp.ElementwiseKernel(*spec, name="rc_batch" + attr))
        self.fused = True

    def _reduce(self, kernel, *args):
        mapped, reducer = kernel
        values = mapped(*args)
        # Two stages: over each row, then over each case's row results. CUB's segmented reduction gives a
        # segment one thread block, so one segment per case (B blocks on ~132 SMs, each over 1M values at
        # N = 1024) cost a near-constant ~30 ms a round at B = 16 to 64 (H200, 2026-11-27); b * ny segments
        # of nx values fill the device.
        return self._two_stage(getattr(self.cp, reducer), values)

    def _two_stage(self, reducer, x, **kw):
        """``reducer`` over each case's values of ``x``, shape ``(B, 1, 1)``: rows first (see ``__init__``)."""
        b = x.shape[0]
        rows = reducer(x.reshape(b * x.shape[1], -1), axis=1, **kw)
        return reducer(rows.reshape(b, -1), axis=1).reshape(b, 1, 1)

    def rsum(self, x):
        return self._two_stage(self.cp.sum, x, dtype=np.float64)

    def rcount(self, m):
        return self._two_stage(self.cp.sum, m, dtype=np.int64)

    def rmin(self, x):
        return self._two_stage(self.cp.min, x)

    def masked_sum(self, x, mask):
        return self._reduce(self._msum, x, mask)

    def orth(self, P, w, gbar, F):
        return self._reduce(self._orth, P, w, gbar, F)

    def dot(self, a, b):
        return self._reduce(self._dot, a, b)

    def to32(self, x, scale, out=None, F=None):
        if out is None:
            return self._to32(x, scale)
        self._to32(x, scale, out)
        return out

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

    def descent_dot(self, g, t, beta, a, F=None):
        return self._reduce(self._ddot, g, t, beta, a)

    def new_direction(self, t, a, g, beta, keep, go, g_prev):
        self._newdir(a, g, beta, keep, go, t, g_prev)

    def proj_any(self, P, t, tau, F):
        return self._reduce(self._pany, P, t, tau, F) > 0

    def pos_sum(self, P, t, tau):
        return self._reduce(self._psum, P, t, tau)

    def project(self, P, t, tau, go, scale, inv_sigma, out=None, F=None):
        d32 = self.cp.empty(P.shape, dtype=np.float32) if out is None else out
        self._project(t, tau, go, scale, inv_sigma, P, d32)
        return d32

    def shrink(self, P, F, t, g_prev):
        self._shrink(P, F, t, g_prev)

    def _new(self, like, dtype):
        return self.cp.empty(like.shape, dtype=dtype)

    def gbar(self, s, n):
        return self._gbar(s, n)

    def decide(self, orth, wmin, gbar, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
               next_sync, best, at, done, waiting, converged, go):
        self._decide(orth, wmin, gbar, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                     next_sync, best, at, done, waiting, converged, go)

    def join_fix(self, nnew, nold, gsum, go, done):
        c, nf = self._new(gsum, np.float64), self._new(gsum, np.float64)
        self._joinfix(nnew, nold, gsum, go, done, c, nf)
        return c, nf

    def beta(self, G, gpa, g_old, delta, gprev_ok, go, done):
        beta, restart = self._new(G, np.float64), self._new(G, np.bool_)
        self._beta(G, gpa, g_old, delta, gprev_ok, go, done, beta, restart)
        return beta, restart

    def direction_done(self, dd, restart, G, go, gprev_ok, g_old, delta):
        keep = self._new(G, np.bool_)
        self._dirdone(dd, restart, G, go, gprev_ok, g_old, delta, keep)
        return keep

    def step_length(self, quad, sigma, gt, nan, go, done):
        tau = self._new(gt, np.float64)
        self._tau(quad, sigma, gt, nan, go, done, tau)
        return tau

    def projection_scale(self, pany, total, target, go, done, tau):
        proj, ps = self._new(total, np.bool_), self._new(total, np.float64)
        self._pscale(pany, total, target, go, done, tau, proj, ps)
        return proj, ps

    def shrink_fix(self, nold, nnew, tsum, frac, proj, go, gprev_ok, fresh):
        c = self._new(tsum, np.float64)
        self._shrinkfix(nold, nnew, tsum, frac, proj, go, gprev_ok, fresh, c)
        return c

    def self_check(self) -> None:
        """Each fused kernel against :class:`ArrayKernels` on random inputs; the plain one where they differ."""
        cp = self.cp
        plain = ArrayKernels(cp)
        calls = {**_field_checks(cp), **_scalar_checks(cp)}
        for name in self.FUSED:
            try:
                got, want = _as_tuple(calls[name](self)), _as_tuple(calls[name](plain))
                ok = len(got) == len(want) and all(
                    g.shape == wv.shape and g.dtype == wv.dtype
                    and bool(cp.allclose(g.astype(np.float64), wv.astype(np.float64), rtol=1e-5, atol=1e-6,
                                         equal_nan=True))
                    for g, wv in zip(got, want, strict=True))
                why = "results differ"
            except Exception as exc:  # noqa: BLE001
                ok, why = False, f"{type(exc).__name__}: {exc}"
            if not ok:
                warnings.warn(f"batched solve: fused kernel {name!r} failed its check ({why}); using the plain "
                              "expression", RuntimeWarning, stacklevel=2)
                setattr(self, name, getattr(plain, name))
                self.fused = False


def _field_checks(cp) -> dict:
    """Calls of the field kernels on a random ``(3, 16, 16)`` batch, ``kernels -> results``."""
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
    return {
        "rsum": lambda k: k.rsum(r32), "rcount": lambda k: k.rcount(f), "rmin": lambda k: k.rmin(a),
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


def _scalar_checks(cp) -> dict:
    """Calls of the per-case decision kernels on six cases chosen to take their branches."""
    def col(values, dtype=np.float64):
        return cp.asarray(np.asarray(values, dtype=dtype).reshape(-1, 1, 1))

    T, F = True, False
    x, one = col([0.3, 0.9, 0.1, 0.5, 0.7, 0.2]), col([1.0] * 6)
    n_new, n_old = col([0, 3, 5, 5, 9, 1], np.int64), col([2, 3, 4, 5, 12, 1], np.int64)
    go, done = col([T, T, F, T, T, T], bool), col([F, F, T, F, F, F], bool)
    fresh, flags = col([T, F, T, F, F, T], bool), col([F, T, F, T, F, T], bool)
    it, max_iter = col([0, 5, 10, 3, 300, 7], np.int64), col([100, 100, 100, 3, 1000, 100], np.int64)
    G = col([1.0, -1.0, 2.0, 0.5, 3.0, 1e-3])
    orth = col([1e-4, 1e-6, 5e-2, 1e-2, 2e-4, 1e-7])
    state = (col([1e-5] * 6), col([np.inf, 1e-2, 1e-3, 1e-1, 1e-3, np.inf]), col([0, 0, 2, 0, 1, 0], np.int64),
             col([F] * 5 + [T], bool), col([F] * 6, bool), col([F] * 6, bool), col([F] * 6, bool))
    return {
        "gbar": lambda k: k.gbar(x, n_new),
        "decide": lambda k: _inplace(lambda *st: k.decide(orth, x * 0.0, x * 0.0, one, x + 0.5, 1e-3, 2, np.inf, it,
                                                          max_iter, fresh, *st), *state),
        "join_fix": lambda k: _inplace(lambda g_, d_: k.join_fix(n_new, n_old, x, g_, d_), go, done),
        "beta": lambda k: _inplace(lambda g_, d_: k.beta(G, x, col([1, 0, 2, -1, 1, 0.5]), col([1, 0, 1, 1, 1, 1]),
                                                         flags, g_, d_), go, done),
        "direction_done": lambda k: _inplace(lambda *st: k.direction_done(x - 0.4, flags, G, go, *st), flags, x, one),
        "step_length": lambda k: _inplace(lambda g_, d_: k.step_length(col([1, 0, 2, -1, 1e-3, 5]), x, x - 0.25,
                                                                       np.nan, g_, d_), go, done),
        "projection_scale": lambda k: _inplace(lambda g_, d_, t_: k.projection_scale(
            flags, col([1, 2, 0, 3, 1, -1]), one * 2.0, g_, d_, t_), go, done, x),
        "shrink_fix": lambda k: _inplace(lambda gp_, fr_: k.shrink_fix(
            col([10, 5, 7, 100, 3, 0], np.int64), col([9, 5, 0, 80, 3, 0], np.int64), x, 0.1, flags, go, gp_, fr_),
            fresh, flags),
    }


def _inplace(fn, *fields):
    """Copies of ``fields``, ``fn``'s results on them, and the copies after ``fn`` (for in-place kernels)."""
    copies = [x.copy() for x in fields]
    out = fn(*copies)
    return (*_as_tuple(out), *copies)


def _as_tuple(x):
    return () if x is None else (x if isinstance(x, tuple) else (x,))


