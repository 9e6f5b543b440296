"""The loads a contact case receives: relative to E* or to each surface's rms slope, or a target A/A0."""
import math

import numpy as np
import pytest

from roughcontact.case.loading import AREA_RTOL, pressure_for_area, schedule
from roughcontact.pipeline.case import load_schedule
from roughcontact.solver import solve_contact
from roughcontact.surfaces.synthetic import generate_surface


def _block(**load):
    return {"load": {"n_steps": 10, "schedule": "uniform", **load}, "solver": {"e_star": 3.0}}


def load_steps(block, rms_slope=None):
    return load_schedule(block).pressures(block["solver"]["e_star"], rms_slope)


def case_loads(block, rms_slope, n_nodes, solve, log=None, name=None):
    """The case's loads as the case runner resolves them, ``solve(loads)`` the surface's solver."""
    return load_schedule(block).resolve(block["solver"]["e_star"], rms_slope, n_nodes,
                                                  lambda p: float(solve([p]).area_fraction[-1]), log, name)


def test_relative_to_the_rms_slope_scales_each_case_by_its_own_slope():
    block = _block(p_max=0.05, relative_to="rms_slope")
    for slope in (0.003, 0.1, 1.7):
        steps = load_steps(block, slope)
        assert steps[-1] == pytest.approx(0.05 * 3.0 * slope, rel=1e-15)
        assert steps[0] == pytest.approx(steps[-1] / 10, rel=1e-15)
    # relative to E*: the same loads whatever the slope
    assert load_steps(_block(p_max=0.005), 0.003) == load_steps(_block(p_max=0.005), 1.7)
    with pytest.raises(ValueError, match="rms slope.*got nan"):
        load_steps(block, float("nan"))


def test_geometric_p_min_is_on_p_max_scale():
    block = _block(p_max=0.05, p_min=0.001, relative_to="rms_slope", schedule="geometric")
    steps = load_steps(block, 0.2)
    assert steps[0] == pytest.approx(0.001 * 3.0 * 0.2) and steps[-1] == pytest.approx(0.05 * 3.0 * 0.2)
    assert np.allclose(np.diff(np.log(steps)), math.log(50) / 9)
    assert schedule(1.0, 4) == [0.25, 0.5, 0.75, 1.0]


@pytest.mark.parametrize("exponent", [0.5, 1.0, 1.6])
def test_pressure_for_area_finds_a_smooth_law_in_few_solves(exponent):
    calls = []

    def area(p):  # saturating power law, like A/A0 against p0 with a sublinear tail
        calls.append(p)
        return 1 - math.exp(-(p / 0.02) ** exponent)

    found = pressure_for_area(area, 0.1, e_star=1.0, rms_slope=0.1, n_nodes=10**8)
    assert found["reached"] and abs(found["area"] - 0.1) <= AREA_RTOL * 0.1
    assert found["probes"] == len(calls) <= 6


def test_pressure_for_area_says_when_a_jump_defeats_it():
    # the area jumps over the target (a flat plateau coming into contact at once): no load gives it
    found = pressure_for_area(lambda p: 0.05 if p < 1e-3 else 0.5, 0.1, e_star=1.0, rms_slope=0.1, n_nodes=10**6)
    assert not found["reached"] and found["probes"] == 12
    assert found["area"] == 0.05 and found["pressure"] < 1e-3  # the closest area, and a load that gives it
    with pytest.raises(ValueError, match=r"target_area must lie in \(0, 1\)"):
        pressure_for_area(lambda p: p, 1.0, e_star=1.0, rms_slope=0.1, n_nodes=100)


@pytest.mark.parametrize("boundary", ["periodic", "free"])
def test_target_area_is_reached_by_the_last_load_step(boundary):
    """On a real surface the schedule ends at the target A/A0: within 1 % or 1.5 nodes of it."""
    h = generate_surface(64, k_l=2, k_s=16, hurst=0.6, seed=3, rms_slope=0.1)
    block = {"load": {"n_steps": 5, "schedule": "uniform", "target_area": 0.08}, "solver": {"e_star": 1.0}}

    def solve(loads, **kw):
        return solve_contact(h, loads, tol=1e-10, boundary=boundary, **kw)

    loads, attrs = case_loads(block, 0.1, h.size, solve)
    last = float(solve(loads).area_fraction[-1])
    tol = max(AREA_RTOL * 0.08, 1.5 / h.size)
    assert abs(attrs["load_target_area_reached"] - 0.08) <= tol and abs(last - 0.08) <= tol + 1.0 / h.size
    assert attrs["load_probes"] <= 6 and attrs["load_p0_max"] == loads[-1]
    assert attrs["load_pbar_max"] == pytest.approx(loads[-1] / 0.1)


def test_a_target_no_load_meets_is_warned_with_the_case_name(caplog):
    """SurfaceTopography's frt-1 and frt-2 (filled plateaus) jump over A/A0 = 0.1: the warning names the case,
    as two jobs' lines meet in one console."""
    import logging
    import re
    from types import SimpleNamespace

    block = {"load": {"n_steps": 3, "schedule": "uniform", "target_area": 0.1}, "solver": {"e_star": 1.0}}

    def solve(loads):  # the area jumps over the target at p0 = 0.01: a plateau touching at once
        return SimpleNamespace(area_fraction=[0.05 if loads[-1] < 0.01 else 0.2])

    with caplog.at_level("WARNING", logger="roughcontact"):
        loads, attrs = case_loads(block, 0.1, 10_000, solve, logging.getLogger("roughcontact.test"), name="frt-2")
    messages = [r.getMessage() for r in caplog.records]
    assert any(re.fullmatch(r"frt-2: target A/A0 = 0\.1: p0 = \S+ gives A/A0 = 0\.(05|2) after \d+ solves "
                            r"\(not within tolerance: the closest is used\)", m) for m in messages), messages
    assert attrs["load_target_area_reached"] in (0.05, 0.2) and loads[-1] == attrs["load_p0_max"]
