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
- rectangular cells (``length=(Lx, Ly)``, heights ``(nx, ny)``, pixels ``dx = Lx / nx``
  and ``dy = Ly / ny``) are checked the same way, with their attributes (``length_x``,
  ``length_y``, ``nx``, ``ny``), the perimeter's edge lengths (``dy`` across x, ``dx``
  across y) and the quadrature over a ``dx x dy`` pixel (:func:`pixel_integral`);
- profiles (1-D heights, plane strain) likewise, with their attributes (``length``, ``n``,
  ``surface_dimension = 1``), the perimeter as interval ends per unit length, and the gap against
  a plain ``numpy.fft`` 1-D product (periodic) or a direct sum with the strip's influence by
  quadrature (free: :func:`direct_free_profile_displacement`);
- on every converged step, the solver's convergence criterion (docs/solver.md,
  "Convergence criterion") recomputed here from the fields, with ``s`` the same
  gap scale (:func:`roughcontact.solver.units.gap_scale`): ``gap >= -tol * s`` wherever
  ``p`` is below the cap, ``gap <= tol * s`` wherever it is at the cap, the gap has
  zero mean on the elastic contact set ``F = {0 < p < hardness}`` (the offset
  convention) and ``sum_F(p |gap|) / (nx ny p0 s) <= tol`` (gap ~ 0 on ``F``).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from roughcontact.solver import contact_perimeter
from roughcontact.solver.halfspace import elastic_kernel
from roughcontact.solver.units import gap_scale

STEP_VARS = (
    "pressure", "area_fraction", "mean_contact_pressure", "mean_gap", "contact_perimeter",
    "iterations", "residual", "converged", "wall_time",
)
PLASTIC_VARS = ("plastic_area_fraction", "plastic_load_fraction")


def independent_displacement(p: np.ndarray, e_star: float, length) -> np.ndarray:
    """Zero-mean displacement of the periodic half-space with plain numpy.fft (``length`` L or (Lx, Ly))."""
    return np.fft.irfft2(np.fft.rfft2(p) * elastic_kernel(p.shape, e_star, length), s=p.shape)


def is_square_cell(shape, length) -> bool:
    """Whether heights of ``shape`` on a cell of ``length`` (L or (Lx, Ly)) are the square case."""
    if np.ndim(length) == 0:
        return True
    return shape[0] == shape[1] and float(length[0]) == float(length[1])


def sides(length) -> tuple[float, float]:
    """``(Lx, Ly)`` of ``length`` (a float L: ``(L, L)``)."""
    return (float(length), float(length)) if np.ndim(length) == 0 else (float(length[0]), float(length[1]))


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


_GL = np.polynomial.legendre.leggauss(12)


