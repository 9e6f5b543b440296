"""The cell value (roughcontact.core.cell): grid shape, sides, pixels, and the attributes files carry."""
import doctest

import pytest

import roughcontact.core.cell as cell_module
from roughcontact.core.cell import Cell, sides_of


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
