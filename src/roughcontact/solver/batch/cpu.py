"""Fused CPU kernels of the batched iteration (:mod:`roughcontact.solver.batch`): each pass over the fields is one loop.

:class:`FusedCpuKernels` replaces the field passes of :class:`~.kernels.ArrayKernels` (plain
array expressions: two to six passes and as many temporaries each) by loops compiled with numba
(``@njit(cache=True)``, no ``fastmath``, no ``parallel``: the results do not depend on the machine's
load or core count), as :class:`~.cuda.CupyKernels` does with CUDA kernels on a GPU. Chosen by
measurement (benchmarks/profile_iteration.py ``--batched``, benchmarks/README.md): at 1024² the
plain expressions cost ~80 ms of CPU an iteration, the fused loops ~10.

What makes most passes cheap: the pressure ``P`` is zero off the free set ``F`` (10 % of the nodes at the
paper's loads), and the iteration's vectors on ``F`` (the direction ``t``, the last gradient ``g_prev``, a
round's gradient ``g`` and preconditioned gradient ``a``) are held compressed: ``(B, nx ny)`` arrays whose
position ``k`` holds node ``F.idx[b, k]``'s value, for ``k < |F|`` (:class:`FreeSet`,
:meth:`FusedCpuKernels.vector`). So a loop reads ``|F|`` consecutive values of each vector, and the
pressure and the gap at ``F``'s nodes through its indices. Only the gap ``w``, ``P`` and the float32
transforms' inputs are fields. Measured against 2133c96 (the same loops on fields indexed through ``F``,
before the per-case decisions were compiled too; 2026-12-02, benchmarks/README.md, each side by side with the
single solve in one process): a batch of one case went from 1.030x to 0.953x the single solve's CPU at 1024²
and from 1.045x to 0.921x at 2048². Passes that follow each other are fused where the iteration allows
(:meth:`FusedCpuKernels.center_dots`, :meth:`FusedCpuKernels.new_direction_input`), and each of a round's five
stretches between two transforms (:meth:`~.kernels.ArrayKernels.measure`, ``join``, ``direction``, ``trial``,
``settle``) is one compiled call that runs those loops in turn, taking the iteration's per-case arrays as they are:
on a small grid the ~25 calls from Python a round cost about as much as the loops (64², 2026-12-02,
benchmarks/bench_round_passes.py: the iterations 1.69x the single solve's CPU with the calls one at a time, 1.10x
composed). Over MPI ranks (:attr:`FusedCpuKernels.split`) they stay one at a time, so that each reduction combines
the ranks' parts before a decision reads it.

Sums are accumulated in index order per case (deterministic; not numpy's pairwise order, so a sum
differs from :class:`~.kernels.ArrayKernels`' in the last bits). Per-case partial results
go through :meth:`~.kernels.ArrayKernels.allsum` (and its siblings) so that
:class:`~roughcontact.solver.mpi.kernels.MpiKernels` adds the ranks' parts.
"""

from __future__ import annotations

import hashlib

import numpy as np
from numba import njit

from ..workspace import CONVERGED, GO, STOP, WAIT, loop_head, stall_rule
from .kernels import ArrayKernels

_JIT = {"cache": True, "nogil": True}


def _fields(*arrays):
    """``(B, n)`` views of ``(B, nx, ny)`` fields (C-contiguous: a reshape is a view)."""
    return [a.reshape(a.shape[0], -1) for a in arrays]


def _rows(a):
    """``(flat, ny, shift, extra)`` of a ``(B, nx, ny)`` field that a kernel reads or writes at grid nodes.

    ``flat`` is a ``(B, m)`` view of the field's memory, in which node ``i`` (flat index on the
    ``nx x ny`` grid) sits at :func:`_at` ``(i, ny, shift, extra)``: ``i`` itself for a C-contiguous
    field (``extra = 0``), ``i + (i // ny) extra`` for the padded rows of an in-place transform's
    buffer (:class:`~.halfspace.BatchFFT`, rows of ``ny + extra`` values). ``shift`` is ``log2(ny)``
    where ``ny`` is a power of two (the division becomes a shift), else -1.
    """
    B, nx, ny = a.shape
    shift = ny.bit_length() - 1 if ny & (ny - 1) == 0 else -1
    if a.flags.c_contiguous:
        return a.reshape(B, -1), ny, shift, 0
    # a padded buffer is a transform's, one object made once and used every round: its view is made once too
    # (the checks and as_strided cost ~15 us, which a small grid's round notices)
    return _made_once(_ROWS, a, (), lambda: _padded_rows(a, shift), 16)


#: :func:`_rows`' views of padded buffers (:func:`_made_once`)
_ROWS: dict = {}


def _made_once(cache: dict, obj, key: tuple, make, limit: int):
    """``make()`` for the object ``obj`` (and ``key``), made at the first call and kept in ``cache``.

    The entry holds ``obj`` itself beside the value, so that its ``id`` cannot be another object's while the
    entry lives; a cache of ``limit`` entries is emptied before it grows further (an object asked for once is
    a caller's own, not an operator's buffer or multiplier).
    """
    k = (id(obj), *key)
    hit = cache.get(k)
    if hit is not None and hit[0] is obj:
        return hit[1]
    if len(cache) >= limit:
        cache.clear()
    value = make()
    cache[k] = (obj, value)
    return value


def _padded_rows(a, shift):
    """:func:`_rows` of a field with padded rows (checked to lie in one buffer)."""
    B, nx, ny = a.shape
    it = a.itemsize
    row = a.strides[1] // it if a.strides[1] % it == 0 else 0
    base = a
    while isinstance(base.base, np.ndarray):
        base = base.base
    start = a.__array_interface__["data"][0]
    if (a.strides[2] != it or row < ny or a.strides[0] != nx * a.strides[1]
            or start + B * nx * row * it > base.__array_interface__["data"][0] + base.nbytes):
        raise ValueError(f"a kernel's field must be C-contiguous or have padded rows in one buffer; got shape "
                         f"{a.shape}, strides {a.strides}")
    flat = np.lib.stride_tricks.as_strided(a, shape=(B, nx * row), strides=(a.strides[0], it))
    return flat, ny, shift, row - ny


