#!/usr/bin/env python
"""Benchmark of roughcontact.solver against Tamaas' PolonskyKeerRey on the paper case.

For each grid size N (one fresh subprocess per N, so that peak memory and FFT
plans of one size do not leak into the next) it:

1. generates the paper surface (k_l = 16, k_s = 32, H = 0.8, rms slope 0.1,
   seed 0) with :func:`roughcontact.surfaces.synthetic.generate_surface`;
2. times one rfft2 + irfft2 pair with the solver's own pyFFTW plan
   (:func:`roughcontact.core.fft.get_fft`, planned with ``FFTW_ESTIMATE``), with the
   same pair planned with ``FFTW_MEASURE`` (what earlier versions used; timing-based,
   so not reproducible bit for bit between processes) and with ``numpy.fft`` (best
   of batches, i.e. hot caches: inside the solver the same pair runs between other
   passes over memory and costs more), and the planning time of both plans;
3. runs :func:`roughcontact.solver.solve_contact` over ``--steps`` loads
   ``p_max/steps ... p_max`` (wall and CPU time, per-step time and iterations)
   and records the process' peak RSS (``ru_maxrss``: imports + surface +
   solve) right after it, before anything else runs; then times the FFT pair
   (item 2) and repeats the solve under ``tracemalloc`` for the peak of the
   solver's own numpy allocations; then (``--plan-repeats``, default 2) solves
   again with ``FFTW_ESTIMATE`` plans, ``FFTW_MEASURE`` plans and the ``numpy.fft``
   backend in turn, several times, for the end-to-end cost of the plan choice;
4. runs Tamaas' ``PolonskyKeerRey`` (pressure primal, pressure constraint) on
   the identical array in the same process (``OMP_NUM_THREADS=1``), with the
   same tolerance, and compares A/A0 step by step;
5. (``--methods``) solves with each elastic iteration of
   :data:`roughcontact.solver.ELASTIC_METHODS` in turn (``"pk"``, the plain
   Polonsky-Keer CG, is the reference): iterations, FFT pairs in double and in
   single precision, CPU and wall time, ``--method-repeats`` interleaved rounds
   (best reported), and the largest A/A0 difference from ``"pk"``. With two or
   more ``--n`` the summary ends with the fitted iteration-scaling exponent
   ``a`` of ``iterations ~ N**a`` per method.

Prints per-step tables and a summary markdown table; ``--out`` also writes the
summary (``.csv`` gives CSV, anything else markdown).

Usage::

    python benchmarks/bench_solver.py                 # N = 512 1024
    python benchmarks/bench_solver.py --n 256 --out benchmarks/out/bench.md
"""

from __future__ import annotations

import argparse
import contextlib
import csv
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


# --------------------------------------------------------------------------- worker
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


def _time_fft_pairs(n: int, repeats: int = 5) -> dict:
    """Best per-pair seconds of rfft2+irfft2: solver's plan (ESTIMATE), MEASURE, numpy.

    Also the seconds it takes to make the ESTIMATE and the MEASURE plan pair.
    """
    from roughcontact.core.fft import RealFFT2, get_fft

    rng = np.random.default_rng(1)
    a = rng.standard_normal((n, n))
    fft = get_fft((n, n))  # the solver's cached plan, made by generate_surface
    if fft.backend != "pyfftw":
        raise RuntimeError(f"pyFFTW is not the default backend here ({fft.backend}): nothing to compare")
    t = time.perf_counter()
    RealFFT2((n, n), backend="pyfftw")
    t_plan_estimate = time.perf_counter() - t
    with _planner(flags=("FFTW_MEASURE",)):
        t = time.perf_counter()
        measured = RealFFT2((n, n), backend="pyfftw")
        t_plan_measure = time.perf_counter() - t
    batch = max(3, int(2e8 / (n * n * np.log2(n * n))))
    pairs = {
        "estimate": lambda: fft.backward(fft.forward(a)),
        "measure": lambda: measured.backward(measured.forward(a)),
        "numpy": lambda: np.fft.irfft2(np.fft.rfft2(a), s=a.shape),
    }
    # Round robin over the candidates, so that a change of machine load hits all alike.
    times: dict[str, list[float]] = {k: [] for k in pairs}
    for fn in pairs.values():
        fn()
    for _ in range(repeats):
        for key, fn in pairs.items():
            t = time.perf_counter()
            for _ in range(batch):
                fn()
            times[key].append((time.perf_counter() - t) / batch)
    return {**{k: min(v) for k, v in times.items()},
            "plan_estimate": t_plan_estimate, "plan_measure": t_plan_measure}


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


