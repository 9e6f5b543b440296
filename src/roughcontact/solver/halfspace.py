"""The elastic half-space: the operator ``K`` from pressure to displacement.

Grids are ``(nx, ny)`` (axis 0 = x, axis 1 = y; an int ``n`` means ``(n, n)``) on a cell of
sides ``Lx x Ly``, pixels ``dx = Lx / nx`` and ``dy = Ly / ny``. Internally ``E* = Lx = 1``:
the operators take the cell's ``aspect`` ``Ly / Lx`` (1 for a square cell), and the physical
operator is ``Lx / E*`` times the internal one.

:class:`PeriodicHalfSpace` is the periodic FFT-BEM operator
``u(q) = 2 p(q) / (E* |q|)``, ``|q| = 2 pi sqrt((mx / Lx)^2 + (my / Ly)^2)`` with integer
mode numbers ``mx``, ``my``, with its Fourier preconditioner ``M = |q| E* / 2`` (``K``'s
inverse off ``q = 0``) and single-precision variants of both products.

:class:`FreeHalfSpace` is the free-boundary (non-periodic) operator with the same
methods: the ``nx x ny`` pressure, uniform on each ``dx x dy`` pixel, is
zero-padded to at least ``2nx x 2ny`` (:func:`padded_shape`) and convolved by FFT with Love's influence function of
one pixel sampled at wrap-around distances (:func:`free_influence`; Hockney's
construction, as ContactMechanics' ``FreeFFTElasticHalfSpace``); the ``nx x ny``
corner of the result is the exact displacement of the infinite half-space under
that pressure, with no periodic images. Its preconditioner is the periodic
``M = |q| E* / 2`` on the ``nx x ny`` cell (an approximate inverse now).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..core.fft import RealFFT2, get_fft, wavenumbers
from .units import cell_aspect, frexp_ratio, side_x
from .validation import check_positive, validate_boundary, validate_heights, validate_length, validate_threads


def grid(shape) -> tuple[int, int]:
    """``(nx, ny)`` of a grid given as an int ``n`` (square, ``(n, n)``) or a pair."""
    if np.ndim(shape) == 0:
        return int(shape), int(shape)
    nx, ny = shape
    return int(nx), int(ny)


def internal_length(aspect: float):
    """The cell's ``length`` in internal units ``Lx = 1``: ``1.0`` when square, else ``(1.0, aspect)``."""
    return 1.0 if aspect == 1.0 else (1.0, aspect)


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
    aspect = cell_aspect(length)
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
    fm, fe = frexp_ratio((side_x(length),), (e_star,))
    with np.errstate(over="ignore", under="ignore"):
        u = np.ldexp(u * fm, fe + ep)
    if not np.all(np.isfinite(u)):
        raise ValueError("displacement: u = K p overflows float64 for this pressure, e_star and length "
                         f"(max |p| * length / e_star must stay below ~1e300; got max |p| = {pm!r}, "
                         f"e_star = {e_star!r}, length = {length!r})")
    return u


def _asinh_diff(a: np.ndarray, b: np.ndarray, a_minus_b: np.ndarray) -> np.ndarray:
    """``asinh(a) - asinh(b)`` without cancellation, given ``a - b`` exactly.

    ``sinh(asinh a - asinh b) = a sqrt(1 + b^2) - b sqrt(1 + a^2)``; for ``a`` and
    ``b`` of one sign that difference is rewritten as
    ``(a - b)(a + b) / (a sqrt(1 + b^2) + b sqrt(1 + a^2))``.
    """
    sa, sb = np.sqrt(1.0 + a * a), np.sqrt(1.0 + b * b)
    same = a * b > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        arg = np.where(same, a_minus_b * (a + b) / (a * sb + b * sa), a * sb - b * sa)
    return np.arcsinh(arg)


