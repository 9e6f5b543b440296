"""Profiles (1-D heights, plane strain) in the same solver: exact solutions, a peer, the cap, refusals.

A profile of ``n`` points on a length ``L`` is solved as the one-row grid ``(n, 1)`` of the 2-D
code: the periodic kernel ``2 / (E* |q|)`` along x, the free one the plane-strain strip
(``roughcontact.solver.love.line_influence``). References and tolerances:

- Westergaard (Johnson 1985, section 13.2): the sinusoid ``h = g cos(2 pi x / lambda)`` on one period,
  ``p* = pi E* g / lambda``; below ``p*`` the contact half-width ``a`` has ``sin^2(pi a / lambda) =
  p0 / p*`` and ``p(x) = 2 p0 cos(pi x / lambda) / sin^2(pi a / lambda) * sqrt(sin^2(pi a / lambda) -
  sin^2(pi x / lambda))``. The discrete contact length is a whole number of pixels, so ``2a`` is
  checked to one pixel either side (grid accuracy); the pressure to 2 % of its peak at nodes more than
  two pixels inside the edge (the square-root edge is where collocation errs, by ~dx^(1/2)).
- Full contact (``p0 > p*`` for the sinusoid; and any profile past its full-contact load): ``p = p0 +
  (E*/2) F^-1[|q| h^]`` exactly, to 1e-9 of p0 (the discrete problem has this solution node for node).
- Hertz, a cylinder of radius ``R`` on the free half-space (Johnson 1985, eq. 4.45): load ``P'`` per
  unit length, ``a^2 = 4 P' R / (pi E*)``, ``p(x) = 2 P' / (pi a^2) sqrt(a^2 - x^2)``: the contact
  width to one pixel, the peak pressure to 1 % (collocation at the peak is smooth), the pressure to
  3 % of its peak away from the edges.
- Tamaas ``model_type.basic_1d`` (test-only peer, ``PolonskyKeerRey``; ``KatoSaturated`` with a
  hardness): the same discrete problem, so the contact sets (and the nodes at the cap) agree node for
  node on rough profiles (A/A0 equal), as for maps.
- Every solve passes ``solver_invariants.check_solution`` (complementarity, gap against an
  independent displacement: numpy.fft for periodic, a direct sum with a quadrature of the strip for
  free).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from roughcontact.solver import solve_contact, solve_step
from roughcontact.solver.effects import Adhesion
from roughcontact.statistics.clusters import ClusterObserver
from solver_invariants import check_solution


def rough_profile(n: int, k_l: int, k_s: int, hurst: float, seed: int) -> np.ndarray:
    """A self-affine profile: random phases, ``|h(q)| ~ q^(-1/2 - H)`` for ``k_l <= k <= k_s`` (1-D PSD
    ``~ q^(-1-2H)``), flat below ``k_l``, zero above ``k_s``; zero mean, rms slope 0.1 (L = 1)."""
    rng = np.random.default_rng(seed)
    k = np.arange(n // 2 + 1, dtype=float)
    amp = np.zeros_like(k)
    band = (k >= 1) & (k <= k_s)
    amp[band] = np.maximum(k[band], k_l) ** (-0.5 - hurst)
    spec = amp * np.exp(2j * np.pi * rng.random(k.size))
    h = np.fft.irfft(spec, n)
    slope = np.sqrt(np.mean(np.gradient(h, 1.0 / n, edge_order=2) ** 2))
    return h * (0.1 / slope)


def westergaard(n: int, g: float = 0.01):
    """Heights of one period (``lambda = L = 1``) and ``p*``; node ``i`` at ``x = i / n``."""
    x = np.arange(n) / n
    return g * np.cos(2 * np.pi * x), math.pi * g


@pytest.mark.parametrize("ratio", [0.05, 0.3, 0.8])
def test_westergaard_partial_contact(ratio):
    n = 1024
    h, p_star = westergaard(n)
    p0 = ratio * p_star
    tol = 1e-10
    ds = solve_contact(h, [p0], tol=tol, store_fields=True)
    check_solution(ds, h, tol=tol)
    s2 = p0 / p_star
    a = math.asin(math.sqrt(s2)) / math.pi  # half-width, units of lambda
    assert abs(float(ds["area_fraction"][0]) - 2 * a) <= 2.0 / n  # one pixel at each edge
    x = np.arange(n) / n
    xs = np.where(x > 0.5, x - 1.0, x)  # signed distance from the crest
    p = ds["contact_pressure"].values[0]
    inside = np.abs(xs) < a - 2.0 / n
    exact = 2 * p0 * np.cos(np.pi * xs[inside]) / s2 * np.sqrt(s2 - np.sin(np.pi * xs[inside]) ** 2)
    assert np.abs(p[inside] - exact).max() <= 0.02 * exact.max()
    assert float(ds["contact_perimeter"][0]) == 2.0  # one interval: two ends on L = 1


def test_westergaard_full_contact():
    n = 256
    h, p_star = westergaard(n)
    p0 = 1.5 * p_star
    ds = solve_contact(h, [p0], tol=1e-12, store_fields=True)
    check_solution(ds, h, tol=1e-12)
    x = np.arange(n) / n
    exact = p0 + p_star * np.cos(2 * np.pi * x)
    np.testing.assert_allclose(ds["contact_pressure"].values[0], exact, rtol=0, atol=1e-9 * p0)
    assert float(ds["area_fraction"][0]) == 1.0 and float(ds["contact_perimeter"][0]) == 0.0


def test_full_contact_of_a_rough_profile():
    """Past full contact, p = p0 + (E*/2) F^-1[|q| h^] exactly (with E* = 2 and L = 3: the units too)."""
    n, e_star, length = 512, 2.0, 3.0
    h = rough_profile(n, 4, 64, 0.7, 1) * length
    q = 2 * np.pi * np.abs(np.fft.rfftfreq(n, d=length / n))
    fluct = 0.5 * e_star * np.fft.irfft(q * np.fft.rfft(h), n)
    p0 = 1.2 * float(-fluct.min())
    ds = solve_contact(h, [p0], tol=1e-12, e_star=e_star, length=length, store_fields=True)
    check_solution(ds, h, tol=1e-12, e_star=e_star, length=length)
    np.testing.assert_allclose(ds["contact_pressure"].values[0], p0 + fluct, rtol=0, atol=1e-9 * p0)


def test_hertz_cylinder_on_the_free_half_space():
    n, length, radius = 2048, 1.0, 2.0
    x = (np.arange(n) + 0.5) / n * length - 0.5 * length
    h = -x**2 / (2 * radius)
    p0 = 1e-4
    ds = solve_contact(h, [p0], boundary="free", tol=1e-10, store_fields=True)
    load = p0 * length  # P' per unit length (E* = 1)
    a = math.sqrt(4 * load * radius / math.pi)
    assert bool(ds["converged"][0])
    assert abs(float(ds["area_fraction"][0]) * length - 2 * a) <= 2 * length / n  # one pixel at each end
    p = ds["contact_pressure"].values[0]
    p_max = 2 * load / (math.pi * a)
    assert abs(p.max() - p_max) <= 0.01 * p_max
    inside = np.abs(x) < a - 3 * length / n
    exact = 2 * load / (math.pi * a**2) * np.sqrt(a**2 - x[inside] ** 2)
    assert np.abs(p[inside] - exact).max() <= 0.03 * p_max


def test_free_profile_invariants_against_a_direct_sum():
    """A rough free profile: the gap against the strip's influence summed directly (n = 256)."""
    h = rough_profile(256, 2, 32, 0.8, 3)
    tol = 1e-10
    ds = solve_contact(h, [0.002, 0.01], boundary="free", tol=tol, store_fields=True)
    check_solution(ds, h, tol=tol, boundary="free")


