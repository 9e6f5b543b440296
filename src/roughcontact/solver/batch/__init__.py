"""Many surfaces in one solve: the batched elastic iteration (issue 48).

:func:`solve_contact_batch` solves ``B`` surfaces of one grid under one load schedule together.
Every field carries a leading case axis, ``(B, nx, ny)``; every transform is one batched
``rfft2`` / ``irfft2`` over the last two axes (cuFFT or scipy.fft batches them); every reduction
runs along ``(-2, -1)`` and gives one number per case, kept as a ``(B, 1, 1)`` array so that it
broadcasts back onto the fields. The iteration is the default elastic one,
``"pk-fourier-f32"`` (:class:`~roughcontact.solver.iteration.BatchIteration`, which runs the single solve
too): Polonsky & Keer's CG on the free set
``F``, the Fourier preconditioner ``M = |q| E* / 2`` with Polak-Ribiere's ``beta`` kept across
joins, the projection onto ``p >= 0`` with the mean restored by rescaling, float32 products in the
loop, float64 recomputations of ``w = K p - h`` below the residual levels 1e-5, 1e-9, ... and to
confirm convergence, the stall guard and the final check on a fresh displacement. It is written
with masks instead of index sets: ``F`` is a boolean field, ``p``, ``t`` and the gradients are
zero off ``F``, and what a case does in a round (iterate, wait for a float64 recomputation, stop)
is a per-case boolean, so a round is the same sequence of array operations for every case and
nothing in it needs the host.

Per case, the iteration is the single solve's: a converged case is frozen (its pressure, gap and
iteration count stop changing) while the others go on, and a case waiting for a float64
recomputation is frozen until the next *check*, where the host reads the per-case flags (one
small transfer: the only host synchronisation of the loop) and recomputes ``w`` for those cases.
The check comes every ``check_every`` rounds (:data:`~.solver.CHECK_EVERY`), between the measure and the
move of a round; a waiting case idles until then, which costs rounds but never iterations: the
iteration counts do not depend on ``check_every``, and with ``check_every = 1`` the rounds are
the iterations of the slowest case. The transforms differ from the single solve's (batched scipy.fft or cuFFT
against pyFFTW's in-place plans, a projected step's change transformed by itself), so the
iterates agree to round-off of float32 products, not bit for bit: the same A/A0 to the
tolerance, iteration counts equal or within one or two per step (tests/test_batch.py).

Not batched: a step whose iteration stalls or breaks down moves on to the fallbacks of
:data:`~roughcontact.solver.workspace.FALLBACKS` on that case alone (a
:class:`~roughcontact.solver.workspace.Workspace` of its own, the single solve's code), and the following
steps start on the batched iteration again (no ``STICKY``). Effects, the free boundary, the other elastic
methods, flat surfaces, stored fields, clusters and observers are refused with a ``ValueError``.

On CuPy the hot element-wise passes and per-case reductions are fused into a few
``ElementwiseKernel`` / ``ReductionKernel`` calls (:class:`.cuda.CupyKernels`, made only when CuPy is
importable; each is checked once against the plain array expressions and replaced by them if it
disagrees), cuFFT plans come from CuPy's plan cache (one shape, ``(B, nx, ny)``, for a whole solve),
and compiled kernels are cached on disk (``CUPY_CACHE_DIR``, :func:`roughcontact.core.backend.get_backend`).
"""

from .run import PER_CASE, solve_contact_batch, validate_batch
from .solver import BATCH_METHOD, CHECK_EVERY, BatchSolver

__all__ = ["BATCH_METHOD", "CHECK_EVERY", "PER_CASE", "BatchSolver", "solve_contact_batch", "validate_batch"]
