"""Profiles through the pipeline (issue 49): surface files, the contact case, its file, the aggregate and the fit.

The 1-D solver is checked first against the same profile solved as the y-invariant map
(:func:`profile_solves.profile_solve`, the plane-strain problem exactly), which these tests used before it existed.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from cfcheck import own_checks
from profile_solves import profile_solve
from roughcontact.analysis import fit
from roughcontact.case import ContactCase, run_case
from roughcontact.case.loading import LoadSchedule
from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.config.checks import check_contact, check_profile_contact
from roughcontact.pipeline.contact_jobs import contact_mem_mb, contact_runtime_min, map_side
from roughcontact.pipeline.datasets import (
    contact_dataset,
    generated_heights,
    measured_surface_dataset,
    surface_dataset,
    surface_heights,
)
from roughcontact.pipeline.io import read_dataset, write_dataset
from roughcontact.pipeline.params import surface as surface_params
from roughcontact.pipeline.sources import SOURCES
from roughcontact.solver import SolverSettings
from roughcontact.surfaces.synthetic import generate_profile, profile_spectral_moments
from roughcontact.surfaces.topography import read_topography
from roughcontact.theory.profiles import full_contact_load_profile

SURFACE = {"N": 512, "L": 2.0, "plateau": False, "rms_slope": 0.1, "unit": "um", "dimension": 1}


def test_the_1d_solver_is_the_y_invariant_map():
    """run_case's solve of a profile equals the same profile as an (n, 4) map invariant along y: A/A0 and the
    interval ends per length to the last bit here (one iteration path), the mean gap to 1e-9 relative."""
    h = generate_profile(1024, 4, 64, 0.8, 0, rms_slope=0.1)
    [one] = run_case(h, ContactCase(LoadSchedule(8, p_max=1e-2)), length=1.0, rms_slope=0.1)
    two = profile_solve(h, one.pressure.values)
    assert one.attrs["surface_dimension"] == 1 and bool(one.converged.all())
    np.testing.assert_allclose(one.area_fraction, two.area_fraction, rtol=1e-12)
    np.testing.assert_allclose(one.contact_perimeter, two.contact_perimeter, rtol=1e-12)
    np.testing.assert_allclose(one.mean_gap, two.mean_gap, rtol=1e-9)


def test_generated_profile_surface_file(tmp_path):
    """A profile's surface file: heights over (x,), CF attributes, surface_dimension = 1, read back as (h, L)."""
    h = generated_heights(SURFACE, "4", "32", "0.6", 1)
    assert h.shape == (512,)
    np.testing.assert_array_equal(h, generate_profile(512, 4.0, 32.0, 0.6, 1, rms_slope=0.1, length=2.0))
    ds = surface_dataset(h, k_l="4", k_s="32", hurst="0.6", seed=1, length=2.0, normalisation={"rms_slope": 0.1},
                         length_unit="um")
    assert ds.heights.dims == ("k_l", "k_s", "H", "seed", "x") and ds.attrs["surface_dimension"] == 1
    assert ds.heights.attrs == {"units": "um", "long_name": "profile height h(x)"}
    assert float(ds.rms_slope.squeeze()) == pytest.approx(0.1, rel=1e-12)
    assert float(ds.rms_slope_fd.squeeze()) < 0.1  # central differences: biased low
    path = tmp_path / "s.nc"
    write_dataset(ds, path, stage="surface", scene="t", scene_parameters={"surface": SURFACE})
    assert own_checks(path) == []
    back = read_dataset(path, stage="surface")
    heights, length = surface_heights(back, path)
    np.testing.assert_array_equal(heights, h)
    assert length == 2.0


def test_measured_line_scan_surface_file(tmp_path):
    surface = read_topography("tests/data/linescans/nonuniform.asc", unit="um", file_unit="um", detrend="height")
    ds = measured_surface_dataset(surface, name="scan")
    assert ds.heights.dims == ("topography", "x") and ds.attrs["surface_dimension"] == 1
    assert '"resampled"' in ds.attrs["source"] and "rms_slope_fd" not in ds
    assert float(ds.undefined_fraction.squeeze()) == 0.0
    path = tmp_path / "m.nc"
    write_dataset(ds, path, stage="surface", scene="t", scene_parameters={"topography": {"path": "x"}})
    assert own_checks(path) == []
    heights, length = surface_heights(read_dataset(path, stage="surface"), path)
    assert heights.shape == (134,) and length == pytest.approx(surface.lengths[0])


def test_bad_profile_surface_file_named():
    ds = xr.Dataset({"heights": (("x",), np.r_[np.zeros(6), np.nan])}, attrs={"surface_dimension": 1, "length": 1.0})
    with pytest.raises(ValueError, match=r"f.nc: 'heights' holds 1 NaN or infinite value\(s\)"):
        surface_heights(ds, "f.nc")
    ds = xr.Dataset({"heights": (("x",), np.arange(8.0))}, attrs={"surface_dimension": 1})
    with pytest.raises(ValueError, match=r"f.nc: the global attribute 'length' \(side of the cell\) is missing"):
        surface_heights(ds, "f.nc")


