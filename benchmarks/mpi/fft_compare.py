"""The two distributed FFTs of the MPI solver side by side: one forward + inverse pair per precision.

``mpiexec -n R python benchmarks/mpi/fft_compare.py N [N ...]`` prints, for each ``N`` and each
library of :data:`roughcontact.solver.mpi.slabs.FFT_LIBRARIES` that imports, the median wall time
of ``REPEATS`` pairs (every rank times the same pairs; rank 0 prints the slowest rank's median) in
float32 and float64 on an ``N x N`` grid split in ``R`` slabs (issue 50: "measure both and choose").
"""

from __future__ import annotations

import sys
import time

import numpy as np
from mpi4py import MPI

from roughcontact.solver.mpi.slabs import FFT_LIBRARIES, Slabs, make_fft

REPEATS = 15


def pair_time(fft, x) -> float:
    """Median seconds of one forward + inverse pair of ``x`` (after one untimed pair: plans, caches)."""
    fft.backward(fft.forward(x))
    times = []
    for _ in range(REPEATS):
        MPI.COMM_WORLD.Barrier()
        t0 = time.perf_counter()
        fft.backward(fft.forward(x))
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main(sizes) -> None:
    comm = MPI.COMM_WORLD
    for n in sizes:
        slabs = Slabs((n, n), comm.size, comm.rank)
        x = np.random.default_rng(comm.rank).standard_normal((1, *slabs.local_shape))
        for lib in FFT_LIBRARIES:
            try:
                fft = make_fft(lib, comm, slabs)
            except ValueError as exc:
                if comm.rank == 0:
                    print(f"N={n} ranks={comm.size} {lib}: unavailable ({exc})", flush=True)
                continue
            row = []
            for dtype in (np.float32, np.float64):
                t = comm.allreduce(pair_time(fft, x.astype(dtype)), op=MPI.MAX)
                row.append(f"{np.dtype(dtype).name} {1e3 * t:7.2f} ms")
            if comm.rank == 0:
                print(f"N={n} ranks={comm.size} {lib:10s} " + "  ".join(row), flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1024, 2048])
