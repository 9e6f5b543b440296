"""A program every MPI rank runs: :func:`run_program` (its errors), :func:`read_rows` (its rows of a surface file).

``python -m roughcontact.solver.mpi`` (:mod:`.__main__`) and ``python -m roughcontact.case`` (a case that
:func:`roughcontact.case.run_case` starts over ranks) are such programs.
"""

from __future__ import annotations

import os
import sys
import traceback

import numpy as np

from ...core.cli import BAD_INPUT, one_line
from .run import MpiUnavailableError, rows_of, world
from .solver import CollectiveError


def check_world(comm, ranks: int) -> None:
    """``ValueError`` unless ``comm`` joins ``ranks`` processes: a launcher that starts ``ranks`` unconnected
    processes (srun without the MPI library's PMI) gives ``ranks`` one-rank worlds, each solving the whole case."""
    if comm.size != ranks:
        raise ValueError(f"ranks: {ranks} MPI ranks were asked for, but this process sees a world of {comm.size}: "
                         "the launcher started processes MPI did not join (srun without the PMI of the MPI library "
                         "mpi4py was built with: try srun --mpi=pmi2, or build mpi4py against the site's MPI, "
                         "docs/cluster.md)")


def run_program(body) -> int:
    """``body(comm)`` on every rank of ``COMM_WORLD``, its exit status; bad input ends every rank with status 2.

    A :class:`~.solver.CollectiveError` (raised on every rank at once) is printed once, by rank 0, as
    ``error: <one line>``; a ``ValueError`` or ``OSError`` raised on one rank alone is printed by it and aborts
    the others, which may wait in a collective call for ever (on a cluster, until the allocation ends); any
    other exception prints its traceback and aborts. MPI not importable is bad input too.
    """
    try:
        comm = world()
    except MpiUnavailableError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return BAD_INPUT
    try:
        return body(comm)
    except CollectiveError as exc:  # raised on every rank at once: each may return
        if comm.rank == 0:
            print(f"error: {one_line(exc)}", file=sys.stderr)
        return BAD_INPUT
    except (ValueError, OSError) as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr, flush=True)
        if comm.size > 1:
            comm.Abort(BAD_INPUT)
        return BAD_INPUT
    except BaseException:
        if comm.size > 1:  # a bug: its traceback, then no rank left waiting
            traceback.print_exc()
            sys.stderr.flush()
            comm.Abort(1)
        raise


def read_rows(path: str, comm) -> tuple[np.ndarray, tuple[int, int], float]:
    """This rank's rows of the file's heights, the grid and the file's ``length`` attribute (1 without).

    Reads the header, then the rank's rows ``[x0, x1)`` (:func:`~.run.rows_of`) and nothing else: one hyperslab
    read of ``(x1 - x0) ny`` values (xarray's lazy ``isel``), decoded as xarray decodes the whole variable (a
    ``_FillValue`` becomes NaN), so no rank holds the whole field (34 GB at 65536²). The rows are checked to be
    finite here, where they are read: the job that starts the ranks checks only a sample of rows
    (:func:`roughcontact.pipeline.datasets.surface_grid`). Raises ``ValueError`` naming the file, the rows and the
    remedy; run under :func:`~.solver.collective` (as :func:`main` does), every rank then ends with it.
    """
    import xarray as xr

    with xr.open_dataset(path) as ds:
        if "heights" not in ds.variables:
            raise ValueError(f"{path}: holds no variable 'heights'")
        var = ds["heights"]
        extra = [d for d in var.dims if d not in ("x", "y")]
        if any(var.sizes[d] != 1 for d in extra) or "x" not in var.dims or "y" not in var.dims:
            raise ValueError(f"{path}: 'heights' must lie over (x, y) (other dimensions of length 1), got "
                             f"{dict(var.sizes)}")
        var = var.isel({d: 0 for d in extra}).transpose("x", "y")
        shape = (var.sizes["x"], var.sizes["y"])
        x0, x1 = rows_of(shape, comm)
        rows = np.asarray(var.isel(x=slice(x0, x1)).values, dtype=np.float64)
        bad = rows.size - int(np.count_nonzero(np.isfinite(rows)))
        if bad:
            raise ValueError(f"{path}: 'heights' holds {bad} NaN or infinite value(s) in rows {x0}..{x1 - 1} (rank "
                             f"{comm.rank}'s); every height must be finite: remake the file (a pipeline's surface "
                             "file: remove it, or rerun with -f), or fill those points")
        return rows, shape, float(ds.attrs.get("length", 1.0))


def file_rows(path, comm) -> tuple[np.ndarray, tuple[int, int], float]:
    """:func:`read_rows` with a folder, an unreadable or a foreign file named as such (``ValueError``)."""
    if os.path.isdir(path):
        raise ValueError(f"{path}: is a folder; give a surface file (NetCDF with 'heights', as the surface jobs write)")
    try:
        return read_rows(path, comm)
    except OSError as exc:
        raise ValueError(f"{path}: cannot be read as NetCDF ({one_line(exc)})") from None
    except ValueError as exc:
        if "IO backends" not in str(exc):
            raise  # the file's content refused (rows, NaN, ...): the message says why
        # xarray names no file when no engine recognises it: a truncated or foreign file
        raise ValueError(f"{path}: not a readable NetCDF file (truncated or foreign?): {one_line(exc)}") from None
