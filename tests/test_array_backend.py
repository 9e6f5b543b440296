"""The array backend seam (roughcontact.core.backend): the CuPy backend's code, run here with numpy.

CI has no GPU, so the CuPy backend's own code (cuFFT-style transforms through the array module,
transfers, the solver's fields created by ``xp``) runs with a stand-in module that is numpy under
CuPy's names (``asnumpy``, ``cuda``). The solve must agree with the default backend within the
solver's tolerance (another FFT library: the same problem, not the same bits) and meet every
invariant. On a lent GPU, ``ROUGHCONTACT_ARRAY_BACKEND=cupy`` runs the suites with CuPy itself
(benchmarks/gpu/run.sh; results in benchmarks/README.md).
"""
from __future__ import annotations

import sys
import types

import numpy as np
import pytest

from roughcontact.core import backend as backend_mod
from roughcontact.core.backend import SpectralProduct, get_backend
from roughcontact.solver import SolverSettings, solve_contact
from roughcontact.surfaces.synthetic import generate_surface
from solver_invariants import check_solution


def _numpy_as_cupy() -> types.ModuleType:
    """A module that is numpy with CuPy's extra names: arrays stay numpy arrays."""
    fake = types.ModuleType("cupy")
    fake.__getattr__ = lambda name: getattr(np, name)
    fake.asnumpy = np.asarray
    fake.ndarray = type("ndarray", (), {})  # no numpy array is a CuPy array (xarray asks)
    fake.cuda = types.SimpleNamespace(runtime=types.SimpleNamespace(getDeviceCount=lambda: 1),
                                      Device=lambda: types.SimpleNamespace(synchronize=lambda: None))
    return fake


@pytest.fixture
def stand_in_cupy(monkeypatch):
    monkeypatch.setitem(sys.modules, "cupy", _numpy_as_cupy())
    get_backend.cache_clear()
    yield get_backend("cupy")
    get_backend.cache_clear()


def test_cupy_missing_is_a_clear_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "cupy", None)  # import fails
    get_backend.cache_clear()
    try:
        with pytest.raises(ValueError, match=r"array_backend 'cupy' needs CuPy.*roughcontact\[gpu\].*'numpy'"):
            solve_contact(np.random.default_rng(0).random((16, 16)), [0.001], array_backend="cupy")
    finally:
        get_backend.cache_clear()


def test_unknown_backend_and_effects_are_refused():
    h = np.random.default_rng(0).random((16, 16))
    with pytest.raises(ValueError, match="array_backend must be one of"):
        solve_contact(h, [0.001], array_backend="jax")


def test_effects_refused_on_cupy(stand_in_cupy):
    h = np.random.default_rng(0).random((16, 16))
    with pytest.raises(ValueError, match="runs the elastic solver only.*PlasticityCap"):
        solve_contact(h, [0.001], array_backend="cupy", hardness=0.5)


def _sparse_reference(x, mult, nodes):
    """``irfft2(mult rfft2(xs))`` for ``xs`` = ``x`` at the flat ``nodes``, 0 elsewhere."""
    xs = np.zeros(x.shape)
    xs.flat[nodes] = x.flat[nodes]
    return np.fft.irfft2(np.fft.rfft2(xs) * mult, s=x.shape)


