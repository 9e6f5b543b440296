"""The cell a surface is sampled on: :class:`Cell` (grid shape, sides, pixel sizes, NetCDF attributes).

A cell is ``nx x ny`` nodes on sides ``Lx x Ly`` [length], axis 0 = x; or a *line* (a profile: ``n``
points on a length ``L``, plane strain), which the solver holds as the one-row grid ``(n, 1)``
(:meth:`Cell.profile`; a 2-D grid has at least 4 nodes a side, so a grid of one row with one length is a
line). The solver's ``length``
argument writes a square cell (``nx == ny`` and ``Lx == Ly``) as the float ``L`` and any other as the
pair ``(Lx, Ly)``; a file's global attributes write a square cell as ``length`` and ``n`` and any
other as ``length_x``, ``length_y`` (never one side for both), with ``nx`` and ``ny`` always. This
module is the one place that translates between the three, and the one place that asks whether a
``length`` is a float or a pair: the rest of the package converts a user's ``length`` to a
:class:`Cell` once (:meth:`Cell.canonical`, or :meth:`Cell.of` to keep the form it was given in) and
asks the cell (``square``, ``side_x``, ``aspect``, :meth:`Cell.perimeter_per_area`, :meth:`Cell.areas`).

Examples
--------
>>> cell = Cell.of((128, 96), (1.0, 0.75))
>>> cell.pixel, cell.length
((0.0078125, 0.0078125), (1.0, 0.75))
>>> Cell.from_attrs(cell.surface_attrs(), (128, 96)) == cell
True
>>> Cell.canonical((64, 64), (2.0, 2.0)) == Cell.of((64, 64), 2.0)  # (L, L) on n x n is the square cell L
True
>>> line = Cell.of((512,), 2.0)  # a profile of 512 points on L = 2
>>> line.line, line.shape, line.length, line.perimeter_per_area(6.0, 0.0)
(True, (512, 1), 2.0, 3.0)
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

#: The forms the solver's ``length`` takes, as the errors name them.
LENGTH_FORMS = "a finite real number > 0 (square cell) or a pair (Lx, Ly) of finite real numbers > 0"


def is_pair_form(length) -> bool:
    """Whether ``length`` is written as a sequence (tuple, list or array of >= 1 dimension), not one number."""
    return isinstance(length, (tuple, list)) or (isinstance(length, np.ndarray) and length.ndim > 0)


def check_length(length):
    """The solver's ``length`` checked, in the form it was given: a float ``L`` or a pair ``(Lx, Ly)``.

    The one parser of ``length`` in the package: :func:`roughcontact.solver.validation.validate_length`
    adds the checks against a grid's shape.

    Parameters
    ----------
    length : float or (float, float)
        A real number (a Python or NumPy scalar, or a 0-d array), or a tuple, list or 1-D array of
        two of them [length]; each finite and > 0.

    Returns
    -------
    float or (float, float)
        ``float(length)``, or the pair of floats.

    Raises
    ------
    ValueError
        Naming ``length``, the forms it may take and what was given (how many values, or the type of
        the one at fault), for anything else (bools and strings included).

    Examples
    --------
    >>> check_length(2), check_length([1, 0.5])
    (2.0, (1.0, 0.5))
    """
    if is_pair_form(length):
        values = list(length) if not isinstance(length, np.ndarray) or length.ndim == 1 else []
        if len(values) != 2:
            given = f"{len(values)} values {length!r}" if values else f"an array of shape {np.shape(length)}"
            raise ValueError(f"length must be {LENGTH_FORMS}, got {given}")
        return tuple(_side(v, length) for v in values)
    return _side(length, length)


def _side(value, length) -> float:
    """One side of ``length``: a real number, finite and > 0, as a float."""
    real = isinstance(value, numbers.Real) or (isinstance(value, np.ndarray) and value.ndim == 0
                                                and value.dtype.kind in "iuf")
    if not real or isinstance(value, (bool, np.bool_)):
        raise ValueError(f"length must be {LENGTH_FORMS}, got {type(value).__name__} {value!r}")
    side = float(value)
    if not (math.isfinite(side) and side > 0):
        raise ValueError(f"length must be {LENGTH_FORMS}, got {length!r}")
    return side


@dataclass(frozen=True)
class Cell:
    """A grid of ``shape = (nx, ny)`` nodes on ``sides = (Lx, Ly)`` [length]; ``square`` when written as one L.

    Attributes
    ----------
    shape : (int, int)
        Nodes along x (axis 0) and y (axis 1).
    sides : (float, float)
        ``(Lx, Ly)`` [length].
    square : bool
        The cell was given as one side ``L`` (the solver's float ``length``; files' ``length``, ``n``).
    line : bool
        A profile of ``n`` points on a length ``L`` (plane strain: the surface is the same along y):
        ``shape = (n, 1)``, ``sides = (L, L / n)`` (one pixel wide, ``dy = dx``), not ``square``.
    """

    shape: tuple[int, int]
    sides: tuple[float, float]
    square: bool
    line: bool = False

    @classmethod
    def profile(cls, n: int, length) -> Cell:
        """The line of ``n`` points on the length ``length`` [length] (a float; a pair is refused).

        Raises
        ------
        ValueError
            Naming ``length``, when it is not one finite real number > 0.

        Examples
        --------
        >>> Cell.profile(8, 2.0).pixel
        (0.25, 0.25)
        """
        length = check_length(length)
        if isinstance(length, tuple):
            raise ValueError(f"length: a profile (1-D heights of {int(n)} points) has one length L, a finite real "
                             f"number > 0, got the pair {length!r}")
        return cls((int(n), 1), (length, length / int(n)), False, True)

    @classmethod
    def of(cls, shape, length) -> Cell:
        """The cell of a ``(nx, ny)`` grid and the solver's ``length``, in the form it was given.

        Parameters
        ----------
        shape : (int, int)
            ``(nx, ny)``, nodes along x (axis 0) and y (axis 1).
        length : float or (float, float)
            A float ``L`` (``square``, sides ``(L, L)``, on any grid: the internal unit cell of a
            rectangle of equal sides is one) or a pair ``(Lx, Ly)`` (not ``square``, even when
            ``Lx == Ly``) [length]; checked by :func:`check_length`.

        Raises
        ------
        ValueError
            Naming ``length``, when it is not a float or a pair of finite numbers > 0.

        Examples
        --------
        >>> Cell.of((8, 8), 2.0).square, Cell.of((8, 8), (2.0, 2.0)).square
        (True, False)
        """
        # a profile (n,), or its one-row grid (n, 1) with one length; a one-row grid given the pair
        # (Lx, Ly) stays the rectangle it is (a strip one pixel wide: the adhesion tests' wavy surface)
        if len(shape) == 1 or (int(shape[1]) == 1 and not isinstance(check_length(length), tuple)):
            return cls.profile(shape[0], length)
        nx, ny = (int(v) for v in shape)
        length = check_length(length)
        if isinstance(length, tuple):
            return cls((nx, ny), length, False)
        return cls((nx, ny), (length, length), True)

    @classmethod
    def canonical(cls, shape, length, name: str = "the grid") -> Cell:
        """The cell the solver solves on: as :meth:`of`, but a pair ``(L, L)`` on an ``n x n`` grid is the
        square cell ``L`` (as :func:`roughcontact.solver.validation.validate_length` returns it, so that
        both are one problem bit for bit), and a float ``L`` needs a square grid.

        Parameters
        ----------
        shape : (int, int)
            ``(nx, ny)`` of the array ``name`` [nodes].
        length : float or (float, float)
            The user's ``length`` [length].
        name : str
            The array whose shape ``shape`` is, for the error.

        Raises
        ------
        ValueError
            Naming ``length``: not a float or a pair of finite numbers > 0, or a float for a grid
            that is not square.

        Examples
        --------
        >>> Cell.canonical((8, 8), (1.0, 1.0)).length, Cell.canonical((8, 4), (1.0, 1.0)).length
        (1.0, (1.0, 1.0))
        """
        cell = cls.of(shape, length)
        (nx, ny), (lx, ly) = cell.shape, cell.sides
        if cell.line:
            return cell
        if cell.square and nx != ny:
            raise ValueError(f"length: a single float means a square cell, and {name} must be a square 2-D array "
                             f"(n, n) for it, got shape {(nx, ny)}: for a rectangular cell give length=(Lx, Ly). "
                             f"A 2-D array is one map: {nx} profiles of {ny} points are not solved at once; solve "
                             "each row as a profile (a 1-D array), one call each")
        if not cell.square and nx == ny and lx == ly:
            return cls(cell.shape, cell.sides, True)
        return cell

    @classmethod
    def from_attrs(cls, attrs, shape, source: str = "the file") -> Cell:
        """The cell a file's attributes describe, for its ``(nx, ny)`` heights; checked.

        Raises ``ValueError`` naming ``source`` when a side is missing or not a finite number > 0, or
        when one ``length`` is given for a grid that is not square.
        """
        keys = ("length_x", "length_y") if "length_x" in attrs else ("length",)
        values = []
        for key in keys:
            value = attrs.get(key)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{source}: the global attribute {key!r} (side of the cell) is missing or not a "
                                 f"number: {value!r}") from None
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{source}: the global attribute {key!r} must be a finite number > 0, got {value!r}")
            values.append(value)
        if len(shape) == 1 and len(values) == 1:
            return cls.profile(shape[0], values[0])
        if len(shape) == 1:
            raise ValueError(f"{source}: 'heights' is a profile of {shape[0]} points but the file gives the sides "
                             "'length_x' and 'length_y'; a profile needs the one attribute 'length'")
        if len(values) == 1 and shape[0] != shape[1]:
            raise ValueError(f"{source}: 'heights' is {shape[0]} x {shape[1]} but the file gives one side 'length'; "
                             "a rectangular cell needs the attributes 'length_x' and 'length_y'")
        return cls.of(shape, values[0] if len(values) == 1 else tuple(values))

    @property
    def length(self):
        """The solver's ``length``: the float ``L`` of a square cell or a line, else ``(Lx, Ly)``."""
        return self.sides[0] if self.square or self.line else self.sides

    @property
    def side_x(self) -> float:
        """``Lx`` [length], the side along x (axis 0): the solver's internal length unit."""
        return self.sides[0]

    @property
    def aspect(self) -> float:
        """``Ly / Lx`` [-]: exactly 1.0 for a square cell (and a line, whose operator has no y), else the y
        side in units of ``Lx``."""
        return 1.0 if self.square or self.line else self.sides[1] / self.sides[0]

    @property
    def pixel(self) -> tuple[float, float]:
        """``(dx, dy) = (Lx / nx, Ly / ny)`` [length]."""
        return self.sides[0] / self.shape[0], self.sides[1] / self.shape[1]

    @property
    def pixel_scale(self) -> float:
        """One pixel length [length]: ``dx`` for square pixels, else the geometric mean ``sqrt(dx dy)``."""
        dx, dy = self.pixel
        return dx if dx == dy else float(np.sqrt(dx * dy))

    def perimeter_per_area(self, edges_x, edges_y):
        """Length of the pixel edges counted, per unit area of the cell [1 / length].

        Parameters
        ----------
        edges_x, edges_y : float or numpy.ndarray of float64
            Edges between neighbours along x (axis 0), each ``dy`` long, and along y (axis 1),
            each ``dx`` long [counts]; arrays of one shape give one value per entry.

        Returns
        -------
        float or numpy.ndarray of float64
            ``(edges_x dy + edges_y dx) / (Lx Ly)``; for a square cell written
            ``(edges_x + edges_y) (L / n) / L**2``, the expression of earlier releases, bit for bit.
            For a line, the ends of the contact intervals per unit length, ``edges_x / L``
            (``edges_y`` is 0 on one row).

        Examples
        --------
        >>> Cell.of((4, 4), 2.0).perimeter_per_area(3.0, 1.0)
        0.5
        """
        (nx, ny), (lx, ly) = self.shape, self.sides
        if self.line:
            return (edges_x + edges_y) / lx
        if self.square:
            return (edges_x + edges_y) * (lx / nx) / lx**2
        return (edges_x * (ly / ny) + edges_y * (lx / nx)) / (lx * ly)

    def areas(self, fractions, pixels):
        """Areas [length**2] of regions given both as fractions of the cell and as node counts.

        Parameters
        ----------
        fractions : numpy.ndarray of float64
            Areas as fractions of ``A0 = Lx Ly`` [-].
        pixels : numpy.ndarray of int
            The same areas as node counts, same shape.

        Returns
        -------
        numpy.ndarray of float64, shape of ``fractions``
            ``fractions * L**2`` for a square cell, ``fractions * L`` (lengths [length]) for a line, else
            ``pixels * (dx * dy)``.

        Examples
        --------
        >>> Cell.of((4, 2), (2.0, 1.0)).areas(np.array([0.25]), np.array([2])).tolist()
        [0.5]
        """
        if self.line:
            return fractions * self.sides[0]
        if self.square:
            return fractions * self.sides[0] ** 2
        dx, dy = self.pixel
        return pixels * (dx * dy)

    def solver_attrs(self) -> tuple[dict, dict]:
        """The solver's global attributes of the cell, ``(sides, grid)``, each put in its place among them.

        Square: ``({"length": L}, {"n", "nx", "ny"})``; a line: ``({"length": L}, {"n", "nx",
        "surface_dimension": 1})``; else ``({"length_x", "length_y"}, {"nx", "ny"})``.
        """
        nx, ny = self.shape
        if self.line:
            return {"length": self.sides[0]}, {"n": nx, "nx": nx, "surface_dimension": 1}
        if self.square:
            return {"length": self.sides[0]}, {"n": nx, "nx": nx, "ny": ny}
        return {"length_x": self.sides[0], "length_y": self.sides[1]}, {"nx": nx, "ny": ny}

    def surface_attrs(self) -> dict:
        """A surface file's attributes: ``length`` and ``n`` when square (and ``surface_dimension = 1`` for a
        line), else the sides, ``nx`` and ``ny``."""
        sides, grid = self.solver_attrs()
        if self.line:
            return {**sides, "n": grid["n"], "surface_dimension": 1}
        return {**sides, "n": grid["n"]} if "n" in grid else {**sides, **grid}


def sides_of(attrs) -> tuple[float, float]:
    """``(Lx, Ly)`` from a file's or a solve's cell attributes (``length`` for both sides of a square cell;
    ``(L, L / n)`` for a line, ``surface_dimension = 1``)."""
    if int(attrs.get("surface_dimension", 2)) == 1:
        return float(attrs["length"]), float(attrs["length"]) / int(attrs["n"])
    if "length_x" in attrs:
        return float(attrs["length_x"]), float(attrs["length_y"])
    return attrs["length"], attrs["length"]
