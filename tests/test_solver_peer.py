"""Agreement with independent solvers: Tamaas (C++) and ContactMechanics (Python).

All three solve the same discrete problem (same kernel 2/(E*|q|), same nodal
collocation, highest points of ``h`` touch first), so at tight tolerances the
contact sets agree node for node; the tests allow 1e-4 relative on A/A0 for
the elastic case and 1e-3 with a hardness, as the spec asks.
"""

from __future__ import annotations

import numpy as np
import pytest

from roughcontact.solver import solve_contact
from roughcontact.surface import generate_surface
from solver_invariants import check_solution

pytestmark = pytest.mark.peer

PAPER = dict(k_l=16, k_s=32, hurst=0.8, seed=0, rms_slope=0.1)


def _tamaas():
    tm = pytest.importorskip("tamaas", reason="tamaas is not installed: peer comparison skipped")
    tm.set_log_level(tm.LogLevel.error)
    return tm


def _tamaas_model(tm, n):
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [1.0, 1.0], [n, n])
    model.E = 1.0
    model.nu = 0.0  # E* = E / (1 - nu^2) = 1
    return model


@pytest.mark.slow
def test_tamaas_polonsky_keer_rey_paper_case():
    tm = _tamaas()
    n = 256
    h = generate_surface(n, PAPER["k_l"], PAPER["k_s"], PAPER["hurst"], PAPER["seed"],
                         rms_slope=PAPER["rms_slope"])
    loads = np.linspace(0.005 / 30, 0.005, 30)
    tol = 1e-10
    ds = solve_contact(h, loads, tol=tol)
    check_solution(ds, h, tol=tol)

    model = _tamaas_model(tm, n)
    solver = tm.PolonskyKeerRey(model, h, 1e-12, tm.PolonskyKeerRey.pressure,
                                tm.PolonskyKeerRey.pressure)
    area_tm = []
    for p0 in loads:
        solver.solve(float(p0))
        traction = np.asarray(model.traction)
        assert traction.mean() == pytest.approx(p0, rel=1e-10)
        area_tm.append(np.count_nonzero(traction > 0) / n**2)
    area_tm = np.array(area_tm)
    rel = np.abs(ds["area_fraction"].values - area_tm) / area_tm
    print(f"max relative A/A0 difference vs Tamaas PKR: {rel.max():.2e}")
    assert rel.max() <= 1e-4


def test_tamaas_kato_saturated_hardness():
    tm = _tamaas()
    n = 64
    hardness = 0.08
    h = generate_surface(n, 8, 32, 0.8, 0, rms_slope=0.1)
    loads = [0.002, 0.005]
    tol = 1e-10
    ds = solve_contact(h, loads, tol=tol, hardness=hardness, store_fields=True)
    check_solution(ds, h, tol=tol, hardness=hardness)
    assert ds["plastic_area_fraction"].values[-1] > 0  # the cap is really active

    model = _tamaas_model(tm, n)
    for k, p0 in enumerate(loads):
        solver = tm.KatoSaturated(model, h, 1e-12, hardness)
        solver.solve(p0)
        traction = np.asarray(model.traction)
        a_tm = np.count_nonzero(traction > 0) / n**2
        plastic_tm = np.count_nonzero(traction >= hardness * (1 - 1e-9)) / n**2
        a = float(ds["area_fraction"][k])
        print(f"p0={p0}: A/A0 {a:.6f} vs Tamaas {a_tm:.6f}; plastic {float(ds.plastic_area_fraction[k]):.6f} "
              f"vs {plastic_tm:.6f}")
        assert abs(a - a_tm) <= 1e-3 * a_tm
        assert abs(float(ds["plastic_area_fraction"][k]) - plastic_tm) <= 1e-3 * a_tm


def _contact_mechanics():
    cm = pytest.importorskip("ContactMechanics",
                             reason="ContactMechanics is not installed: peer comparison skipped")
    from ContactMechanics.Optimization import constrained_conjugate_gradients

    return cm.PeriodicFFTElasticHalfSpace, constrained_conjugate_gradients


@pytest.mark.parametrize("hardness", [None, 0.08])
def test_contact_mechanics_polonsky_keer(hardness):
    halfspace, ccg = _contact_mechanics()
    n = 128
    h = generate_surface(n, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = [0.002, 0.005]
    tol = 1e-10
    ds = solve_contact(h, loads, tol=tol, hardness=hardness)
    check_solution(ds, h, tol=tol, hardness=hardness)
    substrate = halfspace((n, n), 1.0, physical_sizes=(1.0, 1.0))  # "young" is E*
    for k, p0 in enumerate(loads):
        kwargs = {} if hardness is None else {"hardness": hardness / n**2}  # force per node
        res = ccg(substrate, h, external_force=p0, pentol=1e-12, forcetol=1e-12,
                  maxiter=100000, **kwargs)
        assert res.success
        forces = np.asarray(res.jac)
        forces = forces if forces.mean() > 0 else -forces  # sign convention differs by mode
        a_cm = np.count_nonzero(forces > 0) / n**2
        a = float(ds["area_fraction"][k])
        limit = 1e-4 if hardness is None else 1e-3
        assert abs(a - a_cm) <= limit * a_cm, f"p0={p0}: {a} vs ContactMechanics {a_cm}"


def test_huge_hardness_is_elastic():
    # A cap that is never reached must reproduce the elastic solution exactly
    # (same contact set, same iterates up to round-off).
    h = generate_surface(128, 16, 32, 0.8, 0, rms_slope=0.1)
    loads = np.linspace(0.0005, 0.005, 5)
    tol = 1e-10
    el = solve_contact(h, loads, tol=tol, store_fields=True)
    pl = solve_contact(h, loads, tol=tol, hardness=1e9, store_fields=True)
    check_solution(pl, h, tol=tol, hardness=1e9)
    np.testing.assert_array_equal(el["area_fraction"].values, pl["area_fraction"].values)
    np.testing.assert_allclose(pl["contact_pressure"].values, el["contact_pressure"].values,
                               rtol=0, atol=1e-8 * 0.005)
    assert np.all(pl["plastic_area_fraction"].values == 0)
    assert np.all(pl["plastic_load_fraction"].values == 0)
    assert "plastic_area_fraction" not in el