def _composite(half: float, sub: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on ``[-half, half]`` cut into ``sub`` equal pieces (12 points each)."""
    xg, wg = _GL
    edges = np.linspace(-half, half, sub + 1)
    h = half / sub
    return (0.5 * (edges[1:] + edges[:-1])[:, None] + h * xg[None, :]).ravel(), np.tile(h * wg, sub)


def _self_integral(rho: float) -> float:
    """Integral of ``1 / r`` over ``[-1/2, 1/2] x [-rho/2, rho/2]`` about its centre (singular).

    Four corner quadrants ``[0, a] x [0, b]``, each cut along its diagonal into two
    triangles with the singular vertex at the origin; Duffy's substitution
    (``x = a s``, ``y = b s t``: ``dA / r = a b ds dt / sqrt(a^2 + b^2 t^2)``) leaves a smooth
    1-D integrand in ``t``, integrated by composite Gauss-Legendre (64 pieces).
    """
    t, w = _composite(0.5, 64)
    t = t + 0.5  # on [0, 1]
    a, b = 0.5, 0.5 * rho
    below = np.sum(w * a * b / np.sqrt(a * a + (b * t) ** 2))
    above = np.sum(w * a * b / np.sqrt(b * b + (a * t) ** 2))
    return 4.0 * float(below + above)


def pixel_integral(x, y, rho: float) -> np.ndarray:
    """Integral of ``1 / r`` over the pixel ``[-1/2, 1/2] x [-rho/2, rho/2]`` seen from ``(x, y)``, by quadrature.

    Units of ``dx`` (the pixel is ``1 x rho``; ``pi E* u / dx`` under unit pressure).
    Tensor Gauss-Legendre (12 x 12 points per sub-rectangle), the pixel cut into pieces no
    larger than 1/8 of the point's distance ``d`` to it along either side (each piece then
    sees the near-singularity at >= 8 half-sides: error ~16^-24); the singular self-term
    by :func:`_self_integral`. Independent of the solver's closed form (Love's).
    """
    x, y = np.abs(np.atleast_1d(np.asarray(x, float))), np.abs(np.atleast_1d(np.asarray(y, float)))
    d = np.hypot(np.maximum(x - 0.5, 0.0), np.maximum(y - 0.5 * rho, 0.0))
    out = np.empty(x.shape)
    self_term = d == 0.0
    out[self_term] = _self_integral(rho)
    dd = np.where(self_term, 1.0, d)
    subs = np.stack([np.maximum(1, np.ceil(4.0 / dd)), np.maximum(1, np.ceil(4.0 * rho / dd))], axis=-1).astype(int)
    for sx, sy in {tuple(v) for v in subs[~self_term]}:
        pick = ~self_term & (subs[:, 0] == sx) & (subs[:, 1] == sy)
        px, wx = _composite(0.5, sx)
        py, wy = _composite(0.5 * rho, sy)
        acc = np.zeros(int(pick.sum()))
        for xs, w in zip(px, wx, strict=True):
            acc += w * np.sum(wy[None, :] / np.hypot(x[pick, None] - xs, y[pick, None] - py[None, :]), axis=1)
        out[pick] = acc
    return out


@functools.lru_cache(maxsize=4)
def quadrature_influence_rect(nx: int, ny: int, rho: float) -> np.ndarray:
    """``pi E* u / dx`` at offsets ``(i dx, j dy)``, ``0 <= i < nx``, ``0 <= j < ny``, pixel ``dy = rho dx``.

    :func:`pixel_integral` at every offset; shape (nx, ny).
    """
    i, j = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float) * rho, indexing="ij")
    out = pixel_integral(i.ravel(), j.ravel(), rho).reshape(nx, ny)
    out.setflags(write=False)
    return out


def direct_free_displacement(p: np.ndarray, e_star: float = 1.0, length=1.0) -> np.ndarray:
    """Displacement of the free half-space by direct summation (no FFT), ``O(n^4)``: small ``n`` only.

    ``u[i, j] = dx / (pi E*) sum_kl C[|i - k|, |j - l|] p[k, l]`` with ``C`` from
    :func:`quadrature_influence` (square cell) or :func:`quadrature_influence_rect`
    (``length=(Lx, Ly)``: pixels ``dx = Lx / nx`` by ``dy = Ly / ny``).
    """
    if not is_square_cell(p.shape, length):
        return _direct_free_rect(np.asarray(p, dtype=float), e_star, sides(length))
    n = p.shape[0]
    c = quadrature_influence(n)
    k = np.arange(n)
    blocks = c[:, np.abs(k[:, None] - k[None, :])]  # blocks[d][j, l] = C[d, |j - l|], symmetric
    q = np.asarray(p, dtype=float)[None, :, :] @ blocks  # q[d][k, j] = sum_l p[k, l] C[d, |j - l|]
    u = q[np.abs(k[:, None] - k[None, :]), k[None, :], :].sum(axis=1)  # sum over k of q[|i - k|][k, j]
    return u * (length / n) / (math.pi * e_star)


def _direct_free_rect(p: np.ndarray, e_star: float, lengths: tuple[float, float]) -> np.ndarray:
    """:func:`direct_free_displacement` on a rectangular cell: every pixel pair summed, ``O(nx^2 ny^2)``."""
    (nx, ny), (lx, ly) = p.shape, lengths
    dx, dy = lx / nx, ly / ny
    c = quadrature_influence_rect(nx, ny, dy / dx)
    i, j = np.arange(nx), np.arange(ny)
    pairs = c[np.abs(i[:, None] - i[None, :])][:, :, np.abs(j[:, None] - j[None, :])]  # [i, k, j, l]
    return np.einsum("ikjl,kl->ij", pairs, p) * dx / (math.pi * e_star)


def independent_profile_displacement(p: np.ndarray, e_star: float, length: float) -> np.ndarray:
    """Zero-mean plane-strain displacement of a periodic profile, ``2 p(q) / (E* |q|)``, with numpy.fft (1-D)."""
    n = p.size
    q = 2 * np.pi * np.abs(np.fft.rfftfreq(n, d=length / n))
    kern = np.divide(2.0 / e_star, q, out=np.zeros_like(q), where=q > 0)
    return np.fft.irfft(np.fft.rfft(p) * kern, n)


def strip_influence_by_quadrature(n: int, length: float) -> np.ndarray:
    """``integral ln(L / |x - s|) ds`` over a pixel ``|s| < dx / 2`` at offsets ``x = i dx``, ``i = 0..n-1``.

    Off the pixel, composite Gauss-Legendre (12 points on each of 16 pieces: the integrand is smooth
    there); on it, the closed form ``dx (ln(2 L / dx) + 1)`` of the singular self-term. Independent of
    the solver's antiderivative differences (:func:`roughcontact.solver.love.line_influence`).
    """
    dx = length / n
    pts, wts = _composite(0.5 * dx, 16)
    x = np.arange(n, dtype=float)[:, None] * dx
    with np.errstate(divide="ignore"):
        out = np.sum(wts[None, :] * np.log(length / np.abs(x - pts[None, :])), axis=1)
    out[0] = dx * (math.log(2 * length / dx) + 1)
    return out


def direct_free_profile_displacement(p: np.ndarray, e_star: float, length: float) -> np.ndarray:
    """Plane-strain displacement of a free profile by direct summation, ``2 / (pi E*)`` times the strip's
    influence (:func:`strip_influence_by_quadrature`) against every pixel's pressure; datum ``D = L``."""
    n = p.size
    c = strip_influence_by_quadrature(n, length)
    k = np.arange(n)
    return (c[np.abs(k[:, None] - k[None, :])] @ p) * 2.0 / (math.pi * e_star)