@functools.lru_cache(maxsize=4)
def _pixel_influence(n: int) -> np.ndarray:
    """Love's pixel influence ``pi * u`` at node offsets ``0..n`` (both axes), ``dx = E* = 1``.

    The displacement at offset ``(x, y)`` (in pixels) from the centre of a pixel
    of side 1 under unit pressure is ``1 / pi`` times the integral of ``1 / r``
    over the pixel, i.e. the mixed difference of
    ``F(X, Y) = X ln(Y + r) + Y ln(X + r)`` over the corners ``X = x +- 1/2``,
    ``Y = y +- 1/2`` (Love 1929, uniform pressure on a rectangle; Johnson 1985, ch. 3). With
    ``ln(Y + r) = asinh(Y / |X|) + ln|X|`` the ``X ln|X|`` terms cancel, and
    the remaining differences of ``asinh`` are formed without cancellation
    (:func:`_asinh_diff`): relative error ~1e-16 times the offset in pixels.
    """
    i = np.arange(n + 1, dtype=np.float64)
    x, y = i[:, None], i[None, :]
    xp, xm, yp, ym = x + 0.5, x - 0.5, y + 0.5, y - 0.5  # xm = ym = -1/2 at offset 0
    axm, aym = np.abs(xm), np.abs(ym)
    # pi u = [X (asinh(Y+/|X|) - asinh(Y-/|X|))] over X = x+1/2 minus X = x-1/2, plus the
    # same with X and Y swapped; Y+ - Y- = 1, so the asinh arguments differ by 1/|X|
    part_x = xp * _asinh_diff(yp / xp, ym / xp, 1.0 / xp) - xm * _asinh_diff(yp / axm, ym / axm, 1.0 / axm)
    part_y = yp * _asinh_diff(xp / yp, xm / yp, 1.0 / yp) - ym * _asinh_diff(xp / aym, xm / aym, 1.0 / aym)
    out = part_x + part_y
    out.setflags(write=False)
    return out


@functools.lru_cache(maxsize=4)
def _pixel_influence_rect(nx: int, ny: int, rho: float) -> np.ndarray:
    """Love's influence ``pi * u / dx`` at node offsets ``(i dx, j dy)``, ``i = 0..nx``, ``j = 0..ny``.

    The pixel is ``dx x dy`` with ``rho = dy / dx``; everything is in units of ``dx``
    (``E* = 1``, unit pressure): offsets ``x = i``, ``y = j rho`` from the pixel's centre,
    half-sides ``1/2`` and ``rho/2``. As :func:`_pixel_influence` (the case ``rho = 1``,
    ``nx = ny``, which it reproduces bit for bit): ``pi u`` is the integral of ``1 / r`` over
    the pixel, the mixed difference of ``F(X, Y) = X ln(Y + r) + Y ln(X + r)`` over
    ``X = x +- 1/2``, ``Y = y +- rho/2``, written as differences of ``asinh`` with the
    ``X ln|X|`` and ``Y ln|Y|`` terms cancelled exactly, each difference formed without
    cancellation (:func:`_asinh_diff`, the arguments differing by ``rho / |X|`` and
    ``1 / |Y|``). Relative error <= 4e-13 against 60-digit values at offsets up to ~900
    pixels for ``rho`` from 1e-9 to 1e9 (~1e-16 times the offset in pixels, as the square
    case). No corner coordinate is 0 (``x``, ``y / rho`` are integers), so nothing divides by 0.
    """
    x = np.arange(nx + 1, dtype=np.float64)[:, None]
    y = np.arange(ny + 1, dtype=np.float64)[None, :] * rho
    half = 0.5 * rho
    xp, xm, yp, ym = x + 0.5, x - 0.5, y + half, y - half
    axm, aym = np.abs(xm), np.abs(ym)
    part_x = xp * _asinh_diff(yp / xp, ym / xp, rho / xp) - xm * _asinh_diff(yp / axm, ym / axm, rho / axm)
    part_y = yp * _asinh_diff(xp / yp, xm / yp, 1.0 / yp) - ym * _asinh_diff(xp / aym, xm / aym, 1.0 / aym)
    out = part_x + part_y
    out.setflags(write=False)
    return out


def pixel_influence(shape, aspect: float = 1.0) -> np.ndarray:
    """``pi E* u / dx`` at node offsets ``(i dx, j dy)``, ``0 <= i <= nx``, ``0 <= j <= ny``, shape (nx+1, ny+1).

    Unit pressure on one ``dx x dy`` pixel of a cell with ``Ly / Lx = aspect`` on the grid
    ``shape`` (``dy / dx = aspect * nx / ny``); the square case (``nx == ny``, ``aspect == 1``)
    is :func:`_pixel_influence`, any other :func:`_pixel_influence_rect`. Read-only (cached).
    """
    nx, ny = grid(shape)
    if nx == ny and aspect == 1.0:
        return _pixel_influence(nx)
    return _pixel_influence_rect(nx, ny, aspect * nx / ny)


