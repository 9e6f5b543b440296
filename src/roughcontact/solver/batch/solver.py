"""The solver of a batch of surfaces (:mod:`roughcontact.solver.batch`): units per case, fields, warm starts, steps."""

from __future__ import annotations

import math
import os

import numpy as np

from ...core.backend import get_backend
from ...core.cell import Cell
from ...statistics.patches import contact_patches
from ..check import MEAN_RTOL
from ..iteration import BatchIteration
from ..settings import SolverSettings
from ..steps import EXTRAPOLATED, LINEAR, SCALED, fall_back, run_path, start_fresh, start_kind
from ..units import Units, check_loads, rms_about_mean
from ..workspace import SOLVER_PATHS, Workspace
from .cpu import FusedCpuKernels
from .cuda import fused_kernels
from .halfspace import BatchOperator

#: The only elastic iteration a batch runs (the package default).
BATCH_METHOD = "pk-fourier-f32"

#: Rounds between two reads of the per-case flags by the host, per array backend, when the caller
#: gives none. A read drains the GPU's queue of kernels, but a round of a batch of 1024² cases keeps
#: the GPU busy for milliseconds and the host needs only tens of microseconds to launch the next
#: kernel, while a case that asks for a float64 recomputation between two reads idles until the
#: next (15-30 % more rounds at 8): every round on both backends until measured otherwise
#: (benchmarks/gpu/run.sh measures 1 and 8).
CHECK_EVERY = {"numpy": 1, "cupy": 1}


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
        self.cell = Cell.canonical(self.shape, self.length, "heights")
        self.method = BATCH_METHOD
        self.periodic = True
        self.array_backend = settings.array_backend
        self.be = get_backend(self.array_backend)
        self.xp = xp = self.be.xp
        self.check_every = CHECK_EVERY.get(self.be.name, 1) if check_every is None else int(check_every)
        if self.check_every < 1:
            raise ValueError(f"check_every must be an int >= 1, got {check_every!r}")
        # per case on the host, in threads (numpy releases the GIL): at 1024² a case takes ~20 ms here,
        # seconds for a batch of 128 during which the GPU would idle
        self.units = per_case(lambda b: Units(h[b], settings.e_star, settings.length), B, h[0].size)
        flat = [b for b, u in enumerate(self.units) if u.flat]
        if flat:
            raise ValueError(f"heights: case(s) {flat} are flat (all heights equal); a batch takes rough surfaces "
                             "only (solve a flat surface alone with solve_contact)")
        hin = np.stack([u.heights for u in self.units])
        rms = np.array(per_case(lambda b: rms_about_mean(self.units[b].heights)[1], B, h[0].size))
        self.h_rms = xp.asarray(rms.reshape(B, 1, 1))
        self.h_rms_host = rms
        self.kernels = fused_kernels(xp) if self.be.name == "cupy" else FusedCpuKernels()
        self.op = BatchOperator(self.be, self.shape, self.cell.aspect, self.threads, self.kernels, B)
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
        transforms see at most ``log2(B) + 1`` shapes, whose plans the backend caches. On the host,
        case by case instead.
        """
        xp = self.xp
        m = cases.size
        if self.be.name == "numpy":
            # on the host one case at a time (the same transform whichever cases are refreshed together,
            # so that a case's result does not depend on its batch-mates' progress)
            for b in cases:
                self.w[b] = self.op.apply64(self.P[b:b + 1])[0]
                self.w[b] -= self.h[b]
            return
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

        The start of :func:`~roughcontact.solver.steps.start_kind` per case, as the single solve's for the float32
        iteration without a cap: the uniform load at the first step; the scaled last solution (``w`` scaled with
        it: fresh) while there is one; from the third step the extrapolation through the last two, clipped at 0,
        with ``w`` from their gaps and one float32 product of the clipped part (fresh = -1: not recomputed) where
        both ended on the batch's iteration, else computed afresh.
        """
        xp, B = self.xp, self.batch
        target = p_int * self.size
        older = self._older
        linear = self._last[2] & older[3] if older is not None else False
        kinds, c = start_kind(p_int, self.prev, None if older is None else older[0], linear)
        if self.prev is None:
            self.P[...] = xp.asarray(p_int.reshape(B, 1, 1))
            return start_fresh(kinds)
        s = p_int / self.prev
        k = self.kernels
        # the scaled start: p and u = K p scale together, so w follows without a transform
        k.scale_start(self.P, self.w, self.h, xp.asarray(s.reshape(B, 1, 1)),
                      xp.asarray((kinds == SCALED).reshape(B, 1, 1)))
        extrapolated, lin = kinds >= EXTRAPOLATED, kinds == LINEAR
        if extrapolated.any():
            ext, ld = xp.asarray(extrapolated.reshape(B, 1, 1)), xp.asarray(lin.reshape(B, 1, 1))
            # p = max((1 + c) p_last - c p_older, 0) (unscaled yet); where lin, w = (1 + c) w_last - c w_older
            # exactly, plus K of the clipped part (float32, from the transform input x32)
            tot, x32 = k.extrapolate(self.P, self.w, self._last[0], older[1], self._last[1], older[2],
                                     xp.asarray(c.reshape(B, 1, 1)), ext, ld, 1.0 / self.h_rms,
                                     out=self.op.input32)
            R = self.op.inverse32(self.op.transform32(x32), self.op.kmult32) if lin.any() else None
            sc = xp.asarray(target.reshape(B, 1, 1)) / xp.where(tot > 0, tot, 1.0)
            k.finish_start(self.P, self.w, self.h, R, self.h_rms, sc, tot > 0, ext, ld,
                           xp.asarray(p_int.reshape(B, 1, 1)))
        return start_fresh(kinds)

    def fallback(self, b: int, p_int: float, its: int) -> tuple[int, str, bool]:
        """The single solve's fallbacks (:func:`~roughcontact.solver.steps.fall_back`) on case ``b`` alone, from its
        pressure.

        ``its`` iterations are spent; returns ``(iterations in all, path, converged)`` with the
        batch's ``P`` and ``w`` of the case replaced by the fallback's (fresh).
        """
        ws = self._ws.get(b)
        if ws is None:
            ws = self._ws[b] = Workspace(self.h_host[b], self.length, self.threads, "pk-fourier", "periodic",
                                         backend=self.array_backend)
        ws.P[...] = self.P[b]
        ws.w[...] = self.w[b]
        its, path, ok = fall_back(BATCH_METHOD, its, False, self.max_iter,
                                  lambda method, left: run_path(ws, method, p_int, self.tol, left, True, "pk-fourier"))
        self.P[b] = ws.P
        self.w[b] = ws.w
        return its, path, ok

    def final_check(self, p_int: np.ndarray):
        """The single solve's :func:`~roughcontact.solver.check.final_check` per case (no cap).

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
        """Contact perimeter per unit area of every case, host (B,).

        Periodic; :func:`~roughcontact.solver.results.contact_perimeter`.
        """
        xp = self.xp
        m = self.P > 0.0
        ex = xp.sum(m != xp.roll(m, 1, axis=1), axis=(1, 2), dtype=np.int64)
        ey = xp.sum(m != xp.roll(m, 1, axis=2), axis=(1, 2), dtype=np.int64)
        ex, ey = (self.be.to_host(v).astype(np.float64) for v in (ex, ey))
        return self.cell.perimeter_per_area(ex, ey)

    def largest_patches(self) -> np.ndarray:
        """Nodes of the largest contact patch of every case (periodic;
        :func:`~roughcontact.statistics.patches.contact_patches`), host (B,) int64."""
        masks = self.be.to_host(self.P > 0.0)
        return np.array(per_case(lambda b: contact_patches(masks[b])[1], self.batch, self.size), dtype=np.int64)

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
                "contact_perimeter": self.perimeter(), "contact_nodes": nf,
                "largest_patch_nodes": self.largest_patches(), "residual": residual, "iterations": its,
                "converged": ok, "solver_path": np.array([SOLVER_PATHS.index(p) for p in paths], dtype=np.int8),
                "rounds": it.rounds}


def per_case(fn, B: int, size: int) -> list:
    """``[fn(0), ..., fn(B - 1)]``, in up to 8 threads where the cases are large enough to pay for them."""
    if B < 4 or size < 256 * 256:
        return [fn(b) for b in range(B)]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=min(8, B, os.cpu_count() or 1)) as pool:
        return list(pool.map(fn, range(B)))


def _copy_into(dst, src):
    dst[...] = src
    return dst
