"""Array backends of the solver: where its fields live and how its transforms run.

A backend is named by the solver setting ``array_backend`` (config key
``contact.array_backend``):

- ``"numpy"`` (default): numpy arrays in host memory, transforms by pyFFTW with the shipped
  plans (numpy.fft where pyFFTW is missing; :mod:`.fft`);
- ``"cupy"``: CuPy arrays in the memory of the current CUDA device, transforms by cuFFT
  (``pip install roughcontact[gpu]`` brings CuPy; a CUDA GPU must be present).

The solver's iterations are written once against numpy's API: arrays they create come from
``backend.xp`` (``numpy`` or ``cupy``), and numpy functions called on CuPy arrays dispatch to
CuPy (NEP 13/18). What differs between backends lives here: array creation and transfer, the
real FFT pair of :mod:`.fft`'s interface (:meth:`ArrayBackend.real_fft`) and the fused
spectral product (:class:`SpectralProduct`) of the single-precision inner loop.
"""

from __future__ import annotations

import functools
import importlib

import numpy as np

from . import fft as _fft

#: Names the ``array_backend`` setting accepts.
ARRAY_BACKENDS = ("numpy", "cupy")


class SpectralProduct:
    """``y = F^-1[m F[x]]`` on an ``nx x ny`` grid with one plan pair and fixed buffers.

    ``input`` (real, ``dtype``) is written by the caller and never changed by a transform, so a
    caller that writes only a few nodes keeps the rest (zeros, say) from one product to the next.
    A multiplier ``m`` (real, shape ``(nx, ny // 2 + 1)``, from :meth:`multiplier`) carries the
    ``1 / (nx ny)`` of the inverse transform, so the backward transform is unnormalised and works
    in place on the spectrum (c2r destroys its input anyway): two transforms and one pass over the
    half spectrum, nothing else. For grids whose ``nx ny`` is a power of two the result equals
    ``irfft2(m' rfft2(x))`` with ``m' = nx ny m`` bit for bit (the scalings are exact).

    The two halves can also run apart: :meth:`forward` into one of two spectrum slots,
    :meth:`quadratic` (``x . (K x)`` by Parseval, from the spectrum alone) and :meth:`backward`
    of slot 0, so that a caller can combine spectra before the one inverse transform.
    """

    def __init__(self, backend: ArrayBackend, shape, dtype, threads: int = 1):
        self.backend = backend
        self.shape = tuple(int(s) for s in shape)
        self.dtype = np.dtype(dtype)
        self.norm = 1.0 / (self.shape[0] * self.shape[1])
        self.input = backend.zeros(self.shape, self.dtype)
        self._plan = backend.product_plan(self, threads)
        self._square = None

    def multiplier(self, mult: np.ndarray):
        """The device copy of the real multiplier ``mult`` (host, float64) with the ``1 / (nx ny)``.

        Interleaved ``(re, im)`` so that the product is one real ufunc call on the spectrum's
        float view (no complex temporary).
        """
        m = (np.asarray(mult, dtype=np.float64) * self.norm).astype(self.dtype)
        return self.backend.asarray(np.repeat(m[..., None], 2, axis=-1))

    def quadratic_weights(self, mult: np.ndarray):
        """Weights of :meth:`quadratic` for the real multiplier ``mult`` (host, float64).

        ``x . F^-1[mult F[x]] = sum_q w_q mult_q |F[x]_q|^2 / (nx ny)`` over the half spectrum,
        ``w_q`` = 2 for the columns that stand for their Hermitian mirror, 1 for column 0 and
        (even ``ny``) the Nyquist column.
        """
        ny = self.shape[1]
        w = np.full(ny // 2 + 1, 2.0)
        w[0] = 1.0
        if ny % 2 == 0:
            w[-1] = 1.0
        return self.multiplier(np.asarray(mult, dtype=np.float64) * w[None, :])

    def forward(self, slot: int = 0):
        """``F[input]`` in spectrum slot 0 or 1 (overwritten by the next forward into it)."""
        return self._plan.forward(slot)

    def quadratic(self, spec, weights) -> float:
        """``sum(weights * |spec|^2)``: ``x . (K x)`` for ``spec = F[x]`` and :meth:`quadratic_weights` of K.

        Single-precision terms, pairwise summation (relative error ~1e-7, as the products').
        """
        view = spec.view(weights.dtype).reshape(weights.shape)
        if self._square is None:
            self._square = self.backend.xp.empty(weights.shape, dtype=weights.dtype)
        np.multiply(view, view, out=self._square)
        np.multiply(self._square, weights, out=self._square)
        return float(self._square.sum())

    def backward(self, spec, mult):
        """``F^-1[mult spec]`` for ``spec`` from slot 0 (destroyed): a buffer the next product overwrites."""
        return self._plan.backward(spec, mult)

    def __call__(self, mult):
        """``F^-1[mult F[input]]``: a buffer that the next product overwrites (copy to keep)."""
        return self._plan.backward(self._plan.forward(0), mult)


def multiply_spectrum(spec, mult):
    """``spec * mult``, in place when ``mult`` (an interleaved ``(re, im)`` real multiplier) has
    the spectrum's precision; a new array when numpy.fft < 2 has transformed in double."""
    if spec.dtype.itemsize != 2 * mult.dtype.itemsize:
        return spec * mult[..., 0]
    view = spec.view(mult.dtype).reshape(mult.shape)
    np.multiply(view, mult, out=view)
    return spec


class _FFTWProduct:
    """The pyFFTW plans of a :class:`SpectralProduct`: r2c into two slots, c2r in place of slot 0."""

    def __init__(self, prod: SpectralProduct, threads: int):
        pyfftw = _fft.pyfftw
        n0, n1 = prod.shape
        cdtype = np.result_type(prod.dtype, np.complex64)
        self.specs = [pyfftw.empty_aligned((n0, n1 // 2 + 1), dtype=cdtype) for _ in range(2)]
        self.out = pyfftw.empty_aligned(prod.shape, dtype=prod.dtype)
        real = pyfftw.empty_aligned(prod.shape, dtype=prod.dtype)
        real[...] = 0.0
        prod.input = real
        with _fft._shipped_wisdom_only():
            self.fwd = [pyfftw.FFTW(real, spec, axes=(0, 1), direction="FFTW_FORWARD",
                                    flags=_fft.PLANNER_FLAGS, threads=threads) for spec in self.specs]
            self.bwd = pyfftw.FFTW(self.specs[0], self.out, axes=(0, 1), direction="FFTW_BACKWARD",
                                   flags=_fft.PLANNER_FLAGS, threads=threads)

    def forward(self, slot):
        self.fwd[slot].execute()
        return self.specs[slot]

    def backward(self, spec, mult):
        if spec is not self.specs[0]:
            raise ValueError("SpectralProduct.backward takes the spectrum of slot 0")
        multiply_spectrum(spec, mult)
        self.bwd.execute()  # unnormalised: 1 / (n0 n1) is in mult
        return self.out


class _ArrayModuleProduct:
    """The product with an array module's own FFT (numpy.fft, cupy.fft), unnormalised both ways."""

    def __init__(self, prod: SpectralProduct, xp):
        self.prod, self.fft = prod, xp.fft
        self.cdtype = np.result_type(prod.dtype, np.complex64)

    def forward(self, slot):
        spec = self.fft.rfft2(self.prod.input)
        return spec if spec.dtype == self.cdtype else spec.astype(self.cdtype)  # numpy.fft < 2: double

    def backward(self, spec, mult):
        out = self.fft.irfft2(multiply_spectrum(spec, mult), s=self.prod.shape, norm="forward")
        return out.astype(self.prod.dtype, copy=False)


class ArrayBackend:
    """numpy arrays on the host, pyFFTW (or numpy.fft) transforms: the default backend."""

    name = "numpy"
    xp = np

    def asarray(self, a, dtype=None):
        """``a`` as an array of this backend (no copy when it already is one)."""
        return self.xp.asarray(a, dtype=dtype)

    def to_host(self, a) -> np.ndarray:
        """``a`` as a numpy array in host memory."""
        return np.asarray(a)

    def zeros(self, shape, dtype=np.float64):
        return self.xp.zeros(shape, dtype=dtype)

    def fft_name(self) -> str:
        """The FFT library's name, for the outputs' ``fft_backend`` attribute."""
        return _fft.default_backend()

    def real_fft(self, shape, threads: int = 1, dtype=np.float64):
        """The cached FFT pair of :mod:`.fft` for ``shape`` (forward / backward, numpy's norms)."""
        if threads == 1:
            return _fft.get_fft(tuple(shape), backend=None, dtype=dtype)
        return _fft.get_fft(tuple(shape), threads=threads, dtype=dtype)

    def product_plan(self, prod: SpectralProduct, threads: int):
        if _fft.default_backend() == "pyfftw":
            return _FFTWProduct(prod, threads)
        return _ArrayModuleProduct(prod, np)


class _CupyFFT:
    """:class:`~.fft.RealFFT2`'s interface on cuFFT (plans cached by CuPy, numpy's norms)."""

    backend = "cupy"

    def __init__(self, cp, shape, dtype):
        self.cp, self.shape, self.dtype = cp, tuple(shape), np.dtype(dtype)
        self.threads = 1

    def forward(self, a):
        return self.cp.fft.rfft2(self.cp.asarray(a, dtype=self.dtype))

    def backward(self, a_hat):
        return self.cp.fft.irfft2(a_hat, s=self.shape).astype(self.dtype, copy=False)


class CupyBackend(ArrayBackend):
    """CuPy arrays on the current CUDA device, cuFFT transforms (``roughcontact[gpu]``)."""

    name = "cupy"

    def __init__(self, cp):
        self.xp = cp

    def to_host(self, a) -> np.ndarray:
        return self.xp.asnumpy(a)

    def fft_name(self) -> str:
        return "cupy"

    def real_fft(self, shape, threads: int = 1, dtype=np.float64):
        return _CupyFFT(self.xp, shape, dtype)

    def product_plan(self, prod: SpectralProduct, threads: int):
        return _ArrayModuleProduct(prod, self.xp)


@functools.cache
def get_backend(name: str = "numpy") -> ArrayBackend:
    """The backend called ``name`` (one of :data:`ARRAY_BACKENDS`).

    Raises ``ValueError`` naming the remedy when ``name`` is unknown or CuPy cannot run here.
    """
    if name == "numpy":
        return ArrayBackend()
    if name != "cupy":
        raise ValueError(f"array_backend must be one of {ARRAY_BACKENDS}, got {name!r}")
    try:
        cp = importlib.import_module("cupy")
        cp.cuda.runtime.getDeviceCount()
    except Exception as exc:  # ImportError, or CUDA's own error without a device or driver
        raise ValueError(
            f"array_backend 'cupy' needs CuPy and a CUDA GPU ({type(exc).__name__}: {exc}); install "
            "it with `pip install roughcontact[gpu]` on a machine with a GPU, or set array_backend "
            "to 'numpy'") from exc
    return CupyBackend(cp)

