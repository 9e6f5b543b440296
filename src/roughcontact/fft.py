"""Real 2-D FFT pairs with cached plans: pyFFTW when importable, numpy.fft otherwise.

All transforms use numpy's conventions: the forward transform is unnormalised, the
backward transform divides by ``n0 * n1``. Arrays are ``float64`` of shape ``(n0, n1)``
in real space and ``complex128`` of shape ``(n0, n1 // 2 + 1)`` in Fourier space;
``dtype=numpy.float32`` gives single-precision pairs (``float32`` / ``complex64``, about
half the time of a double pair; the solver uses them for its inner products only).

Reproducibility: FFTW plans are made with ``FFTW_ESTIMATE`` (:data:`PLANNER_FLAGS`),
which picks the algorithm from heuristics alone, so the same transform gives the same
bits in every process on a given machine and build. ``FFTW_MEASURE`` would time candidate
plans and, on a loaded machine, pick different ones in different processes, whose results
differ in the last bits. The cost (``benchmarks/README.md``): an ``FFTW_ESTIMATE`` pair
takes 1.1-1.5x the time of an ``FFTW_MEASURE`` one at N = 512-1024, still less than
``numpy.fft``, and planning takes milliseconds instead of about a second per shape.
"""

from __future__ import annotations

import functools
import os

import numpy as np

try:  # pragma: no cover - exercised by whichever backend is installed
    import pyfftw

    _HAVE_PYFFTW = True
except ImportError:  # pragma: no cover
    pyfftw = None
    _HAVE_PYFFTW = False

#: Backends a caller may ask for.
BACKENDS = ("pyfftw", "numpy")

#: FFTW planner flags. ``FFTW_ESTIMATE`` is deterministic (no timing); do not use
#: ``FFTW_MEASURE``/``FFTW_PATIENT`` here: they make results vary between processes.
PLANNER_FLAGS = ("FFTW_ESTIMATE",)


def default_backend() -> str:
    """Name of the backend used when none is asked for.

    ``ROUGHCONTACT_FFT=numpy`` in the environment forces the numpy.fft fallback.
    """
    forced = os.environ.get("ROUGHCONTACT_FFT", "").strip().lower()
    if forced:
        if forced not in BACKENDS:
            raise ValueError(
                f"ROUGHCONTACT_FFT={forced!r} is not a known FFT backend; allowed: {', '.join(BACKENDS)}"
            )
        if forced == "pyfftw" and not _HAVE_PYFFTW:
            raise ValueError("ROUGHCONTACT_FFT=pyfftw but pyfftw cannot be imported")
        return forced
    return "pyfftw" if _HAVE_PYFFTW else "numpy"


