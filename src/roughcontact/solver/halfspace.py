"""The elastic half-space: the operator ``K`` from pressure to displacement.

Grids are ``(nx, ny)`` (axis 0 = x, axis 1 = y; an int ``n`` means ``(n, n)``) on a cell of
sides ``Lx x Ly``, pixels ``dx = Lx / nx`` and ``dy = Ly / ny``. A grid of one row ``(n, 1)`` is a
profile (:meth:`roughcontact.core.cell.Cell.profile`): the surface is the same along y (plane
strain); the periodic operator is then ``2 / (E* |q|)`` with ``|q| = 2 pi |mx| / L`` (the 2-D
kernel at ``qy = 0``), and the free one convolves with the plane-strain strip
(:func:`~.love.line_influence`), so one code serves maps and profiles. Internally ``E* = Lx = 1``:
the operators take the cell's ``aspect`` ``Ly / Lx`` (1 for a square cell), and the physical
operator is ``Lx / E*`` times the internal one.

:class:`PeriodicHalfSpace` is the periodic FFT-BEM operator
``u(q) = 2 p(q) / (E* |q|)``, ``|q| = 2 pi sqrt((mx / Lx)^2 + (my / Ly)^2)`` with integer
mode numbers ``mx``, ``my``, with its Fourier preconditioner ``M = |q| E* / 2`` (``K``'s
inverse off ``q = 0``) and single-precision variants of both products: whole fields
(``apply32``), fields given on a set of nodes and zero elsewhere (``apply_inverse32_on``: only
those nodes are written into the transform's input), or split into a forward transform
(``spectrum32_on``), Parseval's ``x . K x`` (``quadratic32``) and the inverse
(``displacement32``), so that the iteration can combine spectra before one inverse.
The fields live on an array backend (:mod:`roughcontact.core.backend`: numpy, or CuPy on a GPU).

:class:`FreeHalfSpace` is the free-boundary (non-periodic) operator with the same
methods: the ``nx x ny`` pressure, uniform on each ``dx x dy`` pixel, is
zero-padded to at least ``2nx x 2ny`` (:func:`padded_shape`) and convolved by FFT with Love's influence function of
one pixel sampled at wrap-around distances (:func:`free_influence`; Hockney's
construction, as ContactMechanics' ``FreeFFTElasticHalfSpace``); the ``nx x ny``
corner of the result is the exact displacement of the infinite half-space under
that pressure, with no periodic images. Its preconditioner is the periodic
``M = |q| E* / 2`` on the ``nx x ny`` cell (an approximate inverse now), or on a slightly larger
cell where a side is slow for FFTW (:func:`preconditioner_shape`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.backend import ArrayBackend, SpectralProduct, get_backend, multiply_spectrum, remap_rows
from ..core.cell import Cell
from ..core.fft import default_backend, get_fft, wavenumbers
from ..core.fftw_library import fft_label
from .love import (  # noqa: F401 (re-exported: the free operator's influence lives in love)
    free_influence,
    free_multiplier,
    padded_fft,
    padded_shape,
    pixel_influence,
    pixel_influence_rect,
    pixel_influence_square,
    preconditioner_shape,
)
from .units import frexp_ratio, grid, internal_length
from .validation import check_positive, validate_boundary, validate_heights, validate_length, validate_threads


def plans(shape, threads: int):
    """The cached FFT pair for an ``nx x ny`` grid (``shape`` an int ``n`` or ``(nx, ny)``).

    ``get_fft`` is an ``lru_cache`` keyed on the literal arguments; for one
    thread this is the same call as :func:`roughcontact.surfaces.synthetic.generate_surface`
    makes, so both share one set of plans and buffers (33 MB at n = 1024).
    """
    if threads == 1:
        return get_fft(grid(shape), backend=None)
    return get_fft(grid(shape), threads=threads)


def elastic_kernel(shape, e_star: float = 1.0, length=1.0) -> np.ndarray:
    """Fourier multiplier from pressure to displacement on the rfft2 grid.

    Parameters
    ----------
    shape : int or (int, int)
        Grid points ``(nx, ny)``; an int ``n`` means ``(n, n)``.
    e_star : float
        Plane-strain modulus E* [pressure].
    length : float or (float, float)
        Sides ``(Lx, Ly)`` of the periodic cell [length]; a float ``L`` means ``(L, L)``.

    Returns
    -------
    numpy.ndarray, float64, shape (nx, ny//2+1)
        ``2 / (E* |q|)`` [length / pressure] with
        ``|q| = 2 pi sqrt((mx / Lx)^2 + (my / Ly)^2)`` for integer mode numbers ``mx``,
        ``my`` (:func:`roughcontact.core.fft.wavenumbers`); the ``q = 0`` entry is 0 (the
        mean displacement is absorbed by the rigid-body approach).
    """
    kx, ky = wavenumbers(shape, length)
    q = 2.0 * np.pi * np.hypot(kx, ky)
    out = np.zeros_like(q)
    np.divide(2.0 / e_star, q, out=out, where=q > 0)
    return out


def inverse_kernel(shape, e_star: float, length) -> np.ndarray:
    """``M = E* |q| / 2`` on the rfft2 grid of ``shape`` [pressure / length], 0 at ``q = 0``."""
    kx, ky = wavenumbers(shape, length)
    return 0.5 * e_star * 2.0 * np.pi * np.hypot(kx, ky)


def displacement(pressure: np.ndarray, *, e_star: float = 1.0, length=1.0,
                 threads: int = 1, boundary: str = "periodic") -> np.ndarray:
    """Surface displacement of the elastic half-space under a pressure field.

    Parameters
    ----------
    pressure : array_like, shape (nx, ny)
        Nodal pressure [pressure]; square ``(n, n)`` unless ``length`` is a pair.
    e_star, length, threads, boundary
        As in :func:`solve_contact` (``length`` a float ``L`` or a pair ``(Lx, Ly)``).

    Returns
    -------
    numpy.ndarray, float64, shape (nx, ny)
        Displacement ``u`` into the half-space [length]: zero mean for the
        periodic half-space; for ``boundary="free"`` the displacement of the
        infinite half-space loaded by ``pressure`` on the patch alone (zero far
        away), each node's pressure uniform over its ``dx x dy`` pixel.

    Raises
    ------
    ValueError
        For invalid input, or when ``u`` is not representable in float64.
    """
    p = validate_heights(pressure, name="pressure", square=False)
    e_star = check_positive("e_star", e_star)
    length = validate_length(length, p.shape, "pressure")
    boundary = validate_boundary(boundary)
    threads = validate_threads(threads)
    cell = Cell.of(p.shape, length)
    aspect = cell.aspect
    # u = (Lx / E*) K_1 p with K_1 the kernel for E* = Lx = 1; the factor is applied
    # as mantissa and exponent so that no intermediate overflows.
    pm = float(np.max(np.abs(p))) if p.size else 0.0
    if pm == 0.0:
        return np.zeros_like(p)
    ep = math.frexp(pm)[1]
    if boundary == "free":
        u = FreeHalfSpace(p.shape, threads, aspect).apply(np.ldexp(p, -ep)).copy()
    else:
        fft = plans(p.shape, threads)
        kern = elastic_kernel(p.shape, 1.0, internal_length(aspect))
        u = fft.backward(fft.forward(np.ldexp(p, -ep)) * kern).copy()
    fm, fe = frexp_ratio((cell.side_x,), (e_star,))
    with np.errstate(over="ignore", under="ignore"):
        u = np.ldexp(u * fm, fe + ep)
    if not np.all(np.isfinite(u)):
        raise ValueError("displacement: u = K p overflows float64 for this pressure, e_star and length "
                         f"(max |p| * length / e_star must stay below ~1e300; got max |p| = {pm!r}, "
                         f"e_star = {e_star!r}, length = {length!r})")
    return u


class SparseLoad:
    """Loads of values on a set of grid nodes into a :class:`SpectralProduct`, zero elsewhere.

    ``index`` maps the flat indices of the ``nx x ny`` grid to flat indices of the product's grid
    (None: the same; the free operator's is padded). The nodes' positions in the product's buffers
    are computed once per index array (the solver passes the same array while its set does not
    change) and serve both the load and the read-back (:meth:`take`).
    """

    def __init__(self, prod, index=None):
        self.prod, self.index = prod, index
        self.idx, self.pos = None, None

    def positions(self, idx):
        """The buffers' positions of the grid nodes ``idx``, cached for the same array."""
        if self.idx is not idx:
            self.idx = idx
            self.pos = self.prod.positions(idx if self.index is None else self.index(idx))
        return self.pos

    def load(self, idx, values, scale: float) -> None:
        """``input[idx] = values * scale`` (rounded to the input's precision), zero elsewhere."""
        self.prod.load(self.positions(idx), values, scale)

    def take(self, real, idx, out) -> None:
        """``out[:] = real[idx]`` for a product's result ``real`` (grid nodes ``idx``, cast to ``out``)."""
        self.prod.take(real, self.positions(idx), out)


class PeriodicHalfSpace:
    """Periodic elastic half-space on an ``nx x ny`` grid in internal units (``E* = Lx = 1``).

    Parameters
    ----------
    shape : int or (int, int)
        Grid points ``(nx, ny)``; an int ``n`` means ``(n, n)``.
    threads : int
        FFTW threads.
    aspect : float
        ``Ly / Lx`` of the cell (1 for a square cell): its y side in internal units.
    backend : ArrayBackend, optional
        Where the fields live (:mod:`roughcontact.core.backend`; default numpy + pyFFTW).
    patch : int or (int, int), optional
        The ``(px, py)`` corner of the grid that the fields cover (default the whole grid): inputs
        are given on the patch (flat indices of a ``px x py`` grid, ``aspect`` its ``Ly / Lx``),
        zero elsewhere on the periodic ``nx x ny`` cell of the same spacing, and results are the
        patch's corner. :class:`FreeHalfSpace` runs its preconditioner so on a fast FFT grid.

    Every product returns a view of an FFT buffer that the next transform of
    the same precision overwrites (copy it to keep it).
    """

    def __init__(self, shape, threads: int = 1, aspect: float = 1.0, backend: ArrayBackend | None = None,
                 patch=None):
        self.shape = grid(shape)
        self.patch = px, py = self.shape if patch is None else grid(patch)
        self.whole = self.patch == self.shape
        self.be = backend or get_backend()
        self.threads = threads
        # the cell of the grid at the patch's spacing, in units of the patch's Lx
        if self.shape[1] == 1:  # a profile (Cell.profile): plane strain, no y side
            length = self.shape[0] / px
        else:
            length = internal_length(aspect) if self.whole else (self.shape[0] / px, aspect * self.shape[1] / py)
        self.kern = elastic_kernel(self.shape, 1.0, length)
        # the float64 products, in place like the float32 ones
        self.prod64 = SpectralProduct(self.be, self.shape, np.float64, threads)
        self.kmult64 = self.prod64.multiplier(self.kern)
        self._mmult64 = None
        self.prod32 = None

    @property
    def backend(self) -> str:
        return self.be.fft_name()

    def apply(self, field: np.ndarray) -> np.ndarray:
        """``K field`` [length per pressure x field], float64, shape (nx, ny), maybe a strided view of
        a buffer that the next float64 product overwrites."""
        self.prod64.load_dense(field, 1.0)
        return self._on_patch(self.prod64(self.kmult64))

    def _on_patch(self, result):
        """The patch's corner of a product's ``result`` (the result itself without a patch)."""
        px, py = self.patch
        return result[:px, :py]

    def _inverse_host(self) -> np.ndarray:
        """``M = 1 / K`` off ``q = 0`` (0 there), float64 on the host, shape (nx, ny//2+1)."""
        minv = np.zeros_like(self.kern)
        np.divide(1.0, self.kern, out=minv, where=self.kern > 0)
        return minv

    def apply_inverse(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with ``M = |q| E* / 2`` (0 at ``q = 0``), float64 (as :meth:`apply`'s result)."""
        if self._mmult64 is None:
            self._mmult64 = self.prod64.multiplier(self._inverse_host())
        self.prod64.load_dense(field, 1.0)
        return self._on_patch(self.prod64(self._mmult64))

    def single(self, sigma: float) -> None:
        """Make the float32 product and multipliers; inputs are divided by ``sigma``.

        Dividing by a scale of the problem (the internal rms height) before the
        cast makes the float32 values independent of the problem's units, up to
        values within round-off of a float32 rounding boundary.
        """
        if self.prod32 is not None:
            return
        self.prod32 = prod = SpectralProduct(self.be, self.shape, np.float32, self.threads)
        self.kmult32 = prod.multiplier(self.kern)
        self.kquad32 = prod.quadratic_weights(self.kern)
        self.mmult32 = prod.multiplier(self._inverse_host())
        self.loader = SparseLoad(prod, None if self.whole else self._grid_index)
        self.sigma = sigma
        self.inv_sigma = 1.0 / sigma

    def spectrum32_on(self, idx, values):
        """The float32 spectrum of ``x / sigma``, ``x`` = ``values`` at flat ``idx`` and 0 elsewhere.

        One forward transform into the product's spectrum buffer
        (:class:`~roughcontact.core.backend.SpectralProduct`), which the next product overwrites.
        """
        self.loader.load(idx, values, self.inv_sigma)
        return self.prod32.forward()

    def quadratic32(self, spec) -> float:
        """``x . (K x) / sigma^2`` from :meth:`spectrum32_on`'s spectrum of ``x`` (Parseval)."""
        return self.prod32.quadratic(spec, self.kquad32)

    def displacement32(self, spec) -> np.ndarray:
        """``K x / sigma`` from :meth:`spectrum32_on`'s spectrum of ``x / sigma`` (destroyed).

        A float32 ``(nx, ny)`` array, maybe a strided view of a buffer that the next product overwrites.
        """
        return self._on_patch(self.prod32.backward(spec, self.kmult32))

    def _grid_index(self, idx):
        """Flat indices of the patch as flat indices of the grid."""
        return remap_rows(idx, self.patch[1], self.shape[1])

    def apply_inverse32_on(self, idx, values, out) -> np.ndarray:
        """``M x / sigma`` at the nodes ``idx`` in single precision, ``x`` = ``values`` there and 0 elsewhere.

        Only the nodes of ``idx`` are written into the transform's input and read from its output
        (two transforms and one pass over the half spectrum in all); the result goes into ``out``
        (shape of ``values``, any float dtype), which is returned.
        """
        self.loader.load(idx, values, self.inv_sigma)
        self.loader.take(self.prod32(self.mmult32), idx, out)
        return out

    def apply32(self, field: np.ndarray) -> np.ndarray:
        """``K field / sigma`` with single-precision transforms (float32 ``(nx, ny)``, maybe a view of a buffer)."""
        self.prod32.load_dense(field, self.inv_sigma)
        return self._on_patch(self.prod32(self.kmult32))

    def apply_inverse32(self, field: np.ndarray) -> np.ndarray:
        """``M field / sigma`` with single-precision transforms (float32 ``(nx, ny)``, maybe a view of a buffer)."""
        self.prod32.load_dense(field, self.inv_sigma)
        return self._on_patch(self.prod32(self.mmult32))


class FreeHalfSpace:
    """Free-boundary elastic half-space on an ``nx x ny`` patch in internal units (``E* = Lx = 1``).

    Same methods and parameters as :class:`PeriodicHalfSpace`. ``K`` is the
    zero-padded (Hockney) convolution with :func:`free_influence`: one FFT pair on
    :func:`padded_shape` (``2nx x 2ny`` or the next fast even lengths) per product; the
    displacement is that of the infinite half-space (not zero mean). ``M`` is the periodic preconditioner
    ``|q| E* / 2`` on the ``nx x ny`` cell, or on a slightly larger cell of the same spacing
    where a side is slow for FFTW (:func:`preconditioner_shape`, the patch in its corner): an
    approximate inverse of this ``K`` (the CG stays exact with it).

    Every product returns a buffer that the next product of the same kind and
    precision overwrites (copy it to keep it).
    """

    def __init__(self, shape, threads: int = 1, aspect: float = 1.0, backend: ArrayBackend | None = None):
        self.shape = grid(shape)
        self.be = be = backend or get_backend()
        self.threads, self.aspect = threads, aspect
        self.padded = padded_shape(self.shape)
        if be.name == "numpy":
            self.fft = padded_fft(self.shape, threads, default_backend(), "float64")  # the name: a cache key
        else:
            self.fft = be.real_fft(self.padded)
        self.kern2 = be.asarray(free_multiplier(self.shape, aspect))
        mx, my = self.padded
        self.norm = 1.0 / (mx * my)
        self.out = be.xp.empty(self.shape)
        self.pad = None if self.fft.backend == "pyfftw" else be.xp.zeros((mx, my))
        self.precond = PeriodicHalfSpace(preconditioner_shape(self.shape), threads, aspect, be, patch=self.shape)
        self.prod32 = None

    @property
    def backend(self) -> str:
        return fft_label(self.fft.backend)

    def apply(self, field: np.ndarray) -> np.ndarray:
        """``K field`` [length per pressure x field], float64, shape (nx, ny)."""
        nx, ny = self.shape
        fft = self.fft
        if fft.backend == "pyfftw":
            np.copyto(fft._real[:nx, :ny], field)
            fft._fwd.execute()
            view = fft._spec.view(self.kern2.dtype).reshape(self.kern2.shape)
            np.multiply(view, self.kern2, out=fft._spec_in.view(self.kern2.dtype).reshape(self.kern2.shape))
            fft._bwd.execute()  # c2r: unnormalised, the normalisation goes with the copy
            return np.multiply(fft._real_out[:nx, :ny], self.norm, out=self.out)
        self.pad[:nx, :ny] = field
        spec = multiply_spectrum(fft.forward(self.pad), self.kern2)
        self.out[...] = fft.backward(spec)[:nx, :ny]
        return self.out

    def apply_inverse(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with the periodic ``M = |q| E* / 2`` (0 at ``q = 0``), float64."""
        return self.precond.apply_inverse(field)

    def single(self, sigma: float) -> None:
        """Make the float32 product and multiplier; inputs are divided by ``sigma``."""
        if self.prod32 is not None:
            return
        self.precond.single(sigma)
        # out of place: the padded input is 3/4 zero and kept between loads (an in-place transform
        # would need the whole padded buffer zeroed before each load)
        self.prod32 = prod = SpectralProduct(self.be, self.padded, np.float32, self.threads, in_place=False)
        mult = free_multiplier(self.shape, self.aspect)[..., 0]
        self.kmult32 = prod.multiplier(mult)
        self.kquad32 = prod.quadratic_weights(mult)  # Parseval on the padded grid: x is 0 off the patch
        self.loader = SparseLoad(prod, self._padded_index)
        self.out32 = self.be.xp.empty(self.shape, dtype=np.float32)
        self.sigma = sigma
        self.inv_sigma = 1.0 / sigma

    def spectrum32_on(self, idx, values):
        """The float32 spectrum of the padded ``x / sigma`` (as :meth:`PeriodicHalfSpace.spectrum32_on`)."""
        self.loader.load(idx, values, self.inv_sigma)
        return self.prod32.forward()

    def quadratic32(self, spec) -> float:
        """``x . (K x) / sigma^2`` from :meth:`spectrum32_on`'s spectrum of ``x`` (Parseval)."""
        return self.prod32.quadratic(spec, self.kquad32)

    def displacement32(self, spec) -> np.ndarray:
        """``K x / sigma`` on the patch from :meth:`spectrum32_on`'s spectrum (destroyed); float32 ``(nx, ny)``."""
        nx, ny = self.shape
        self.out32[...] = self.prod32.backward(spec, self.kmult32)[:nx, :ny]
        return self.out32

    def _padded_index(self, idx):
        """Flat indices of the ``nx x ny`` grid as flat indices of the padded grid."""
        return remap_rows(idx, self.shape[1], self.padded[1])

    def apply_inverse32_on(self, idx, values, out) -> np.ndarray:
        """``M x / sigma`` at the nodes ``idx`` in single precision (the periodic preconditioner's), into ``out``."""
        return self.precond.apply_inverse32_on(idx, values, out)

    def apply32(self, field: np.ndarray) -> np.ndarray:
        """``K field / sigma`` with single-precision transforms (float32 buffer)."""
        self.prod32.load_dense(field, self.inv_sigma)
        return self.displacement32(self.prod32.forward())

    def apply_inverse32(self, field: np.ndarray) -> np.ndarray:
        """``M field / sigma`` with single-precision transforms (float32 buffer)."""
        return self.precond.apply_inverse32(field)


def half_space(boundary: str, shape, threads: int = 1, aspect: float = 1.0, backend: ArrayBackend | None = None):
    """The operator for ``boundary`` (one of :data:`BOUNDARIES`) on an ``nx x ny`` grid.

    ``shape`` an int ``n`` or ``(nx, ny)``; ``aspect`` the cell's ``Ly / Lx`` (internal units ``Lx = 1``);
    ``backend`` where its fields live (default numpy + pyFFTW).
    """
    cls = FreeHalfSpace if boundary == "free" else PeriodicHalfSpace
    return cls(shape, threads, aspect, backend)
