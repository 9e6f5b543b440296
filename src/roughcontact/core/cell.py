"""The cell a surface is sampled on: :class:`Cell` (grid shape, sides, pixel sizes, NetCDF attributes).

A cell is ``nx x ny`` nodes on sides ``Lx x Ly`` [length], axis 0 = x. The solver's ``length``
argument writes a square cell (``nx == ny`` and ``Lx == Ly``) as the float ``L`` and any other as the
pair ``(Lx, Ly)``; a file's global attributes write a square cell as ``length`` and ``n`` and any
other as ``length_x``, ``length_y`` (never one side for both), with ``nx`` and ``ny`` always. This
module is the one place that translates between the three.

Examples
--------
>>> cell = Cell.of((128, 96), (1.0, 0.75))
>>> cell.pixel, cell.length
((0.0078125, 0.0078125), (1.0, 0.75))
>>> Cell.from_attrs(cell.surface_attrs(), (128, 96)) == cell
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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
    """

    shape: tuple[int, int]
    sides: tuple[float, float]
    square: bool

    @classmethod
    def of(cls, shape, length) -> Cell:
        """The cell of a ``(nx, ny)`` grid and the solver's ``length`` (a float L, or (Lx, Ly))."""
        nx, ny = (int(v) for v in shape)
        if np.ndim(length) == 0:
            return cls((nx, ny), (float(length), float(length)), True)
        lx, ly = (float(v) for v in length)
        return cls((nx, ny), (lx, ly), False)

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
        if len(values) == 1 and shape[0] != shape[1]:
            raise ValueError(f"{source}: 'heights' is {shape[0]} x {shape[1]} but the file gives one side 'length'; "
                             "a rectangular cell needs the attributes 'length_x' and 'length_y'")
        return cls.of(shape, values[0] if len(values) == 1 else tuple(values))

    @property
    def length(self):
        """The solver's ``length``: the float ``L`` of a square cell, else ``(Lx, Ly)``."""
        return self.sides[0] if self.square else self.sides

    @property
    def pixel(self) -> tuple[float, float]:
        """``(dx, dy) = (Lx / nx, Ly / ny)`` [length]."""
        return self.sides[0] / self.shape[0], self.sides[1] / self.shape[1]

    @property
    def pixel_scale(self) -> float:
        """One pixel length [length]: ``dx`` for square pixels, else the geometric mean ``sqrt(dx dy)``."""
        dx, dy = self.pixel
        return dx if dx == dy else float(np.sqrt(dx * dy))

    def solver_attrs(self) -> tuple[dict, dict]:
        """The solver's global attributes of the cell, ``(sides, grid)``, each put in its place among them.

        Square: ``({"length": L}, {"n", "nx", "ny"})``; else ``({"length_x", "length_y"}, {"nx", "ny"})``.
        """
        nx, ny = self.shape
        if self.square:
            return {"length": self.sides[0]}, {"n": nx, "nx": nx, "ny": ny}
        return {"length_x": self.sides[0], "length_y": self.sides[1]}, {"nx": nx, "ny": ny}

    def surface_attrs(self) -> dict:
        """A surface file's attributes: ``length`` and ``n`` when square, else the sides, ``nx`` and ``ny``."""
        sides, grid = self.solver_attrs()
        return {**sides, "n": grid["n"]} if "n" in grid else {**sides, **grid}


def sides_of(attrs) -> tuple[float, float]:
    """``(Lx, Ly)`` from a file's or a solve's cell attributes (``length`` for both sides of a square cell)."""
    if "length_x" in attrs:
        return float(attrs["length_x"]), float(attrs["length_y"])
    return attrs["length"], attrs["length"]
