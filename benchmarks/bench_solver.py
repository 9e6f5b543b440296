#!/usr/bin/env python
"""Benchmark of roughcontact.solver against Tamaas' PolonskyKeerRey on the paper case.

For each grid size N (one fresh subprocess per N, ``OMP_NUM_THREADS=1``, so that peak
memory and FFT plans of one size do not leak into the next) it:

1. generates the paper surface (k_l = 16, k_s = 32, H = 0.8, rms slope 0.1, seed 0) with
   :func:`roughcontact.surfaces.synthetic.generate_surface` (which also makes the FFT plans),
   and pays the process' one-off solver set-up (the unit registry built on a process' first
   solve, about 0.5 s CPU; with ``--backend cupy`` also a one-step solve that compiles the
   kernels and makes the cuFFT plans) outside the timing: "setup CPU" in the detail table;
2. runs :func:`roughcontact.solver.solve_contact` over ``--steps`` loads ``p_max/steps ...
   p_max``: wall (``perf_counter``) and CPU (``process_time``) time, iterations, the CPU
   time at the end of each step (its ``progress`` callback: a timestamp, no change to the
   solve) and the FFT pairs it computes (the ``Workspace.apply_*`` products wrapped by a
   Python call counter, about a microsecond a pair); then reads the process' peak RSS
   (``ru_maxrss``: imports + surface + solve) before anything else allocates;
3. times FFT pairs (best of batches, candidates in turn so that load drift hits all alike):
   float32 ``rfft2`` + ``irfft2`` with the solver's own cached plan
   (``roughcontact.core.fft.get_fft((N, N), dtype=numpy.float32)``) by ``process_time``,
   "raw" (the two plans' ``execute()`` alone; the backward plan is pointed at the forward
   plan's output for the timing, the same plan, because a c2r transform destroys its input
   and its own buffer would turn to NaN after a few pairs), "+ copies"
   (``fft.backward(fft.forward(a))``: copy in, transform, copy in, transform, scale) and "in
   place", the pair of the solver's inner loop (:class:`roughcontact.core.backend.SpectralProduct`'s
   in-place plans, ``execute()`` alone; :func:`_in_place_pairs`);
   float64 pairs by ``perf_counter``: the solver's plan, the same pair planned with
   ``FFTW_MEASURE`` (only where the plan comparison runs or N <= 1024: planning is slow at
   large N) and ``numpy.fft``, and the planning time of both plans;
4. for N <= 2048 repeats the solve under ``tracemalloc`` (peak of the solver's own numpy
   allocations; n/a above);
5. ``--plan-repeats`` (default "auto": 2 for N <= 1024, 0 above): solves again with
   ``FFTW_ESTIMATE`` plans, ``FFTW_MEASURE`` plans and ``numpy.fft`` in turn, several times;
6. ``--methods`` (default "auto": ``pk,pk-fourier,pk-fourier-f32`` for N <= 1024, none
   above): solves with each elastic iteration of :data:`roughcontact.solver.workspace.ELASTIC_METHODS`
   (``"pk"`` is the reference) in ``--method-repeats`` interleaved rounds; with two or more
   ``--n`` the output ends with the exponent ``a`` of ``iterations ~ N**a`` per method;
7. runs Tamaas' ``PolonskyKeerRey`` (pressure primal and constraint, one thread, the same
   array and tolerance) on the first ``--tamaas-steps`` loads (default "auto": all for
   N <= 1024, the first one above: its cold start from a uniform pressure costs Tamaas 290 s
   CPU at N = 4096, 2026-11-26) and compares A/A0 over those steps.

An explicit ``--plan-repeats``, ``--methods`` or ``--tamaas-steps`` applies to every N.
``--backend cupy`` solves on the GPU (the solver's array backend option): Tamaas, the
plan and method comparisons and ``tracemalloc`` are skipped (they measure host CPU work),
times are ``perf_counter`` after the solve returns (its host arrays mean the GPU has
finished), the float32 pair is ``cupy.fft.irfft2(cupy.fft.rfft2(a), s=a.shape)`` timed with
CUDA events, and the GPU memory pool's size after the solve is reported.

Output: a header line (UTC date, CPU model, ``os.getloadavg()`` at the start and the end,
versions), per-step tables, a wide detail table (every measurement), then, last, the summary:

=============================  ===============================================================
column                         meaning
=============================  ===============================================================
N, steps                       grid points per side, load steps
iterations                     our iterations summed over the steps
converged                      every step passed the solver's final check
CPU [s], wall [s]              our solve, ``process_time`` / ``perf_counter``, set-up excluded
ms/iter                        sum of the steps' wall times / iterations [ms]
f32 pair [ms] (raw)            item 3, the cheaper of "raw" and "in place" (cupy: the GPU
                               pair) [ms]
pair-eq/iter                   our CPU seconds per iteration / that pair's CPU seconds: the
                               cost of an iteration in float32 FFT pairs (cupy: wall seconds)
FFT pairs/iter                 FFT pairs (float64 + float32) counted in the solve / iterations
peak RSS [MB]                  process peak RSS after the solve (MiB)
peak GPU pool [MB]             (cupy) ``cupy.get_default_memory_pool().total_bytes()`` (MiB)
Tamaas CPU [s]                 Tamaas' ``process_time`` over the steps it ran
Tamaas steps                   steps Tamaas ran (K of steps)
CPU ratio Tamaas/ours          Tamaas CPU / our CPU; when Tamaas ran the first K < steps
                               steps only, over those: our CPU from the solve's start to the
                               end of step K (progress timestamps, set-up of the solve included)
max rel dA/A0                  max over Tamaas' steps of ``|A_ours - A_tamaas| / A_tamaas``
=============================  ===============================================================

``--out FILE`` writes the header, the summary and then the detail table (``.csv``: two CSV
blocks, the header lines as ``#`` comments; anything else markdown).

Usage::

    python benchmarks/bench_solver.py                          # N = 512 1024
    python benchmarks/bench_solver.py --n 512 1024 4096        # issue 29's table
    python benchmarks/bench_solver.py --n 256 --out benchmarks/out/bench.md
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import datetime
import importlib.metadata
import io
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc

import numpy as np

#: Largest N at which "auto" runs the extras: plan and method comparisons, every Tamaas step.
AUTO_MAX_N = 1024
#: Largest N at which the solve is repeated under tracemalloc.
TRACEMALLOC_MAX_N = 2048
#: Tamaas steps above AUTO_MAX_N under "auto".
TAMAAS_AUTO_STEPS = 1
DEFAULT_PLAN_REPEATS = 2
DEFAULT_METHODS = "pk,pk-fourier,pk-fourier-f32"
RESULT_TAG = "@@RESULT@@"


# --------------------------------------------------------------------------- options
def resolve_extras(n: int, steps: int, plan_repeats="auto", methods="auto", tamaas_steps="auto",
                   backend: str = "numpy") -> dict:
    """What runs at grid size ``n`` besides the main solve ("auto": module docstring)."""
    small = n <= AUTO_MAX_N
    host = backend == "numpy"
    plans = (DEFAULT_PLAN_REPEATS if small else 0) if plan_repeats == "auto" else int(plan_repeats)
    names = (DEFAULT_METHODS if small else "") if methods == "auto" else methods
    if tamaas_steps == "auto":
        k = steps if small else min(steps, TAMAAS_AUTO_STEPS)
    else:
        k = min(steps, int(tamaas_steps))
    return {
        "plan_repeats": plans if host else 0,
        "methods": [m for m in names.split(",") if m] if host else [],
        "tamaas_steps": k if host else 0,
        "tracemalloc": host and n <= TRACEMALLOC_MAX_N,
        "measure_pair": host and (small or plans > 0),
    }


def _backend_option(backend: str) -> dict:
    """Keyword option selecting ``backend`` in ``solve_contact`` (none for the default numpy)."""
    if backend == "numpy":
        return {}
    from roughcontact.solver import SolverSettings

    fields = {f.name for f in dataclasses.fields(SolverSettings)}
    name = next((k for k in ("backend", "array_backend") if k in fields), "backend")
    return {name: backend}


# --------------------------------------------------------------------------- worker: timing helpers
def _rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _batch(n: int) -> int:
    """Calls per timed batch of an ``n x n`` FFT pair (about 0.1-0.3 s a batch, at least 3)."""
    return max(3, int(2e8 / (n * n * np.log2(n * n))))


def _repeat(fn):
    def batch(k: int) -> None:
        for _ in range(k):
            fn()
    return batch


def _best_of_batches(candidates: dict, batch: int, repeats: int = 5, clock=time.perf_counter) -> dict:
    """Best seconds per call of each candidate (``fn(k)`` runs ``k`` calls), candidates in turn."""
    for fn in candidates.values():
        fn(1)
    times: dict[str, list[float]] = {k: [] for k in candidates}
    for _ in range(repeats):
        for key, fn in candidates.items():
            t = clock()
            fn(batch)
            times[key].append((clock() - t) / batch)
    return {k: min(v) for k, v in times.items()}


@contextlib.contextmanager
def _planner(flags: tuple[str, ...] | None = None, backend: str | None = None):
    """Make the solver's cached FFTs use FFTW ``flags`` / ``backend`` inside the block."""
    from roughcontact.core import fft as _fft

    saved_flags, saved_env = _fft.PLANNER_FLAGS, os.environ.get("ROUGHCONTACT_FFT")
    _fft._cached_fft.cache_clear()
    if flags is not None:
        _fft.PLANNER_FLAGS = flags
    if backend is not None:
        os.environ["ROUGHCONTACT_FFT"] = backend
    try:
        yield
    finally:
        _fft.PLANNER_FLAGS = saved_flags
        if saved_env is None:
            os.environ.pop("ROUGHCONTACT_FFT", None)
        else:
            os.environ["ROUGHCONTACT_FFT"] = saved_env
        _fft._cached_fft.cache_clear()


