#!/usr/bin/env python
"""Experiment (issue 63): the single solve's float32 iteration run by the batched iteration class, byte for byte.

One iteration class needs ``solve_contact`` to run :class:`roughcontact.solver.iteration.BatchIteration` with
B = 1. Switched as it is, every scene's outputs would move in their last bits (another order of summation, the
float64 update of ``w``, another descent test), and every published number would need rechecking. This script
tries the other route: kernels of ``BatchIteration`` (:class:`SingleKernels`) whose arithmetic is
:class:`~roughcontact.solver.elastic.PKIteration`'s for ``pk-fourier-f32`` (the workspace's compressed index sets
in numpy, pairwise sums and einsum dots, ``w`` updated in float32 and then subtracted, the descent test on the new
direction, the resync's total over the free set), with the transforms of the workspace's own half-space
(:class:`SingleOperator`: the periodic one, the free one with its periodic preconditioner, a profile's). It routes
``contact.pk_solve`` for ``pk-fourier-f32`` through them (:func:`pk_f32_solve`) and compares every output
variable but the wall time with the plain ``solve_contact`` (every step's pressure and gap fields stored), byte for
byte:

- the paper case (k_l = 16, k_s = 32, H = 0.8, rms slope 0.1; 10 steps to p0/E* = 0.005) at 64² to 512² and other
  seeds, the free boundary at 128², a profile of 2048 points (k_l = 4, k_s = 64);
- SurfaceTopography's five example files (``bench_real_files.py``'s reading, ``mpi/real_files.py``'s loads);

then the CPU of ``pk_solve``'s calls (the iterations, with the experiment's set-up per call), PKIteration against
these kernels, interleaved in one process.

Not covered (the experiment raises): a projection that leaves no pressure (PKIteration's full projection with a
fresh ``K p``). Not tried: ``pk-fourier`` (float64 products), ``pk``, the CuPy backend. Not optimised: the kernels
gather the pressure on the free set each round and convert per-case numbers one by one.

    OMP_NUM_THREADS=1 python benchmarks/one_iteration_spike.py [--repeats 9]
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from roughcontact.solver.batch.iteration import BatchIteration  # noqa: E402

from roughcontact.solver.batch.kernels import ArrayKernels  # noqa: E402
from roughcontact.solver.workspace import dot  # noqa: E402

HERE = Path(__file__).resolve().parent


def _f(x):
    return float(np.asarray(x).reshape(-1)[0])


def _i(x):
    return int(np.asarray(x).reshape(-1)[0])


def _b(x):
    return bool(np.asarray(x).reshape(-1)[0]) if isinstance(x, np.ndarray) else bool(x)


class _Token:
    """A transform input: the product it was loaded into."""

    def __init__(self, loader, prod):
        self.loader, self.prod = loader, prod


class SingleOperator:
    """The batched iteration's operator interface over a workspace's half-space (float32 products)."""

    def __init__(self, ws):
        ws.setup_method()
        op = ws.op
        self.ws, self.hs = ws, op
        self.kmult32, self.kquad32 = op.kmult32, op.kquad32
        m = op.precond if hasattr(op, "precond") else op
        self.mmult32 = m.mmult32
        self.m = _Token(m.loader, m.prod32)  # the preconditioner's product (its loader, its plans)
        self.k = _Token(op.loader, op.prod32)  # K's
        self.input32 = self.k  # BatchIteration passes it as ``out``; the kernels pick the product they load
        self._last = None

    def transform32(self, token):
        self._last = token
        return token.prod.forward()

    def inverse32(self, spec, mult):
        token = self._last
        out = token.prod.backward(spec, mult)
        hs = self.hs if token is self.k else (self.hs.precond if hasattr(self.hs, "precond") else self.hs)
        if hasattr(hs, "_on_patch"):
            return hs._on_patch(out)
        nx, ny = self.hs.shape
        return out[:nx, :ny]


class _Set:
    """The free set: indices (ascending at first, joined nodes appended), the vectors made on it."""

    def __init__(self, ws):
        self.ws = ws
        self.idx = ws.active_set()
        self.vectors = []
        self.g_cand = self.cand = None
        self.trial = None


class _Vec:
    def __init__(self, n):
        self.a = np.zeros(n)
        self.valid = True  # g_prev: False where the single solve has None


class SingleKernels(ArrayKernels):
    """The round's passes with PKIteration's arithmetic (B = 1, host)."""

    def __init__(self, ws, op: SingleOperator):
        super().__init__(np)
        self.ws, self.op = ws, op
        self.F = None

    def free_set(self, mask):
        self.F = _Set(self.ws)
        return self.F

    def rcount(self, m):
        return np.full((1, 1, 1), m.idx.size, dtype=np.int64)

    def vector(self, F):
        v = _Vec(F.idx.size)
        F.vectors.append(v)
        return v

    def rsum(self, x):  # the resync's pressure total: P is zero off F; the single solve sums p_c
        return np.full((1, 1, 1), self.ws.Pf[self.F.idx].sum())

    def measure(self, P, w, F, nF, inv_norm, scale, tol, stall, big, it, max_iter, fresh,
                next_sync, best, at, done, waiting, converged, go):
        ws, idx = self.ws, F.idx
        nf = idx.size
        gbar = 0.0
        if nf:
            g_c = np.take(ws.wf, idx)
            gbar = g_c.sum() / nf
            g_c -= gbar
        np.less(ws.w, gbar, out=ws.bbuf)
        np.greater(ws.bbuf, ws.mask, out=ws.bbuf)
        ncand = int(np.count_nonzero(ws.bbuf))
        pen = 0.0
        F.cand = F.g_cand = None
        if ncand:
            F.cand = np.flatnonzero(ws.bbuf)
            F.g_cand = ws.wf[F.cand] - gbar
            pen = -float(F.g_cand.min())
        orth = 0.0
        if nf:
            pen = max(pen, -float(g_c.min()))
            orth = dot(ws.Pf[idx], np.abs(g_c))
        # the decisions of ArrayKernels.decide on the single solve's residual (orth already a sum; pen as gbar - wmin)
        r = max(orth * _f(inv_norm.reshape(())), pen / _f(scale.reshape(())), 0.0)
        self._decide(r, tol, stall, it, max_iter, fresh, next_sync, best, at, done, waiting, converged, go)
        return np.full((1, 1, 1), gbar)

    @staticmethod
    def _decide(r, tol, stall, it, max_iter, fresh, next_sync, best, at, done, waiting, converged, go):
        active = not (_b(done) or _b(waiting))
        below = r <= tol
        fr = _b(fresh)
        conv = active and below and fr
        sync_level = (not below) and r < _f(next_sync)
        want = active and (not fr) and (below or sync_level)
        if want and sync_level:
            while _f(next_sync) > r:
                next_sync *= 1e-4
        rest = active and not conv and not want
        if rest and math.isfinite(r) and _i(it) < _i(max_iter) and r < 0.5 * _f(best):
            best[...] = r
            at[...] = it
        stop = rest and (not math.isfinite(r) or _i(it) >= _i(max_iter) or _i(it) - _i(at) >= stall)
        go[...] = rest and not stop
        converged |= conv
        waiting |= want
        done |= conv or stop

    def join(self, w, gbar, F, nF, go, done, it, inv_sigma, out=None):
        ws = self.ws
        it += go
        g_c = np.take(ws.wf, F.idx) - _f(gbar.reshape(()))  # the measure's g_c (recomputed: the same values)
        joined = F.cand is not None and _b(go)
        if joined:
            F.idx = np.concatenate([F.idx, F.cand])
            g_c = np.concatenate([g_c, F.g_cand])
            for v in F.vectors:
                v.a = np.concatenate([v.a, np.zeros(F.cand.size)])
            ws.mask.reshape(-1)[F.cand] = True
        n = F.idx.size
        if _b(go) and n == 0:
            go[...] = False
            done[...] = True
        if joined:
            g_c -= g_c.sum() / n
        F.g = g_c
        self.op.m.loader.load(F.idx, g_c, 1.0 / ws.sigma)
        return F, _Vec(0), np.full((1, 1, 1), n, dtype=np.int64), np.full((1, 1, 1), float(max(n, 1))), self.op.m

    def direction(self, R, sigma, nf, F, g, g_prev, t, g_old, delta, gprev_ok, go, done, inv_sigma, out=None):
        ws, idx, g_c = self.ws, F.idx, F.g
        n = idx.size
        if not _b(go):
            return self.op.k, np.zeros((1, 1, 1))
        a_c = np.empty(n)
        self.op.m.loader.take(R, idx, a_c)
        a_c *= ws.sigma
        a_c -= a_c.sum() / n
        restart = not (_f(delta) > 0.0 and _f(g_old) > 0.0)
        G = dot(g_c, a_c)
        if not (G > 0.0 and math.isfinite(G)):
            go[...] = False
            done[...] = True
            return self.op.k, np.zeros((1, 1, 1))
        t_c = t.a
        if restart:
            t_c[...] = a_c
        else:
            beta = G / _f(g_old) if not (_b(gprev_ok) and g_prev.valid) else \
                max(0.0, (G - dot(g_prev.a, a_c)) / _f(g_old))
            t_c *= beta
            t_c += a_c
            if not dot(g_c, t_c) > 0.0:
                t_c[...] = a_c
        g_prev.a = g_c.copy()
        g_prev.valid = True
        gprev_ok[...] = True
        g_old[...] = G
        delta[...] = 1.0
        self.op.k.loader.load(idx, t_c, 1.0 / ws.sigma)
        return self.op.k, np.full((1, 1, 1), dot(g_c, t_c))

    def trial(self, spec, weights, sigma, gt, nan, P, t, F, target, go, done):
        ws = self.ws
        tau = np.zeros((1, 1, 1))
        proj = np.zeros((1, 1, 1), dtype=bool)
        ps = np.ones((1, 1, 1))
        if not _b(go):
            return tau, proj, ps
        rt = self.op.k.prod.quadratic(spec, weights) * ws.sigma ** 2
        tt = _f(gt.reshape(())) / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tt) and tt > 0.0):
            go[...] = False
            done[...] = True
            return tau, proj, ps
        tau[...] = tt
        trial = np.multiply(t.a, -tt)
        trial += ws.Pf[F.idx]
        F.trial = trial
        if _b((trial <= 0.0).any()):
            x = np.maximum(-trial, 0.0)
            np.maximum(trial, 0.0, out=trial)
            total = float(trial.sum())
            if not total > 0.0:
                raise NotImplementedError("spike: the single solve's full projection (no pressure left)")
            F.x = x
            proj[...] = True
            ps[...] = _f(target.reshape(())) / total
        return tau, proj, ps

    def step_on(self, P, t, tau, go, F):
        if _b(go):
            self.ws.Pf[F.idx] = F.trial

    def project(self, P, t, tau, go, scale, inv_sigma, out=None, F=None):
        ws, trial, x = self.ws, F.trial, F.x
        s = _f(scale.reshape(()))
        x += (s - 1.0) * trial
        trial *= s
        x -= _f(tau.reshape(())) * t.a
        ws.Pf[F.idx] = trial
        self.op.k.loader.load(F.idx, x, 1.0 / ws.sigma)
        return self.op.k

    def settle(self, w, R, factor, P, F, t, g_prev, nF, frac, proj, go, gprev_ok, fresh):
        ws = self.ws
        f = _f(factor)
        np.multiply(R, R.dtype.type(abs(f)), out=R)
        if f < 0:
            np.subtract(ws.w, R, out=ws.w)
        else:
            np.add(ws.w, R, out=ws.w)
        if _b(proj):
            idx = F.idx
            keep = F.trial > 0.0
            gone = idx[~keep]
            ws.mask.reshape(-1)[gone] = False
            ws.Pf[gone] = 0.0
            F.idx = idx[keep]
            if g_prev.valid and gone.size >= frac * idx.size:
                g_prev.valid = False
                gprev_ok[...] = False
            g_prev.a = g_prev.a[keep] if g_prev.a.size == idx.size else g_prev.a
            t.a = t.a[keep]
            if t.a.size:
                t.a -= t.a.mean()
        if _b(go):
            fresh[...] = False
        return np.full((1, 1, 1), F.idx.size, dtype=np.int64)


class _Case:
    """What BatchIteration reads of its solver, over one workspace."""

    def __init__(self, ws, tol):
        self.ws = ws
        self.xp, self.be = np, ws.be
        self.op = SingleOperator(ws)
        self.kernels = SingleKernels(ws, self.op)
        self.batch, self.tol, self.size = 1, tol, ws.size
        self.h_rms = np.full((1, 1, 1), ws.h_rms)
        self.P, self.w = ws.P[None], ws.w[None]

    def refresh(self, cases):
        self.ws.refresh()


def pk_f32_solve(ws, p0: float, tol: float, max_iter: int, fresh):
    """:func:`~.elastic.pk_solve` for ``pk-fourier-f32`` through :class:`BatchIteration` with :class:`SingleKernels`."""
    case = _Case(ws, tol)
    f0 = np.array([1 if fresh is True else (0 if fresh is False else -1)])
    it = BatchIteration(case, np.full((1, 1, 1), p0), f0, np.array([max_iter]))
    its, conv = it.run(1)
    np.greater(ws.P, 0.0, out=ws.mask)
    return int(its[0]), _b(conv[0])


def _routed(real):
    def pk_solve(ws, p0, tol, max_iter, fresh):
        if ws.method == "pk-fourier-f32":
            return pk_f32_solve(ws, p0, tol, max_iter, fresh)
        return real(ws, p0, tol, max_iter, fresh)
    return pk_solve


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two arrays hold the same dtype, shape and bytes (so +0.0 and -0.0 differ, and NaNs compare)."""
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def compare(label, solve, *args, **kwargs) -> bool:
    """``solve`` with PKIteration and with these kernels, every step's fields stored; prints the iterations and the
    variables whose bytes differ (every variable of the dataset but the wall time: the per-step numbers and the
    pressure and gap fields)."""
    from roughcontact.solver import contact

    real = contact.pk_solve
    ref = solve(*args, store_fields=True, **kwargs)
    contact.pk_solve = _routed(real)
    try:
        new = solve(*args, store_fields=True, **kwargs)
    finally:
        contact.pk_solve = real
    names = sorted(k for k in ref.data_vars if k != "wall_time")
    diff = [k for k in names if not _same_bits(ref[k].values, new[k].values)]
    print(f"{label}: iterations {int(ref.iterations.sum())} and {int(new.iterations.sum())}; {len(names)} variables "
          f"compared ({', '.join(n for n in names if ref[n].ndim > 1)} among them); bytes differ in: {diff or 'none'}",
          flush=True)
    return not diff


