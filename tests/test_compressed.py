"""The single solve's kernels of the one iteration class (roughcontact.solver.compressed).

The outputs of every scene are byte-identical to those of the single solve's former iteration (checked when
it was replaced, 2026-12-03: tests/solver_fingerprints.py and benchmarks/same_outputs.py); these tests hold
the kernels' own rules: a step that leaves no pressure, the decisions of the loop's head, and the module's
example.
"""
from __future__ import annotations

import doctest
import math

import numpy as np
import pytest

from roughcontact.solver import compressed
from roughcontact.solver.compressed import CompressedKernels, WorkspaceProducts, pk_solve
from roughcontact.solver.workspace import STALL_WINDOW, StallGuard, Workspace
from roughcontact.surfaces.synthetic import generate_surface


def test_the_module_example_runs():
    assert doctest.testmod(compressed).failed == 0


def _workspace(n=32, p0=2e-3):
    h = generate_surface(n, 2, 8, 0.8, 1, rms_slope=0.1)
    ws = Workspace(h / n, 1.0, 1, "pk-fourier-f32")
    ws.P.fill(p0)
    ws.refresh()
    return ws


def test_a_step_that_leaves_no_pressure_spreads_the_load_and_recomputes_w():
    """Polonsky & Keer's full projection: the load spread evenly over every node, ``F`` every node, ``w = K p - h``
    recomputed in float64 (equal to the operator's own product), ``t`` kept on the old ``F`` and re-centred,
    Polak-Ribiere's history dropped, the case fresh."""
    p0 = 2e-3
    ws = _workspace(p0=p0)
    ws.P[ws.h < np.median(ws.h)] = 0.0  # half the nodes in contact
    ws.P *= p0 * ws.size / ws.P.sum()
    ws.refresh()
    op = WorkspaceProducts(ws)
    k = CompressedKernels(ws, op, p0 * ws.size)
    F = k.free_set(ws.P > 0.0)
    old = F.idx.copy()
    t, g_prev = k.vector(F), k.vector(F)
    t.a[:] = np.linspace(1.0, 2.0, old.size)
    g_prev.a[:] = 1.0
    g_prev.valid = True
    op.k.loader.load(F.idx, t.a, k.inv_sigma)
    spec = op.transform32(op.k)
    rt = op.k.prod32.quadratic(spec, op.kquad32) * ws.sigma ** 2
    go, done, fresh = (np.ones((1, 1, 1), dtype=bool), np.zeros((1, 1, 1), dtype=bool),
                       np.zeros((1, 1, 1), dtype=bool))
    target = np.full((1, 1, 1), p0 * ws.size)
    tau, proj, scale = k.trial(spec, op.kquad32, None, 1e3 * rt, math.nan, None, t, F, target, go, done)
    assert tau > 0 and proj[0] and not done.item()  # every node's trial pressure p - tau t is below 0
    assert k.project(None, t, tau, go, scale, None, F=F) is None  # nothing to transform: w is recomputed
    k.settle(ws.w, None, None, None, F, t, g_prev, old.size, 0.1, proj, go, None, fresh)
    assert fresh.item()
    np.testing.assert_array_equal(ws.P, np.full(ws.shape, p0))
    assert ws.mask.all() and np.array_equal(F.idx, np.arange(ws.size))
    np.testing.assert_array_equal(ws.w, ws.op.apply(ws.P) - ws.h)
    T = np.zeros(ws.size)
    T[old] = np.linspace(1.0, 2.0, old.size)
    np.testing.assert_allclose(t.a, T - T.mean(), rtol=0, atol=1e-15)
    assert not g_prev.valid and g_prev.a.size == ws.size


def _decide(r, *, fresh=False, it=5, best=1.0, at=0, next_sync=1e-5, max_iter=100):
    state = dict(it=np.full((1, 1, 1), it), max_iter=np.full((1, 1, 1), max_iter),
                 fresh=np.full((1, 1, 1), fresh), next_sync=np.full((1, 1, 1), next_sync),
                 best=np.full((1, 1, 1), best), at=np.full((1, 1, 1), at),
                 **{k: np.zeros((1, 1, 1), dtype=bool) for k in ("done", "waiting", "converged", "go")})
    CompressedKernels._decide(r, 1e-8, STALL_WINDOW, **state)
    return {k: v.item() for k, v in state.items()}


