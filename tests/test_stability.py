"""Property-based stability suite over the parameter space a config can express.

Hypothesis draws surfaces (N 16..N_MAX odd and even, 0.01 < H < 0.99, k_l < k_s <= N/2,
rms slope 1e-3..1), loads from a single contact node to past full contact, and
tolerances 1e-3..1e-12, and asserts the invariants of tests/solver_invariants.py on every
solve: p >= 0, mean p = p0, gap >= -tol*s on the contact set, complementarity on it, A/A0
non-decreasing and in (0, 1], everything finite, and converged or an honest converged=False
with its residual.

``test_capped_invariants_hold_everywhere`` does the same with a hardness in [1e-3, 1e-1] E*
and loads from 1e-4 of it to the fully plastic limit (within 1e-9), with the cap's own
invariants (p <= hardness, gap <= tol*s at the cap) and requires every step to converge.

Profiles: ``ci`` (default, few small examples so CI stays fast) and ``long``
(``HYPOTHESIS_PROFILE=long pytest tests/test_stability.py``) for a by-hand soak.
Failing examples hypothesis finds are to be pinned below with ``@example`` as regression
tests; none so far (the long profile, 500 examples up to N = 512, passed on 2026-11-21; the
capped test, 400 random examples up to N = 128, and the elastic one with the complementarity
check, 250 examples, passed on 2026-11-22).
"""
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from roughcontact import generate_surface
from roughcontact.solver import solve_contact
from roughcontact.solver.halfspace import elastic_kernel
from roughcontact.surfaces.synthetic import spectral_moments
from solver_invariants import check_solution

settings.register_profile("ci", max_examples=20, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("long", max_examples=500, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
N_MAX = 128 if os.environ.get("HYPOTHESIS_PROFILE", "ci") == "ci" else 512


def full_contact_pressure(h: np.ndarray, e_star: float = 1.0, length: float = 1.0) -> float:
    """Smallest p0 giving full contact: p = p0 + K^-1 (h - mean h) must stay >= 0."""
    n = h.shape[0]
    kernel = elastic_kernel(n, e_star, length)
    with np.errstate(divide="ignore"):
        inv = np.where(kernel > 0, 1.0 / np.where(kernel > 0, kernel, 1.0), 0.0)
    extra = np.fft.irfft2(np.fft.rfft2(h) * inv, s=h.shape)
    return float(max(-extra.min(), 0.0))


@st.composite
def cases(draw):
    n = draw(st.integers(16, N_MAX))
    k_s = draw(st.integers(2, n // 2))
    k_l = draw(st.integers(1, k_s - 1))
    hurst = draw(st.floats(0.01, 0.99))
    slope = 10 ** draw(st.floats(-3, 0))
    seed = draw(st.integers(0, 2**31 - 1))
    tol = 10 ** draw(st.floats(-12, -3))
    # loads as fractions of the full-contact pressure, log-uniform from 1e-6 to 2
    fracs = sorted(10 ** np.array(draw(st.lists(st.floats(-6, np.log10(2.0)), min_size=1, max_size=4))))
    return n, k_l, k_s, hurst, slope, seed, tol, fracs


@given(cases())
def test_invariants_hold_everywhere(case):
    n, k_l, k_s, hurst, slope, seed, tol, fracs = case
    h = generate_surface(n, k_l, k_s, hurst, seed, rms_slope=slope)
    assert np.all(np.isfinite(h))
    assert spectral_moments(h)["rms_slope"] == pytest.approx(slope, rel=1e-6)
    assert abs(h.mean()) <= 1e-12 * np.abs(h).max()
    p_full = full_contact_pressure(h)
    pressures = [f * p_full for f in fracs]
    ds = solve_contact(h, pressures, tol=tol, max_iter=2000, store_fields=True)
    check_solution(ds, h, tol=tol, require_converged=False)
    area = ds.area_fraction.values
    assert np.all((area > 0) & (area <= 1))
    for i, f in enumerate(fracs):
        if f >= 1.0 + 1e-6 and bool(ds.converged.values[i]):
            assert area[i] == 1.0, "past the full-contact pressure every node is in contact"
    unconverged = ~ds.converged.values
    assert np.all(np.isfinite(ds.residual.values[unconverged]))


@st.composite
def capped_cases(draw):
    n = draw(st.integers(16, N_MAX))
    k_s = draw(st.integers(2, n // 2))
    k_l = draw(st.integers(1, k_s - 1))
    hurst = draw(st.floats(0.01, 0.99))
    slope = 10 ** draw(st.floats(-2, 0))
    seed = draw(st.integers(0, 2**31 - 1))
    tol = 10 ** draw(st.floats(-12, -4))
    hardness = 10 ** draw(st.floats(-3, -1))
    # loads as fractions of the hardness, log-uniform from 1e-4 to the plastic limit
    # (1 - 1e-9), the last one often close to it
    fracs = 10 ** np.array(draw(st.lists(st.floats(-4, 0), min_size=1, max_size=4)))
    fracs = np.minimum(fracs, 1 - 10 ** -draw(st.floats(1, 9)))
    return n, k_l, k_s, hurst, slope, seed, tol, hardness, sorted(fracs)


@settings(max_examples=max(60, settings().max_examples))  # cheap: mostly small grids
@given(capped_cases())
def test_capped_invariants_hold_everywhere(case):
    # Every converged step, elastic part and plastic part, satisfies the invariants
    # of solver_invariants.check_solution (mean p = p0, 0 <= p <= hardness, gap >= 0
    # below the cap, gap <= 0 at it, complementarity on 0 < p < hardness), recomputed
    # from the fields with an independent FFT; and every step converges.
    n, k_l, k_s, hurst, slope, seed, tol, hardness, fracs = case
    h = generate_surface(n, k_l, k_s, hurst, seed, rms_slope=slope)
    pressures = [f * hardness for f in fracs]
    ds = solve_contact(h, pressures, tol=tol, max_iter=3000, store_fields=True, hardness=hardness)
    check_solution(ds, h, tol=tol, hardness=hardness, require_converged=False)
    assert ds.converged.values.all(), f"unconverged steps, residuals {ds.residual.values}"
    p = ds.contact_pressure.values
    area = ds.area_fraction.values
    assert np.all(area >= np.array(pressures) / hardness * (1 - 1e-12))  # p <= H carries p0
    assert np.all(p.max(axis=(1, 2)) <= hardness)
