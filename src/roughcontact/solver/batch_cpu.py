"""Fused CPU kernels of the batched iteration (:mod:`.batch`): each pass over the fields is one loop.

:class:`FusedCpuKernels` replaces the field passes of :class:`~.batch_kernels.ArrayKernels` (plain
array expressions: two to six passes and as many temporaries each) by loops compiled with numba
(``@njit(cache=True)``, no ``fastmath``, no ``parallel``: the results do not depend on the machine's
load or core count), as :class:`~.batch_cuda.CupyKernels` does with CUDA kernels on a GPU. Chosen by
measurement (benchmarks/profile_iteration.py ``--batched``, benchmarks/README.md): at 1024² the
plain expressions cost ~80 ms of CPU an iteration, the fused loops ~10.

What makes most passes cheap: the pressure ``P``, the direction ``t`` and the last gradient
``g_prev`` are zero off the free set ``F`` (10 % of the nodes at the paper's loads), and the gradient
``g`` and the preconditioned gradient ``a`` are read on ``F`` only (their values off ``F`` are left
undefined here). So a loop touches the float64 values on ``F``'s nodes only, and skips eight nodes at
a time where ``F`` holds none of them (one 8-byte read of ``F``'s flags). Only the gap ``w`` and the
float32 transforms' inputs are dense. Passes that follow each other are fused where the iteration
allows (:meth:`FusedCpuKernels.center_dots`, :meth:`FusedCpuKernels.new_direction_on`).

Sums are accumulated in index order per case (deterministic; not numpy's pairwise order, so a sum
differs from :class:`~.batch_kernels.ArrayKernels`' in the last bits). Per-case partial results
go through :meth:`~.batch_kernels.ArrayKernels.allsum` (and its siblings) so that
:class:`~.mpi.kernels.MpiKernels` adds the ranks' parts.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .batch_kernels import ArrayKernels

_JIT = {"cache": True, "nogil": True}


def _fields(*arrays):
    """``(B, n)`` views of ``(B, nx, ny)`` fields (C-contiguous: a reshape is a view)."""
    return tuple(a.reshape(a.shape[0], -1) for a in arrays)


def _blocks(F):
    """``(F (B, n) bool, its flags of eight nodes at a time (B, n // 8) uint64)``: views, no copy."""
    f = F.reshape(F.shape[0], -1)
    m = f.shape[1] // 8 * 8
    return f, f[:, :m].view(np.uint64)


def _cases(x, B: int, dtype=np.float64):
    """A per-case value as a contiguous ``(B,)`` array (``(B, 1, 1)`` arrays and scalars alike)."""
    a = np.asarray(x, dtype=dtype).reshape(-1)
    return np.ascontiguousarray(np.broadcast_to(a, (B,)) if a.size == 1 else a)


@njit(**_JIT)
def _span(j, n):
    """The nodes ``[lo, hi)`` of block ``j`` (the last block may be short)."""
    lo = 8 * j
    return lo, min(lo + 8, n)


@njit(**_JIT)
def _sum(x):
    B, n = x.shape
    out = np.zeros(B)
    for b in range(B):
        s0 = s1 = s2 = s3 = 0.0
        m = n - n % 4
        for i in range(0, m, 4):
            s0 += x[b, i]
            s1 += x[b, i + 1]
            s2 += x[b, i + 2]
            s3 += x[b, i + 3]
        for i in range(m, n):
            s0 += x[b, i]
        out[b] = (s0 + s1) + (s2 + s3)
    return out


@njit(**_JIT)
def _count(f):
    B, n = f.shape
    out = np.zeros(B, dtype=np.int64)
    for b in range(B):
        c = 0
        for i in range(n):
            c += f[b, i]
        out[b] = c
    return out


@njit(**_JIT)
def _min(x):
    B, n = x.shape
    out = np.empty(B)
    for b in range(B):
        m = x[b, 0]
        for i in range(1, n):
            v = x[b, i]
            if v < m or v != v:
                m = v
                if v != v:
                    break
        out[b] = m
    return out


@njit(**_JIT)
def _gap_stats(w, f):
    """Per case the sum of ``w`` on ``F`` and the least ``w`` (NaN if any): one pass over ``w``."""
    B, n = w.shape
    sums = np.zeros(B)
    mins = np.empty(B)
    for b in range(B):
        s, m = 0.0, w[b, 0]
        for i in range(n):
            v = w[b, i]
            if f[b, i]:
                s += v
            if v < m or v != v:
                m = v if m == m else m
        sums[b] = s
        mins[b] = m
    return sums, mins


@njit(**_JIT)
def _masked_sum(x, f, f8):
    B, n = x.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    out = np.zeros(B)
    for b in range(B):
        s = 0.0
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    s += x[b, i]
        out[b] = s
    return out


@njit(**_JIT)
def _orth(p, w, gbar, f, f8):
    B, n = p.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    out = np.zeros(B)
    for b in range(B):
        s, gb = 0.0, gbar[b]
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    s += p[b, i] * abs(w[b, i] - gb)
        out[b] = s
    return out


@njit(**_JIT)
def _dot(u, v):
    B, n = u.shape
    out = np.zeros(B)
    for b in range(B):
        s0 = s1 = 0.0
        m = n - n % 2
        for i in range(0, m, 2):
            s0 += u[b, i] * v[b, i]
            s1 += u[b, i + 1] * v[b, i + 1]
        if m < n:
            s0 += u[b, n - 1] * v[b, n - 1]
        out[b] = s0 + s1
    return out


@njit(**_JIT)
def _dot_on(u, v, f, f8):
    B, n = u.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    out = np.zeros(B)
    for b in range(B):
        s = 0.0
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    s += u[b, i] * v[b, i]
        out[b] = s
    return out


@njit(**_JIT)
def _to32(x, scale, out):
    B, n = x.shape
    for b in range(B):
        s = scale[b]
        for i in range(n):
            out[b, i] = np.float32(x[b, i] * s)


@njit(**_JIT)
def _to32_on(x, scale, f, f8, out):
    B, n = x.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    zero = np.float32(0.0)
    for b in range(B):
        s = scale[b]
        for j in range(nb):
            lo, hi = _span(j, n)
            if j < full and f8[b, j] == 0:
                for i in range(lo, hi):
                    out[b, i] = zero
                continue
            for i in range(lo, hi):
                out[b, i] = np.float32(x[b, i] * s) if f[b, i] else zero


@njit(**_JIT)
def _quadratic(re_im, weights):
    # re_im: (B, m, 2) float32 view of the complex64 half spectrum; weights (m,) float32
    B, m = re_im.shape[0], re_im.shape[1]
    out = np.zeros(B)
    for b in range(B):
        s0 = s1 = 0.0
        k = m - m % 2
        for i in range(0, k, 2):
            r, q = re_im[b, i, 0], re_im[b, i, 1]
            s0 += np.float64(weights[i] * (r * r + q * q))
            r, q = re_im[b, i + 1, 0], re_im[b, i + 1, 1]
            s1 += np.float64(weights[i + 1] * (r * r + q * q))
        if k < m:
            r, q = re_im[b, m - 1, 0], re_im[b, m - 1, 1]
            s0 += np.float64(weights[m - 1] * (r * r + q * q))
        out[b] = s0 + s1
    return out


@njit(**_JIT)
def _scaled_on(r, c, f, f8, out):
    """``out = r c`` on F (undefined off it) and its sum per case."""
    B, n = r.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    sums = np.zeros(B)
    for b in range(B):
        cb, s = c[b], 0.0
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    v = np.float64(r[b, i]) * cb
                    out[b, i] = v
                    s += v
        sums[b] = s
    return sums


@njit(**_JIT)
def _add_scaled(w, r, c):
    B, n = w.shape
    for b in range(B):
        cb = c[b]
        if cb == 0.0:
            continue
        for i in range(n):
            w[b, i] += np.float64(r[b, i]) * cb


@njit(**_JIT)
def _sub_on(x, c, f, f8):
    B, n = x.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    for b in range(B):
        cb = c[b]
        if cb == 0.0:
            continue
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    x[b, i] -= cb


@njit(**_JIT)
def _join(w, gbar, f, go, g):
    """``F |= w < gbar`` where ``go``, ``g = w - gbar`` on the new F (undefined off it), ``|F|`` and ``sum(g)``."""
    B, n = w.shape
    counts = np.zeros(B, dtype=np.int64)
    sums = np.zeros(B)
    for b in range(B):
        gb, c, s, moving = gbar[b], 0, 0.0, go[b]
        for i in range(n):
            fi = f[b, i]
            if not fi and moving and w[b, i] < gb:
                fi = True
                f[b, i] = True
            if fi:
                v = w[b, i] - gb
                g[b, i] = v
                s += v
                c += 1
        counts[b] = c
        sums[b] = s
    return counts, sums


@njit(**_JIT)
def _center_dots(a, c, f, f8, g, g_prev, t):
    """``a -= c`` on F, then per case ``g . a``, ``g_prev . a`` and ``g . t``, one pass over F's nodes."""
    B, n = a.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    ga = np.zeros(B)
    pa = np.zeros(B)
    gt = np.zeros(B)
    for b in range(B):
        cb, s0, s1, s2 = c[b], 0.0, 0.0, 0.0
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    v = a[b, i] - cb
                    a[b, i] = v
                    gi = g[b, i]
                    s0 += gi * v
                    s1 += g_prev[b, i] * v
                    s2 += gi * t[b, i]
        ga[b] = s0
        pa[b] = s1
        gt[b] = s2
    return ga, pa, gt


@njit(**_JIT)
def _new_direction(t, a, g, beta, keep, go, g_prev, f, f8, scale, out):
    """``t = beta t + a`` where kept, else ``a`` (cases that move), ``g_prev = g``, on F; ``out =
    float32(t scale)`` (0 off F) for the transform; per case ``g . t``."""
    B, n = t.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    zero = np.float32(0.0)
    gts = np.zeros(B)
    for b in range(B):
        be, k, moving, sc, s = beta[b], keep[b], go[b], scale[b], 0.0
        for j in range(nb):
            lo, hi = _span(j, n)
            if j < full and f8[b, j] == 0:
                for i in range(lo, hi):
                    out[b, i] = zero
                continue
            for i in range(lo, hi):
                if not f[b, i]:
                    out[b, i] = zero
                    continue
                if moving:
                    t[b, i] = t[b, i] * be + a[b, i] if k else a[b, i]
                    g_prev[b, i] = g[b, i]
                ti = t[b, i]
                out[b, i] = np.float32(ti * sc)
                s += g[b, i] * ti
        gts[b] = s
    return gts


@njit(**_JIT)
def _trial_stats(p, t, tau, f, f8):
    """``(sum(max(p - tau t, 0)), any(F & p - tau t <= 0))`` per case; both zero off F (p = t = 0 there)."""
    B, n = p.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    sums = np.zeros(B)
    anys = np.zeros(B, dtype=np.bool_)
    for b in range(B):
        s, ta, hit = 0.0, tau[b], False
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    tr = p[b, i] - ta * t[b, i]
                    if tr > 0.0:
                        s += tr
                    else:
                        hit = True
        sums[b] = s
        anys[b] = hit
    return sums, anys


@njit(**_JIT)
def _project(p, t, tau, go, scale, inv_sigma, f, f8, out):
    # off F p = t = 0: the change is 0 there
    B, n = p.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    zero = np.float32(0.0)
    for b in range(B):
        ta, sc, isg, moving = tau[b], scale[b], inv_sigma[b], go[b]
        for j in range(nb):
            lo, hi = _span(j, n)
            if not moving or (j < full and f8[b, j] == 0):
                for i in range(lo, hi):
                    out[b, i] = zero
                continue
            for i in range(lo, hi):
                if not f[b, i]:
                    out[b, i] = zero
                    continue
                trial = p[b, i] - ta * t[b, i]
                tp = trial if trial > 0.0 else 0.0
                d = (tp - trial) + (sc - 1.0) * tp - ta * t[b, i]
                out[b, i] = np.float32(d * isg)
                p[b, i] = tp * sc


@njit(**_JIT)
def _step_on(p, t, tau, go, f, f8):
    B, n = p.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    for b in range(B):
        if not go[b]:
            continue
        ta = tau[b]
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    p[b, i] = p[b, i] - ta * t[b, i]


@njit(**_JIT)
def _shrink(p, f, f8, t, g_prev):
    B, n = p.shape
    nb = (n + 7) // 8
    full = f8.shape[1]
    counts = np.zeros(B, dtype=np.int64)
    sums = np.zeros(B)
    for b in range(B):
        c, s = 0, 0.0
        for j in range(nb):
            if j < full and f8[b, j] == 0:
                continue
            lo, hi = _span(j, n)
            for i in range(lo, hi):
                if f[b, i]:
                    if p[b, i] > 0.0:
                        c += 1
                        s += t[b, i]
                    else:
                        f[b, i] = False
                        t[b, i] = 0.0
                        g_prev[b, i] = 0.0
        counts[b] = c
        sums[b] = s
    return counts, sums


class FusedCpuKernels(ArrayKernels):
    """:class:`~.batch_kernels.ArrayKernels` on the host with each field pass one compiled loop.

    The same results as the plain expressions up to the order of summation (module docstring),
    except where marked: the gradient of :meth:`join_stats` and the field of :meth:`scaled_sum` are
    defined on ``F`` only. Outputs that the plain kernels allocate are written into buffers kept per
    shape and reused: a result is valid until the same kernel is called again (the iteration uses
    each before that). :meth:`join_stats` updates ``F`` in place and returns it.
    """

    def __init__(self):
        super().__init__(np)
        self._buffers = {}

    def buffer(self, name: str, shape, dtype) -> np.ndarray:
        """A scratch array ``name`` of ``shape`` and ``dtype``, made once and reused."""
        key = (name, tuple(shape), np.dtype(dtype))
        out = self._buffers.get(key)
        if out is None:
            out = self._buffers[key] = np.zeros(shape, dtype=dtype)
        return out

    @staticmethod
    def _col(v):
        return v.reshape(-1, 1, 1)

    # -- reductions ---------------------------------------------------------------------------

    def rsum(self, x):
        if x.dtype != np.float64:
            return super().rsum(x)
        return self.allsum(self._col(_sum(*_fields(np.ascontiguousarray(x)))))

    def rcount(self, m):
        return self.allcount(self._col(_count(*_fields(np.ascontiguousarray(m)))))

    def rmin(self, x):
        return self.allmin(self._col(_min(*_fields(np.ascontiguousarray(x)))))

    def masked_sum(self, x, mask):
        return self.allsum(self._col(_masked_sum(*_fields(x), *_blocks(mask))))

    def gap_stats(self, w, F):
        sums, mins = _gap_stats(*_fields(w, F))
        return self.allsum(self._col(sums)), self.allmin(self._col(mins))

    def orth(self, P, w, gbar, F):
        B = P.shape[0]
        return self.allsum(self._col(_orth(*_fields(P, w), _cases(gbar, B), *_blocks(F))))

    def dot(self, a, b):
        return self.allsum(self._col(_dot(*_fields(a, b))))

    def dot_on(self, a, b, F):
        return self.allsum(self._col(_dot_on(*_fields(a, b), *_blocks(F))))

    def quadratic(self, spec, weights):
        B = spec.shape[0]
        ri = np.ascontiguousarray(spec).view(np.float32).reshape(B, -1, 2)
        wq = np.ascontiguousarray(np.broadcast_to(weights, spec.shape[1:]).reshape(-1), dtype=np.float32)
        return self.allsum(self._col(_quadratic(ri, wq)))

    def trial_stats(self, P, t, tau, F):
        B = P.shape[0]
        sums, anys = _trial_stats(*_fields(P, t), _cases(tau, B), *_blocks(F))
        return self.allsum(self._col(sums)), self.allany(self._col(anys))

    def proj_any(self, P, t, tau, F):
        return self.trial_stats(P, t, tau, F)[1]

    def center_dots(self, a, c, F, g, g_prev, t):
        B = a.shape[0]
        ga, pa, gt = _center_dots(*_fields(a), _cases(c, B), *_blocks(F), *_fields(g, g_prev, t))
        return self.allsum(self._col(ga)), self.allsum(self._col(pa)), self.allsum(self._col(gt))

    # -- element-wise passes --------------------------------------------------------------------

    def to32(self, x, scale, out=None, F=None):
        B = x.shape[0]
        out = self.buffer("to32", x.shape, np.float32) if out is None else out
        if F is None:
            _to32(*_fields(x), _cases(scale, B), *_fields(out))
        else:
            _to32_on(*_fields(x), _cases(scale, B), *_blocks(F), *_fields(out))
        return out

    def scaled_sum(self, R, factor, F):
        B = R.shape[0]
        a = self.buffer("scaled", R.shape, np.float64)
        sums = _scaled_on(*_fields(R), _cases(factor, B), *_blocks(F), *_fields(a))
        return a, self.allsum(self._col(sums))

    def add_scaled(self, w, R, factor):
        _add_scaled(*_fields(w, R), _cases(factor, w.shape[0]))
        return w

    def sub_masked(self, x, c, F):
        _sub_on(*_fields(x), _cases(c, x.shape[0]), *_blocks(F))
        return x

    def join_stats(self, w, gbar, F, go):
        B = w.shape[0]
        g = self.buffer("gap", w.shape, np.float64)
        counts, sums = _join(*_fields(w), _cases(gbar, B), *_fields(F), _cases(go, B, np.bool_), *_fields(g))
        return F, g, self.allcount(self._col(counts)), self.allsum(self._col(sums))

    def new_direction_input(self, t, a, g, beta, keep, go, g_prev, F, inv_sigma, out=None):
        B = t.shape[0]
        out = self.buffer("to32", t.shape, np.float32) if out is None else out
        gt = _new_direction(*_fields(t, a, g), _cases(beta, B), _cases(keep, B, np.bool_), _cases(go, B, np.bool_),
                            *_fields(g_prev), *_blocks(F), _cases(inv_sigma, B), *_fields(out))
        return out, self.allsum(self._col(gt))

    def project(self, P, t, tau, go, scale, inv_sigma, out=None, F=None):
        if F is None:  # the loop below skips the nodes off F
            return super().project(P, t, tau, go, scale, inv_sigma, out)
        B = P.shape[0]
        out = self.buffer("project", P.shape, np.float32) if out is None else out
        _project(*_fields(P, t), _cases(tau, B), _cases(go, B, np.bool_), _cases(scale, B), _cases(inv_sigma, B),
                 *_blocks(F), *_fields(out))
        return out

    def step_on(self, P, t, tau, go, F):
        B = P.shape[0]
        _step_on(*_fields(P, t), _cases(tau, B), _cases(go, B, np.bool_), *_blocks(F))

    def shrink(self, P, F, t, g_prev):
        self.shrink_stats(P, F, t, g_prev)

    def shrink_stats(self, P, F, t, g_prev):
        counts, sums = _shrink(*_fields(P), *_blocks(F), *_fields(t, g_prev))
        return self.allcount(self._col(counts)), self.allsum(self._col(sums))
