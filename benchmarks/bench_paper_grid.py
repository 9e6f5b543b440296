#!/usr/bin/env python
"""Projected cost of the paper's contact grid from a stratified sample of its cases.

The paper grid (config/config.yaml, ``contact``) is k_l in {1, 2, 8, 16} x k_s in {32, 64, 128,
256, 512} x five H x 12 seeds = 1200 cases at N = 1024, 30 load steps to p0/E* = 0.005, tol 1e-8.
The sample takes every (k_l, k_s) pair with ``--hurst`` (default 0.2, 0.52, 0.84) and seed 0:
60 cases, each standing for 20 of the grid. Per case it generates the surface as the pipeline does
(:func:`roughcontact.surfaces.synthetic.generate_surface`, not timed) and solves it with
:func:`roughcontact.solver.solve_contact` on ``--backend`` (numpy: one thread; cupy: the GPU), timing
the solve (CPU and wall; on the GPU the solve returns host arrays, so it has synchronised).

Prints one row per case and the projection: the sample's solve time x 1200 / sample size, in CPU
hours (numpy) or wall minutes (cupy). The pipeline adds surface generation and I/O per case
(measured by ``python -m roughcontact.pipeline.runcost``; ~1.3 s CPU per surface at N = 1024).

With ``--batch B`` (issue 48) the cases are solved ``B`` at a time by
:func:`roughcontact.solver.batch.solve_contact_batch` (several values: one run each, on the same
surfaces, generated once). Cases are sorted by (k_s, k_l, H, seed) first, so that a batch holds
cases of similar iteration counts (a batch steps at the pace of its slowest case). Per batch it
prints the wall time, the rounds (iterations of the slowest case plus waits for host checks),
the iterations, how many cases converged at every step, the GPU memory in use, and the largest
|A/A0 - reference| over the batch's cases and steps: against ``--reference`` (a ``--csv`` of an
earlier run) and/or against single solves of the batch's first ``--compare K`` cases on
``--compare-backend`` (numpy: the CPU path). ``--whole`` runs the 1200 cases (5 H x 12 seeds)
instead of the sample; ``--max-batches`` stops each B after that many batches and projects.

Usage::

    python benchmarks/bench_paper_grid.py                       # 60 cases, numpy, one thread
    python benchmarks/bench_paper_grid.py --backend cupy        # on a CUDA GPU
    python benchmarks/bench_paper_grid.py --n 256 --limit 4     # a smoke run
    python benchmarks/bench_paper_grid.py --backend cupy --batch 16 64 128        # batched sample
    python benchmarks/bench_paper_grid.py --backend cupy --batch 128 --whole      # the whole grid
    python benchmarks/bench_paper_grid.py --backend cupy --batch 3 --n 512 --limit 3 --compare 3
"""

from __future__ import annotations

import argparse
import csv
import itertools
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

K_L = (1, 2, 8, 16)
K_S = (32, 64, 128, 256, 512)
HURST = (0.2, 0.36, 0.52, 0.68, 0.84)
SEEDS = 12
GRID_CASES = 1200


def sample(hursts, limit=None) -> list[tuple[int, int, float]]:
    """The stratified sample: every (k_l, k_s) pair with each H of ``hursts``, seed 0."""
    cases = list(itertools.product(K_L, K_S, hursts))
    return cases[:limit] if limit else cases


def solve_case(n: int, k_l: int, k_s: int, hurst: float, backend: str, steps: int) -> dict:
    """Generate one surface (untimed) and solve it; times, iterations and the final A/A0."""
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(n, k_l, k_s, hurst, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / steps, 0.005, steps)
    w0, c0 = time.perf_counter(), time.process_time()
    ds = solve_contact(h, loads, tol=1e-8, array_backend=backend)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return {"k_l": k_l, "k_s": k_s, "H": hurst, "wall": wall, "cpu": cpu,
            "iterations": int(ds["iterations"].values.sum()), "converged": bool(ds["converged"].values.all()),
            "area": float(ds["area_fraction"].values[-1])}


def whole_grid(limit=None) -> list[tuple[int, int, float, int]]:
    """The paper grid's 1200 cases ``(k_l, k_s, H, seed)``."""
    cases = list(itertools.product(K_L, K_S, HURST, range(SEEDS)))
    return cases[:limit] if limit else cases


