"""``launcher -n R python -m roughcontact.case JOB``: the ranks' program of a case over ``R`` MPI ranks.

:func:`roughcontact.case.run_case` starts it for a :class:`~roughcontact.case.ContactCase` with ``ranks`` > 1
and writes ``JOB``, a JSON file: the case as plain values (:func:`~roughcontact.case.run.case_document`), the
surface file, its grid, the cell's sides, the surface's rms slope and the file rank 0 writes. Every rank runs
``run_case`` on the file with its communicator (``comm=``): each reads its own rows of the surface
(:func:`roughcontact.solver.mpi.program.read_rows`), resolves the schedule as the starting process did and solves
its slab; rank 0 prints each step's line to stderr, as the starting ``run_case`` reads it, and writes the dataset.
Bad input ends in one line ``error: ...`` on rank 0 and exit status 2 on every rank
(:func:`roughcontact.solver.mpi.program.run_program`).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..core.cli import BAD_INPUT, one_line
from ..core.files import atomic_output, check_writable
from .run import case_from_document, run_case


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if len(args) != 1:
        print("usage: python -m roughcontact.case JOB (the JSON file run_case writes for a case over MPI ranks)",
              file=sys.stderr)
        return BAD_INPUT
    try:
        job = json.loads(Path(args[0]).read_text())
        case = case_from_document(job["case"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        print(f"error: {args[0]}: not a case job written by run_case ({one_line(exc)})", file=sys.stderr)
        return BAD_INPUT
    from ..solver.mpi.program import run_program

    return run_program(lambda comm: _solve(job, case, comm))


def _solve(job, case, comm) -> int:
    """:func:`~roughcontact.case.run_case` on every rank; rank 0 writes the file."""
    from ..solver.mpi.solver import collective

    # rank 0 writes at the end: a path it cannot write fails now, on every rank, not after the solve
    collective(comm, lambda: check_writable(job["out"], "the case's output") if comm.rank == 0 else None)
    sides = job["length"]
    length = sides[0] if sides[0] == sides[1] else tuple(sides)
    solved = run_case(job["surface_file"], case, length=length, rms_slope=job["rms_slope"], shape=job["shape"],
                      comm=comm)
    for ds in solved:  # rank 0's
        with atomic_output(job["out"]) as tmp:
            ds.to_netcdf(tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