@pytest.mark.parametrize("method", ["pk", "pk-fourier", "pk-fourier-f32"])
def test_methods_agree_on_a_rough_profile(method):
    h = rough_profile(1024, 4, 128, 0.6, 2)
    loads = np.linspace(0.0005, 0.005, 6)
    ds = solve_contact(h, loads, tol=1e-10, method=method, store_fields=[6])
    check_solution(ds, h, tol=1e-10)
    ref = solve_contact(h, loads, tol=1e-10, method="pk")
    np.testing.assert_array_equal(ds["area_fraction"].values, ref["area_fraction"].values)


def test_plasticity_cap_on_a_profile():
    h = rough_profile(512, 4, 64, 0.8, 0)
    hardness = 0.02
    loads = [0.002, 0.006]
    ds = solve_contact(h, loads, tol=1e-10, hardness=hardness, store_fields=True)
    check_solution(ds, h, tol=1e-10, hardness=hardness)
    assert float(ds["plastic_area_fraction"][-1]) > 0  # the cap is really active
    step = solve_step(h, 0.006, tol=1e-10, hardness=hardness)
    assert step.pressure.shape == (512,) and step.gap.shape == (512,)
    assert step.pressure.max() <= hardness and step.converged


def _tamaas():
    tm = pytest.importorskip("tamaas", reason="tamaas is not installed: peer comparison skipped")
    tm.set_log_level(tm.LogLevel.error)
    return tm


