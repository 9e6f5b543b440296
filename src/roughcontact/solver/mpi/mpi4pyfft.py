"""The distributed real 2-D FFT of :mod:`.slabs`' layout by mpi4py-fft (``fft_library="mpi4py-fft"``).

mpi4py-fft has no wheel on PyPI and builds only where FFTW's headers and libraries are installed (``libfftw3-dev``);
measured against the default ``"slab"`` transforms in ``benchmarks/README.md`` ("The solver over MPI ranks").
"""

from __future__ import annotations

import numpy as np


class MpiFFTPlan:
    """The same transforms by mpi4py-fft's ``PFFT`` (FFTW), one plan per precision, on one case (B = 1).

    mpi4py-fft splits rows and spectral columns as :class:`~.slabs.Slabs` does (``slabs``, this rank's; checked
    at construction: a different split is refused).
    """

    name = "mpi4py-fft"

    def __init__(self, comm, slabs, threads: int = 1):
        try:
            from mpi4py_fft import PFFT
        except ImportError as exc:
            raise ValueError(f"fft_library='mpi4py-fft' needs mpi4py-fft, not importable here ({exc}); it builds "
                             "only with FFTW installed (libfftw3-dev): use fft_library='slab'") from exc
        self.slabs, self.shape = slabs, slabs.shape
        self.plans = {np.dtype(d): PFFT(comm, slabs.shape, axes=(0, 1), dtype=d, grid=(-1,), threads=threads)
                      for d in (np.float32, np.float64)}
        plan = self.plans[np.dtype(np.float64)]
        rows, cols = plan.local_slice(False)[0], plan.local_slice(True)[1]
        if (rows.start, rows.stop, cols.start, cols.stop) != (slabs.x0, slabs.x1, slabs.c0, slabs.c1):
            raise ValueError(f"mpi4py-fft split the grid differently ({rows}, {cols}) from the solver's slabs")

    def forward(self, x):
        plan = self.plans[x.dtype]
        out = np.empty((1, *plan.shape(True)), dtype=plan.forward.output_array.dtype)
        plan.forward(np.ascontiguousarray(x[0]), out[0], normalize=False)
        return out

    def backward(self, spec):
        real = np.float32 if spec.dtype == np.complex64 else np.float64
        plan = self.plans[np.dtype(real)]
        out = np.empty((1, *plan.shape(False)), dtype=real)
        plan.backward(np.ascontiguousarray(spec[0]), out[0], normalize=False)
        return out
