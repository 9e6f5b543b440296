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
    from roughcontact.solver import iteration as batch_iteration

    monkeypatch.setattr(batch_iteration, "STALL_WINDOW", 0)  # the batched iteration "stalls" at once, every case
    ds = solve_contact_batch(np.stack([_surface(0), _surface(2)]), LOADS[:3])
    assert bool(ds.converged.values.all())
    np.testing.assert_array_equal(ds.solver_path.values, 2)  # pk-fourier (float64 products) ended every step
    for b, k in enumerate((0, 2)):
        ref = _single(k)
        assert np.max(np.abs(ds.area_fraction.values[b] - ref.area_fraction.values[:3])) <= 2.0 / N**2


def test_the_linear_start_needs_both_last_steps_on_the_batch_iteration(monkeypatch):
    """A step's start (``steps.start_kind``) per case: uniform, then scaled (``fresh`` 1), then extrapolated with
    ``w`` from the last two steps' gaps (-1) only where both ended on the batch's own iteration; a case whose
    second step is marked as ended on a fallback starts its third and fourth steps extrapolated with ``w``
    computed afresh (0), and its fifth linear again."""
    from roughcontact.solver.batch.solver import BatchSolver

    seen, real = [], BatchSolver.start

    def start(self, p_int):
        if len(seen) == 2:
            self._last[2][0] = False  # case 0's second step, as if a fallback had ended it
        fresh = real(self, p_int)
        seen.append(fresh.tolist())
        return fresh

    monkeypatch.setattr(BatchSolver, "start", start)
    ds = solve_contact_batch(np.stack([_surface(0), _surface(2)]), LOADS[:5])
    assert seen == [[0, 0], [1, 1], [0, -1], [0, -1], [-1, -1]]
    assert bool(ds.converged.values.all())


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


def _padded(shape, extra, dtype=np.float32):
    """A ``(B, nx, ny)`` view with rows of ``ny + extra`` values in one buffer (an in-place transform's layout),
    its padding set to a value no kernel may read."""
    B, nx, ny = shape
    buf = np.full((B, nx, ny + extra), 7.0, dtype=dtype)
    return buf[:, :, :ny], buf


@pytest.mark.parametrize("ny", [8, 6], ids=["power-of-two", "other"])
def test_fused_kernels_read_and_write_padded_rows_as_contiguous_ones(ny):
    """Every fused kernel that writes a transform's input or reads its output gives the same values whether
    that buffer is contiguous or has padded rows (the in-place plans of one case), padding left untouched."""
    from roughcontact.solver.batch.cpu import FusedCpuKernels

    rng = np.random.default_rng(3)
    B, nx = 2, 5
    shape = (B, nx, ny)
    mask = rng.random(shape) < 0.4
    P = np.where(mask, rng.random(shape), 0.0)
    t = np.where(mask, rng.standard_normal(shape), 0.0)
    g, a, g_prev = (np.where(mask, rng.standard_normal(shape), 0.0) for _ in range(3))
    R = rng.standard_normal(shape).astype(np.float32)
    col = lambda *v: np.array(v, dtype=float).reshape(B, 1, 1)  # noqa: E731
    tau, scale, inv_sigma = col(0.3, 0.7), col(1.1, 0.9), col(2.0, 0.5)
    go, keep, beta = np.array([True, True]).reshape(B, 1, 1), np.array([True, False]).reshape(B, 1, 1), col(0.4, 0.2)

    def run(out, rin):
        k = FusedCpuKernels()
        vec = functools.partial(k.gather, F=mask)  # t, g, a, g_prev as the kernels hold them: vectors on F
        got = {}
        k.to32(vec(P), inv_sigma, out=out, F=mask)
        got["to32"] = out.copy()
        k.overwritten(out)  # as after an in-place transform: the next sparse write zeroes it whole
        out[...] = 5.0
        tt, gp = vec(t), vec(g_prev)
        _, gt = k.new_direction_input(tt, vec(a), vec(g), beta, keep, go, gp, mask, inv_sigma, out=out)
        got["direction"], got["t"], got["gt"] = out.copy(), k.scatter(tt, mask), gt
        PP = P.copy()
        k.project(PP, vec(t), tau, go, scale, inv_sigma, out=out, F=mask)
        got["project"], got["P"] = out.copy(), PP
        rin[...] = R
        sc, s = k.scaled_sum(rin, col(1.5, 2.5), mask)
        got["scaled"], got["scaled_sum"] = k.scatter(sc, mask), s
        w = g.copy()
        k.add_scaled(w, rin, col(0.25, -1.0))
        got["w"] = w
        P2, w2 = P.copy(), g.copy()
        tot, x32 = k.extrapolate(P2, w2, P, 0.5 * P, g, a, col(0.5, 1.0), go, keep, inv_sigma, out=out)
        got["extrapolate"], got["tot"], got["P2"], got["w2"] = x32.copy(), tot, P2.copy(), w2.copy()
        k.finish_start(P2, w2, g, rin, col(1.0, 2.0), col(0.9, 1.1), col(1.0, 0.0) > 0, go, keep, col(0.1, 0.2))
        got["finish_P"], got["finish_w"] = P2, w2
        return got

    flat = run(np.zeros(shape, np.float32), np.zeros(shape, np.float32))
    out, buf = _padded(shape, 2)
    rin, rbuf = _padded(shape, 3)
    padded = run(out, rin)
    for name, value in flat.items():
        np.testing.assert_array_equal(padded[name], value, err_msg=name)
    assert np.all(buf[:, :, ny:] == 7.0) and np.all(rbuf[:, :, ny:] == 7.0)


