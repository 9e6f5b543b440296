"""One case split over MPI ranks: :class:`MpiSolver`, the batched solver (B = 1) on the rank's slab.

The iteration is :class:`~roughcontact.solver.iteration.BatchIteration` unchanged, with
:class:`~.kernels.MpiKernels` (collective reductions) and :class:`~.kernels.SlabOperator` (the
distributed transforms). What the batched solver does on a whole field is made rank-aware here:
the surface's moments (the internal units, the rms height of the convergence criterion) are
collective (:func:`moments`), and so is the contact perimeter, whose edges along x cross the slab
boundaries (:meth:`MpiSolver.perimeter` exchanges one row with each neighbour). Nothing else in the
iteration indexes a whole field: its only index operations select cases along the leading axis.

A step whose float32 iteration stalls goes on with the single solve's first fallback, over the
ranks: the same iteration with float64 products (``pk-fourier``, :meth:`MpiSolver.fallback`). Not
distributed: the box fallback after that (a :class:`~roughcontact.solver.workspace.Workspace` holds a
whole field); a step whose float64 iteration stalls too ends ``converged = False``, as one that
reaches ``max_iter``.
"""

from __future__ import annotations

import math

import numpy as np

from ...core.backend import get_backend
from ...core.cell import Cell
from ...core.cli import one_line
from ...statistics.patches import merge_slabs, slab_patches
from ..batch.solver import BATCH_METHOD, BatchSolver
from ..iteration import BatchIteration
from ..steps import fall_back
from ..units import Units
from ..workspace import FALLBACKS, SOLVER_PATHS, STALL_WINDOW as SINGLE_STALL_WINDOW
from .kernels import MpiKernels, SlabOperator
from .slabs import make_fft

#: The fallback a stalled step gets over the ranks: the float32 iteration's first (float64 products).
FLOAT64_FALLBACK = FALLBACKS[BATCH_METHOD][0]


class CollectiveError(ValueError):
    """A ``ValueError`` raised on every rank at once by :func:`collective`: each rank may return on it, as no
    rank is left waiting in a collective call."""


def collective(comm, fn):
    """``fn()`` on every rank; a ``ValueError`` or ``OSError`` on any rank is raised on every rank as a
    :class:`CollectiveError` (the first failing rank's message).

    A check that fails on one rank only (its slab holds the bad value, or only rank 0 generates or
    writes) would otherwise leave the others waiting in the next collective call for ever.
    """
    try:
        out, msg = fn(), None
    except (ValueError, OSError) as exc:
        out, msg = None, one_line(exc)
    msgs = comm.allgather(msg)
    bad = [m for m in msgs if m is not None]
    if bad:
        raise CollectiveError(bad[0])
    return out


def moments(comm, h: np.ndarray, size: int) -> tuple[bool, float, float]:
    """``(flat, mean, rms about the mean)`` of a surface split over the ranks (``h`` the rank's part).

    As :func:`~roughcontact.solver.units.rms_about_mean`: squares of heights scaled by a power of two
    so that the largest is in [0.5, 1), no overflow or underflow; sums added in rank order.
    """
    lo = min(comm.allgather(float(h.min())))
    hi = max(comm.allgather(float(h.max())))
    if not hi > lo:
        return True, 0.0, 0.0
    e = math.frexp(max(hi, -lo))[1]
    hs = np.ldexp(h, -e)
    mu = sum(comm.allgather(float(np.sum(hs)))) / size
    hs -= mu
    var = sum(comm.allgather(float(np.sum(hs * hs)))) / size
    return False, math.ldexp(mu, e), math.ldexp(math.sqrt(var), e)


