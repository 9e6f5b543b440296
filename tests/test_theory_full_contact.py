"""The exact periodic full-contact solution (roughcontact.theory.full_contact): cosines, rectangular
cells, agreement with the hard-case suite's reference, and input checks."""

import math

import numpy as np
import pytest

from roughcontact.solver.halfspace import elastic_kernel
from roughcontact.theory import full_contact_load, full_contact_pressure, wavenumbers


def _coords(shape, length):
    (nx, ny), (lx, ly) = shape, length
    return (np.arange(nx) * lx / nx)[:, None], (np.arange(ny) * ly / ny)[None, :]


@pytest.mark.parametrize("n", [8, 33])
def test_single_cosine(n):
    a, length, e_star, p0 = 0.3, 2.5, 7.0, 1.2
    x, _ = _coords((n, n), (length, length))
    h = a * np.cos(2 * math.pi * x / length) * np.ones((1, n))
    p = full_contact_pressure(h, p0, e_star, length)
    assert p.shape == (n, n)
    expected = p0 + 0.5 * e_star * (2 * math.pi / length) * a * np.cos(2 * math.pi * x / length)
    np.testing.assert_allclose(p, np.broadcast_to(expected, (n, n)), rtol=0, atol=1e-12)
    # pi E* a / L exactly where a node sits at the trough (even n); the lowest node's pressure otherwise.
    trough = 1.0 if n % 2 == 0 else -np.cos(2 * math.pi * x / length).min()
    assert full_contact_load(h, e_star, length) == pytest.approx(math.pi * e_star * a / length * trough, rel=1e-13)
    # At exactly that load the trough's pressure is zero: the last node touches.
    assert full_contact_pressure(h, full_contact_load(h, e_star, length), e_star, length).min() == pytest.approx(
        0.0, abs=1e-12)


def test_rectangular_cell():
    shape, length, a, e_star = (16, 24), (2.0, 0.5), 0.05, 3.0
    x, y = _coords(shape, length)
    h = a * np.cos(2 * math.pi * x / length[0]) * np.cos(2 * math.pi * y / length[1])
    q = 2 * math.pi * math.hypot(1 / length[0], 1 / length[1])
    assert full_contact_load(h, e_star, length) == pytest.approx(0.5 * e_star * q * a, rel=1e-12)
    # A cosine along y alone: pi E* a / Ly, not / Lx.
    hy = a * np.cos(2 * math.pi * y / length[1]) * np.ones((shape[0], 1))
    assert full_contact_load(hy, e_star, length) == pytest.approx(math.pi * e_star * a / length[1], rel=1e-12)
    qgrid = wavenumbers(shape, length)
    assert qgrid.shape == shape and qgrid[0, 0] == 0.0
    assert qgrid[1, 0] == pytest.approx(2 * math.pi / length[0])
    assert qgrid[0, 1] == pytest.approx(2 * math.pi / length[1])
    assert qgrid[-1, 0] == qgrid[1, 0]  # fftfreq order: the last row is mode -1


@pytest.mark.parametrize("shape, length", [((32, 32), 1.0), ((32, 32), 3.0), ((20, 27), (2.0, 0.7))])
def test_solver_operator_closes_the_gap(shape, length):
    """Through the solver's own operator K (rfft2 multiplier), K p_exact - h is uniform: the gap vanishes."""
    h = np.random.default_rng(5).standard_normal(shape)
    p = full_contact_pressure(h, 2.5, 2.0, length)
    u = np.fft.irfft2(np.fft.rfft2(p - p.mean()) * elastic_kernel(shape, 2.0, length), s=shape)
    gap = u - h
    assert np.ptp(gap) <= 1e-11 * np.abs(h).max()
    assert full_contact_load(h, 2.0, length) == pytest.approx(2.5 - p.min(), rel=1e-12)


@pytest.mark.parametrize("call, name", [
    (lambda: full_contact_pressure(np.ones(4), 1.0), "h"),
    (lambda: full_contact_pressure(np.ones((2, 2, 2)), 1.0), "h"),
    (lambda: full_contact_pressure(np.zeros((0, 3)), 1.0), "h"),
    (lambda: full_contact_pressure(np.ones((4, 4)) * 1j, 1.0), "h"),
    (lambda: full_contact_pressure(np.full((4, 4), np.nan), 1.0), "h"),
    (lambda: full_contact_pressure(np.ones((4, 4)), np.inf), "p0"),
    (lambda: full_contact_pressure(np.ones((4, 4)), 1.0, e_star=0.0), "e_star"),
    (lambda: full_contact_load(np.ones((4, 4)), e_star=-1.0), "e_star"),
    (lambda: full_contact_load(np.ones((4, 4)), length=0.0), "length"),
    (lambda: full_contact_load(np.ones((4, 4)), length=(1.0, -2.0)), "length"),
    (lambda: full_contact_load(np.ones((4, 4)), length=(1.0, 2.0, 3.0)), "length"),
    (lambda: full_contact_load(np.ones((4, 4)), length="big"), "length"),
    (lambda: wavenumbers((4, 0), 1.0), "shape"),
    (lambda: wavenumbers(4.5, 1.0), "shape"),
    (lambda: wavenumbers((4, 4), np.nan), "length"),
])
def test_bad_inputs(call, name):
    with pytest.raises(ValueError, match=name):
        call()
