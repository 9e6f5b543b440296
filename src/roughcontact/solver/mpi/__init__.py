"""One case split over MPI ranks (issue 50): the batched elastic iteration on slabs of the grid.

``mpiexec -n R python -m roughcontact.solver.mpi ...`` (:mod:`.__main__`) or
:func:`solve_contact_mpi` from a program every rank runs. The grid ``(nx, ny)`` is split along x
into ``R`` slabs of rows (:mod:`.slabs`); each rank holds its rows of the heights, the pressure, the
gap and the masks, and the iteration is the batched one (:class:`~roughcontact.solver.iteration.
BatchIteration`, B = 1) unchanged: its per-case reductions are collective (:class:`.kernels.MpiKernels`)
and its transforms distributed (:class:`.kernels.SlabOperator`: a real FFT along y, an all-to-all
transpose, a complex FFT along x). Same answers as :func:`~roughcontact.solver.solve_contact`
to the tolerance, for any number of ranks (tests/test_solver_mpi.py).

Runs the periodic elastic problem with the default method ``"pk-fourier-f32"``; the free boundary
(its zero-padded ``2n x 2n`` grid), effects, other methods and the GPU backend are refused with a
``ValueError``, and a stalled step goes on with float64 products over the ranks (the single solve's first
fallback; not the box fallback after it: :mod:`.solver`).
mpi4py and an MPI runtime come with ``pip install 'roughcontact[mpi]'``; importing this package
needs neither (:class:`.run.MpiUnavailableError` is raised when a solve asks for MPI). A rank's peak memory, as
measured: :func:`.memory.rank_memory_mib`.
"""

from .memory import rank_memory_mib
from .run import MpiUnavailableError, rows_of, solve_contact_mpi
from .slabs import FFT_LIBRARIES, Slabs

__all__ = ["FFT_LIBRARIES", "MpiUnavailableError", "Slabs", "rank_memory_mib", "rows_of", "solve_contact_mpi"]
