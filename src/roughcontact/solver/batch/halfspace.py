"""The periodic half-space's products on a batch (:mod:`roughcontact.solver.batch`): transforms and multipliers.

:class:`BatchFFT` holds the batched real transforms over the last two axes of ``(B, nx, ny)`` (pyFFTW's
plans on the host, cuFFT through ``cupyx.scipy.fft`` on a GPU); :class:`BatchOperator` the multipliers ``K``
and ``M`` and the products the iteration calls; :class:`Float64Products` the same products in float64 (a
fallback's). The element-wise passes are :mod:`.kernels`'.
"""

from __future__ import annotations

import numpy as np

from ...core import fft as fft_module
from ..halfspace import elastic_kernel
from ..units import internal_length
from .kernels import ArrayKernels


class BatchFFT:
    """Real 2-D transforms over the last two axes of a ``(B, nx, ny)`` batch.

    numpy backend: the float32 pair with pyFFTW's plans on buffers of their own (:attr:`input32`,
    where the kernels write a transform's input; the spectrum; the output), as the single solve's
    :class:`~roughcontact.core.backend.SpectralProduct` (planned with the package's shipped wisdom
    only, :func:`~roughcontact.core.fft.shipped_wisdom_only`: the same plan whatever else the process
    planned), and :mod:`scipy.fft` for the rest (the float64 refreshes, other shapes) or where pyFFTW
    is missing or ``ROUGHCONTACT_FFT=numpy`` asks for no FFTW (:func:`~roughcontact.core.fft.default_backend`,
    which the outputs' ``fft_backend`` names); CuPy: :mod:`cupyx.scipy.fft` (cuFFT, plans from CuPy's plan cache:
    the batch keeps one shape, so one plan per precision and direction serves the whole solve); a stand-in CuPy without
    ``cupyx`` (tests): the array module's ``fft``. The inverse is unnormalised (``norm="forward"``):
    the ``1 / (nx ny)`` sits in the multipliers.
    """

    def __init__(self, be, shape, threads: int = 1, batch: int | None = None):
        self.shape = tuple(shape)
        self.kw, self.ikw = {}, {}
        self.input32 = None
        self.in_place = False
        # called after a float32 transform in place has overwritten input32 (set by BatchOperator: the kernels'
        # next sparse write there must zero the whole buffer)
        self.on_overwrite = None
        mod = be.xp.fft  # no SciPy; the tests' stand-in CuPy (numpy's fft under CuPy's name)
        try:
            if be.name == "numpy":
                import scipy.fft as mod

                self.kw = {"workers": threads}
            elif hasattr(be.xp, "ElementwiseKernel"):  # the real CuPy
                import cupyx.scipy.fft as mod
            # the spectrum is not needed after the inverse: cuFFT's c2r may destroy it, no copy first
            if mod is not be.xp.fft:
                self.ikw = {**self.kw, "overwrite_x": True}
        except ImportError:
            mod = be.xp.fft
        self.mod = mod
        self.batch, self.threads, self.spec64 = batch, threads, None
        # pyFFTW unless ROUGHCONTACT_FFT=numpy asks for none: the library the outputs' fft_backend names
        if be.name == "numpy" and batch is not None and fft_module.default_backend() == "pyfftw":
            self._plan32(batch, threads)

    def _plan32(self, batch: int, threads: int) -> None:
        import pyfftw

        nx, ny = self.shape
        self.spec32 = pyfftw.empty_aligned((batch, nx, ny // 2 + 1), dtype=np.complex64)
        # One case on a grid with shipped plans: both transforms in the spectrum's buffer, on the padded
        # layout (rows of 2 (ny // 2 + 1) reals), as the single solve's SpectralProduct. Measured at 2048²
        # (2026-12-02, one core): forward 14.4-14.5 ms against 16.2-17.3 out of place, inverse 13.8
        # against 15.3-15.9. Every forward then overwrites its input, which the next sparse write must
        # zero whole (:meth:`BatchOperator.transform32` says so to the kernels). Batches keep
        # out-of-place plans: the shipped wisdom holds one case's transforms only.
        self.in_place = batch == 1 and fft_module.has_shipped_plans(self.shape)
        if self.in_place:
            self.input32 = self.output32 = self.spec32.view(np.float32)[:, :, :ny]
        else:
            self.input32 = pyfftw.empty_aligned((batch, nx, ny), dtype=np.float32)
            self.output32 = pyfftw.empty_aligned((batch, nx, ny), dtype=np.float32)
        with fft_module.shipped_wisdom_only():
            self.fwd32 = pyfftw.FFTW(self.input32, self.spec32, axes=(1, 2), direction="FFTW_FORWARD",
                                     flags=fft_module.PLANNER_FLAGS, threads=threads)
            self.bwd32 = pyfftw.FFTW(self.spec32, self.output32, axes=(1, 2), direction="FFTW_BACKWARD",
                                     flags=fft_module.PLANNER_FLAGS, threads=threads)

    def _plan64(self) -> None:
        """The float64 pair of one case (the refreshes, case by case), in place: one complex buffer, made at
        first use. One case at a time whatever the batch, so that a case's refresh is the same
        arithmetic whichever cases are refreshed with it."""
        import pyfftw

        nx, ny = self.shape
        self.spec64 = pyfftw.empty_aligned((1, nx, ny // 2 + 1), dtype=np.complex128)
        self.real64 = self.spec64.view(np.float64)[:, :, :ny]  # rows padded to 2 (ny // 2 + 1) reals
        with fft_module.shipped_wisdom_only():
            self.fwd64 = pyfftw.FFTW(self.real64, self.spec64, axes=(1, 2), direction="FFTW_FORWARD",
                                     flags=fft_module.PLANNER_FLAGS, threads=self.threads)
            self.bwd64 = pyfftw.FFTW(self.spec64, self.real64, axes=(1, 2), direction="FFTW_BACKWARD",
                                     flags=fft_module.PLANNER_FLAGS, threads=self.threads)

    def _overwritten(self) -> None:
        if self.in_place and self.on_overwrite is not None:
            self.on_overwrite()

    def rfft2(self, x):
        """The spectrum of ``x`` over its last two axes; a buffer of the plans where they hold ``x``'s shape
        (valid until the next transform of that precision)."""
        if self.input32 is not None:
            if x.dtype == np.float32 and x.shape == self.input32.shape:
                if x is not self.input32:
                    self.input32[...] = x
                self.fwd32.execute()
                self._overwritten()
                return self.spec32
            if x.dtype == np.float64 and x.shape == (1, *self.shape):
                if self.spec64 is None:
                    self._plan64()
                self.real64[...] = x
                self.fwd64.execute()
                return self.spec64
        return self.mod.rfft2(x, axes=(-2, -1), **self.kw)

    def irfft2(self, spec):
        """The unnormalised inverse; the spectrum is destroyed. A plan's buffer where ``spec`` is one."""
        if self.input32 is not None:
            if spec is self.spec32:
                self.bwd32.execute()  # destroys the spectrum, as the c2r elsewhere may (overwrite_x)
                self._overwritten()
                return self.output32
            if spec is self.spec64:
                self.bwd64.execute()
                return self.real64
        return self.mod.irfft2(spec, s=self.shape, axes=(-2, -1), norm="forward", **self.ikw)


class BatchOperator:
    """The periodic half-space's products on a ``(B, nx, ny)`` batch, internal units (``E* = Lx = 1``).

    ``K`` (float64 and float32) and the preconditioner ``M = |q| E* / 2`` (float32), multipliers of
    shape ``(nx, ny // 2 + 1)`` carrying the inverse transform's ``1 / (nx ny)``, and Parseval's
    weights for ``x . K x``. float32 inputs are divided by each case's ``sigma`` (its internal rms
    height, ``(B, 1, 1)``) before the cast, as the single solve's products.
    """

    def __init__(self, be, shape, aspect: float, threads: int, kernels: ArrayKernels, batch: int | None = None):
        self.be, self.xp, self.k = be, be.xp, kernels
        nx, ny = self.shape = tuple(shape)
        self.input_shape = (batch or 1, nx, ny)
        self.fft = BatchFFT(be, shape, threads, batch)
        if self.fft.in_place:
            self.fft.on_overwrite = lambda: kernels.overwritten(self.fft.input32)
        if be.name == "cupy":
            # one plan per shape, precision and direction: the batch's and the float64 refreshes'
            # power-of-two subsets (<= 2 log2(B) + 6 plans) stay in CuPy's plan cache (default 16)
            try:
                cache = be.xp.fft.config.get_plan_cache()
                cache.set_size(max(cache.get_size(), 64))
            except Exception:  # noqa: BLE001 (the tests' stand-in has no plan cache; a failure here costs speed only)
                pass
        kern = elastic_kernel(self.shape, 1.0, internal_length(aspect))
        minv = np.zeros_like(kern)
        np.divide(1.0, kern, out=minv, where=kern > 0)
        norm = 1.0 / (nx * ny)
        herm = np.full(ny // 2 + 1, 2.0)  # columns standing for their Hermitian mirror count twice
        herm[0] = 1.0
        if ny % 2 == 0:
            herm[-1] = 1.0
        self.kmult64 = be.asarray(kern * norm)
        self.kmult32 = be.asarray((kern * norm).astype(np.float32))
        self.mmult32 = be.asarray((minv * norm).astype(np.float32))
        self.kquad32 = be.asarray((kern * herm[None, :] * norm).astype(np.float32))
        self.mmult64 = be.asarray(minv * norm)
        self.kquad64 = be.asarray(kern * herm[None, :] * norm)
        self._input64 = None

    def transform32(self, x32):
        """float32 spectrum of a float32 field (:meth:`input32` or any ``(B, nx, ny)``), unscaled.

        A transform in place overwrites :meth:`input32`, and the kernels are told (:attr:`BatchFFT.on_overwrite`,
        :meth:`~.kernels.ArrayKernels.overwritten`), so that their next sparse write there zeroes all of it.
        """
        return self.fft.rfft2(x32)

    def spectrum32(self, x, inv_sigma, F=None):
        """float32 spectrum of ``x * inv_sigma`` (one batched forward transform; ``x`` zero off ``F`` if given).

        The spectrum may be a buffer of the transforms, valid until the next transform.
        """
        return self.transform32(self.k.to32(x, inv_sigma, out=self.input32, F=F))

    @property
    def input32(self):
        """The forward float32 transform's own input buffer ``(B, nx, ny)`` (a kernel writes there), or None."""
        return getattr(self.fft, "input32", None)

    def float64_input(self):
        """A float64 transform input ``(B, nx, ny)`` for :class:`Float64Products` (made once)."""
        if self._input64 is None:
            self._input64 = self.xp.zeros(self.input_shape, dtype=np.float64)
        return self._input64

    def float64_products(self):
        """This operator with its iteration's products in float64: :class:`Float64Products` (a fallback's)."""
        return Float64Products(self)

    def quadratic32(self, spec):
        """``x . (K x) / sigma^2`` per case from :meth:`spectrum32`'s spectrum, ``(B, 1, 1)`` float64."""
        return self.k.quadratic(spec, self.kquad32)

    def inverse32(self, spec, mult):
        """``F^-1[mult spec]``: float32 ``(B, nx, ny)``, maybe a view with padded rows (the spectrum is
        overwritten; in place, so is :meth:`input32`)."""
        spec *= mult
        return self.fft.irfft2(spec)

    def apply64(self, P):
        """``K P`` in float64, ``(B, nx, ny)``."""
        spec = self.fft.rfft2(P)
        spec *= self.kmult64
        return self.fft.irfft2(spec)


class Float64Products:
    """An operator's products of the iteration (``spectrum32``, ``inverse32``, ``quadratic32``,
    ``transform32``, ``kmult32``, ``mmult32``, ``input32``: the names the iteration calls) in float64.

    The float32 iteration with float64 products is the single solve's ``pk-fourier``: the first
    fallback of a step that the float32 one leaves stalled (:data:`~roughcontact.solver.workspace.FALLBACKS`). The
    transform input is a float64 buffer of the shape the iteration writes, of its own (the
    transforms' output may overwrite theirs).

    Parameters
    ----------
    op : BatchOperator
        The operator (or :class:`~roughcontact.solver.mpi.kernels.SlabOperator`); its float64 multipliers are used.
    """

    def __init__(self, op):
        self.op, self.k, self.xp, self.fft = op, op.k, op.xp, op.fft
        self.kmult32, self.mmult32, self.kquad32 = op.kmult64, op.mmult64, op.kquad64
        self.kmult64 = op.kmult64
        self.input32 = op.float64_input()

    # the operator's own products, on these multipliers and this input buffer
    spectrum32 = BatchOperator.spectrum32
    transform32 = BatchOperator.transform32
    quadratic32 = BatchOperator.quadratic32
    inverse32 = BatchOperator.inverse32

    def apply64(self, P):
        return self.op.apply64(P)
