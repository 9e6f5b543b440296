"""A scene computes what it calls for and nothing else: jobs planned and variables written."""
import copy
import re

import numpy as np
import pytest
import xarray as xr

from conftest import copy_workflow, run_snakemake
from test_workflow import TINY, _jobs

CASE = "results/tiny/contact/kl2_ks8_H0.5_s0.nc"


def _scene(**contact_extra):
    cfg = copy.deepcopy(TINY)
    cfg["scenes"]["tiny"]["contact"].update(contact_extra)
    return cfg


#: The tiny scene's contact block extended by each optional output and effect, a scene each.
VARIANTS = {
    "base": {},
    "fields": {"outputs": {"fields": [3, 12]}},
    "plastic": {"effects": {"plasticity": {"hardness": 0.02}}},
    "clusters": {"outputs": {"clusters": True}},
    "adhesion": {"effects": {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3}}},
}


def _variables(tmp_path) -> dict:
    """Each variant's case file (one Snakemake run of every scene's one case, side by side): name -> (variables,
    dataset)."""
    cfg = _scene()
    for name, extra in VARIANTS.items():
        cfg["scenes"][name] = copy.deepcopy(_scene(**extra)["scenes"]["tiny"])
    wd = copy_workflow(tmp_path / "wf", cfg)
    targets = [CASE.replace("results/tiny/", f"results/{name}/") for name in VARIANTS]
    res = run_snakemake(wd, "-j2", *targets)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    out = {}
    for name, target in zip(VARIANTS, targets, strict=True):
        with xr.open_dataset(wd / target) as ds:
            out[name] = (set(ds.variables), ds.load())
    return out


@pytest.mark.slow
def test_optional_outputs_and_effects_add_exactly_their_variables(tmp_path):
    runs = _variables(tmp_path)
    base, ds_base = runs["base"]
    fields, ds_f = runs["fields"]
    plastic, ds_p = runs["plastic"]
    clusters, ds_c = runs["clusters"]
    assert clusters - base == {"cluster_count", "cluster_mean_area", "cluster_max_area", "cluster_area_histogram",
                               "area_bin", "area_bin_low", "area_bin_high", "cluster_wrapping", "connectivity"}
    assert int(ds_c["cluster_count"].min()) >= 1
    assert fields - base == {"contact_pressure", "gap", "field_step", "x", "y"}
    assert not base - fields
    assert ds_f["contact_pressure"].shape[-2:] == (32, 32)
    assert ds_f["field_step"].values.tolist() == [3, 12]
    assert plastic - base == {"plastic_area_fraction", "plastic_load_fraction"}
    assert float(ds_p["plastic_area_fraction"].max()) > 0
    adhesive, ds_a = runs["adhesion"]
    assert adhesive - base == {"adhesive_pressure", "adhesive_area_fraction", "adhesive_zone_cells",
                               "unload_mean_gap", "unload_mean_pressure", "unload_area_fraction",
                               "unload_converged", "unload_unconverged_steps", "pull_off_pressure", "pull_off_status",
                               "attraction_across_cell"}
    assert ds_a.attrs["adhesion_law"] == "exponential" and ds_a.attrs["elastic_method"] == "adhesive"
    assert bool(ds_a["converged"].all()) and float(ds_a["pull_off_pressure"].min()) > 0
    assert ds_a.attrs["solver"] == "roughcontact.solver.adhesion.AdhesiveIteration"
    assert int(ds_a["pull_off_status"].squeeze()) == 0 and float(ds_a["adhesive_zone_cells"].squeeze()) >= 1.5
    # adhesion pulls more of the surface into contact at every load
    assert np.all(ds_a["area_fraction"].values > ds_base["area_fraction"].values)


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_scene_without_contact_block_plans_no_contact_jobs(tmp_path):
    cfg = copy.deepcopy(TINY)
    del cfg["scenes"]["tiny"]["contact"]
    wd = copy_workflow(tmp_path / "rep", cfg)
    res = run_snakemake(wd, "-n")
    assert res.returncode == 0, res.stderr[-2000:]
    jobs = _jobs(res.stdout)
    assert "representativity" in jobs
    assert not {"surface", "contact", "aggregate_contact", "fit_cel"} & set(jobs)
    assert _figures(res.stdout + res.stderr) == {"representativity", "surface_examples"}
    cfg = copy.deepcopy(TINY)
    del cfg["scenes"]["tiny"]["representativity"]
    wd = copy_workflow(tmp_path / "con", cfg)
    res = run_snakemake(wd, "-n")
    jobs = _jobs(res.stdout)
    assert "contact" in jobs and not {"surface_rep", "representativity"} & set(jobs)
    assert _figures(res.stdout + res.stderr) == {"area_load", "kappa", "dpbar"}


def _figures(log):
    """Names of the figures a dry run plans."""
    return set(re.findall(r"output: results/tiny/figures/(\w+)\.png", log))
