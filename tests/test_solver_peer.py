"""Agreement with independent solvers: Tamaas (C++) and ContactMechanics (Python).

All three solve the same discrete problem (same kernel 2/(E*|q|), same nodal
collocation, highest points of ``h`` touch first), so at tight tolerances the
contact sets agree node for node; the tests allow 1e-4 relative on A/A0 for
the elastic case and 1e-3 with a hardness, as the spec asks.

With a hardness, the sweeps cover hardness 1e-3..1e-1 E* and loads from 5 % of
the hardness to the fully plastic limit (99.9 %): A/A0 and the plastic area equal
Tamaas' KatoSaturated node for node everywhere. ContactMechanics' hardness option
agrees node for node where it converges to its own contact conditions; near the
plastic limit at low hardness it switches to a relaxation that stops with a
penetration of ~1e-2 of the rms height (and a plastic area a few 1e-3 short), so
there the contact conditions, checked independently, decide (last test).
"""

from __future__ import annotations

import numpy as np
import pytest

from roughcontact.solver import solve_contact
from roughcontact.solver.halfspace import elastic_kernel
from roughcontact.solver.units import gap_scale
from roughcontact.surfaces.synthetic import generate_surface
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


# --------------------------------------------------------------------------- hardness sweeps
# The surface of the plasticity issue (hardness 1e-3 gave "converged" steps carrying
# 12 % of the load) and loads from 5 % of the hardness to the fully plastic limit.
ISSUE = dict(n=64, k_l=2, k_s=16, hurst=0.3, seed=0, rms_slope=0.1)
SWEEP_FRACTIONS = (0.05, 0.3, 0.7, 0.95, 0.999)


def _issue_surface():
    return generate_surface(ISSUE["n"], ISSUE["k_l"], ISSUE["k_s"], ISSUE["hurst"], ISSUE["seed"],
                            rms_slope=ISSUE["rms_slope"])


def _counts(p, hardness):
    """Nodes in contact and nodes at the cap (a peer's cap to 1e-9 relative)."""
    return np.count_nonzero(p > 0), np.count_nonzero(p >= hardness * (1 - 1e-9))


def _kkt_violation(p, h, hardness):
    """Largest sign violation of a pressure field's gap, relative to the rms height."""
    n = h.shape[0]
    w = np.fft.irfft2(np.fft.rfft2(p) * elastic_kernel(n), s=p.shape) - h
    capped = p >= hardness * (1 - 1e-9)
    free = (p > 0) & ~capped
    g = w - w[free].mean()
    return max(0.0, -g[~capped].min(), g[capped].max() if capped.any() else 0.0) / gap_scale(h, 1.0)


@pytest.mark.parametrize("hardness", [1e-3, 1e-2, 1e-1])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_tamaas_kato_saturated_sweep(hardness):
    # A/A0 and the plastic area equal to KatoSaturated's to 1e-3 relative from 5 % of
    # the hardness to 99.9 % (measured: node for node equal in all 15 cases).
    tm = _tamaas()
    h = _issue_surface()
    n = h.shape[0]
    loads = [f * hardness for f in SWEEP_FRACTIONS]
    tol = 1e-10
    ds = solve_contact(h, loads, tol=tol, hardness=hardness, store_fields=True)
    check_solution(ds, h, tol=tol, hardness=hardness)
    model = _tamaas_model(tm, n)
    for k, p0 in enumerate(loads):
        solver = tm.KatoSaturated(model, h, 1e-12, hardness)
        solver.solve(p0)
        traction = np.asarray(model.traction)
        a_tm, pl_tm = _counts(traction, hardness)
        a, pl = _counts(ds["contact_pressure"].values[k], hardness)
        print(f"H={hardness} p0/H={p0 / hardness}: contact {a} vs Tamaas {a_tm}, plastic {pl} vs {pl_tm}")
        assert abs(a - a_tm) <= 1e-3 * a_tm
        assert abs(pl - pl_tm) <= 1e-3 * pl_tm
        assert float(ds["area_fraction"][k]) * n**2 == a
        assert float(ds["plastic_area_fraction"][k]) * n**2 == pl


