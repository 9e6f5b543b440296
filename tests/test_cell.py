"""The cell value (roughcontact.core.cell): grid shape, sides, pixels, and the attributes files carry."""
import doctest

import numpy as np
import pytest

import roughcontact.core.cell as cell_module
from roughcontact.core.cell import Cell, check_length, sides_of


def test_the_module_examples_run():
    assert doctest.testmod(cell_module).failed == 0


def test_a_square_cell_is_one_side_and_n():
    cell = Cell.of((64, 64), 2.0)
    assert cell.length == 2.0 and cell.pixel == (2.0 / 64, 2.0 / 64) and cell.pixel_scale == 2.0 / 64
    assert cell.solver_attrs() == ({"length": 2.0}, {"n": 64, "nx": 64, "ny": 64})
    assert cell.surface_attrs() == {"length": 2.0, "n": 64}
    assert Cell.from_attrs(cell.surface_attrs(), (64, 64)) == cell and sides_of(cell.surface_attrs()) == (2.0, 2.0)


def test_a_rectangular_cell_never_gives_one_side_for_both():
    cell = Cell.of((40, 30), (1.0, 1.5))
    assert cell.solver_attrs() == ({"length_x": 1.0, "length_y": 1.5}, {"nx": 40, "ny": 30})
    assert "length" not in cell.surface_attrs() and "n" not in cell.surface_attrs()
    assert cell.pixel_scale == pytest.approx((1.0 / 40 * 1.5 / 30) ** 0.5)
    assert Cell.from_attrs({**cell.surface_attrs()}, (40, 30)).length == (1.0, 1.5)
    assert Cell.of((8, 8), (1.0, 1.0)).length == (1.0, 1.0)  # a pair stays a pair: the solver's (L, L)


@pytest.mark.parametrize("attrs, shape, words", [
    ({}, (8, 8), "'length' (side of the cell) is missing"),
    ({"length": "x"}, (8, 8), "is missing or not a number: 'x'"),
    ({"length": -1.0}, (8, 8), "must be a finite number > 0"),
    ({"length_x": 1.0, "length_y": float("inf")}, (8, 4), "'length_y' must be a finite number > 0"),
    ({"length": 1.0}, (8, 4), "8 x 4 but the file gives one side 'length'"),
])
def test_bad_attributes_name_the_file(attrs, shape, words):
    with pytest.raises(ValueError, match="^f.nc: ") as info:
        Cell.from_attrs(attrs, shape, "f.nc")
    assert words in str(info.value)


def test_a_pair_of_equal_sides_on_a_square_grid_is_the_square_cell():
    assert Cell.canonical((16, 16), (2.0, 2.0)) == Cell.of((16, 16), 2.0) == Cell.canonical((16, 16), 2)
    assert Cell.canonical((16, 16), (2.0, 2.0)).length == 2.0
    assert not Cell.canonical((16, 12), (2.0, 2.0)).square  # equal sides, rectangular pixels: a rectangle
    assert not Cell.canonical((16, 16), (2.0, 1.0)).square
    assert Cell.of((16, 16), (2.0, 2.0)).length == (2.0, 2.0)  # of() keeps the form it was given


def test_the_sides_a_solver_needs():
    rect, square = Cell.of((40, 30), (2.0, 1.5)), Cell.of((40, 40), 2.0)
    assert (rect.side_x, rect.aspect) == (2.0, 0.75)
    assert (square.side_x, square.aspect) == (2.0, 1.0)
    assert Cell.of((8, 4), 3.0).sides == (3.0, 3.0)  # a float on a rectangular grid: both sides L (internal units)


def test_perimeter_per_area_weighs_each_edge_with_its_length():
    # a rectangle: edges along x are dy = 1.5 / 30 long, along y dx = 2 / 40; area 2 * 1.5
    rect = Cell.of((40, 30), (2.0, 1.5))
    assert rect.perimeter_per_area(3.0, 5.0) == pytest.approx((3 * 0.05 + 5 * 0.05) / 3.0, rel=1e-15)
    assert rect.perimeter_per_area(6.0, 0.0) == pytest.approx(6 * 0.05 / 3.0, rel=1e-15)
    square = Cell.of((4, 4), 2.0)
    assert square.perimeter_per_area(3.0, 1.0) == (3.0 + 1.0) * (2.0 / 4) / 2.0**2  # the square's own expression
    edges = np.array([1.0, 2.0])
    assert square.perimeter_per_area(edges, edges).tolist() == [0.25, 0.5]


def test_areas_from_fractions_or_node_counts():
    fractions, pixels = np.array([0.5, 0.25]), np.array([8, 4])
    assert Cell.of((4, 4), 2.0).areas(fractions, pixels).tolist() == [2.0, 1.0]  # fractions * L**2
    assert Cell.of((4, 4), (2.0, 3.0)).areas(fractions, pixels).tolist() == [3.0, 1.5]  # counts * dx * dy


@pytest.mark.parametrize("length", [0.0, -1.0, float("inf"), float("nan"), "1", True, None, (1.0,), (1.0, 2.0, 3.0),
                                    [1.0, -2.0], (1.0, "a"), np.ones((2, 1)), np.array([1.0, np.nan])])
def test_a_bad_length_is_named(length):
    with pytest.raises(ValueError, match="^length must be a finite real number > 0"):
        Cell.of((8, 8), length)
    with pytest.raises(ValueError, match="^length must be"):
        check_length(length)


def test_a_float_length_needs_a_square_grid():
    with pytest.raises(ValueError, match=r"^length: a single float means a square cell, and mask must be a square 2-D "
                                         r"array \(n, n\) for it, got shape \(8, 4\)"):
        Cell.canonical((8, 4), 1.0, "mask")


def test_check_length_keeps_the_form():
    assert check_length(np.float32(0.5)) == 0.5 and check_length(np.array(2)) == 2.0
    assert check_length(np.array([1, 2])) == (1.0, 2.0) and check_length([1, 2]) == (1.0, 2.0)


@pytest.mark.parametrize(("length", "given"), [((1.0,), r"got 1 values \(1.0,\)"), ([1, 2, 3], "got 3 values"),
                                               (np.ones((2, 2)), r"got an array of shape \(2, 2\)"),
                                               ((1.0, "a"), "got str 'a'"), (True, "got bool True")])
def test_the_solver_and_the_cell_refuse_a_length_with_one_message(length, given):
    from roughcontact.solver.validation import validate_length
    for check in (check_length, lambda v: validate_length(v, (8, 8)), lambda v: Cell.of((8, 8), v)):
        with pytest.raises(ValueError, match=f"^length must be a finite real number > 0 .*{given}"):
            check(length)
