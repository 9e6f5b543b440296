"""Solver robustness: awkward surfaces and grids, input validation, stalls, warm start.

Every solve either converges or says ``converged=False`` with finite outputs;
:func:`solver_invariants.check_solution` runs on each of them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from roughcontact import solver as solver_mod
from roughcontact.solver import contact_perimeter, solve_contact, solve_step, step_notes
from roughcontact.solver.results import FRACTION_UNITS
from roughcontact.solver.settings import DEFAULT_MAX_ITER
from roughcontact.solver.workspace import FALLBACKS, SOLVER_PATHS, STALL_WINDOW
from roughcontact.surfaces.synthetic import generate_surface
from solver_invariants import check_solution

TOL = 1e-10


def _loads(p_max, n_steps=5):
    return np.linspace(p_max / n_steps, p_max, n_steps)


def test_first_contact_single_node():
    # A load so small that the crest node alone carries it: the conjugate
    # direction on a single free node is null, only the active set can move.
    n = 64
    h = generate_surface(n, 8, 32, 0.8, 0, rms_slope=0.1)
    loads = [1e-12, 1e-10]
    ds = solve_contact(h, loads, tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)
    p = ds["contact_pressure"].values[0]
    assert np.count_nonzero(p) == 1
    assert np.unravel_index(np.argmax(p), p.shape) == np.unravel_index(np.argmax(h), h.shape)


@pytest.mark.parametrize("hurst", [0.05, 0.95])
def test_extreme_hurst(hurst):
    n = 128
    h = generate_surface(n, 8, 32, hurst, 0, rms_slope=0.1)
    ds = solve_contact(h, _loads(0.005), tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)


def test_short_cutoff_at_nyquist():
    n = 128
    h = generate_surface(n, 8, n // 2, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, _loads(0.005), tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)


def test_flat_surface_uniform_pressure():
    n = 32
    h = np.zeros((n, n))
    ds = solve_contact(h, [0.01, 0.02], tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)
    assert np.all(ds["area_fraction"].values == 1.0)
    np.testing.assert_allclose(ds["contact_pressure"].values[1], 0.02, rtol=1e-14)
    assert np.all(ds["contact_perimeter"].values == 0.0)
    np.testing.assert_allclose(ds["mean_gap"].values, 0.0, atol=1e-15)


def test_constant_offset_surface_is_flat():
    # A constant height is a rigid shift: same pressure as the flat case.
    n = 16
    ds = solve_contact(np.full((n, n), 3.0), [0.01], tol=TOL, store_fields=True)
    np.testing.assert_allclose(ds["contact_pressure"].values[0], 0.01, rtol=1e-14)


def test_two_dimensional_sinusoid_past_full_contact():
    # h = D cos(2 pi x/L) cos(2 pi y/L): full contact needs p0 >= the amplitude
    # of the single-mode pressure, p* = E* q D / 2 with q = 2 pi sqrt(2) / L.
    n = 64
    x = np.arange(n) / n
    delta = 0.01
    h = delta * np.cos(2 * np.pi * x)[:, None] * np.cos(2 * np.pi * x)[None, :]
    p_star = np.pi * np.sqrt(2) * delta
    loads = np.array([0.2, 0.6, 1.0 - 1e-3, 1.3, 2.0]) * p_star
    ds = solve_contact(h, loads, tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)
    assert ds["area_fraction"].values[-1] == 1.0
    exact = loads[-1] + p_star * h / delta
    np.testing.assert_allclose(ds["contact_pressure"].values[-1], exact, atol=1e-8 * loads[-1])


def test_rms_slope_one():
    n = 128
    h = generate_surface(n, 8, 32, 0.8, 0, rms_slope=1.0)
    ds = solve_contact(h, _loads(0.05), tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)


@pytest.mark.parametrize("n", [63, 96, 100])
def test_odd_and_non_power_of_two_grids(n):
    h = generate_surface(n, 4, 16, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, _loads(0.005), tol=TOL, store_fields=True, length=2.5, e_star=3.0)
    check_solution(ds, h, tol=TOL, length=2.5, e_star=3.0)


def test_max_iter_reached_is_reported_not_raised():
    h = generate_surface(64, 8, 32, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, _loads(0.005, 3), tol=TOL, max_iter=1, store_fields=True)
    check_solution(ds, h, tol=TOL, require_converged=False, area_slack_nodes=64 * 64)
    assert not ds["converged"].values.any()
    assert np.all(ds["iterations"].values == 1)


def test_unreachable_tolerance_stalls_cleanly():
    # 1e-16 is below the round-off floor of the gap (~1e-15 of the rms height):
    # the solver must give up by itself long before max_iter, once every fallback has stalled too
    # (each iteration stops 300 iterations after its last halving of the residual).
    h = generate_surface(64, 8, 32, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, [0.002, 0.004], tol=1e-16, store_fields=True)
    check_solution(ds, h, tol=1e-16, require_converged=False)
    assert not ds["converged"].values.any()
    stages = 1 + len(FALLBACKS[solver_mod.SolverSettings().method])
    assert np.all(ds["iterations"].values < stages * 3 * STALL_WINDOW) and DEFAULT_MAX_ITER > stages * 3 * STALL_WINDOW
    last = FALLBACKS[solver_mod.SolverSettings().method][-1]
    assert [SOLVER_PATHS[c] for c in ds["solver_path"].values] == [last] * 2
    assert np.all(ds["residual"].values < 1e-12)  # it got to the floor before stopping


def test_step_notes_say_why_a_step_did_not_converge():
    h = generate_surface(64, 8, 32, 0.8, 0, rms_slope=0.1)
    assert step_notes(solve_contact(h, [0.002, 0.004], tol=TOL)) == []
    capped = step_notes(solve_contact(h, [0.002], tol=TOL, max_iter=1))
    assert len(capped) == 1 and capped[0].startswith("step 1: NOT converged (max_iter = 1 reached; residual ")
    stalled = step_notes(solve_contact(h, [0.002], tol=1e-16))
    assert len(stalled) == 1 and f"stalled, last on {FALLBACKS[solver_mod.SolverSettings().method][-1]}" in stalled[0]


def test_tight_tolerance_reachable():
    h = generate_surface(128, 16, 32, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, _loads(0.005, 3), tol=1e-13, store_fields=True)
    check_solution(ds, h, tol=1e-13)


def test_decreasing_loads_are_accepted():
    h = generate_surface(64, 8, 32, 0.8, 0, rms_slope=0.1)
    loads = [0.004, 0.001, 0.003]
    ds = solve_contact(h, loads, tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)
    ref = solve_step(h, 0.001, tol=TOL)
    assert float(ds["area_fraction"][1]) == ref.area_fraction


def test_warm_start_reduces_iterations():
    h = generate_surface(128, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = _loads(0.005, 10)
    warm = solve_contact(h, loads, tol=TOL)
    cold = [solve_step(h, p0, tol=TOL) for p0 in loads]
    n_warm = int(warm["iterations"].sum())
    n_cold = sum(r.iterations for r in cold)
    print(f"iterations warm {n_warm}, cold {n_cold}, ratio {n_warm / n_cold:.2f}")
    assert n_warm < n_cold
    np.testing.assert_array_equal(warm["area_fraction"].values, [r.area_fraction for r in cold])


def test_dataset_layout_and_units():
    n = 32
    h = generate_surface(n, 2, 8, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, [0.001, 0.002, 0.003], tol=TOL)
    assert isinstance(ds, xr.Dataset)
    assert list(ds["step"].values) == [1, 2, 3]
    assert "contact_pressure" not in ds and "x" not in ds.coords
    assert ds["pressure"].attrs["units"] == ds["mean_contact_pressure"].attrs["units"] == "1"  # nondimensional
    assert ds["mean_gap"].attrs["units"] == ds["contact_perimeter"].attrs["units"] == "1"
    assert ds["area_fraction"].attrs["units"] == FRACTION_UNITS == "1"
    assert ds.attrs["pressure_units"] == ds.attrs["length_units"] == "1"
    um = solve_contact(h, [0.001, 0.002, 0.003], tol=TOL, length_unit="um", pressure_unit="MPa")
    assert um["pressure"].attrs["units"] == um["mean_contact_pressure"].attrs["units"] == "MPa"
    assert um["mean_gap"].attrs["units"] == "um" and um["contact_perimeter"].attrs["units"] == "um^-1"
    assert um["area_fraction"].attrs["units"] == "1"
    np.testing.assert_array_equal(um["area_fraction"].values, ds["area_fraction"].values)  # labels only
    assert ds["converged"].dtype == bool
    assert ds.attrs["n"] == n and ds.attrs["fft_backend"] in ("pyfftw", "numpy")

    full = solve_contact(h, [0.001, 0.002, 0.003], tol=TOL, store_fields=True, length=2.0)
    assert full["contact_pressure"].dims == ("step", "x", "y")
    np.testing.assert_allclose(full["x"].values, np.arange(n) * 2.0 / n)
    check_solution(full, h, tol=TOL, length=2.0)

    some = solve_contact(h, [0.001, 0.002, 0.003], tol=TOL, store_fields=[3, 1], length=2.0)
    assert some["contact_pressure"].dims == ("field_step", "x", "y")
    assert list(some["field_step"].values) == [1, 3]
    np.testing.assert_array_equal(some["contact_pressure"].sel(field_step=3).values,
                                  full["contact_pressure"].sel(step=3).values)
    check_solution(some, h, tol=TOL, length=2.0)


def test_netcdf_roundtrip(tmp_path):
    h = generate_surface(32, 2, 8, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, [0.001, 0.002], tol=TOL, store_fields=True, hardness=0.05)
    path = tmp_path / "solve.nc"
    ds.to_netcdf(path)
    back = xr.load_dataset(path)
    xr.testing.assert_identical(back, ds)


def test_perimeter_of_a_square_patch():
    # A k x k patch has 4k pixel edges on its boundary: P = 4 k dx / L^2.
    n, k, length = 20, 5, 2.0
    mask = np.zeros((n, n), dtype=bool)
    mask[3:3 + k, 18:] = True
    mask[3:3 + k, :k - 2] = True  # wraps across the periodic edge
    assert contact_perimeter(mask, length) == pytest.approx(4 * k * (length / n) / length**2)


# --------------------------------------------------------------------------- validation
GOOD = np.zeros((8, 8))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(heights=np.full((8, 8), np.nan)), "heights must contain only finite"),
        (dict(heights=np.zeros((8, 7))), "heights must be a 2-D square"),
        (dict(heights=np.zeros(3)), "heights: a profile \\(1-D heights\\) needs at least 4 points"),
        (dict(heights=np.zeros((2, 4, 4, 4))), "heights must be a 2-D square"),
        (dict(heights=np.zeros((8, 8), complex)), "heights must be real"),
        (dict(heights=[[1, 2], [3]]), "heights must be a real 2-D square array"),
        (dict(heights=np.zeros((2, 2))), "at least 4 x 4"),
        (dict(pressures=[0.01, -0.01]), "pressures must all be finite and > 0"),
        (dict(pressures=[0.0]), "pressures must all be finite and > 0"),
        (dict(pressures=[np.inf]), "pressures must all be finite and > 0"),
        (dict(pressures=[]), "pressures must be a non-empty 1-D"),
        (dict(pressures=[[0.1]]), "pressures must be a non-empty 1-D"),
        (dict(pressures="abc"), "pressures must be a 1-D sequence"),
        (dict(tol=0.0), r"tol must be a number in the open interval \(0, 1\)"),
        (dict(tol=1.0), r"tol must be a number in the open interval \(0, 1\)"),
        (dict(tol=np.nan), r"tol must be a number in the open interval \(0, 1\)"),
        (dict(max_iter=0), "max_iter must be an integer >= 1"),
        (dict(max_iter=2.5), "max_iter must be an integer >= 1"),
        (dict(e_star=0.0), "e_star must be a finite real number > 0"),
        (dict(length=-1.0), "length must be a finite real number > 0"),
        (dict(hardness=-1.0), "hardness must be a finite real number > 0"),
        (dict(hardness=0.005), "must be < hardness"),
        (dict(threads=0), "threads must be an integer >= 1"),
        (dict(store_fields=[0]), "store_fields must be a bool or an iterable of step numbers in 1..1"),
        (dict(store_fields="yes"), "store_fields must be a bool"),
        # strings and other wrong types: refused, naming the argument (not converted)
        (dict(heights="abc"), "heights must be a real numeric array, got the string 'abc'"),
        (dict(pressures=["0.01"]), "pressures must be a 1-D sequence of finite real numbers > 0"),
        (dict(pressures=[True]), "pressures must be a 1-D sequence of finite real numbers > 0"),
        (dict(pressures=[0.01 + 0j]), "pressures must be a 1-D sequence of finite real numbers > 0"),
        (dict(e_star="1"), "e_star must be a finite real number > 0, got str '1'"),
        (dict(length="1"), "length must be a finite real number > 0 .*, got str '1'"),
        (dict(tol="1e-8"), r"tol must be a number in the open interval \(0, 1\), got str '1e-8'"),
        (dict(hardness="0.1"), "hardness must be a finite real number > 0, got str '0.1'"),
        (dict(hardness=True), "hardness must be a finite real number > 0, got bool True"),
        (dict(max_iter="10"), "max_iter must be an integer >= 1"),
        # a load the cap cannot carry
        (dict(pressures=[0.001, 0.02], hardness=0.02),
         r"pressures: every p0 must be in the open interval \(0, hardness\) = \(0, 0.02\)"),
    ],
)
def test_input_validation(kwargs, match):
    args = dict(heights=GOOD, pressures=[0.01])
    args.update(kwargs)
    heights = args.pop("heights")
    pressures = args.pop("pressures")
    with pytest.raises(ValueError, match=match):
        solve_contact(heights, pressures, **args)


def test_clusters_are_an_observer_and_the_old_flag_says_so():
    # cluster statistics are one observer of the steps, not a path through the solver: the former
    # flag is refused with the way to ask for them
    with pytest.raises(TypeError, match=r"\[.clusters.\].*observers=\[roughcontact.statistics.clusters.Cluster"):
        solve_contact(GOOD, [0.01], clusters=True)


@pytest.mark.parametrize("p0", [0.0, -1.0, np.nan, "x", "0.01", True, [0.01]])
def test_solve_step_validates_p0(p0):
    with pytest.raises(ValueError, match="p0 must be a finite number > 0"):
        solve_step(GOOD, p0)


def test_solve_step_refuses_a_load_the_cap_cannot_carry():
    with pytest.raises(ValueError, match=r"p0: p0 must be in the open interval \(0, hardness\) = \(0, 0.01\)"):
        solve_step(GOOD, 0.01, hardness=0.01)
    with pytest.raises(ValueError, match=r"p0: p0 must be in the open interval \(0, hardness\)"):
        solve_step(ROUGH, 0.02, hardness=0.01)


# --------------------------------------------------------------------------- float64 range
ROUGH = generate_surface(32, 2, 8, 0.8, 0, rms_slope=0.1)  # rms height 4.4e-3
RANGE_MSG = r"every p0 \* length / \(e_star \* s\) must be in \[1e-100, 1e\+100\] with s = "


@pytest.mark.parametrize(
    ("scale", "kwargs", "match"),
    [
        # the rms of h * 1e200 overflowed (A/A0 = 1 "converged" after 0 iterations)
        (1e200, dict(pressures=[0.001]), "pressures: " + RANGE_MSG + "4.44049e[+]197"),
        (1e-200, dict(pressures=[0.001]), "pressures: " + RANGE_MSG),
        # a subnormal load gave a NaN residual
        (1.0, dict(pressures=[5e-324]), "pressures: " + RANGE_MSG + r".*got p0 = 5e-324"),
        (1.0, dict(pressures=[1e-3], e_star=1e300), "pressures: " + RANGE_MSG),
        (1.0, dict(pressures=[1e-3], e_star=1e-300, length=1e300), "pressures: " + RANGE_MSG),
        (1.0, dict(pressures=[1e305]), r"pressures: every p0 must be <= 1e\+300 / n\*\*2"),
        (1.0, dict(pressures=[1e-3], hardness=1e200),
         r"hardness: hardness \* length / \(e_star \* s\) must be in \[1e-100, 1e\+100\]"),
    ],
)
def test_loads_outside_the_float64_range_are_refused(scale, kwargs, match):
    pressures = kwargs.pop("pressures")
    with pytest.raises(ValueError, match=match):
        solve_contact(ROUGH * scale, pressures, **kwargs)


def test_solve_step_refuses_a_subnormal_load():
    with pytest.raises(ValueError, match="p0: p0 " + RANGE_MSG[len("every p0 "):]):
        solve_step(ROUGH, 5e-324)


@pytest.mark.parametrize("factor", [1e-150, 1e150])
@pytest.mark.parametrize("hardness", [None, 0.02])
def test_extreme_but_representable_scales_are_exact(solver_options, factor, hardness, monkeypatch):
    # Inside the range the solution scales exactly: heights and pressures by one
    # factor (same dimensionless load), or heights by it and E* by its inverse.
    # The unit handling is checked with the double-precision iteration, whose
    # path does not depend on the round-off of the rescaled input; the default's
    # float32 products do (test_default_iteration_scales_to_its_tolerance).
    solver_options(method="pk-fourier")
    loads = [0.001, 0.01]
    ref = solve_contact(ROUGH, loads, tol=TOL, store_fields=True, hardness=hardness)
    big = solve_contact(ROUGH * factor, [p * factor for p in loads], tol=TOL, store_fields=True,
                        hardness=None if hardness is None else hardness * factor)
    check_solution(big, ROUGH * factor, tol=TOL, hardness=None if hardness is None else hardness * factor)
    np.testing.assert_array_equal(big["area_fraction"].values, ref["area_fraction"].values)
    np.testing.assert_allclose(big["contact_pressure"].values / factor, ref["contact_pressure"].values,
                               rtol=0, atol=1e-12)
    soft = solve_contact(ROUGH * factor, loads, tol=TOL, store_fields=True, e_star=1 / factor,
                         hardness=hardness)
    np.testing.assert_array_equal(soft["area_fraction"].values, ref["area_fraction"].values)
    np.testing.assert_allclose(soft["gap"].values / factor, ref["gap"].values, rtol=0, atol=1e-15)


@pytest.mark.parametrize("factor", [1e-150, 3.0, 1e150])
def test_default_iteration_scales_to_its_tolerance(factor):
    # float32 rounding of the small late directions is not a smooth function of
    # the input, so a rescaled problem ends at a solution that differs by what
    # the tolerance allows, not by round-off: same contact set, and pressures
    # and gaps within the accuracy tol implies.
    loads = [0.001, 0.01]
    ref = solve_contact(ROUGH, loads, tol=TOL, store_fields=True)
    soft = solve_contact(ROUGH * factor, loads, tol=TOL, store_fields=True, e_star=1 / factor)
    check_solution(soft, ROUGH * factor, tol=TOL, e_star=1 / factor)
    np.testing.assert_array_equal(soft["area_fraction"].values, ref["area_fraction"].values)
    s = float(ROUGH.std())
    np.testing.assert_allclose(soft["gap"].values / factor, ref["gap"].values, rtol=0, atol=100 * TOL * s)
    np.testing.assert_allclose(soft["contact_pressure"].values, ref["contact_pressure"].values, rtol=0,
                               atol=100 * TOL * ref["contact_pressure"].values.max())


def test_flat_surface_any_load_is_exact():
    # Flat surfaces have the exact solution p = p0, g = 0 for any representable p0.
    ds = solve_contact(np.zeros((8, 8)), [5e-324, 1e-3, 1e296], store_fields=True, hardness=1e297)
    assert ds["converged"].values.all()
    assert np.all(ds["contact_pressure"].values == np.array([5e-324, 1e-3, 1e296])[:, None, None])
    assert np.all(ds["gap"].values == 0) and np.all(ds["iterations"].values == 0)


def test_displacement_overflow_is_refused():
    from roughcontact.solver.halfspace import displacement

    p = np.zeros((8, 8))
    p[0, 0] = 1e300
    with pytest.raises(ValueError, match="displacement: u = K p overflows float64"):
        displacement(p, e_star=1e-300)
    np.testing.assert_allclose(displacement(p * 1e-300, e_star=1e-300) * 1e-300, displacement(p * 1e-300),
                               rtol=1e-12)


def test_solve_step_initial_pressure_shape():
    with pytest.raises(ValueError, match="initial_pressure must have shape"):
        solve_step(GOOD, 0.01, initial_pressure=np.ones((4, 4)))


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("target_fraction", [0.05, 0.3, 0.7])
def test_enforce_mean_under_cap(seed, target_fraction):
    # The projection's mean restoration with a cap: any admissible target is
    # hit exactly and the bounds hold, including when the capped nodes alone
    # would carry more than the target (the exact beta-scaling branch).
    from roughcontact.solver.projection import enforce_mean as _enforce_mean

    rng = np.random.default_rng(seed)
    cap = 1.0
    P = np.where(rng.random((16, 16)) < 0.5, rng.random((16, 16)) * 3 * cap, 0.0)
    np.minimum(P, cap, out=P)
    target = target_fraction * cap * P.size
    _enforce_mean(P, target, cap)
    assert P.min() >= 0 and P.max() <= cap
    assert P.sum() == pytest.approx(target, rel=1e-12)


# --------------------------------------------------------------------------- fallback after a stall
MEASURED = Path(__file__).resolve().parent / "data" / "surfacetopography"
MEASURED_TOL = 1e-8  # the scene's tol


@pytest.mark.slow
def test_a_stalled_step_on_a_measured_surface_converges_on_a_fallback():
    # SurfaceTopography's mi-1.mi (AFM, 256^2, 20 um), as the `measured` scene reads it, on the free
    # half-space at E* = 1e5 MPa to p0/E* = 0.005 in 30 steps: the single-precision iteration stalled
    # at residuals near 1.5e-5 on steps 27 and 30 (2026-11-25, AVX-512, before the fallback: 2 of 30
    # steps unconverged); float64 products converge them. Every step must satisfy the invariants, and the
    # last equals ContactMechanics' free-boundary CG (A/A0 to 1e-4 relative, the issue's bound).
    from roughcontact.surfaces.topography import read_topography

    surface = read_topography(MEASURED / "mi-1.mi", unit="um", undefined="harmonic", detrend="height")
    h, length = surface.heights, surface.length
    loads = [500.0 * (k + 1) / 30 for k in range(30)]
    ds = solve_contact(h, loads, e_star=1e5, length=length, tol=MEASURED_TOL, boundary="free", store_fields=True)
    check_solution(ds, h, tol=MEASURED_TOL, e_star=1e5, length=length, boundary="free")
    # whether a step stalls at all depends on the CPU's rounding (here with AVX-512: step 27; with
    # numpy's AVX-512 paths disabled: none), so the fallback itself is tested on a forced stall below
    paths = [SOLVER_PATHS[c] for c in ds["solver_path"].values]
    assert set(paths) <= {solver_mod.SolverSettings().method, *FALLBACKS[solver_mod.SolverSettings().method]}
    a_cm = _contact_mechanics_free_area(h, length, loads[-1])
    assert a_cm is not None and abs(float(ds["area_fraction"][-1]) - a_cm) <= 1e-4 * a_cm


def _contact_mechanics_free_area(h, length, p0, maxiter=10000):
    """A/A0 of ContactMechanics' free-boundary CG (tolerances as the scene's tol), or None if it fails."""
    cm = pytest.importorskip("ContactMechanics", reason="ContactMechanics is not installed: peer skipped")
    from ContactMechanics.Optimization import constrained_conjugate_gradients

    n = h.shape[0]
    res = constrained_conjugate_gradients(cm.FreeFFTElasticHalfSpace((n, n), 1e5, physical_sizes=(length, length)), h,
                                          external_force=p0 * length**2, pentol=MEASURED_TOL * float(np.std(h)),
                                          forcetol=MEASURED_TOL * p0 * (length / n) ** 2, maxiter=maxiter)
    if not res.success:
        return None
    return np.count_nonzero(np.abs(np.asarray(res.jac)[:n, :n]) > 0) / n**2


@pytest.mark.slow
def test_spikes_on_a_plateau_converge_without_a_stall():
    # SurfaceTopography's frt-2.frt (150 x 300, 27 % undefined, cropped to 150^2 as the measured scene
    # does): the harmonic fill is a wide flat plateau, with three isolated one-node spikes 12 rms high
    # standing on it. At the first load the preconditioned iterations used to cycle far from the
    # answer (A/A0 0.34 where the answer is 15 nodes; ContactMechanics' CG fails there too) until the
    # stall guard handed the step to the gradient projection; since issue 29 (Fletcher-Reeves' beta
    # after a projection that empties a large part of F, elastic.FR_AFTER_LOSS) the default iteration
    # converges it in ~16 iterations. The reference at those steps is the solution's own certificate:
    # the problem is a strictly convex QP, so a pressure meeting every KKT condition to tol
    # (check_solution, with the gap summed directly) is its solution; where ContactMechanics converges
    # (the last step) A/A0 agrees to 1e-4 relative (the bound).
    surface, loads = _frt2()
    h, length = surface.heights, surface.length
    ds = solve_contact(h, loads, e_star=1e5, length=length, tol=MEASURED_TOL, boundary="free", store_fields=True)
    check_solution(ds, h, tol=MEASURED_TOL, e_star=1e5, length=length, boundary="free")
    assert {SOLVER_PATHS[c] for c in ds["solver_path"].values} == {solver_mod.SolverSettings().method}
    assert int(ds["iterations"].max()) < STALL_WINDOW // 2
    assert 0 < float(ds["area_fraction"][0]) < 1e-3  # the spikes alone carry the first load
    a_cm = _contact_mechanics_free_area(h, length, loads[-1])
    assert a_cm is not None and abs(float(ds["area_fraction"][-1]) - a_cm) <= 1e-4 * a_cm


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_spikes_on_a_plateau_converge_on_the_gradient_projection_after_pk(solver_options, monkeypatch):
    # Unpreconditioned, Polonsky & Keer's active-set rule cycles on frt-2's first loads (residual
    # 8.8 / 4.1 / 1.4 at steps 1-3, 2026-11-25): the monotone gradient projection ("box" with an
    # unreachable cap) converges in ~10 iterations after the stall window, and steps 2-5 start on it.
    solver_options(method="pk")
    surface, loads = _frt2()
    h, length = surface.heights, surface.length
    ds = solve_contact(h, loads[:5], e_star=1e5, length=length, tol=MEASURED_TOL, boundary="free",
                       store_fields=True)
    check_solution(ds, h, tol=MEASURED_TOL, e_star=1e5, length=length, boundary="free")
    assert {SOLVER_PATHS[c] for c in ds["solver_path"].values} == {"box"}
    assert int(ds["iterations"][0]) < 2 * STALL_WINDOW


def _frt2():
    """frt-2.frt as the measured scene reads it, and that scene's 30 loads [Pa]."""
    from roughcontact.surfaces.topography import read_topography

    surface = read_topography(MEASURED / "frt-2.frt", unit="um", undefined="harmonic", detrend="height",
                              non_square="crop")
    return surface, [500.0 * (k + 1) / 30 for k in range(30)]


def test_a_forced_stall_is_finished_by_the_next_iteration(monkeypatch):
    # The first iteration of the chain is cut short (3 iterations, unconverged: what a stall
    # returns); the next one in FALLBACKS takes its pressure and converges the step, every invariant
    # holds, solver_path names it and the iterations count both.
    from roughcontact.solver import steps

    real = steps.pk_solve
    first = solver_mod.SolverSettings().method

    def stalling(ws, p0, tol, max_iter, fresh):
        if ws.method == first:
            return real(ws, p0, 1e-300, 3, fresh)[0], False
        return real(ws, p0, tol, max_iter, fresh)

    monkeypatch.setattr(steps, "pk_solve", stalling)
    h = generate_surface(64, 8, 32, 0.8, 0, rms_slope=0.1)
    ds = solve_contact(h, _loads(0.005, 3), tol=TOL, store_fields=True)
    check_solution(ds, h, tol=TOL)
    assert [SOLVER_PATHS[c] for c in ds["solver_path"].values] == [FALLBACKS[first][0]] * 3
    assert np.all(ds["iterations"].values > 3)
    assert all("converged by the fallback" in note for note in step_notes(ds)) and len(step_notes(ds)) == 3