def timing(n: int, repeats: int) -> str:
    """CPU of the iterations alone (``pk_solve``'s calls), PKIteration against these kernels, least of ``repeats``."""
    from roughcontact.solver import contact, solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.0005, 0.005, 10)
    real = contact.pk_solve
    spent = [0.0]

    def timed(fn):
        def call(*a):
            c0 = time.process_time()
            try:
                return fn(*a)
            finally:
                spent[0] += time.process_time() - c0
        return call

    modes = {"PKIteration": timed(real), "kernels": timed(_routed(real))}
    cpu = {k: [] for k in modes}
    try:
        for fn in modes.values():
            contact.pk_solve = fn
            solve_contact(h, loads)
        for _ in range(repeats):
            for k, fn in modes.items():
                contact.pk_solve = fn
                spent[0] = 0.0
                solve_contact(h, loads)
                cpu[k].append(spent[0])
    finally:
        contact.pk_solve = real
    a, b = cpu["PKIteration"], cpu["kernels"]
    paired = statistics.median(y / x for x, y in zip(a, b, strict=True))
    return f"| {n}² | {min(a):.4f} | {min(b):.4f} | {min(b) / min(a):.3f} | {paired:.3f} |"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--repeats", type=int, default=9)
    a = ap.parse_args(argv)
    sys.path.insert(0, str(HERE))
    sys.path.insert(0, str(HERE / "mpi"))
    from bench_real_files import FILES
    from real_files import E_STAR, P_MAX, STEPS

    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_profile, generate_surface
    from roughcontact.surfaces.topography import read_topography

    load0 = os.getloadavg()[0]
    print(f"one_iteration_spike {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, load {load0:.2f}")
    loads = np.linspace(0.0005, 0.005, 10)
    same = []
    for n, seed in ((64, 0), (128, 0), (128, 3), (256, 1), (512, 2)):
        h = generate_surface(n, 16, 32, 0.8, seed, rms_slope=0.1)
        same.append(compare(f"{n}² seed {seed}", solve_contact, h, loads))
    h = generate_surface(128, 16, 32, 0.8, 0, rms_slope=0.1)
    same.append(compare("128² free boundary", solve_contact, h, loads, boundary="free"))
    same.append(compare("profile of 2048 points", solve_contact, generate_profile(2048, 4, 64, 0.8, 0, rms_slope=0.1),
                        loads))
    data = HERE.parent / "tests" / "data" / "surfacetopography"
    real_loads = [P_MAX * (k + 1) / STEPS for k in range(STEPS)]
    for name, crop in FILES:
        s = read_topography(data / name, unit="um", undefined="harmonic", detrend="height",
                            **({"non_square": crop} if crop else {}))
        same.append(compare(f"{name} {s.heights.shape}", solve_contact, s.heights, real_loads, e_star=E_STAR,
                            length=s.length, tol=1e-8))
    print(f"byte-identical: {sum(same)} of {len(same)}")
    print("| grid | PKIteration CPU [s] | kernels CPU [s] | ratio, least | paired median |")
    print("|---|---:|---:|---:|---:|")
    for n in (64, 128, 256):
        print(timing(n, a.repeats), flush=True)
    print(f"ended {datetime.datetime.now(datetime.UTC):%H:%M} UTC, load {os.getloadavg()[0]:.2f}")
    return 0 if all(same) else 1


if __name__ == "__main__":
    raise SystemExit(main())
