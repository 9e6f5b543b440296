"""Rectangular cells (nx != ny) and anisotropic pixels (dx != dy), periodic and free boundary.

Heights of shape ``(nx, ny)`` on a cell of sides ``length=(Lx, Ly)``, pixels ``dx = Lx / nx``
by ``dy = Ly / ny``. What is proven here, each against an exact solution or a peer, with the
tolerance and why next to each check:

- the periodic operator ``u(q) = 2 p(q) / (E* |q|)``, ``|q| = 2 pi sqrt((kx/Lx)^2 + (ky/Ly)^2)``:
  single Fourier modes along x and y exactly; Westergaard's wavy contact with the sinusoid
  along x and along y (half-width, pressure profile, mean gap); full contact,
  ``p = p0 + (E*/2) F^-1[|q| h_hat]``, to 1e-9; A/A0 equal to Tamaas' PolonskyKeerRey at
  every step;
- the free operator: Love's influence of a ``dx x dy`` pixel equals an independent
  quadrature of ``1 / r`` over the pixel to 1e-12 at near and far offsets and the point load
  ``dx dy / (pi E* r)`` far away; the FFT product equals a brute-force sum of Love's closed
  form over every pixel pair, and ContactMechanics' ``FreeFFTElasticHalfSpace``; A/A0 equal
  to ContactMechanics' free-boundary CG; the rectangular flat punch;
- every invariant of :func:`solver_invariants.check_solution` on periodic and free
  rectangles, with and without hardness, for every elastic method;
- the perimeter's edge lengths, the cluster areas ``dx dy`` per node and the attributes
  (``length_x``, ``length_y``, ``nx``, ``ny``; coordinates stepping by ``dx`` and ``dy``);
- validation of ``length`` and ``initial_pressure``; and that ``length=(L, L)`` on a square
  grid is bit for bit the square problem of ``length=L``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from roughcontact.core.fft import wavenumbers
from roughcontact.solver import contact_perimeter, solve_contact, solve_step
from roughcontact.solver.halfspace import (
    FreeHalfSpace,
    displacement,
    free_influence,
    pixel_influence_rect,
    pixel_influence_square,
)
from roughcontact.solver.workspace import ELASTIC_METHODS
from roughcontact.statistics.clusters import ClusterObserver, cluster_dataset, cluster_statistics, label_clusters
from roughcontact.surfaces.synthetic import generate_surface
from solver_invariants import check_solution, direct_free_displacement, pixel_integral

TOL = 1e-10

#: A rectangular cell with anisotropic pixels: dx = 1.5 / 48 = 0.03125, dy = 0.6 / 30 = 0.02.
SHAPE, SIDES = (48, 30), (1.5, 0.6)


def _rough(shape=SHAPE, seed=5):
    """A random rough rectangle: a corner of a square self-affine surface (not periodic on the rectangle)."""
    nx, ny = shape
    return generate_surface(2 * max(nx, ny), 2, min(16, max(nx, ny)), 0.8, seed, rms_slope=0.1)[:nx, :ny].copy()


def _wave_numbers(shape, sides):
    """``|q|`` on the rfft2 grid, written out here (not the solver's helper)."""
    (nx, ny), (lx, ly) = shape, sides
    mx = np.fft.fftfreq(nx, 1.0 / nx)[:, None]
    my = np.fft.rfftfreq(ny, 1.0 / ny)[None, :]
    return 2 * np.pi * np.sqrt((mx / lx) ** 2 + (my / ly) ** 2)


# --------------------------------------------------------------------------- periodic operator
def test_wavenumbers_keep_the_square_call_and_give_rectangles():
    kx, ky = wavenumbers(8)
    kx2, ky2 = wavenumbers((8, 8), (1.0, 1.0))
    np.testing.assert_array_equal(kx, kx2)
    np.testing.assert_array_equal(ky, ky2)
    kx, ky = wavenumbers((6, 10), (2.0, 0.5))
    assert kx.shape == (6, 1) and ky.shape == (1, 6)
    np.testing.assert_array_equal(kx[:, 0], np.array([0, 1, 2, -3, -2, -1]) / 2.0)
    np.testing.assert_array_equal(ky[0], np.arange(6) / 0.5)


@pytest.mark.parametrize("axis", [0, 1])
def test_single_modes_along_each_axis(axis):
    # u(q) = 2 p(q) / (E* |q|) exactly for one cosine of pressure (up to round-off: 1e-14
    # absolute on an O(1) field, as the square test), with |q| = 2 pi k / Lx along x and
    # 2 pi k / Ly along y.
    (nx, ny), (lx, ly), e_star, k = (40, 24), (3.0, 0.7), 2.5, 3
    side, n = (lx, nx) if axis == 0 else (ly, ny)
    wave = np.cos(2 * np.pi * k * np.arange(n) / n)
    p = np.broadcast_to(wave[:, None] if axis == 0 else wave[None, :], (nx, ny)).copy()
    u = displacement(p, e_star=e_star, length=(lx, ly))
    np.testing.assert_allclose(u, p * 2 / (e_star * 2 * np.pi * k / side), rtol=0, atol=1e-14)


def _westergaard_pressure(x, p0, p_star, lam):
    """Exact partial-contact pressure of the wavy surface at signed positions ``x`` in (-lam/2, lam/2]."""
    s2a = p0 / p_star
    inside = s2a - np.sin(np.pi * x / lam) ** 2
    return np.where(inside > 0, 2 * p0 * np.cos(np.pi * x / lam) * np.sqrt(np.clip(inside, 0, None)) / s2a, 0.0)


@pytest.mark.parametrize(("axis", "shape", "sides"), [(0, (512, 6), (1.0, 0.3)), (1, (6, 512), (0.45, 2.0))])
def test_westergaard_on_a_rectangle(axis, shape, sides):
    # h = Delta cos(2 pi s / lam) along one axis (lam the cell's side along it), uniform along
    # the other; dx != dy and Lx != Ly. Johnson 1985 section 13.2, as tests/test_solver_exact.py.
    delta, e_star = 0.01, 1.0
    n, lam = shape[axis], sides[axis]
    s_pos = np.arange(n) * (lam / n)
    wave = delta * np.cos(2 * np.pi * s_pos / lam)
    h = np.broadcast_to(wave[:, None] if axis == 0 else wave[None, :], shape).copy()
    p_star = np.pi * e_star * delta / lam
    ratios = np.array([0.1, 0.3, 0.5, 0.8])
    ds = solve_contact(h, ratios * p_star, e_star=e_star, length=sides, tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL, e_star=e_star, length=sides)
    s_signed = np.where(s_pos > lam / 2, s_pos - lam, s_pos)
    for k, s in enumerate(ratios):
        p = ds["contact_pressure"].values[k]
        # 1-D problem: every line along the other axis carries the same solution (1e-9 of the peak,
        # as the square test; measured identical)
        assert np.ptp(p, axis=1 - axis).max() <= 1e-9 * p.max()
        profile = p[:, 0] if axis == 0 else p[0, :]
        # half-width from A/A0 = 2a/lam to one grid spacing (the nodes sample the strip; measured
        # <= 0.5 spacing)
        a_exact = lam / np.pi * np.arcsin(np.sqrt(s))
        assert abs(float(ds["area_fraction"][k]) * lam / 2 - a_exact) <= lam / n
        # relative L2 error of the profile, 1% of the peak as the square test (edge cells where
        # p ~ sqrt(a - |x|); measured <= 9e-4 at 512 nodes)
        p_exact = _westergaard_pressure(s_signed, s * p_star, p_star, lam)
        assert np.linalg.norm(profile - p_exact) / (p_exact.max() * np.sqrt(n)) <= 0.01
        # mean gap Delta [(1 - s) + s ln s] to 1e-3 (an integral; measured <= 5e-5)
        g_exact = delta * ((1 - s) + s * np.log(s))
        assert float(ds["mean_gap"][k]) == pytest.approx(g_exact, rel=1e-3)


@pytest.mark.parametrize("method", ELASTIC_METHODS)
def test_full_contact_on_a_rectangle(solver_options, method, monkeypatch):
    # Past full contact the gap is 0 everywhere, so u = h - mean(h) and, K being diagonal in
    # Fourier space, p = p0 + (E*/2) F^-1[|q| h_hat] exactly. The solver's error is its tolerance
    # on the gap (1e-12 s) times the largest |q| E*/2 (~100 / s here): 1e-9 of the peak is a
    # bound with margin (measured <= 3e-13).
    solver_options(method=method)
    e_star = 2.0
    h = _rough()
    h -= h.mean()
    dp = np.fft.irfft2(0.5 * e_star * _wave_numbers(SHAPE, SIDES) * np.fft.rfft2(h), s=SHAPE)
    loads = [-1.5 * dp.min(), -3.0 * dp.min()]
    ds = solve_contact(h, loads, e_star=e_star, length=SIDES, tol=1e-12, store_fields=True)
    check_solution(ds, h, tol=1e-12, e_star=e_star, length=SIDES)
    for k, p0 in enumerate(loads):
        assert float(ds["area_fraction"][k]) == 1.0
        p = ds["contact_pressure"].values[k]
        assert np.abs(p - (p0 + dp)).max() <= 1e-9 * p.max()


@pytest.mark.peer
def test_tamaas_on_a_rectangle():
    # Tamaas' basic_2d model on [Lx, Ly] x [nx, ny] solves the same discrete problem (same
    # kernel, nodal collocation; its surface array is (nx, ny) too): A/A0 equal at every step to
    # 1e-4 relative as the square peer test (measured node for node, pressures within 2e-10 of
    # the peak). PolonskyKeerRey with the pressure as primal variable, as the square peer test:
    # with the gap as primal its traction is left ~1e-9 positive off the contact set, so its
    # node count would not be the contact area.
    tm = pytest.importorskip("tamaas", reason="tamaas is not installed: peer comparison skipped")
    tm.set_log_level(tm.LogLevel.error)
    h = _rough()
    loads = [0.001, 0.003, 0.008]
    ds = solve_contact(h, loads, length=SIDES, tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL, length=SIDES)
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, list(SIDES), list(SHAPE))
    model.E, model.nu = 1.0, 0.0  # E* = 1
    solver = tm.PolonskyKeerRey(model, h, 1e-12, tm.PolonskyKeerRey.pressure, tm.PolonskyKeerRey.pressure)
    for k, p0 in enumerate(loads):
        solver.solve(p0)
        traction = np.asarray(model.traction)
        assert traction.shape == SHAPE and traction.mean() == pytest.approx(p0, rel=1e-10)
        a_tm = np.count_nonzero(traction > 0) / traction.size
        a = float(ds["area_fraction"][k])
        print(f"p0={p0}: A/A0 {a:.6f} vs Tamaas {a_tm:.6f}")
        assert abs(a - a_tm) <= 1e-4 * a_tm


