"""Internal units of one surface (docs/solver.md, "Units") and the range of loads.

A cell's ``length`` is a float ``L`` (square cell) or a pair ``(Lx, Ly)`` (rectangle, as
validated by :func:`.validation.validate_length`); the internal length unit of the operators is
``Lx`` (:attr:`roughcontact.core.cell.Cell.side_x`), so ``L`` for a square cell.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.cell import Cell

#: Allowed range of the dimensionless loads ``p0 * L / (E* * s)`` and
#: ``hardness * L / (E* * s)`` (``s`` the rms height; ``L = Lx`` for a rectangular cell):
#: beyond it squares of the pressures or gaps leave the float64 range.
LOAD_RANGE = (1e-100, 1e100)
#: Largest float64 with some head room: a single node may carry ``nx * ny * p0``.
_FLOAT_CEILING = 1e300


def grid(shape) -> tuple[int, int]:
    """``(nx, ny)`` of a grid given as an int ``n`` (square, ``(n, n)``) or a pair."""
    if np.ndim(shape) == 0:
        return int(shape), int(shape)
    nx, ny = shape
    return int(nx), int(ny)


def internal_length(aspect: float):
    """The cell's ``length`` in internal units ``Lx = 1``: ``1.0`` when square, else ``(1.0, aspect)``."""
    return 1.0 if aspect == 1.0 else (1.0, aspect)


def rms_about_mean(h: np.ndarray) -> tuple[float, float]:
    """``(mean, rms about the mean)`` of ``h`` without overflow or underflow.

    The squares are taken of ``h`` scaled by a power of two (exact) so that the
    largest entry is in [0.5, 1): for ordinary inputs the result is bit for bit
    ``sqrt(mean((h - mean(h))**2))``.
    """
    hmax = max(float(h.max()), -float(h.min()))
    if hmax == 0.0:
        return 0.0, 0.0
    e = math.frexp(hmax)[1]
    hs = np.ldexp(h, -e)
    mu = hs.mean()
    hs -= mu
    return math.ldexp(float(mu), e), math.ldexp(float(np.sqrt(np.mean(hs * hs))), e)


def gap_scale(heights: np.ndarray, p0: float, e_star: float = 1.0, length=1.0) -> float:
    """Gap scale ``s`` of the convergence criterion [length].

    The rms height of ``heights`` (shape ``(nx, ny)``) about its mean (computed without
    overflow); for a perfectly flat surface, where that is 0, the displacement scale
    ``p0 * L / E*`` instead, with ``L`` the float ``length`` or, for a pair ``(Lx, Ly)``, ``Lx``
    (the solver's internal length unit).
    """
    h = np.asarray(heights, dtype=float)
    rms = rms_about_mean(h)[1] if h.size and h.max() > h.min() else 0.0
    return rms if rms > 0 else float(p0) * Cell.of(h.shape, length).side_x / float(e_star)


def frexp_ratio(num, den) -> tuple[float, int]:
    """``prod(num) / prod(den)`` as ``(mantissa, exponent)``, without overflow."""
    m, e = 1.0, 0
    for x in num:
        fm, fe = math.frexp(x)
        m, e = m * fm, e + fe
    for x in den:
        fm, fe = math.frexp(x)
        m, e = m / fm, e - fe
    fm, fe = math.frexp(m)
    return fm, e + fe