def padded_shape(shape) -> tuple[int, int]:
    """The FFT grid of :class:`FreeHalfSpace` for an ``nx x ny`` patch: ``(fast(2 nx), fast(2 ny))``.

    Hockney's construction needs at least ``2n - 1`` points along each axis; ``2n`` is the
    textbook choice, but for a measured map of ``n = 563`` (a prime) FFTW then transforms a
    length with a large prime factor, ~3x slower than the next even 2-3-5 length (1152,
    measured). Any length >= 2n gives the same corner (the kernel is laid out by wrap-around
    offsets), so each axis takes the smallest even 5-smooth length >= 2n: ``2n`` itself for
    every ``n`` whose ``2n`` is already 5-smooth (powers of two, 150, 480, 640: bit for bit
    as before).
    """
    return tuple(_even_5_smooth(2 * n) for n in grid(shape))


def _even_5_smooth(n: int) -> int:
    """The smallest even integer >= ``n`` with no prime factor above 5."""
    m = n + (n % 2)
    while True:
        rest = m
        for f in (2, 3, 5):
            while rest % f == 0:
                rest //= f
        if rest == 1:
            return m
        m += 2


def free_influence(shape, e_star: float = 1.0, length=1.0, padded=None) -> np.ndarray:
    """Influence coefficients of the free half-space on the padded grid (default ``2nx x 2ny``).

    Parameters
    ----------
    shape : int or (int, int)
        Grid points ``(nx, ny)`` of the patch; an int ``n`` means ``(n, n)``.
    e_star : float
        Plane-strain modulus E* [pressure].
    length : float or (float, float)
        Sides ``(Lx, Ly)`` of the patch [length] (a float ``L``: ``(L, L)``); pixels of sides
        ``dx = Lx / nx`` and ``dy = Ly / ny``.

    padded : (int, int), optional
        The padded grid ``(Mx, My)``, each ``M >= 2n`` (default ``(2nx, 2ny)``;
        :class:`FreeHalfSpace` uses :func:`padded_shape`).

    Returns
    -------
    numpy.ndarray, float64, shape (Mx, My)
        Entry ``[i, j]``: displacement [length / pressure] at a node offset by
        ``(i' dx, j' dy)`` from the centre of a pixel under unit uniform pressure,
        ``i' = min(i, Mx - i, nx)`` (``j'`` likewise with ``My`` and ``ny``: wrap-around
        distances, the influence being even in both offsets; offsets beyond ``n`` never
        reach the corner and repeat the value at ``n``): Love's solution
        ``u = 1 / (pi E*) sum_{+-} F(x +- dx/2, y +- dy/2)`` (signs of the mixed
        difference) with ``F(X, Y) = X ln(Y + r) + Y ln(X + r)``, ``r = sqrt(X^2 + Y^2)``
        (~ ``dx dy / (pi E* r)`` far away). Its cyclic convolution with a pressure
        zero-padded to ``2nx x 2ny`` is, on the ``nx x ny`` corner, the linear convolution
        (Hockney 1970).
    """
    nx, ny = grid(shape)
    mx, my = (2 * nx, 2 * ny) if padded is None else (int(v) for v in padded)
    if mx < 2 * nx or my < 2 * ny:
        raise ValueError(f"padded grid {(mx, my)} is smaller than twice the patch {(nx, ny)}")
    c = pixel_influence((nx, ny), cell_aspect(length))
    i, j = np.arange(mx), np.arange(my)
    di, dj = np.minimum(np.minimum(i, mx - i), nx), np.minimum(np.minimum(j, my - j), ny)
    return c[di[:, None], dj[None, :]] * (side_x(length) / (math.pi * nx * e_star))


@functools.lru_cache(maxsize=4)
def _free_multiplier(shape: tuple[int, int], aspect: float) -> np.ndarray:
    """rfft2 of :func:`free_influence` on :func:`padded_shape` for ``E* = Lx = 1``, interleaved (re, im) real copy.

    The influence is real and even, so its transform is real (the imaginary
    round-off is dropped); the backward normalisation ``1 / (Mx My)`` is applied
    by the caller.
    """
    mult = np.fft.rfft2(free_influence(shape, 1.0, internal_length(aspect), padded_shape(shape))).real
    out = np.repeat(mult[..., None], 2, axis=-1)
    out.setflags(write=False)
    return out