# --------------------------------------------------------------------------- free operator
@pytest.mark.parametrize("rho", [0.4, 1.0, 2.5])
def test_influence_matches_quadrature_near_and_far(rho):
    # Love's closed form vs an independent tensor Gauss-Legendre quadrature of 1 / r over the
    # dx x dy pixel (Duffy's substitution for the self-term; 1e-15 against 60-digit values).
    # The closed form loses ~1e-16 x the offset in pixels to cancellation: 1e-12 holds out to
    # the far corner here (~300 pixels; measured <= 1.2e-13).
    nx, ny, e_star = 200, 120, 3.0
    lx = 2.0
    ly = rho * lx * ny / nx  # dy / dx = rho
    dx = lx / nx
    k = free_influence((nx, ny), e_star, (lx, ly))
    assert k.shape == (2 * nx, 2 * ny)
    # even in both offsets: entry 2n - i is offset i, along each axis
    np.testing.assert_array_equal(k[1:, :], k[:0:-1, :])
    np.testing.assert_array_equal(k[:, 1:], k[:, :0:-1])
    offsets = [(0, 0), (1, 0), (0, 1), (1, 1), (2, 3), (3, 2), (7, 0), (0, 9), (40, 25), (nx - 1, ny - 1),
               (nx, 0), (0, ny), (nx, ny)]
    i, j = (np.array(v, dtype=float) for v in zip(*offsets, strict=True))
    ref = pixel_integral(i, j * rho, rho) * dx / (math.pi * e_star)
    got = k[i.astype(int), j.astype(int)]
    assert np.abs(got / ref - 1).max() <= 1e-12
    # far away the point load dx dy / (pi E* r), with the quadrupole correction of a uniform
    # rectangle, <3(s.e)^2 - s^2> / (2 r^2) = (dx^2 (3 cos^2 - 1) + dy^2 (3 sin^2 - 1)) / (24 r^2);
    # the next term is O((pixel / r)^4): measured <= 3e-10 at these distances, 1e-8 allowed; the plain
    # point load is off by the quadrupole term, bounded by (dx^2 + dy^2) / (8 r^2)
    dy = rho * dx
    for a, b in ((nx, 0), (0, ny), (nx, ny), (nx // 2, ny)):
        x, y = a * dx, b * dy
        r = math.hypot(x, y)
        point = dx * dy / (math.pi * e_star * r)
        quad = (dx**2 * (3 * x * x / r**2 - 1) + dy**2 * (3 * y * y / r**2 - 1)) / (24 * r**2)
        assert k[a, b] == pytest.approx(point * (1 + quad), rel=1e-8)
        assert k[a, b] == pytest.approx(point, rel=(dx**2 + dy**2) / (8 * r**2))


def test_square_pixels_reduce_to_the_square_influence():
    # The aspect-ratio formula with rho = 1 performs the square one's operations: bit for bit.
    np.testing.assert_array_equal(pixel_influence_rect(37, 37, 1.0), pixel_influence_square(37))
    # a rectangle of square pixels (nx != ny, dx == dy) samples the same function
    np.testing.assert_array_equal(pixel_influence_rect(20, 33, 1.0), pixel_influence_square(33)[:21, :34])


def _love(x, y, a, b):
    """``pi E* u`` at ``(x, y)`` under unit pressure on ``[-a, a] x [-b, b]``: Love's mixed difference, plainly.

    ``F(X, Y) = X ln(Y + r) + Y ln(X + r)``; for a negative argument ``ln(Y + r)`` is written
    ``2 ln|X| - ln(r - Y)`` (the same number without the cancellation of ``r + Y``).
    """
    def log_plus(s, t):  # ln(s + sqrt(s^2 + t^2))
        r = math.hypot(s, t)
        return math.log(s + r) if s >= 0 else 2 * math.log(abs(t)) - math.log(r - s)

    def f(xx, yy):
        return xx * log_plus(yy, xx) + yy * log_plus(xx, yy)

    return f(x + a, y + b) - f(x - a, y + b) - f(x + a, y - b) + f(x - a, y - b)


@pytest.mark.parametrize("backend", ["pyfftw", "numpy"])
def test_free_product_is_the_pixel_pair_sum(backend, monkeypatch):
    # 7 x 9 nodes (x padded to 16 > 2 nx: padded_shape), dx = 0.5, dy = 0.3: the Hockney FFT
    # product equals the brute-force sum over every pair of pixels of Love's closed form
    # (evaluated plainly above, ~1e-15 at these offsets), to 1e-13 of max |u| (round-off of the
    # transforms, as the square test), and the quadrature-based direct sum of solver_invariants
    # to the same.
    if backend == "numpy":
        monkeypatch.setenv("ROUGHCONTACT_FFT", "numpy")
    else:
        pytest.importorskip("pyfftw")
    (nx, ny), (lx, ly), e_star = (7, 9), (3.5, 2.7), 1.7
    dx, dy = lx / nx, ly / ny
    p = np.random.default_rng(7).random((nx, ny))
    ref = np.zeros((nx, ny))
    for i in range(nx):
        for j in range(ny):
            for k in range(nx):
                for m in range(ny):
                    ref[i, j] += p[k, m] * _love((i - k) * dx, (j - m) * dy, dx / 2, dy / 2)
    ref /= math.pi * e_star
    u = displacement(p, e_star=e_star, length=(lx, ly), boundary="free")
    assert np.abs(u - ref).max() <= 1e-13 * np.abs(ref).max()
    quad = direct_free_displacement(p, e_star, (lx, ly))
    assert np.abs(quad - ref).max() <= 1e-13 * np.abs(ref).max()
    # the operator in internal units (E* = Lx = 1), both precisions: float32 to its round-off
    op = FreeHalfSpace((nx, ny), aspect=ly / lx)
    assert op.backend == backend
    np.testing.assert_allclose(op.apply(p) * (lx / e_star), ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    op.single(0.25)
    u32 = op.apply32(p).astype(np.float64) * 0.25 * (lx / e_star)
    assert np.abs(u32 - ref).max() <= 1e-5 * np.abs(ref).max()


@pytest.mark.peer
def test_contact_mechanics_free_rectangle():
    # ContactMechanics' FreeFFTElasticHalfSpace on (nx, ny) with physical sizes (Lx, Ly) is the
    # same operator (Love's rectangle, Hockney's padding): displacements to 1e-12 of max |u|
    # (measured 8e-14); its free-boundary Polonsky-Keer CG solves the same discrete problem, A/A0
    # equal to 1e-4 relative (measured node for node, pressures within 3e-10 of the peak).
    cm = pytest.importorskip("ContactMechanics", reason="ContactMechanics is not installed: peer comparison skipped")
    from ContactMechanics.Optimization import constrained_conjugate_gradients

    (nx, ny), (lx, ly), e_star = (40, 28), (2.0, 0.9), 3.0
    dx, dy = lx / nx, ly / ny
    p = np.random.default_rng(1).random((nx, ny))
    substrate = cm.FreeFFTElasticHalfSpace((nx, ny), e_star, physical_sizes=(lx, ly))  # "young" is E*
    u_cm = -substrate.evaluate_disp(p * dx * dy)  # forces per node; opposite sign convention
    u = displacement(p, e_star=e_star, length=(lx, ly), boundary="free")
    assert np.abs(u - u_cm).max() <= 1e-12 * np.abs(u).max()

    h = _rough((nx, ny), seed=0)
    loads = [0.0005, 0.002, 0.005]
    ds = solve_contact(h, loads, e_star=e_star, length=(lx, ly), tol=TOL, store_fields=True, boundary="free")
    check_solution(ds, h, tol=TOL, e_star=e_star, length=(lx, ly), boundary="free")
    for k, p0 in enumerate(loads):
        res = constrained_conjugate_gradients(substrate, h, external_force=p0 * lx * ly, pentol=1e-12,
                                              forcetol=1e-12, maxiter=100000)
        assert res.success
        forces = np.asarray(res.jac)[:nx, :ny]
        forces = forces if forces.sum() > 0 else -forces
        a_cm = np.count_nonzero(forces > 0) / forces.size
        a = float(ds["area_fraction"][k])
        print(f"p0={p0}: A/A0 {a:.6f} vs ContactMechanics {a_cm:.6f}")
        assert abs(a - a_cm) <= 1e-4 * a_cm


# --------------------------------------------------------------------------- invariants
@pytest.mark.parametrize("boundary", ["periodic", "free"])
@pytest.mark.parametrize("hardness", [None, 0.03])
def test_invariants_on_a_rectangle(boundary, hardness):
    # Every invariant of check_solution (mean p = p0 to 1e-10, bounds, gap sign and
    # complementarity to tol, zero-mean gap on the elastic contact set, mean gap, perimeter,
    # attributes, the gap against an independent displacement: numpy.fft, or the direct sum
    # with the quadrature influence for the free patch), on a 36 x 22 cell with dx != dy.
    shape, sides = (36, 22), (1.2, 0.5)
    h = _rough(shape, seed=2)
    loads = [0.001, 0.004, 0.01]
    ds = solve_contact(h, loads, length=sides, tol=TOL, store_fields=True, boundary=boundary, hardness=hardness,
                       e_star=1.5, observers=[ClusterObserver(sides, periodic=boundary == "periodic")])
    check_solution(ds, h, tol=TOL, e_star=1.5, length=sides, hardness=hardness, boundary=boundary)
    if hardness is not None:
        assert ds["plastic_area_fraction"].values[-1] > 0  # the cap is really active
    for k in range(len(loads)):  # clusters of the rectangle, no wrap on the free patch
        st = cluster_statistics(ds["contact_pressure"].values[k] > 0, sides, periodic=boundary == "periodic")
        assert ds["cluster_count"].values[k] == st["count"]
        assert ds["cluster_max_area"].values[k] == st["max_area"]


@pytest.mark.parametrize("method", ELASTIC_METHODS)
def test_every_method_on_a_rectangle(solver_options, method, monkeypatch):
    # The same answer from every elastic iteration: contact sets equal, pressures within
    # what the tolerance allows (the gap to 1e-10 s; measured 1.3e-10 of the peak): 1e-7.
    solver_options(method=method)
    h = _rough()
    loads = [0.002, 0.006]
    ds = solve_contact(h, loads, length=SIDES, tol=TOL, store_fields=True)
    assert ds.attrs["elastic_method"] == method
    check_solution(ds, h, tol=TOL, length=SIDES)
    solver_options(method="pk")
    ref = solve_contact(h, loads, length=SIDES, tol=TOL, store_fields=True)
    np.testing.assert_array_equal(ds["area_fraction"].values, ref["area_fraction"].values)
    p, p_ref = ds["contact_pressure"].values, ref["contact_pressure"].values
    assert np.abs(p - p_ref).max() <= 1e-7 * p_ref.max()


@pytest.mark.parametrize("boundary", ["periodic", "free"])
def test_flat_rectangle(boundary):
    # Periodic: the exact uniform pressure p = p0, g = 0, no iteration. Free: the rigid
    # rectangular flat punch: all nodes in contact, the punch rigid (u uniform to the
    # tolerance), pressure highest at the corners and symmetric under both mirror flips (the
    # discrete problem is; the solution to its tolerance: 1e-8 of the peak, measured 3e-10),
    # linear in p0, and the perimeter the rectangle's, 2 (Lx + Ly) / (Lx Ly).
    (nx, ny), (lx, ly), e_star, p0 = (16, 24), (1.0, 2.0), 2.0, 0.01
    h = np.full((nx, ny), 0.3)
    ds = solve_contact(h, [p0, 2 * p0], e_star=e_star, length=(lx, ly), tol=TOL, store_fields=True,
                       boundary=boundary)
    check_solution(ds, h, tol=TOL, e_star=e_star, length=(lx, ly), boundary=boundary)
    p = ds["contact_pressure"].values
    assert np.all(ds["area_fraction"].values == 1.0) and ds["converged"].all()
    assert ds["contact_perimeter"].values[0] == (0.0 if boundary == "periodic" else
                                                 pytest.approx(2 * (lx + ly) / (lx * ly), rel=1e-14))
    if boundary == "periodic":
        assert np.all(p[0] == p0) and np.all(ds["iterations"].values == 0)
        assert np.all(ds["gap"].values == 0)
        return
    assert ds["iterations"].values[1] == 0
    np.testing.assert_allclose(p[1], 2 * p[0], rtol=1e-15)
    assert p[0].mean() == pytest.approx(p0, rel=1e-10)
    assert p[0][0, 0] == pytest.approx(p[0].max(), rel=1e-8) and p[0][0, 0] > 5 * p[0][nx // 2, ny // 2]
    assert np.abs(p[0] - p[0][::-1, :]).max() <= 1e-8 * p[0].max()
    assert np.abs(p[0] - p[0][:, ::-1]).max() <= 1e-8 * p[0].max()
    u = displacement(p[0], e_star=e_star, length=(lx, ly), boundary="free")
    assert np.ptp(u) <= TOL * u.mean() * 10
    with pytest.raises(ValueError, match="hardness: a perfectly flat surface"):
        solve_contact(h, [p0], hardness=1.0, length=(lx, ly), boundary="free")


def test_step_api_on_a_rectangle():
    # solve_step on a rectangle, from a given initial pressure: the same solution as
    # solve_contact's step (to the tolerance: 1e-7 of the peak, measured 2e-11), its gap that of
    # displacement() (1e-9 of the rms height, as the square free-boundary test).
    h = _rough()
    ds = solve_contact(h, [0.004], length=SIDES, tol=TOL, store_fields=True, boundary="free")
    init = np.random.default_rng(0).random(SHAPE)
    res = solve_step(h, 0.004, length=SIDES, tol=TOL, boundary="free", initial_pressure=init)
    assert res.converged and res.pressure.shape == SHAPE
    p = ds["contact_pressure"].values[0]
    assert np.abs(res.pressure - p).max() <= 1e-7 * p.max()
    g = displacement(res.pressure, length=SIDES, boundary="free") - h
    g -= g[res.pressure > 0].mean()
    np.testing.assert_allclose(res.gap, g, rtol=0, atol=1e-9 * h.std())
    assert res.contact_perimeter == contact_perimeter(res.pressure > 0, SIDES, periodic=False)


# --------------------------------------------------------------------------- outputs
def test_attributes_coordinates_and_file():
    # The rectangle's cell in the attributes (numbers only: netCDF writes them) and the field
    # coordinates stepping by dx and dy; the file reads back the same.
    h = _rough()
    ds = solve_contact(h, [0.003], length=SIDES, store_fields=True)
    nx, ny = SHAPE
    assert (ds.attrs["length_x"], ds.attrs["length_y"], ds.attrs["nx"], ds.attrs["ny"]) == (*SIDES, nx, ny)
    assert "length" not in ds.attrs and "n" not in ds.attrs
    np.testing.assert_array_equal(ds["x"].values, np.arange(nx) * (SIDES[0] / nx))
    np.testing.assert_array_equal(ds["y"].values, np.arange(ny) * (SIDES[1] / ny))
    assert "rectangular pixel" in solve_contact(h, [0.003], length=SIDES, boundary="free").attrs["solver_description"]
    import xarray as xr

    path = __import__("tempfile").mkdtemp() + "/rect.nc"
    ds.to_netcdf(path)
    with xr.open_dataset(path) as back:
        assert back.attrs["length_y"] == SIDES[1] and back.attrs["ny"] == ny
        np.testing.assert_array_equal(back["contact_pressure"].values, ds["contact_pressure"].values)


def test_perimeter_and_clusters_on_a_rectangle():
    # One 2 x 3 block of contact nodes away from the edges of a 6 x 8 cell with dx = 0.5,
    # dy = 0.25: its boundary has 2 x 3 edges between neighbours along x (dy long each) and
    # 2 x 2 between neighbours along y (dx long): 6 dy + 4 dx = 3.5 over A0 = 3 x 2.
    (nx, ny), (lx, ly) = (6, 8), (3.0, 2.0)
    mask = np.zeros((nx, ny), dtype=bool)
    mask[2:4, 3:6] = True
    assert contact_perimeter(mask, (lx, ly)) == pytest.approx(3.5 / 6.0, rel=1e-15)
    assert contact_perimeter(mask, (lx, ly), periodic=False) == pytest.approx(3.5 / 6.0, rel=1e-15)
    # a strip across the x edge: wraps on the torus (one cluster, no edge across x), not on a patch
    strip = np.zeros((nx, ny), dtype=bool)
    strip[0, 2:4] = strip[-1, 2:4] = True
    # torus: one 2 x 2 block, 4 edges dy long and 4 dx long; patch: two 1 x 2 blocks, 4 + 2 each
    assert contact_perimeter(strip, (lx, ly)) == pytest.approx((4 * 0.25 + 4 * 0.5) / 6.0, rel=1e-15)
    assert contact_perimeter(strip, (lx, ly), periodic=False) == pytest.approx(2 * (4 * 0.25 + 2 * 0.5) / 6.0,
                                                                               rel=1e-15)
    assert label_clusters(strip, square=False)[1] == 1
    assert cluster_statistics(strip, (lx, ly), periodic=False)["count"] == 2
    st = cluster_statistics(mask, (lx, ly))
    assert st["areas_pixels"].tolist() == [6] and st["areas"][0] == 6 / 48
    assert st["areas_physical"][0] == pytest.approx(6 * 0.5 * 0.25, rel=1e-15)  # nodes x dx dy
    stats = cluster_dataset([mask, strip], [1, 2], (lx, ly))
    assert stats.attrs["length_x"] == lx and stats.attrs["nx"] == nx and "n" not in stats.attrs
    assert stats["cluster_count"].values.tolist() == [1, 1]
    assert stats["area_bin_low"].values[0] == pytest.approx(1 / (nx * ny))
    with pytest.raises(ValueError, match="square"):
        cluster_statistics(mask, 1.0)  # a float length means a square cell
    with pytest.raises(ValueError, match=r"length: a single float means a square cell"):
        contact_perimeter(mask, 1.0)


# --------------------------------------------------------------------------- arguments
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(length=1.0), r"length: a single float means a square cell, and heights must be a 2-D square array "
                           r"\(n, n\) for it; .*give length=\(Lx, Ly\), .* A 2-D array is one map: \d+ profiles of "
                           r"\d+ points are not solved at once; solve each row as a profile \(a 1-D array\)"),
        (dict(length=(1.0,)), r"length must be a finite real number > 0 \(square cell\) or a pair \(Lx, Ly\) .* "
                              r"got 1 values"),
        (dict(length=(1.0, 2.0, 3.0)), r"length must be .* a pair \(Lx, Ly\) .*got 3 values"),
        (dict(length=np.ones((2, 2))), r"length must be .* a pair \(Lx, Ly\)"),
        (dict(length=(1.0, np.inf)), r"length must be .* a pair \(Lx, Ly\) of finite real numbers > 0, got"),
        (dict(length=(1.0, np.nan)), r"length must be .* a pair \(Lx, Ly\) of finite real numbers > 0"),
        (dict(length=(0.0, 1.0)), r"length must be .* a pair \(Lx, Ly\) of finite real numbers > 0"),
        (dict(length=(1.0, -2.0)), r"length must be .* a pair \(Lx, Ly\) of finite real numbers > 0"),
        (dict(length=("1", 2.0)), r"length must be .* a pair \(Lx, Ly\) .*got str '1'"),
        (dict(length=(True, 2.0)), r"length must be .* got bool True"),
        (dict(heights=np.zeros((8, 3))), r"heights must be at least 4 x 4 \(nx, ny >= 4\)"),
        (dict(pressures=[1e299]), r"p0 must be <= 1e\+300 / \(nx \* ny\)"),
        (dict(pressures=[1e-120]), r"every p0 \* Lx / \(e_star \* s\) must be in \[1e-100, 1e\+100\]"),
    ],
)
def test_bad_arguments_are_refused(kwargs, match):
    args = dict(heights=_rough((8, 12)), pressures=[0.01], length=(1.0, 1.5))
    args.update(kwargs)
    heights, pressures = args.pop("heights"), args.pop("pressures")
    with pytest.raises(ValueError, match=match):
        solve_contact(heights, pressures, **args)
    if "pressures" not in kwargs:
        with pytest.raises(ValueError, match=match):
            solve_step(heights, 0.01, **args)
        with pytest.raises(ValueError, match=match.replace("heights must", "pressure must")):
            displacement(heights if heights.shape == (8, 3) else np.ones(heights.shape), **args)


def test_initial_pressure_must_have_the_shape_of_heights():
    h = _rough((8, 12))
    with pytest.raises(ValueError, match=r"initial_pressure must have shape \(8, 12\), the shape of heights, "
                                         r"got \(12, 8\)"):
        solve_step(h, 0.01, length=(1.0, 1.5), initial_pressure=np.ones((12, 8)))
    with pytest.raises(ValueError, match=r"initial_pressure must have shape \(8, 12\)"):
        solve_step(h, 0.01, length=(1.0, 1.5), initial_pressure=np.ones((8, 8)))


# --------------------------------------------------------------------------- the square case
@pytest.mark.parametrize("boundary", ["periodic", "free"])
@pytest.mark.parametrize("hardness", [None, 0.03])
def test_a_square_pair_is_the_square_problem(boundary, hardness):
    # length=(L, L) (tuple, list or array) on an n x n grid is the square cell of length=L: the
    # same datasets bit for bit, attributes included (length and n, plus nx = ny = n).
    h = generate_surface(32, 2, 8, 0.8, 3, rms_slope=0.1) * 0.7
    kwargs = dict(e_star=2.0, tol=TOL, store_fields=True, boundary=boundary, hardness=hardness)
    periodic = boundary == "periodic"
    ref = solve_contact(h, [0.001, 0.004], length=0.7, observers=[ClusterObserver(0.7, periodic)], **kwargs)
    assert ref.attrs["length"] == 0.7 and ref.attrs["n"] == ref.attrs["nx"] == ref.attrs["ny"] == 32
    assert "length_x" not in ref.attrs
    for pair in ((0.7, 0.7), [0.7, 0.7], np.array([0.7, 0.7])):
        ds = solve_contact(h, [0.001, 0.004], length=pair, observers=[ClusterObserver(pair, periodic)], **kwargs)
        assert ds.attrs == ref.attrs
        assert list(ds.variables) == list(ref.variables)
        for name in ref.variables:
            if name != "wall_time":
                np.testing.assert_array_equal(ds[name].values, ref[name].values, err_msg=name)
    res, res_pair = solve_step(h, 0.002, length=0.7, boundary=boundary), solve_step(h, 0.002, length=(0.7, 0.7),
                                                                                      boundary=boundary)
    np.testing.assert_array_equal(res.pressure, res_pair.pressure)
    np.testing.assert_array_equal(res.gap, res_pair.gap)
    np.testing.assert_array_equal(displacement(res.pressure, length=0.7, boundary=boundary),
                                  displacement(res.pressure, length=(0.7, 0.7), boundary=boundary))
    mask = res.pressure > 0
    assert contact_perimeter(mask, (0.7, 0.7), periodic) == contact_perimeter(mask, 0.7, periodic)
    assert cluster_dataset([mask], [1], (0.7, 0.7)).attrs == cluster_dataset([mask], [1], 0.7).attrs
