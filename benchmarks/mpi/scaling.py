"""Strong and weak scaling and the memory per rank of the MPI solver (issue 50).

``mpiexec -n R python benchmarks/mpi/scaling.py SURFACE.npy STEPS [--tile T]`` solves the surface
(a ``.npy`` file, memory-mapped: each rank reads its rows only) under ``STEPS`` equal loads up to
``P_MAX`` and prints one line on rank 0: grid, ranks, iterations, wall time, time per iteration and
the peak resident memory of each rank (``ru_maxrss``) and how much of it is the other ranks' parts of its machine's
shared-memory windows, which it maps where it writes its blocks (:attr:`~roughcontact.solver.mpi.slabs.FftwSlabFFT.
peer_parts`, read from ``/proc/self/pagemap`` before the windows are freed; 0 where that is unreadable): the machine
holds those pages once, in their owner's count. ``--tile T`` stacks the surface ``T`` times
along x (a ``T L x L`` cell): the same contact problem repeated, so the iterations stay the same and
the work per rank is constant when ``T`` grows with ``R`` (weak scaling). ``--max-iter`` stops each
step early: every field is allocated in the first iterations, so a few give the peak memory.
``--measured-plans`` (one rank, ``T > 1``): the tiled grid's 2-D pair is not in the shipped wisdom (square grids
only), so FFTW would plan it by its heuristics; this measures it first (``FFTW_MEASURE``, both precisions, before the
timed solve) into a copy of the shipped wisdom that the process then plans with, so that one rank on the tiled grid
is timed with plans of the quality the square grid's have (the weak scaling's serial reference, benchmarks/README.md,
"The weak scaling's serial reference").
``python benchmarks/mpi/scaling.py --make N SURFACE.npy`` writes the surface (k_l = 4, k_s = N / 8,
H = 0.8, rms slope 0.1) first, in a process of its own; ``--single`` solves it without MPI
(:func:`~roughcontact.solver.solve_contact` and the batched solver with B = 1), for reference.
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np

P_MAX = 0.005


def make(n: int, path: str) -> None:
    from roughcontact.surfaces.synthetic import generate_surface

    np.save(path, generate_surface(n, 4, n // 8, 0.8, 0, rms_slope=0.1))


def mapped_bytes(parts) -> int:
    """Bytes of the address ranges ``parts`` (``(address, bytes)`` each) that this process maps: the pages whose
    ``/proc/self/pagemap`` entry has its present bit (63) set. 0 where the file cannot be read (not Linux)."""
    page = os.sysconf("SC_PAGE_SIZE")
    try:
        fh = open("/proc/self/pagemap", "rb")
    except OSError:
        return 0
    total = 0
    with fh:
        for address, nbytes in parts:
            first, last = address // page, (address + nbytes - 1) // page
            fh.seek(8 * first)
            entries = np.frombuffer(fh.read(8 * (last - first + 1)), dtype=np.uint64)
            total += int(np.count_nonzero(entries >> np.uint64(63))) * page
    return total


def measured_plans(shape, directory: str) -> None:
    """Plan ``shape``'s 2-D pairs on one rank with FFTW_MEASURE into a copy of the shipped wisdom in ``directory``,
    and make this process plan with that copy, ``shape`` counted as a grid it holds (module docstring)."""
    import shutil
    from pathlib import Path

    from roughcontact.core import fft
    from roughcontact.solver.mpi import slabs

    shape = nx, ny = tuple(int(s) for s in shape)
    if nx % ny:
        raise ValueError(f"measured_plans: {shape} is not a square tiled along x")
    shipped = fft.has_shipped_plans
    fft.has_shipped_plans = lambda s: tuple(int(v) for v in s) == shape or shipped(s)  # in place, as a square's
    copy = Path(directory) / "wisdom.json"
    shutil.copy(fft.WISDOM_FILE, copy)
    # the one-rank problems of the slab wisdom's own list (both precisions)
    fft.add_plans(slabs.slab_problems(sizes=(ny,), ranks=(1,), tiles=(nx // ny,)), copy,
                  {"benchmark": f"{shape} on one rank"})
    fft.WISDOM_FILE = copy
    fft.shipped_wisdom.cache_clear()


def run(path: str, steps: int, tile: int, max_iter: int | None, measured: bool = False) -> None:
    import tempfile

    from mpi4py import MPI

    from roughcontact.solver.mpi import rows_of, slabs, solve_contact_mpi

    peer = [0]
    close = slabs.FftwSlabFFT.close

    def close_counting(self):  # the other ranks' pages this one maps, counted before the windows are freed
        peer[0] = max(peer[0], mapped_bytes(self.peer_parts))
        close(self)

    slabs.FftwSlabFFT.close = close_counting

    comm = MPI.COMM_WORLD
    h = np.load(path, mmap_mode="r")
    n = h.shape[0]
    shape = (tile * n, n)
    x0, x1 = rows_of(shape, comm)
    rows = np.ascontiguousarray(np.take(h, np.arange(x0, x1) % n, axis=0))
    if measured:
        if comm.size != 1 or tile == 1:
            raise SystemExit("--measured-plans: one rank and --tile 2 or more (the square grids' plans are shipped)")
        tmp = tempfile.TemporaryDirectory()  # kept until run returns: the solve reads the copy when it plans
        measured_plans(shape, tmp.name)
    comm.Barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    ds = solve_contact_mpi(rows, shape, P_MAX * np.arange(1, steps + 1) / steps, comm=comm,
                           length=(float(tile), 1.0) if tile > 1 else 1.0,
                           **({} if max_iter is None else {"max_iter": max_iter}))
    wall = time.perf_counter() - t0
    cpu = comm.gather(time.process_time() - c0, root=0)  # each rank's CPU: its share of the work on a busy machine
    rss = comm.gather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20, root=0)  # GiB (ru_maxrss in KiB)
    peers = comm.gather(peer[0] / 2**30, root=0)
    if comm.rank == 0:
        its = int(ds.iterations.sum())
        print(f"grid {shape[0]}x{shape[1]} ranks {comm.size} steps {steps} iterations {its} "
              f"converged {int(ds.converged.sum())}/{steps} wall {wall:.1f} s per_iteration {1e3 * wall / its:.1f} ms "
              f"cpu_per_rank {' '.join(f'{c:.1f}' for c in cpu)} s "
              f"A/A0 {float(ds.area_fraction[-1]):.6f} peak_rss_GiB {' '.join(f'{r:.3f}' for r in rss)} "
              f"peer_window_GiB {' '.join(f'{r:.3f}' for r in peers)}", flush=True)


def single(path: str, steps: int) -> None:
    """The same problem without MPI: solve_contact (pyFFTW's in-place plans) and the batched solver (B = 1)."""
    from roughcontact.solver import solve_contact, solve_contact_batch

    h = np.load(path)
    loads = P_MAX * np.arange(1, steps + 1) / steps
    for name, fn in (("solve_contact", lambda: solve_contact(h, loads)),
                     ("solve_contact_batch", lambda: solve_contact_batch(h[None], loads))):
        t0, c0 = time.perf_counter(), time.process_time()
        ds = fn()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        its = int(ds.iterations.sum())
        print(f"grid {h.shape[0]}x{h.shape[1]} {name} steps {steps} iterations {its} wall {wall:.1f} s per_iteration "
              f"{1e3 * wall / its:.1f} ms cpu {cpu:.1f} s", flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--make", type=int, default=None)
    ap.add_argument("surface")
    ap.add_argument("steps", type=int, nargs="?", default=4)
    ap.add_argument("--tile", type=int, default=1)
    ap.add_argument("--single", action="store_true", help="the same problem by solve_contact and the batch, no MPI")
    ap.add_argument("--max-iter", type=int, default=None, help="iterations per step at most (memory runs)")
    ap.add_argument("--measured-plans", action="store_true",
                    help="one rank on a tiled grid: its 2-D pair measured first (module docstring)")
    a = ap.parse_args()
    if a.make:
        make(a.make, a.surface)
    elif a.single:
        single(a.surface, a.steps)
    else:
        run(a.surface, a.steps, a.tile, a.max_iter, a.measured_plans)
