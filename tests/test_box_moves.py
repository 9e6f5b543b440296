"""The capped iteration's rare moves, driven one at a time (:class:`~roughcontact.solver.box.BoxIteration`).

A CG trial that leaves the box ``0 <= p <= H`` is projected onto the face and searched
on the segment to it; when that segment climbs, the CG step is truncated at the first
bound. Whole solves reach these moves seldom, so each is set up here on a small grid
and checked against the invariants every move must keep: the bounds, the total load,
and ``w = K p - h`` after the incremental update (the move never recomputes it).
"""

import numpy as np
import pytest

from roughcontact.solver.box import BoxIteration
from roughcontact.solver.workspace import Workspace

N, P0, CAP = 8, 1.0e-3, 1.6e-3


def _state(seed: int):
    """A box iteration on an 8x8 grid with every node strictly inside the box, and a direction."""
    rng = np.random.default_rng(seed)
    h = rng.standard_normal((N, N)) * 1e-2
    ws = Workspace(h, 1.0, 1, "pk")
    p = P0 * (1.0 + 0.5 * rng.uniform(-1.0, 1.0, (N, N)))
    ws.P[...] = p * (P0 * N * N / p.sum())
    ws.refresh()
    it = BoxIteration(ws, P0, 1e-10, 100, CAP, fresh=True)
    it._measure()
    assert it.idx.size == N * N  # all free: the move works on the whole face
    t_f = rng.standard_normal(N * N)
    t_f -= t_f.mean()  # a direction on the face keeps the load
    it.t[it.idx] = t_f
    it.kt[:] = ws.apply_k(it.t.reshape(N, N)).ravel()
    y_f = it.p_f - 2.0 * P0 * t_f / np.abs(t_f).max()  # far enough to leave the box
    assert y_f.min() < 0.0 or y_f.max() > CAP
    return ws, it, y_f, t_f


def _check_invariants(ws, total):
    assert ws.P.min() >= 0.0 and ws.P.max() <= CAP
    assert ws.P.sum() == pytest.approx(total, rel=1e-12)
    exact = ws.apply_k(ws.P) - ws.h
    # the incremental update of w matches a fresh K p - h to round-off (|w| ~ 1e-2)
    np.testing.assert_allclose(ws.w, exact, rtol=0, atol=1e-13)


@pytest.mark.parametrize("seed", range(4))
def test_segment_search_stops_inside_when_the_projection_overshoots(seed):
    # g along -s with a small weight: descent on the segment, minimum before its end
    ws, it, y_f, t_f = _state(seed)
    total = ws.P.sum()
    from roughcontact.solver.projection import project

    s_f = project(y_f, float(it.p_f.sum()), CAP) - it.p_f
    it.g_f = -1e-9 * s_f
    p_before = it.p_f.copy()
    assert it._leave_box(y_f, t_f)
    moved = ws.Pf[it.idx] - p_before
    theta = float(moved @ s_f / (s_f @ s_f))
    assert 0.0 < theta < 1.0
    np.testing.assert_allclose(moved, theta * s_f, rtol=0, atol=1e-15)
    _check_invariants(ws, total)


@pytest.mark.parametrize("seed", range(4))
def test_cg_step_truncates_at_the_first_bound_when_the_segment_climbs(seed):
    # g along +s: the segment to the projection climbs, so the CG step stops at a bound
    ws, it, y_f, t_f = _state(seed)
    total = ws.P.sum()
    from roughcontact.solver.projection import project

    it.g_f = project(y_f, float(it.p_f.sum()), CAP) - it.p_f
    assert it._leave_box(y_f, t_f)
    p = ws.Pf[it.idx]
    at_bound = (p == 0.0) | (p == CAP)
    assert at_bound.sum() == 1  # exactly the first bound met along -t, set exactly
    _check_invariants(ws, total)


def test_preconditioned_cg_keeps_its_direction_across_a_change_of_face(monkeypatch):
    # After a CG step that leaves the box, the preconditioned iteration keeps its direction on the
    # new face (zero off it: checked at every change of face) and conjugates against it; every
    # CG step is a descent (the energy 1/2 p.Kp - h.p falls). Measured on this case (N = 128, 10
    # steps): 201 iterations against 220 when every change of face restarts the CG.
    from roughcontact.solver import box, solve_contact
    from roughcontact.surfaces.synthetic import generate_surface

    h = generate_surface(128, 1, 64, 0.52, 0, rms_slope=0.1)
    loads = np.linspace(5e-4, 5e-3, 10)
    seen = {"kept": 0}
    cg_step, changed = box.BoxIteration._cg_step, box.BoxIteration._sets_changed

    def energy(self):
        return 0.5 * self.P @ self.ws.apply_k(self.ws.P).ravel() - self.ws.hf @ self.P

    def checked_cg_step(self, G):
        before = energy(self)
        kept = not self.restart
        moved = cg_step(self, G)
        if moved:  # a descent, to round-off of the energy (its terms are ~1e4 in internal units)
            assert energy(self) <= before + 1e-13 * abs(before)
        if kept and moved:
            seen["kept"] += 1
        return moved

    def checked_sets_changed(self, keep):
        changed(self, keep)
        if not self.restart:
            off = np.ones(self.P.size, dtype=bool)
            off[self.idx] = False
            assert not self.t[off].any() and not self.g_prev[off].any()

    monkeypatch.setattr(box.BoxIteration, "_cg_step", checked_cg_step)
    monkeypatch.setattr(box.BoxIteration, "_sets_changed", checked_sets_changed)
    kept = solve_contact(h, loads, tol=1e-8, hardness=0.05)
    assert kept["converged"].all() and seen["kept"] > 0
    monkeypatch.setattr(box.BoxIteration, "_sets_changed", lambda self, keep: changed(self, False))
    restarted = solve_contact(h, loads, tol=1e-8, hardness=0.05)
    assert restarted["converged"].all()
    # two paths to tol 1e-8: the same answer up to a node whose contact is borderline (equal here)
    np.testing.assert_allclose(kept["area_fraction"].values, restarted["area_fraction"].values,
                               rtol=0, atol=1.0 / 128**2)
    assert int(kept["iterations"].sum()) < int(restarted["iterations"].sum())