@pytest.mark.parametrize("r", [1e-3, 0.6, 0.4, math.inf, math.nan])
@pytest.mark.parametrize("it", [5, 99, 100, 299, 300, 305])
def test_the_loop_head_stops_as_the_stall_guard(r, it):
    """Above ``tol`` and every recomputation level, a case stops exactly where :class:`StallGuard` stops."""
    guard = StallGuard(100 if it <= 100 else 400)
    guard.best, guard.at = 1.0, 0
    stop = guard.stop(r, it)
    got = _decide(r, it=it, next_sync=1e-12, max_iter=guard.max_iter)
    assert (got["done"], got["go"]) == (stop, not stop)
    assert (got["best"], got["at"]) == (guard.best, guard.at)
    assert not got["converged"] and not got["waiting"]


def test_the_loop_head_recomputes_w_before_it_converges_and_at_each_level():
    # below tol: converged on a fresh w, else a float64 recomputation first
    assert _decide(1e-9, fresh=True)["converged"]
    got = _decide(1e-9, fresh=False)
    assert got["waiting"] and not got["done"] and not got["go"]
    # below a level of next_sync on a stale w: the level drops by four decades until below the residual
    got = _decide(3e-10, fresh=False)
    assert got["waiting"] and not got["converged"]  # below tol = 1e-8 already
    got = _decide(3e-6, fresh=False)
    assert got["waiting"] and got["next_sync"] == pytest.approx(1e-9)
    got = _decide(3e-6, fresh=True)  # fresh: no recomputation, it iterates
    assert got["go"] and not got["waiting"] and got["next_sync"] == 1e-5


def test_a_solve_holds_the_mean_and_the_contact_mask():
    ws = _workspace(p0=1e-3)
    its, ok = pk_solve(ws, 1e-3, 1e-8, 1000, True)
    assert ok and its > 0
    assert abs(ws.P.sum() - 1e-3 * ws.size) <= 1e-12 * 1e-3 * ws.size
    assert np.array_equal(ws.mask, ws.P > 0)
    np.testing.assert_array_equal(ws.w, ws.op.apply(ws.P) - ws.h)  # w fresh on exit


@pytest.mark.parametrize("boundary", ["periodic", "free"])
@pytest.mark.parametrize("method", ["pk-fourier-f32", "pk-fourier", "pk"])
def test_a_solve_from_no_pressure_joins_into_an_empty_free_set(method, boundary):
    """``P = 0`` (an empty ``F``: every node joins at the first iteration; the gradient is not re-centred there, as
    the former loop did) converges for every method and boundary, with the mean, the mask and a fresh ``w``."""
    h = generate_surface(32, 2, 8, 0.8, 0, rms_slope=0.1) / 32
    ws = Workspace(h, 1.0, 1, method, boundary=boundary)
    its, ok = pk_solve(ws, 1e-3, 1e-8, 1000, False)
    assert ok and its > 0
    assert abs(ws.P.sum() - 1e-3 * ws.size) <= 1e-12 * 1e-3 * ws.size
    assert ws.P.min() >= 0.0 and np.array_equal(ws.mask, ws.P > 0)
    np.testing.assert_array_equal(ws.w, ws.op.apply(ws.P) - ws.h)