@functools.lru_cache(maxsize=8)
def _padded_fft(shape: tuple[int, int], threads: int, backend: str, dtype: str) -> RealFFT2:
    """A :func:`padded_shape` FFT pair owned by :class:`FreeHalfSpace` (never shared with ``get_fft``).

    Only the ``nx x ny`` corner of its input buffer is ever written, so the
    padding stays zero from here on.
    """
    fft = RealFFT2(padded_shape(shape), threads=threads, backend=backend, dtype=np.dtype(dtype))
    if fft.backend == "pyfftw":
        fft._real.fill(0.0)
    return fft


def _multiply_spectrum(spec: np.ndarray, mult: np.ndarray) -> np.ndarray:
    """``spec * mult`` in place, ``mult`` an interleaved (re, im) real multiplier."""
    if spec.dtype.itemsize != 2 * mult.dtype.itemsize:  # numpy.fft < 2 computes in double
        return spec * mult[..., 0]
    view = spec.view(mult.dtype).reshape(mult.shape)
    np.multiply(view, mult, out=view)
    return spec


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

    Every product returns a view of an FFT buffer that the next transform of
    the same precision overwrites (copy it to keep it).
    """

    def __init__(self, shape, threads: int = 1, aspect: float = 1.0):
        self.shape = grid(shape)
        self.fft = plans(self.shape, threads)
        kern = elastic_kernel(self.shape, 1.0, internal_length(aspect))
        # Interleaved (re, im) copy so that the kernel product is a float64 ufunc
        # call on the complex buffer, with no complex temporary.
        self.kern2 = np.repeat(kern[..., None], 2, axis=-1)
        self._minv2 = None
        self.fft32 = None

    @property
    def backend(self) -> str:
        return self.fft.backend

    def apply(self, field: np.ndarray) -> np.ndarray:
        """``K field`` [length per pressure x field], float64, shape (nx, ny)."""
        spec = self.fft.forward(field)
        view = spec.view(np.float64).reshape(self.kern2.shape)
        np.multiply(view, self.kern2, out=view)
        return self.fft.backward(spec)

    def apply_inverse(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with ``M = |q| E* / 2`` (0 at ``q = 0``), float64."""
        if self._minv2 is None:
            kern = self.kern2[..., 0]
            minv = np.zeros_like(kern)
            np.divide(1.0, kern, out=minv, where=kern > 0)
            self._minv2 = np.repeat(minv[..., None], 2, axis=-1)
        return self.fft.backward(_multiply_spectrum(self.fft.forward(field), self._minv2))

    def single(self, sigma: float) -> None:
        """Make the float32 plans and multipliers; inputs are divided by ``sigma``.

        Dividing by a scale of the problem (the internal rms height) before the
        cast makes the float32 values independent of the problem's units, up to
        values within round-off of a float32 rounding boundary.
        """
        if self.fft32 is not None:
            return
        self.apply_inverse(np.zeros(self.shape))  # makes the multiplier
        self.fft32 = get_fft(self.shape, threads=self.fft.threads, backend=self.fft.backend,
                             dtype=np.float32)
        self.kern2_32 = self.kern2.astype(np.float32)
        self.minv2_32 = self._minv2.astype(np.float32)
        self.sigma = sigma
        self.inv_sigma = 1.0 / sigma

    def _product32(self, field: np.ndarray, mult: np.ndarray) -> np.ndarray:
        fft = self.fft32
        if fft.backend == "pyfftw":
            # scale and cast in one pass into the plan's input buffer
            np.multiply(field, self.inv_sigma, out=fft._real, casting="unsafe")
            fft._fwd.execute()
            spec = fft._spec
        else:
            spec = fft.forward(field * self.inv_sigma)
        return fft.backward(_multiply_spectrum(spec, mult))

    def apply32(self, field: np.ndarray) -> np.ndarray:
        """``K field / sigma`` with single-precision transforms (float32 buffer)."""
        return self._product32(field, self.kern2_32)

    def apply_inverse32(self, field: np.ndarray) -> np.ndarray:
        """``M field / sigma`` with single-precision transforms (float32 buffer)."""
        return self._product32(field, self.minv2_32)