def _check_profile_attrs(ds, n: int) -> None:
    """A profile's global attributes: ``length``, ``n`` and ``surface_dimension = 1``, no y side."""
    assert ds.attrs["surface_dimension"] == 1 and ds.attrs["n"] == n
    assert "length_x" not in ds.attrs and "ny" not in ds.attrs
    if "contact_pressure" in ds:
        assert ds["contact_pressure"].dims[1:] == ("x",) and "y" not in ds.coords


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
    n2 = h.size
    profile = h.ndim == 1
    square = profile or is_square_cell(h.shape, length)
    if square and np.ndim(length) == 1:
        length = float(length[0])  # (L, L) on an n x n grid: the square cell, as the solver takes it
    for name in STEP_VARS:
        assert name in ds, f"missing variable {name}"
    for name in PLASTIC_VARS:
        assert (name in ds) == (hardness is not None), f"{name} presence wrong for hardness={hardness}"
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, f"{name} lacks units/long_name"
        if var.dtype.kind in "fc":
            assert np.all(np.isfinite(var.values)), f"{name} has non-finite values"
    cell = ("length", "n") if square else ("length_x", "length_y", "nx", "ny")
    for key in ("e_star", *cell, "tol", "max_iter", "fft_backend", "solver"):
        assert key in ds.attrs, f"missing dataset attribute {key}"
    if profile:
        _check_profile_attrs(ds, n)
    elif square:
        assert ds.attrs["n"] == n
    else:
        assert "length" not in ds.attrs and "n" not in ds.attrs
        assert (ds.attrs["length_x"], ds.attrs["length_y"]) == sides(length)
        assert (ds.attrs["nx"], ds.attrs["ny"]) == h.shape
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
                    f"step {step}: complementarity sum_F(p|g|)/(nx ny p0 s) = {e_orth:.3e} > tol = {tol:.1e}")
        if hardness is not None:
            plastic = p >= hardness
            np.testing.assert_allclose(ds["plastic_area_fraction"].values[i], plastic.mean())
            np.testing.assert_allclose(ds["plastic_load_fraction"].values[i],
                                       hardness * plastic.sum() / (pp * n2), rtol=1e-12)
        # gap = u - h + d with u from an independent path: d is a constant
        if profile:
            displacement = independent_profile_displacement if periodic else direct_free_profile_displacement
        else:
            displacement = independent_displacement if periodic else direct_free_displacement
        u_ref = displacement(p, e_star, length)
        g_ref = u_ref - h
        offset = g - g_ref
        spread = offset.max() - offset.min()
        assert spread <= max(1e-9 * s, 1e-12 * np.abs(h).max()), (
            f"step {step}: gap inconsistent with the pressure (spread {spread:.3e}, scale {s:.3e})")
