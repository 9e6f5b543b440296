"""``launcher -n R python -m roughcontact.case JOB``: the ranks' program of a case over ``R`` MPI ranks.

:func:`roughcontact.case.run_case` starts it for a :class:`~roughcontact.case.ContactCase` with ``ranks`` > 1
and writes ``JOB``, a JSON file: the case as plain values (:func:`~roughcontact.case.run.case_document`), the
surface file, its grid and the cell's sides, the resolved loads and the file rank 0 writes. Every rank reads
its own rows of the surface (:func:`roughcontact.solver.mpi.program.read_rows`) and solves its slab
(:func:`roughcontact.solver.mpi.solve_contact_mpi`); rank 0 logs each step to stderr, as ``run_case`` reads
it, and writes the dataset. Bad input ends in one line ``error: ...`` on rank 0 and exit status 2 on every rank
(:func:`roughcontact.solver.mpi.program.run_program`).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..core.cli import BAD_INPUT, one_line
from ..core.files import atomic_output, check_writable
from .run import case_from_document


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
    """The case's solve on every rank; rank 0 writes the file."""
    from ..solver.mpi import solve_contact_mpi
    from ..solver.mpi.program import file_rows
    from ..solver.mpi.solver import collective

    def check():
        if comm.size != case.ranks:
            raise ValueError(f"ranks: {case.ranks} MPI ranks were asked for, but this process sees a world of "
                             f"{comm.size}: the launcher started processes MPI did not join (srun without the PMI "
                             "of the MPI library mpi4py was built with: try srun --mpi=pmi2, or build mpi4py "
                             "against the site's MPI, docs/cluster.md)")
        if comm.rank == 0:
            check_writable(job["out"], "the case's output")

    collective(comm, check)
    rows, shape, _ = collective(comm, lambda: file_rows(job["surface_file"], comm))

    def same_grid():
        if list(shape) != list(job["shape"]):
            raise ValueError(f"{job['surface_file']}: its grid is {shape[0]} x {shape[1]}, not the {job['shape'][0]} x "
                             f"{job['shape'][1]} the case was planned for; solve it again from the file")

    collective(comm, same_grid)
    length = job["length"][0] if job["length"][0] == job["length"][1] else tuple(job["length"])
    ds = solve_contact_mpi(rows, shape, job["loads"], case.solver_settings(length), comm=comm, progress=_log_step)
    if comm.rank == 0:
        ds.attrs["Conventions"] = "CF-1.8"
        with atomic_output(job["out"]) as tmp:
            ds.to_netcdf(tmp)
    return 0


def _log_step(step, p0, area, iterations, converged, seconds):
    print(f"step {step}: p0={p0:.6g} A/A0={area:.6g} iterations={iterations} converged={converged} "
          f"{seconds:.2f} s", file=sys.stderr, flush=True)


if __name__ == "__main__":
    sys.exit(main())
