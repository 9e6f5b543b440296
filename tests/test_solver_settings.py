"""The solver's settings object and the effects registry: one validated set-up, effects found by name."""
import dataclasses

import numpy as np
import pytest

from roughcontact import solver as solver_mod
from roughcontact.solver import EFFECTS, Effect, PlasticityCap, SolverSettings, effects_from_config, solve_contact
from roughcontact.surfaces.synthetic import generate_surface

LOADS = [0.001, 0.003]


@pytest.fixture(scope="module")
def surface():
    return generate_surface(64, 2, 16, 0.5, seed=1, rms_slope=0.1)


def test_settings_object_and_keyword_options_are_one_problem(surface):
    # the same settings given as an object, as keyword options, or as an object with an option
    # replacing one field: bit-identical outputs (wall_time aside)
    settings = SolverSettings(e_star=2.0, length=3.0, tol=1e-9, effects=(PlasticityCap(0.02),))
    a = solve_contact(surface, LOADS, settings).drop_vars("wall_time")
    b = solve_contact(surface, LOADS, e_star=2.0, length=3.0, tol=1e-9, hardness=0.02).drop_vars("wall_time")
    c = solve_contact(surface, LOADS, dataclasses.replace(settings, tol=1e-3), tol=1e-9).drop_vars("wall_time")
    assert a.identical(b) and a.identical(c)
    assert a.attrs["hardness"] == 0.02 and a.attrs["e_star"] == 2.0


def test_unknown_option_is_a_type_error_naming_it(surface):
    with pytest.raises(TypeError, match="hardnes"):
        solve_contact(surface, LOADS, hardnes=0.1)


@pytest.mark.parametrize("field, value, message", [
    ("e_star", -1.0, "e_star must be a finite real number > 0"),
    ("tol", 2.0, "tol must be a number in the open interval"),
    ("max_iter", 0, "max_iter must be an integer >= 1"),
    ("boundary", "open", "boundary must be one of"),
    ("method", "cg", "method must be one of"),
    ("effects", ("plasticity",), "effects must be Effect objects"),
    ("length_unit", "furlong", "furlong"),
])
def test_bad_settings_name_the_field(surface, field, value, message):
    with pytest.raises(ValueError, match=message):
        SolverSettings(**{field: value}).checked(surface.shape)


def test_settings_must_be_a_settings_object(surface):
    with pytest.raises(ValueError, match="settings must be a SolverSettings"):
        solve_contact(surface, LOADS, {"tol": 1e-6})


def test_method_defaults_to_the_solver_option(solver_options, surface):
    assert SolverSettings().method == "pk-fourier-f32"
    solver_options(method="pk")
    assert SolverSettings().checked(surface.shape).method == "pk"
    assert SolverSettings(method=None).checked(surface.shape).method == "pk"  # None: the option at the solve
    assert SolverSettings(method="pk-fourier").checked(surface.shape).method == "pk-fourier"


def test_registry_builds_effects_from_config():
    assert EFFECTS["plasticity"] is PlasticityCap
    (cap,) = effects_from_config({"plasticity": {"hardness": 0.01}}, e_star=3.0)
    assert isinstance(cap, PlasticityCap) and cap.hardness == pytest.approx(0.03)
    assert effects_from_config({}, e_star=1.0) == ()
    with pytest.raises(ValueError, match=r"contact.effects: unknown effect\(s\) \['friction'\]"):
        effects_from_config({"friction": {}}, e_star=1.0)


def test_register_refuses_a_nameless_or_taken_name():
    class Nameless(Effect):
        pass

    class Twin(Effect):
        name = "plasticity"

    for cls in (Nameless, Twin):
        with pytest.raises(ValueError, match="empty or already registered"):
            solver_mod.effects.register(cls)


def test_a_new_effect_needs_no_change_in_the_solver(surface):
    # An effect written outside the package (one class) reaches the output through the
    # protocol alone: its column per step and its attribute.
    class LoadLog(Effect):
        name = "load-log"

        def finish(self, p, p_int, p0):
            return {"max_pressure_ratio": float(p.max()) / p0}

        def variables(self, length_unit="1", pressure_unit="1"):
            return {"max_pressure_ratio": ("1", "largest nodal pressure over the mean")}

        def attrs(self):
            return {"load_log": "on"}

    ds = solve_contact(surface, LOADS, effects=(LoadLog(),))
    assert ds.attrs["load_log"] == "on"
    assert np.all(ds["max_pressure_ratio"].values > 1) and ds["max_pressure_ratio"].attrs["long_name"]
