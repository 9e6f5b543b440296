"""The batched iteration's kernels and operator over MPI ranks: collective reductions, slab transforms.

:class:`MpiKernels` are the fused CPU kernels (:class:`~roughcontact.solver.batch.cpu.FusedCpuKernels`)
whose per-case reductions add the ranks' partial results: every reduction of the iteration (sums,
dots, the complementarity, the masked sums, the quadratic form over the half spectrum, the
projection's positive part) goes through :meth:`MpiKernels.allsum`, :meth:`~MpiKernels.allcount`,
:meth:`~MpiKernels.allmin` or :meth:`~MpiKernels.allany`. Each gathers the ranks' local results
(``Allgather``, a few bytes per case) and combines them in rank order on every rank, instead of
``Allreduce``: the MPI standard does not promise the same floating-point sum on every rank, and the
iteration's decisions (converge, join, stop) must be the same on all of them or the ranks would
take different branches and wait on each other for ever. The element-wise passes and per-case
decisions are the batched ones unchanged: they act on the rank's slab and on per-case numbers that
are equal on every rank.

:class:`SlabOperator` is :class:`~roughcontact.solver.batch.halfspace.BatchOperator` with the
transforms of :mod:`.slabs`: multipliers for the rank's columns of the half spectrum only, so no
rank ever holds a whole field.
"""

from __future__ import annotations

import numpy as np

from ...core.fft import rfft_weights, wavenumbers
from ..batch.cpu import FusedCpuKernels
from ..batch.halfspace import BatchOperator
from ..units import internal_length


class MpiKernels(FusedCpuKernels):
    """:class:`~roughcontact.solver.batch.cpu.FusedCpuKernels` whose per-case reductions combine the ranks' parts.

    Each reduction of the iteration computes the rank's part in one fused pass over its slab, then
    goes through one of :meth:`allsum`, :meth:`allcount`, :meth:`allmin` or :meth:`allany`.
    """

    split = True  # a round's passes one at a time, each reduction combined over the ranks (FusedCpuKernels.split)

    def __init__(self, comm):
        super().__init__()
        self.comm = comm

    def _gather(self, local):
        """``(size, *local.shape)``: every rank's ``local``, on every rank."""
        local = np.ascontiguousarray(local)
        out = np.empty((self.comm.size, *local.shape), dtype=local.dtype)
        self.comm.Allgather(local, out)
        return out

    def allsum(self, local):
        """Sum over every rank's part per case ``(B, 1, 1)`` float64, added in rank order."""
        parts = self._gather(local)
        total = parts[0].copy()
        for part in parts[1:]:
            total += part
        return total

    def allcount(self, local):
        return self._gather(local).sum(axis=0)

    def allmin(self, local):
        # np.min over the ranks: a NaN on any rank is a NaN on all (MPI's MIN leaves that unsaid)
        return self._gather(local).min(axis=0)

    def allany(self, local):
        return self._gather(local).any(axis=0)


class _SlabTransforms:
    """The ``rfft2`` / ``irfft2`` pair of :class:`SlabOperator` (the interface of the batched ``BatchFFT``)."""

    def __init__(self, fft):
        self.impl = fft
        self.input32 = getattr(fft, "input32", None)  # where the kernels write a forward transform's input

    def rfft2(self, x):
        return self.impl.forward(x)

    def irfft2(self, spec):
        return self.impl.backward(spec)


class SlabOperator(BatchOperator):
    """The periodic half-space's products on the rank's slab (internal units, ``E* = Lx = 1``).

    :class:`~roughcontact.solver.batch.halfspace.BatchOperator`'s products (its methods, which
    :class:`~roughcontact.solver.iteration.BatchIteration` calls), with the distributed
    transforms and the multipliers ``K``, ``M = |q| E* / 2`` and Parseval's weights on the rank's
    spectral columns ``[c0, c1)`` (shape ``(nx, c1 - c0)``), computed there alone.

    Parameters
    ----------
    slabs : .slabs.Slabs
        The decomposition.
    aspect : float
        ``Ly / Lx`` of the cell.
    fft : .slabs.SlabFFT or .mpi4pyfft.MpiFFTPlan
        The distributed transforms.
    kernels : MpiKernels
        The reductions (the quadratic form sums over every rank's columns).
    """

    def __init__(self, slabs, aspect: float, fft, kernels: MpiKernels):
        # not the parent's __init__: it makes the whole half spectrum's multipliers and a batched FFT
        self.k, self.xp = kernels, np
        nx, ny = self.shape = slabs.shape
        self.fft = _SlabTransforms(fft)
        if hasattr(fft, "on_overwrite"):  # its float32 transforms in place write over input32 (FftwSlabFFT)
            fft.on_overwrite = lambda: kernels.overwritten(fft.input32)
        kx, ky = wavenumbers(self.shape, internal_length(aspect))
        ky = ky[:, slabs.c0:slabs.c1]
        q = 2.0 * np.pi * np.hypot(kx, ky)  # (nx, c1 - c0): this rank's columns only
        kern = np.zeros_like(q)
        np.divide(2.0, q, out=kern, where=q > 0)
        minv = np.zeros_like(kern)
        np.divide(1.0, kern, out=minv, where=kern > 0)
        norm = 1.0 / (nx * ny)
        herm = rfft_weights(ny)[:, slabs.c0:slabs.c1]
        herm = np.broadcast_to(herm, kern.shape)
        if getattr(fft, "transposed", False):  # the spectrum held (c1 - c0, nx): .slabs.FftwSlabFFT
            kern, minv, herm = (np.ascontiguousarray(a.T) for a in (kern, minv, herm))
        self.kmult64 = kern * norm
        self.kmult32 = (kern * norm).astype(np.float32)
        self.mmult32 = (minv * norm).astype(np.float32)
        self.kquad32 = (kern * herm * norm).astype(np.float32)
        self.mmult64 = minv * norm
        self.kquad64 = kern * herm * norm
        self.input_shape = (1, *slabs.local_shape)
        self._input64 = None

    def float64_input(self):
        """A float64 transform input of the rank's slab, made once: not the float64 transforms' own, which
        their output overwrites (the kernels zero only the nodes they wrote last)."""
        return super().float64_input()