@contextlib.contextmanager
def _capture_fds():
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


def _run_tamaas(h, loads, tol):
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
        with _capture_fds() as log:
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


@contextlib.contextmanager
def _count_pairs():
    """Count the solver's FFT pairs (double and single precision) inside the block."""
    from roughcontact.solver.workspace import Workspace

    counts = {"double": 0, "single": 0}
    ws = Workspace
    names = {"apply_k": "double", "apply_m": "double", "apply_k32": "single", "apply_m32": "single"}
    saved = {name: getattr(ws, name) for name in names}

    def wrap(name, kind):
        original = saved[name]

        def counting(self, field):
            counts[kind] += 1
            return original(self, field)
        return counting

    for name, kind in names.items():
        setattr(ws, name, wrap(name, kind))
    try:
        yield counts
    finally:
        for name, fn in saved.items():
            setattr(ws, name, fn)


def _method_solves(h, loads, tol, methods, repeats: int) -> dict:
    """Iterations, FFT pairs and best wall/CPU seconds of each elastic method, interleaved."""
    from roughcontact import solver as _solver

    saved = _solver.ELASTIC_METHOD
    out = {m: {"wall": [], "cpu": []} for m in methods}
    try:
        for _ in range(max(1, repeats)):
            for m in methods:
                _solver.ELASTIC_METHOD = m
                with _count_pairs() as counts:
                    w0, c0 = time.perf_counter(), time.process_time()
                    ds = _solver.solve_contact(h, loads, tol=tol)
                    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
                rec = out[m]
                rec["wall"].append(wall)
                rec["cpu"].append(cpu)
                rec["iterations"] = ds["iterations"].values.tolist()
                rec["pairs_double"], rec["pairs_single"] = counts["double"], counts["single"]
                rec["converged"] = bool(ds["converged"].values.all())
                rec["area"] = ds["area_fraction"].values.tolist()
                rec["max_residual"] = float(ds["residual"].values.max())
    finally:
        _solver.ELASTIC_METHOD = saved
    return out


def worker(n: int, steps: int, p_max: float, tol: float, tamaas: bool, plan_repeats: int = 2,
           methods: tuple[str, ...] = (), method_repeats: int = 2) -> dict:
    from roughcontact.core.fft import PLANNER_FLAGS
    from roughcontact.solver import ELASTIC_METHOD, solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    rss_start = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(p_max / steps, p_max, steps)
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

    # The FFT plans were made (and cached) by generate_surface: the timed solve
    # is the solver alone, as in a workflow that generates then solves.
    w0, c0 = time.perf_counter(), time.process_time()
    ds = solve_contact(h, loads, tol=tol)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    # Peak RSS of "imports + surface + solve", before anything else allocates.
    rss_after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

    pairs = _time_fft_pairs(n)

    # Second, instrumented solve: numpy allocation peak and the number of FFT
    # pairs (operator and preconditioner products, double and single) per iteration.
    tracemalloc.start()
    try:
        with _count_pairs() as counts:
            solve_contact(h, loads, tol=tol)
        traced_peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    calls = [counts["double"] + counts["single"]]

    iters = ds["iterations"].values
    res = {
        "n": n,
        "steps": steps,
        "p_max": p_max,
        "tol": tol,
        "fft_backend": ds.attrs["fft_backend"],
        "fft_planner": list(PLANNER_FLAGS),
        "elastic_method": ELASTIC_METHOD,
        "fft_pair_estimate": pairs["estimate"],
        "fft_pair_measure": pairs["measure"],
        "fft_pair_numpy": pairs["numpy"],
        "fft_plan_time_estimate": pairs["plan_estimate"],
        "fft_plan_time_measure": pairs["plan_measure"],
        "ours": {
            "wall": wall,
            "cpu": cpu,
            "area": ds["area_fraction"].values.tolist(),
            "step_time": ds["wall_time"].values.tolist(),
            "iterations": iters.tolist(),
            "converged": bool(ds["converged"].values.all()),
            "time_per_iter": float(ds["wall_time"].values.sum() / max(1, iters.sum())),
            "fft_pairs_per_iter": calls[0] / max(1, int(iters.sum())),
        },
        "rss_start_mb": rss_start / 1024,
        "rss_before_solve_mb": rss_before / 1024,
        "rss_peak_mb": rss_after / 1024,
        "tracemalloc_peak_mb": traced_peak / 2**20,
        "plan_solves": _plan_solves(h, loads, tol, plan_repeats) if plan_repeats > 0 else None,
        "method_solves": _method_solves(h, loads, tol, methods, method_repeats) if methods else None,
        "tamaas": _run_tamaas(h, loads, tol) if tamaas else None,
    }
    return res


