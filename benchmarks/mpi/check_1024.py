"""Issue 50's check at 1024²: ``mpiexec -n R python benchmarks/mpi/check_1024.py SURFACE.npy OUT.json``.

Solves the surface of ``scaling.py --make 1024`` under 8 equal steps to p0/E* = 0.005 over R ranks and
writes A/A0, the mean gap, the iterations and the wall time per step (rank 0); ``--single OUT.json``
without ``mpiexec`` writes the same for :func:`~roughcontact.solver.solve_contact`, to compare.
"""

import json
import sys

import numpy as np

LOADS = 0.005 * np.arange(1, 9) / 8


def record(ds, path):
    json.dump({"A": ds.area_fraction.values.tolist(), "gap": ds.mean_gap.values.tolist(),
               "its": ds.iterations.values.tolist(), "conv": bool(ds.converged.all()),
               "wall": float(ds.wall_time.sum())}, open(path, "w"))


def main(surface, out, single=False):
    h = np.load(surface)
    if single:
        from roughcontact.solver import solve_contact

        record(solve_contact(h, LOADS), out)
        return
    from mpi4py import MPI

    from roughcontact.solver.mpi import rows_of, solve_contact_mpi

    comm = MPI.COMM_WORLD
    x0, x1 = rows_of(h.shape, comm)
    ds = solve_contact_mpi(h[x0:x1], h.shape, LOADS, comm=comm)
    if comm.rank == 0:
        record(ds, out)


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--single"]
    main(*args, single="--single" in sys.argv)