def test_the_step_rules_every_solver_shares():
    """``solver.steps``: the module's example; the extrapolation's factor at its edges (the last two loads equal,
    the loads turning back, an increment of exactly and of more than twice the last); the fallbacks' chain ends
    where the solver cannot go on (MPI ranks run the float64 iteration only), where iterations run out, and at
    the first iteration that converges."""
    from roughcontact.solver import steps

    assert doctest.testmod(steps).failed == 0
    c = steps.extrapolation_factor(np.array([3.0, 2.5, 1.5, 4.0, 4.0001, 2.5]), np.full(6, 2.0),
                                   np.array([1.0, 2.0, 1.0, 1.0, 1.0, 3.0]))
    assert c.tolist() == [1.0, 0.0, 0.0, 2.0, 0.0, 0.0]
    assert float(steps.extrapolation_factor(3.0, 2.0, 1.0)) == 1.0
    # the start of each case: none solved yet; one solved (no older load); extrapolated or linear where c > 0
    kinds, c = steps.start_kind(np.array([1.0, 2.0]), None, None, True)
    assert kinds.tolist() == [steps.UNIFORM] * 2 and c.tolist() == [0.0, 0.0]
    kinds, c = steps.start_kind(2.5, 2.0, None, True)
    assert int(kinds) == steps.SCALED and float(c) == 0.0
    kinds, c = steps.start_kind(np.array([3.0, 3.0, 2.5, 1.5, 4.0001]), np.full(5, 2.0), np.full(5, 1.0),
                                np.array([True, False, False, True, True]))
    assert kinds.tolist() == [steps.LINEAR, steps.EXTRAPOLATED, steps.EXTRAPOLATED, steps.SCALED, steps.SCALED]
    assert c.tolist() == [1.0, 1.0, 0.5, 0.0, 0.0]
    assert steps.start_fresh(kinds).tolist() == [-1, 0, 0, 1, 1]
    assert steps.start_fresh(kinds, capped=True).tolist() == [-1, 0, 0, 0, 0]
    assert steps.start_fresh(np.array([steps.UNIFORM])).tolist() == [0]
    ran = []

    def run(method, left):
        ran.append((method, left))
        return 7, False

    assert steps.fall_back("pk-fourier-f32", 10, False, 100, run, reachable=("pk-fourier",)) == (17, "pk-fourier",
                                                                                               False)
    assert ran == [("pk-fourier", 90)]
    assert steps.fall_back("pk-fourier-f32", 100, False, 100, run) == (100, "pk-fourier-f32", False)
    assert steps.fall_back("pk-fourier-f32", 10, True, 100, run) == (10, "pk-fourier-f32", True)
    assert steps.fall_back("pk", 10, False, 100, run) == (17, "box", False)
    assert ran == [("pk-fourier", 90), ("box", 90)]


def test_the_loop_head_lowers_its_level_until_it_is_below_the_residual():
    """``workspace.loop_head``: on a stale ``w`` a residual below the recomputation level waits for ``w`` in float64,
    the level lowered by four decades as often as it takes (three times here); without ``levels`` (the float64
    methods) or on a fresh ``w`` the case goes on; at or below ``tol`` it converges on a fresh ``w`` only."""
    from roughcontact.solver.workspace import CONVERGED, GO, WAIT, loop_head

    decision, level, best, at = loop_head(3e-14, 1e-20, False, 1e-5, True, 7, 100, 1.0, 2, 300)
    assert (decision, best, at) == (WAIT, 1.0, 2) and level == pytest.approx(1e-17) and level < 3e-14 < level * 1e4
    assert loop_head(3e-14, 1e-20, False, 1e-5, False, 7, 100, 1.0, 2, 300) == (GO, 1e-5, 3e-14, 7)
    assert loop_head(3e-14, 1e-20, True, 1e-5, True, 7, 100, 1.0, 2, 300)[0] == GO
    assert loop_head(1e-21, 1e-20, True, 1e-5, True, 7, 100, 1.0, 2, 300)[0] == CONVERGED
    assert loop_head(1e-21, 1e-20, False, 1e-5, False, 7, 100, 1.0, 2, 300)[0] == WAIT


@pytest.mark.parametrize("method", ["pk", "pk-fourier"])
def test_run_path_runs_each_iteration_with_the_workspace_method_restored(monkeypatch, method):
    """``steps.run_path``: an elastic path runs ``pk_solve`` with that method; ``"box"`` the capped iteration with a
    cap of twice the total load, unpreconditioned under the reference ``"pk"`` only; the workspace's method comes
    back either way, after an error too."""
    from roughcontact.solver import steps

    ws = _workspace()
    ws.method = method
    seen = []
    monkeypatch.setattr(steps, "box_solve", lambda w, p0, tol, it, cap, fresh: seen.append(("box", w.method, cap)) or
                        (1, True))
    monkeypatch.setattr(steps, "pk_solve", lambda w, p0, tol, it, fresh: seen.append(("pk", w.method)) or (2, False))
    assert steps.run_path(ws, "box", 2e-3, 1e-8, 10, True, method) == (1, True)
    assert steps.run_path(ws, "pk-fourier-f32", 2e-3, 1e-8, 10, True, method) == (2, False)
    assert seen == [("box", method, 2.0 * 2e-3 * ws.size), ("pk", "pk-fourier-f32")] and ws.method == method

    def broken(*args):
        raise RuntimeError("broken")

    monkeypatch.setattr(steps, "pk_solve", broken)
    with pytest.raises(RuntimeError):
        steps.run_path(ws, "pk-fourier", 2e-3, 1e-8, 10, True, method)
    assert ws.method == method