class RealFFT2:
    """A planned real-to-complex / complex-to-real 2-D transform pair for one shape.

    Parameters
    ----------
    shape : (int, int)
        Real-space shape ``(n0, n1)``.
    threads : int
        Threads FFTW may use (numpy's pocketfft is single-threaded here).
    backend : {"pyfftw", "numpy"} or None
        ``None`` picks :func:`default_backend`.
    dtype : numpy.float64 or numpy.float32
        Precision of the transforms (real ``dtype``, complex of the same precision).

    Notes
    -----
    ``forward`` and ``backward`` return views of internal buffers that the next call
    overwrites: copy the result if it must outlive the next transform. This is what
    makes the solver's inner loop allocation-free.
    """

    def __init__(self, shape: tuple[int, int], threads: int = 1, backend: str | None = None,
                 dtype=np.float64):
        n0, n1 = (int(s) for s in shape)
        if n0 < 2 or n1 < 2:
            raise ValueError(f"FFT shape must be at least 2x2, got {shape}")
        self.shape = (n0, n1)
        self.spectral_shape = (n0, n1 // 2 + 1)
        self.backend = backend or default_backend()
        if self.backend not in BACKENDS:
            raise ValueError(f"FFT backend {self.backend!r} unknown; allowed: {', '.join(BACKENDS)}")
        self.threads = max(1, int(threads))
        self.dtype = np.dtype(dtype)
        if self.dtype not in (np.dtype(np.float64), np.dtype(np.float32)):
            raise ValueError(f"FFT dtype must be float64 or float32, got {self.dtype}")
        cdtype = np.result_type(self.dtype, np.complex64)
        if self.backend == "pyfftw":
            if not _HAVE_PYFFTW:
                raise ValueError("pyfftw backend requested but pyfftw cannot be imported")
            self._real = pyfftw.empty_aligned(self.shape, dtype=self.dtype)
            self._spec = pyfftw.empty_aligned(self.spectral_shape, dtype=cdtype)
            self._spec_in = pyfftw.empty_aligned(self.spectral_shape, dtype=cdtype)
            self._real_out = pyfftw.empty_aligned(self.shape, dtype=self.dtype)
            # FFTW reuses wisdom from a more rigorous planner: a plan timed with
            # FFTW_MEASURE earlier in this process (by any pyFFTW user) would replace
            # the deterministic FFTW_ESTIMATE choice. Forgetting the wisdom first keeps
            # the plan a function of the shape alone; plans already made stay valid.
            pyfftw.forget_wisdom()
            flags = tuple(PLANNER_FLAGS)
            self._fwd = pyfftw.FFTW(
                self._real, self._spec, axes=(0, 1), direction="FFTW_FORWARD",
                flags=flags, threads=self.threads,
            )
            self._bwd = pyfftw.FFTW(
                self._spec_in, self._real_out, axes=(0, 1), direction="FFTW_BACKWARD",
                flags=flags, threads=self.threads,
            )

    def forward(self, a: np.ndarray) -> np.ndarray:
        """rfft2 of real ``a`` (n0, n1) -> complex (n0, n1//2+1), unnormalised."""
        if self.backend == "numpy":
            return np.fft.rfft2(np.asarray(a, dtype=self.dtype))
        self._real[...] = a
        self._fwd.execute()
        return self._spec

    def backward(self, a_hat: np.ndarray) -> np.ndarray:
        """irfft2 of complex ``a_hat`` (n0, n1//2+1) -> real (n0, n1), divided by n0*n1."""
        if self.backend == "numpy":
            return np.fft.irfft2(a_hat, s=self.shape).astype(self.dtype, copy=False)
        # c2r transforms destroy their input, so FFTW always works on our copy.
        self._spec_in[...] = a_hat
        self._bwd.execute()
        self._real_out *= self.dtype.type(1.0 / (self.shape[0] * self.shape[1]))
        return self._real_out


@functools.lru_cache(maxsize=32)
def _cached_fft(shape: tuple[int, int], threads: int, backend: str, dtype: str = "float64") -> RealFFT2:
    return RealFFT2(shape, threads=threads, backend=backend, dtype=np.dtype(dtype))


def get_fft(shape: tuple[int, int], threads: int = 1, backend: str | None = None,
            dtype=np.float64) -> RealFFT2:
    """Cached :class:`RealFFT2` for ``shape``: plans are made once per shape and reused.

    The cache key is normalised (shape as ints, threads >= 1, the resolved backend name,
    the dtype's name), so every caller asking for the same transform shares one set of
    plans and buffers. A ``float64`` pair is keyed exactly as before single-precision
    pairs existed.
    """
    key = (tuple(int(s) for s in shape), max(1, int(threads)), backend or default_backend())
    name = np.dtype(dtype).name
    if name == "float64":
        return _cached_fft(*key)
    return _cached_fft(*key, name)


def wavenumbers(n: int, length: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Mode numbers of the rfft2 grid for an ``n x n`` periodic domain of side ``length``.

    Returns ``(kx, ky)`` broadcastable to ``(n, n//2+1)``, in cycles per ``length``
    (integers for ``length = 1``): ``kx`` along axis 0 (``fftfreq``), ``ky`` along
    axis 1 (``rfftfreq``). Multiply by ``2*pi/length`` for angular wavenumbers in
    rad per unit length.
    """
    kx = np.fft.fftfreq(n, d=1.0 / n)[:, None] / length
    ky = np.fft.rfftfreq(n, d=1.0 / n)[None, :] / length
    return kx, ky


def rfft_weights(n: int) -> np.ndarray:
    """Multiplicity of each rfft2 column in the full spectrum, shape ``(1, n//2+1)``.

    Columns 1..ceil(n/2)-1 stand for themselves and their Hermitian mirror (weight 2);
    column 0 and, for even ``n``, the Nyquist column have weight 1. Sums over the full
    spectrum are ``(w * x).sum()`` over the half spectrum.
    """
    w = np.full((1, n // 2 + 1), 2.0)
    w[0, 0] = 1.0
    if n % 2 == 0:
        w[0, -1] = 1.0
    return w
