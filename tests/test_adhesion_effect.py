"""The adhesion effect through the solver's front door: solve_contact with ``Adhesion``.

The physics of the gap iteration (JKR, DMT, Johnson's wavy surface, Tamaas) is checked in
tests/test_adhesion.py; here: what the effect adds to a solve, its limits and its refusals.
"""
import numpy as np
import pytest

from roughcontact.solver import Adhesion, SolverSettings, effects_from_config, solve_contact
from roughcontact.solver.adhesion import Exponential, MaugisDugdale
from roughcontact.surfaces.synthetic import generate_surface

LOADS = [0.001, 0.002, 0.004]


@pytest.fixture(scope="module")
def surface():
    return generate_surface(64, 2, 16, 0.5, seed=0, rms_slope=0.1)


def test_vanishing_adhesion_is_the_elastic_contact(surface):
    # w = 1e-12 E* L: the largest tension w / rho = 1e-9 is 1e-6 of the smallest load, far below
    # what moves a node in or out of contact; the contact sets agree node for node (measured: equal)
    ds = solve_contact(surface, LOADS, effects=(Adhesion("exponential", 1e-12, 1e-3, unloading=False),),
                       store_fields=True)
    ref = solve_contact(surface, LOADS, store_fields=True)
    assert ds["converged"].all()
    np.testing.assert_array_equal(ds["gap"].values == 0, ref["contact_pressure"].values > 0)
    np.testing.assert_allclose(ds["area_fraction"].values, ref["area_fraction"].values, rtol=0, atol=0)
    # pressures: the two iterations stop at tol = 1e-8 on their own residuals; measured 2e-7 of max p
    scale = ref["contact_pressure"].values.max()
    assert np.abs(ds["contact_pressure"].values - ref["contact_pressure"].values).max() <= 1e-5 * scale
    assert "pull_off_pressure" not in ds


@pytest.mark.parametrize("law", ["exponential", "maugis-dugdale"])
def test_adhesive_steps_meet_their_invariants(surface, law):
    # g >= 0 exactly; p = -tension(g) where g > 0 and p + tension(0) >= 0 where g = 0, each within
    # tol times the residual's pressure scale (the rms of M h, recomputed here from the solver's kernel)
    effect = Adhesion(law, 2e-6, 1e-3)
    ds = solve_contact(surface, LOADS, effects=(effect,), store_fields=True, tol=1e-8)
    assert ds["converged"].all() and ds.attrs["elastic_method"] == "adhesive"
    from roughcontact.solver.halfspace import inverse_kernel

    mult = inverse_kernel(surface.shape, 1.0, 1.0)
    p_ref = float(np.sqrt(np.mean(np.fft.irfft2(np.fft.rfft2(surface) * mult, s=surface.shape) ** 2)))
    for k, p0 in enumerate(LOADS):
        p, g = ds["contact_pressure"].values[k], ds["gap"].values[k]
        assert g.min() >= 0.0
        tension = effect.functional.tension(g)
        assert np.abs(p[g > 0] + tension[g > 0]).max() <= 1e-8 * p_ref * 10
        assert (p[g == 0] + effect.functional.tension(0.0)).min() >= -1e-8 * p_ref * 10
        assert abs(p.mean() - p0) <= 1e-8 * p_ref * 10
        assert ds["area_fraction"].values[k] == np.count_nonzero(g == 0) / g.size
    # adhesion adds contact, and the pull-off pressure is tensile and below the largest tension
    assert np.all(ds["area_fraction"].values > solve_contact(surface, LOADS)["area_fraction"].values)
    assert 0 < float(ds["pull_off_pressure"]) < effect.functional.max_tension
    assert ds["pull_off_pressure"].attrs["units"] == "1" and ds["adhesive_pressure"].attrs["long_name"]


def test_refusals_name_the_argument(surface):
    effect = Adhesion("exponential", 1e-5, 1e-3)
    with pytest.raises(ValueError, match="boundary: adhesion needs the periodic half-space"):
        solve_contact(surface, LOADS, effects=(effect,), boundary="free")
    with pytest.raises(ValueError, match="one interaction law at a time, and not with a pressure cap"):
        solve_contact(surface, LOADS, effects=(effect,), hardness=0.5)
    with pytest.raises(ValueError, match="needs a rough surface"):
        solve_contact(np.zeros((16, 16)), LOADS, effects=(effect,))
    with pytest.raises(ValueError, match="law must be one of"):
        Adhesion("lennard-jones", 1e-5, 1e-3)
    with pytest.raises(ValueError, match="rho must be a finite number > 0"):
        Adhesion("exponential", 1e-5, 0.0)


def test_from_config_scales_the_work_with_the_modulus():
    (effect,) = effects_from_config({"adhesion": {"law": "maugis-dugdale", "work": 1e-5, "range": 2e-3}},
                                    e_star=3.0)
    assert isinstance(effect.functional, MaugisDugdale)
    assert effect.functional.w == pytest.approx(3e-5) and effect.functional.rho == 2e-3
    (effect,) = effects_from_config({"adhesion": {"law": "exponential", "work": 1e-5, "range": 2e-3,
                                                  "unloading": False}}, e_star=1.0)
    assert isinstance(effect.functional, Exponential) and not effect.unloading
    assert SolverSettings(effects=(effect,)).hardness is None
