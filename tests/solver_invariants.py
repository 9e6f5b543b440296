"""Invariant checks shared by the solver tests (no test functions here).

``check_solution`` verifies everything a :func:`roughcontact.solver.solve_contact`
result must satisfy whatever the surface, so that every test solve exercises it:

- every output is finite, every variable carries ``units`` and ``long_name``;
- ``mean_contact_pressure == p0 / area_fraction`` and ``0 < A/A0 <= 1``;
- A/A0 is non-decreasing with load (frictionless elastic contact grows
  monotonically with load, Barber 2003), checked on the steps sorted by ``p0``;
- a converged step has ``residual <= tol``;
- with stored fields: ``p >= 0`` (``<= hardness``), ``mean(p) == p0`` to 1e-10
  relative, ``mean(gap) == mean_gap``, A/A0 equals the fraction of ``p > 0``, and
  the gap equals ``u - h + d`` recomputed here with ``numpy.fft`` (an independent
  path from the solver's pyFFTW buffers and incremental updates) or, for
  ``boundary="free"``, by the direct (non-FFT) convolution of
  :func:`direct_free_displacement` with an influence function integrated here
  by quadrature;
- on every converged step, the solver's convergence criterion (module docstring of
  :mod:`roughcontact.solver`) recomputed here from the fields, with ``s`` the same
  gap scale (:func:`roughcontact.solver.gap_scale`): ``gap >= -tol * s`` wherever
  ``p`` is below the cap, ``gap <= tol * s`` wherever it is at the cap, the gap has
  zero mean on the elastic contact set ``F = {0 < p < hardness}`` (the offset
  convention) and ``sum_F(p |gap|) / (n^2 p0 s) <= tol`` (gap ~ 0 on ``F``).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from roughcontact.solver import contact_perimeter, elastic_kernel, gap_scale

STEP_VARS = (
    "pressure", "area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter",
    "iterations", "residual", "converged", "wall_time",
)
PLASTIC_VARS = ("plastic_area_fraction", "plastic_load_fraction")


def independent_displacement(p: np.ndarray, e_star: float, length: float) -> np.ndarray:
    """Zero-mean displacement of the periodic half-space with plain numpy.fft."""
    n = p.shape[0]
    return np.fft.irfft2(np.fft.rfft2(p) * elastic_kernel(n, e_star, length), s=p.shape)


@functools.lru_cache(maxsize=4)
def quadrature_influence(n: int) -> np.ndarray:
    """``pi E* u / dx`` at pixel offsets ``0..n-1`` under unit pressure on one pixel, by quadrature.

    Boussinesq: ``u = 1 / (pi E*) * integral of 1 / r over the pixel``. Written
    independently of the solver's closed form (Love's): Gauss-Legendre in both
    directions (12 x 12 points; composite, 8 x 8 sub-squares, for offsets up to
    3 pixels where the integrand varies most), and the singular self-term in polar
    coordinates, ``8 * integral_0^{pi/4} dtheta / (2 cos theta)``.
    """
    xg, wg = np.polynomial.legendre.leggauss(12)

    def integral(offsets: np.ndarray, sub: int) -> np.ndarray:
        edges = np.linspace(-0.5, 0.5, sub + 1)
        mids, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 / sub
        pts = (mids[:, None] + half * xg[None, :]).ravel()
        wts = np.tile(half * wg, sub)
        X, Y = offsets[:, None], offsets[None, :]
        acc = np.zeros((offsets.size, offsets.size))
        for xs, wx in zip(pts, wts, strict=True):
            acc += wx * np.sum(wts[:, None, None] / np.hypot(X - xs, Y - pts[:, None, None]), axis=0)
        return acc

    out = integral(np.arange(n, dtype=float), 1)
    m = min(n, 4)
    out[:m, :m] = integral(np.arange(m, dtype=float), 8)
    theta = 0.5 * (xg + 1.0) * (math.pi / 4)
    out[0, 0] = 8 * np.sum(0.5 * wg * (math.pi / 4) / (2 * np.cos(theta)))
    out.setflags(write=False)
    return out


def direct_free_displacement(p: np.ndarray, e_star: float = 1.0, length: float = 1.0) -> np.ndarray:
    """Displacement of the free half-space by direct summation (no FFT), ``O(n^4)``: small ``n`` only.

    ``u[i, j] = dx / (pi E*) sum_kl C[|i - k|, |j - l|] p[k, l]`` with ``C`` from
    :func:`quadrature_influence`.
    """
    n = p.shape[0]
    c = quadrature_influence(n)
    k = np.arange(n)
    blocks = c[:, np.abs(k[:, None] - k[None, :])]  # blocks[d][j, l] = C[d, |j - l|], symmetric
    q = np.asarray(p, dtype=float)[None, :, :] @ blocks  # q[d][k, j] = sum_l p[k, l] C[d, |j - l|]
    u = q[np.abs(k[:, None] - k[None, :]), k[None, :], :].sum(axis=1)  # sum over k of q[|i - k|][k, j]
    return u * (length / n) / (math.pi * e_star)


def check_solution(ds, heights, *, tol, e_star=1.0, length=1.0, hardness=None,
                   require_converged=True, area_slack_nodes=0, boundary="periodic"):
    """Assert the solver invariants on ``ds`` (see module docstring).

    ``area_slack_nodes`` allows that many nodes of decrease in the contact set
    between consecutive loads (0 by default: strict monotonicity). ``boundary``
    is the half-space the solve used (also checked against the ``boundary``
    attribute).
    """
    periodic = boundary == "periodic"
    h = np.asarray(heights, dtype=float)
    n = h.shape[0]
    n2 = n * n
    for name in STEP_VARS:
        assert name in ds, f"missing variable {name}"
    for name in PLASTIC_VARS:
        assert (name in ds) == (hardness is not None), f"{name} presence wrong for hardness={hardness}"
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, f"{name} lacks units/long_name"
        if var.dtype.kind in "fc":
            assert np.all(np.isfinite(var.values)), f"{name} has non-finite values"
    for key in ("e_star", "length", "tol", "max_iter", "fft_backend", "n", "solver"):
        assert key in ds.attrs, f"missing dataset attribute {key}"
    assert ds.attrs["n"] == n
    assert ds.attrs.get("boundary", "periodic") == boundary

    p0 = ds["pressure"].values
    area = ds["area_fraction"].values
    assert np.all(area > 0) and np.all(area <= 1)
    np.testing.assert_allclose(ds["mean_contact_pressure"].values, p0 / area, rtol=1e-12)
    assert np.all(ds["contact_perimeter"].values >= 0)
    assert np.all(ds["iterations"].values >= 0)
    converged = ds["converged"].values.astype(bool)
    if require_converged:
        assert converged.all(), f"not converged at steps {np.flatnonzero(~converged) + 1}"
    assert np.all(ds["residual"].values[converged] <= tol)

    order = np.argsort(p0, kind="stable")
    nodes = np.rint(area[order] * n2)
    assert np.all(np.diff(nodes) >= -area_slack_nodes), f"A/A0 decreases with load: {nodes}"

    if "contact_pressure" not in ds:
        return
    dim = ds["contact_pressure"].dims[0]
    steps = ds[dim].values
    for k, step in enumerate(steps):
        i = int(step) - 1
        p = ds["contact_pressure"].values[k]
        g = ds["gap"].values[k]
        pp = float(p0[i])
        assert p.min() >= 0.0
        if hardness is not None:
            assert p.max() <= hardness
        assert abs(p.mean() - pp) <= 1e-10 * pp, f"mean pressure {p.mean()} != p0 {pp}"
        mask = p > 0
        assert np.count_nonzero(mask) / n2 == area[i]
        assert contact_perimeter(mask, length, periodic) == ds["contact_perimeter"].values[i]
        np.testing.assert_allclose(g.mean(), ds["mean_gap"].values[i], rtol=1e-9,
                                   atol=1e-12 * (np.abs(h).max() + 1e-300))
        s = gap_scale(h, pp, e_star, length)
        below_cap = p < hardness if hardness is not None else np.ones_like(mask)
        if converged[i]:
            assert g[below_cap].min() >= -tol * s * (1 + 1e-9), (
                f"step {step}: gap {g[below_cap].min()} below -tol*s = {-tol * s}")
            at_cap = ~below_cap
            if at_cap.any():
                assert g[at_cap].max() <= tol * s * (1 + 1e-9), (
                    f"step {step}: gap {g[at_cap].max()} at the cap above tol*s = {tol * s}")
            free = mask & below_cap
            if free.any():
                assert abs(g[free].mean()) <= 1e-9 * s + 1e-12 * np.abs(g[free]).max(), (
                    f"step {step}: gap not zero-mean on the elastic contact set ({g[free].mean():.3e})")
                e_orth = float(np.sum(p[free] * np.abs(g[free]))) / (pp * n2 * s)
                assert e_orth <= tol * (1 + 1e-6), (
                    f"step {step}: complementarity sum_F(p|g|)/(n^2 p0 s) = {e_orth:.3e} > tol = {tol:.1e}")
        if hardness is not None:
            plastic = p >= hardness
            np.testing.assert_allclose(ds["plastic_area_fraction"].values[i], plastic.mean())
            np.testing.assert_allclose(ds["plastic_load_fraction"].values[i],
                                       hardness * plastic.sum() / (pp * n2), rtol=1e-12)
        # gap = u - h + d with u from an independent path: d is a constant
        u_ref = (independent_displacement if periodic else direct_free_displacement)(p, e_star, length)
        g_ref = u_ref - h
        offset = g - g_ref
        spread = offset.max() - offset.min()
        assert spread <= max(1e-9 * s, 1e-12 * np.abs(h).max()), (
            f"step {step}: gap inconsistent with the pressure (spread {spread:.3e}, scale {s:.3e})")