def _time_fft_pairs(n: int, measure: bool = True, repeats: int = 5) -> dict:
    """Best wall seconds per float64 pair: solver's plan (ESTIMATE), MEASURE (if ``measure``), numpy.

    Also the seconds it takes to make the ESTIMATE and the MEASURE plan pair.
    """
    from roughcontact.core.fft import RealFFT2, get_fft

    a = np.random.default_rng(1).standard_normal((n, n))
    fft = get_fft((n, n))  # the solver's cached plan, made by generate_surface
    if fft.backend != "pyfftw":
        raise RuntimeError(f"pyFFTW is not the default backend here ({fft.backend}): nothing to compare")
    t = time.perf_counter()
    RealFFT2((n, n), backend="pyfftw")
    t_plan_estimate = time.perf_counter() - t
    pairs = {"estimate": _repeat(lambda: fft.backward(fft.forward(a))),
             "numpy": _repeat(lambda: np.fft.irfft2(np.fft.rfft2(a), s=a.shape))}
    t_plan_measure = None
    if measure:
        with _planner(flags=("FFTW_MEASURE",)):
            t = time.perf_counter()
            measured = RealFFT2((n, n), backend="pyfftw")
            t_plan_measure = time.perf_counter() - t
        pairs["measure"] = _repeat(lambda: measured.backward(measured.forward(a)))
    best = _best_of_batches(pairs, _batch(n), repeats)
    return {"fft_pair_estimate": best["estimate"], "fft_pair_measure": best.get("measure"),
            "fft_pair_numpy": best["numpy"], "fft_plan_time_estimate": t_plan_estimate,
            "fft_plan_time_measure": t_plan_measure}