@pytest.mark.parametrize("in_place", [True, False])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(32, 32), (24, 40)])
def test_spectral_product_matches_numpy_fft(stand_in_cupy, dtype, shape, in_place):
    """Split or whole, the product and Parseval's quadratic form equal numpy.fft's in float64,
    with transforms in place or out of place (a kept input: a new node set must clear the old one)."""
    rng = np.random.default_rng(3)
    x = rng.standard_normal(shape)
    mult = rng.random((shape[0], shape[1] // 2 + 1))
    ref = np.fft.irfft2(np.fft.rfft2(x) * mult, s=shape)
    tol = 2e-6 if dtype == np.float32 else 1e-13
    node_sets = [np.flatnonzero(rng.random(shape) < 0.3) for _ in range(2)]  # sparse loads
    refs = [_sparse_reference(x, mult, nodes) for nodes in node_sets]
    for be in (get_backend("numpy"), stand_in_cupy):
        prod = SpectralProduct(be, shape, dtype, in_place=in_place)
        m = prod.multiplier(mult)
        for _ in range(2):  # a second round: the first's transforms must not leak into the loads
            prod.load_dense(x, 1.0)
            quad = prod.quadratic(prod.forward(), prod.quadratic_weights(mult))
            assert quad == pytest.approx(float(np.sum(x * ref)), rel=tol)
            with pytest.raises(ValueError, match="load the input first"):
                prod.forward()  # in place: the last forward consumed the input
            prod.load_dense(x, 1.0)
            out = np.asarray(prod(m), dtype=np.float64)
            assert out.shape == shape
            assert np.max(np.abs(out - ref)) <= tol * np.max(np.abs(ref))
            for nodes, ref_s in [*zip(node_sets, refs, strict=True), (node_sets[0], refs[0])]:
                pos = prod.positions(nodes)
                prod.load(pos, x.flat[nodes], 1.0)
                got = np.empty(nodes.size)
                prod.take(prod(m), pos, got)
                assert np.max(np.abs(got - ref_s.flat[nodes])) <= tol * np.max(np.abs(ref_s))


def test_products_work_in_place_only_with_shipped_plans():
    """In place by default only where the shipped wisdom has measured plans (FFTW_ESTIMATE's
    in-place pair is slower at other sizes); the free operator's padded product never (its input
    is 3/4 zero and kept between loads)."""
    from roughcontact.solver.halfspace import FreeHalfSpace

    be = get_backend("numpy")
    assert SpectralProduct(be, (32, 32), np.float32).in_place
    assert not SpectralProduct(be, (24, 40), np.float32).in_place
    assert not SpectralProduct(be, (480, 480), np.float64).in_place
    free = FreeHalfSpace(32)
    free.single(1.0)
    assert not free.prod32.in_place and free.precond.prod32.in_place


@pytest.mark.parametrize("boundary", ["periodic", "free"])
def test_stand_in_cupy_solves_as_numpy(stand_in_cupy, boundary):
    """The backend-neutral solver on the stand-in: same A/A0 within tol, invariants hold, host outputs."""
    h = generate_surface(64, 2, 16, 0.8, 1, rms_slope=0.1)
    loads = np.linspace(0.0005, 0.005, 4)
    ref = solve_contact(h, loads, boundary=boundary, store_fields=True)
    got = solve_contact(h, loads, settings=SolverSettings(boundary=boundary, array_backend="cupy"),
                        store_fields=True)
    assert got.attrs["fft_backend"] == "cupy"
    assert bool(got.converged.all())
    assert isinstance(got.pressure.values, np.ndarray)
    # A/A0 within a node or two of each other's; the fields within the solution's bound (check_solution)
    assert np.max(np.abs(got.area_fraction.values - ref.area_fraction.values)) <= 2.0 / h.size
    check_solution(got, h, tol=1e-8, boundary=boundary)


def test_array_backend_switch(solver_options, stand_in_cupy):
    """``set_options(array_backend=...)`` is the default of settings that name none."""
    solver_options(array_backend="cupy")
    assert SolverSettings().checked((8, 8)).array_backend == "cupy"
    assert SolverSettings(array_backend="numpy").checked((8, 8)).array_backend == "numpy"
    assert backend_mod.ARRAY_BACKENDS == ("numpy", "cupy")


@pytest.mark.parametrize("in_place", [True, False])
def test_products_of_one_kind_share_their_plans_and_stay_exact(in_place):
    """The pyFFTW plans and buffers are made once per shape, precision, layout and threads (planning with the
    shipped wisdom costs ~8 ms): two products of one kind share them, and used in turn, each on its own node
    set, each still gives its own product (a load clears what the other left in the shared input)."""
    from roughcontact.core.fft import has_pyfftw

    if not has_pyfftw():
        pytest.skip("pyFFTW's plans only")
    be = get_backend("numpy")
    shape = (24, 40)
    a, b = (SpectralProduct(be, shape, np.float64, in_place=in_place) for _ in range(2))
    assert a._plan is b._plan
    assert SpectralProduct(be, shape, np.float32, in_place=in_place)._plan is not a._plan
    big = (520, 520)  # above SHARED_PLAN_NODES: its own plans, freed with it
    assert SpectralProduct(be, big, np.float32)._plan is not SpectralProduct(be, big, np.float32)._plan
    rng = np.random.default_rng(5)
    x = rng.standard_normal(shape)
    mult = rng.random((shape[0], shape[1] // 2 + 1))
    ma, mb = a.multiplier(mult), b.multiplier(mult)
    nodes = [np.flatnonzero(rng.random(shape) < f) for f in (0.2, 0.6)]
    refs = [_sparse_reference(x, mult, k) for k in nodes]
    for _ in range(2):
        for prod, m, k, ref in ((a, ma, nodes[0], refs[0]), (b, mb, nodes[1], refs[1])):
            pos = prod.positions(k)
            prod.load(pos, x.flat[k], 1.0)
            got = np.empty(k.size)
            prod.take(prod(m), pos, got)
            assert np.max(np.abs(got - ref.flat[k])) <= 1e-13 * np.max(np.abs(ref))