class FreeHalfSpace:
    """Free-boundary elastic half-space on an ``nx x ny`` patch in internal units (``E* = Lx = 1``).

    Same methods and parameters as :class:`PeriodicHalfSpace`. ``K`` is the
    zero-padded (Hockney) convolution with :func:`free_influence`: one FFT pair on
    :func:`padded_shape` (``2nx x 2ny`` or the next fast even lengths) per product; the
    displacement is that of the infinite half-space (not zero mean). ``M`` is the periodic preconditioner
    ``|q| E* / 2`` on the ``nx x ny`` cell, an approximate inverse of this ``K``
    (the CG stays exact with it).

    Every product returns a buffer that the next product of the same kind and
    precision overwrites (copy it to keep it).
    """

    def __init__(self, shape, threads: int = 1, aspect: float = 1.0):
        self.shape = grid(shape)
        backend = plans(self.shape, threads).backend
        self.fft = _padded_fft(self.shape, threads, backend, "float64")
        self.kern2 = _free_multiplier(self.shape, aspect)
        mx, my = padded_shape(self.shape)
        self.norm = 1.0 / (mx * my)
        self.out = np.empty(self.shape)
        self.pad = None if backend == "pyfftw" else np.zeros((mx, my))
        self.precond = PeriodicHalfSpace(self.shape, threads, aspect)
        self.fft32 = None

    @property
    def backend(self) -> str:
        return self.fft.backend

    def _product(self, fft, pad, field, mult, out, inv_sigma=None):
        """The ``nx x ny`` corner of ``fft^-1(mult * fft(pad(field)))`` in ``out``."""
        nx, ny = self.shape
        if fft.backend == "pyfftw":
            corner = fft._real[:nx, :ny]
            if inv_sigma is None:
                np.copyto(corner, field)
            else:
                np.multiply(field, inv_sigma, out=corner, casting="unsafe")
            fft._fwd.execute()
            view = fft._spec.view(mult.dtype).reshape(mult.shape)
            np.multiply(view, mult, out=fft._spec_in.view(mult.dtype).reshape(mult.shape))
            fft._bwd.execute()  # c2r: unnormalised, the normalisation goes with the copy
            return np.multiply(fft._real_out[:nx, :ny], out.dtype.type(self.norm), out=out)
        if inv_sigma is None:
            pad[:nx, :ny] = field
        else:
            np.multiply(field, inv_sigma, out=pad[:nx, :ny], casting="unsafe")
        spec = _multiply_spectrum(fft.forward(pad), mult)
        out[...] = fft.backward(spec)[:nx, :ny]
        return out

    def apply(self, field: np.ndarray) -> np.ndarray:
        """``K field`` [length per pressure x field], float64, shape (nx, ny)."""
        return self._product(self.fft, self.pad, field, self.kern2, self.out)

    def apply_inverse(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with the periodic ``M = |q| E* / 2`` (0 at ``q = 0``), float64."""
        return self.precond.apply_inverse(field)

    def single(self, sigma: float) -> None:
        """Make the float32 plans and multipliers; inputs are divided by ``sigma``."""
        if self.fft32 is not None:
            return
        self.precond.single(sigma)
        self.fft32 = _padded_fft(self.shape, self.fft.threads, self.fft.backend, "float32")
        self.kern2_32 = self.kern2.astype(np.float32)
        self.out32 = np.empty(self.shape, dtype=np.float32)
        self.pad32 = None if self.pad is None else np.zeros(self.pad.shape, dtype=np.float32)
        self.sigma = sigma
        self.inv_sigma = 1.0 / sigma

    def apply32(self, field: np.ndarray) -> np.ndarray:
        """``K field / sigma`` with single-precision transforms (float32 buffer)."""
        return self._product(self.fft32, self.pad32, field, self.kern2_32, self.out32, self.inv_sigma)

    def apply_inverse32(self, field: np.ndarray) -> np.ndarray:
        """``M field / sigma`` with single-precision transforms (float32 buffer)."""
        return self.precond.apply_inverse32(field)


def half_space(boundary: str, shape, threads: int = 1, aspect: float = 1.0):
    """The operator for ``boundary`` (one of :data:`BOUNDARIES`) on an ``nx x ny`` grid.

    ``shape`` an int ``n`` or ``(nx, ny)``; ``aspect`` the cell's ``Ly / Lx`` (internal units ``Lx = 1``).
    """
    cls = FreeHalfSpace if boundary == "free" else PeriodicHalfSpace
    return cls(shape, threads, aspect)
