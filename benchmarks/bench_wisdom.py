#!/usr/bin/env python
"""Two FFTW wisdom files side by side: the transform pairs and the paper case, interleaved.

The package plans every transform from its shipped wisdom (``roughcontact.core.fft``), so a new
wisdom file changes the speed of everything and the results only in the last bits. This compares
a candidate file with another (by default the shipped one), in one process and one thread:

- each transform pair the solver and the surfaces use (float32 / float64, in place / out of
  place) at each ``--n``, planned from each file's set for this processor, best of ``--rounds``
  interleaved batches of CPU time;
- the paper case (``k_l = 16, k_s = 32, H = 0.8``, 30 steps to p0/E* = 0.005, tol 1e-8) on one
  surface per ``--n`` (made with the ``--old`` file), solved in turn with each file's plans,
  ``--rounds`` times: CPU seconds, iterations, and whether A/A0 is equal at every step.

    python benchmarks/bench_wisdom.py --new FILE [--old FILE] [--n 512 1024] [--rounds 2]

Results of the FFTW_PATIENT wisdom (2026-11-27): docs/solver.md, "Plans measured with FFTW_PATIENT".
"""

from __future__ import annotations

import argparse
import json
import os
import resource
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

PAIRS = [(np.float32, True), (np.float32, False), (np.float64, True), (np.float64, False)]


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def use(path: Path) -> None:
    """Make the package plan from the wisdom file ``path`` from now on."""
    from roughcontact.core import fft

    fft.WISDOM_FILE = Path(path)
    fft.shipped_wisdom.cache_clear()
    fft._cached_fft.cache_clear()


def plan_pair(n: int, real, in_place: bool):
    """``(input, forward, backward)`` of the package's own ``n x n`` pair, planned from the current file.

    In place: the solver's product (:class:`roughcontact.core.backend.SpectralProduct`); out of
    place: :class:`roughcontact.core.fft.RealFFT2` (the surfaces' and the float64 paths' pair), its
    backward plan pointed at the forward's output so that one pair's data stay finite.
    """
    from roughcontact.core.backend import SpectralProduct, get_backend
    from roughcontact.core.fft import RealFFT2

    if in_place:
        plan = SpectralProduct(get_backend(), (n, n), real, in_place=True)._plan
        return plan.input, plan.fwd, plan.bwd
    pair = RealFFT2((n, n), backend="pyfftw", dtype=real)  # a fresh pair, not the cached one
    pair._bwd.update_arrays(pair._spec, pair._real_out)
    return pair._real, pair._fwd, pair._bwd


def time_pairs(files: dict, n: int, rounds: int) -> list[dict]:
    """Best CPU seconds of one pair with each file's plans, per kind of pair."""
    reps = max(5, int(2e8 / (n * n * np.log2(n))))
    rows = []
    for real, in_place in PAIRS:
        plans = {}
        for key, path in files.items():
            use(path)
            plans[key] = plan_pair(n, real, in_place)
        best = dict.fromkeys(files, np.inf)
        for _ in range(rounds):
            for key, (a, fwd, bwd) in plans.items():
                for _ in range(reps):
                    a[...] = 0.1
                    t = cpu()
                    fwd()
                    bwd()
                    best[key] = min(best[key], cpu() - t)
        rows.append({"n": n, "pair": f"{np.dtype(real).name} {'in place' if in_place else 'out of place'}", **best})
    return rows


def time_solves(files: dict, n: int, rounds: int) -> dict:
    """The paper case solved with each file's plans in turn; best CPU, iterations, equal A/A0."""
    from roughcontact.solver import solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    use(files["old"])
    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.005 / 30, 0.005, 30)
    out = {key: {"cpu": np.inf} for key in files}
    for _ in range(rounds):
        for key, path in files.items():
            use(path)
            t = cpu()
            ds = solve_contact(h.copy(), loads, tol=1e-8)
            rec = out[key]
            rec["cpu"] = min(rec["cpu"], cpu() - t)
            rec["iterations"] = int(ds["iterations"].values.sum())
            rec["area"] = ds["area_fraction"].values.copy()
            rec["converged"] = bool(ds["converged"].values.all())
    return out


def main(argv=None) -> int:
    from roughcontact.core import fft

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--new", type=Path, required=True, help="candidate wisdom file")
    ap.add_argument("--old", type=Path, default=fft.WISDOM_FILE, help="wisdom to compare with (default: shipped)")
    ap.add_argument("--n", type=int, nargs="+", default=[512, 1024])
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--no-solve", action="store_true", help="time the pairs only")
    args = ap.parse_args(argv)
    files = {"old": args.old, "new": args.new}
    for key, path in files.items():
        sets = json.loads(path.read_text())["machines"]
        print(f"{key}: {path} ({'own set' if fft.machine_key() in sets else 'default set'} for {fft.machine_key()!r})")
    print("\n| N | pair | old [ms] | new [ms] | new / old |\n|---:|---|---:|---:|---:|")
    for n in args.n:
        for row in time_pairs(files, n, args.rounds):
            # a pair below the clock's resolution reads 0 s (tiny N on a fast machine): no ratio, not a crash
            ratio = f"{row['new'] / row['old']:.3f}" if row["old"] > 0 else "n/a (below the clock's resolution)"
            print(f"| {n} | {row['pair']} | {1e3 * row['old']:.3f} | {1e3 * row['new']:.3f} | {ratio} |", flush=True)
    if args.no_solve:
        return 0
    print("\n| N | CPU old [s] | CPU new [s] | new / old | iterations old, new | A/A0 equal | converged |\n"
          "|---:|---:|---:|---:|---|---|---|")
    for n in args.n:
        r = time_solves(files, n, args.rounds)
        o, w = r["old"], r["new"]
        ratio = w["cpu"] / o["cpu"] if o["cpu"] > 0 else float("nan")  # 0 s: below the clock's resolution
        print(f"| {n} | {o['cpu']:.2f} | {w['cpu']:.2f} | {ratio:.3f} | {o['iterations']}, "
              f"{w['iterations']} | {np.array_equal(o['area'], w['area'])} | {o['converged'] and w['converged']} |",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
