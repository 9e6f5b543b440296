"""The elastic half-space: the operator ``K`` from pressure to displacement.

:class:`PeriodicHalfSpace` is the periodic FFT-BEM operator
``u(q) = 2 p(q) / (E* |q|)`` on an ``n x n`` cell (internal units ``E* = L = 1``),
with its Fourier preconditioner ``M = |q| E* / 2`` (``K``'s inverse off
``q = 0``) and single-precision variants of both products. A non-periodic
operator (zero-padded, Hockney) will be a second class with the same methods.
"""

from __future__ import annotations

import math

import numpy as np

from ..fft import get_fft, wavenumbers
from .units import frexp_ratio
from .validation import check_positive, validate_heights, validate_threads


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
                 threads: int = 1) -> np.ndarray:
    """Surface displacement of the periodic half-space under a pressure field.

    Parameters
    ----------
    pressure : array_like, shape (n, n)
        Nodal pressure [pressure].
    e_star, length, threads
        As in :func:`solve_contact`.

    Returns
    -------
    numpy.ndarray, float64, shape (n, n)
        Displacement ``u`` into the half-space [length], zero mean.

    Raises
    ------
    ValueError
        For invalid input, or when ``u`` is not representable in float64.
    """
    p = validate_heights(pressure, name="pressure")
    e_star = check_positive("e_star", e_star)
    length = check_positive("length", length)
    n = p.shape[0]
    fft = plans(n, validate_threads(threads))
    # u = (L / E*) K_1 p with K_1 the kernel for E* = L = 1; the factor is applied
    # as mantissa and exponent so that no intermediate overflows.
    pm = float(np.max(np.abs(p))) if p.size else 0.0
    if pm == 0.0:
        return np.zeros_like(p)
    ep = math.frexp(pm)[1]
    u = fft.backward(fft.forward(np.ldexp(p, -ep)) * elastic_kernel(n)).copy()
    fm, fe = frexp_ratio((length,), (e_star,))
    with np.errstate(over="ignore", under="ignore"):
        u = np.ldexp(u * fm, fe + ep)
    if not np.all(np.isfinite(u)):
        raise ValueError("displacement: u = K p overflows float64 for this pressure, e_star and length "
                         f"(max |p| * length / e_star must stay below ~1e300; got max |p| = {pm!r}, "
                         f"e_star = {e_star!r}, length = {length!r})")
    return u




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
