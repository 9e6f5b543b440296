"""Issue 46: each documented option works or is refused before any job, with the field and a remedy.

One test (or parametrized case) per example of the issue, in its classes: an option that could not work
(target_area with seeds, adopt into a patch scene), checks that passed what fails later (pixel sizes,
heights, hardness, CuPy, map shapes against fields), silent results (a target of one node, round-off
"roughness", negative benchmark times), tracebacks (progress, onstart) and unclear messages. Issue 45
item 7: an invalid scene stops only a run of that scene. All fast: validation and small in-process calls.
"""
import copy
import importlib.util

import numpy as np
import pytest
import yaml

from cel_synthetic import simulate_cel_cases
from conftest import REPO
from roughcontact.analysis.aggregate.derived import aggregate_contact
from roughcontact.analysis.fit.grid import fit_cel
from roughcontact.case import run_case
from roughcontact.case.loading import pressure_for_area
from roughcontact.pipeline import adopt, progress, runcost
from roughcontact.pipeline.case import check_case_loads, contact_case, load_schedule
from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.scenes import validate_config
from roughcontact.pipeline.sources import SOURCES

GEN = {"surface": {"N": 32}, "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5"]}, "seeds": 2}
ARRAY = {"files": {"a": {"path": "data/array/patch-a.npy", "pixel_size": 0.5},
                   "b": {"path": "data/array/patch-b.npy", "pixel_size": [0.5, 0.6]}}, "unit": "um"}
MEASURED = {"files": {"ground-a": "data/measured/ground-a.x3p",
                      "ground-c": {"path": "data/measured/ground-c.txt", "file_unit": "nm",
                                   "physical_size": [100000.0, 125000.0]}}, "unit": "um"}


@pytest.fixture(autouse=True)
def _in_repo(monkeypatch):
    monkeypatch.chdir(REPO)  # the scenes' data paths are relative to the workflow's folder


def plan(shipped_config, scene, name="t", **config):
    """The validated ``scene`` run as ``name`` over the shipped config."""
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"][name] = scene
    cfg["scene"] = name
    cfg.update(config)
    return validate_config(cfg)["scenes"][name]


def refused(shipped_config, scene, field, *words):
    with pytest.raises(ConfigError) as info:
        plan(shipped_config, scene)
    msg = str(info.value)
    assert f"scene 't', field '{field}'" in msg and all(w in msg for w in words), msg
    assert "\n" not in msg
    return msg


def _array_file(tmp_path, heights, name="h.npy"):
    path = tmp_path / name
    np.save(path, heights)
    return {"array": {"files": {"a": {"path": str(path), "pixel_size": 0.5}}, "unit": "um"}, "contact": {}}


# --- unclear messages, false docs: text read as a number, null, oneOf fields -------------------------------

@pytest.mark.parametrize("value, words", [
    ([0.5], ["[0.5] (a list of 1) is not what this field takes", "one number (dx = dy) or [dx, dy]"]),
    ("abc", ["'abc' (text) is not what this field takes", "text that reads as a number is read as one"]),
    (True, ["True (a boolean)"]),
])
def test_pixel_size_of_another_form_is_told_the_forms(shipped_config, value, words):
    refused(shipped_config, {"array": {**ARRAY, "pixel_size": value}, "contact": {}}, "array.pixel_size", *words)


def test_pixel_size_text_that_reads_as_a_number_is_one(shipped_config):
    # config/README: text that reads as a number is read as one, also array.pixel_size (a number or a pair)
    files = {"a": {"path": "data/array/patch-a.npy", "pixel_size": "0.5"},
             "b": {"path": "data/array/patch-b.npy", "pixel_size": ["0.5", "0.6"]}}
    scene = plan(shipped_config, {"array": {"files": files, "unit": "um"}, "contact": {}})
    assert [scene["array"]["files"][k]["pixel_size"] for k in "ab"] == [[0.5, 0.5], [0.5, 0.6]]


def test_null_pixel_size_is_absent_and_named(shipped_config):
    block = {"files": {"a": "data/array/patch-a.npy"}, "unit": "um", "pixel_size": None}
    refused(shipped_config, {"array": block, "contact": {}}, "array.files.a.pixel_size", "has no pixel size")


def test_adhesion_null_is_no_adhesion(shipped_config):
    scene = plan(shipped_config, {"contact": {**GEN, "effects": {"adhesion": None}}})
    assert scene["contact"]["effects"] == {}


def test_text_named_npy_is_named_as_text(shipped_config, tmp_path):
    path = tmp_path / "h.npy"
    path.write_text("1 2 3\n4 5 6\n")
    scene = {"array": {"files": {"a": {"path": str(path), "pixel_size": 0.5}}, "unit": "um"}, "contact": {}}
    msg = refused(shipped_config, scene, "array.files.a", "does not start as a .npy file does", "numpy.save")
    assert "pickle" not in msg


