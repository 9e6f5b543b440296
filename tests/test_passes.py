"""The fused passes of the numpy backend (roughcontact.core.passes): numpy's bits, one pass each.

Each kernel stands in for numpy expressions inside the single solve, whose outputs must not change by a bit
(tests/solver_fingerprints.py); so each is compared here with those expressions for equality, not to a
tolerance, on shapes that exercise every branch (padded rows, blocks of 8 and 128 with rests, NaN), and the
single solve with the passes against the same solve with numpy's.
"""
from __future__ import annotations

import doctest

import numpy as np
import pytest

from roughcontact.core import passes
from roughcontact.core.backend import remap_rows
from roughcontact.core.passes import move_field, remap, scatter_scaled, weighted_squares
from roughcontact.solver import compressed, solve_contact
from roughcontact.surfaces.synthetic import generate_surface


def test_the_module_examples_run():
    assert doctest.testmod(passes).failed == 0


def _padded(rng, nx, ny):
    """A float32 ``(nx, ny)`` view with padded rows, as an in-place transform's output."""
    buf = rng.standard_normal((nx, 2 * (ny // 2 + 1))).astype(np.float32)
    return buf[:, :ny]


@pytest.mark.parametrize("shape", [(1, 1), (3, 5), (16, 16), (64, 40), (128, 128)])
@pytest.mark.parametrize("subtract", [True, False])
def test_move_field_is_numpys_two_passes_and_finds_the_least_w_off_the_mask(shape, subtract):
    rng = np.random.default_rng(sum(shape) + subtract)
    w = rng.standard_normal(shape) * 1e-3
    mask = rng.random(shape) < 0.3
    for r in (_padded(rng, *shape), rng.standard_normal(shape).astype(np.float32)):
        c = np.float32(rng.random() * 1e-2)
        expected = w.copy()
        rs = np.multiply(r, c)  # what settle's numpy passes did: r scaled in float32, then added in float64
        (np.subtract if subtract else np.add)(expected, rs, out=expected)
        r_before = r.copy()
        least = move_field(w, r, c, subtract, mask)
        assert np.array_equal(w, expected)
        assert np.array_equal(r, r_before)  # the product's output is left as it was
        assert least == (expected[~mask].min() if (~mask).any() else np.inf)


def test_move_field_ignores_nan_and_gives_inf_where_every_node_is_masked():
    w = np.array([[np.nan, 1.0], [2.0, 3.0]])
    r = np.zeros((2, 2), dtype=np.float32)
    assert move_field(w.copy(), r, np.float32(1.0), True, np.array([[False, True], [False, True]])) == 2.0
    assert move_field(w.copy(), r, np.float32(1.0), True, np.ones((2, 2), dtype=bool)) == np.inf


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 15, 16, 127, 128, 129, 136, 255, 256, 1000, 4099, 65 * 66, 513 * 1026])
def test_weighted_squares_is_numpys_pairwise_sum_to_the_bit(n):
    rng = np.random.default_rng(n)
    a = (rng.standard_normal(n) * 10.0 ** rng.integers(-3, 4, n)).astype(np.float32)
    wt = rng.random(n).astype(np.float32)
    square = np.multiply(a, a)
    np.multiply(square, wt, out=square)
    assert weighted_squares(a, wt) == float(square.sum())


def test_weighted_squares_keeps_nan_and_refuses_other_dtypes():
    a = np.ones(300, dtype=np.float32)
    a[200] = np.nan
    assert np.isnan(weighted_squares(a, np.ones(300, dtype=np.float32)))
    with pytest.raises(ValueError, match="float32"):
        weighted_squares(a.astype(np.float64), np.ones(300))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_scatter_scaled_is_numpys_scaled_copy_and_fancy_index(dtype):
    """Each product taken in float64 and rounded once, as ``np.multiply(..., out=buffer, casting="unsafe")``: over
    magnitudes that float32 overflows and rounds to subnormals, and scales that are not powers of two."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        values = rng.standard_normal(700) * 10.0 ** rng.integers(-45, 45, 700)
        scale = float(rng.standard_normal() * 10.0 ** rng.integers(-8, 8))
        pos = rng.choice(3000, 700, replace=False)
        expected, flat = np.zeros(3000, dtype=dtype), np.zeros(3000, dtype=dtype)
        with np.errstate(over="ignore"):  # (float32 overflows to inf, as the kernel's rounding does)
            expected[pos] = np.multiply(values, scale, out=np.empty(700, dtype=dtype), casting="unsafe")
        scatter_scaled(flat, pos, values, scale)
        assert np.array_equal(flat, expected, equal_nan=True)


@pytest.mark.parametrize("itype", [np.int32, np.int64])
@pytest.mark.parametrize("n1", [999, 1024, 1])
def test_remap_is_numpys_expression_and_keeps_the_dtype(itype, n1):
    """Both forms, a division (999) and a shift and mask (powers of two), on negative indices too (both floor)."""
    idx = np.random.default_rng(n1).integers(-5000, 1000 * 999, 5000).astype(itype)
    out = remap(idx, n1, n1 + 2)
    assert out.dtype == itype and np.array_equal(out, (idx // n1) * (n1 + 2) + idx % n1)
    assert np.array_equal(remap_rows(idx, n1, n1 + 2), out) and remap_rows(idx, n1, n1) is idx
    assert np.array_equal(remap(np.zeros(0, dtype=itype), n1, n1 + 2), np.zeros(0, dtype=itype))


@pytest.mark.parametrize("boundary", ["periodic", "free"])
def test_the_single_solve_gives_the_same_bits_with_the_fused_passes(monkeypatch, boundary):
    """The solve's every output with :func:`move_field` (and the measure's skip it allows) against numpy's passes."""
    h = generate_surface(128, 4, 32, 0.8, 2, rms_slope=0.1)
    loads = np.linspace(5e-4, 5e-3, 6)
    fused = solve_contact(h, loads, boundary=boundary, store_fields=[6])
    monkeypatch.setattr(compressed.CompressedKernels, "FUSED", False)
    plain = solve_contact(h, loads, boundary=boundary, store_fields=[6])
    assert int(fused["iterations"].sum()) > 0
    for name in plain.variables:
        if name != "wall_time":
            assert np.array_equal(fused[name].values, plain[name].values, equal_nan=True), name


def test_a_sparse_load_gives_numpys_input_and_refuses_mismatched_lengths_as_before():
    """``SpectralProduct.load``'s one-pass path (float64 values, index arrays of one length) writes numpy's input;
    anything else takes numpy's path, which refuses values that do not fit the positions."""
    from roughcontact.core.backend import SpectralProduct, get_backend

    prod = SpectralProduct(get_backend("numpy"), (16, 16), np.float32, in_place=True)
    rng = np.random.default_rng(5)
    pos = prod.positions(np.sort(rng.choice(256, 40, replace=False)))
    values = rng.standard_normal(40)
    prod.load(pos, values, 0.3)
    expected = np.zeros_like(prod._plan.flat)
    expected[pos] = np.multiply(values, 0.3, out=np.empty(40, dtype=np.float32), casting="unsafe")
    assert np.array_equal(prod._plan.flat, expected)
    with pytest.raises(ValueError):
        prod.load(pos, values[:39], 0.3)