@pytest.mark.parametrize(
    ("hardness", "fractions"),
    [
        (1e-1, (0.05, 0.3, 0.7, 0.95)),
        (1e-2, (0.05, 0.3, 0.7)),
        pytest.param(1e-3, (0.05, 0.3), marks=pytest.mark.slow),
    ],
)
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_contact_mechanics_hardness_sweep(hardness, fractions):
    # Where ContactMechanics' hardness option converges to its own contact conditions
    # (its CG mode: more than 1 % of the contact area elastic) A/A0 and the plastic area
    # equal ours to 1e-3 relative (measured: node for node). Closer to the plastic
    # limit it switches to a relaxation that stops with a penetration of ~1e-2 s; see
    # the next test.
    halfspace, ccg = _contact_mechanics()
    h = _issue_surface()
    n = h.shape[0]
    loads = [f * hardness for f in fractions]
    tol = 1e-10
    ds = solve_contact(h, loads, tol=tol, hardness=hardness, store_fields=True)
    check_solution(ds, h, tol=tol, hardness=hardness)
    substrate = halfspace((n, n), 1.0, physical_sizes=(1.0, 1.0))
    for k, p0 in enumerate(loads):
        res = ccg(substrate, h, external_force=p0, pentol=1e-12, forcetol=1e-12, maxiter=20000,
                  hardness=hardness / n**2)
        assert res.success
        forces = np.asarray(res.jac)
        forces = forces if forces.mean() > 0 else -forces
        a_cm, pl_cm = _counts(forces * n**2, hardness)
        a, pl = _counts(ds["contact_pressure"].values[k], hardness)
        print(f"H={hardness} p0/H={p0 / hardness}: contact {a} vs CM {a_cm}, plastic {pl} vs {pl_cm}")
        assert abs(a - a_cm) <= 1e-3 * a_cm
        assert abs(pl - pl_cm) <= 1e-3 * pl_cm


@pytest.mark.slow
def test_where_the_peers_disagree_the_contact_conditions_decide():
    # Hardness 1e-3, p0 = 0.95 H: ContactMechanics' relaxation mode stops 18 nodes short
    # of the cap (plastic area -4.6e-3 relative to ours and to Tamaas'), with its gap
    # violating the contact conditions by ~1e-2 of the rms height; ours satisfies them
    # to 1e-10 and equals KatoSaturated node for node.
    halfspace, ccg = _contact_mechanics()
    tm = _tamaas()
    h = _issue_surface()
    n = h.shape[0]
    hardness, p0 = 1e-3, 0.95e-3
    ours = solve_contact(h, [p0], tol=1e-10, hardness=hardness, store_fields=True)
    p = ours["contact_pressure"].values[0]
    res = ccg(halfspace((n, n), 1.0, physical_sizes=(1.0, 1.0)), h, external_force=p0, pentol=1e-12,
              forcetol=1e-12, maxiter=20000, hardness=hardness / n**2)
    forces = np.asarray(res.jac)
    p_cm = (forces if forces.mean() > 0 else -forces) * n**2
    model = _tamaas_model(tm, n)
    tm.KatoSaturated(model, h, 1e-12, hardness).solve(p0)
    p_tm = np.asarray(model.traction)
    assert _counts(p, hardness) == _counts(p_tm, hardness)
    v_ours, v_cm, v_tm = (_kkt_violation(x, h, hardness) for x in (p, p_cm, p_tm))
    print(f"contact-condition violation / s: ours {v_ours:.1e}, Tamaas {v_tm:.1e}, ContactMechanics {v_cm:.1e}")
    assert v_ours <= 1e-10 and v_tm <= 1e-8
    if _counts(p_cm, hardness) != _counts(p, hardness):
        assert v_cm > 1e3 * max(v_ours, v_tm)