class MpiSolver(BatchSolver):
    """The batched solver of one case whose fields are the rank's slab ``(1, x1 - x0, ny)``.

    Parameters
    ----------
    comm : mpi4py.MPI.Comm
        The ranks sharing the case.
    slabs : .slabs.Slabs
        The decomposition of the grid ``(nx, ny)``.
    h : numpy.ndarray, shape (x1 - x0, ny)
        The rank's rows of the validated heights [length].
    settings : SolverSettings
        Checked for ``(nx, ny)``; the periodic ``"pk-fourier-f32"`` iteration without effects.
    fft_library : str
        :data:`.slabs.FFT_LIBRARIES`.
    """

    def __init__(self, comm, slabs, h: np.ndarray, settings, fft_library: str = "slab"):
        self.comm, self.slabs = comm, slabs
        self.settings = settings
        self.batch = 1
        self.shape = slabs.shape
        self.size = self.shape[0] * self.shape[1]
        self.tol, self.max_iter = settings.tol, settings.max_iter
        self.length, self.threads = settings.length, settings.threads
        self.cell = Cell.canonical(self.shape, self.length, "heights")
        self.method, self.periodic, self.array_backend = BATCH_METHOD, True, "numpy"
        self.be = get_backend("numpy")
        self.xp = np
        self.check_every = 1
        flat, mean, rms = moments(comm, h, self.size)
        if flat:
            raise ValueError("heights: the surface is flat (all heights equal); the MPI solver takes rough surfaces "
                             "only (solve a flat surface with solve_contact)")
        unit = Units.of_moments(self.shape, settings.e_star, settings.length, False, mean, rms)
        self.units = [unit]
        hin = unit.internal_heights(h)[None]
        rms_int = moments(comm, hin[0], self.size)[2]
        self.h_rms = np.full((1, 1, 1), rms_int)
        self.h_rms_host = np.array([rms_int])
        self.kernels = MpiKernels(comm)
        self.fft = make_fft(fft_library, comm, slabs, self.threads)
        self.op = SlabOperator(slabs, self.cell.aspect, self.fft, self.kernels)
        self.h = self.h_host = np.ascontiguousarray(hin)
        self.P = np.zeros(hin.shape)
        self.w = np.empty(hin.shape)
        self.prev = None
        self._older = None
        self._last = None
        self._ws = {}
        self._op64 = None
        self.paths = SOLVER_PATHS

    def close(self) -> None:
        """Free the memory the transforms share with the other ranks of the machine (collective; the solver is spent
        after: :class:`~.slabs.FftwSlabFFT`'s windows)."""
        close = getattr(self.fft, "close", None)
        if close is not None:
            close()

    @property
    def backend(self) -> str:
        return f"mpi-{self.fft.name}"

    def fallback(self, b: int, p_int: float, its: int) -> tuple[int, str, bool]:
        """The single solve's first fallback over the ranks: ``pk-fourier``, the same iteration with float64
        products (:class:`~roughcontact.solver.batch.halfspace.Float64Products`), from the stalled pressure
        with ``w`` recomputed, for the iterations left, with the single solve's stall guard.

        Returns ``(iterations in all, path, converged)``; the box fallback does not run over ranks
        (module docstring).
        """
        return fall_back(BATCH_METHOD, its, False, self.max_iter, lambda method, left: self._float64(p_int, left),
                         reachable=(FLOAT64_FALLBACK,))

    def _float64(self, p_int: float, left: int) -> tuple[int, bool]:
        """``pk-fourier`` over the ranks to the internal load ``p_int`` for ``left`` iterations at most;
        ``(iterations, converged)``."""
        if self._op64 is None:
            self._op64 = self.op.float64_products()
        it = BatchIteration(self, np.full((1, 1, 1), p_int), np.zeros(1, dtype=np.int8), np.array([left]),
                            op=self._op64, stall=SINGLE_STALL_WINDOW)
        more, conv = it.run(1)
        return int(more[0]), bool(conv[0])

    def perimeter(self) -> np.ndarray:
        """Contact perimeter per unit area (periodic), the edges along x across slab boundaries included; (1,)."""
        m = self.P[0] > 0.0
        comm, r, R = self.comm, self.comm.rank, self.comm.size
        # the row before this slab's first: the previous rank's last (periodic)
        before = np.empty(m.shape[1], dtype=bool)
        comm.Sendrecv(np.ascontiguousarray(m[-1]), dest=(r + 1) % R, recvbuf=before, source=(r - 1) % R)
        ex = int(np.count_nonzero(m[1:] != m[:-1])) + int(np.count_nonzero(m[0] != before))
        ey = int(np.count_nonzero(m != np.roll(m, 1, axis=1)))
        ex, ey = (sum(comm.allgather(v)) for v in (ex, ey))
        return self.cell.perimeter_per_area(np.array([float(ex)]), np.array([float(ey)]))

    def largest_patches(self) -> np.ndarray:
        """Nodes of the largest contact patch (periodic), the patches across slab boundaries joined; (1,) int64.

        Each rank labels its rows (:func:`~roughcontact.statistics.patches.slab_patches`: the patch ids of its
        first and last rows and its largest patch touching neither); rank 0 joins them
        (:func:`~roughcontact.statistics.patches.merge_slabs`) and broadcasts the count.
        """
        parts = self.comm.gather(slab_patches(self.P[0] > 0.0), root=0)
        largest = merge_slabs(parts)[1] if self.comm.rank == 0 else None
        return np.array([self.comm.bcast(largest, root=0)], dtype=np.int64)

    def fields(self) -> tuple[np.ndarray, np.ndarray]:
        """The rank's rows of the last step's pressure [pressure] and gap ``w - gbar`` [length]."""
        unit = self.units[0]
        w = self.w[0]
        pos = self.P[0] > 0.0
        nf = self.kernels.rcount(pos[None])
        gbar = float((self.kernels.masked_sum(w[None], pos[None]) / np.where(nf > 0, nf, 1)).reshape(()))
        return unit.pressure(self.P[0].copy()), unit.length_field(w - gbar)
