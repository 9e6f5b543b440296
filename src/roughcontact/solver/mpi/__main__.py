"""``mpiexec -n R python -m roughcontact.solver.mpi``: one contact case over ``R`` MPI ranks.

The surface is a NetCDF file (``--surface``: the variable ``heights`` over ``x, y``, any other
dimension of length 1, as the pipeline's surface files; every rank reads its own rows) or is
generated (``--generate N K_L K_S H SEED`` with ``--rms-slope`` or ``--rms-height``: rank 0 generates
it and sends each rank its rows; ``--plateau`` keeps the spectrum flat below ``K_L``: a roll-off).
The loads are ``--steps`` equal steps up to ``--p-max`` [pressure] (``p0 = p_max k / steps``,
``k = 1..steps``), or the mean pressures listed by ``--loads`` (the pipeline's resolved schedule,
:class:`roughcontact.case.loading.LoadSchedule`, as ``repr`` strings: exact). Rank 0 writes the contact NetCDF file
(``--out``), :func:`~roughcontact.solver.solve_contact`'s dataset, and logs each step to stderr.
Bad input ends in one line ``error: ...`` on rank 0 and exit status 2 on every rank.

Example (the Contact-Mechanics-Challenge-like surface of issue 50 at N = 8192 on 2 ranks)::

    mpiexec -n 2 python -m roughcontact.solver.mpi --generate 8192 5 1000 0.8 0 --plateau --rms-slope 1 \\
        --p-max 0.01 --steps 1 --out cmc_8192.nc
"""

from __future__ import annotations

import argparse
import resource
import sys

import numpy as np

from ...core.files import atomic_output, check_writable
from .program import check_world, file_rows, run_program
from .run import rows_of, solve_contact_mpi
from .slabs import FFT_LIBRARIES


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m roughcontact.solver.mpi", description=__doc__.split("\n\n")[0])
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--surface", help="NetCDF file with the variable 'heights' over (x, y)")
    src.add_argument("--generate", nargs=5, metavar=("N", "K_L", "K_S", "H", "SEED"),
                     help="a self-affine surface: grid points per side, cutoffs (mode numbers), Hurst exponent, seed")
    ap.add_argument("--rms-slope", type=float, help="rms slope of the generated surface")
    ap.add_argument("--rms-height", type=float, help="rms height of the generated surface")
    ap.add_argument("--plateau", action="store_true",
                    help="keep the spectrum constant below K_L (a roll-off, as the Contact-Mechanics Challenge's) "
                         "instead of cutting it")
    ap.add_argument("--length", type=float, default=None, help="side L of the cell, or its side Lx along x with "
                                                                   "--length-y (default: the file's, or 1)")
    ap.add_argument("--length-y", type=float, default=None, help="side Ly along y of a rectangular cell (with "
                                                                 "--length)")
    loads = ap.add_mutually_exclusive_group(required=True)
    loads.add_argument("--p-max", type=float, help="last mean pressure [pressure] of --steps equal steps")
    loads.add_argument("--loads", type=float, nargs="+", metavar="P0", help="the mean pressures [pressure], in order")
    ap.add_argument("--steps", type=int, default=10, help="equal load steps up to --p-max (default 10)")
    ap.add_argument("--e-star", type=float, default=1.0, help="plane-strain modulus E* [pressure] (default 1)")
    ap.add_argument("--tol", type=float, default=1e-8, help="convergence tolerance (default 1e-8)")
    ap.add_argument("--max-iter", type=int, default=None, help="iterations per step at most")
    ap.add_argument("--length-unit", default="1", help="unit of heights and lengths, as the file says it (default 1)")
    ap.add_argument("--pressure-unit", default="1", help="unit of E* and the pressures (default 1: nondimensional)")
    ap.add_argument("--fft-library", choices=FFT_LIBRARIES, default="slab", help="distributed FFT (default slab)")
    ap.add_argument("--expect-ranks", type=int, default=None, metavar="R",
                    help="fail unless MPI joins R ranks (a launcher that starts R unconnected processes, e.g. srun "
                         "without the MPI library's PMI, gives R one-rank worlds)")
    ap.add_argument("--fields", action="store_true", help="gather the last step's pressure and gap into the file")
    ap.add_argument("--out", required=True, help="contact NetCDF file written by rank 0")
    return ap


#: The values of ``--generate``, in order, with the type each must have.
GENERATE_VALUES = (("N", int), ("K_L", float), ("K_S", float), ("H", float), ("SEED", int))


def generator_values(values) -> tuple[int, float, float, float, int]:
    """``--generate N K_L K_S H SEED`` as numbers, else ``ValueError`` naming the value at fault."""
    out = []
    for (name, kind), text in zip(GENERATE_VALUES, values, strict=True):
        try:
            out.append(kind(text))
        except ValueError:
            raise ValueError(f"--generate {name}: {text!r} is not {'an integer' if kind is int else 'a number'}") \
                from None
    return tuple(out)


