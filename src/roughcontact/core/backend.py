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
import os

import numpy as np

from . import fft as _fft
from .fftw_library import fft_label
from .passes import remap, scatter_scaled, weighted_squares

#: Names the ``array_backend`` setting accepts.
ARRAY_BACKENDS = ("numpy", "cupy")


class SpectralProduct:
    """``y = F^-1[m F[x]]`` on an ``nx x ny`` grid with one plan pair and fixed buffers.

    The caller writes ``x`` with :meth:`load` (values on a set of nodes, zero elsewhere) or
    :meth:`load_dense` (a whole field), runs :meth:`forward` into its spectrum buffer and
    :meth:`backward` of that spectrum, and reads the result with :meth:`take` (at a set of nodes) or as
    the returned ``(nx, ny)`` array. A multiplier ``m`` (real, shape ``(nx, ny // 2 + 1)``, from
    :meth:`multiplier`) carries the ``1 / (nx ny)`` of the inverse transform, so the backward
    transform is unnormalised: two transforms and one pass over the half spectrum, nothing else.
    For grids whose ``nx ny`` is a power of two the result equals ``irfft2(m' rfft2(x))`` with
    ``m' = nx ny m`` up to the transforms' rounding (the scalings are exact).

    With pyFFTW and ``in_place`` both transforms work in the spectrum buffer (FFTW's r2c and c2r on
    the padded layout, rows of ``2 (ny // 2 + 1)`` reals): measured at N = 1024 on one core, a
    forward in place costs ~0.75-0.85 of one that preserves a separate input; the whole product
    with its sparse load and read-back 0.88 of the former with another process loading memory,
    1.03 on a quiet machine (docs/solver.md). Out of place, a separate input is kept, which
    the transform preserves, so a load writes only the nodes that change: the choice for an input
    that is mostly zero (the free operator's padded grid, 3/4 zero), and the default (``in_place``
    None) for grids without shipped plans, where FFTW_ESTIMATE's in-place pair cost ~1.1x its
    out-of-place one (960², measured). Node positions in the buffers' layout come from
    :meth:`positions`. :meth:`quadratic` gives ``x . (K x)`` (Parseval) from a spectrum alone, so
    a caller knows it before the inverse transform.
    """

    def __init__(self, backend: ArrayBackend, shape, dtype, threads: int = 1, in_place: bool | None = None):
        self.backend = backend
        self.shape = tuple(int(s) for s in shape)
        self.dtype = np.dtype(dtype)
        self.in_place = _fft.has_shipped_plans(self.shape) if in_place is None else in_place
        self.norm = 1.0 / (self.shape[0] * self.shape[1])
        self._plan = backend.product_plan(self, threads)
        self._square = None
        self._loaded = False  # an input waits for its forward transform

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

    def positions(self, idx):
        """Where the nodes of flat grid indices ``idx`` (int array) sit in the buffers' layout."""
        return self._plan.positions(idx)

    def load(self, pos, values, scale: float) -> None:
        """Input of :meth:`forward`: ``values * scale`` at :meth:`positions` ``pos``, 0 elsewhere.

        The product is taken in float64 for float64 ``values`` (the solver's) and rounded once to the product's
        precision. Loading the same ``pos`` array again writes only those nodes where the plan keeps its input.
        """
        plan = self._plan
        if (isinstance(plan, _FFTWProduct) and isinstance(values, np.ndarray) and isinstance(pos, np.ndarray)
                and values.dtype == np.float64 and values.ndim == pos.ndim == 1 and values.size == pos.size):
            scatter_scaled(plan.cleared(pos), pos, values, float(scale))  # (one pass, the same bits)
        else:
            plan.load(pos, np.multiply(values, scale, out=self.backend.xp.empty(values.shape, dtype=self.dtype),
                                       casting="unsafe"))
        self._loaded = True

    def load_dense(self, field, scale: float) -> None:
        """Input of :meth:`forward`: ``field * scale`` in its top-left corner, 0 elsewhere."""
        self._plan.load_dense(field, scale)
        self._loaded = True

    def forward(self):
        """``F[x]`` of the loaded input (the spectrum buffer, overwritten by the next product).

        Each forward transform needs its own load: the transforms may work in place.
        """
        if not self._loaded:
            raise ValueError("SpectralProduct.forward(): load the input first (the transform "
                             "may have overwritten the last one)")
        self._loaded = False
        return self._plan.forward()

    def quadratic(self, spec, weights) -> float:
        """``sum(weights * |spec|^2)``: ``x . (K x)`` for ``spec = F[x]`` and :meth:`quadratic_weights` of K.

        Single-precision terms, pairwise summation (relative error ~1e-7, as the products'); on the host in
        one pass (:func:`~.passes.weighted_squares`, the same bits).
        """
        view = spec.view(weights.dtype).reshape(weights.shape)
        if (self.backend.xp is np and view.dtype == np.float32 and weights.dtype == np.float32
                and view.flags.c_contiguous and weights.flags.c_contiguous):
            return weighted_squares(view, weights)
        if self._square is None:
            self._square = self.backend.xp.empty(weights.shape, dtype=weights.dtype)
        np.multiply(view, view, out=self._square)
        np.multiply(self._square, weights, out=self._square)
        return float(self._square.sum())

    def backward(self, spec, mult):
        """``F^-1[mult spec]`` for ``spec`` from :meth:`forward` (destroyed): an ``(nx, ny)`` array
        (maybe a strided view) that the next load or product overwrites."""
        return self._plan.backward(spec, mult)

    def take(self, real, pos, out) -> None:
        """``out[:] =`` :meth:`backward`'s ``real`` at the :meth:`positions` ``pos`` (cast to ``out``'s dtype)."""
        self._plan.take(real, pos, out)

    def __call__(self, mult):
        """``F^-1[mult F[x]]`` of the loaded input: as :meth:`backward`."""
        return self._plan.backward(self.forward(), mult)


