"""The elastic half-space: the operator ``K`` from pressure to displacement.

:class:`PeriodicHalfSpace` is the periodic FFT-BEM operator
``u(q) = 2 p(q) / (E* |q|)`` on an ``n x n`` cell (internal units ``E* = L = 1``),
with its Fourier preconditioner ``M = |q| E* / 2`` (``K``'s inverse off
``q = 0``) and single-precision variants of both products.

:class:`FreeHalfSpace` is the free-boundary (non-periodic) operator with the same
methods: the ``n x n`` pressure, uniform on each pixel of side ``dx = L / n``, is
zero-padded to ``2n x 2n`` and convolved by FFT with Love's influence function of
one pixel sampled at wrap-around distances (:func:`free_influence`; Hockney's
construction, as ContactMechanics' ``FreeFFTElasticHalfSpace``); the ``n x n``
corner of the result is the exact displacement of the infinite half-space under
that pressure, with no periodic images. Its preconditioner is the periodic
``M = |q| E* / 2`` on the ``n x n`` grid (an approximate inverse now).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..fft import RealFFT2, get_fft, wavenumbers
from .units import frexp_ratio
from .validation import check_positive, validate_boundary, validate_heights, validate_threads


def plans(n: int, threads: int):
    """The cached FFT pair for an ``n x n`` grid.

    ``get_fft`` is an ``lru_cache`` keyed on the literal arguments; for one
    thread this is the same call as :func:`roughcontact.surface.generate_surface`
    makes, so both share one set of plans and buffers (33 MB at n = 1024).
    """
    if threads == 1:
        return get_fft((n, n), backend=None)
    return get_fft((n, n), threads=threads)


def elastic_kernel(n: int, e_star: float = 1.0, length: float = 1.0) -> np.ndarray:
    """Fourier multiplier from pressure to displacement on the rfft2 grid.

    Parameters
    ----------
    n : int
        Grid points per side.
    e_star : float
        Plane-strain modulus E* [pressure].
    length : float
        Side L of the periodic cell [length].

    Returns
    -------
    numpy.ndarray, float64, shape (n, n//2+1)
        ``2 / (E* |q|)`` [length / pressure] with ``|q| = 2 pi |k| / L``; the
        ``q = 0`` entry is 0 (the mean displacement is absorbed by the rigid-body
        approach).
    """
    kx, ky = wavenumbers(n, length)
    q = 2.0 * np.pi * np.hypot(kx, ky)
    out = np.zeros_like(q)
    np.divide(2.0 / e_star, q, out=out, where=q > 0)
    return out


def displacement(pressure: np.ndarray, *, e_star: float = 1.0, length: float = 1.0,
                 threads: int = 1, boundary: str = "periodic") -> np.ndarray:
    """Surface displacement of the elastic half-space under a pressure field.

    Parameters
    ----------
    pressure : array_like, shape (n, n)
        Nodal pressure [pressure].
    e_star, length, threads, boundary
        As in :func:`solve_contact`.

    Returns
    -------
    numpy.ndarray, float64, shape (n, n)
        Displacement ``u`` into the half-space [length]: zero mean for the
        periodic half-space; for ``boundary="free"`` the displacement of the
        infinite half-space loaded by ``pressure`` on the patch alone (zero far
        away), each node's pressure uniform over its pixel.

    Raises
    ------
    ValueError
        For invalid input, or when ``u`` is not representable in float64.
    """
    p = validate_heights(pressure, name="pressure")
    e_star = check_positive("e_star", e_star)
    length = check_positive("length", length)
    boundary = validate_boundary(boundary)
    n = p.shape[0]
    threads = validate_threads(threads)
    # u = (L / E*) K_1 p with K_1 the kernel for E* = L = 1; the factor is applied
    # as mantissa and exponent so that no intermediate overflows.
    pm = float(np.max(np.abs(p))) if p.size else 0.0
    if pm == 0.0:
        return np.zeros_like(p)
    ep = math.frexp(pm)[1]
    if boundary == "free":
        u = FreeHalfSpace(n, threads).apply(np.ldexp(p, -ep)).copy()
    else:
        fft = plans(n, threads)
        u = fft.backward(fft.forward(np.ldexp(p, -ep)) * elastic_kernel(n)).copy()
    fm, fe = frexp_ratio((length,), (e_star,))
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


def free_influence(n: int, e_star: float = 1.0, length: float = 1.0) -> np.ndarray:
    """Influence coefficients of the free half-space on the ``2n x 2n`` padded grid.

    Parameters
    ----------
    n : int
        Grid points per side of the patch.
    e_star : float
        Plane-strain modulus E* [pressure].
    length : float
        Side L of the patch [length]; pixels of side ``dx = L / n``.

    Returns
    -------
    numpy.ndarray, float64, shape (2n, 2n)
        Entry ``[i, j]``: displacement [length / pressure] at a node offset by
        ``(i', j') dx`` from the centre of a pixel under unit uniform pressure,
        ``i' = i`` for ``i <= n`` and ``2n - i`` above (wrap-around distances,
        the influence being even in both offsets): Love's solution
        ``u = 1 / (pi E*) sum_{+-} F(x +- dx/2, y +- dx/2)`` (signs of the mixed
        difference) with ``F(X, Y) = X ln(Y + r) + Y ln(X + r)``. Its cyclic
        convolution with a pressure zero-padded to ``2n x 2n`` is, on the
        ``n x n`` corner, the linear convolution (Hockney 1970).
    """
    c = _pixel_influence(n)
    k = np.arange(2 * n)
    d = np.minimum(k, 2 * n - k)
    return c[d[:, None], d[None, :]] * (length / (math.pi * n * e_star))


@functools.lru_cache(maxsize=4)
def _free_multiplier(n: int) -> np.ndarray:
    """rfft2 of :func:`free_influence` for ``E* = L = 1``, interleaved (re, im) real copy.

    The influence is real and even, so its transform is real (the imaginary
    round-off is dropped); the backward normalisation ``1 / (2n)^2`` is applied
    by the caller.
    """
    mult = np.fft.rfft2(free_influence(n)).real
    out = np.repeat(mult[..., None], 2, axis=-1)
    out.setflags(write=False)
    return out


@functools.lru_cache(maxsize=8)
def _padded_fft(n: int, threads: int, backend: str, dtype: str) -> RealFFT2:
    """A ``2n x 2n`` FFT pair owned by :class:`FreeHalfSpace` (never shared with ``get_fft``).

    Only the ``n x n`` corner of its input buffer is ever written, so the
    padding stays zero from here on.
    """
    fft = RealFFT2((2 * n, 2 * n), threads=threads, backend=backend, dtype=np.dtype(dtype))
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
    """Periodic elastic half-space on an ``n x n`` grid in internal units (``E* = L = 1``).

    Parameters
    ----------
    n : int
        Grid points per side.
    threads : int
        FFTW threads.

    Every product returns a view of an FFT buffer that the next transform of
    the same precision overwrites (copy it to keep it).
    """

    def __init__(self, n: int, threads: int = 1):
        self.n = n
        self.fft = plans(n, threads)
        kern = elastic_kernel(n)
        # Interleaved (re, im) copy so that the kernel product is a float64 ufunc
        # call on the complex buffer, with no complex temporary.
        self.kern2 = np.repeat(kern[..., None], 2, axis=-1)
        self._minv2 = None
        self.fft32 = None

    @property
    def backend(self) -> str:
        return self.fft.backend

    def apply(self, field: np.ndarray) -> np.ndarray:
        """``K field`` [length per pressure x field], float64, shape (n, n)."""
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
        self.apply_inverse(np.zeros((self.n, self.n)))  # makes the multiplier
        self.fft32 = get_fft((self.n, self.n), threads=self.fft.threads, backend=self.fft.backend,
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
    """Free-boundary elastic half-space on an ``n x n`` patch in internal units (``E* = L = 1``).

    Same methods as :class:`PeriodicHalfSpace`. ``K`` is the zero-padded
    (Hockney) convolution with :func:`free_influence`: one ``2n x 2n`` FFT pair
    per product; the displacement is that of the infinite half-space (not zero
    mean). ``M`` is the periodic preconditioner ``|q| E* / 2`` on the ``n x n``
    grid, an approximate inverse of this ``K`` (the CG stays exact with it).

    Every product returns a buffer that the next product of the same kind and
    precision overwrites (copy it to keep it).
    """

    def __init__(self, n: int, threads: int = 1):
        self.n = n
        backend = plans(n, threads).backend
        self.fft = _padded_fft(n, threads, backend, "float64")
        self.kern2 = _free_multiplier(n)
        self.norm = 1.0 / (4.0 * n * n)
        self.out = np.empty((n, n))
        self.pad = None if backend == "pyfftw" else np.zeros((2 * n, 2 * n))
        self.precond = PeriodicHalfSpace(n, threads)
        self.fft32 = None

    @property
    def backend(self) -> str:
        return self.fft.backend

    def _product(self, fft, pad, field, mult, out, inv_sigma=None):
        """The ``n x n`` corner of ``fft^-1(mult * fft(pad(field)))`` in ``out``."""
        n = self.n
        if fft.backend == "pyfftw":
            corner = fft._real[:n, :n]
            if inv_sigma is None:
                np.copyto(corner, field)
            else:
                np.multiply(field, inv_sigma, out=corner, casting="unsafe")
            fft._fwd.execute()
            view = fft._spec.view(mult.dtype).reshape(mult.shape)
            np.multiply(view, mult, out=fft._spec_in.view(mult.dtype).reshape(mult.shape))
            fft._bwd.execute()  # c2r: unnormalised, the normalisation goes with the copy
            return np.multiply(fft._real_out[:n, :n], out.dtype.type(self.norm), out=out)
        if inv_sigma is None:
            pad[:n, :n] = field
        else:
            np.multiply(field, inv_sigma, out=pad[:n, :n], casting="unsafe")
        spec = _multiply_spectrum(fft.forward(pad), mult)
        out[...] = fft.backward(spec)[:n, :n]
        return out

    def apply(self, field: np.ndarray) -> np.ndarray:
        """``K field`` [length per pressure x field], float64, shape (n, n)."""
        return self._product(self.fft, self.pad, field, self.kern2, self.out)

    def apply_inverse(self, field: np.ndarray) -> np.ndarray:
        """``M field`` with the periodic ``M = |q| E* / 2`` (0 at ``q = 0``), float64."""
        return self.precond.apply_inverse(field)

    def single(self, sigma: float) -> None:
        """Make the float32 plans and multipliers; inputs are divided by ``sigma``."""
        if self.fft32 is not None:
            return
        self.precond.single(sigma)
        self.fft32 = _padded_fft(self.n, self.fft.threads, self.fft.backend, "float32")
        self.kern2_32 = self.kern2.astype(np.float32)
        self.out32 = np.empty((self.n, self.n), dtype=np.float32)
        self.pad32 = None if self.pad is None else np.zeros((2 * self.n, 2 * self.n), dtype=np.float32)
        self.sigma = sigma
        self.inv_sigma = 1.0 / sigma

    def apply32(self, field: np.ndarray) -> np.ndarray:
        """``K field / sigma`` with single-precision transforms (float32 buffer)."""
        return self._product(self.fft32, self.pad32, field, self.kern2_32, self.out32, self.inv_sigma)

    def apply_inverse32(self, field: np.ndarray) -> np.ndarray:
        """``M field / sigma`` with single-precision transforms (float32 buffer)."""
        return self.precond.apply_inverse32(field)


def half_space(boundary: str, n: int, threads: int = 1):
    """The operator for ``boundary`` (one of :data:`BOUNDARIES`) on an ``n x n`` grid."""
    return FreeHalfSpace(n, threads) if boundary == "free" else PeriodicHalfSpace(n, threads)