def test_run_case_on_a_profile_loads_relative_to_its_slope():
    """Loads p0/(E* h') with h' the profile's rms slope; stiffness and the exact full-contact load of a profile;
    the contact file has kappa and no perimeter-corrected area (derived for maps only)."""
    h = generate_profile(512, 4, 32, 0.8, 0, rms_slope=0.1)
    slope = profile_spectral_moments(h)["rms_slope"]
    schedule = LoadSchedule(10, p_max=0.05, relative_to="rms_slope")
    contact = ContactCase(schedule, SolverSettings(e_star=2.0),
                          outputs={"fields": [10], "clusters": False, "stiffness": True, "full_contact_load": True})
    [result] = run_case(h, contact, length=1.0, rms_slope=slope)
    assert result.attrs["load_pbar_max"] == pytest.approx(0.05) and bool(result.converged.all())
    assert result.attrs["load_p0_max"] == pytest.approx(0.05 * 2.0 * slope)
    assert float(result.full_contact_pressure) == pytest.approx(full_contact_load_profile(h, 2.0, 1.0))
    assert result.contact_pressure.dims == ("field_step", "x")
    assert np.isfinite(result.contact_stiffness.values[1:-1]).all()
    ds = contact_dataset(result, rms_slope=slope, alpha=7.0, e_star=2.0, k_l="4", k_s="32", hurst="0.8", seed=0)
    assert "area_fraction_corrected" not in ds and ds.kappa.dims == ("k_l", "k_s", "H", "seed", "step")
    np.testing.assert_allclose(ds.kappa.squeeze(), 2.0 * slope / result.mean_contact_pressure)


def _cases():
    """Eight profiles' contact files as the contact jobs write them (2 k_l x 2 H x 2 seeds), loaded alike."""
    out = []
    contact = ContactCase(LoadSchedule(30, p_max=0.1, relative_to="rms_slope"))
    for kl in ("4", "8"):
        for hurst in ("0.36", "0.84"):
            for seed in range(2):
                h = generate_profile(1024, float(kl), 64, float(hurst), seed, rms_slope=0.1)
                [result] = run_case(h, contact, length=1.0, rms_slope=0.1)
                out.append(contact_dataset(result, rms_slope=0.1, alpha=5.0, e_star=1.0, k_l=kl, k_s="64",
                                           hurst=hurst, seed=seed))
    return out


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_aggregate_and_fit_of_profiles():
    """The generated source's aggregate indexes profiles by (k_l, k_s, H, seed) and step as maps; the CEL fit
    runs on them and reports each group with its seeds. On these profiles
    (16 points per lambda_s) kappa = (A/A0) / pbar falls from ~4.4 to ~2.5 over the window and the paper
    route's log-log slope is mu > 1: the CEL form does not apply, and the fit says so with NaN (van Dokkum
    et al. 2018: no constant kappa for line contacts), which the pipeline carries to the report."""
    datasets = _cases()
    cases = [[kl, "64", hurst, seed] for kl in ("4", "8") for hurst in ("0.36", "0.84") for seed in range(2)]
    agg = SOURCES["generated"].aggregate(datasets, [f"c{i}" for i in range(8)], cases)
    assert dict(agg.sizes) == {"k_l": 2, "k_s": 1, "H": 2, "seed": 2, "step": 30}
    assert agg.attrs["surface_dimension"] == 1 and int(agg.n_unconverged.sum()) == 0
    result = fit.fit_cel(agg, window=(0.01, 0.11), n_boot=10, rng_seed=1, on_insufficient="nan")
    assert list(result.H_group.values) == ["0.36", "0.84", "pooled"]
    assert (result.n_seeds.sel(H_group="0.36") == 2).all() and (result.n_seeds.sel(H_group="pooled") == 4).all()
    mu = result.value.sel(constant="mu", estimator="paper")
    assert np.isnan(mu.values).all()  # mu > 1 on every group: the CEL form does not apply to these profiles


def test_profile_scenes_refuse_what_the_1d_solver_cannot_do():
    block = {"outputs": {"fields": [], "clusters": True}, "effects": {}, "solver": {}}
    with pytest.raises(ConfigError, match=r"scene 's', field 'contact.outputs.clusters': labels a map's contact "
                                          r"clusters; .* \(surface.dimension: 1 makes profiles\); remove it"):
        check_profile_contact("s", block, "surface.dimension: 1 makes profiles")
    block = {"outputs": {"fields": []}, "effects": {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3}},
             "solver": {"e_star": 1.0}}
    with pytest.raises(ConfigError, match="field 'contact.effects.adhesion': the gap iteration"):
        check_profile_contact("s", block, "x")
    with pytest.raises(ConfigError, match="field 'contact.solver.batch': a batch of surfaces solves maps only"):
        check_profile_contact("s", {"outputs": {}, "effects": {}, "solver": {"batch": 4}}, "x")
    contact = {"surface": {"N": 64, "dimension": 1}, "load": {"target_area": 0.1, "n_steps": 30, "schedule": "uniform"},
               "outputs": {"fields": [], "clusters": False}, "effects": {}, "solver": {}}
    with pytest.raises(ConfigError, match=r"0.1 of the 64 nodes of the N = 64 profile is 6.4 node\(s\)"):
        check_contact("s", contact)


def test_dimension_two_written_out_changes_no_job():
    base = {"surface": {"N": 64, "L": 1.0, "plateau": False, "rms_slope": 0.1, "unit": "1"}}
    two = {"surface": {**base["surface"], "dimension": 2}}
    assert surface_params(two) == surface_params(base) and "dimension" not in surface_params(base)
    assert surface_params({"surface": {**base["surface"], "dimension": 1}})["dimension"] == 1


def test_profile_jobs_request_a_profiles_resources():
    """A profile of N points has N nodes, not N^2: its jobs' resource formulas get the side sqrt(N) of the square
    map with as many nodes (N = 4096: 64), so a contact job asks ~300 MB and 5 min, not 5.4 GB and 5 h."""
    assert map_side({"N": 4096, "dimension": 1}) == 64 and map_side({"N": 4096}) == 4096
    assert contact_mem_mb(map_side({"N": 4096, "dimension": 1})) < 310 < 5000 < contact_mem_mb(4096)
    assert contact_runtime_min(map_side({"N": 4096, "dimension": 1}), 30) == 5