def multiply_spectrum(spec, mult):
    """``spec * mult``, in place when ``mult`` (an interleaved ``(re, im)`` real multiplier) has
    the spectrum's precision; a new array when numpy.fft < 2 has transformed in double."""
    if spec.dtype.itemsize != 2 * mult.dtype.itemsize:
        return spec * mult[..., 0]
    view = spec.view(mult.dtype).reshape(mult.shape)
    np.multiply(view, mult, out=view)
    return spec


class _FFTWProduct:
    """The pyFFTW plans of a :class:`SpectralProduct`: an r2c into the spectrum buffer, a c2r out of it.

    In place (``prod.in_place``): the buffer is complex ``(n0, n1 // 2 + 1)`` and its
    real view ``(n0, n1)`` (rows padded to ``2 (n1 // 2 + 1)`` reals) holds the input before the
    forward transform and the output after the inverse; a transform destroys the input, so every
    load zeroes the buffer first. Out of place: a real input of its own, which the r2c
    keeps, so a load at the same positions as the last one writes only those nodes (a new
    set first zeroes the old one's nodes): the cheaper choice where the input is mostly zero, as on
    the free operator's padded grid.
    """

    def __init__(self, shape, dtype, in_place: bool, threads: int):
        pyfftw = _fft.pyfftw
        n0, n1 = shape
        cdtype = np.result_type(dtype, np.complex64)
        self.spec = pyfftw.empty_aligned((n0, n1 // 2 + 1), dtype=cdtype)
        self.in_place = in_place
        if self.in_place:
            self.n1, self.row = n1, 2 * (n1 // 2 + 1)
            self.input = self.spec.view(dtype)[:, :n1]
            self.flat = self.spec.view(dtype).reshape(-1)
            self.spec.fill(0.0)
            self.out, self.out_flat = self.input, self.flat
        else:
            self.n1 = self.row = n1
            self.input = pyfftw.zeros_aligned(shape, dtype=dtype)
            self.flat = self.input.reshape(-1)
            self.out = pyfftw.empty_aligned(shape, dtype=dtype)
            self.out_flat = self.out.reshape(-1)
        self.last = None  # out of place: the last load's positions (True: dense)
        with _fft.shipped_wisdom_only():
            self.fwd = pyfftw.FFTW(self.input, self.spec, axes=(0, 1), direction="FFTW_FORWARD",
                                   flags=_fft.PLANNER_FLAGS, threads=threads)
            self.bwd = pyfftw.FFTW(self.spec, self.out, axes=(0, 1), direction="FFTW_BACKWARD",
                                   flags=_fft.PLANNER_FLAGS, threads=threads)

    def positions(self, idx):
        return remap_rows(idx, self.n1, self.row)

    def cleared(self, pos):
        """The flat input, zero but where ``pos`` (the next load's positions) will be written."""
        flat, last = self.flat, self.last
        if self.in_place or last is True:
            flat.fill(0.0)
        elif last is not None and last is not pos:
            flat[last] = 0.0
        self.last = pos
        return flat

    def load(self, pos, values):
        self.cleared(pos)[pos] = values

    def load_dense(self, field, scale):
        real = self.input
        fx, fy = field.shape
        if (fx, fy) != real.shape:
            real.fill(0.0)
        np.multiply(field, scale, out=real[:fx, :fy], casting="unsafe")
        self.last = True

    def forward(self):
        self.fwd.execute()
        return self.spec

    def backward(self, spec, mult):
        if spec is not self.spec:
            raise ValueError("SpectralProduct.backward takes the spectrum of its own forward transform")
        multiply_spectrum(spec, mult)
        self.bwd.execute()  # unnormalised: 1 / (n0 n1) is in mult
        return self.out

    def take(self, real, pos, out):
        take_into(self.out_flat, pos, out)  # ``real`` is this plan's output


#: Grids of at most this many nodes share their products' plans and buffers within a process
#: (:func:`fftw_product`); larger ones plan their own, whose ~10 ms is nothing beside their solve, and free
#: their buffers with it (16 kept products of 512² hold ~100 MiB at most).
SHARED_PLAN_NODES = 512 * 512


@functools.lru_cache(maxsize=16)
def fftw_product(shape: tuple, dtype, in_place: bool, threads: int) -> _FFTWProduct:
    """The pyFFTW plans and buffers of a :class:`SpectralProduct`, made once per process for each shape,
    precision, layout and thread count (the 16 most recent kept; grids up to :data:`SHARED_PLAN_NODES`).

    Planning runs inside :func:`~.fft.shipped_wisdom_only`, whose swap of FFTW's wisdom costs ~9-10 ms of CPU
    whatever the size (measured 2026-12-03): a periodic solve made two products (four plans) and paid two
    swaps, a free one three or four. Every product of one kind then shares the buffers, like the solver's
    other FFTs (the package's note: two solves of one size must not run concurrently in threads of one
    process). Sharing is safe where each product's load, transforms and read-back run in one sequence before
    another product of its kind is loaded, as in the solver; interleaving two (loading one, then the other,
    then transforming the first) would transform the other's input without an error. The plans are those
    the shipped wisdom gives, so the results are the same bit for bit.
    """
    return _FFTWProduct(shape, np.dtype(dtype), in_place, threads)


class _ArrayModuleProduct:
    """The product with an array module's own FFT (numpy.fft, cupy.fft), unnormalised both ways.

    One input array, kept by the transforms: a load at the same positions as the last one writes
    only those nodes; a load at new positions first zeroes the old ones (a dense load, the whole
    input).
    """

    def __init__(self, prod: SpectralProduct, xp):
        self.prod, self.fft = prod, xp.fft
        self.cdtype = np.result_type(prod.dtype, np.complex64)
        self.input = xp.zeros(prod.shape, dtype=prod.dtype)
        self.flat = self.input.reshape(-1)
        self.pos, self.full = None, False

    def positions(self, idx):
        return idx

    def load(self, pos, values):
        if self.pos is not pos:
            if self.full:
                self.flat.fill(0.0)
            elif self.pos is not None:
                self.flat[self.pos] = 0.0
            self.pos, self.full = pos, False
        self.flat[pos] = values

    def load_dense(self, field, scale):
        fx, fy = field.shape
        if (fx, fy) != self.input.shape:
            self.input.fill(0.0)
        np.multiply(field, scale, out=self.input[:fx, :fy], casting="unsafe")
        self.pos, self.full = None, True

    def forward(self):
        spec = self.fft.rfft2(self.input)
        return spec if spec.dtype == self.cdtype else spec.astype(self.cdtype)  # numpy.fft < 2: double

    def backward(self, spec, mult):
        out = self.fft.irfft2(multiply_spectrum(spec, mult), s=self.prod.shape, norm="forward")
        return out.astype(self.prod.dtype, copy=False)

    def take(self, real, pos, out):
        take_into(real.reshape(-1), pos, out)


def remap_rows(idx, n1: int, row: int):
    """Flat indices ``idx`` of a grid with rows of ``n1`` as flat indices with rows of ``row >= n1``."""
    if row == n1:
        return idx
    if isinstance(idx, np.ndarray) and idx.ndim == 1 and idx.dtype.kind == "i":
        return remap(idx, n1, row)  # (one pass where numpy made four, each with its temporary)
    return (idx // n1) * row + idx % n1


def take_into(flat, pos, out) -> None:
    """``out[:] = flat[pos]``, converting to ``out``'s dtype (float32 into float64, say)."""
    if flat.dtype == out.dtype:
        np.take(flat, pos, out=out)
    else:
        out[...] = np.take(flat, pos)


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
        """The FFT library's name, for the outputs' ``fft_backend`` attribute (:func:`fft_label`)."""
        return fft_label(_fft.default_backend())

    def real_fft(self, shape, threads: int = 1, dtype=np.float64):
        """The cached FFT pair of :mod:`.fft` for ``shape`` (forward / backward, numpy's norms)."""
        if threads == 1:
            return _fft.get_fft(tuple(shape), backend=None, dtype=dtype)
        return _fft.get_fft(tuple(shape), threads=threads, dtype=dtype)

    def product_plan(self, prod: SpectralProduct, threads: int):
        if _fft.default_backend() == "pyfftw":
            if prod.shape[0] * prod.shape[1] <= SHARED_PLAN_NODES:
                return fftw_product(prod.shape, prod.dtype, prod.in_place, threads)
            return _FFTWProduct(prod.shape, prod.dtype, prod.in_place, threads)
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


def default_cupy_cache() -> str:
    """Where CuPy caches compiled kernels unless ``CUPY_CACHE_DIR`` says otherwise:
    ``$XDG_CACHE_HOME/roughcontact/cupy`` (``~/.cache/roughcontact/cupy``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "roughcontact", "cupy")


@functools.cache
def get_backend(name: str = "numpy") -> ArrayBackend:
    """The backend called ``name`` (one of :data:`ARRAY_BACKENDS`).

    Raises ``ValueError`` naming the remedy when ``name`` is unknown or CuPy cannot run here.
    """
    if name == "numpy":
        return ArrayBackend()
    if name != "cupy":
        raise ValueError(f"array_backend must be one of {ARRAY_BACKENDS}, got {name!r}")
    # compiled kernels on disk, so that a fresh process loads them instead of compiling (CuPy reads
    # the variable when it compiles); a path the caller set is kept
    os.environ.setdefault("CUPY_CACHE_DIR", default_cupy_cache())
    try:
        cp = importlib.import_module("cupy")
        cp.cuda.runtime.getDeviceCount()
    except Exception as exc:  # ImportError, or CUDA's own error without a device or driver
        raise ValueError(
            f"array_backend 'cupy' needs CuPy and a CUDA GPU ({type(exc).__name__}: {exc}); install "
            "it with `pip install roughcontact[gpu]` on a machine with a GPU, or set array_backend "
            "to 'numpy'") from exc
    return CupyBackend(cp)

