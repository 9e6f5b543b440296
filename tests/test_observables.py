"""The observables the open questions need: P(p) per step, the contact stiffness, the exact full-contact load.

Each appears only when a scene asks (config ``contact.outputs``), in the per-case file and the
aggregate, with CF units and long names; each is checked against what defines it.
"""

import numpy as np
import pytest
import xarray as xr

from cfcheck import own_checks
from roughcontact.analysis.stiffness import contact_stiffness, stiffness_variable
from roughcontact.case.outputs import contact_observers, full_contact_variable
from roughcontact.pipeline.datasets import contact_dataset
from roughcontact.pipeline.io import write_dataset
from roughcontact.pipeline.sources.generated import Generated
from roughcontact.solver import solve_contact
from roughcontact.statistics.pressure import pressure_bins, pressure_density
from roughcontact.surfaces.synthetic import generate_surface
from roughcontact.theory.full_contact import full_contact_load

OUTPUTS = {"pressure_distribution": {"bins": 60, "max": 6.0}, "stiffness": True, "full_contact_load": True}


def test_density_integrates_to_the_contact_area_with_the_overflow():
    p = np.array([[0.0, 0.1, 0.5], [1.0, 2.0, 6.0], [0.0, 7.5, 0.25]])
    edges = pressure_bins(4, 4.0)  # p / scale with scale 1.5: 6 / 1.5 = 4 is the last edge -> overflow
    density, over = pressure_density(p, edges, 1.5)
    assert over == pytest.approx(2 / 9)  # 6.0 and 7.5
    assert np.sum(density * np.diff(edges)) + over == pytest.approx(np.count_nonzero(p) / p.size)
    assert density[0] * 1.0 * 9 == pytest.approx(4)  # 0.1, 0.25, 0.5, 1.0 reduce to < 1; zeros are not contact


@pytest.mark.parametrize("bins, top, field", [(0, 1.0, "bins"), (2.5, 1.0, "bins"), (3, 0.0, "max"),
                                              (3, float("nan"), "max")])
def test_bad_bins_name_the_field(bins, top, field):
    with pytest.raises(ValueError, match=f"pressure_distribution {field}"):
        pressure_bins(bins, top)


def _solve(n=64, outputs=OUTPUTS):
    h = generate_surface(n, 2, 16, 0.7, 3, rms_slope=0.1)
    loads = 0.1 * np.array([0.01, 0.05, 0.2, 0.8, 2.5, 4.0])
    res = solve_contact(h, loads, tol=1e-10, observers=contact_observers(outputs, 0.1))
    return h, loads, res


def test_the_observer_accounts_for_every_node_in_contact_at_every_step():
    _, _, res = _solve()
    width = res["pressure_bin_high"] - res["pressure_bin_low"]
    total = (res["pressure_distribution"] * width).sum("pressure_bin") + res["pressure_distribution_overflow"]
    np.testing.assert_allclose(total, res["area_fraction"], rtol=0, atol=1e-12)
    attrs = res["pressure_distribution"].attrs
    assert attrs["units"] == "1" and "P(p)" in attrs["long_name"]
    assert res["pressure_bin"].values[0] == pytest.approx(0.05)


def test_nothing_is_observed_unless_asked():
    _, _, res = _solve(outputs={})
    assert contact_observers({"clusters": False, "fields": []}, 0.1) == []
    assert not {"pressure_distribution", "pressure_distribution_overflow", "pressure_bin"} & set(res.variables)


def test_observers_must_observe():
    with pytest.raises(ValueError, match="observers: int has no observe"):
        solve_contact(np.random.default_rng(0).standard_normal((16, 16)), [0.01], observers=[3])


def test_full_contact_starts_at_the_exact_load():
    h, loads, res = _solve(outputs={})
    p_fc = full_contact_load(h)
    full = res["area_fraction"].values >= 1.0
    assert full.any() and not full.all()
    np.testing.assert_array_equal(full, loads > p_fc)


def test_stiffness_of_an_exponential_law_is_exact():
    # Persson's intermediate regime: u = -u0 ln(p / pa) gives K = p / u0; second-order differences in
    # ln p0 are exact for a function linear in ln p0, at the ends too.
    p = np.geomspace(1e-4, 1e-2, 9)
    k = contact_stiffness(-0.3 * np.log(p / 0.5), p, np.full(9, 0.5))
    np.testing.assert_allclose(k, p / 0.3, rtol=1e-12)


def test_stiffness_is_nan_at_and_beside_full_contact():
    p = np.geomspace(1e-3, 1.0, 8)
    area = np.array([0.01, 0.02, 0.05, 0.1, 0.3, 0.7, 1.0, 1.0])
    k = contact_stiffness(np.array([5, 4, 3, 2, 1, 0.5, 0, 0.0]), p, area)
    assert np.isnan(k[5:]).all() and np.isfinite(k[:5]).all()
    with pytest.raises(ValueError, match="1-D of one length >= 3"):
        contact_stiffness(np.ones(2), np.ones(2), np.ones(2))


def test_the_observables_in_the_case_and_aggregate_files_are_cf_clean(tmp_path):
    paths, datasets = [], []
    for seed in (0, 1):
        h = generate_surface(32, 2, 8, 0.7, seed, rms_slope=0.1)
        res = solve_contact(h, 0.1 * np.geomspace(0.02, 3.0, 6), tol=1e-10,
                            observers=contact_observers(OUTPUTS, 0.1))
        res["contact_stiffness"] = stiffness_variable(res)
        res["full_contact_pressure"] = full_contact_variable(h, 1.0, 1.0, "1")
        ds = contact_dataset(res, rms_slope=0.1, alpha=2.0, e_star=1.0, k_l="2", k_s="8", hurst="0.7", seed=seed)
        paths.append(write_dataset(ds, tmp_path / f"case{seed}.nc", stage="contact", scene="t", scene_parameters={}))
        datasets.append(xr.load_dataset(paths[-1]))
    agg = Generated.aggregate(datasets, paths, [(2.0, 8.0, 0.7, 0), (2.0, 8.0, 0.7, 1)])
    out = write_dataset(agg, tmp_path / "contact.nc", stage="aggregate", scene="t", scene_parameters={})
    got = xr.load_dataset(out)
    for name in ("pressure_distribution", "pressure_distribution_overflow", "contact_stiffness",
                 "full_contact_pressure"):
        assert name in got and got[name].attrs["long_name"] and got[name].attrs["units"]
    assert got["pressure_distribution"].dims == ("k_l", "k_s", "H", "seed", "step", "pressure_bin")
    assert own_checks(out) == [] and all(own_checks(p) == [] for p in paths)
