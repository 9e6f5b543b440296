"""Adhesive normal contact: interaction laws and a gap-based FFT-BEM solver.

:mod:`.laws` the interaction laws and what a grid must resolve, :mod:`.iteration` the gap iteration
(:func:`solve_adhesive`), :mod:`.solver` the solver of one surface that
:func:`~roughcontact.solver.solve.solve_contact` runs when an effect supplies an interaction energy
(:class:`~.solver.AdhesiveSolver`, imported from its module: it needs the solver's settings, whose
effects import this package, so it is not re-exported here).

Problem
-------
The conventions of the contact solver (docs/solver.md, "Problem"): a rigid surface of heights ``h`` [length]
(highest points touch first) on a periodic elastic half-space of plane-strain modulus
``E*`` [pressure], cell ``Lx x Ly`` on ``nx x ny`` nodes (``length`` a float ``L`` means a
square cell; ``ny = 1`` is a plane-strain 1-D problem, ``h`` independent of y). ``p`` is
the net surface pressure [pressure], compressive positive, tensile negative, and

    u(q) = 2 p(q) / (E* |q|),  u(q = 0) = 0,     g = u - h + d,   mean(g) = d - mean(h).

The surfaces attract each other through an interaction law of energy ``phi(g)`` per unit
area (:class:`Exponential`, :class:`MaugisDugdale`), ``phi(0) = -w`` with ``w`` the work of
adhesion, ``phi(inf) = 0``, whose tensile stress ``tension(g) = d phi / d g >= 0`` pulls the
surfaces together. (The tension is ``+d phi/d g``: ``phi`` rises from ``-w`` to 0 as the
gap opens, and the stress it exerts is tensile, ``p = -tension(g)`` in the gap.)
The discrete adhesive problem (the invariants that a converged step satisfies):

* ``g >= 0`` everywhere (exactly: the projection sets it);
* where ``g > 0``: ``p = -tension(g)``;
* where ``g = 0``: ``p + tension(0) >= 0`` (the repulsive part of the pressure is >= 0);
* displacement control: ``mean(g)`` equals the imposed mean gap; pressure control:
  ``mean(p) = p0`` (``p0 < 0`` is a tensile load).

These are the stationarity conditions of the total energy (Rey, Anciaux & Molinari 2017,
Comput. Mech. 60, 69-81), written with the gap as primal variable:

    E(g) = 1/2 <(g + h), M (g + h)> + sum phi(g)    over {g >= 0, mean(g) = gbar},

``M = E* |q| / 2`` (0 at ``q = 0``) the inverse of the elastic operator, so that
``p = M (g + h) - lam``, ``lam`` the multiplier of the mean-gap constraint and
``mean(p) = -lam``. Both laws are concave in ``g``, so the elastic quadratic is an upper
bound of ``E`` along any line: a step length computed from ``M`` alone lowers the energy.

Algorithm (:class:`AdhesiveIteration`)
--------------------------------------
Polonsky & Keer's constrained conjugate gradient with the roles of pressure and gap
exchanged, as Rey et al. (2017) and Tamaas' ``PolonskyKeerRey(model, h, tol, gap, gap)``
with an adhesion functional term: the gradient is ``r = M (g + h) + tension(g)``; the free
set ``F`` is ``{g > 0}`` plus the contact nodes where ``r < lam`` (they want to open, PK's
join rule, restarting the CG); the search direction is conjugate on ``F`` and zero-mean
there (``mean(g)`` is kept); the step length is the elastic one,
``tau = <z, t> / <t, M t>``; a step that takes nodes below 0 is clipped at 0, the mean
restored by rescaling the gaps (Tamaas' rule) and the CG restarts. One FFT pair per
iteration (``M t``); ``M (g + h)`` is updated incrementally and recomputed after each
projection and before the final check. Pressure control wraps displacement control: the
mean gap is found by a bracketing secant (Illinois) search on the load-stable branch
(mean pressure decreasing with the mean gap), each evaluation warm-started.

Convergence criterion
---------------------
With ``p_ref`` the rms of ``M h`` (the rms pressure that flattens ``h`` completely,
``p* / sqrt 2`` for a sinusoid of amplitude ``Delta``: ``p* = pi E* Delta / lambda``; the
law's ``tension(0)`` when ``h`` is flat), the residual is

    max( max_{g > 0} |p + tension(g)|,  max(0, -min_{g = 0} (p + tension(0))) ) / p_ref

(and, under pressure control, ``|mean(p) - p0| / p_ref`` too). A step is ``converged`` only
when this residual, recomputed from the returned gap with a fresh FFT, is ``<= tol``, every
value is finite, ``g >= 0`` and the mean gap is the imposed one to 1e-12 relative. The
contact area fraction is the fraction of nodes with ``g == 0`` exactly.

Resolution of the adhesive zone
-------------------------------
Where the surfaces part, the tension acts over a process zone of length of order
``l_a = E* rho^2 / w`` (:func:`process_zone_length`: the length over which the largest tension
``w / rho`` opens the gap by ``rho`` elastically; a Dugdale zone is ``pi/8`` of it). A grid whose
cell ``dx`` is not small against ``l_a`` cannot represent the law: nodes jump in and out of
contact as a whole and the tension they carry is too large (measured on a sphere, Tabor
parameter ``mu_T`` 8 at 64 nodes: a pull-off of 7 pi w R, 3.5 times the largest physically
possible, every step meeting the residual). :func:`zone_cells` is ``l_a / dx``; below
:data:`MIN_ZONE_CELLS` no step is reported converged, whatever its residual.

The energy is not convex when ``w / rho^2`` exceeds ``pi E* / L`` (the smallest eigenvalue
of ``M`` on zero-mean fields): equilibria then depend on the start (hysteresis), and a
converged step is *an* equilibrium, not necessarily the one another solver finds. With
the Maugis-Dugdale law each node's tension jumps at ``g = rho``; unless the cohesive zone
spans many nodes the discrete system is trapped in many states (measured on the 1-D wavy
surface: loading and unloading curves 0.04 p* apart where the exponential law's agree).
"""

from .iteration import (
    DEFAULT_MAX_ITER,
    MAX_OUTER,
    MEAN_GAP_RTOL,
    AdhesiveIteration,
    AdhesiveResult,
    adhesive_state,
    elastic_product,
    pressure_control,
    solve_adhesive,
)
from .laws import (
    LAWS,
    MAX_ATTRACTION_ACROSS_CELL,
    MIN_ZONE_CELLS,
    PULL_OFF_REASONS,
    PULL_OFF_STATUS,
    UNTRUSTED_TRACE_STEPS,
    WARN_ZONE_CELLS,
    Exponential,
    MaugisDugdale,
    attraction_across_cell,
    process_zone_length,
    unresolved_zone_message,
    zone_cells,
)

__all__ = ["DEFAULT_MAX_ITER", "LAWS", "MAX_ATTRACTION_ACROSS_CELL", "MAX_OUTER", "MEAN_GAP_RTOL", "MIN_ZONE_CELLS",
           "PULL_OFF_REASONS", "PULL_OFF_STATUS", "UNTRUSTED_TRACE_STEPS", "WARN_ZONE_CELLS", "AdhesiveIteration",
           "AdhesiveResult", "Exponential", "MaugisDugdale", "adhesive_state", "attraction_across_cell",
           "elastic_product", "pressure_control", "process_zone_length", "solve_adhesive", "unresolved_zone_message",
           "zone_cells"]
