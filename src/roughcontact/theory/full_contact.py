"""The exact periodic full-contact solution: the pressure when every node touches.

Once the whole surface is in contact the gap vanishes everywhere, so the elastic displacement is
the height itself up to a rigid shift, ``u = h - d``. On a periodic half-space each Fourier mode
``q != 0`` obeys ``u(q) = 2 p(q) / (E* |q|)``, which inverts to ``p(q) = (E* |q| / 2) h(q)``; the
mean pressure is the applied ``p0``. The field is a contact solution while it stays positive, i.e.
for ``p0`` above :func:`full_contact_load` (ContactMechanics and Tamaas use the same identity).

Conventions: heights ``h`` and the cell sides share one length unit; axis 0 is x (side ``Lx``),
axis 1 is y (side ``Ly``); pressures and ``E*`` share one pressure unit.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.cell import Cell
from .laws import positive_number


def _grid(shape) -> tuple[int, int]:
    """``(nx, ny)`` of an int (square grid) or a pair of ints, each >= 1."""
    dims = (shape, shape) if np.ndim(shape) == 0 else tuple(shape)
    if len(dims) != 2 or not all(
        isinstance(d, (int, np.integer)) and not isinstance(d, (bool, np.bool_)) and d >= 1 for d in dims
    ):
        raise ValueError(f"shape must be an int >= 1 or a pair of them (nx, ny), got {shape!r}")
    return int(dims[0]), int(dims[1])


def _heights(h) -> np.ndarray:
    arr = np.asarray(h)
    if arr.ndim != 2 or arr.size == 0 or not np.isrealobj(arr) or not np.issubdtype(arr.dtype, np.number):
        raise ValueError(f"h must be a non-empty 2-D real array, got shape {arr.shape} and dtype {arr.dtype}")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise ValueError("h must be finite everywhere (found NaN or inf)")
    return arr


def wavenumbers(shape, length=1.0) -> np.ndarray:
    """``|q|`` on the full FFT grid of a periodic ``nx x ny`` cell of sides ``Lx x Ly``.

    Parameters
    ----------
    shape : int or (int, int)
        Grid points ``(nx, ny)`` along axis 0 (x) and axis 1 (y); an int ``n`` means ``(n, n)``.
    length : float or (float, float)
        Sides ``(Lx, Ly)`` (> 0) [length]; a float ``L`` means ``(L, L)``.

    Returns
    -------
    numpy.ndarray, float64, shape (nx, ny)
        ``|q| = 2 pi sqrt((mx/Lx)^2 + (my/Ly)^2)`` [rad / length], ``mx, my`` the ``fftfreq``
        mode numbers (the order of ``numpy.fft.fft2``); 0 at ``[0, 0]``.
    """
    cell = Cell.of(_grid(shape), length)
    (nx, ny), (lx, ly) = cell.shape, cell.sides
    qx = 2.0 * math.pi * np.fft.fftfreq(nx, 1.0 / nx) / lx
    qy = 2.0 * math.pi * np.fft.fftfreq(ny, 1.0 / ny) / ly
    return np.hypot(qx[:, None], qy[None, :])


def full_contact_pressure(h, p0: float, e_star: float = 1.0, length=1.0) -> np.ndarray:
    """The exact pressure at full contact, ``p = p0 + (E*/2) F^-1[|q| h_hat]`` (periodic).

    Parameters
    ----------
    h : array_like, shape (nx, ny)
        Heights of the rigid rough surface [length], axis 0 = x; its mean does not matter.
    p0 : float
        Applied mean pressure [pressure unit of ``e_star``].
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].
    length : float or (float, float)
        Cell side ``L`` or sides ``(Lx, Ly)`` (> 0) [length].

    Returns
    -------
    numpy.ndarray, float64, shape (nx, ny)
        Pressure [pressure unit], mean ``p0``; the contact solution where it is > 0 everywhere,
        i.e. for ``p0 >`` :func:`full_contact_load`.
    """
    arr = _heights(h)
    p = float(p0)
    if not math.isfinite(p):
        raise ValueError(f"p0 must be a finite number, got {p0!r}")
    q = wavenumbers(arr.shape, length)
    return p + np.real(np.fft.ifft2(np.fft.fft2(arr) * (0.5 * positive_number("e_star", e_star) * q)))


def full_contact_load(h, e_star: float = 1.0, length=1.0) -> float:
    """The mean pressure at which the last node touches, ``-min (E*/2) F^-1[|q| h_hat]``.

    Parameters
    ----------
    h : array_like, shape (nx, ny)
        Heights [length], axis 0 = x.
    e_star : float
        Contact modulus ``E*`` (> 0) [pressure unit].
    length : float or (float, float)
        Cell side ``L`` or sides ``(Lx, Ly)`` (> 0) [length].

    Returns
    -------
    float
        ``p0`` of full contact [pressure unit] (>= 0; 0 for a flat surface).
    """
    return -float(full_contact_pressure(h, 0.0, e_star, length).min())