class Units:
    """Internal units of one surface (module docstring, "Units").

    Lengths are counted in ``c = 2**e_len`` (``s / c`` in [0.5, 1) with ``s`` the
    rms height), pressures in ``E* c / L = pm * 2**pe`` with ``L = length`` for a
    square cell and ``L = Lx`` for a rectangle ``length = (Lx, Ly)`` (stored as
    ``self.length``; ``label`` is its name in messages); ``heights`` holds the
    internal (exactly scaled) heights. ``flat`` marks a surface whose heights
    are all equal.
    """

    def __init__(self, h: np.ndarray, e_star: float, length):
        flat = not bool(h.max() > h.min())
        self._set(h.shape, e_star, length, flat, *((0.0, 0.0) if flat else rms_about_mean(h)))
        self.heights = None if flat else self.internal_heights(h)

    @classmethod
    def of_moments(cls, shape, e_star: float, length, flat: bool, mean: float, rms: float) -> Units:
        """The units of a surface known by its moments alone (``mean``, ``rms`` about it, as
        :func:`rms_about_mean`), e.g. one split over MPI ranks; ``heights`` is None: the caller
        converts its part with :meth:`internal_heights`."""
        self = cls.__new__(cls)
        self._set(shape, e_star, length, flat, mean, rms)
        self.heights = None
        return self

    def _set(self, shape, e_star: float, length, flat: bool, mean: float, rms: float) -> None:
        cell = Cell.of(shape, length)
        self.e_star, self.length = e_star, cell.side_x
        self.label = "length" if cell.square else "Lx"
        self.flat = flat
        if flat:
            self.rms = 0.0
            return
        self.mean, self.rms = mean, rms
        self.e_len = math.frexp(rms)[1]
        pm, pe = frexp_ratio((e_star,), (self.length,))
        self.pm, self.pe = pm, pe + self.e_len

    def internal_heights(self, h: np.ndarray) -> np.ndarray:
        """``h`` [length] (the whole surface or a part of it) in internal lengths, exactly scaled."""
        if abs(self.mean) > self.rms:
            # a rigid offset larger than the roughness: remove it (absorbed by d)
            # so that the round-off of the gap is relative to the roughness.
            h = h - self.mean
        return np.ldexp(h, -self.e_len)

    def ratio_log10(self, p: float) -> float:
        """``log10(p * L / (E* s))``, the dimensionless load (no overflow)."""
        return math.log10(p) + math.log10(self.length) - math.log10(self.e_star) - math.log10(self.rms)

    def to_internal(self, p: float) -> float:
        return math.ldexp(p, -self.pe) / self.pm

    def pressure(self, p_int: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        if -1000 < self.pe < 1000:
            # one multiply by a normal float (exact for E* = L = 1: a power of two)
            return np.multiply(p_int, math.ldexp(self.pm, self.pe), out=out)
        out = np.multiply(p_int, self.pm, out=out)
        return np.ldexp(out, self.pe, out=out)

    def length_field(self, g_int):
        return np.ldexp(g_int, self.e_len)


def check_loads(units: Units, p: np.ndarray, shape: tuple[int, int], name: str) -> None:
    """Refuse mean pressures ``p`` outside float64's reach (``name`` is the argument).

    ``shape`` is the grid ``(nx, ny)``: a single node may carry the whole load ``nx * ny * p0``.
    """
    label = "p0" if name == "p0" else "every p0"
    top = float(p.max())
    nx, ny = shape
    if top * float(nx) * float(ny) > _FLOAT_CEILING:
        nodes = "n**2" if nx == ny else "(nx * ny)"
        raise ValueError(
            f"{name}: {label} must be <= {_FLOAT_CEILING:g} / {nodes} = {_FLOAT_CEILING / nx / ny:.3g} (a single "
            f"node may carry the whole load {nodes} p0); got {top!r}")
    for value in (p.min(), p.max()):
        check_range(units, name, label, float(value))


def check_range(units: Units, arg: str, what: str, value: float) -> None:
    """Refuse a pressure ``value`` whose ``value * L / (E* s)`` is outside :data:`LOAD_RANGE` (``L = Lx``
    for a rectangle)."""
    if units.flat:
        return
    lo, hi = LOAD_RANGE
    r = units.ratio_log10(value)
    if not (math.log10(lo) <= r <= math.log10(hi)):
        raise ValueError(
            f"{arg}: {what} * {units.label} / (e_star * s) must be in [{lo:g}, {hi:g}] with s = "
            f"{units.rms:.6g} the rms height of heights (outside it float64 cannot represent the "
            f"contact); got {what.split()[-1]} = {value!r}, i.e. 10**{r:.1f}")
