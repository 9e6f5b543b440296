"""Pressure-controlled FFT-BEM normal contact solver (Polonsky & Keer 1999).

Problem
-------
A rigid rough surface with heights ``h(x, y)`` (highest points touch first; the
same convention as Tamaas, where ``h`` is the combined roughness) is pressed onto
a periodic elastic half-space of plane-strain modulus ``E*`` over a square cell of
side ``L`` sampled on ``n x n`` nodes (spacing ``dx = L / n``, node ``i`` at
``x = i * dx``, axis 0 = x, axis 1 = y). With ``p >= 0`` the nodal contact
pressure, the surface displacement into the half-space is, in Fourier space,

    u(q) = 2 p(q) / (E* |q|)   for q != 0,      u(q = 0) = 0,

``|q| = 2 pi |k| / L`` in rad per length. Fixing ``u(0) = 0`` makes ``u`` the
displacement relative to its mean; the rigid-body approach is the Lagrange
multiplier of the mean-pressure constraint ``mean(p) = p0``. The gap is

    g = u - h + d,     d = rigid-body offset,

so that ``mean(g) = d - mean(h)`` is the mean separation between the rigid
surface and the deformed half-space (the ``mean_gap`` output). The discrete
problem: ``p >= 0``, ``g >= 0``, ``p * g = 0``, ``mean(p) = p0``. With a
``hardness`` ``H`` (perfect plasticity of the interface, as in Tamaas'
``KatoSaturated``) the pressure is also capped, ``p <= H``, and nodes at the cap
may interpenetrate (``g <= 0`` there); each load step is solved for the current
load alone (no plastic history carried between steps).

Algorithm
---------
Constrained conjugate gradient on the free set ``F = {0 < p < H}`` (``H = inf``
when no hardness) with the mean-pressure constraint, projection onto the bounds
and Polonsky-Keer's active-set rules: nodes out of contact with a negative gap
(and, with a hardness, capped nodes with a positive gap) join ``F`` and the CG
restarts; a step that would take nodes below 0 (or above ``H``) is projected,
the mean restored by rescaling, and the CG continues on the reduced set.
Implementation details:

* the Fourier kernel ``2 / (E* |q|)`` and the pyFFTW plans are made once per
  grid (:func:`roughcontact.fft.get_fft`), all buffers are preallocated and the
  inner loop calls no BLAS routine (OpenBLAS' thread wake-up interleaved with
  FFTW costs more than the transform at these sizes);
* the search direction ``t`` is kept zero-mean on ``F``, so a step
  ``p <- p - tau t`` keeps ``mean(p)`` and, since ``u`` is linear in ``p``, the
  displacement is updated as ``u <- u - tau K t`` from the response ``K t`` that
  the step length needs anyway: such an iteration costs one FFT pair. Joining
  nodes are folded into the search direction (they start at ``p = 0``), so
  joins keep this exact update too. Only a projection (nodes leaving the
  contact set or reaching the cap) recomputes ``u = K p`` with a second FFT
  pair, and so does the final check before convergence is declared, so that no
  drift of the incremental update is ever reported as converged;
* reductions run on compressed arrays over ``F`` only;
* each load step starts from the previous step's pressure scaled to the new
  ``p0`` (for the elastic problem ``u`` scales with it, so no FFT is needed).

Convergence criterion
---------------------
Let ``s`` be the gap scale: the rms height of ``h`` about its mean (or
``p0 * L / E*`` for a perfectly flat surface), see :func:`gap_scale`; ``d`` is
taken so that ``g`` has zero mean on ``F``. After each update the solver forms

    e_orth = sum_F(p |g|) / (n^2 p0 * s)      (complementarity, pressure-weighted)
    e_pen  = max(0, -min g over all nodes not at the cap) / s   (gap sign)
    e_cap  = max(0, max g over nodes at the cap) / s           (hardness only)

and ``residual = max(e_orth, e_pen, e_cap)``. A step is converged when
``residual <= tol`` evaluated on a displacement freshly recomputed by FFT. All
three terms are ratios of gaps to ``s`` and do not depend on ``n``. In floating
point the gap carries a round-off error of order ``1e-16 * max|h| / s`` (about
``1e-15`` for Gaussian surfaces), so any ``tol >= 1e-13`` is reachable. Should
the iteration still stall (no halving of the residual within
:data:`STALL_WINDOW` iterations, or a breakdown of the step length), the step
ends with ``converged = False`` and finite fields instead of running to
``max_iter``. A converged step guarantees ``g >= -tol * s`` wherever the
pressure is below the cap.

The FFT plans and buffers are shared per grid size within a process, so two
solves of the same size must not run concurrently in threads of one process
(separate processes, as under Snakemake, are fine).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import xarray as xr

from .fft import get_fft, rfft_weights, wavenumbers

#: ``units`` attribute of pressures: they carry whatever unit ``e_star`` has.
PRESSURE_UNITS = "same as e_star"
#: ``units`` attribute of lengths: the unit of ``heights`` and ``length``.
LENGTH_UNITS = "same as heights"
#: ``units`` attribute of lengths per unit area.
INVERSE_LENGTH_UNITS = "1/(same as heights)"
#: ``units`` attribute of dimensionless fractions.
FRACTION_UNITS = "1"

SOLVER_NAME = "roughcontact.solver.pk_pressure"
SOLVER_DESCRIPTION = (
    "Pressure-controlled constrained conjugate gradient (Polonsky & Keer 1999) on a "
    "periodic FFT-BEM elastic half-space, u(q) = 2 p(q) / (E* |q|); converged when "
    "max(sum_F(p|g|)/(sum(p) s), max(0,-min g)/s) <= tol with s the rms height, "
    "checked on a freshly recomputed displacement"
)

#: Default iteration cap per load step.
DEFAULT_MAX_ITER = 10000
#: A step that does not halve its best residual within this many iterations is
#: declared stalled (round-off floor or breakdown); when it progresses, the CG
#: halves the residual every ~5-20 iterations on the paper case (n <= 1024).
STALL_WINDOW = 300


@dataclass
class StepResult:
    """Outcome of one load step of :func:`solve_step`.

    Attributes
    ----------
    p0 : float
        Applied mean pressure [pressure].
    pressure : numpy.ndarray, shape (n, n)
        Nodal contact pressure ``p >= 0`` [pressure].
    gap : numpy.ndarray, shape (n, n)
        Gap ``g = u - h + d`` [length]; zero (to ``tol``) on the contact set.
    area_fraction : float
        Fraction of nodes with ``p > 0`` [-].
    mean_gap : float
        Mean of ``gap`` over the cell [length].
    contact_perimeter : float
        Contact-set boundary length per unit nominal area [1/length].
    iterations : int
        Conjugate-gradient iterations.
    residual : float
        Final value of the convergence measure (module docstring) [-].
    converged : bool
        ``residual <= tol`` on a freshly recomputed displacement.
    wall_time : float
        Wall-clock seconds spent in the step.
    plastic_area_fraction, plastic_load_fraction : float or None
        Fraction of nodes at the hardness cap and share of the load they carry;
        ``None`` when no hardness is given.
    """

    p0: float
    pressure: np.ndarray
    gap: np.ndarray
    area_fraction: float
    mean_gap: float
    contact_perimeter: float
    iterations: int
    residual: float
    converged: bool
    wall_time: float
    plastic_area_fraction: float | None = None
    plastic_load_fraction: float | None = None


# --------------------------------------------------------------------------- kernels
def elastic_kernel(n: int, e_star: float = 1.0, length: float = 1.0) -> np.ndarray:
    """Fourier multiplier from pressure to displacement on the rfft2 grid.

    Parameters
    ----------
    n : int
        Grid points per side.
    e_star : float
        Plane-strain modulus E* [pressure].
    length : float
        Side L of the periodic cell [length].

    Returns
    -------
    numpy.ndarray, float64, shape (n, n//2+1)
        ``2 / (E* |q|)`` [length / pressure] with ``|q| = 2 pi |k| / L``; the
        ``q = 0`` entry is 0 (the mean displacement is absorbed by the rigid-body
        approach).
    """
    kx, ky = wavenumbers(n, length)
    q = 2.0 * np.pi * np.hypot(kx, ky)
    out = np.zeros_like(q)
    np.divide(2.0 / e_star, q, out=out, where=q > 0)
    return out


def displacement(pressure: np.ndarray, *, e_star: float = 1.0, length: float = 1.0,
                 threads: int = 1) -> np.ndarray:
    """Surface displacement of the periodic half-space under a pressure field.

    Parameters
    ----------
    pressure : array_like, shape (n, n)
        Nodal pressure [pressure].
    e_star, length, threads
        As in :func:`solve_contact`.

    Returns
    -------
    numpy.ndarray, float64, shape (n, n)
        Displacement ``u`` into the half-space [length], zero mean.
    """
    p = _validate_heights(pressure, name="pressure")
    _check_positive("e_star", e_star)
    _check_positive("length", length)
    n = p.shape[0]
    fft = _plans(n, _validate_threads(threads))
    return fft.backward(fft.forward(p) * elastic_kernel(n, e_star, length)).copy()


def gap_scale(heights: np.ndarray, p0: float, e_star: float = 1.0, length: float = 1.0) -> float:
    """Gap scale ``s`` of the convergence criterion [length].

    The rms height of ``heights`` about its mean; for a perfectly flat surface,
    where that is 0, the displacement scale ``p0 * L / E*`` instead.
    """
    h = np.asarray(heights, dtype=float)
    rms = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    return rms if rms > 0 else float(p0) * float(length) / float(e_star)


def contact_perimeter(mask: np.ndarray, length: float = 1.0) -> float:
    """Length of the contact-set boundary per unit nominal area [1/length].

    Counts pixel edges between a contact and a non-contact node, with periodic
    wrap in both directions, times ``dx = L / n``, divided by ``L**2``.

    Parameters
    ----------
    mask : numpy.ndarray of bool, shape (n, n)
        Contact set.
    length : float
        Side L of the cell [length].
    """
    m = np.asarray(mask, dtype=bool)
    n = m.shape[0]
    edges = np.count_nonzero(m != np.roll(m, 1, axis=0)) + np.count_nonzero(m != np.roll(m, 1, axis=1))
    return float(edges) * (length / n) / length**2


# --------------------------------------------------------------------------- validation
def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """Inner product of 1-D float arrays without BLAS.

    OpenBLAS wakes its thread pool for ``ddot``/``daxpy`` on vectors of this
    size; interleaved with FFTW calls the wake-up costs more than the FFT pair
    (measured 0.4 ms per call at 3e4 entries on 2 cores). einsum stays in numpy.
    """
    return float(np.einsum("i,i->", a, b))


def _check_positive(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite real number > 0, got {value!r}") from None
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a finite real number > 0, got {value!r}")
    return v


def _validate_heights(heights, name: str = "heights") -> np.ndarray:
    try:
        a = np.asarray(heights)
    except Exception as exc:  # ragged lists and the like
        raise ValueError(f"{name} must be a real 2-D square array of finite numbers: {exc}") from None
    if a.dtype == object or a.dtype.kind not in "iuf":
        if a.dtype.kind == "c":
            raise ValueError(f"{name} must be real, got complex dtype {a.dtype}")
        raise ValueError(f"{name} must be a real numeric array, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a 2-D square array (n, n), got shape {a.shape}")
    if a.shape[0] < 4:
        raise ValueError(f"{name} must be at least 4 x 4, got shape {a.shape}")
    # The solver only reads the heights, so an input that is already float64
    # and C-contiguous is used as is (saves a field's worth of memory).
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must contain only finite values (found NaN or inf)")
    return a


def _validate_pressures(pressures) -> np.ndarray:
    try:
        p = np.asarray(pressures, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"pressures must be a 1-D sequence of finite numbers > 0, got {pressures!r}"
        ) from None
    if p.ndim == 0:
        raise ValueError(
            f"pressures must be a non-empty 1-D sequence of mean pressures p0 > 0, got the scalar {pressures!r}"
        )
    if p.ndim != 1 or p.size == 0:
        raise ValueError(
            f"pressures must be a non-empty 1-D sequence of mean pressures p0 > 0, got shape {p.shape}"
        )
    if not np.all(np.isfinite(p)) or np.any(p <= 0):
        raise ValueError(f"pressures must all be finite and > 0, got {p.tolist()}")
    return p


def _validate_threads(threads) -> int:
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
        raise ValueError(f"threads must be an integer >= 1, got {threads!r}")
    return int(threads)


def _validate_solver_args(e_star, length, tol, max_iter, hardness, threads):
    e_star = _check_positive("e_star", e_star)
    length = _check_positive("length", length)
    try:
        tol_f = float(tol)
    except (TypeError, ValueError):
        raise ValueError(f"tol must be a number in the open interval (0, 1), got {tol!r}") from None
    if not (0.0 < tol_f < 1.0):
        raise ValueError(f"tol must be a number in the open interval (0, 1), got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    if hardness is not None:
        hardness = _check_positive("hardness", hardness)
    return e_star, length, tol_f, int(max_iter), hardness, _validate_threads(threads)


def _validate_store(store_fields, n_steps: int) -> set[int]:
    if isinstance(store_fields, (bool, np.bool_)):
        return set(range(1, n_steps + 1)) if store_fields else set()
    if isinstance(store_fields, Iterable) and not isinstance(store_fields, (str, bytes)):
        steps = set()
        for s in store_fields:
            if isinstance(s, (bool, np.bool_)) or not isinstance(s, (int, np.integer)) or not 1 <= s <= n_steps:
                raise ValueError(
                    f"store_fields must be a bool or an iterable of step numbers in 1..{n_steps}, got {s!r}"
                )
            steps.add(int(s))
        return steps
    raise ValueError(
        f"store_fields must be a bool or an iterable of step numbers in 1..{n_steps}, got {store_fields!r}"
    )


# --------------------------------------------------------------------------- workspace
def _plans(n: int, threads: int):
    """The cached FFT pair for an ``n x n`` grid.

    ``get_fft`` is an ``lru_cache`` keyed on the literal arguments; for one
    thread this is the same call as :func:`roughcontact.surface.generate_surface`
    makes, so both share one set of plans and buffers (33 MB at n = 1024).
    """
    if threads == 1:
        return get_fft((n, n), backend=None)
    return get_fft((n, n), threads=threads)


class _Workspace:
    """Grid-level state reused across load steps: plans, kernel, buffers, fields."""

    def __init__(self, heights: np.ndarray, e_star: float, length: float, threads: int):
        n = heights.shape[0]
        self.n = n
        self.size = n * n
        self.length = length
        self.e_star = e_star
        self.fft = _plans(n, threads)
        kern = elastic_kernel(n, e_star, length)
        # Interleaved (re, im) copy so that the kernel product is a float64 ufunc
        # call on the complex buffer, with no complex temporary.
        self.kern2 = np.repeat(kern[..., None], 2, axis=-1)
        # Diagonal of the real-space influence matrix: the natural step for a
        # node whose conjugate direction vanished (e.g. a single contact node).
        self.self_influence = float((kern * rfft_weights(n)).sum() / self.size)
        self.h = heights
        self.hf = heights.ravel()
        self.h_mean = float(heights.mean())
        self.h_rms = float(np.sqrt(np.mean((heights - self.h_mean) ** 2)))
        self.w = np.empty((n, n))  # u - h (gap without the rigid-body offset)
        self.wf = self.w.ravel()
        self.P = np.zeros((n, n))  # pressure, full field
        self.Pf = self.P.ravel()
        self.T = np.zeros((n, n))  # conjugate direction, zero off the free set
        self.Tf = self.T.ravel()
        self.mask = np.zeros((n, n), dtype=bool)
        self.bbuf = np.empty((n, n), dtype=bool)

    def apply_k(self, field: np.ndarray) -> np.ndarray:
        """``K field`` in an FFT buffer that the next transform overwrites."""
        spec = self.fft.forward(field)
        view = spec.view(np.float64).reshape(self.kern2.shape)
        np.multiply(view, self.kern2, out=view)
        return self.fft.backward(spec)

    def refresh(self) -> None:
        """Recompute ``w = K P - h`` from the full pressure field (one FFT pair)."""
        np.subtract(self.apply_k(self.P), self.h, out=self.w)

    def scale(self, p0: float) -> float:
        return self.h_rms if self.h_rms > 0 else p0 * self.length / self.e_star


def _enforce_mean(P: np.ndarray, target: float, hardness: float | None) -> None:
    """Make ``P.sum() == target`` in place, keeping ``0 <= P <= hardness``.

    Without a cap this is a plain rescale. With a cap, the nodes below it are
    rescaled (clipping those pushed over it, repeatedly); when the capped nodes
    alone carry more than ``target``, ``P <- min(beta P, H)`` with the unique
    ``beta`` for which the sum hits ``target`` (the sum is piecewise linear and
    increasing in ``beta``, so ``beta`` follows from the sorted entries).
    """
    if hardness is None:
        s = P.sum()
        if s > 0:
            P *= target / s
        else:
            P.fill(target / P.size)
        return
    for _ in range(64):
        # Preferred: rescale only the nodes below the cap, so that capped nodes
        # stay capped (the active-set logic releases them when their gap opens).
        sat = P >= hardness
        ns = np.count_nonzero(sat)
        need = target - hardness * ns
        free_sum = P.sum() - hardness * ns
        if need <= 0 or free_sum <= 0:
            break
        free = ~sat
        alpha = need / free_sum
        top = alpha * P[free].max()
        P[free] *= alpha
        if top < hardness:
            return
        np.minimum(P, hardness, out=P)
    flat = P.ravel()
    pos = np.flatnonzero(flat > 0)
    if hardness * pos.size <= target:
        # Too few loaded nodes to carry p0 under the cap: restart from the
        # uniform field (admissible since p0 < hardness).
        P.fill(target / P.size)
        return
    a = np.sort(flat[pos])[::-1]  # descending
    tail = np.cumsum(a[::-1])[::-1]  # tail[k] = sum(a[k:])
    k = np.arange(a.size)
    beta = (target - hardness * k) / tail
    ok = (beta * a <= hardness) & (target - hardness * k > 0)
    ok[1:] &= beta[1:] * a[:-1] >= hardness
    first = int(np.argmax(ok)) if ok.any() else 0
    b = float(beta[first])
    flat[pos] = np.minimum(flat[pos] * b, hardness)


def _active_sets(ws: _Workspace, hardness: float | None):
    np.greater(ws.P, 0.0, out=ws.mask)
    if hardness is None:
        return np.flatnonzero(ws.mask), np.empty(0, dtype=np.intp)
    sat = ws.Pf >= hardness
    free = ws.mask.ravel() & ~sat
    return np.flatnonzero(free), np.flatnonzero(sat)


# --------------------------------------------------------------------------- core loop
def _pk_solve(ws: _Workspace, p0: float, tol: float, max_iter: int,
              hardness: float | None, fresh: bool):
    """Solve one load step in place on ``ws`` from the pressure already in ``ws.P``.

    ``ws.P`` must be >= 0 (<= hardness) with mean ``p0``; ``fresh`` says whether
    ``ws.w`` already equals ``K P - h``. Returns ``(gbar, iterations, residual,
    converged, n_saturated)`` with ``ws.P`` and ``ws.w`` consistent on exit.
    """
    hard = hardness is not None
    cap = hardness if hard else math.inf
    target = p0 * ws.size
    scale = ws.scale(p0)
    inv_norm = 1.0 / (target * scale)
    w, wf, Pf, T, Tf, mask, bbuf = ws.w, ws.wf, ws.Pf, ws.T, ws.Tf, ws.mask, ws.bbuf
    maskf = mask.ravel()

    if not fresh:
        ws.refresh()
    idx, sidx = _active_sets(ws, hardness)
    p_c = Pf[idx]
    t_c = np.zeros_like(p_c)
    g_c, a_c = np.empty_like(p_c), np.empty_like(p_c)
    T.fill(0.0)
    fresh = True
    delta = 0.0
    g_old = 1.0
    it = 0
    ref, it_ref = math.inf, 0
    converged = False
    gbar = 0.0
    residual = math.inf
    joined_after = 0  # > 0: nodes from this index on joined F this iteration

    while True:
        nf = idx.size
        # ---- gap on the free set, offset chosen so that it has zero mean there
        if nf:
            np.take(wf, idx, out=g_c)
            gbar = g_c.sum() / nf
            g_c -= gbar
        elif sidx.size:
            # Every contact node is at the cap: the least admissible offset
            # leaves them all at g <= 0.
            gbar = float(wf[sidx].max())
        # ---- sign violations: out-of-contact nodes with g < 0, capped nodes with g > 0
        np.less(w, gbar, out=bbuf)
        np.greater(bbuf, mask, out=bbuf)  # (w < gbar) & ~mask, for booleans
        ncand = np.count_nonzero(bbuf)
        pen = 0.0
        if ncand:
            cand = np.flatnonzero(bbuf)
            g_cand = wf[cand] - gbar
            pen = -float(g_cand.min())
        orth = 0.0
        if nf:
            pen = max(pen, -float(g_c.min()))
            np.abs(g_c, out=a_c)
            orth = _dot(p_c, a_c) * inv_norm
        nrel, cap_err = 0, 0.0
        if hard and sidx.size:
            g_s = wf[sidx] - gbar
            rel = g_s > 0
            nrel = np.count_nonzero(rel)
            if nrel:
                cap_err = float(g_s.max())
        residual = max(orth, pen / scale, cap_err / scale)

        if residual <= tol:
            if fresh:
                converged = True
                break
            # Incremental updates may have drifted: confirm on a fresh K p.
            _sync_pressure(ws, idx, p_c, target, hardness, sidx.size)
            ws.refresh()
            fresh = True
            continue
        if not math.isfinite(residual) or it >= max_iter:
            break
        if residual < 0.5 * ref:
            ref, it_ref = residual, it
        elif it - it_ref >= STALL_WINDOW:
            break
        it += 1

        # ---- violating nodes join the free set and the CG restarts (PK's rule):
        # folding them into the search direction keeps the update of u exact.
        if ncand or nrel:
            parts_i, parts_p, parts_g = [idx], [p_c], [g_c]
            if ncand:
                parts_i.append(cand)
                parts_p.append(np.zeros(ncand))
                parts_g.append(g_cand)
            if nrel:
                parts_i.append(sidx[rel])
                parts_p.append(np.full(nrel, cap))
                parts_g.append(g_s[rel])
                sidx = sidx[~rel]
            joined_after = nf
            idx = np.concatenate(parts_i)
            p_c = np.concatenate(parts_p)
            g_c = np.concatenate(parts_g)
            a_c = np.empty_like(p_c)
            t_c = np.empty_like(p_c)
            if ncand:
                maskf[cand] = True
            delta = 0.0
            nf = idx.size
        if nf == 0:
            break

        # ---- conjugate direction (zero mean on F, so mean(p) is kept) and step
        G = _dot(g_c, g_c)
        if delta > 0.0 and g_old > 0.0:
            t_c *= delta * G / g_old
            t_c += g_c
        else:
            t_c[...] = g_c
            if joined_after:
                # Restore zero mean on the nodes already in contact only: each
                # joining node keeps t = g (< 0, or > 0 for a capped node), so
                # the step moves it into the admissible range as PK's rule does
                # instead of clipping it at once. g.t = |g|^2 still holds
                # because g has zero mean on the old free set.
                t_c[:joined_after] -= t_c.sum() / joined_after
            joined_after = 0
        g_old = G
        delta = 1.0
        Tf[idx] = t_c
        Rf = ws.apply_k(T).ravel()
        np.take(Rf, idx, out=a_c)
        rt = _dot(a_c, t_c)
        tau = _dot(g_c, t_c) / rt if rt > 0.0 else math.nan
        if not (math.isfinite(tau) and tau > 0.0):
            break  # null direction: nothing can move, report as not converged
        # trial pressure in a_c
        np.multiply(t_c, -tau, out=a_c)
        a_c += p_c
        out = a_c <= 0.0
        if hard:
            out |= a_c >= cap
        n_out = np.count_nonzero(out)
        if n_out == 0:
            p_c, a_c = a_c, p_c
            np.multiply(Rf, tau, out=Rf)
            wf -= Rf  # u <- u - tau K t: exact, no FFT pair for p
            fresh = False
            continue

        # ---- Polonsky-Keer projection onto the bounds, exact mean, fresh K p
        np.clip(a_c, 0.0, cap, out=a_c)
        Pf[idx] = a_c
        _enforce_mean(ws.P, target, hardness)
        idx, sidx = _active_sets(ws, hardness)
        t_c = Tf[idx]
        if t_c.size:
            t_c -= t_c.mean()
        T.fill(0.0)
        p_c = Pf[idx]
        g_c, a_c = np.empty_like(p_c), np.empty_like(p_c)
        ws.refresh()
        fresh = True

    Pf[idx] = p_c
    if not fresh:
        _sync_pressure(ws, idx, p_c, target, hardness, sidx.size)
        ws.refresh()
        if idx.size:
            gbar = float(wf[idx].mean())
    # An early exit right after nodes joined leaves them flagged with p = 0.
    np.greater(ws.P, 0.0, out=mask)
    return gbar, it, residual, converged, int(np.count_nonzero(Pf >= cap)) if hard else 0


def _sync_pressure(ws, idx, p_c, target, hardness, n_sat):
    """Write the free-set pressure back to the full field with the exact mean.

    Between full rebuilds the mean drifts only by round-off; the rescale is
    ``1 + O(1e-16)`` and keeps ``mean(p) = p0`` to machine precision.
    """
    if not p_c.size:
        return
    need = target - (hardness * n_sat if hardness is not None else 0.0)
    s = p_c.sum()
    if s > 0 and need > 0:
        p_c *= need / s
        if hardness is not None:
            np.minimum(p_c, hardness, out=p_c)
    ws.Pf[idx] = p_c


# --------------------------------------------------------------------------- public API
def _step_stats(ws: _Workspace, p0, gbar, hardness, n_sat):
    n2 = ws.size
    area = np.count_nonzero(ws.mask) / n2
    if area <= 0:
        raise RuntimeError(f"no contact node at p0={p0!r}: the solver lost the load (bug)")
    mean_gap = float(ws.w.mean()) - gbar
    perim = contact_perimeter(ws.mask, ws.length)
    plastic_area = plastic_load = None
    if hardness is not None:
        plastic_area = n_sat / n2
        plastic_load = hardness * n_sat / (p0 * n2)
    return area, mean_gap, perim, plastic_area, plastic_load


def solve_step(heights, p0: float, *, e_star: float = 1.0, length: float = 1.0,
               tol: float = 1e-8, max_iter: int = DEFAULT_MAX_ITER, threads: int = 1,
               hardness: float | None = None, initial_pressure=None) -> StepResult:
    """Solve the contact for one mean pressure.

    Parameters
    ----------
    heights : array_like, shape (n, n)
        Rigid surface heights [length]; the highest points touch first.
    p0 : float
        Applied mean pressure, ``0 < p0`` (``< hardness`` if given) [pressure].
    e_star, length, tol, max_iter, threads, hardness
        As in :func:`solve_contact`.
    initial_pressure : array_like, shape (n, n), optional
        Starting pressure (clipped to ``>= 0`` and rescaled to mean ``p0``);
        uniform ``p0`` when omitted.

    Returns
    -------
    StepResult
        Fields are fresh arrays owned by the caller.
    """
    h = _validate_heights(heights)
    try:
        p0 = float(p0)
    except (TypeError, ValueError):
        raise ValueError(f"p0 must be a finite number > 0, got {p0!r}") from None
    if not (math.isfinite(p0) and p0 > 0):
        raise ValueError(f"p0 must be a finite number > 0, got {p0!r}")
    p = np.array([p0])
    e_star, length, tol, max_iter, hardness, threads = _validate_solver_args(
        e_star, length, tol, max_iter, hardness, threads)
    _check_below_hardness(p, hardness)
    ws = _Workspace(h, e_star, length, threads)
    if initial_pressure is None:
        ws.P.fill(p[0])
    else:
        init = _validate_heights(initial_pressure, name="initial_pressure")
        if init.shape != h.shape:
            raise ValueError(f"initial_pressure must have shape {h.shape}, got {init.shape}")
        np.maximum(init, 0.0, out=ws.P)
        if hardness is not None:
            np.minimum(ws.P, hardness, out=ws.P)
    _enforce_mean(ws.P, p[0] * ws.size, hardness)
    t0 = time.perf_counter()
    gbar, its, res, conv, n_sat = _pk_solve(ws, float(p[0]), tol, max_iter, hardness, fresh=False)
    wall = time.perf_counter() - t0
    area, mean_gap, perim, pa, pl = _step_stats(ws, float(p[0]), gbar, hardness, n_sat)
    return StepResult(float(p[0]), ws.P.copy(), ws.w - gbar, area, mean_gap, perim, its,
                      float(res), bool(conv), wall, pa, pl)


def _check_below_hardness(p: np.ndarray, hardness):
    if hardness is not None and np.any(p >= hardness):
        raise ValueError(
            f"every applied mean pressure must be < hardness={hardness!r} (pressure is capped "
            f"at the hardness, so its mean cannot reach it); got max pressure {float(p.max())!r}"
        )


def solve_contact(heights, pressures, *, e_star: float = 1.0, length: float = 1.0,
                  tol: float = 1e-8, max_iter: int = DEFAULT_MAX_ITER, store_fields=False,
                  threads: int = 1, hardness: float | None = None,
                  clusters: bool = False) -> xr.Dataset:
    """Solve the normal contact of a rigid rough surface on a periodic half-space.

    Parameters
    ----------
    heights : array_like, shape (n, n)
        Rigid surface heights [length] on the square periodic cell, axis 0 = x,
        axis 1 = y; the highest points touch first. Any ``n >= 4``, odd or not.
    pressures : sequence of float, shape (n_steps,)
        Applied mean pressures ``p0 > 0``, one load step each [pressure, same unit
        as ``e_star``]. Any order is accepted; each step warm-starts from the
        previous one, which pays off most for increasing loads.
    e_star : float
        Plane-strain modulus ``E* = E / (1 - nu**2)`` of the half-space, > 0.
    length : float
        Side ``L`` of the periodic cell [length], > 0.
    tol : float
        Convergence tolerance in (0, 1) on the scale-free residual of the module
        docstring.
    max_iter : int
        Iteration cap per step, >= 1.
    store_fields : bool or iterable of int
        ``True`` stores ``contact_pressure`` and ``gap`` for every step (dims
        ``step, x, y``); an iterable of 1-based step numbers stores only those
        (dims ``field_step, x, y``, coordinate ``field_step`` = step numbers).
    threads : int
        FFTW threads (default 1).
    hardness : float, optional
        Cap on the pressure (perfectly plastic interface) [pressure], > every p0.
    clusters : bool
        Add contact-cluster statistics per step (periodic 4-connected labelling, see
        :mod:`roughcontact.clusters`): ``cluster_count``, ``cluster_mean_area``,
        ``cluster_max_area`` and ``cluster_area_histogram``. Off: no labelling work.

    Returns
    -------
    xarray.Dataset
        Dimension ``step`` (coordinate 1..n_steps) with ``pressure``,
        ``area_fraction``, ``mean_contact_pressure``, ``mean_gap``,
        ``contact_perimeter``, ``iterations``, ``residual``, ``converged``,
        ``wall_time`` and, with a hardness, ``plastic_area_fraction`` and
        ``plastic_load_fraction``; fields and ``x``/``y`` coordinates only when
        stored. Every variable carries ``units`` and ``long_name``.

    Raises
    ------
    ValueError
        For invalid input, naming the argument and its allowed range.
    """
    h = _validate_heights(heights)
    p = _validate_pressures(pressures)
    e_star, length, tol, max_iter, hardness, threads = _validate_solver_args(
        e_star, length, tol, max_iter, hardness, threads)
    _check_below_hardness(p, hardness)
    store = _validate_store(store_fields, p.size)
    n = h.shape[0]
    ws = _Workspace(h, e_star, length, threads)

    n_steps = p.size
    cols = {k: np.empty(n_steps) for k in
            ("area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter",
             "residual", "wall_time", "plastic_area_fraction", "plastic_load_fraction")}
    iters = np.empty(n_steps, dtype=np.int64)
    conv = np.empty(n_steps, dtype=bool)
    fields_p, fields_g, field_steps = [], [], []
    masks = [] if clusters else None
    prev = None
    for k, p0 in enumerate(p):
        p0 = float(p0)
        t0 = time.perf_counter()
        if prev is None:
            ws.P.fill(p0)
            fresh = False
        elif hardness is None:
            # Warm start: p and u = K p scale together, so w = K p - h follows
            # without a transform.
            s = p0 / prev
            ws.w *= s
            ws.w += (s - 1.0) * ws.h
            ws.P *= s
            fresh = True
        else:
            ws.P *= p0 / prev
            np.minimum(ws.P, hardness, out=ws.P)
            _enforce_mean(ws.P, p0 * ws.size, hardness)
            fresh = False
        gbar, its, res, ok, n_sat = _pk_solve(ws, p0, tol, max_iter, hardness, fresh)
        area, mean_gap, perim, pa, pl = _step_stats(ws, p0, gbar, hardness, n_sat)
        cols["wall_time"][k] = time.perf_counter() - t0
        cols["area_fraction"][k] = area
        cols["mean_contact_pressure"][k] = p0 / area
        cols["mean_gap"][k] = mean_gap
        cols["contact_perimeter"][k] = perim
        cols["residual"][k] = res
        cols["plastic_area_fraction"][k] = pa if pa is not None else 0.0
        cols["plastic_load_fraction"][k] = pl if pl is not None else 0.0
        iters[k] = its
        conv[k] = ok
        if k + 1 in store:
            fields_p.append(ws.P.copy())
            fields_g.append(ws.w - gbar)
            field_steps.append(k + 1)
        if masks is not None:
            masks.append(ws.P > 0)
        prev = p0

    ds = _to_dataset(p, cols, iters, conv, fields_p, fields_g, field_steps, store_fields,
                     n, e_star, length, tol, max_iter, hardness, threads, ws.fft.backend)
    if masks is not None:
        from .clusters import cluster_dataset

        stats = cluster_dataset(masks, ds["step"].values, length)
        ds = ds.merge(stats.drop_vars("step"), combine_attrs="override")
    return ds


def _to_dataset(p, cols, iters, conv, fields_p, fields_g, field_steps, store_fields, n,
                e_star, length, tol, max_iter, hardness, threads, backend) -> xr.Dataset:
    steps = np.arange(1, p.size + 1)
    meta = {
        "pressure": (p, PRESSURE_UNITS, "applied mean pressure p0 = F / A0"),
        "area_fraction": (cols["area_fraction"], FRACTION_UNITS,
                          "real contact area fraction A / A0 (fraction of nodes with p > 0)"),
        "mean_contact_pressure": (cols["mean_contact_pressure"], PRESSURE_UNITS,
                                  "mean contact pressure F / A = p0 / (A / A0)"),
        "mean_gap": (cols["mean_gap"], LENGTH_UNITS,
                     "mean gap between the rigid surface and the deformed half-space"),
        "contact_perimeter": (cols["contact_perimeter"], INVERSE_LENGTH_UNITS,
                              "contact-set boundary length (pixel edges x dx) per unit nominal area"),
        "iterations": (iters, FRACTION_UNITS, "conjugate-gradient iterations"),
        "residual": (cols["residual"], FRACTION_UNITS,
                     "final scale-free residual max(sum_F(p|g|)/(sum(p) s), max(0,-min g)/s)"),
        "converged": (conv, FRACTION_UNITS, "residual <= tol on a freshly recomputed displacement"),
        "wall_time": (cols["wall_time"], "s", "wall-clock time of the load step"),
    }
    if hardness is not None:
        meta["plastic_area_fraction"] = (cols["plastic_area_fraction"], FRACTION_UNITS,
                                         "fraction of nodes at the hardness cap")
        meta["plastic_load_fraction"] = (cols["plastic_load_fraction"], FRACTION_UNITS,
                                         "share of the load carried by nodes at the hardness cap")
    data_vars = {name: xr.Variable(("step",), val, {"units": u, "long_name": ln})
                 for name, (val, u, ln) in meta.items()}
    coords = {"step": xr.Variable(("step",), steps, {"units": FRACTION_UNITS,
                                                      "long_name": "load step number (1-based)"})}
    if field_steps:
        dim = "step" if (isinstance(store_fields, (bool, np.bool_)) and store_fields) else "field_step"
        dims = (dim, "x", "y")
        xs = np.arange(n) * (length / n)
        coords["x"] = xr.Variable(("x",), xs, {"units": LENGTH_UNITS, "long_name": "node position along axis 0"})
        coords["y"] = xr.Variable(("y",), xs.copy(), {"units": LENGTH_UNITS, "long_name": "node position along axis 1"})
        if dim == "field_step":
            coords["field_step"] = xr.Variable(("field_step",), np.array(field_steps),
                                               {"units": FRACTION_UNITS,
                                                "long_name": "load step number of the stored fields"})
        data_vars["contact_pressure"] = xr.Variable(
            dims, np.stack(fields_p), {"units": PRESSURE_UNITS, "long_name": "nodal contact pressure"})
        data_vars["gap"] = xr.Variable(
            dims, np.stack(fields_g), {"units": LENGTH_UNITS,
                                       "long_name": "gap between the rigid surface and the half-space"})
    attrs = {
        "e_star": e_star,
        "length": length,
        "tol": tol,
        "max_iter": max_iter,
        "threads": threads,
        "fft_backend": backend,
        "n": n,
        "solver": SOLVER_NAME,
        "solver_description": SOLVER_DESCRIPTION,
        "pressure_units": PRESSURE_UNITS,
    }
    if hardness is not None:
        attrs["hardness"] = hardness
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


__all__ = [
    "DEFAULT_MAX_ITER",
    "FRACTION_UNITS",
    "INVERSE_LENGTH_UNITS",
    "LENGTH_UNITS",
    "PRESSURE_UNITS",
    "STALL_WINDOW",
    "StepResult",
    "contact_perimeter",
    "displacement",
    "elastic_kernel",
    "gap_scale",
    "solve_contact",
    "solve_step",
]