def _surface(n: int, case) -> np.ndarray:
    from roughcontact.surfaces.synthetic import generate_surface

    k_l, k_s, hurst, seed = case
    k_s = min(k_s, n // 2)  # below N = 1024 (smoke runs) the finest wavelengths are capped at Nyquist
    return generate_surface(n, min(k_l, k_s), k_s, hurst, seed, rms_slope=0.1)


def _gpu_memory(backend: str) -> str:
    """Bytes CuPy's memory pool holds now and at most (this process), for the batch rows."""
    if backend != "cupy":
        return "-"
    import cupy

    pool = cupy.get_default_memory_pool()
    return f"{pool.total_bytes() / 2**30:.1f} GiB"


def _read_reference(path: str) -> dict:
    """``(k_l, k_s, H, seed) -> A/A0 per step`` from a ``--csv`` file."""
    ref: dict = {}
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            key = (int(row["k_l"]), int(row["k_s"]), float(row["H"]), int(row["seed"]))
            ref.setdefault(key, {})[int(row["step"])] = float(row["area_fraction"])
    return {k: np.array([v[s] for s in sorted(v)]) for k, v in ref.items()}


def _projection(size: int, wall: float, case_rounds: int, case_its: int, by_ks: dict) -> str:
    """The grid's wall time in batches of ``size`` cases of one k_s, from a sample's measurements.

    The sample's batches mix k_s (the sample has 12 cases of each), so each steps at the pace of a
    slower case than the grid's would: in the grid, sorted by k_s, a batch holds cases of one k_s
    (240 each). Measured: the wall time per case-round (a round of one case of a batch) and the rounds
    per iteration of a batch's slowest case (waits for host checks); assumed: a grid batch of one k_s
    takes the rounds of the sample's slowest case of that k_s (each sample case stands for 20).
    """
    per_case_round = wall / max(case_rounds, 1)
    overhead = case_rounds / max(case_its, 1)
    per_ks = GRID_CASES // len(K_S)
    total = 0.0
    for its in by_ks.values():
        n_batches = -(-per_ks // size)
        total += n_batches * min(size, per_ks) * its * overhead * per_case_round
    total *= len(K_S) / max(len(by_ks), 1)  # a sample without some k_s: the others stand for them
    return (f"in batches of one k_s: {total / 60:.2f} min ({1e6 * per_case_round:.0f} us a case-round, "
            f"{overhead:.2f} rounds an iteration of the slowest case)")


def _batches(cases, size: int, interleave: bool) -> list:
    """``cases`` (sorted by k_s) cut into batches of ``size``; ``interleave``: the batches in turns over
    k_s groups (slow and fast alternate), so that a run cut short by a time limit has seen each kind."""
    batches = [cases[i:i + size] for i in range(0, len(cases), size)]
    if not interleave:
        return batches
    groups: dict = {}
    for b in batches:
        groups.setdefault(b[0][1], []).append(b)
    ordered = []
    while any(groups.values()):
        for key in sorted(groups):
            if groups[key]:
                ordered.append(groups[key].pop(0))
    return ordered


class _Surfaces:
    """The cases' surfaces, generated by a pool of processes, the next batch's while the current one
    is solved; kept for the sample (every batch size reuses them).

    Processes, not threads: ``generate_surface`` shares its FFT buffers per grid size within a
    process, so two threads generating at once corrupt each other's surfaces (measured: a smoke
    run's iterations changed). ``forkserver`` workers never inherit this process's CUDA context.
    """

    def __init__(self, n: int, keep: bool, workers: int):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        self.n, self.keep = n, keep
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("forkserver"))
        self.cache: dict = {}

    def request(self, chunk) -> None:
        for c in chunk:
            if c not in self.cache:
                self.cache[c] = self.pool.submit(_surface, self.n, c)

    def get(self, chunk) -> np.ndarray:
        self.request(chunk)
        h = np.stack([self.cache[c].result() for c in chunk])
        if not self.keep:
            for c in chunk:
                del self.cache[c]
        return h


def run_batched(args, cases) -> int:
    """Solve ``cases`` in batches of each ``args.batch``; one table per batch size and a summary."""
    cases = sorted(cases, key=lambda c: (c[1], c[0], c[2], c[3]))  # similar iteration counts together
    reference = _read_reference(args.reference) if args.reference else {}
    surfaces = _Surfaces(args.n, keep=not args.whole, workers=max(1, min(8, (os.cpu_count() or 2) - 1)))
    state = {"rows": [], "summary": [], "compared": []}
    print(f"# {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load {os.getloadavg()}, backend "
          f"{args.backend}, N = {args.n}, {args.steps} steps, {len(cases)} cases "
          f"({'the whole grid' if args.whole else 'the sample'}), batches {args.batch}, "
          f"check_every {args.check_every or 'default'}", flush=True)
    for size in args.batch:
        try:
            _run_size(args, size, cases, surfaces, reference, state)
        except Exception as exc:  # noqa: BLE001 (an out-of-memory batch size must not stop the others)
            line = f"B = {size}: FAILED ({type(exc).__name__}: {str(exc)[:200]})"
            state["summary"].append(line)
            print(f"\n{line}", flush=True)
            _free_gpu(args.backend)
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            wr = csv.writer(fh)
            wr.writerow(["k_l", "k_s", "H", "seed", "step", "area_fraction", "iterations", "converged"])
            wr.writerows(state["rows"])
    compared = state["compared"]
    if compared:
        d, di, ok = max(c[0] for c in compared), max(c[1] for c in compared), all(c[2] for c in compared)
        state["summary"].append(
            f"batched {args.backend} against single {args.compare_backend} solves of {len(compared)} cases x "
            f"{args.steps} steps: max |dA/A0| {d:.3g} ({d * args.n ** 2:.0f} nodes of {args.n}^2), iterations "
            f"within {di} per step, single solves converged: {ok}")
    tag = f"N = {args.n}, {args.backend}, check_every {args.check_every or 'default'}"
    print("\n# summary\n" + "\n".join(f"SUMMARY {args.label} ({tag}): {line}" for line in state["summary"]))
    return 0


def _free_gpu(backend: str) -> None:
    if backend == "cupy":
        import cupy

        cupy.get_default_memory_pool().free_all_blocks()


def _run_size(args, size: int, cases, surfaces: _Surfaces, reference: dict, state: dict) -> None:
    """One batch size: its warm-up, a row per batch, a running total, its summary line."""
    from roughcontact.solver import solve_contact
    from roughcontact.solver.batch import solve_contact_batch

    loads = np.linspace(0.005 / args.steps, 0.005, args.steps)
    batches = _batches(cases, size, interleave=args.whole)
    if args.max_batches:
        batches = batches[:args.max_batches]
    surfaces.request([c for b in batches[:2] for c in b])
    # warm-up outside the timing: units, transforms' plans and kernels for this batch shape
    # (one surface repeated: the batch's shape is what the plans depend on)
    solve_contact_batch(np.repeat(surfaces.get(batches[0][:1]), len(batches[0]), axis=0), loads[:2],
                        tol=1e-8, array_backend=args.backend, check_every=args.check_every)
    print(f"\n## B = {size}\n")
    print("| batch | cases | k_s | wall [s] | rounds | iterations (sum / max case) | converged cases | "
          "unconverged steps | max abs dA/A0 | GPU pool | cases so far, wall so far |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|", flush=True)
    t_all, solved, its_all, conv_all, worst_all = 0.0, 0, 0, 0, 0.0
    case_rounds, case_its, by_ks = 0, 0, {}  # for the projection onto batches of one k_s
    for i, chunk in enumerate(batches):
        h = surfaces.get(chunk)
        if i + 1 < len(batches):
            surfaces.request(batches[i + 1])  # generated while this batch is solved
        w0 = time.perf_counter()
        ds = solve_contact_batch(h, loads, tol=1e-8, array_backend=args.backend, check_every=args.check_every)
        wall = time.perf_counter() - w0
        area = ds["area_fraction"].values
        its = ds["iterations"].values.sum(axis=1)
        conv = ds["converged"].values.all(axis=1)
        worst = [np.max(np.abs(area[b] - reference[c])) for b, c in enumerate(chunk) if c in reference]
        for b, c in enumerate(chunk[:args.compare] if i < (args.compare_batches or len(batches)) else []):
            single = solve_contact(h[b], loads, tol=1e-8, array_backend=args.compare_backend)
            d = np.abs(area[b] - single["area_fraction"].values)
            di = np.abs(ds["iterations"].values[b] - single["iterations"].values)
            worst.append(float(d.max()))
            state["compared"].append((float(d.max()), int(di.max()), bool(single["converged"].values.all())))
            print(f"  compare case {c}: max |dA/A0| {d.max():.3g} ({d.max() * args.n ** 2:.0f} nodes), "
                  f"iterations batch {int(its[b])} / single {int(single['iterations'].values.sum())} "
                  f"(max per step {int(di.max())}), single converged {bool(single['converged'].values.all())}",
                  flush=True)
        if args.csv:
            for b, c in enumerate(chunk):
                for k in range(args.steps):
                    state["rows"].append((*c, k + 1, area[b, k], int(ds["iterations"].values[b, k]),
                                          bool(ds["converged"].values[b, k])))
        t_all += wall
        solved += len(chunk)
        its_all += int(its.sum())
        conv_all += int(conv.sum())
        case_rounds += int(ds["rounds"].values.sum()) * len(chunk)
        case_its += int(its.max()) * len(chunk)
        for b, c in enumerate(chunk):
            by_ks[c[1]] = max(by_ks.get(c[1], 0), int(its[b]))
        if worst:
            worst_all = max(worst_all, max(worst))
        ks = sorted({c[1] for c in chunk})
        dmax = f"{max(worst):.2g}" if worst else "-"
        print(f"| {i + 1} | {len(chunk)} | {ks[0]}-{ks[-1]} | {wall:.2f} | {int(ds['rounds'].values.sum())} | "
              f"{int(its.sum())} / {int(its.max())} | {int(conv.sum())}/{len(chunk)} | "
              f"{int((~ds['converged'].values).sum())} | {dmax} | {_gpu_memory(args.backend)} | "
              f"{solved}, {t_all:.1f} s |", flush=True)
        del ds, h
    scale = GRID_CASES / solved
    line = (f"B = {size}: {solved} cases in {t_all:.1f} s ({t_all / solved:.3f} s a case, "
            f"{its_all} iterations, {conv_all}/{solved} converged at every step"
            f"{f', max |dA/A0| {worst_all:.2g}' if worst_all else ''}); grid of {GRID_CASES}: "
            f"{t_all * scale / 60:.2f} min{' (measured)' if solved == GRID_CASES else ' (projected)'}")
    if solved < GRID_CASES and not args.whole:
        line += f"; {_projection(size, t_all, case_rounds, case_its, by_ks)}"
    state["summary"].append(line)
    print(f"\n{line}", flush=True)
    _free_gpu(args.backend)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1024, help="grid points per side (default 1024)")
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--hurst", type=float, nargs="+", default=[0.2, 0.52, 0.84])
    ap.add_argument("--backend", choices=("numpy", "cupy"), default="numpy")
    ap.add_argument("--limit", type=int, help="only the first this many cases (smoke runs)")
    ap.add_argument("--batch", type=int, nargs="+", help="solve in batches of B cases (several: one run each)")
    ap.add_argument("--whole", action="store_true", help="with --batch: the whole 1200-case grid, not the sample")
    ap.add_argument("--max-batches", type=int, help="with --batch: only this many batches per B (projected)")
    ap.add_argument("--check-every", type=int, help="with --batch: rounds between host checks (default: backend's)")
    ap.add_argument("--reference", help="with --batch: CSV of an earlier run (--csv) to compare A/A0 with")
    ap.add_argument("--csv", help="with --batch: write every case's A/A0, iterations and flag per step here")
    ap.add_argument("--compare", type=int, default=0,
                    help="with --batch: solve the first K cases of each batch singly and compare (default 0)")
    ap.add_argument("--compare-batches", type=int, default=1, help="with --compare: in this many batches (default 1)")
    ap.add_argument("--label", default="grid", help="names this run's SUMMARY lines (default grid)")
    ap.add_argument("--compare-backend", choices=("numpy", "cupy"), default="numpy",
                    help="with --compare: the single solves' backend (default numpy: the CPU path)")
    args = ap.parse_args(argv)
    if args.batch:
        if min(args.batch) < 1:
            ap.error("--batch takes sizes >= 1")
        cases = whole_grid(args.limit) if args.whole else [(*c, 0) for c in sample(args.hurst, args.limit)]
        return run_batched(args, cases)
    cases = sample(args.hurst, args.limit)
    # units registry, FFT plans (cupy: kernels) made outside the timing
    solve_case(args.n, 16, 32, 0.8, args.backend, 2)
    print(f"# {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load {os.getloadavg()}, "
          f"backend {args.backend}, N = {args.n}, {len(cases)} cases")
    print("| k_l | k_s | H | iterations | converged | A/A0 | CPU [s] | wall [s] |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    rows = []
    for k_l, k_s, hurst in cases:
        r = solve_case(args.n, k_l, k_s, hurst, args.backend, args.steps)
        rows.append(r)
        print(f"| {k_l} | {k_s} | {hurst} | {r['iterations']} | {'yes' if r['converged'] else 'NO'} | "
              f"{r['area']:.4f} | {r['cpu']:.2f} | {r['wall']:.2f} |", flush=True)
    scale = GRID_CASES / len(rows)
    cpu, wall = sum(r["cpu"] for r in rows), sum(r["wall"] for r in rows)
    print(f"\nsample: {len(rows)} cases, {sum(r['iterations'] for r in rows)} iterations, "
          f"{sum(not r['converged'] for r in rows)} with an unconverged step; CPU {cpu:.1f} s, wall {wall:.1f} s")
    print(f"projected grid of {GRID_CASES} cases (solves only): {cpu * scale / 3600:.2f} CPU-hours, "
          f"{wall * scale / 60:.1f} wall minutes; load at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