def _time_f32_pairs(n: int, repeats: int = 5) -> dict:
    """Best CPU seconds per float32 pair with the solver's cached plan: "raw" and "copies".

    Raw: ``_fwd.execute(); _bwd.execute()``, the backward plan reading the forward's output
    (``update_arrays``: the same plan on other buffers, put back after each batch), so that
    the data stay finite (module docstring, item 3).
    """
    from roughcontact.core.fft import get_fft

    fft = get_fft((n, n), dtype=np.float32)
    a = np.random.default_rng(1).standard_normal((n, n)).astype(np.float32)
    candidates = {"copies": _repeat(lambda: fft.backward(fft.forward(a)))}
    if fft.backend == "pyfftw":
        fft._real[...] = a
        fwd, bwd = fft._fwd, fft._bwd

        def raw(k: int) -> None:
            bwd.update_arrays(fft._spec, fft._real_out)
            try:
                for _ in range(k):
                    fwd.execute()
                    bwd.execute()
            finally:
                bwd.update_arrays(fft._spec_in, fft._real_out)

        candidates["raw"] = raw
        candidates["in place"] = _in_place_pairs(n, a)
    best = _best_of_batches(candidates, _batch(n), repeats, clock=time.process_time)
    return {"raw": best.get("raw"), "copies": best["copies"], "in place": best.get("in place")}


def _in_place_pairs(n: int, a: np.ndarray):
    """``fn(k)``: ``k`` float32 pairs on the solver's own product plans (in place, unnormalised).

    The solver's inner loop runs :class:`roughcontact.core.backend.SpectralProduct`'s in-place
    plans; their ``execute()`` alone is a floor for "pair-eq/iter" (with "raw"). A pair multiplies
    the data by ``n^2``, so the input starts at ``2^-100 a`` and is put back every 8 pairs (one
    4-byte copy per node every 8 pairs, inside the timing: ~1 % of a pair at N = 1024).
    """
    from roughcontact.core.backend import SpectralProduct, get_backend

    plan = SpectralProduct(get_backend(), (n, n), np.float32)._plan
    scaled = np.ldexp(a, -100)

    def run(k: int) -> None:
        while k > 0:
            plan.input[...] = scaled
            for _ in range(min(8, k)):
                plan.fwd.execute()
                plan.bwd.execute()
            k -= 8
    return run


def _time_cupy_pair(cp, n: int, repeats: int = 5) -> float:
    """Best seconds per float32 ``irfft2(rfft2(a))`` on the GPU, by CUDA events."""
    a = cp.random.standard_normal((n, n), dtype=cp.float32)
    batch = 50
    cp.fft.irfft2(cp.fft.rfft2(a), s=a.shape)
    start, end = cp.cuda.Event(), cp.cuda.Event()
    best = float("inf")
    for _ in range(repeats):
        start.record()
        for _ in range(batch):
            cp.fft.irfft2(cp.fft.rfft2(a), s=a.shape)
        end.record()
        end.synchronize()
        best = min(best, cp.cuda.get_elapsed_time(start, end) / 1e3 / batch)
    return best


# --------------------------------------------------------------------------- worker: solves
@contextlib.contextmanager
def _count_pairs():
    """Count the solver's FFT pairs (double and single precision) inside the block.

    Every ``Workspace.apply_*`` method is one product (one FFT pair), names with ``32`` single
    precision; so is a ``SpectralProduct`` called whole, and its ``forward`` (a forward transform) and
    ``backward`` (an inverse) are half a pair each, single precision where the product's dtype is
    float32 (the float32 iteration's products, :mod:`roughcontact.solver.compressed`). Only the
    outermost call counts, should one product call another.
    """
    from roughcontact.core.backend import SpectralProduct
    from roughcontact.solver.workspace import Workspace

    counts = {"double": 0.0, "single": 0.0}
    depth = [0]
    wrapped = [(Workspace, k, 1.0) for k, v in vars(Workspace).items() if k.startswith("apply_") and callable(v)]
    wrapped += [(SpectralProduct, "__call__", 1.0), (SpectralProduct, "forward", 0.5),
                (SpectralProduct, "backward", 0.5)]
    saved = [(cls, name, getattr(cls, name)) for cls, name, _ in wrapped]

    def kind_of(obj, name):
        if isinstance(obj, SpectralProduct):
            return "single" if obj.dtype == np.float32 else "double"
        return "single" if "32" in name else "double"

    def wrap(original, name, weight):
        def counting(self, *args, **kwargs):
            if depth[0] == 0:
                counts[kind_of(self, name)] += weight
            depth[0] += 1
            try:
                return original(self, *args, **kwargs)
            finally:
                depth[0] -= 1
        return counting

    for cls, name, weight in wrapped:
        setattr(cls, name, wrap(getattr(cls, name), name, weight))
    try:
        yield counts
    finally:
        for cls, name, fn in saved:
            setattr(cls, name, fn)