# --- physical ranges checked before any job -------------------------------------------------------------

@pytest.mark.parametrize("pixel", [1.0e-300, 1.0e300])
def test_array_pixel_size_outside_float_range(shipped_config, pixel):
    block = {**ARRAY, "files": {"a": {"path": "data/array/patch-a.npy", "pixel_size": pixel}}}
    refused(shipped_config, {"array": block, "contact": {}}, "array.files.a", "pixel size dx", "[1e-50, 1e+50]")


def test_topography_pixel_size_outside_float_range(shipped_config):
    files = {"c": {"path": "data/measured/ground-c.txt", "file_unit": "nm", "physical_size": [1e-70, 1e-70]}}
    refused(shipped_config, {"topography": {"files": files, "unit": "um"}, "contact": {}}, "topography.files.c",
            "pixel size dx = 7.8125e-76 um is outside [1e-50, 1e+50]", "topography.file_unit")


@pytest.mark.parametrize("scale, words", [(1e300, "beyond 1e+100"), (1e-310, "below 1e-100")])
def test_array_heights_outside_float_range(shipped_config, tmp_path, scale, words):
    h = np.load(REPO / "data/array/patch-a.npy").astype(float) * scale
    refused(shipped_config, _array_file(tmp_path, h), "array.files.a", words)


def test_round_off_is_not_roughness(shipped_config, tmp_path):
    h = 1.0 + 1e-15 * np.random.default_rng(0).standard_normal((16, 16))
    refused(shipped_config, _array_file(tmp_path, h), "array.files.a", "round-off, not roughness")


def test_hardness_below_the_final_load_relative_to_the_slope(shipped_config):
    load = {"relative_to": "rms_slope", "p_max": 0.05}
    contact = {**GEN, "surface": {"N": 32, "rms_slope": 0.1}, "load": load,
               "effects": {"plasticity": {"hardness": 0.004}}}
    refused(shipped_config, {"contact": contact}, "contact.effects.plasticity.hardness", "0.05 x 0.1 = 0.005")


@pytest.mark.parametrize("source, block, words", [("array", ARRAY, "array file 'a': 0.05 x 0.09764"),
                                                   ("topography", MEASURED, "topography file 'ground-a': 0.05 x")])
def test_hardness_below_a_files_final_load_is_refused_before_any_job(shipped_config, source, block, words):
    scene = {source: block, "contact": {"effects": {"plasticity": {"hardness": 0.004}}}}
    refused(shipped_config, scene, "contact.effects.plasticity.hardness", words, "raise it or lower load.p_max")
    plan(shipped_config, {source: block, "contact": {"effects": {"plasticity": {"hardness": 0.5}}}})


def test_hardness_below_a_cases_final_load_names_the_field_before_any_solve():
    # a surface normalised by rms height has its slope measured in its job: the loads are checked there
    block = {"load": {"relative_to": "rms_slope", "p_max": 0.05, "n_steps": 3},
             "solver": {"e_star": 1.0, "tol": 1e-8, "max_iter": 100, "boundary": "periodic", "pressure_unit": "1"},
             "effects": {"plasticity": {"hardness": 0.004}}, "outputs": {"fields": [], "clusters": False}}
    case = contact_case(block)
    # the contact job's check, naming the config field and the remedy
    with pytest.raises(ValueError, match=r"contact.effects.plasticity.hardness: 0.004 must exceed this case's final "
                                         r"load p0/E\* = 0.005 .*raise it or lower load.p_max"):
        check_case_loads(case, rms_slope=0.1)
    check_case_loads(case, rms_slope=0.07)
    # the library's own guard (run_case before any solve): the same rule, named by the effect
    with pytest.raises(ValueError, match=r"plasticity.hardness/E\*: 0.004 must exceed this case's final"):
        run_case(np.zeros((8, 8)), case, length=1.0, rms_slope=0.1)
    with pytest.raises(ValueError, match=r"plasticity.hardness/E\*: 0.004 must exceed this case's final"):
        load_schedule(block).check_final_load(case.settings.effects, 1.0, 0.1)


def test_target_area_search_stays_below_the_hardness():
    # the first probe (target E* h' / 2 = 0.025) would exceed the cap 0.02; a capped surface reaches the
    # target below it, and the search finds it there
    def area_at(p):
        assert p < 0.02, p
        return 0.6 * (p / 0.02) ** 0.5
    found = pressure_for_area(area_at, 0.5, e_star=1.0, rms_slope=0.1, n_nodes=4096, p_cap=0.02)
    assert found["reached"] and found["pressure"] < 0.02


