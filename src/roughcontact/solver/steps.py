"""The rules of a load step that every solver shares: its warm start and its fallbacks.

The single solve (:class:`~.contact.ContactSolver`), a batch (:class:`~.batch.solver.BatchSolver`) and one case
over MPI ranks (:class:`~.mpi.solver.MpiSolver`) start a step and hand a stalled one on by these functions, so
that each rule is written once:

- :func:`start_kind`: which start a step takes (:data:`UNIFORM`, :data:`SCALED`, :data:`EXTRAPOLATED` or
  :data:`LINEAR`), with :func:`extrapolation_factor`'s factor, and :func:`start_fresh` what that start leaves of
  ``w = K P - h`` (per case for a batch);
- :func:`fall_back`: a step that stalled moves on to the next, more robust iteration of :data:`.workspace.FALLBACKS`
  from its pressure, within the same ``max_iter`` in all;
- :func:`run_path`: one of those iterations on a :class:`~.workspace.Workspace`.

The iteration's own stop rule is :func:`.workspace.stall_rule` and its loop head :func:`.workspace.loop_head`.

Examples
--------
>>> import numpy as np
>>> float(extrapolation_factor(3.0, 2.0, 1.0)), float(extrapolation_factor(2.5, 2.0, 2.0))
(1.0, 0.0)
>>> extrapolation_factor(np.array([3.0, 9.0, 1.0]), np.array([2.0, 2.0, 2.0]), np.array([1.0, 1.0, 1.0]))
array([1., 0., 0.])
>>> kinds, c = start_kind(np.array([3.0, 3.0, 9.0]), np.full(3, 2.0), np.full(3, 1.0), np.array([True, False, True]))
>>> kinds.tolist() == [LINEAR, EXTRAPOLATED, SCALED], c.tolist(), start_fresh(kinds).tolist()
(True, [1.0, 1.0, 0.0], [-1, 0, 1])
>>> calls = []
>>> def run(method, left):
...     calls.append((method, left))
...     return 5, method == "box"
>>> fall_back("pk-fourier-f32", 300, False, 1000, run)
(310, 'box', True)
>>> calls
[('pk-fourier', 700), ('box', 695)]
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .box import box_solve
from .compressed import pk_solve
from .workspace import FALLBACKS, Workspace


def extrapolation_factor(p, prev, older):
    """The factor ``c`` of a step's start ``P = (1 + c) P_last - c P_older``; 0 where that start does not apply.

    Parameters
    ----------
    p, prev, older : float or numpy.ndarray
        This step's load, the last step's and the one's before it (per case for a batch; internal units).

    Returns
    -------
    numpy.ndarray
        ``c = (p - prev) / (prev - older)`` where the loads move on in the same direction by at most twice the last
        increment (``0 < c <= 2``, ``older != prev``), else 0: the start is then the last solution scaled to the
        load. The shape of the loads' broadcast (a 0-d array for floats).
    """
    p, prev, older = (np.asarray(a, dtype=np.float64) for a in (p, prev, older))
    with np.errstate(divide="ignore", invalid="ignore"):
        c = (p - prev) / (prev - older)
    return np.where((older != prev) & (c > 0.0) & (c <= 2.0), c, 0.0)


#: the starts of a load step (:func:`start_kind`)
UNIFORM, SCALED, EXTRAPOLATED, LINEAR = 0, 1, 2, 3
#: ``fresh`` after each start, in the iterations' code: 1 ``w`` is ``K P - h`` (``P`` and ``u = K P`` scale
#: together), 0 ``w`` must be computed, -1 it is, up to float32 round-off of a small part (not recomputed, not
#: taken as fresh either)
_FRESH = np.array([0, 1, 0, -1], dtype=np.int8)


def start_kind(p, prev, older, linear):
    """Which start each case's load step takes, and the extrapolation's factor: ``(kinds, c)``.

    - :data:`UNIFORM` where no step was solved yet (``prev`` None): the load spread evenly;
    - :data:`EXTRAPOLATED` where :func:`extrapolation_factor` gives ``c > 0`` (``older`` given):
      ``P = max((1 + c) P_last - c P_older, 0)`` scaled to the load, ``w`` computed afresh;
    - :data:`LINEAR`, the same start where ``linear`` (the last two steps ended on the float32 iteration with a
      fresh ``w`` kept): ``w = (1 + c) w_last - c w_older`` exactly (``K`` is linear) plus ``K`` of the clipped
      part in float32, no float64 product;
    - :data:`SCALED` otherwise: the last solution scaled to the load, ``w`` with it.

    Parameters
    ----------
    p : float or numpy.ndarray
        This step's internal load (per case for a batch).
    prev, older : float or numpy.ndarray or None
        The last step's load and the one's before it; None where there is none (``older`` None also where the
        solver does not extrapolate: the reference ``"pk"``, ``warm_start="scaled"``).
    linear : bool or numpy.ndarray
        Whether the linear update of ``w`` is available (per case).

    Returns
    -------
    kinds : numpy.ndarray of int8
        The start per case (the loads' broadcast shape; 0-d for floats).
    c : numpy.ndarray of float64
        The factor, 0 where the start is not extrapolated.
    """
    p = np.asarray(p, dtype=np.float64)
    if prev is None:
        return np.full(p.shape, UNIFORM, dtype=np.int8), np.zeros(p.shape)
    c = np.zeros(np.broadcast(p, prev).shape) if older is None else extrapolation_factor(p, prev, older)
    kinds = np.where(c > 0.0, np.where(linear, LINEAR, EXTRAPOLATED), SCALED).astype(np.int8)
    return kinds, c


def start_fresh(kinds, capped: bool = False) -> np.ndarray:
    """``fresh`` after each start of ``kinds`` (:func:`start_kind`): 1, 0 or -1 (int8, as the iterations take it).

    ``capped``: a cap acts (the single solve's plasticity); the scaled start is clipped at it, so its ``w`` is
    computed afresh.
    """
    kinds = np.asarray(kinds)
    fresh = _FRESH[kinds]
    return np.where(kinds == SCALED, 0, fresh).astype(np.int8) if capped else fresh


def run_path(ws: Workspace, path: str, p0: float, tol: float, max_iter: int, fresh: bool | None,
             method: str) -> tuple[int, bool]:
    """One iteration of :data:`~.workspace.SOLVER_PATHS` on ``ws`` from its pressure; ``(iterations, converged)``.

    ``path`` an elastic method runs :func:`~.compressed.pk_solve` with it. ``"box"`` is the capped iteration
    (:func:`~.box.box_solve`) with the cap at twice the total load, which no node can reach (every node's
    pressure is at most the total), preconditioned unless ``method`` (the workspace's own, restored on exit) is
    the reference ``"pk"``. ``p0`` the internal mean load; ``fresh`` as :func:`~.compressed.pk_solve`'s.
    """
    try:
        if path == "box":
            ws.method = "pk" if method == "pk" else "pk-fourier"
            return box_solve(ws, p0, tol, max_iter, 2.0 * p0 * ws.size, fresh)
        ws.method = path
        return pk_solve(ws, p0, tol, max_iter, fresh)
    finally:
        ws.method = method


def fall_back(path: str, its: int, ok: bool, max_iter: int, run: Callable[[str, int], tuple[int, bool]],
              reachable: tuple[str, ...] | None = None) -> tuple[int, str, bool]:
    """A step that ended on ``path`` unconverged after ``its`` iterations, handed down :data:`~.workspace.FALLBACKS`.

    Each iteration in turn, while the step is not converged (``ok``) and iterations are left, runs from the
    pressure the last one stopped at, ``run(method, iterations left)`` returning ``(iterations, converged)``:
    single-precision products stall at ~1e-5 on some measured surfaces whose gaps span many decades, where
    float64 converges; Polonsky & Keer's active-set rule can cycle far from the solution on a plateau with isolated
    spikes, where the monotone gradient projection ``"box"`` converges (tests/test_solver_hard_cases.py).
    ``reachable``: the iterations this solver can run (all when None); the chain ends at the first it cannot.

    Returns ``(iterations in all, the path that ended the step, converged)``.
    """
    for method in FALLBACKS[path]:
        if ok or its >= max_iter or (reachable is not None and method not in reachable):
            break
        path = method
        more, ok = run(method, max_iter - its)
        its += more
    return its, path, ok