def test_one_case_transforms_in_place_with_the_out_of_place_results(monkeypatch):
    """B = 1 on a grid with shipped plans: both float32 transforms in the spectrum's buffer (padded rows),
    as the single solve's; the results those of the out-of-place plans up to the transforms' rounding."""
    from roughcontact.solver.batch import halfspace

    h = _surface(0)[None]
    inplace = solve_contact_batch(h, LOADS)
    monkeypatch.setattr(halfspace.fft_module, "has_shipped_plans", lambda shape: False)
    apart = solve_contact_batch(h, LOADS)
    assert bool(inplace.converged.values.all()) and bool(apart.converged.values.all())
    assert np.max(np.abs(inplace.area_fraction.values - apart.area_fraction.values)) <= 2.0 / N**2
    np.testing.assert_allclose(inplace.mean_gap.values, apart.mean_gap.values, rtol=1e-6)
    assert np.max(np.abs(inplace.iterations.values - apart.iterations.values)) <= 1


def test_the_in_place_plans_are_those_of_one_case_with_shipped_plans():
    from roughcontact.core.backend import get_backend
    from roughcontact.solver.batch.halfspace import BatchFFT

    be = get_backend("numpy")
    one, many, odd = BatchFFT(be, (64, 64), 1, 1), BatchFFT(be, (64, 64), 1, 3), BatchFFT(be, (60, 60), 1, 1)
    assert one.in_place and not many.in_place and not odd.in_place
    assert one.input32.base is not None and not one.input32.flags.c_contiguous
    assert np.shares_memory(one.input32, one.spec32) and not np.shares_memory(many.input32, many.spec32)


def _per_case(rng, B, kind):
    """A ``(B, 1, 1)`` per-case array of random values with the edge values a decision must handle."""
    if kind == "bool":
        return (rng.random(B) < 0.5).reshape(B, 1, 1)
    if kind == "int":
        return rng.integers(0, 12, B).astype(np.int64).reshape(B, 1, 1)
    v = rng.standard_normal(B) * 10.0 ** rng.integers(-12, 3, B)
    special = rng.random(B)
    v[special < 0.08] = 0.0
    v[(special >= 0.08) & (special < 0.12)] = -0.0
    v[(special >= 0.12) & (special < 0.15)] = np.inf
    v[(special >= 0.15) & (special < 0.17)] = np.nan
    return v.reshape(B, 1, 1)


