"""Love's influence of a uniformly loaded pixel, and the zero-padded grid of the free half-space.

:class:`~.halfspace.FreeHalfSpace` convolves the pressure with :func:`free_influence` on
:func:`padded_shape` (Hockney's construction, as ContactMechanics' ``FreeFFTElasticHalfSpace``);
this module holds the influence coefficients and the cached transforms of that grid. Units as in
:mod:`.halfspace`: internally ``E* = Lx = 1``.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..core.cell import Cell
from ..core.fft import RealFFT2
from .units import grid, internal_length


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
def pixel_influence_square(n: int) -> np.ndarray:
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
def pixel_influence_rect(nx: int, ny: int, rho: float) -> np.ndarray:
    """Love's influence ``pi * u / dx`` at node offsets ``(i dx, j dy)``, ``i = 0..nx``, ``j = 0..ny``.

    The pixel is ``dx x dy`` with ``rho = dy / dx``; everything is in units of ``dx``
    (``E* = 1``, unit pressure): offsets ``x = i``, ``y = j rho`` from the pixel's centre,
    half-sides ``1/2`` and ``rho/2``. As :func:`pixel_influence_square` (the case ``rho = 1``,
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
    is :func:`pixel_influence_square`, any other :func:`pixel_influence_rect`. Read-only (cached).
    """
    nx, ny = grid(shape)
    if nx == ny and aspect == 1.0:
        return pixel_influence_square(nx)
    return pixel_influence_rect(nx, ny, aspect * nx / ny)


def padded_shape(shape) -> tuple[int, int]:
    """The FFT grid of :class:`FreeHalfSpace` for an ``nx x ny`` patch: ``(fast(2 nx), fast(2 ny))``.

    A profile's grid ``(n, 1)`` (:meth:`~roughcontact.core.cell.Cell.profile`) is padded along x only.
    Hockney's construction needs at least ``2n - 1`` points along each axis; ``2n`` is the
    textbook choice, but for a measured map of ``n = 563`` (a prime) FFTW then transforms a
    length with a large prime factor, ~3x slower than the next even 2-3-5 length (1152,
    measured). Any length >= 2n gives the same corner (the kernel is laid out by wrap-around
    offsets), so each axis takes the smallest even 5-smooth length >= 2n: ``2n`` itself for
    every ``n`` whose ``2n`` is already 5-smooth (powers of two, 150, 480, 640: bit for bit
    as before).
    """
    nx, ny = grid(shape)
    if ny == 1:  # a profile's one-row grid: no y to pad
        return _even_5_smooth(2 * nx), 1
    return _even_5_smooth(2 * nx), _even_5_smooth(2 * ny)


def preconditioner_shape(shape) -> tuple[int, int]:
    """The periodic grid of :class:`FreeHalfSpace`'s preconditioner for an ``nx x ny`` patch.

    Each side is the patch's own where FFTW transforms it fast (no prime factor above 13, the
    radices FFTW has hard-coded), else the smallest even 5-smooth length above it: the patch then
    sits in a corner of a slightly larger periodic cell with the same spacing. Measured with
    FFTW_ESTIMATE (float32 pair, one core, 2026-11-26): 563² (a prime) 28.6 ms against 2.6 ms at
    560², 503² 16.8 ms against 1.65 ms at 500², 1009² 72 ms against 10 ms at 1000²; 484² (2² 11²)
    and 650² (2 5² 13) within 1.3x of their 5-smooth neighbours, so they stay as they are.
    """
    return tuple(n if _largest_prime_factor(n) <= 13 else _even_5_smooth(n) for n in grid(shape))


def _largest_prime_factor(n: int) -> int:
    """The largest prime factor of ``n >= 1`` (1 for ``n = 1``)."""
    largest, f = 1, 2
    while f * f <= n:
        while n % f == 0:
            largest, n = f, n // f
        f += 1
    return max(largest, n) if n > 1 else largest


def _even_5_smooth(n: int) -> int:
    """The smallest even integer >= ``n`` with no prime factor above 5."""
    m = n + (n % 2)
    while _largest_prime_factor(m) > 5:
        m += 2
    return m


def line_influence(n: int) -> np.ndarray:
    """Plane-strain influence ``pi E* u / (2 L)`` of a unit pressure on one pixel of a line, offsets ``0..n``.

    A profile of ``n`` points on a length ``L`` (pixels ``dx = L / n``): a uniform pressure on
    ``|s| < dx / 2`` (the strip of a line load, the surface the same along y) displaces the surface by
    ``u(x) = 2 / (pi E*) integral ln(D / |x - s|) ds`` (Johnson 1985, eq. 2.19b, integrated over
    the pixel; plane strain fixes ``u`` only up to a constant, here the datum ``D = L``). In units of
    ``L``, ``pi E* u / (2 L) = -[G(t)]`` over ``t = x - dx/2 .. x + dx/2``, ``G(t) = t ln|t| - t``
    (``G(0) = 0``). The datum ``D = L`` makes the operator positive definite on the patch (the kernel
    ``ln(D / |x - s|)`` is, on an interval shorter than ``4 D``: its logarithmic capacity is a quarter
    of its length), as the iterations need; the constant it adds to ``u`` is taken up by the rigid
    approach, so the gap does not depend on it.
    """
    dx = 1.0 / n
    x = np.arange(n + 1, dtype=np.float64) * dx
    t = np.stack([x + 0.5 * dx, x - 0.5 * dx])  # the pixel's ends seen from x (x - dx/2 < 0 at offset 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(t != 0, t * np.log(np.abs(t)) - t, 0.0)
    out = -(g[0] - g[1])
    out.setflags(write=False)
    return out


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
        (Hockney 1970). A profile's grid ``(n, 1)`` gives shape ``(Mx, 1)``: the plane-strain
        :func:`line_influence`, ``2 L / (pi E*)`` times it.
    """
    nx, ny = grid(shape)
    if ny == 1:  # a profile (Cell.profile): the plane-strain strip, padded along x only
        mx = 2 * nx if padded is None else int(padded[0])
        if mx < 2 * nx:
            raise ValueError(f"padded grid {(mx, 1)} is shorter than twice the profile {(nx, 1)}")
        i = np.arange(mx)
        di = np.minimum(np.minimum(i, mx - i), nx)
        side = Cell.of((nx, 1), length).side_x
        return (line_influence(nx)[di] * (2.0 * side / (math.pi * e_star)))[:, None]
    mx, my = (2 * nx, 2 * ny) if padded is None else (int(v) for v in padded)
    if mx < 2 * nx or my < 2 * ny:
        raise ValueError(f"padded grid {(mx, my)} is smaller than twice the patch {(nx, ny)}")
    cell = Cell.of((nx, ny), length)
    c = pixel_influence((nx, ny), cell.aspect)
    i, j = np.arange(mx), np.arange(my)
    di, dj = np.minimum(np.minimum(i, mx - i), nx), np.minimum(np.minimum(j, my - j), ny)
    return c[di[:, None], dj[None, :]] * (cell.side_x / (math.pi * nx * e_star))


@functools.lru_cache(maxsize=4)
def free_multiplier(shape: tuple[int, int], aspect: float) -> np.ndarray:
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
def padded_fft(shape: tuple[int, int], threads: int, backend: str, dtype: str) -> RealFFT2:
    """A :func:`padded_shape` FFT pair owned by :class:`FreeHalfSpace` (never shared with ``get_fft``).

    Only the ``nx x ny`` corner of its input buffer is ever written, so the
    padding stays zero from here on.
    """
    fft = RealFFT2(padded_shape(shape), threads=threads, backend=backend, dtype=np.dtype(dtype))
    if fft.backend == "pyfftw":
        fft._real.fill(0.0)
    return fft