def _warm_up(h, loads, tol, backend: str) -> float:
    """CPU seconds of the process' one-off solver set-up, paid before the timing (item 1)."""
    from roughcontact.solver import SolverSettings, solve_contact

    c0 = time.process_time()
    SolverSettings().checked(h.shape)  # builds the unit registry, as a process' first solve does
    if backend != "numpy":
        solve_contact(h, loads[:1], tol=tol, **_backend_option(backend))
    return time.process_time() - c0


def _main_solve(h, loads, tol, backend: str) -> dict:
    """The timed solve: times, per-step CPU marks, iterations, A/A0 and counted FFT pairs."""
    from roughcontact.solver import solve_contact

    marks: list[float] = []
    with _count_pairs() as counts:
        w0, c0 = time.perf_counter(), time.process_time()
        ds = solve_contact(h, loads, tol=tol, progress=lambda *_: marks.append(time.process_time()),
                           **_backend_option(backend))
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    iters = ds["iterations"].values
    total = max(1, int(iters.sum()))
    pairs = counts["double"] + counts["single"]
    return {
        "wall": wall,
        "cpu": cpu,
        "step_cpu_cum": [m - c0 for m in marks],
        "area": ds["area_fraction"].values.tolist(),
        "step_time": ds["wall_time"].values.tolist(),
        "iterations": iters.tolist(),
        "converged": bool(ds["converged"].values.all()),
        "time_per_iter": float(ds["wall_time"].values.sum() / total),
        "cpu_per_iter": cpu / total,
        "wall_per_iter": wall / total,
        "pairs_double": counts["double"],
        "pairs_single": counts["single"],
        "fft_pairs_per_iter": pairs / total if pairs else None,
        "fft_backend": ds.attrs.get("fft_backend"),
        "elastic_method": ds.attrs.get("elastic_method"),
    }


def _traced_peak_mb(h, loads, tol) -> float:
    """Peak of the numpy allocations (MiB) of a second solve under tracemalloc."""
    from roughcontact.solver import solve_contact

    tracemalloc.start()
    try:
        solve_contact(h, loads, tol=tol)
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


#: Plans compared end to end: keyword arguments of ``_planner``.
PLAN_SOLVES = {
    "ESTIMATE": {},
    "MEASURE": {"flags": ("FFTW_MEASURE",)},
    "numpy": {"backend": "numpy"},
}


def _plan_solves(h, loads, tol, repeats: int) -> dict:
    """Best wall/CPU seconds of the solve with each plan of ``PLAN_SOLVES``, interleaved.

    Plans are made before the timing (as ``generate_surface`` does for the main solve);
    the candidates run in turn ``repeats`` times so that load drift hits all alike.
    """
    from roughcontact.core.fft import get_fft
    from roughcontact.solver import solve_contact

    out = {k: {"wall": [], "cpu": []} for k in PLAN_SOLVES}
    for _ in range(repeats):
        for key, planner in PLAN_SOLVES.items():
            with _planner(**planner):
                get_fft(h.shape)
                w0, c0 = time.perf_counter(), time.process_time()
                ds = solve_contact(h, loads, tol=tol)
                out[key]["wall"].append(time.perf_counter() - w0)
                out[key]["cpu"].append(time.process_time() - c0)
                out[key]["iterations"] = int(ds["iterations"].values.sum())
                out[key]["backend"] = ds.attrs["fft_backend"]
    for rec in out.values():
        rec["wall_all"], rec["cpu_all"] = rec["wall"], rec["cpu"]
        rec["wall"], rec["cpu"] = min(rec["wall"]), min(rec["cpu"])
    return out


def _method_solves(h, loads, tol, methods, repeats: int) -> dict:
    """Iterations, FFT pairs and best wall/CPU seconds of each elastic method, interleaved."""
    from roughcontact import solver as _solver

    out = {m: {"wall": [], "cpu": []} for m in methods}
    for _ in range(max(1, repeats)):
        for m in methods:
            with _count_pairs() as counts:
                w0, c0 = time.perf_counter(), time.process_time()
                ds = _solver.solve_contact(h, loads, tol=tol, method=m)
                cpu, wall = time.process_time() - c0, time.perf_counter() - w0
            rec = out[m]
            rec["wall"].append(wall)
            rec["cpu"].append(cpu)
            rec["iterations"] = ds["iterations"].values.tolist()
            rec["pairs_double"], rec["pairs_single"] = counts["double"], counts["single"]
            rec["converged"] = bool(ds["converged"].values.all())
            rec["area"] = ds["area_fraction"].values.tolist()
            rec["max_residual"] = float(ds["residual"].values.max())
    return out


# --------------------------------------------------------------------------- worker: Tamaas
@contextlib.contextmanager
def capture_fds():
    """Capture C-level stdout/stderr (Tamaas logs from C++) into a string buffer."""
    buf = io.StringIO()
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with tempfile.TemporaryFile(mode="w+") as tmp:
        os.dup2(tmp.fileno(), 1)
        os.dup2(tmp.fileno(), 2)
        try:
            yield buf
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            tmp.seek(0)
            buf.write(tmp.read())


