"""The wrapping statistic (percolation on the periodic cell) against a brute-force unrolled count."""
import numpy as np
import pytest
from scipy import ndimage

from roughcontact.statistics.wrapping import (
    WRAPS_BOTH,
    WRAPS_X,
    first_wrapping,
    winding_vectors,
    wrapping,
    wrapping_code,
    wrapping_variable,
)


def _brute(mask, connectivity, tiles=5):
    """Tile the cell ``tiles x tiles`` times, label the open plane, and read which images of the centre
    cell's nodes share a cluster with them: the shifts ``(sx, sy)`` in {-1, 0, 1}^2 each realises."""
    nx, ny = mask.shape
    big = np.tile(mask, (tiles, tiles))
    structure = ndimage.generate_binary_structure(2, 1 if connectivity == 4 else 2)
    lab, _ = ndimage.label(big, structure=structure)
    c = tiles // 2
    centre = lab[c * nx:(c + 1) * nx, c * ny:(c + 1) * ny]
    shifts = set()
    for sx in (-1, 0, 1):
        for sy in (-1, 0, 1):
            if sx or sy:
                image = lab[(c + sx) * nx:(c + sx + 1) * nx, (c + sy) * ny:(c + sy + 1) * ny]
                if np.any((centre > 0) & (centre == image)):
                    shifts.add((sx, sy))
    v = np.array(sorted(shifts)) if shifts else np.zeros((0, 2))
    return (bool(v[:, 0].any()) if len(v) else False, bool(v[:, 1].any()) if len(v) else False,
            bool(len(v) and np.linalg.matrix_rank(v) == 2))


@pytest.mark.parametrize("connectivity", [4, 8])
def test_wrapping_equals_the_unrolled_plane(connectivity):
    # random site masks around the square lattice's thresholds (4: 0.593, 8: 0.407), rectangles too
    rng = np.random.default_rng(7)
    seen = set()
    for trial in range(300):
        shape = (int(rng.integers(4, 20)), int(rng.integers(4, 20)))
        density = rng.uniform(0.3, 0.75) if connectivity == 4 else rng.uniform(0.2, 0.55)
        mask = rng.random(shape) < density
        got = wrapping(mask, connectivity)
        assert got == _brute(mask, connectivity), (trial, shape, density)
        seen.add(got)
    assert len(seen) >= 3  # the sample holds wrapping and non-wrapping cells


def test_simple_shapes():
    band_x = np.zeros((6, 4), dtype=bool)
    band_x[:, 1] = True  # a column of nodes along x
    assert wrapping(band_x) == (True, False, False) and winding_vectors(band_x) == {1: [(1, 0)]}
    diagonal = np.eye(6, dtype=bool)
    assert wrapping(diagonal, 4) == (False, False, False)  # corners touch only: no edge joins them
    assert wrapping(diagonal, 8) == (True, True, False)  # one winding (1, 1): it wraps along its diagonal
    assert wrapping_code(diagonal, 8) == WRAPS_X + 2 and not wrapping_code(diagonal, 8) & WRAPS_BOTH
    full = np.ones((3, 5), dtype=bool)
    assert wrapping(full) == (True, True, True)
    assert wrapping(np.zeros((4, 4), dtype=bool)) == (False, False, False)
    with pytest.raises(ValueError, match="connectivity must be one of"):
        wrapping(full, 6)
    with pytest.raises(ValueError, match="boolean"):
        wrapping(full.astype(int))


def test_first_wrapping_brackets_the_threshold():
    area = np.array([0.1, 0.2, 0.3, 0.4])
    codes = np.array([0, WRAPS_X, WRAPS_X | 2 | WRAPS_BOTH, 7])
    assert first_wrapping(codes, area) == (0.2, 0.3)
    assert first_wrapping(codes, area, WRAPS_X) == (0.1, 0.2)
    below, at = first_wrapping(np.zeros(4, dtype=int), area)
    assert below == 0.4 and np.isnan(at)
    var = wrapping_variable([np.eye(4, dtype=bool), np.ones((4, 4), dtype=bool)])
    assert var.dims == ("step", "connectivity") and var.values.tolist() == [[0, 3], [7, 7]]
    assert var.attrs["flag_meanings"] == "wraps_x wraps_y wraps_both"