def generated_rows(args, comm) -> tuple[np.ndarray, tuple[int, int], float]:
    """Rank 0 generates the surface and sends each rank its rows (``Scatterv``); a value the generator refuses
    ends every rank (:func:`~.solver.collective`)."""
    from .solver import collective

    n, k_l, k_s, hurst, seed = generator_values(args.generate)
    length = 1.0 if args.length is None else args.length

    def generate():
        from ...surfaces.synthetic import generate_surface

        return generate_surface(n, k_l, k_s, hurst, seed, rms_slope=args.rms_slope, rms_height=args.rms_height,
                                length=length, plateau=args.plateau)

    # rank 0 alone generates: its refusal of a value (k_s beyond Nyquist, H out of range...) must reach the
    # others, which would otherwise wait in the Scatterv below for ever
    full = collective(comm, lambda: generate() if comm.rank == 0 else None)
    x0, x1 = rows_of((n, n), comm)
    mine = np.empty((x1 - x0, n))
    counts = comm.allgather(mine.size)
    offsets = comm.allgather(x0 * n)
    comm.Scatterv([full, (counts, offsets)] if comm.rank == 0 else None, mine, root=0)
    return mine, (n, n), length


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    return run_program(lambda comm: _run(args, comm))


def _run(args, comm) -> int:
    """The command on every rank (:func:`main` without its handling of errors)."""
    from .solver import collective

    collective(comm, lambda: _check_arguments(args, comm))
    h, shape, length = _heights(args, comm)
    p = np.asarray(args.loads) if args.loads is not None else args.p_max * np.arange(1, args.steps + 1) / args.steps
    if args.length is not None:
        length = args.length if args.length_y is None else (args.length, args.length_y)
    options = {"tol": args.tol, "e_star": args.e_star, "length": length, "length_unit": args.length_unit,
               "pressure_unit": args.pressure_unit}
    if args.max_iter is not None:
        options["max_iter"] = args.max_iter
    ds = solve_contact_mpi(h, shape, p, comm=comm, fft_library=args.fft_library, fields=args.fields,
                           progress=_log_step, **options)
    # each rank's peak resident memory (ru_maxrss, KiB on Linux): what a run at a new size must budget
    rss = comm.gather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20, root=0)
    if comm.rank == 0:
        # a file of its own, outside the pipeline (whose writer adds the same attribute): CF-checked
        ds.attrs["Conventions"] = "CF-1.8"
        with atomic_output(args.out) as tmp:
            ds.to_netcdf(tmp)
        print(f"{args.out}: {shape[0]} x {shape[1]} over {comm.size} ranks, {len(p)} steps, "
              f"converged {int(ds.converged.sum())}/{len(p)}, {int(ds.iterations.sum())} iterations, "
              f"{float(ds.wall_time.sum()):.1f} s; peak RSS per rank [GiB]: {' '.join(f'{r:.2f}' for r in rss)}",
              file=sys.stderr)
    return 0


def _check_arguments(args, comm) -> None:
    """What the command line alone decides, before any work; ``--out`` on rank 0, which writes it at the end (a
    path it cannot write fails now, not after the solve)."""
    if args.expect_ranks is not None:
        check_world(comm, args.expect_ranks)
    if args.steps < 1:
        raise ValueError(f"--steps must be >= 1, got {args.steps}")
    if args.length_y is not None and args.length is None:
        raise ValueError("--length-y needs --length (the side along x)")
    if comm.rank == 0:
        check_writable(args.out, "--out")


def _heights(args, comm):
    """This rank's rows, the grid and the cell's side, from the file or the generator; errors on every rank."""
    from .solver import collective

    if args.surface is not None:
        return collective(comm, lambda: file_rows(args.surface, comm))
    collective(comm, lambda: _check_generate(args, comm))
    return generated_rows(args, comm)


def _check_generate(args, comm):
    n = generator_values(args.generate)[0]
    if (args.rms_slope is None) == (args.rms_height is None):
        raise ValueError("--generate needs exactly one of --rms-slope and --rms-height")
    if comm.size > n:
        raise ValueError(f"ranks: {comm.size} MPI ranks for {n} rows along x: each rank needs at least one row "
                         f"(run at most {n} ranks)")


def _log_step(step, p0, area, iterations, converged, seconds):
    print(f"step {step}: p0={p0:.6g} A/A0={area:.6g} iterations={iterations} converged={converged} "
          f"{seconds:.2f} s", file=sys.stderr, flush=True)


if __name__ == "__main__":
    sys.exit(main())