_ITER_LINE = re.compile(r"^\s*(\d+)\s+[-+0-9.eE]+\s+[-+0-9.eE]+\s*$")


def run_tamaas(h, loads, tol):
    """Tamaas' PolonskyKeerRey over ``loads``: times, iterations, A/A0; None if not importable."""
    try:
        import tamaas as tm
    except ImportError:
        return None
    n = h.shape[0]
    tm.set_log_level(tm.LogLevel.info)  # the final iteration count is only logged
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [1.0, 1.0], [n, n])
    model.E = 1.0
    model.nu = 0.0
    solver = tm.PolonskyKeerRey(model, h, tol, tm.PolonskyKeerRey.pressure,
                                tm.PolonskyKeerRey.pressure)
    area, times, iters = [], [], []
    w0, c0 = time.perf_counter(), time.process_time()
    for p0 in loads:
        t = time.perf_counter()
        with capture_fds() as log:
            solver.solve(float(p0))
        times.append(time.perf_counter() - t)
        lines = [m.group(1) for m in map(_ITER_LINE.match, log.getvalue().splitlines()) if m]
        iters.append(int(lines[-1]) if lines else -1)
        area.append(np.count_nonzero(np.asarray(model.traction) > 0) / n**2)
    return {
        "version": getattr(tm, "__version__", "?"),
        "wall": time.perf_counter() - w0,
        "cpu": time.process_time() - c0,
        "area": area,
        "step_time": times,
        "iterations": iters,
    }


# --------------------------------------------------------------------------- worker
def _host_measures(h, loads, tol, extras: dict, method_repeats: int) -> dict:
    """Everything after the main solve on the numpy backend (items 3-7)."""
    n = h.shape[0]
    k = extras["tamaas_steps"]
    tamaas = run_tamaas(h, loads[:k], tol) if k else None
    note = "" if tamaas else ("not installed" if k else "not run")
    return {
        **_time_fft_pairs(n, measure=extras["measure_pair"]),
        "fft_pair_f32": _time_f32_pairs(n),
        "tracemalloc_peak_mb": _traced_peak_mb(h, loads, tol) if extras["tracemalloc"] else None,
        "plan_solves": (_plan_solves(h, loads, tol, extras["plan_repeats"])
                        if extras["plan_repeats"] > 0 else None),
        "method_solves": (_method_solves(h, loads, tol, extras["methods"], method_repeats)
                          if extras["methods"] else None),
        "tamaas": tamaas,
        "tamaas_note": note,
    }


def _gpu_measures(n: int) -> dict:
    """GPU pool size right after the solve, the GPU's name, the float32 pair on the GPU."""
    import cupy as cp

    pool = cp.get_default_memory_pool().total_bytes() / 2**20
    name = cp.cuda.runtime.getDeviceProperties(0)["name"]
    return {
        "gpu_pool_mb": pool,
        "gpu_name": name.decode() if isinstance(name, bytes) else str(name),
        "cupy_version": cp.__version__,
        "fft_pair_f32": {"raw": _time_cupy_pair(cp, n), "copies": None},
        "tamaas": None,
        "tamaas_note": "cupy backend",
    }


def worker(n: int, steps: int, p_max: float, tol: float, tamaas: bool = True, plan_repeats="auto",
           methods="auto", method_repeats: int = 2, tamaas_steps="auto", backend: str = "numpy") -> dict:
    """All measurements at grid size ``n`` (module docstring), as a JSON-ready dict."""
    from roughcontact.surfaces.synthetic import generate_surface

    extras = resolve_extras(n, steps, plan_repeats, methods, tamaas_steps if tamaas else 0, backend)
    rss_start = _rss_mb()
    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(p_max / steps, p_max, steps)
    setup_cpu = _warm_up(h, loads, tol, backend)
    rss_before = _rss_mb()
    ours = _main_solve(h, loads, tol, backend)
    rss_peak = _rss_mb()  # "imports + surface + solve", before anything else allocates
    res = {"n": n, "steps": steps, "p_max": p_max, "tol": tol, "backend": backend, "extras": extras,
           "setup_cpu": setup_cpu, "ours": ours, "rss_start_mb": rss_start,
           "rss_before_solve_mb": rss_before, "rss_peak_mb": rss_peak}
    if backend == "cupy":
        res.update(_gpu_measures(n))
    else:
        res.update(_host_measures(h, loads, tol, extras, method_repeats))
    if not tamaas:
        res["tamaas_note"] = "--no-tamaas"
    return res


# --------------------------------------------------------------------------- driver: header
def _cpu_model() -> str:
    from roughcontact.core.fft import machine_key

    return machine_key() or "unknown CPU"


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def _git_describe() -> str:
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        out = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=here, capture_output=True,
                             text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip() if out.returncode == 0 else ""


def machine_info() -> dict:
    """Date (UTC), CPU, load and versions at the start of the run."""
    return {
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu": f"{_cpu_model()} ({os.cpu_count()} logical CPUs)",
        "load_start": os.getloadavg(),
        "versions": {"roughcontact": _version("roughcontact"), "numpy": _version("numpy"),
                     "pyFFTW": _version("pyFFTW"), "Tamaas": _version("tamaas")},
        "git": _git_describe(),
    }


