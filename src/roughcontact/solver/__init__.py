"""Pressure-controlled FFT-BEM normal contact solver (Polonsky & Keer 1999), with effects (plasticity, adhesion).

Problem
-------
A rigid rough surface with heights ``h(x, y)`` (highest points touch first; the
same convention as Tamaas, where ``h`` is the combined roughness) is pressed onto
a periodic elastic half-space of plane-strain modulus ``E*`` over a square cell of
side ``L`` sampled on ``n x n`` nodes (spacing ``dx = L / n``, node ``i`` at
``x = i * dx``, axis 0 = x, axis 1 = y), or over a rectangular cell of sides
``Lx x Ly`` (``length=(Lx, Ly)``) sampled on ``nx x ny`` nodes (heights of shape
``(nx, ny)``, ``nx, ny >= 4``; pixels ``dx = Lx / nx`` by ``dy = Ly / ny``, which may
differ; node ``(i, j)`` at ``(i dx, j dy)``). A float ``length`` means the square
cell and needs square heights; ``(L, L)`` on an ``n x n`` grid is that same
problem, bit for bit. With ``p >= 0`` the nodal contact pressure, the surface
displacement into the half-space is, in Fourier space,

    u(q) = 2 p(q) / (E* |q|)   for q != 0,      u(q = 0) = 0,

``|q| = 2 pi |k| / L`` in rad per length (``|q| = 2 pi sqrt((kx / Lx)^2 + (ky / Ly)^2)``
with integer mode numbers ``kx``, ``ky`` on a rectangle). Fixing ``u(0) = 0`` makes ``u`` the
displacement relative to its mean; the rigid-body approach is the Lagrange
multiplier of the mean-pressure constraint ``mean(p) = p0``. The gap is

    g = u - h + d,     d = rigid-body offset,

so that ``mean(g) = d - mean(h)`` is the mean separation between the rigid
surface and the deformed half-space (the ``mean_gap`` output). The discrete
problem: ``p >= 0``, ``g >= 0``, ``p * g = 0``, ``mean(p) = p0``. With a
``hardness`` ``H`` (perfect plasticity of the interface, as in Tamaas'
``KatoSaturated``) the pressure is also capped, ``p <= H``, nodes at the cap
may interpenetrate (``g <= 0`` there) and nodes strictly between the bounds
have ``g = 0``; a mean ``p0 >= H`` cannot be carried and is refused. Each load
step is solved for the current load alone (no plastic history carried between
steps). Both problems are the optimality conditions of the convex quadratic
program ``min 1/2 p.Kp - h.p`` over ``{0 <= p (<= H), mean(p) = p0}``, ``d``
being the multiplier of the mean constraint; the solution is unique.

That is ``boundary="periodic"``, the default. A measured patch is not periodic,
and the periodic half-space glues its edges together; with ``boundary="free"``
the ``n x n`` (``nx x ny``) cell is an isolated patch on an infinite elastic half-space loaded
there alone (no periodic images, nothing outside the patch touches). Each
node's pressure acts uniformly on its pixel of side ``dx`` (``dx x dy``), and

    u(x_i) = sum_j G(x_i - x_j) p_j,   G = Love's displacement under unit pressure on
                                       one pixel, ~ dx dy / (pi E* r) far away,

computed by zero-padding ``p`` to ``2n x 2n`` (``2nx x 2ny``) and one FFT pair there
(Hockney's method, :class:`FreeHalfSpace`; an iteration costs 3-5x a periodic
one). ``u`` is then the true displacement,
not zero mean, ``-d`` the true approach of the rigid surface and
``mean(g) = mean(u) + d - mean(h)``; the iterations use ``u`` only through the
gap ``g`` (with ``d`` the free offset), so they, the final check and every
output are otherwise the same. The contact perimeter and cluster labelling do
not wrap around. On a rectangle the contact perimeter counts an edge between
neighbours along x as ``dy`` long and one between neighbours along y as ``dx``
long (:func:`contact_perimeter`), and a node's area is ``dx dy`` (cluster areas);
the output's attributes name the cell as :meth:`roughcontact.core.cell.Cell.solver_attrs` says.

A profile ``h(x)`` (1-D heights of ``n >= 4`` points, a float ``length`` ``L``: what a stylus
profilometer gives) is the same problem in plane strain, the surface unchanged along y: the same
kernel with ``q`` along x alone (``|q| = 2 pi |k| / L``), solved by the same code on the one-row
grid ``(n, 1)`` (:meth:`roughcontact.core.cell.Cell.profile`). With ``boundary="free"`` the influence
of a pixel is the plane-strain strip ``u(x) = 2 / (pi E*) integral ln(L / |x - s|) ds``
(:func:`~.love.line_influence`; plane strain fixes ``u`` only up to a constant, absorbed by ``d``),
padded to ``2n``. ``area_fraction`` is then the contact length fraction and ``contact_perimeter`` the
ends of the contact intervals per unit length. The plasticity cap works on profiles; adhesion,
cluster statistics and the GPU backend are maps' only (refused).

Units
-----
Internally the solver works in units where ``E* = L = 1`` and lengths are
counted in ``c``, the power of two just above the rms height ``s`` of ``h``
(so the internal heights have rms in [0.5, 1) and are an exact copy of ``h``);
pressures are counted in ``E* c / L``. Both operators are ``L / E*`` times
their form for ``E* = L = 1`` (Love's influence scales with ``dx = L / n``), so
the internal operator is the one for ``E* = L = 1``. On a rectangle ``L`` is ``Lx``
throughout this section: internally ``E* = Lx = 1`` and the cell is ``1 x Ly / Lx``
(the operators take its aspect ``Ly / Lx``; Love's influence scales with ``dx`` at a
fixed pixel aspect ``dy / dx``), so a square cell's units and scalings are exactly
those above. Every load then enters through the
dimensionless ``p0 L / (E* s)``, which must lie in :data:`LOAD_RANGE` (as must
``hardness L / (E* s)``): outside it float64 cannot represent the contact
(squares of pressures or gaps overflow or underflow) and the load is refused
with a ``ValueError`` naming the argument. When ``|mean(h)| > s`` the mean is
subtracted first (a rigid shift absorbed by ``d``). A perfectly flat surface
(all heights equal) has the exact solution ``p = p0`` everywhere, ``g = 0``;
it is returned directly, with ``iterations = 0``. On the free half-space a
flat surface is instead the rigid square (rectangular) flat punch (its pressure peaks at the
edges): solved once at unit load, with gap scale ``s = p0 L / E*``
(:func:`gap_scale`), and scaled to every load (``iterations = 0`` after the
first step); a hardness is refused there. For the default
``E* = L = 1`` the unit changes are exact (powers of two), so the iterates are
bit for bit those of the unscaled problem.

Algorithm
---------
*Elastic* (no hardness): constrained conjugate gradient on the contact set
``F = {p > 0}`` with the mean-pressure constraint, projection onto ``p >= 0``
and Polonsky-Keer's active-set rules: nodes out of contact with a negative gap
join ``F`` and the CG restarts (with the Fourier preconditioner below, the
direction is kept instead); a step that would take nodes below 0 is
projected, the mean restored by rescaling, and the CG continues on the reduced
set. Implementation details:

* the Fourier kernel and the pyFFTW plans are made once per grid
  (:func:`roughcontact.core.fft.get_fft`), all buffers are preallocated and the
  inner loop calls no BLAS routine (OpenBLAS' thread wake-up interleaved with
  FFTW costs more than the transform at these sizes);
* the search direction ``t`` is kept zero-mean on ``F``, so a step
  ``p <- p - tau t`` keeps ``mean(p)`` and, since ``u`` is linear in ``p``, the
  displacement is updated as ``u <- u - tau K t`` from the response ``K t`` that
  the step length needs anyway: such an iteration costs one FFT pair. Joining
  nodes are folded into the search direction (they start at ``p = 0``), so
  joins keep this exact update too. Only a projection (nodes leaving the
  contact set) recomputes ``u = K p`` with a second FFT pair, and so does
  the confirmation of a small residual before the final check;
* reductions run on compressed arrays over ``F`` only;
* each load step starts from the previous step's pressure scaled to the new
  ``p0`` (for the elastic problem ``u`` scales with it, so no FFT is needed).

That is the reference iteration, the method ``"pk"`` (:class:`SolverSettings` ``method``) (the
iteration of Tamaas' ``PolonskyKeerRey``, with the same iteration count).
``"pk-fourier"`` keeps its projections, active-set rules, stall guard and final
check, and changes two things; the default, ``"pk-fourier-f32"``, a third:

* *Fourier preconditioner*: the search direction is built from
  ``z = P_F M P_F g`` with ``M = |q| E* / 2`` (the exact inverse of the
  periodic operator when ``F`` is the whole cell; 0 at ``q = 0``; for
  ``boundary="free"`` the same periodic ``M`` on the ``n x n`` grid, an
  approximate inverse that still cuts the iterations 1.6-2.5x), ``P_F`` the
  restriction to ``F``, and ``z``'s mean over ``F`` removed; ``t = z + beta t``
  with Polak-Ribiere's ``beta = max(0, z.(g - g_prev)) / (g_old.z_old)``. At
  iterations where nodes join ``F`` the gradient is re-centred on the enlarged
  ``F`` (a shift of ``d``) and the direction is kept (zero on the joining nodes)
  instead of restarting: on fine-scale surfaces a few nodes join at most
  iterations of a step, and a restart at each made the iteration a
  preconditioned steepest descent there (issue 29: 2261 -> ~1100 iterations
  at k_s = 512, N = 1024); the max with 0, and ``t = z`` where ``t`` is no
  descent direction, restart it when the old directions stop helping. One more FFT pair per
  iteration; on the paper case the iterations drop 2-3x and grow more slowly
  with ``n`` (``benchmarks/README.md``);
* *extrapolated warm start*: from the third step on, the start is the linear
  extrapolation in ``p0`` of the last two solutions, clipped at 0 (and at the
  cap, for the capped iteration) and rescaled to the mean, instead of the scaled
  last one; ``u`` follows from the last two
  steps' fresh gaps by the same linear combination, plus one float32 product of
  the clipped part (the single-precision iteration; a float64 pair otherwise);
* *single-precision transforms* (``float32`` pyFFTW plans, ``FFTW_ESTIMATE``
  as the double ones; :class:`roughcontact.core.backend.SpectralProduct`): the
  products of the loop are computed in ``float32`` (inputs divided by the
  internal rms height before the cast, so that the float32 values do not depend
  on the problem's units), while ``p``, the gap, every reduction and the mean
  removal of the direction stay in ``float64``. The transforms work in place in
  their spectrum buffers where shipped plans exist (elsewhere out of place, with
  a kept input); only the nodes of ``F`` are written into the transforms' input
  and read back from the preconditioner's result, the ``1 / n^2`` of
  the inverse transform sits in the multipliers, and a step costs one forward
  and one inverse transform, a projected one a second forward: ``t . K t`` comes
  from the spectrum of ``t`` (Parseval) before the inverse, and a projected
  step's change ``p_new - p = x - tau t`` (``x`` the clipped part plus the
  rescale to the mean, on ``F``) is transformed forward in place of ``t`` and
  inverse-transformed once, so ``K p`` is never transformed afresh (2.35
  transform pairs an iteration on the paper case, against 2.7 before;
  ``docs/solver.md``). The gap then drifts from ``K p - h`` by ~1e-7
  of the steps taken, so ``u = K p`` is recomputed in ``float64`` when the
  residual first falls below 1e-5 and after each further four decades, and
  before the final check (which always uses a fresh ``float64`` product). Same answers to the
  tolerance, tolerances down to 1e-13 reachable, deterministic. Float32 rounding of the
  small late directions is not a smooth function of the input, though: two
  problems that differ only by round-off (an exact rescaling of heights and
  ``E*``) end at solutions that differ by what ``tol`` allows instead of by
  O(1e-16) as with ``"pk-fourier"`` (``tests/test_solver_hard_cases.py``).

*With a hardness*: the bound-constrained problem is solved by a monotone
gradient-projection / conjugate-gradient scheme (Moré & Toraldo 1991, with
Dostál's proportioning test), every step of which lowers the energy and keeps
``0 <= p <= H`` and ``mean(p) = p0``:

* the feasible set's projection is ``P(y) = clip(y - lam, 0, H)`` with the
  offset ``lam`` found by a 1-D search (Newton steps on the piecewise linear
  ``sum(clip(y - lam, 0, H))``, safeguarded by bisection): it is the exact
  projection onto ``{0 <= p <= H, mean(p) = p0}``, so the load carried by the
  capped nodes never has to be rescaled away (the free set's share
  ``p0 n^2 - H |capped|`` may be tiny or the capped set too large; the
  projection releases nodes from the cap as needed);
* with ``d`` chosen so that ``g`` has zero mean on the free set
  ``F = {0 < p < H}``, the *free gradient* is ``g`` on ``F`` and the
  *chopped gradient* the sign violations at the bounds (``g < 0`` at ``p = 0``,
  ``g > 0`` at ``p = H``); while the chopped part is not larger than 0.17 of
  the free part (2-norms; ``box.PROPORTIONING`` = 0.17^2), a CG step minimises
  the energy on the current face
  (direction zero-mean on ``F``); a step that would leave the box is replaced
  by the projection of the CG trial point onto the face (exact line search on
  the segment, or the full projected point when it lowers the energy); the CG
  restarts there without a preconditioner, and with one keeps its direction on
  the new face (zero off it, zero mean on it) and conjugates against it with
  Polak-Ribiere's ``beta``, restarting where that is no descent;
* otherwise, and after any move that stopped short of the projected trial (a
  segment minimum inside, or a CG step truncated at the first bound), a
  gradient-projection step ``P(p - alpha g)`` (Barzilai-Borwein ``alpha``, exact
  line search on the segment) changes the active sets, many nodes at a time,
  and the CG restarts (without it, a start far from the solution released a node
  or two per CG step: docs/solver.md).

With any elastic method but ``"pk"``, the CG steps on the face use the same
Fourier preconditioner (``z = P_F M P_F g`` on ``F = {0 < p < H}``, capped
nodes outside it; one more float64 FFT pair per CG step): on the paper case at
``n = 512`` it takes 2.4x fewer iterations and 0.57x the CPU time when few
nodes are capped, 1.5x fewer when a quarter are (``tests/test_solver_methods.py``).

In the rigid-plastic limit (``H`` far below ``E* s / L``) this finds the
bearing-area solution in one or two steps; for a cap that is never reached it
is a CG on the contact set with gradient-projection steps for the joins, about
as many iterations as the elastic path (each one dearer: full-grid passes).

Convergence criterion
---------------------
Let ``s`` be the gap scale: the rms height of ``h`` about its mean, see
:func:`gap_scale`; ``d`` is taken so that ``g`` has zero mean on
``F = {0 < p < H}`` (``H = inf`` without hardness; when ``F`` is empty, the
offset in the middle of the admissible interval). The solver forms

    e_orth = sum_F(p |g|) / (N p0 * s)        (complementarity, pressure-weighted,
                                               N = n^2 = nx ny nodes:
                                               g ~ 0 on the elastic contact set;
                                               pointwise |g| <= ~6 tol s measured)
    e_pen  = max(0, -min g over all nodes below the cap) / s   (gap sign)
    e_cap  = max(0, max g over nodes at the cap) / s           (hardness only)

and ``residual = max(e_orth, e_pen, e_cap)``. All three terms are ratios of
gaps to ``s`` and do not depend on ``n`` (``nx``, ``ny``). A step is converged only when a final
check on ``u = K p`` recomputed by FFT from the returned pressure finds

* every value finite, ``0 <= p`` (``<= H``), ``|mean(p) - p0| <= MEAN_RTOL p0``
  (:data:`MEAN_RTOL`, 1e-10), and
* ``residual <= tol`` as defined above, hence ``g >= -tol * s`` wherever
  ``p < H`` and ``g <= tol * s`` wherever ``p = H``;

a step that fails any of these is ``converged = False``, whatever the iteration
said, and its ``residual`` is the one of the check. In floating point the gap
carries a round-off error of order ``1e-16 * max|h - mean(h)| / s`` (about
``1e-15`` for Gaussian surfaces) plus ``1e-16 * p0 L / (E* s)``, so any
``tol >= 1e-13`` is reachable at moderate loads; far past full contact
(``p0 L / (E* s)`` above roughly ``tol * 1e16``) the pressure field itself cannot
resolve the gap to ``tol`` and the step ends ``converged = False``. Should the
iteration stall (no halving of the residual within :data:`STALL_WINDOW`
iterations, or a breakdown of the step length), the step moves on from its
pressure to the next iteration of :data:`FALLBACKS` (float64 products, then the
monotone gradient projection of the capped problem with a cap no node can reach,
which cannot cycle), within the same ``max_iter``; the per-step ``solver_path``
says which ended it, and later steps start on it. Only when the last stalls too
does the step end with ``converged = False`` and finite fields, instead of
running to ``max_iter``.

Parts
-----
:mod:`.halfspace` the elastic operators (periodic, free), :mod:`.workspace` the fields
of one surface, :mod:`.elastic` and :mod:`.box` the two iterations,
:mod:`.effects` what acts on them (one module per effect, found by name: the plasticity
cap; adhesion, whose interaction energy makes :func:`solve_contact` use the gap iteration of
:mod:`.adhesion` through :class:`~.adhesive.AdhesiveSolver`, Rey, Anciaux & Molinari 2017;
docs/solver.md), :mod:`.check` the final check, :mod:`.results` the assembly of the output,
:mod:`.units` and :mod:`.validation` the checks of the input, :mod:`.settings` what a solve
is asked to do (:class:`SolverSettings`), :mod:`.contact` one surface's solver (warm starts,
the step), :mod:`.solve` the entry points and the step loop; :mod:`.batch` many surfaces of one
grid in one solve (:func:`solve_contact_batch`, or :func:`solve_contact` with heights of shape
``(B, nx, ny)``: the default elastic iteration on a leading case axis, every case converging on its
own; issue 48);
:mod:`.stanley_kato` a reference iteration of the paper's kind (Stanley & Kato's displacement
relaxation), used by the κ-gap study only.

The FFT plans and buffers are shared per grid size within a process, so two
solves of the same size must not run concurrently in threads of one process
(separate processes, as under Snakemake, are fine).
"""