def test_compiled_decisions_are_the_plain_expressions_bit_for_bit():
    """The per-case decisions of the fused host kernels (one compiled call each) give the plain expressions'
    results and in-place updates bit for bit, signed zeros, infinities and NaNs among the inputs."""
    from roughcontact.solver.batch.cpu import FusedCpuKernels
    from roughcontact.solver.batch.kernels import ArrayKernels

    rng = np.random.default_rng(11)
    B = 4000
    r = functools.partial(_per_case, rng, B)
    pos = np.abs(r("float"))
    it, at, max_iter = r("int"), r("int"), r("int")
    calls = {
        "gbar": (lambda k, s, n: k.gbar(s, n), (r("float"), r("int")), 0),
        "decide": (lambda k, *a: k.decide(*a),
                   (pos, r("float"), r("float"), pos + 0.5, pos + 1.0, 1e-8, 3, np.inf, it, max_iter, r("bool"),
                    10.0 ** rng.integers(-9, -3, B).reshape(B, 1, 1), pos * 10, at, r("bool"), r("bool"),
                    r("bool"), r("bool")), 11),
        "join_fix": (lambda k, *a: k.join_fix(*a), (r("int"), r("int"), r("float"), r("bool"), r("bool")), 3),
        "beta": (lambda k, *a: k.beta(*a), (r("float"), r("float"), r("float"), r("float"), r("bool"), r("bool"),
                                           r("bool")), 5),
        "direction_done": (lambda k, *a: k.direction_done(*a), (r("float"), r("bool"), r("float"), r("bool"),
                                                               r("bool"), r("float"), r("float")), 4),
        "step_length": (lambda k, *a: k.step_length(*a), (r("float"), r("float"), r("float"), np.nan, r("bool"),
                                                         r("bool")), 4),
        "projection_scale": (lambda k, *a: k.projection_scale(*a), (r("bool"), r("float"), pos, r("bool"),
                                                                   r("bool"), r("float")), 3),
        "shrink_fix": (lambda k, *a: k.shrink_fix(*a), (r("int"), r("int"), r("float"), 0.1, r("bool"), r("bool"),
                                                       r("bool"), r("bool")), 6),
    }
    for name, (call, args, first_state) in calls.items():
        got = {}
        for label, k in (("plain", ArrayKernels(np)), ("fused", FusedCpuKernels())):
            a = [x.copy() if isinstance(x, np.ndarray) else x for x in args]
            with np.errstate(all="ignore"):  # the NaNs and infinities are meant
                out = call(k, *a)
            got[label] = [*(out if isinstance(out, tuple) else (() if out is None else (out,))), *a[first_state:]]
        for plain, fused in zip(got["plain"], got["fused"], strict=True):
            plain, fused = np.asarray(plain), np.asarray(fused)
            assert plain.dtype == fused.dtype and plain.shape == fused.shape, name
            same = plain.view(np.uint8) == fused.view(np.uint8) if plain.dtype != bool else plain == fused
            assert same.all(), (name, np.flatnonzero(~same.reshape(B, -1).all(axis=1))[:5])


def _loop_head_states():
    """Every combination of the loop head's inputs around its edges: (B, 1, 1) arrays by name."""
    import itertools

    grid = itertools.product(
        [0.0, 5e-19, 3e-14, 1e-10, 1e-8, 5e-8, 3e-6, 2e-5, 0.4, 1.0, np.inf, np.nan],  # residual: tol, levels, best/2
        [False, True], [(False, False), (True, False), (False, True)],  # fresh; (done, waiting)
        [1e-5, 1e-9], [(5, 100), (100, 100), (399, 400)],  # next_sync; (it, max_iter)
        [0, 2, 3], [np.inf, 1.0, 1e-7])  # it - at against the window; best
    rows = [(r, f, d, wt, lv, it, mx, it - back, bst) for r, f, (d, wt), lv, (it, mx), back, bst in grid]
    names = ("r", "fresh", "done", "waiting", "next_sync", "it", "max_iter", "at", "best")
    return {n: np.array(col).reshape(-1, 1, 1) for n, col in zip(names, zip(*rows, strict=True), strict=True)}


@pytest.mark.parametrize(("window", "tol"), [(3, 1e-8), (0, 1e-8), (3, 1e-20)],
                         ids=["window3", "window0", "tol1e-20"])