def header(info: dict, args, results=(), load_end=None) -> str:
    """One line: date, CPU (and GPU), load averages, versions, the case."""
    load = "load avg 1/5/15 min: start " + " ".join(f"{x:.2f}" for x in info["load_start"])
    if load_end is not None:
        load += ", end " + " ".join(f"{x:.2f}" for x in load_end)
    v = info["versions"]
    git = f" (git {info['git']})" if info["git"] else ""
    versions = f"roughcontact {v['roughcontact']}{git}, numpy {v['numpy']}, pyFFTW {v['pyFFTW']}, " \
               f"Tamaas {v['Tamaas']}"
    gpu = next((r for r in results if r.get("gpu_name")), None)
    machine = info["cpu"] + (f", GPU {gpu['gpu_name']} (CuPy {gpu['cupy_version']})" if gpu else "")
    case = (f"backend {args.backend}, tol {args.tol:g}, {args.steps} steps to p0 = {args.p_max:g} E*, "
            "OMP_NUM_THREADS=1")
    return f"# {info['date']} | {machine} | {load} | {versions} | {case}"


# --------------------------------------------------------------------------- driver: tables
def _per_step_table(r: dict) -> str:
    ours, tm = r["ours"], r.get("tamaas")
    head = "| step | p0 | A/A0 ours | iters ours | t ours [s] | CPU ours [s] |"
    sep = "|---:|---:|---:|---:|---:|---:|"
    if tm:
        head += " A/A0 Tamaas | iters Tamaas | t Tamaas [s] |"
        sep += "---:|---:|---:|"
    rows = [head, sep]
    loads = np.linspace(r["p_max"] / r["steps"], r["p_max"], r["steps"])
    cum = [0.0, *ours["step_cpu_cum"]]
    for k in range(r["steps"]):
        step_cpu = f"{cum[k + 1] - cum[k]:.4f}" if k + 1 < len(cum) else ""
        row = (f"| {k + 1} | {loads[k]:.3e} | {ours['area'][k]:.6f} | {ours['iterations'][k]} | "
               f"{ours['step_time'][k]:.4f} | {step_cpu} |")
        if tm and k < len(tm["area"]):
            row += f" {tm['area'][k]:.6f} | {tm['iterations'][k]} | {tm['step_time'][k]:.4f} |"
        elif tm:
            row += " | | |"
        rows.append(row)
    return "\n".join(rows)


def _ms(seconds) -> str:
    return "n/a" if seconds is None else f"{1e3 * seconds:.2f}"


def _tamaas_comparison(r: dict) -> dict | None:
    """Tamaas against our solve over the steps Tamaas ran (first K of the loads)."""
    ours, tm = r["ours"], r.get("tamaas")
    if not tm:
        return None
    k = len(tm["area"])
    full = k == r["steps"]
    ours_cpu = ours["cpu"] if full else ours["step_cpu_cum"][k - 1]
    ours_wall = ours["wall"] if full else float(sum(ours["step_time"][:k]))
    a, b = np.array(ours["area"][:k]), np.array(tm["area"])
    return {"k": k, "full": full, "cpu_ratio": tm["cpu"] / ours_cpu, "wall_ratio": tm["wall"] / ours_wall,
            "max_rel": float(np.max(np.abs(a - b) / b))}


def _tamaas_cells(r: dict) -> dict:
    cmp = _tamaas_comparison(r)
    if cmp is None:
        note = f"n/a ({r.get('tamaas_note') or 'not run'})"
        return {"Tamaas CPU [s]": note, "Tamaas steps": "", "CPU ratio Tamaas/ours": "", "max rel dA/A0": ""}
    suffix = "" if cmp["full"] else f" (first {cmp['k']} steps)"
    return {"Tamaas CPU [s]": f"{r['tamaas']['cpu']:.2f}",
            "Tamaas steps": f"{cmp['k']} of {r['steps']}",
            "CPU ratio Tamaas/ours": f"{cmp['cpu_ratio']:.1f}{suffix}",
            "max rel dA/A0": f"{cmp['max_rel']:.1e}"}


def _floor_pair(f32: dict):
    """The float32 pair that "pair-eq/iter" divides by: the cheaper of "raw" and "in place"."""
    pairs = [t for t in (f32["raw"], f32.get("in place")) if t]
    return min(pairs) if pairs else None


def compact_row(r: dict) -> dict:
    """The summary row of one N (module docstring's columns)."""
    ours = r["ours"]
    gpu = r["backend"] == "cupy"
    pair = _floor_pair(r["fft_pair_f32"])
    per_iter = ours["wall_per_iter"] if gpu else ours["cpu_per_iter"]
    per_pair = ours["fft_pairs_per_iter"]
    row = {
        "N": r["n"],
        "steps": r["steps"],
        "iterations": int(sum(ours["iterations"])),
        "converged": "yes" if ours["converged"] else "NO",
        "CPU [s]": f"{ours['cpu']:.2f}",
        "wall [s]": f"{ours['wall']:.2f}",
        "ms/iter": f"{1e3 * ours['time_per_iter']:.2f}",
        "f32 pair [ms] (raw)": _ms(pair),
        "pair-eq/iter": "n/a" if pair is None else f"{per_iter / pair:.2f}",
        "FFT pairs/iter": "n/a" if per_pair is None else f"{per_pair:.2f}",
        "peak RSS [MB]": f"{r['rss_peak_mb']:.0f}",
    }
    if gpu:
        row["peak GPU pool [MB]"] = f"{r['gpu_pool_mb']:.0f}"
    row.update(_tamaas_cells(r))
    return row


