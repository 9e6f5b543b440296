"""A contact case as a library object: ContactCase, LoadSchedule and run_case (roughcontact.case), and the scene's
contact block made one (roughcontact.pipeline.case.contact_case)."""
import ast
import doctest
from pathlib import Path

import numpy as np
import pytest

import roughcontact.case as case_package
import roughcontact.case.run as case_module
from roughcontact.case import ContactCase, LoadSchedule, run_case
from roughcontact.pipeline.case import contact_case, load_schedule
from roughcontact.solver import SolverSettings, solve_contact, solve_step
from roughcontact.statistics.clusters import ClusterObserver
from roughcontact.surfaces.synthetic import generate_surface

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def surface():
    return generate_surface(64, 2, 16, 0.6, seed=3, rms_slope=0.1)


def test_the_module_examples_run():
    assert doctest.testmod(case_module).failed == 0
    assert doctest.testmod(case_package).failed == 0


def test_a_block_runs_as_the_solver_with_its_settings(surface):
    block = {"load": {"n_steps": 6, "schedule": "geometric", "p_max": 0.05, "relative_to": "rms_slope"},
             "solver": {"e_star": 2.0, "tol": 1e-9, "max_iter": 5000, "boundary": "periodic", "pressure_unit": "MPa"},
             "effects": {"plasticity": {"hardness": 0.5}},
             "outputs": {"fields": [6], "clusters": True, "stiffness": True}}
    case = contact_case(block, length_unit="um")
    [ds] = run_case(surface, case, length=1.0, rms_slope=0.1)
    loads = np.geomspace(0.05 * 2.0 * 0.1 / 6, 0.05 * 2.0 * 0.1, 6)
    ref = solve_contact(surface, load_schedule(block).pressures(2.0, 0.1), e_star=2.0, tol=1e-9,
                        max_iter=5000, hardness=1.0, store_fields=[6], length_unit="um", pressure_unit="MPa",
                        observers=[ClusterObserver(1.0, length_unit="um")])
    np.testing.assert_allclose(ds["pressure"].values, loads, rtol=1e-12)
    for name in ("area_fraction", "mean_gap", "iterations", "plastic_area_fraction", "contact_pressure",
                 "cluster_count"):
        np.testing.assert_array_equal(ds[name].values, ref[name].values, err_msg=name)
    assert "contact_stiffness" in ds and "full_contact_pressure" not in ds
    assert ds.attrs["load_relative_to"] == "rms_slope" and ds.attrs["load_p_max"] == 0.05
    assert ds.attrs["load_p0_max"] == pytest.approx(0.01) and ds.attrs["load_pbar_max"] == pytest.approx(0.05)


def test_a_target_area_is_searched_on_the_case_surface(surface):
    case = ContactCase(LoadSchedule(4, target_area=0.05), SolverSettings(tol=1e-10))
    [ds] = run_case(surface, case, length=1.0, rms_slope=0.1)
    assert abs(float(ds.area_fraction[-1]) - 0.05) <= max(0.01 * 0.05, 1.5 / surface.size) + 1 / surface.size
    assert ds.attrs["load_probes"] >= 1 and "load_p_max" not in ds.attrs


def test_scaled_warm_start_is_the_step_by_step_solve_bit_for_bit(surface):
    """The κ-gap study's start (each step from the last pressure scaled to its load), through the case runner:
    the same fields as a loop of solve_step calls, bit for bit."""
    loads = LoadSchedule(8, "geometric", p_max=0.01, p_min=0.01 / 30).pressures(1.0)

    class Keep:
        needs_gap = True

        def __init__(self):
            self.steps = []

        def observe(self, step):
            self.steps.append((step.pressure.copy(), step.gap.copy(), step.iterations))

        def dataset(self, steps):
            import xarray as xr
            return xr.Dataset(coords={"step": steps})

    keep = Keep()
    run_case(surface, ContactCase(LoadSchedule(8, "geometric", p_max=0.01, p_min=0.01 / 30), warm_start="scaled"),
             length=1.0, rms_slope=0.1, observers=[keep])
    prev = None
    for p0, (pressure, gap, its) in zip(loads, keep.steps, strict=True):
        init = None if prev is None else prev * (p0 / prev.mean())
        r = solve_step(surface, p0, initial_pressure=init)
        np.testing.assert_array_equal(pressure, r.pressure)
        np.testing.assert_array_equal(gap, r.gap)
        assert its == r.iterations
        prev = r.pressure


def test_bad_warm_start_is_named(surface):
    with pytest.raises(ValueError, match="warm_start must be one of"):
        solve_contact(surface, [0.001], warm_start="cold")


def _solver_callers() -> set[str]:
    """Files outside src/roughcontact/solver that call solve_contact, solve_step or solve_contact_batch (src and
    workflow scripts)."""
    found = set()
    files = [p for p in (REPO / "src" / "roughcontact").rglob("*.py") if "solver" not in p.relative_to(REPO).parts]
    files += list((REPO / "workflow" / "scripts").glob("*.py"))
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call):
                fn = node.func
                name = fn.id if isinstance(fn, ast.Name) else fn.attr if isinstance(fn, ast.Attribute) else ""
                if name in ("solve_contact", "solve_step", "solve_contact_batch"):
                    found.add(str(path.relative_to(REPO)))
    return found


def test_one_module_outside_the_solver_runs_a_case():
    assert _solver_callers() == {"src/roughcontact/case/run.py"}