# --------------------------------------------------------------------------- driver
def _per_step_table(r: dict) -> str:
    ours, tm = r["ours"], r["tamaas"]
    head = "| step | p0 | A/A0 ours | iters ours | t ours [s] |"
    sep = "|---:|---:|---:|---:|---:|"
    if tm:
        head += " A/A0 Tamaas | iters Tamaas | t Tamaas [s] |"
        sep += "---:|---:|---:|"
    rows = [head, sep]
    loads = np.linspace(r["p_max"] / r["steps"], r["p_max"], r["steps"])
    for k in range(r["steps"]):
        row = (f"| {k + 1} | {loads[k]:.3e} | {ours['area'][k]:.6f} | {ours['iterations'][k]} | "
               f"{ours['step_time'][k]:.4f} |")
        if tm:
            row += f" {tm['area'][k]:.6f} | {tm['iterations'][k]} | {tm['step_time'][k]:.4f} |"
        rows.append(row)
    return "\n".join(rows)


def _summary_rows(results: list[dict]) -> list[dict]:
    rows = []
    for r in results:
        ours, tm = r["ours"], r["tamaas"]
        row = {
            "N": r["n"],
            "steps": r["steps"],
            "ours wall [s]": f"{ours['wall']:.2f}",
            "ours CPU [s]": f"{ours['cpu']:.2f}",
            "ours iters": int(sum(ours["iterations"])),
            "converged": "yes" if ours["converged"] else "NO",
            "ms/iter": f"{1e3 * ours['time_per_iter']:.2f}",
            "FFT pair ESTIMATE [ms]": f"{1e3 * r['fft_pair_estimate']:.2f}",
            "FFT pair MEASURE [ms]": f"{1e3 * r['fft_pair_measure']:.2f}",
            "FFT pair numpy [ms]": f"{1e3 * r['fft_pair_numpy']:.2f}",
            "ESTIMATE/MEASURE pair": f"{r['fft_pair_estimate'] / r['fft_pair_measure']:.2f}",
            "plan ESTIMATE [ms]": f"{1e3 * r['fft_plan_time_estimate']:.1f}",
            "plan MEASURE [ms]": f"{1e3 * r['fft_plan_time_measure']:.0f}",
            "iter/pair ESTIMATE": f"{ours['time_per_iter'] / r['fft_pair_estimate']:.2f}",
            "iter/pair numpy": f"{ours['time_per_iter'] / r['fft_pair_numpy']:.2f}",
            "FFT pairs/iter": f"{ours['fft_pairs_per_iter']:.2f}",
            "peak RSS [MB]": f"{r['rss_peak_mb']:.0f}",
            "RSS imports [MB]": f"{r['rss_start_mb']:.0f}",
            "RSS after surface [MB]": f"{r['rss_before_solve_mb']:.0f}",
            "tracemalloc peak [MB]": f"{r['tracemalloc_peak_mb']:.0f}",
        }
        ms = r.get("method_solves") or {}
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
        for label, rec in (r.get("plan_solves") or {}).items():
            row[f"best wall {label} [s]"] = f"{rec['wall']:.2f}"
            row[f"best CPU {label} [s]"] = f"{rec['cpu']:.2f}"
            row[f"iters {label}"] = rec["iterations"]
        if tm:
            a = np.array(ours["area"])
            b = np.array(tm["area"])
            row.update({
                "Tamaas wall [s]": f"{tm['wall']:.2f}",
                "Tamaas CPU [s]": f"{tm['cpu']:.2f}",
                "Tamaas iters": int(sum(tm["iterations"])),
                "speed-up wall": f"{tm['wall'] / ours['wall']:.1f}",
                "speed-up CPU": f"{tm['cpu'] / ours['cpu']:.1f}",
                "max rel dA/A0": f"{float(np.max(np.abs(a - b) / b)):.1e}",
            })
        else:
            row.update({"Tamaas wall [s]": "n/a (not installed)"})
        rows.append(row)
    return rows


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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, nargs="+", default=[512, 1024], help="grid sizes (default: 512 1024)")
    ap.add_argument("--steps", type=int, default=30, help="load steps (default 30)")
    ap.add_argument("--p-max", type=float, default=0.005, help="largest mean pressure / E* (default 0.005)")
    ap.add_argument("--tol", type=float, default=1e-8,
                    help="tolerance of both solvers (default 1e-8; both criteria are sum(p g)/(sum(p) h_rms)-type)")
    ap.add_argument("--no-tamaas", action="store_true", help="run our solver only")
    ap.add_argument("--plan-repeats", type=int, default=2,
                    help="extra solves with FFTW_ESTIMATE, FFTW_MEASURE and numpy.fft, each this many "
                         "times, interleaved; the best is reported (default 2; 0 skips them)")
    ap.add_argument("--methods", default="pk,pk-fourier,pk-fourier-f32",
                    help="comma-separated elastic methods to compare (default: all of "
                         "roughcontact.solver.ELASTIC_METHODS; '' skips the comparison)")
    ap.add_argument("--method-repeats", type=int, default=2,
                    help="interleaved rounds of the method comparison (default 2; best reported)")
    ap.add_argument("--out", help="write the summary table here (.csv -> CSV, else markdown)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker:
        methods = tuple(m for m in args.methods.split(",") if m)
        res = worker(args.n[0], args.steps, args.p_max, args.tol, not args.no_tamaas, args.plan_repeats,
                     methods, args.method_repeats)
        print("@@RESULT@@" + json.dumps(res))
        return 0

    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    results = []
    for n in args.n:
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--n", str(n),
               "--steps", str(args.steps), "--p-max", str(args.p_max), "--tol", str(args.tol)]
        if args.no_tamaas:
            cmd.append("--no-tamaas")
        cmd += ["--plan-repeats", str(args.plan_repeats), "--methods", args.methods,
                "--method-repeats", str(args.method_repeats)]
        print(f"== N = {n}: running in a subprocess ...", flush=True)
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if proc.returncode != 0:
            sys.stderr.write(proc.stdout + proc.stderr)
            return proc.returncode
        line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("@@RESULT@@"))
        r = json.loads(line[len("@@RESULT@@"):])
        results.append(r)
        if r["tamaas"] is None and not args.no_tamaas:
            print("Tamaas is not importable: our solver only.")
        print(_per_step_table(r))
        print()

    rows = _summary_rows(results)
    table = _markdown(rows)
    print(f"== summary (tol = {args.tol:g}, {args.steps:d} steps to p0 = {args.p_max:g} E*)")
    print(table)
    scaling = _scaling(results)
    if scaling:
        print(f"\n== iteration scaling, iterations ~ N**a over N = {', '.join(str(r['n']) for r in results)}")
        print(scaling)
        table += "\n\n" + scaling
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w", newline="") as f:
            if args.out.endswith(".csv"):
                keys = list(dict.fromkeys(k for r in rows for k in r))
                w = csv.DictWriter(f, fieldnames=keys)
                w.writeheader()
                w.writerows(rows)
            else:
                f.write(table + "\n")
        print(f"summary written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