def _ours_cells(r: dict) -> dict:
    ours, f32 = r["ours"], r["fft_pair_f32"]
    est, meas = r.get("fft_pair_estimate"), r.get("fft_pair_measure")
    return {
        "N": r["n"], "steps": r["steps"], "backend": r["backend"],
        "ours wall [s]": f"{ours['wall']:.2f}", "ours CPU [s]": f"{ours['cpu']:.2f}",
        "setup CPU [s]": f"{r['setup_cpu']:.2f}",
        "ours iters": int(sum(ours["iterations"])),
        "converged": "yes" if ours["converged"] else "NO",
        "ms/iter": f"{1e3 * ours['time_per_iter']:.2f}",
        "CPU ms/iter": f"{1e3 * ours['cpu_per_iter']:.2f}",
        "f32 pair raw [ms]": _ms(f32["raw"]),
        "f32 pair in place [ms]": _ms(f32.get("in place")),
        "f32 pair + copies [ms]": _ms(f32["copies"]),
        "FFT pair ESTIMATE [ms]": _ms(est),
        "FFT pair MEASURE [ms]": _ms(meas),
        "FFT pair numpy [ms]": _ms(r.get("fft_pair_numpy")),
        "ESTIMATE/MEASURE pair": f"{est / meas:.2f}" if est and meas else "n/a",
        "plan ESTIMATE [ms]": _ms(r.get("fft_plan_time_estimate")),
        "plan MEASURE [ms]": _ms(r.get("fft_plan_time_measure")),
        "iter/pair ESTIMATE": f"{ours['time_per_iter'] / est:.2f}" if est else "n/a",
        "iter/pair numpy": (f"{ours['time_per_iter'] / r['fft_pair_numpy']:.2f}"
                            if r.get("fft_pair_numpy") else "n/a"),
        "FFT pairs f64 + f32": f"{ours['pairs_double']} + {ours['pairs_single']}",
        "peak RSS [MB]": f"{r['rss_peak_mb']:.0f}",
        "RSS imports [MB]": f"{r['rss_start_mb']:.0f}",
        "RSS after surface [MB]": f"{r['rss_before_solve_mb']:.0f}",
        "tracemalloc peak [MB]": ("n/a" if r.get("tracemalloc_peak_mb") is None
                                  else f"{r['tracemalloc_peak_mb']:.0f}"),
    }


def _method_cells(ms: dict) -> dict:
    row = {}
    for label, rec in ms.items():
        row[f"{label}: iters"] = int(sum(rec["iterations"]))
        row[f"{label}: FFT pairs f64 + f32"] = f"{rec['pairs_double']} + {rec['pairs_single']}"
        row[f"{label}: best CPU [s]"] = f"{min(rec['cpu']):.2f}"
        row[f"{label}: best wall [s]"] = f"{min(rec['wall']):.2f}"
        row[f"{label}: converged"] = "yes" if rec["converged"] else "NO"
        if "pk" in ms and label != "pk":
            a, b = np.array(rec["area"]), np.array(ms["pk"]["area"])
            row[f"{label}: CPU / pk CPU"] = f"{min(rec['cpu']) / min(ms['pk']['cpu']):.2f}"
            row[f"{label}: max rel dA/A0 vs pk"] = f"{float(np.max(np.abs(a - b) / b)):.1e}"
    return row


def _wide_tamaas_cells(r: dict) -> dict:
    tm, cmp = r.get("tamaas"), _tamaas_comparison(r)
    if cmp is None:
        return {"Tamaas wall [s]": f"n/a ({r.get('tamaas_note') or 'not run'})"}
    suffix = "" if cmp["full"] else f" (first {cmp['k']} steps)"
    return {
        "Tamaas steps": f"{cmp['k']} of {r['steps']}",
        "Tamaas wall [s]": f"{tm['wall']:.2f}",
        "Tamaas CPU [s]": f"{tm['cpu']:.2f}",
        "Tamaas iters": int(sum(tm["iterations"])),
        "speed-up wall": f"{cmp['wall_ratio']:.1f}{suffix}",
        "speed-up CPU": f"{cmp['cpu_ratio']:.1f}{suffix}",
        "max rel dA/A0": f"{cmp['max_rel']:.1e}",
    }


def wide_row(r: dict) -> dict:
    """The detail row of one N: every measurement."""
    row = _ours_cells(r)
    if r["backend"] == "cupy":
        row["peak GPU pool [MB]"] = f"{r['gpu_pool_mb']:.0f}"
    row.update(_method_cells(r.get("method_solves") or {}))
    for label, rec in (r.get("plan_solves") or {}).items():
        row[f"best wall {label} [s]"] = f"{rec['wall']:.2f}"
        row[f"best CPU {label} [s]"] = f"{rec['cpu']:.2f}"
        row[f"iters {label}"] = rec["iterations"]
    row.update(_wide_tamaas_cells(r))
    return row


