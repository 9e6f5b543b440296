"""Elastic iterations: the Fourier-preconditioned default against the plain Polonsky-Keer CG.

Same answers (the solution is unique; both pass the same final check), fewer
iterations, tight tolerances reachable with single-precision transforms.
"""
import numpy as np
import pytest

from roughcontact import solver as solver_mod
from roughcontact.core.fft import get_fft
from roughcontact.solver import solve_contact
from roughcontact.solver.workspace import ELASTIC_METHODS
from roughcontact.surfaces.synthetic import generate_surface
from solver_invariants import check_solution


@pytest.fixture
def method(solver_options):
    def set_method(name):
        solver_options(method=name)
    return set_method


@pytest.fixture(scope="module")
def surface():
    return generate_surface(128, 8, 32, 0.8, 0, rms_slope=0.1)


def _loads(p_max=0.005, steps=8):
    return np.linspace(p_max / steps, p_max, steps)


def test_default_is_the_preconditioned_single_precision_iteration(surface):
    # float32 transforms inside the loop, float64 gaps, reductions and final check;
    # "pk-fourier" is the same iteration in double precision, "pk" the reference.
    assert solver_mod.SolverSettings().method == "pk-fourier-f32"
    ds = solve_contact(surface, [0.001])
    assert ds.attrs["elastic_method"] == "pk-fourier-f32"


@pytest.mark.parametrize("name", ELASTIC_METHODS)
def test_every_method_solves_the_problem(surface, method, name):
    method(name)
    ds = solve_contact(surface, _loads(), tol=1e-10, store_fields=True)
    assert ds.attrs["elastic_method"] == name
    check_solution(ds, surface, tol=1e-10)


def test_methods_agree_and_preconditioning_cuts_iterations(surface, method):
    out = {}
    for name in ELASTIC_METHODS:
        method(name)
        out[name] = solve_contact(surface, _loads(), tol=1e-8, store_fields=True)
    ref = out["pk"]
    for ds in out.values():
        assert ds["converged"].values.all()
        np.testing.assert_allclose(ds["area_fraction"].values, ref["area_fraction"].values, rtol=1e-4)
        # same pressure field to the accuracy the tolerance implies
        dp = np.abs(ds["contact_pressure"].values - ref["contact_pressure"].values).max()
        assert dp <= 1e-4 * ref["contact_pressure"].values.max()
    n_pk = int(ref["iterations"].sum())
    for name in ("pk-fourier", "pk-fourier-f32"):
        n = int(out[name]["iterations"].sum())
        print(f"{name}: {n} iterations, pk: {n_pk}")
        assert n < 0.7 * n_pk


@pytest.mark.parametrize("tol", [1e-12, 1e-13])
def test_single_precision_reaches_tight_tolerances(surface, method, tol):
    method("pk-fourier-f32")
    ds = solve_contact(surface, _loads(steps=4), tol=tol, store_fields=True)
    check_solution(ds, surface, tol=tol)


def test_non_monotone_loads_fall_back_to_the_scaled_start(surface, method):
    method("pk-fourier-f32")
    loads = [0.001, 0.002, 0.0015, 0.004, 0.0045, 0.0001]
    ds = solve_contact(surface, loads, tol=1e-9, store_fields=True)
    check_solution(ds, surface, tol=1e-9)
    cold = [solver_mod.solve_step(surface, p0, tol=1e-9) for p0 in loads]
    np.testing.assert_allclose(ds["area_fraction"].values, [r.area_fraction for r in cold], rtol=1e-4)


def test_unknown_method_is_refused(surface):
    with pytest.raises(ValueError, match="method must be one of"):
        solve_contact(surface, [0.001], method="cg")
    with pytest.raises(ValueError, match="solver option method must be one of"):
        solver_mod.set_options(method="cg")
    with pytest.raises(TypeError, match="unknown solver option"):
        solver_mod.set_options(tol=1e-3)
    assert solver_mod.get_options() == {"method": "pk-fourier-f32", "array_backend": "numpy"}


def test_set_options_is_restored_after_its_block(surface):
    with solver_mod.set_options(method="pk"):
        assert solver_mod.SolverSettings().method == "pk"
        assert solve_contact(surface, [0.001]).attrs["elastic_method"] == "pk"
        made_inside = solver_mod.SolverSettings()
    assert solver_mod.SolverSettings().method == "pk-fourier-f32"
    assert made_inside.method == "pk"  # a settings object keeps the default it was made with


@pytest.mark.parametrize("backend", ["numpy", "pyfftw"])
def test_single_precision_fft_pair(backend):
    if backend == "pyfftw":
        pytest.importorskip("pyfftw")
    n = 64
    a = np.random.default_rng(0).standard_normal((n, n))
    f32 = get_fft((n, n), backend=backend, dtype=np.float32)
    f64 = get_fft((n, n), backend=backend)
    assert f32 is not f64 and f64 is get_fft((n, n), backend=backend, dtype="float64")
    assert f32 is get_fft((n, n), backend=backend, dtype=np.float32)
    spec = f32.forward(a)
    assert spec.dtype == np.complex64
    back = f32.backward(spec)
    assert back.dtype == np.float32
    np.testing.assert_allclose(back, a, atol=1e-5 * np.abs(a).max())
    # deterministic: the same input gives the same bits
    again = f32.backward(f32.forward(a)).copy()
    np.testing.assert_array_equal(again, f32.backward(f32.forward(a)))


@pytest.mark.parametrize(("hardness", "max_ratio"), [(0.02, 0.95), (1.0, 0.7)])
def test_capped_solves_use_the_preconditioner_too(surface, method, hardness, max_ratio):
    # The plasticity cap acts on the same preconditioned CG (on the face 0 < p < H):
    # same solution as the plain bounded iteration, fewer iterations (measured at
    # N = 128: 187 -> 166 with 23 % of the nodes capped, 284 -> 170 with none).
    out = {}
    for name in ("pk", "pk-fourier-f32"):
        method(name)
        out[name] = solve_contact(surface, _loads(), tol=1e-9, store_fields=True, hardness=hardness)
        check_solution(out[name], surface, tol=1e-9, hardness=hardness)
    ref, new = out["pk"], out["pk-fourier-f32"]
    np.testing.assert_allclose(new["area_fraction"].values, ref["area_fraction"].values, rtol=1e-4)
    np.testing.assert_allclose(new["plastic_area_fraction"].values, ref["plastic_area_fraction"].values,
                               atol=1e-4)
    n_ref, n_new = int(ref["iterations"].sum()), int(new["iterations"].sum())
    print(f"hardness {hardness}: pk {n_ref}, pk-fourier-f32 {n_new} iterations")
    assert n_new < max_ratio * n_ref


def test_progress_reports_every_step_as_it_goes(surface):
    seen = []
    ds = solve_contact(surface, _loads(steps=4), progress=lambda *args: seen.append(args))
    assert [s[0] for s in seen] == [1, 2, 3, 4]
    np.testing.assert_array_equal([s[2] for s in seen], ds["area_fraction"].values)
    np.testing.assert_array_equal([s[3] for s in seen], ds["iterations"].values)
    assert all(s[4] for s in seen) and all(s[5] > 0 for s in seen)
    with pytest.raises(ValueError, match="progress must be a callable"):
        solve_contact(surface, [0.001], progress="yes")