def test_cupy_refused_when_it_cannot_be_imported(shipped_config, monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "cupy" else real(name, *a))
    contact = {**GEN, "solver": {"array_backend": "cupy"}}
    refused(shipped_config, {"contact": contact}, "contact.solver.array_backend", "pip install roughcontact[gpu]")
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["t"] = {"contact": contact}
    assert "t" in validate_config(cfg)["scenes"]  # checked for the scene that runs only


@pytest.mark.parametrize("source, block", [("topography", MEASURED), ("array", ARRAY)])
def test_fields_with_maps_of_different_shapes(shipped_config, source, block):
    scene = {source: block, "contact": {"outputs": {"fields": [3]}}}
    msg = refused(shipped_config, scene, "contact.outputs.fields", "grids differ", "remove outputs.fields")
    assert "x 160 points" in msg or "96 x 80 points" in msg


def test_fields_with_maps_of_different_pixel_sizes(shipped_config):
    files = {"a": {"path": "data/array/patch-a.npy", "pixel_size": 0.5},
             "b": {"path": "data/array/patch-a.npy", "pixel_size": 0.6}}
    scene = {"array": {"files": files, "unit": "um"}, "contact": {"outputs": {"fields": [3]}}}
    refused(shipped_config, scene, "contact.outputs.fields", "128 x 128 points of 0.5 x 0.5, b 128 x 128 points of 0.6")
    files["b"]["pixel_size"] = 0.5 * (1 + 1e-13)  # round-off of a unit conversion: one grid
    plan(shipped_config, scene)


# --- silent results ---------------------------------------------------------------------------------------

def test_target_area_of_one_node_is_refused(shipped_config):
    contact = {**GEN, "load": {"target_area": 1.0e-6}}
    refused(shipped_config, {"contact": contact}, "contact.load.target_area", "1024 nodes", "15 nodes")
    array = {"array": ARRAY, "contact": {"load": {"target_area": 1.0e-4}}, "fit": {"window": [1e-5, 0.1]}}
    refused(shipped_config, array, "contact.load.target_area", "array file 'a' (128 x 128)")


def test_target_area_below_the_fit_window_is_refused(shipped_config):
    contact = {**GEN, "surface": {"N": 256}, "load": {"target_area": 0.005}}
    refused(shipped_config, {"contact": contact}, "contact.load.target_area", "below fit.window's low end 0.01")


def test_negative_benchmark_times_are_refused(tmp_path):
    bench = tmp_path / "x.tsv"
    bench.write_text("s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
                     "-5.0\t0:00:05\t100\t1\t1\t1\t0\t0\t50\t-2.5\n")
    with pytest.raises(ValueError, match=r"x.tsv: s = '-5.0' is negative"):
        runcost.read_benchmark(bench)


# --- an option that could not work ------------------------------------------------------------------------

def test_target_area_with_seeds_fits_each_seeds_own_schedule():
    # seeds loaded by target_area end at their own p0: fit_cel 'auto' (the pipeline's) fits every point
    agg = aggregate_contact(*simulate_cel_cases(seeds=range(4), point_noise=1e-3, seed_scatter=0.0, area_max=0.13,
                                                rng_seed=0))
    agg["pressure"] = agg["pressure"] * (1 + 0.01 * agg["seed"])  # each seed its own schedule
    agg["mean_contact_pressure"] = agg["pressure"] / agg["area_fraction"]
    agg = agg.drop_vars(["kappa", "dpbar_dp0"])
    with pytest.raises(ValueError, match="load.target_area"):
        fit_cel(agg, n_boot=10)  # the message names config keys, not only a function argument
    fit = fit_cel(agg, n_boot=10, paper_average="auto")
    assert fit.attrs["paper_average"] == "none"
    assert np.isfinite(fit["value"].sel(estimator="paper")).all()


def test_target_area_with_seeds_plans(shipped_config):
    scene = plan(shipped_config, {"contact": {**GEN, "surface": {"N": 64}, "load": {"target_area": 0.1}}})
    assert scene["contact"]["load"]["target_area"] == 0.1 and "p_max" not in scene["contact"]["load"]