def _scaling(results: list[dict]) -> str:
    """Exponent ``a`` of ``iterations ~ N**a`` (least squares in log-log) per method."""
    if len(results) < 2 or not all(r.get("method_solves") for r in results):
        return ""
    ns = np.array([r["n"] for r in results], dtype=float)
    lines = ["| method | " + " | ".join(f"iters N={int(n)}" for n in ns) + " | exponent a |",
             "|---|" + "---:|" * (len(ns) + 1)]
    for m in results[0]["method_solves"]:
        its = np.array([sum(r["method_solves"][m]["iterations"]) for r in results], dtype=float)
        a = float(np.polyfit(np.log(ns), np.log(its), 1)[0])
        lines.append(f"| {m} | " + " | ".join(str(int(i)) for i in its) + f" | {a:.2f} |")
    return "\n".join(lines)


def _markdown(rows: list[dict]) -> str:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    lines = ["| " + " | ".join(keys) + " |", "|" + "---:|" * len(keys)]
    for r in rows:
        lines.append("| " + " | ".join(str(r.get(k, "")) for k in keys) + " |")
    return "\n".join(lines)


def _write_out(path: str, head: str, compact: list[dict], wide: list[dict], scaling: str) -> None:
    """``--out``: header, summary, then details (markdown, or two CSV blocks for ``.csv``)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="") as f:
        if not path.endswith(".csv"):
            parts = [head, "## Summary", _markdown(compact), "## Details", _markdown(wide)]
            f.write("\n\n".join(parts + ([scaling] if scaling else [])) + "\n")
            return
        f.write(head + "\n")
        for i, rows in enumerate((compact, wide)):
            f.write("\n" if i else "")
            w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
            w.writeheader()
            w.writerows(rows)


# --------------------------------------------------------------------------- driver
def _auto_int(text: str):
    if text == "auto":
        return text
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto' or an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected 'auto' or an integer >= 0, got {text!r}")
    return value


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, nargs="+", default=[512, 1024], help="grid sizes (default: 512 1024)")
    ap.add_argument("--steps", type=int, default=30, help="load steps (default 30)")
    ap.add_argument("--p-max", type=float, default=0.005, help="largest mean pressure / E* (default 0.005)")
    ap.add_argument("--tol", type=float, default=1e-8,
                    help="tolerance of both solvers (default 1e-8; both criteria are sum(p g)/(sum(p) h_rms)-type)")
    ap.add_argument("--backend", choices=("numpy", "cupy"), default="numpy",
                    help="the solver's array backend (default numpy; cupy skips Tamaas and the comparisons)")
    ap.add_argument("--no-tamaas", action="store_true", help="run our solver only")
    ap.add_argument("--tamaas-steps", type=_auto_int, default="auto",
                    help=f"run Tamaas on the first K loads (default auto: all for N <= {AUTO_MAX_N}, "
                         f"the first {TAMAAS_AUTO_STEPS} above)")
    ap.add_argument("--plan-repeats", type=_auto_int, default="auto",
                    help="extra solves with FFTW_ESTIMATE, FFTW_MEASURE and numpy.fft, each this many "
                         f"times, interleaved; the best is reported (default auto: {DEFAULT_PLAN_REPEATS} "
                         f"for N <= {AUTO_MAX_N}, 0 above; 0 skips them)")
    ap.add_argument("--methods", default="auto",
                    help=f"comma-separated elastic methods to compare (default auto: {DEFAULT_METHODS} "
                         f"for N <= {AUTO_MAX_N}, none above; '' skips the comparison)")
    ap.add_argument("--method-repeats", type=int, default=2,
                    help="interleaved rounds of the method comparison (default 2; best reported)")
    ap.add_argument("--out", help="write header, summary and details here (.csv -> CSV, else markdown)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    return ap


def _run_worker(n: int, args) -> dict | None:
    """One N in a fresh subprocess (one thread); its result, or None after printing its error."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--n", str(n),
           "--steps", str(args.steps), "--p-max", str(args.p_max), "--tol", str(args.tol),
           "--backend", args.backend, "--tamaas-steps", str(args.tamaas_steps),
           "--plan-repeats", str(args.plan_repeats), "--methods", args.methods,
           "--method-repeats", str(args.method_repeats)]
    if args.no_tamaas:
        cmd.append("--no-tamaas")
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        return None
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith(RESULT_TAG))
    return json.loads(line[len(RESULT_TAG):])


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.worker:
        res = worker(args.n[0], args.steps, args.p_max, args.tol, not args.no_tamaas, args.plan_repeats,
                     args.methods, args.method_repeats, args.tamaas_steps, args.backend)
        print(RESULT_TAG + json.dumps(res))
        return 0

    info = machine_info()
    print(header(info, args), flush=True)
    results = []
    for n in args.n:
        print(f"== N = {n}: running in a subprocess ...", flush=True)
        r = _run_worker(n, args)
        if r is None:
            return 1
        results.append(r)
        print(_per_step_table(r) + "\n")
    wide = [wide_row(r) for r in results]
    print("== details (every measurement; the summary follows)")
    print(_markdown(wide))
    scaling = _scaling(results)
    if scaling:
        print(f"\n== iteration scaling, iterations ~ N**a over N = {', '.join(str(r['n']) for r in results)}")
        print(scaling)
    head = header(info, args, results, os.getloadavg())
    compact = [compact_row(r) for r in results]
    if args.out:
        _write_out(args.out, head, compact, wide, scaling)
        print(f"\nheader, summary and details written to {args.out}")
    print("\n== summary")
    print(head)
    print(_markdown(compact))
    return 0


if __name__ == "__main__":
    sys.exit(main())
