"""The batched solve (issue 48): B surfaces of one grid under one load schedule, solved together.

A batch must give each case what the single solve gives it: the same A/A0, mean gap and converged
flags, and the iteration counts within one per step (the batched transforms round differently from
pyFFTW's in-place plans). One case of each batch is broadband (k_s = N/2, H = 0.2) with a small
rms slope, so that half its nodes touch at the last load: it needs 1.8x the iterations of the
others, which sit converged and frozen while it goes on. The CuPy code paths run through the
backend seam with numpy standing in for CuPy, as in tests/test_array_backend.py; the fused CUDA
kernels need a GPU (benchmarks/gpu/run.sh).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from roughcontact.solver import SolverSettings, solve_contact
from roughcontact.solver.batch import CHECK_EVERY, solve_contact_batch
from roughcontact.statistics.clusters import ClusterObserver
from roughcontact.surfaces.synthetic import generate_surface
from test_array_backend import stand_in_cupy  # noqa: F401 (fixture)

N = 128
LOADS = np.linspace(0.005 / 8, 0.005, 8)
#: (k_l, k_s, H, seed, rms slope): the paper's kind of surface, and a broadband one in wide contact
#: (the slow case: 204 iterations against 113 for case 0)
CASES = [(2, 16, 0.8, 0, 0.1), (1, 64, 0.2, 1, 0.02), (4, 32, 0.5, 2, 0.1), (2, 8, 0.8, 3, 0.1),
         (1, 32, 0.84, 4, 0.1), (8, 32, 0.52, 5, 0.1), (16, 32, 0.8, 6, 0.1), (2, 64, 0.36, 7, 0.05)]


@functools.cache
def _surface(k):
    k_l, k_s, hurst, seed, slope = CASES[k]
    return generate_surface(N, k_l, k_s, hurst, seed, rms_slope=slope)


@functools.cache
def _single(k):
    return solve_contact(_surface(k), LOADS)


def _agree(ds, cases):
    """Each case of the batch ``ds`` against its single solve."""
    assert ds.sizes["case"] == len(cases) and ds.sizes["step"] == LOADS.size
    for b, k in enumerate(cases):
        ref = _single(k)
        np.testing.assert_array_equal(ds.converged.values[b], ref.converged.values)
        assert bool(ds.converged.values[b].all())
        # A/A0: the same contact set to a node or two (float32 round-off at the tolerance)
        assert np.max(np.abs(ds.area_fraction.values[b] - ref.area_fraction.values)) <= 2.0 / N**2
        np.testing.assert_allclose(ds.mean_gap.values[b], ref.mean_gap.values, rtol=1e-6)
        assert np.max(np.abs(ds.iterations.values[b] - ref.iterations.values)) <= 1, (k, ds.iterations.values[b],
                                                                                     ref.iterations.values)
        assert np.all(ds.residual.values[b] <= 1e-8)


@pytest.mark.parametrize("cases", [(1,), (0, 1, 2)], ids=["B1", "B3"])
def test_batch_agrees_with_single_solves(cases):
    ds = solve_contact(np.stack([_surface(k) for k in cases]), LOADS)
    _agree(ds, cases)
    assert ds.attrs["batch_size"] == len(cases) and ds.attrs["elastic_method"] == "pk-fourier-f32"
    assert ds.area_fraction.dims == ("case", "step") and ds.pressure.dims == ("step",)
    if len(cases) > 1:
        # the broadband case needs many more iterations: the others wait converged and frozen
        its = ds.iterations.values.sum(axis=1)
        assert its[1] > 1.5 * max(its[0], its[2])
        assert np.all(ds.rounds.values >= ds.iterations.values.max(axis=0))


def test_batch_of_eight_agrees_with_single_solves():
    cases = tuple(range(8))
    _agree(solve_contact_batch(np.stack([_surface(k) for k in cases]), LOADS), cases)


def test_check_every_changes_rounds_not_iterations():
    """A case waiting for its float64 recomputation idles until the next check: more rounds, the same
    iterations and results whatever ``check_every``."""
    h = np.stack([_surface(0), _surface(1)])
    one = solve_contact_batch(h, LOADS, check_every=1)
    some = solve_contact_batch(h, LOADS, check_every=5)
    np.testing.assert_array_equal(some.iterations.values, one.iterations.values)
    np.testing.assert_array_equal(some.area_fraction.values, one.area_fraction.values)
    np.testing.assert_allclose(some.mean_gap.values, one.mean_gap.values, rtol=1e-12)
    assert some.rounds.values.sum() > one.rounds.values.sum()
    # with a check every round no case waits: the rounds are the slowest case's iterations
    np.testing.assert_array_equal(one.rounds.values, one.iterations.values.max(axis=0))
    assert one.attrs["check_every"] == 1 and CHECK_EVERY["numpy"] == 1


def test_unconverged_case_stops_at_max_iter_like_the_single_solve():
    """``max_iter`` reached: the case stops there, unconverged, as alone; no fallback runs."""
    loads = LOADS[:2]
    ref = solve_contact(_surface(1), loads, max_iter=6)
    ds = solve_contact(np.stack([_surface(0), _surface(1)]), loads, max_iter=6)
    np.testing.assert_array_equal(ds.iterations.values[1], ref.iterations.values)
    np.testing.assert_array_equal(ds.converged.values[1], ref.converged.values)
    assert not ds.converged.values[1].any()


def test_fallback_runs_on_the_stalled_case_alone(monkeypatch):
    """A case whose batched iteration stalls moves on to the single solve's fallbacks, from its pressure."""
    from roughcontact.solver.batch import iteration as batch_iteration

    monkeypatch.setattr(batch_iteration, "STALL_WINDOW", 0)  # the batched iteration "stalls" at once, every case
    ds = solve_contact_batch(np.stack([_surface(0), _surface(2)]), LOADS[:3])
    assert bool(ds.converged.values.all())
    np.testing.assert_array_equal(ds.solver_path.values, 2)  # pk-fourier (float64 products) ended every step
    for b, k in enumerate((0, 2)):
        ref = _single(k)
        assert np.max(np.abs(ds.area_fraction.values[b] - ref.area_fraction.values[:3])) <= 2.0 / N**2