def test_each_form_of_the_loop_head_is_the_rule(window, tol):
    """The loop head is written once (``workspace.loop_head``): the single solve's kernels call it, the fused host
    kernels compile it, and the array kernels (numpy here, CuPy on a GPU) write it over per-case arrays. Each
    form gives the rule's decisions and state (``next_sync``, ``best``, ``at``, the four flags) for every
    combination of residual, freshness, flags, recomputation level, iteration, stall window and best residual.
    A window of 0 stops every case at once (the batch's fallback test uses it); a tol of 1e-20 lowers the float64
    recomputation level up to four times in one call. A stale numba cache of the compiled form would fail here."""
    from roughcontact.solver.batch.cpu import FusedCpuKernels
    from roughcontact.solver.batch.kernels import ArrayKernels
    from roughcontact.solver.compressed import CompressedKernels
    from roughcontact.solver.workspace import CONVERGED, GO, STOP, WAIT, loop_head

    st = _loop_head_states()
    B = st["r"].shape[0]
    flags = ("done", "waiting", "converged", "go")

    def state():
        out = {k: st[k].copy() for k in ("next_sync", "best", "at", "done", "waiting")}
        out["converged"], out["go"] = np.zeros((B, 1, 1), bool), np.zeros((B, 1, 1), bool)
        return out

    want = state()
    for b in range(B):
        if st["done"][b].item() or st["waiting"][b].item():
            continue
        d, want["next_sync"][b], want["best"][b], want["at"][b] = loop_head(
            st["r"][b].item(), tol, st["fresh"][b].item(), st["next_sync"][b].item(), True, st["it"][b].item(),
            st["max_iter"][b].item(), st["best"][b].item(), st["at"][b].item(), window)
        want["go"][b], want["converged"][b], want["waiting"][b] = d == GO, d == CONVERGED, d == WAIT
        want["done"][b] = d in (CONVERGED, STOP)
    seen = {int(v) for v in np.unique(want["go"] * 1 + want["converged"] * 2 + want["waiting"] * 4)}
    assert seen == ({0, 1, 2, 4} if window else {0, 2, 4})  # (window 0: no case goes on)
    got = {}
    for label, k in (("array", ArrayKernels(np)), ("compiled", FusedCpuKernels())):
        s = got[label] = state()
        zero = np.zeros((B, 1, 1))
        with np.errstate(invalid="ignore"):
            k.decide(st["r"], zero, zero, np.ones((B, 1, 1)), np.ones((B, 1, 1)), tol, window, np.inf, st["it"],
                     st["max_iter"], st["fresh"], *(s[n] for n in ("next_sync", "best", "at", *flags)))
    s = got["compressed"] = state()
    for b in range(B):
        one = {n: s[n][b:b + 1] for n in s}
        CompressedKernels._decide(st["r"][b].item(), tol, window, st["it"][b:b + 1], st["max_iter"][b:b + 1],
                                  st["fresh"][b:b + 1], one["next_sync"], one["best"], one["at"],
                                  *(one[n] for n in flags))
    for label, s in got.items():
        for name, value in want.items():
            same = np.asarray(s[name] == value) | (np.isnan(s[name]) & np.isnan(value) if value.dtype.kind == "f"
                                                   else False)
            assert same.all(), (label, name, np.flatnonzero(~same.reshape(-1))[:5])