from ..core.backend import ARRAY_BACKENDS
from .batch import solve_contact_batch
from .check import MEAN_RTOL
from .contact import ContactSolver
from .effects import EFFECTS, Adhesion, Effect, PlasticityCap, effects_from_config
from .halfspace import FreeHalfSpace, PeriodicHalfSpace, displacement, elastic_kernel, free_influence
from .options import get_options, set_options
from .results import (
                      FRACTION_UNITS,
                      SOLVER_DESCRIPTION,
                      SOLVER_NAME,
                      StepResult,
                      contact_perimeter,
                      step_notes,
)
from .settings import DEFAULT_MAX_ITER, SolverSettings
from .solve import solve_contact, solve_step
from .units import LOAD_RANGE, gap_scale
from .validation import BOUNDARIES
from .workspace import ELASTIC_METHODS, FALLBACKS, SOLVER_PATHS, STALL_WINDOW

__all__ = [
    "ARRAY_BACKENDS",
    "BOUNDARIES",
    "Adhesion",
    "DEFAULT_MAX_ITER",
    "EFFECTS",
    "ELASTIC_METHODS",
    "FALLBACKS",
    "FRACTION_UNITS",
    "LOAD_RANGE",
    "MEAN_RTOL",
    "SOLVER_DESCRIPTION",
    "SOLVER_NAME",
    "SOLVER_PATHS",
    "STALL_WINDOW",
    "ContactSolver",
    "Effect",
    "FreeHalfSpace",
    "PeriodicHalfSpace",
    "PlasticityCap",
    "SolverSettings",
    "StepResult",
    "contact_perimeter",
    "get_options",
    "set_options",
    "displacement",
    "effects_from_config",
    "elastic_kernel",
    "free_influence",
    "gap_scale",
    "solve_contact",
    "solve_contact_batch",
    "solve_step",
    "step_notes",
]