def test_batch_through_the_backend_seam(stand_in_cupy):  # noqa: F811
    """The CuPy code paths (transfers, the transforms of the array module, the kernels' plain form)
    with numpy standing in for CuPy: the same answers as the numpy backend."""
    cases = (0, 1)
    ds = solve_contact_batch(np.stack([_surface(k) for k in cases]), LOADS[:4],
                             SolverSettings(array_backend="cupy"))
    assert ds.attrs["fft_backend"] == "cupy" and ds.attrs["check_every"] == CHECK_EVERY["cupy"]
    assert bool(ds.converged.values.all())
    for b, k in enumerate(cases):
        ref = _single(k)
        assert np.max(np.abs(ds.area_fraction.values[b] - ref.area_fraction.values[:4])) <= 2.0 / N**2
        assert np.max(np.abs(ds.iterations.values[b] - ref.iterations.values[:4])) <= 1


@pytest.mark.parametrize(("options", "match"), [
    ({"hardness": 0.5}, "elastic solver only"),
    ({"boundary": "free"}, "periodic half-space only"),
    ({"method": "pk"}, "elastic method 'pk-fourier-f32' only"),
    ({"store_fields": True}, "stores no fields"),
    ({"observers": [ClusterObserver(1.0)]}, "takes no observers"),
])
def test_what_a_batch_refuses(options, match):
    h = np.stack([_surface(0)[:16, :16], _surface(2)[:16, :16]])
    with pytest.raises(ValueError, match=match):
        solve_contact(h, [0.001], **options)


def test_bad_batches_are_refused():
    h = _surface(0)[:16, :16]
    with pytest.raises(ValueError, match=r"case\(s\) \[1\] are flat"):
        solve_contact(np.stack([h, np.ones_like(h)]), [0.001])
    with pytest.raises(ValueError, match=r"heights\[1\] must contain only finite"):
        solve_contact(np.stack([h, np.full_like(h, np.nan)]), [0.001])
    with pytest.raises(ValueError, match="shape \\(B, nx, ny\\)"):
        solve_contact_batch(h, [0.001])
    with pytest.raises(ValueError, match="check_every must be"):
        solve_contact_batch(np.stack([h, h]), [0.001], check_every=0)


def test_cupy_kernel_cache_on_disk_by_default(monkeypatch):
    """``CUPY_CACHE_DIR`` defaults to a persistent path when CuPy is first asked for; a caller's is kept."""
    import os
    import sys

    from roughcontact.core import backend as backend_mod
    from test_array_backend import _numpy_as_cupy

    monkeypatch.setitem(sys.modules, "cupy", _numpy_as_cupy())
    monkeypatch.setenv("CUPY_CACHE_DIR", "/somewhere/else")
    monkeypatch.setenv("XDG_CACHE_HOME", "/cache-home")
    backend_mod.get_backend.cache_clear()
    try:
        backend_mod.get_backend("cupy")
        assert os.environ["CUPY_CACHE_DIR"] == "/somewhere/else"
        monkeypatch.delenv("CUPY_CACHE_DIR")
        backend_mod.get_backend.cache_clear()
        backend_mod.get_backend("cupy")
        assert os.environ["CUPY_CACHE_DIR"] == "/cache-home/roughcontact/cupy" == backend_mod.default_cupy_cache()
    finally:
        backend_mod.get_backend.cache_clear()