def test_compressed_vectors_on_the_free_set_are_the_plain_fields():
    """The fused host kernels hold t, g, a and g_prev compressed over F (one value per node of F, in its
    index order); the plain kernels as fields zero off F. Through a join, the direction's passes, a
    projected step, a shrink (F compacted) and a second join (the joining nodes' t and g_prev must be 0),
    both give the same fields, exactly where a value is element-wise and to round-off where a sum's order
    differs."""
    from roughcontact.solver.batch.cpu import FusedCpuKernels
    from roughcontact.solver.batch.kernels import ArrayKernels

    rng = np.random.default_rng(5)
    B, n = 3, 12
    shape = (B, n, n)
    col = lambda *v, dt=float: np.array(v, dtype=dt).reshape(B, 1, 1)  # noqa: E731
    mask0 = rng.random(shape) < 0.3
    P0 = np.where(mask0, rng.random(shape) + 0.05, 0.0)
    w0 = rng.standard_normal(shape)
    t0, gp0 = (np.where(mask0, rng.standard_normal(shape), 0.0) for _ in range(2))
    R = rng.standard_normal(shape).astype(np.float32)
    go = col(True, False, True, dt=bool)
    gbar, tau, sigma = col(-0.5, 0.0, 0.3), col(0.4, 0.2, 0.9), col(1.5, 0.7, 2.0)

    def run(k):
        F = k.free_set(mask0.copy())
        P, w = P0.copy(), w0.copy()
        t, gp = k.gather(t0, F), k.gather(gp0, F)
        out = {}
        F, g, nF, gsum = k.join_stats(w, gbar, F, go)
        k.sub_masked(g, gsum / np.maximum(nF, 1), F)
        out["g"], out["t_joined"], out["F"] = k.scatter(g, F), k.scatter(t, F), getattr(F, "mask", F).copy()
        a, a_sum = k.scaled_sum(R, sigma, F)
        G, gpa, gt = k.center_dots(a, a_sum / np.maximum(nF, 1), F, g, gp, t)
        out["a"], out["dots"] = k.scatter(a, F), np.concatenate([G, gpa, gt])
        x32, gt2 = k.new_direction_input(t, a, g, col(0.5, 0.1, 0.0), col(True, False, False, dt=bool), go, gp, F,
                                         1.0 / sigma, out=np.zeros(shape, np.float32))
        out["x32"], out["t"], out["gp"], out["gt"] = x32.copy(), k.scatter(t, F), k.scatter(gp, F), gt2
        total, pany = k.trial_stats(P, t, tau, F)
        out["trial"] = np.concatenate([total, pany.astype(float)])
        d32 = k.project(P, t, tau, go, col(1.2, 1.0, 0.9), 1.0 / sigma, out=np.zeros(shape, np.float32), F=F)
        out["d32"], out["P"] = d32.copy(), P.copy()
        nF2, tsum = k.shrink_stats(P, F, t, gp)
        out["shrunk"] = np.concatenate([nF2.astype(float), tsum])
        out["t_shrunk"], out["gp_shrunk"] = k.scatter(t, F), k.scatter(gp, F)
        F, g, nF3, _ = k.join_stats(w - 0.3, gbar + 0.8, F, col(True, True, True, dt=bool))
        out["t_rejoined"], out["gp_rejoined"], out["n3"] = k.scatter(t, F), k.scatter(gp, F), nF3
        return out

    plain, fused = run(ArrayKernels(np)), run(FusedCpuKernels())
    assert plain["n3"].sum() > plain["shrunk"][:B].sum() > 0  # the second join added nodes, the shrink took some
    for name, want in plain.items():
        np.testing.assert_allclose(fused[name], want, rtol=1e-12, atol=1e-12, err_msg=name)


@pytest.mark.parametrize("cases", [(1,), (0, 1, 2)], ids=["B1", "B3"])
def test_each_round_pass_as_one_compiled_call_is_the_kernels_one_at_a_time(cases, monkeypatch):
    """The fused host kernels run each of a round's passes (measure, join, direction, trial, settle) as one
    compiled call; the kernels one at a time (ArrayKernels' compositions of the same fused kernels, as the MPI
    ranks run them) give every output bit for bit. B = 1 takes the in-place transforms (padded rows, the
    transform's output in the buffer that the direction's pass writes), B = 3 the out-of-place ones."""
    from roughcontact.solver.batch.cpu import FusedCpuKernels
    from roughcontact.solver.batch.kernels import ArrayKernels

    h = np.stack([_surface(k) for k in cases])
    loads = LOADS[::2]
    composed = solve_contact_batch(h, loads)
    for name in ("measure", "join", "direction", "trial", "settle"):
        assert getattr(FusedCpuKernels, name) is not getattr(ArrayKernels, name)
        monkeypatch.setattr(FusedCpuKernels, name, getattr(ArrayKernels, name))
    apart = solve_contact_batch(h, loads)
    assert int(composed.iterations.sum()) > 20 * len(cases) * loads.size
    timed = [name for name, var in apart.data_vars.items() if "wall" in name]
    assert timed == ["wall_time"]  # the one column that is a clock's, not the solve's
    for name, var in apart.drop_vars(timed).data_vars.items():
        np.testing.assert_array_equal(composed[name].values, var.values, err_msg=name)