def test_adopt_into_a_batched_scene_is_refused_in_one_line(tmp_path, monkeypatch, capsys):
    # a batched scene's cases are groups of its batches' files (one contact job a batch): a copied case file
    # would be read by nothing
    config = tmp_path / "batched.yaml"
    config.write_text(yaml.safe_dump({"scenes": {"batched": {"contact": {**GEN, "surface": {"N": 64},
                                                                         "solver": {"batch": 2}}}}}))
    with pytest.raises(SystemExit) as stop:
        adopt.main(["results/adhesion", "--scene", "batched", "--configfile", str(config), "--dry-run"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert "solves its seeds in batches (contact.solver.batch: 2)" in err and "without solver.batch" in err


@pytest.mark.parametrize("target", ["measured", "array"])
def test_adopt_into_a_patch_scene_is_refused_in_one_line(capsys, target):
    with pytest.raises(SystemExit) as stop:
        adopt.main(["results/adhesion", "--scene", target, "--dry-run"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert f"scene '{target}' takes its surfaces from its" in err and "generated cases" in err


# --- the measured scene's loads, as config/README says --------------------------------------------------

def test_p_max_default_follows_relative_to(shipped_config):
    topo = {"files": {"ground-a": "data/measured/ground-a.x3p"}, "unit": "um"}
    e_star = plan(shipped_config, {"topography": topo, "contact": {"load": {"relative_to": "e_star"}}})
    slope = plan(shipped_config, {"contact": {**GEN, "load": {"relative_to": "rms_slope"}}})
    assert e_star["contact"]["load"]["p_max"] == 0.005 and slope["contact"]["load"]["p_max"] == 0.05


def test_per_file_settings_are_no_surprise():
    measured = SOURCES["measured"]
    assert measured.unexpected_settings(["topography.file_unit", "topography.path"]) == []
    assert measured.unexpected_settings(["topography.detrend"]) == ["topography.detrend"]
    assert SOURCES["generated"].unexpected_settings(["surface.N"]) == ["surface.N"]


# --- tracebacks -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, words", [
    ("{bad", "not valid JSON at line 1"),
    ("[]", "holds a JSON list"),
    ('{"total": -5}', "'scene' is None, not a str"),
    ('{"scene": "x", "cores": 0, "jobs": []}', "cores = 0 must be >= 1"),
    ('{"scene": "x", "cores": 2, "jobs": [{"rule": "contact"}]}', "jobs[0] is {'rule': 'contact'}, not a job"),
])
def test_progress_on_a_corrupt_plan_says_so_in_one_line(tmp_path, capsys, text, words):
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "plan.json").write_text(text)
    with pytest.raises(SystemExit) as stop:
        progress.main([str(tmp_path)])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and "plan.json" in err and words in err, err


# --- issue 45 item 7: an invalid scene stops only a run of that scene -----------------------------------

def test_an_invalid_scene_stops_only_its_own_run(shipped_config):
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["broken"] = {"contact": {**GEN, "seeds": 0}}
    valid = validate_config(cfg)
    assert valid["scene"] == "demo" and "demo" in valid["scenes"] and "broken" not in valid["scenes"]
    assert valid["invalid"]["broken"].startswith("scene 'broken', field 'contact.seeds'")
    with pytest.raises(ConfigError, match="scene 'broken', field 'contact.seeds'"):
        validate_config({**cfg, "scene": "broken"})
    with pytest.raises(ConfigError, match="scene 'broken'"):
        validate_config(cfg, strict=True)


def test_the_config_check_names_an_invalid_other_scene_and_plans_the_run(tmp_path, capsys):
    from roughcontact.pipeline.scenes import main

    extra = tmp_path / "extra.yaml"
    extra.write_text("scenes:\n  broken:\n    contact: {surface: {N: 32}, grid: {k_l: ['2'], k_s: ['8'], H: ['0.5']}, "
                     "seeds: 0}\n")
    main([str(extra)])
    out, err = capsys.readouterr()
    assert out.startswith("roughcontact: scene 'demo' plans")
    assert err.count("\n") == 1 and err.startswith("warning: scene 'broken', field 'contact.seeds'"), err
    with pytest.raises(SystemExit) as stop:
        main([str(extra), "--scene", "broken"])
    assert stop.value.code == 2 and "error: scene 'broken', field 'contact.seeds'" in capsys.readouterr().err


@pytest.mark.parametrize("source, block, words", [
    ("array", ARRAY, "array file 'a': the adhesive process zone"),
    ("topography", MEASURED, "topography file 'ground-a': the adhesive")])
def test_an_adhesive_zone_a_files_grid_cannot_resolve_is_refused_before_any_job(shipped_config, source, block, words):
    # work 1e-3 um (w / E*), range 1e-3 um: the zone range^2 / work = 1e-3 um spans 0.002 pixels of 0.5 um
    # (the array files) or 0.0013 of 0.78 um (the measured ones)
    contact = {"solver": {"boundary": "periodic"},
               "effects": {"adhesion": {"law": "exponential", "work": 1e-3, "range": 1e-3}}}
    refused(shipped_config, {source: block, "contact": contact}, "contact.effects.adhesion", words,
            "fewer than 1.5", "refine the grid")
    # a range of 0.1 um: the zone is 10 um, 12.8 pixels of 0.78 um, 16.7 of the array's 0.6 um
    contact["effects"]["adhesion"]["range"] = 0.1
    plan(shipped_config, {source: block, "contact": contact})