@pytest.mark.peer
@pytest.mark.parametrize("seed", [0, 1])
def test_tamaas_basic_1d_rough_profiles(seed):
    """A/A0 node for node against Tamaas' PolonskyKeerRey on ``basic_1d`` (the same discrete problem)."""
    tm = _tamaas()
    n = 2048
    h = rough_profile(n, 4, 256, 0.7, seed)
    loads = np.linspace(0.0004, 0.004, 8)
    tol = 1e-10
    ds = solve_contact(h, loads, tol=tol)
    check_solution(ds, h, tol=tol)
    model = tm.ModelFactory.createModel(tm.model_type.basic_1d, [1.0], [n])
    model.E, model.nu = 1.0, 0.0  # E* = 1
    solver = tm.PolonskyKeerRey(model, h, 1e-12, tm.PolonskyKeerRey.pressure, tm.PolonskyKeerRey.pressure)
    nodes = []
    for p0 in loads:
        solver.solve(float(p0))
        traction = np.asarray(model.traction).ravel()
        assert traction.mean() == pytest.approx(p0, rel=1e-10)
        nodes.append(np.count_nonzero(traction > 0))
    np.testing.assert_array_equal(np.rint(ds["area_fraction"].values * n), nodes)


@pytest.mark.peer
def test_tamaas_kato_saturated_basic_1d_cap():
    """With a hardness: A/A0 and the plastic nodes equal Tamaas' KatoSaturated on ``basic_1d`` node for node."""
    tm = _tamaas()
    n, hardness = 1024, 0.02
    h = rough_profile(n, 4, 128, 0.8, 0)
    loads = [0.002, 0.006]
    ds = solve_contact(h, loads, tol=1e-10, hardness=hardness)
    model = tm.ModelFactory.createModel(tm.model_type.basic_1d, [1.0], [n])
    model.E, model.nu = 1.0, 0.0
    solver = tm.KatoSaturated(model, h, 1e-12, hardness)
    for k, p0 in enumerate(loads):
        solver.solve(p0)
        traction = np.asarray(model.traction).ravel()
        assert round(float(ds["area_fraction"][k]) * n) == np.count_nonzero(traction > 0)
        assert round(float(ds["plastic_area_fraction"][k]) * n) == np.count_nonzero(traction >= hardness * (1 - 1e-12))


@pytest.mark.parametrize(("heights", "options", "match"), [
    (np.zeros(3), {}, "at least 4 points"),
    (np.array([0.0, 1.0, np.nan, 0.0, 1.0]), {}, "finite"),
    (np.cos(np.arange(16)), {"length": (1.0, 1.0)}, "a profile .* has one length L"),
    (np.cos(np.arange(16)), {"effects": (Adhesion("exponential", 1e-4, 1e-2),)}, "maps .* only"),
])
def test_profile_refusals(heights, options, match):
    with pytest.raises(ValueError, match=match):
        solve_contact(heights, [1e-3], **options)


def test_cluster_observer_is_refused_for_a_profile():
    with pytest.raises(ValueError, match="ClusterObserver is a map's statistic"):
        solve_contact(np.cos(np.arange(64) / 5), [1e-3], observers=[ClusterObserver(1.0)])