@njit(inline="always")
def _at(i, ny, shift, extra):
    """Where node ``i`` sits in a :func:`_rows` view."""
    if extra == 0:
        return i
    if shift >= 0:
        return i + (i >> shift) * extra
    return i + (i // ny) * extra


def _cases(x, B: int, dtype=np.float64):
    """A per-case value as a contiguous ``(B,)`` array (``(B, 1, 1)`` arrays and scalars alike)."""
    if type(x) is np.ndarray and x.dtype == dtype and x.size == B and x.flags.c_contiguous:
        return x.reshape(B)  # the iteration's own per-case arrays: a view, no conversion
    a = np.asarray(x, dtype=dtype).reshape(-1)
    return a if a.size == B else np.full(B, a[0], dtype=dtype)


def _state(*arrays):
    """``(B,)`` views of per-case state arrays that a kernel updates in place (``(B, 1, 1)``, C-contiguous)."""
    out = []
    for a in arrays:
        if not (isinstance(a, np.ndarray) and a.flags.c_contiguous):
            raise TypeError(f"a per-case state must be a C-contiguous numpy array to be updated in place; got "
                            f"{type(a).__name__}")
        out.append(a.reshape(-1))
    return out


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
def _index(f, idx):
    """The flat indices of each case's nodes in ``F`` into ``idx`` (ascending); their counts."""
    B, n = f.shape
    counts = np.zeros(B, dtype=np.int64)
    for b in range(B):
        c = 0
        for i in range(n):
            if f[b, i]:
                idx[b, c] = i
                c += 1
        counts[b] = c
    return counts


@njit(**_JIT)
def _masked_sum(x, idx, cnt):
    B = x.shape[0]
    out = np.zeros(B)
    for b in range(B):
        s = 0.0
        for k in range(cnt[b]):
            s += x[b, idx[b, k]]
        out[b] = s
    return out


@njit(**_JIT)
def _orth(p, w, gbar, idx, cnt):
    B = p.shape[0]
    out = np.zeros(B)
    for b in range(B):
        s, gb = 0.0, gbar[b]
        for k in range(cnt[b]):
            i = idx[b, k]
            s += p[b, i] * abs(w[b, i] - gb)
        out[b] = s
    return out


@njit(**_JIT)
def _dot_on(u, v, cnt):
    """``u . v`` per case of two vectors on F."""
    B = u.shape[0]
    out = np.zeros(B)
    for b in range(B):
        s = 0.0
        for k in range(cnt[b]):
            s += u[b, k] * v[b, k]
        out[b] = s
    return out


@njit(**_JIT)
def _clear(out, ny, shift, extra, written, wcnt):
    """Zero the nodes of ``out`` (a :func:`_rows` view) that the last sparse write set (``written``, ``wcnt``
    per case)."""
    zero = 0.0
    for b in range(out.shape[0]):
        for k in range(wcnt[b]):
            out[b, _at(written[b, k], ny, shift, extra)] = zero


@njit(**_JIT)
def _to32_on(x, scale, idx, cnt, out, ny, shift, extra):
    """``out = x scale`` at F's nodes (``x`` a vector on F, ``out`` a :func:`_rows` view)."""
    for b in range(x.shape[0]):
        s = scale[b]
        for k in range(cnt[b]):
            out[b, _at(idx[b, k], ny, shift, extra)] = x[b, k] * s  # rounded once to out's precision


@njit(**_JIT)
def _quadratic(re_im, weights):
    # re_im: (B, m, 2) real view of the half spectrum (complex64: float32 terms; complex128: float64)
    B, m = re_im.shape[0], re_im.shape[1]
    out = np.zeros(B)
    for b in range(B):
        s0 = s1 = 0.0
        k = m - m % 2
        for i in range(0, k, 2):
            r, q = re_im[b, i, 0], re_im[b, i, 1]
            s0 += weights[i] * (r * r + q * q)
            r, q = re_im[b, i + 1, 0], re_im[b, i + 1, 1]
            s1 += weights[i + 1] * (r * r + q * q)
        if k < m:
            r, q = re_im[b, m - 1, 0], re_im[b, m - 1, 1]
            s0 += weights[m - 1] * (r * r + q * q)
        out[b] = s0 + s1
    return out


@njit(**_JIT)
def _scaled_on(r, ny, shift, extra, c, idx, cnt, out):
    """The vector ``out = r c`` on F (``r`` a :func:`_rows` view of a field) and its sum per case."""
    B = out.shape[0]
    sums = np.zeros(B)
    for b in range(B):
        cb, s = c[b], 0.0
        for k in range(cnt[b]):
            v = np.float64(r[b, _at(idx[b, k], ny, shift, extra)]) * cb
            out[b, k] = v
            s += v
        sums[b] = s
    return sums


@njit(**_JIT)
def _add_scaled(w, r, ny, extra, c):
    """``w += r c`` (``r`` a :func:`_rows` view with rows of ``ny + extra``), row by row."""
    B, n = w.shape
    row = ny + extra
    for b in range(B):
        cb = c[b]
        if cb == 0.0:
            continue
        for y in range(n // ny):
            i0, j0 = y * ny, y * row
            for x in range(ny):
                w[b, i0 + x] += np.float64(r[b, j0 + x]) * cb


@njit(**_JIT)
def _sub_on(x, c, cnt):
    """``x -= c`` per case, ``x`` a vector on F."""
    for b in range(x.shape[0]):
        cb = c[b]
        if cb == 0.0:
            continue
        for k in range(cnt[b]):
            x[b, k] -= cb


@njit(**_JIT)
def _join(w, gbar, f, idx, cnt, go, g):
    """Nodes off F with ``w < gbar`` join it where ``go`` (appended to ``idx``); the vector ``g = w - gbar``
    on the new F; per case ``|F|`` and ``sum(g)``. ``cnt`` is updated in place. The vectors on F that the
    iteration keeps (``t``, ``g_prev``) are zero past ``cnt`` (:func:`_shrink`): a joining node's are 0."""
    B, n = w.shape
    sums = np.zeros(B)
    for b in range(B):
        gb, c = gbar[b], cnt[b]
        if go[b]:
            for i in range(n):
                if w[b, i] < gb and not f[b, i]:
                    f[b, i] = True
                    idx[b, c] = i
                    c += 1
            cnt[b] = c
        s = 0.0
        for k in range(c):
            v = w[b, idx[b, k]] - gb
            g[b, k] = v
            s += v
        sums[b] = s
    return sums


@njit(**_JIT)
def _center_dots(a, c, cnt, g, g_prev, t):
    """``a -= c``, then per case ``g . a``, ``g_prev . a`` and ``g . t``, one pass (vectors on F)."""
    B = a.shape[0]
    ga = np.zeros(B)
    pa = np.zeros(B)
    gt = np.zeros(B)
    for b in range(B):
        cb, s0, s1, s2 = c[b], 0.0, 0.0, 0.0
        for k in range(cnt[b]):
            v = a[b, k] - cb
            a[b, k] = v
            gi = g[b, k]
            s0 += gi * v
            s1 += g_prev[b, k] * v
            s2 += gi * t[b, k]
        ga[b] = s0
        pa[b] = s1
        gt[b] = s2
    return ga, pa, gt


@njit(**_JIT)
def _new_direction(t, a, g, beta, keep, go, g_prev, idx, cnt, scale, out, ny, shift, extra):
    """``t = beta t + a`` where kept, else ``a`` (cases that move), ``g_prev = g`` (vectors on F); ``out =
    float32(t scale)`` at F's nodes (a :func:`_rows` view; the caller zeroed the rest); per case ``g . t``."""
    B = t.shape[0]
    gts = np.zeros(B)
    for b in range(B):
        be, kp, moving, sc, s = beta[b], keep[b], go[b], scale[b], 0.0
        for k in range(cnt[b]):
            if moving:
                t[b, k] = t[b, k] * be + a[b, k] if kp else a[b, k]
                g_prev[b, k] = g[b, k]
            tk = t[b, k]
            out[b, _at(idx[b, k], ny, shift, extra)] = tk * sc
            s += g[b, k] * tk
        gts[b] = s
    return gts


@njit(**_JIT)
def _trial_stats(p, t, tau, idx, cnt):
    """``(sum(max(p - tau t, 0)), any(p - tau t <= 0))`` over F per case (``p`` a field, 0 off F; ``t`` a
    vector on F)."""
    B = p.shape[0]
    sums = np.zeros(B)
    anys = np.zeros(B, dtype=np.bool_)
    for b in range(B):
        s, ta, hit = 0.0, tau[b], False
        for k in range(cnt[b]):
            tr = p[b, idx[b, k]] - ta * t[b, k]
            if tr > 0.0:
                s += tr
            else:
                hit = True
        sums[b] = s
        anys[b] = hit
    return sums, anys


@njit(**_JIT)
def _project(p, t, tau, go, scale, inv_sigma, idx, cnt, out, ny, shift, extra):
    """The projected step on F where ``go`` (p = t = 0 off F: the change is 0 there; the caller zeroed
    ``out``, a :func:`_rows` view); returns how many nodes each case wrote."""
    B = p.shape[0]
    wrote = np.zeros(B, dtype=np.int64)
    for b in range(B):
        if not go[b]:
            continue
        ta, sc, isg = tau[b], scale[b], inv_sigma[b]
        for k in range(cnt[b]):
            i = idx[b, k]
            tk = t[b, k]
            trial = p[b, i] - ta * tk
            tp = trial if trial > 0.0 else 0.0
            d = (tp - trial) + (sc - 1.0) * tp - ta * tk
            out[b, _at(i, ny, shift, extra)] = d * isg
            p[b, i] = tp * sc
        wrote[b] = cnt[b]
    return wrote


@njit(**_JIT)
def _step_on(p, t, tau, go, idx, cnt):
    for b in range(p.shape[0]):
        if not go[b]:
            continue
        ta = tau[b]
        for k in range(cnt[b]):
            i = idx[b, k]
            p[b, i] = p[b, i] - ta * t[b, k]


@njit(**_JIT)
def _shrink(p, f, idx, cnt, t, g_prev):
    """Nodes of F at ``p <= 0`` leave it: ``idx`` and the vectors ``t``, ``g_prev`` compacted together, ``cnt``
    updated in place, the vectors zeroed past the new count (a node that joins later starts at 0 there);
    per case ``sum(t)`` over what is left."""
    B = p.shape[0]
    sums = np.zeros(B)
    for b in range(B):
        c, s, n = 0, 0.0, cnt[b]
        for k in range(n):
            i = idx[b, k]
            if p[b, i] > 0.0:
                idx[b, c] = i
                tk = t[b, k]
                t[b, c] = tk
                g_prev[b, c] = g_prev[b, k]
                c += 1
                s += tk
            else:
                f[b, i] = False
        for k in range(c, n):
            t[b, k] = 0.0
            g_prev[b, k] = 0.0
        cnt[b] = c
        sums[b] = s
    return sums


@njit(**_JIT)
def _scale_start(P, w, h, s, plain):
    B, n = P.shape
    for b in range(B):
        if not plain[b]:
            continue
        sb = s[b]
        for i in range(n):
            w[b, i] = w[b, i] * sb + (sb - 1.0) * h[b, i]
            P[b, i] = P[b, i] * sb


@njit(**_JIT)
def _extrapolate(P, w, Pl, Po, wl, wo, c, ext, lin, inv_sigma, out, ny, shift, extra):
    B, n = P.shape
    tot = np.zeros(B)
    zero = 0.0
    for b in range(B):
        if not ext[b]:
            for i in range(n):
                out[b, _at(i, ny, shift, extra)] = zero
            continue
        cb, isg, ln, s = c[b], inv_sigma[b], lin[b], 0.0
        for i in range(n):
            pe = (Pl[b, i] - Po[b, i]) * cb + Pl[b, i]
            cl = pe if pe > 0.0 else 0.0
            P[b, i] = cl
            s += cl
            out[b, _at(i, ny, shift, extra)] = (cl - pe) * isg if ln else zero
            if ln:
                w[b, i] = (wl[b, i] - wo[b, i]) * cb + wl[b, i]
        tot[b] = s
    return tot


@njit(**_JIT)
def _finish_start(P, w, h, R, ny, shift, extra, sigma, sc, loaded, ext, lin, p_fill, has_r):
    B, n = P.shape
    for b in range(B):
        if not ext[b]:
            continue
        scb = sc[b]
        if has_r and lin[b]:
            sg = sigma[b]
            for i in range(n):
                r = np.float64(R[b, _at(i, ny, shift, extra)])
                w[b, i] = (w[b, i] + r * sg) * scb + (scb - 1.0) * h[b, i]
        if loaded[b]:
            for i in range(n):
                P[b, i] = P[b, i] * scb
        else:
            for i in range(n):
                P[b, i] = p_fill[b]


# -- per-case decisions: one compiled call each instead of up to ~80 numpy operations on (B, 1, 1) arrays --
# The same arithmetic as ArrayKernels' expressions, case by case: ``_nmax(a, b)`` is numpy's maximum (NaN
# propagated; ``a`` where equal), so the results are those of the plain expressions bit for bit.


@njit(inline="always")
def _nmax(a, b):
    if a != a or a >= b:
        return a
    return b


@njit(**_JIT)
def _gbar(s, n, out):
    for b in range(s.shape[0]):
        out[b] = s[b] / n[b] if n[b] > 0 else 0.0


@njit(**_JIT)
def _join_fix(nnew, nold, gsum, go, done, c, nf):
    for b in range(nnew.shape[0]):
        joined = go[b] and nnew[b] > nold[b]
        empty = go[b] and nnew[b] == 0
        done[b] = done[b] or empty
        go[b] = go[b] and not empty
        nf[b] = np.float64(nnew[b]) if nnew[b] > 0 else 1.0
        c[b] = gsum[b] / nf[b] if joined else 0.0


@njit(**_JIT)
def _beta(G, gpa, g_old, delta, gprev_ok, go, done, beta, restart):
    for b in range(G.shape[0]):
        ok = G[b] > 0.0 and np.isfinite(G[b])
        done[b] = done[b] or (go[b] and not ok)
        go[b] = go[b] and ok
        restart[b] = not (delta[b] > 0.0 and g_old[b] > 0.0)
        d = g_old[b] if g_old[b] != 0.0 else 1.0
        bb = _nmax(0.0, (G[b] - gpa[b]) / d) if gprev_ok[b] else G[b] / d
        beta[b] = 0.0 if restart[b] or not go[b] else bb


@njit(**_JIT)
def _direction_done(dd, restart, G, go, gprev_ok, g_old, delta, keep):
    for b in range(dd.shape[0]):
        keep[b] = go[b] and (restart[b] or dd[b] > 0.0)
        if go[b]:
            gprev_ok[b] = True
            g_old[b] = G[b]
            delta[b] = 1.0


@njit(**_JIT)
def _step_length(quad, sigma, gt, nan, go, done, tau):
    for b in range(quad.shape[0]):
        rt = quad[b] * (sigma[b] * sigma[b])  # numpy's sigma ** 2 is this product
        tt = gt[b] / rt if rt > 0.0 else nan
        ok = np.isfinite(tt) and tt > 0.0
        done[b] = done[b] or (go[b] and not ok)
        go[b] = go[b] and ok
        tau[b] = tt if go[b] else 0.0


@njit(**_JIT)
def _projection_scale(pany, total, target, go, done, tau, proj, ps):
    for b in range(pany.shape[0]):
        pj = go[b] and pany[b]
        bad = pj and not (total[b] > 0.0)
        done[b] = done[b] or bad
        go[b] = go[b] and not bad
        proj[b] = pj and not bad
        if not go[b]:
            tau[b] = 0.0
        ps[b] = target[b] / (total[b] if total[b] > 0.0 else 1.0) if proj[b] else 1.0


@njit(**_JIT)
def _shrink_fix(nold, nnew, tsum, frac, proj, go, gprev_ok, fresh, c):
    for b in range(nold.shape[0]):
        if proj[b] and (nold[b] - nnew[b]) >= frac * nold[b]:
            gprev_ok[b] = False
        fresh[b] = fresh[b] and not go[b]
        c[b] = tsum[b] / (nnew[b] if nnew[b] > 0 else 1) if proj[b] else 0.0


# -- a round's passes between two transforms, each one compiled call (FusedCpuKernels.measure, ...) ----------
# The same compiled loops and decisions as the methods one at a time, called in the same order: the same results
# bit for bit (tests/test_batch.py). A small grid's round is otherwise mostly the calls' own cost (at 64² ~25
# calls of ~5-10 us each against ~0.18 ms for the single solve's whole iteration: benchmarks/bench_round_passes.py).


@njit(**_JIT)
def _sparse_begin(out, ny, shift, extra, written, wcnt, clear):
    """Before a sparse write into ``out`` (a :func:`_rows` view): undo the last one (``written``, ``wcnt``)
    where ``clear``, else zero every node (not the rows' padding). Here, not before the call: ``out`` may be
    the buffer that the call reads first (an in-place transform's output)."""
    if clear:
        _clear(out, ny, shift, extra, written, wcnt)
        return
    row = ny + extra
    zero = 0.0
    for b in range(out.shape[0]):
        for y in range(out.shape[1] // row):
            for x in range(ny):
                out[b, y * row + x] = zero


@njit(**_JIT)
def _sparse_end(idx, cnt, written, wcnt):
    """After a sparse write at ``F``'s nodes: they are the ones to undo next (:meth:`FusedCpuKernels._record`)."""
    for b in range(idx.shape[0]):
        for k in range(cnt[b]):
            written[b, k] = idx[b, k]
        wcnt[b] = cnt[b]


@njit(inline="always")
def _v(x):
    """A per-case array (``(B, 1, 1)``, C-contiguous) as ``(B,)``: a view, so in-place updates reach the caller's.
    Done here, not by the caller: :func:`_cases` and :func:`_state` cost ~1 us an argument on this VM, and a
    round's passes take ~40 of them."""
    return x.reshape(x.size)


@njit(inline="always")
def _f(x):
    """A ``(B, nx, ny)`` C-contiguous field as ``(B, nx ny)`` (:func:`_fields`)."""
    return x.reshape(x.shape[0], x.size // x.shape[0])


def _rule_digest() -> int:
    """A digest of the loop head's rule as numba compiles it: ``workspace.loop_head`` and ``stall_rule``'s bytecode,
    constants, names, defaults and the values of the module's numbers they name (the decisions ``GO`` ...)."""
    h = hashlib.sha256()
    for fn in (loop_head, stall_rule):
        code = fn.__code__
        numbers = {n: fn.__globals__[n] for n in code.co_names if isinstance(fn.__globals__.get(n), (int, float))}
        h.update(code.co_code + repr((code.co_consts, code.co_names, fn.__defaults__, numbers)).encode())
    return int.from_bytes(h.digest()[:7], "little")


def _head_kernels(digest: int):
    """``(decide, measure_round)``: the kernels that compile the loop head's rule (``workspace.loop_head``) in.

    numba finds a cached kernel by its own file's stamp, its bytecode and the values of its closure, not by the
    functions it compiles in: were the rule edited, a kernel cached here could go on running the former rule (seen
    2026-12-03). ``digest`` (:func:`_rule_digest`) sits in their closure, so a changed rule is compiled anew (a
    function the rule comes to call must join the digest). A cached kernel that calls these must carry it too,
    and call them as globals (a dispatcher in a closure defeats the cache).
    """

    @njit(**_JIT)
    def decide(orth, wmin, gbar, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
               next_sync, best, at, done, waiting, converged, go):
        digest  # noqa: B018 (the rule's digest in the closure: the docstring above)
        for b in range(orth.shape[0]):
            pen = _nmax(gbar[b] - wmin[b], 0.0)
            o = orth[b] * inv_norm[b]
            r = _nmax(_nmax(o, pen / scale[b]), 0.0) if np.isfinite(o) and np.isfinite(pen) else big
            if done[b] or waiting[b]:
                go[b] = False
                continue
            decision, level, best_b, at_b = loop_head(r, tol, fresh[b], next_sync[b], True, it[b], max_iter[b],
                                                      best[b], at[b], stall)
            next_sync[b], best[b], at[b] = level, best_b, at_b
            go[b] = decision == GO
            converged[b] = converged[b] or decision == CONVERGED
            waiting[b] = waiting[b] or decision == WAIT
            done[b] = done[b] or decision == CONVERGED or decision == STOP

    @njit(**_JIT)
    def measure_round(p, w, idx, cnt, nf, wmin, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                      next_sync, best, at, done, waiting, converged, go, gbar):
        digest  # noqa: B018
        p, w, gbar = _f(p), _f(w), _v(gbar)
        _gbar(_masked_sum(w, idx, cnt), _v(nf), gbar)
        _decide(_orth(p, w, gbar, idx, cnt), _v(wmin), gbar, _v(inv_norm), _v(scale), tol, stall, big, _v(it),
                _v(max_iter), _v(fresh), _v(next_sync), _v(best), _v(at), _v(done), _v(waiting), _v(converged),
                _v(go))

    return decide, measure_round


_decide, _measure_round = _head_kernels(_rule_digest())


@njit(**_JIT)
def _join_round(w, gbar, f, idx, cnt, go, done, it, nold, g, c, nf, inv_sigma,
                out, ny, shift, extra, written, wcnt, clear):
    go, done, it, c, nf = _v(go), _v(done), _v(it), _v(c), _v(nf)
    for b in range(go.shape[0]):
        it[b] += go[b]
    _join_fix(cnt, _v(nold), _join(_f(w), _v(gbar), f, idx, cnt, go, g), go, done, c, nf)
    _sub_on(g, c, cnt)
    _sparse_begin(out, ny, shift, extra, written, wcnt, clear)
    _to32_on(g, _v(inv_sigma), idx, cnt, out, ny, shift, extra)
    _sparse_end(idx, cnt, written, wcnt)


@njit(**_JIT)
def _direction_round(r, rny, rshift, rextra, sigma, nf, idx, cnt, a, g, g_prev, t, g_old, delta, gprev_ok, go,
                     done, inv_sigma, out, ny, shift, extra, written, wcnt, clear, gt):
    g_old, delta, gprev_ok, go, done = _v(g_old), _v(delta), _v(gprev_ok), _v(go), _v(done)
    B = a.shape[0]
    G, gpa, gt_old = _center_dots(a, _scaled_on(r, rny, rshift, rextra, _v(sigma), idx, cnt, a) / _v(nf), cnt, g,
                                  g_prev, t)
    beta, restart, keep = np.empty(B), np.empty(B, dtype=np.bool_), np.empty(B, dtype=np.bool_)
    _beta(G, gpa, g_old, delta, gprev_ok, go, done, beta, restart)
    dd = np.empty(B)
    for b in range(B):
        dd[b] = beta[b] * gt_old[b] + G[b]
    _direction_done(dd, restart, G, go, gprev_ok, g_old, delta, keep)
    _sparse_begin(out, ny, shift, extra, written, wcnt, clear)
    _v(gt)[:] = _new_direction(t, a, g, beta, keep, go, g_prev, idx, cnt, _v(inv_sigma), out, ny, shift, extra)
    _sparse_end(idx, cnt, written, wcnt)


@njit(**_JIT)
def _trial_round(re_im, weights, sigma, gt, nan, p, t, idx, cnt, target, go, done, tau, proj, ps):
    go, done, tau = _v(go), _v(done), _v(tau)
    _step_length(_quadratic(re_im, weights), _v(sigma), _v(gt), nan, go, done, tau)
    total, pany = _trial_stats(_f(p), t, tau, idx, cnt)
    _projection_scale(pany, total, _v(target), go, done, tau, _v(proj), _v(ps))


@njit(**_JIT)
def _settle_round(w, r, rny, rextra, factor, p, f, idx, cnt, t, g_prev, nold, frac, proj, go, gprev_ok, fresh, c):
    c = _v(c)
    _add_scaled(_f(w), r, rny, rextra, _v(factor))
    _shrink_fix(_v(nold), cnt, _shrink(_f(p), f, idx, cnt, t, g_prev), frac, _v(proj), _v(go), _v(gprev_ok),
                _v(fresh), c)
    _sub_on(t, c, cnt)


class FreeSet:
    """The free set ``F`` of every case of a batch: its mask and each case's node indices.

    The compressed form of the single solve's index sets, kept beside the mask: a pass over ``F``
    costs ``|F|`` reads, not the grid's. Made by :meth:`FusedCpuKernels.free_set`; the kernels
    update both forms together (the join appends to the indices, the shrink compacts them).

    Attributes
    ----------
    mask : numpy.ndarray
        ``(B, nx, ny)`` bool.
    idx : numpy.ndarray
        ``(B, nx ny)`` int32 (int64 beyond 2**31 nodes); the first ``count[b]`` of row ``b`` are
        case ``b``'s nodes (flat indices), in no particular order after a join.
    count : numpy.ndarray
        ``(B,)`` int64.
    """

    def __init__(self, mask: np.ndarray):
        self.mask = mask
        f = mask.reshape(mask.shape[0], -1)
        self.idx = np.empty(f.shape, dtype=np.int32 if f.shape[1] < 2**31 else np.int64)
        self.count = _index(f, self.idx)

    @property
    def shape(self):
        return self.mask.shape

    def flat(self):
        """``(mask (B, n), idx, count)``: the arguments of the compiled loops."""
        return self.mask.reshape(self.mask.shape[0], -1), self.idx, self.count


class _Written:
    """Which nodes of a transform input the last sparse write set, per case (None: unknown)."""

    def __init__(self, shape, itype):
        self.idx = np.empty(shape, dtype=itype)
        self.count = None


class FusedCpuKernels(ArrayKernels):
    """:class:`~.kernels.ArrayKernels` on the host with each field pass one compiled loop.

    The same results as the plain expressions up to the order of summation (module docstring), the
    vectors on ``F`` compressed (:meth:`vector`; :meth:`gather` and :meth:`scatter` convert). Where a
    kernel takes the free set ``F``, it may be a :class:`FreeSet`
    (:meth:`free_set`, the iteration's: updated in place by :meth:`join_stats` and
    :meth:`shrink_stats`) or a plain mask (indexed for the call). Outputs that the plain kernels
    allocate are written into buffers kept per shape and reused: a result is valid until the same
    kernel is called again (the iteration uses each before that). A transform input written
    on ``F`` (``to32`` with ``F``, :meth:`new_direction_input`, :meth:`project`) zeroes only the nodes
    that the buffer's last such write set: the buffer must not be written by anything else
    in between (a dense write through these kernels is noted, as is an in-place transform's through
    :meth:`overwritten`, and the next sparse one zeroes it all). A transform's buffers may have padded
    rows (:func:`_rows`): the kernels that write its input or read its output take them as they are.
    """

    #: Whether the fields are split over processes (:class:`~roughcontact.solver.mpi.kernels.MpiKernels`): then a
    #: round's passes (:meth:`measure`, :meth:`join`, ...) run one kernel at a time, as
    #: :class:`~.kernels.ArrayKernels` composes them, so that each reduction adds the processes' parts before the
    #: decisions read it; here each is one compiled call.
    split = False

    def __init__(self):
        super().__init__(np)
        self._buffers = {}
        self._written = {}
        self._wq = {}

    def buffer(self, name: str, shape, dtype) -> np.ndarray:
        """A scratch array ``name`` of ``shape`` and ``dtype``, made once and reused."""
        key = (name, tuple(shape), np.dtype(dtype))
        out = self._buffers.get(key)
        if out is None:
            out = self._buffers[key] = np.zeros(shape, dtype=dtype)
        return out

    def free_set(self, mask):
        return FreeSet(mask)

    # -- vectors on F: compressed, position k holding node idx[b, k]'s value ------------------

    def vector(self, F):
        """A zero vector on ``F``: ``(B, nx ny)`` float64, of which case ``b`` uses the first ``|F|`` values.

        Room for every node, since ``F`` may grow to the whole grid; the pages past the largest ``|F|``
        are never touched (so never made resident).
        """
        return np.zeros(self._set(F).idx.shape)

    def gather(self, field, F):
        fs = self._set(F)
        flat = field.reshape(field.shape[0], -1)
        out = np.zeros(fs.idx.shape)
        for b in range(flat.shape[0]):
            n = fs.count[b]
            out[b, :n] = flat[b, fs.idx[b, :n]]
        return out

    def scatter(self, vector, F):
        fs = self._set(F)
        out = np.zeros(fs.shape)
        flat = out.reshape(out.shape[0], -1)
        for b in range(flat.shape[0]):
            n = fs.count[b]
            flat[b, fs.idx[b, :n]] = vector[b, :n]
        return out

    @staticmethod
    def _set(F):
        return F if isinstance(F, FreeSet) else FreeSet(np.ascontiguousarray(F))

    def _sparse_out(self, out, shape):
        """``(out, its written record)`` with ``out``'s last sparse write undone (all of it if unknown)."""
        out = self.buffer("to32", shape, np.float32) if out is None else out
        rec = self._written.get(id(out))
        flat = (out.shape[0], out.shape[1] * out.shape[2])
        if rec is None or rec.idx.shape != flat:
            rec = self._written[id(out)] = _Written(flat, np.int32 if flat[1] < 2**31 else np.int64)
        if rec.count is None:
            out.fill(0.0)
        else:
            _clear(*_rows(out), rec.idx, rec.count)
        return out, rec

    @staticmethod
    def _record(rec, fs, count=None):
        """``fs``'s nodes are those written (``count`` per case where fewer)."""
        n = fs.count if count is None else count
        m = int(n.max(initial=0))
        rec.idx[:, :m] = fs.idx[:, :m]
        rec.count = n.copy()

    def _dense(self, out) -> None:
        """``out`` was written whole: the next sparse write zeroes all of it."""
        rec = self._written.get(id(out))
        if rec is not None:
            rec.count = None

    def overwritten(self, out) -> None:
        self._dense(out)

    @staticmethod
    def _col(v):
        return v.reshape(-1, 1, 1)

    # -- reductions ---------------------------------------------------------------------------

    def rsum(self, x):
        if x.dtype != np.float64:
            return super().rsum(x)
        return self.allsum(self._col(_sum(*_fields(np.ascontiguousarray(x)))))

    def rcount(self, m):
        if isinstance(m, FreeSet):
            return self.allcount(self._col(m.count.copy()))
        return self.allcount(self._col(_count(*_fields(np.ascontiguousarray(m)))))

    def rmin(self, x):
        # numpy's SIMD minimum (NaN if any): no loop of ours does it faster
        return self.allmin(np.min(x, axis=(-2, -1), keepdims=True))

    def masked_sum(self, x, mask):
        fs = self._set(mask)
        return self.allsum(self._col(_masked_sum(*_fields(x), fs.idx, fs.count)))

    def orth(self, P, w, gbar, F):
        fs = self._set(F)
        return self.allsum(self._col(_orth(*_fields(P, w), _cases(gbar, P.shape[0]), fs.idx, fs.count)))

    def dot_on(self, a, b, F):
        fs = self._set(F)
        return self.allsum(self._col(_dot_on(a, b, fs.count)))

    def quadratic(self, spec, weights):
        B = spec.shape[0]
        real = np.float32 if spec.dtype == np.complex64 else np.float64
        ri = np.ascontiguousarray(spec).view(real).reshape(B, -1, 2)
        return self.allsum(self._col(_quadratic(ri, self._weights(weights, spec.shape[1:], real))))

    def _weights(self, weights, shape, real):
        """``weights`` over ``shape`` as a contiguous 1-D array of ``real`` (an operator's multiplier, asked
        for every round: made once, :func:`_made_once`; an operator has two, float32 and float64)."""
        return _made_once(self._wq, weights, (tuple(shape), np.dtype(real)),
                          lambda: np.ascontiguousarray(np.broadcast_to(weights, shape).reshape(-1), dtype=real), 8)

    def trial_stats(self, P, t, tau, F):
        fs = self._set(F)
        sums, anys = _trial_stats(*_fields(P), t, _cases(tau, P.shape[0]), fs.idx, fs.count)
        return self.allsum(self._col(sums)), self.allany(self._col(anys))

    def proj_any(self, P, t, tau, F):
        return self.trial_stats(P, t, tau, F)[1]

    def center_dots(self, a, c, F, g, g_prev, t):
        fs = self._set(F)
        ga, pa, gt = _center_dots(a, _cases(c, a.shape[0]), fs.count, g, g_prev, t)
        return self.allsum(self._col(ga)), self.allsum(self._col(pa)), self.allsum(self._col(gt))

    # -- element-wise passes --------------------------------------------------------------------

    def to32(self, x, scale, out=None, F=None):
        B = x.shape[0]
        if F is None:  # numpy's one pass, the product rounded once into out
            out = super().to32(x, scale, self.buffer("to32", x.shape, np.float32) if out is None else out)
            self._dense(out)
            return out
        fs = self._set(F)  # x: a vector on F
        out, rec = self._sparse_out(out, fs.shape)
        _to32_on(x, _cases(scale, B), fs.idx, fs.count, *_rows(out))
        self._record(rec, fs)
        return out

    def scaled_sum(self, R, factor, F):
        fs = self._set(F)
        a = self.buffer("scaled", fs.idx.shape, np.float64)
        sums = _scaled_on(*_rows(R), _cases(factor, R.shape[0]), fs.idx, fs.count, a)
        return a, self.allsum(self._col(sums))

    def add_scaled(self, w, R, factor):
        r, ny, _, extra = _rows(R)
        _add_scaled(*_fields(w), r, ny, extra, _cases(factor, w.shape[0]))
        return w

    def sub_masked(self, x, c, F):
        fs = self._set(F)
        _sub_on(x, _cases(c, x.shape[0]), fs.count)
        return x

    def join_stats(self, w, gbar, F, go):
        fs = self._set(F)
        B = w.shape[0]
        g = self.buffer("gap", fs.idx.shape, np.float64)
        f, idx, cnt = fs.flat()
        sums = _join(*_fields(w), _cases(gbar, B), f, idx, cnt, _cases(go, B, np.bool_), g)
        return fs, g, self.allcount(self._col(cnt.copy())), self.allsum(self._col(sums))

    def new_direction_input(self, t, a, g, beta, keep, go, g_prev, F, inv_sigma, out=None):
        fs = self._set(F)
        B = t.shape[0]
        out, rec = self._sparse_out(out, fs.shape)
        gt = _new_direction(t, a, g, _cases(beta, B), _cases(keep, B, np.bool_), _cases(go, B, np.bool_),
                            g_prev, fs.idx, fs.count, _cases(inv_sigma, B), *_rows(out))
        self._record(rec, fs)
        return out, self.allsum(self._col(gt))

    def project(self, P, t, tau, go, scale, inv_sigma, out=None, F=None):
        if F is None:
            raise TypeError("FusedCpuKernels.project needs the free set F: t is a vector on it")
        fs = self._set(F)
        B = P.shape[0]
        out, rec = self._sparse_out(out, P.shape)
        wrote = _project(*_fields(P), t, _cases(tau, B), _cases(go, B, np.bool_), _cases(scale, B),
                         _cases(inv_sigma, B), fs.idx, fs.count, *_rows(out))
        self._record(rec, fs, wrote)
        return out

    def step_on(self, P, t, tau, go, F):
        fs = self._set(F)
        _step_on(*_fields(P), t, _cases(tau, P.shape[0]), _cases(go, P.shape[0], np.bool_), fs.idx, fs.count)

    def shrink(self, P, F, t, g_prev):
        self.shrink_stats(P, F, t, g_prev)

    def shrink_stats(self, P, F, t, g_prev):
        fs = self._set(F)  # a plain mask is updated in place too (where C-contiguous)
        f, idx, cnt = fs.flat()
        sums = _shrink(*_fields(P), f, idx, cnt, t, g_prev)
        return self.allcount(self._col(cnt.copy())), self.allsum(self._col(sums))

    # -- per-case decisions (the state arguments in place) ------------------------------------

    def gbar(self, s, n):
        B = s.shape[0]
        out = np.empty(B)
        _gbar(_cases(s, B), _cases(n, B, np.int64), out)
        return self._col(out)

    def decide(self, orth, wmin, gbar, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
               next_sync, best, at, done, waiting, converged, go):
        B = orth.shape[0]
        _decide(_cases(orth, B), _cases(wmin, B), _cases(gbar, B), _cases(inv_norm, B), _cases(scale, B),
                float(tol), int(stall), float(big), _cases(it, B, np.int64), _cases(max_iter, B, np.int64),
                _cases(fresh, B, np.bool_), *_state(next_sync, best, at, done, waiting, converged, go))

    def join_fix(self, nnew, nold, gsum, go, done):
        B = gsum.shape[0]
        c, nf = np.empty(B), np.empty(B)
        _join_fix(_cases(nnew, B, np.int64), _cases(nold, B, np.int64), _cases(gsum, B), *_state(go, done), c, nf)
        return self._col(c), self._col(nf)

    def beta(self, G, gpa, g_old, delta, gprev_ok, go, done):
        B = G.shape[0]
        beta, restart = np.empty(B), np.empty(B, dtype=np.bool_)
        _beta(_cases(G, B), _cases(gpa, B), _cases(g_old, B), _cases(delta, B), _cases(gprev_ok, B, np.bool_),
              *_state(go, done), beta, restart)
        return self._col(beta), self._col(restart)

    def direction_done(self, dd, restart, G, go, gprev_ok, g_old, delta):
        B = G.shape[0]
        keep = np.empty(B, dtype=np.bool_)
        _direction_done(_cases(dd, B), _cases(restart, B, np.bool_), _cases(G, B), _cases(go, B, np.bool_),
                        *_state(gprev_ok, g_old, delta), keep)
        return self._col(keep)

    def step_length(self, quad, sigma, gt, nan, go, done):
        B = gt.shape[0]
        tau = np.empty(B)
        _step_length(_cases(quad, B), _cases(sigma, B), _cases(gt, B), float(nan), *_state(go, done), tau)
        return self._col(tau)

    def projection_scale(self, pany, total, target, go, done, tau):
        B = total.shape[0]
        proj, ps = np.empty(B, dtype=np.bool_), np.empty(B)
        _projection_scale(_cases(pany, B, np.bool_), _cases(total, B), _cases(target, B), *_state(go, done, tau),
                          proj, ps)
        return self._col(proj), self._col(ps)

    def shrink_fix(self, nold, nnew, tsum, frac, proj, go, gprev_ok, fresh):
        B = tsum.shape[0]
        c = np.empty(B)
        _shrink_fix(_cases(nold, B, np.int64), _cases(nnew, B, np.int64), _cases(tsum, B), float(frac),
                    _cases(proj, B, np.bool_), _cases(go, B, np.bool_), *_state(gprev_ok, fresh), c)
        return self._col(c)

    # -- a round's passes, each one compiled call (ArrayKernels' compositions where split) ----------

    def _sparse_target(self, out, shape):
        """``(out, written record, whether the record holds the last write)`` for a compiled sparse write
        (:func:`_sparse_begin` zeroes ``out`` where it does not, :func:`_sparse_end` records the write)."""
        out = self.buffer("to32", shape, np.float32) if out is None else out
        rec = self._written.get(id(out))
        flat = (out.shape[0], out.shape[1] * out.shape[2])
        if rec is None or rec.idx.shape != flat:
            rec = self._written[id(out)] = _Written(flat, np.int32 if flat[1] < 2**31 else np.int64)
        clear = rec.count is not None
        if not clear:
            rec.count = np.zeros(flat[0], dtype=np.int64)
        return out, rec, clear

    # The compiled calls below take the iteration's per-case arrays ((B, 1, 1), C-contiguous, of the dtypes
    # ArrayKernels' expressions give them) and its fields as they are, without _cases or _state (:func:`_v`).

    def measure(self, P, w, F, nF, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                next_sync, best, at, done, waiting, converged, go):
        if self.split:
            return super().measure(P, w, F, nF, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                                   next_sync, best, at, done, waiting, converged, go)
        fs = self._set(F)
        gbar = np.empty((P.shape[0], 1, 1))
        wmin = np.min(w, axis=(-2, -1))  # numpy's SIMD minimum, as rmin
        _measure_round(P, w, fs.idx, fs.count, nF, wmin, inv_norm, scale, float(tol), int(stall), float(big), it,
                       max_iter, fresh, next_sync, best, at, done, waiting, converged, go, gbar)
        return gbar

    def join(self, w, gbar, F, nF, go, done, it, inv_sigma, out=None):
        if self.split:
            return super().join(w, gbar, F, nF, go, done, it, inv_sigma, out=out)
        fs = self._set(F)
        B = w.shape[0]
        g = self.buffer("gap", fs.idx.shape, np.float64)
        c, nf = np.empty((B, 1, 1)), np.empty((B, 1, 1))
        out, rec, clear = self._sparse_target(out, fs.shape)
        f, idx, cnt = fs.flat()
        _join_round(w, gbar, f, idx, cnt, go, done, it, nF, g, c, nf, inv_sigma, *_rows(out), rec.idx, rec.count,
                    clear)
        return fs, g, self._col(cnt.copy()), nf, out

    def direction(self, R, sigma, nf, F, g, g_prev, t, g_old, delta, gprev_ok, go, done, inv_sigma, out=None):
        if self.split:
            return super().direction(R, sigma, nf, F, g, g_prev, t, g_old, delta, gprev_ok, go, done, inv_sigma,
                                     out=out)
        fs = self._set(F)
        a = self.buffer("scaled", fs.idx.shape, np.float64)
        gt = np.empty((R.shape[0], 1, 1))
        out, rec, clear = self._sparse_target(out, fs.shape)
        _direction_round(*_rows(R), sigma, nf, fs.idx, fs.count, a, g, g_prev, t, g_old, delta, gprev_ok, go, done,
                         inv_sigma, *_rows(out), rec.idx, rec.count, clear, gt)
        return out, gt

    def trial(self, spec, weights, sigma, gt, nan, P, t, F, target, go, done):
        if self.split:
            return super().trial(spec, weights, sigma, gt, nan, P, t, F, target, go, done)
        fs = self._set(F)
        B = P.shape[0]
        real = np.float32 if spec.dtype == np.complex64 else np.float64
        ri = np.ascontiguousarray(spec).view(real).reshape(B, -1, 2)
        tau, proj, ps = np.empty((B, 1, 1)), np.empty((B, 1, 1), dtype=np.bool_), np.empty((B, 1, 1))
        _trial_round(ri, self._weights(weights, spec.shape[1:], real), sigma, gt, float(nan), P, t, fs.idx, fs.count,
                     target, go, done, tau, proj, ps)
        return tau, proj, ps

    def settle(self, w, R, factor, P, F, t, g_prev, nF, frac, proj, go, gprev_ok, fresh):
        if self.split:
            return super().settle(w, R, factor, P, F, t, g_prev, nF, frac, proj, go, gprev_ok, fresh)
        fs = self._set(F)
        r, ny, _, extra = _rows(R)
        f, idx, cnt = fs.flat()
        _settle_round(w, r, ny, extra, factor, P, f, idx, cnt, t, g_prev, nF, float(frac), proj, go, gprev_ok, fresh,
                      np.empty((w.shape[0], 1, 1)))
        return self._col(cnt.copy())

    # -- the warm start of a load step --------------------------------------------------------

    def scale_start(self, P, w, h, s, plain):
        B = P.shape[0]
        _scale_start(*_fields(P, w, h), _cases(s, B), _cases(plain, B, np.bool_))

    def extrapolate(self, P, w, P_last, P_older, w_last, w_older, c, ext, lin, inv_sigma, out=None):
        B = P.shape[0]
        out = self.buffer("to32", P.shape, np.float32) if out is None else out
        tot = _extrapolate(*_fields(P, w, P_last, P_older, w_last, w_older), _cases(c, B), _cases(ext, B, np.bool_),
                           _cases(lin, B, np.bool_), _cases(inv_sigma, B), *_rows(out))
        self._dense(out)
        return self.allsum(self._col(tot)), out

    def finish_start(self, P, w, h, R, sigma, sc, loaded, ext, lin, p_fill):
        B = P.shape[0]
        _finish_start(*_fields(P, w, h), *_rows(P if R is None else R), _cases(sigma, B), _cases(sc, B),
                      _cases(loaded, B, np.bool_), _cases(ext, B, np.bool_), _cases(lin, B, np.bool_),
                      _cases(p_fill, B), R is not None)
