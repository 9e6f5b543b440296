"""roughcontact.pipeline.targets: what the rules ask of a scene, tested without Snakemake's planner.

The dry runs of every shipped scene (tests/test_workflow.py) check the same functions through Snakemake;
here each is called directly with a job's wildcards, on the shipped config.
"""

import copy
import re
from types import SimpleNamespace

import pytest
from snakemake.exceptions import WorkflowError

from roughcontact.figures.registry import FIGURES
from roughcontact.pipeline import targets as t
from roughcontact.pipeline.targets import Targets
from roughcontact.studies.accuracy import variants


def wildcards(scene="demo", **values):
    return SimpleNamespace(scene=scene, **values)


@pytest.fixture(scope="module")
def targets(repo, shipped_config):
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(repo)  # the measured scene's files are relative to the workflow's folder
        return Targets.from_config(shipped_config, variants, FIGURES)


@pytest.fixture
def case(targets):
    """A case of the demo scene's contact grid: its first values."""
    grid = targets.scenes["demo"]["contact"]["grid"]
    return dict(k_l=grid["k_l"][0], k_s=grid["k_s"][0], H=grid["H"][0], seed="0")


def test_the_config_is_validated_once_into_scenes(targets, shipped_config):
    assert targets.active == shipped_config["scene"]
    assert set(targets.scenes) | set(targets.invalid) == set(shipped_config["scenes"])
    assert targets.invalid == {}


def test_an_invalid_config_is_one_workflow_error(shipped_config):
    bad = copy.deepcopy(shipped_config)
    bad["scene"] = "nowhere"
    with pytest.raises(WorkflowError, match="^invalid config: "):
        Targets.from_config(bad, variants, FIGURES)


def test_file_patterns():
    assert t.case_path("contact") == "results/{scene}/contact/kl{k_l}_ks{k_s}_H{H}_s{seed}.nc"
    assert t.case_path("logs/contact", "log") == "results/{scene}/logs/contact/kl{k_l}_ks{k_s}_H{H}_s{seed}.log"
    assert t.batch_path("representativity") == "results/{scene}/representativity/kl{k_l}_H{H}.nc"
    assert t.topography_path("surfaces", "tsv") == "results/{scene}/surfaces/{topography}.tsv"


@pytest.mark.parametrize("name, generated", [("kl4_ks32_H0.8_s0.nc", True), ("kl4_H0.8.nc", True),
                                             ("surface-a.x3p", False), ("kl4.nc", False)])
def test_a_named_case_never_looks_generated(name, generated):
    pattern = re.compile(t.WILDCARD_CONSTRAINTS["topography"] + "$")
    assert (pattern.match(name) is None) == generated


def test_resources_follow_n():
    assert t.surface_mem_mb(1024) == 330
    assert t.contact_mem_mb(1024) == 620
    assert t.surface_runtime_min(256) == 5 and t.surface_runtime_min(4096) == 80
    assert t.contact_runtime_min(1024, 30) == 20 and t.contact_runtime_min(256, 30) == 5
    block = {"surface": {"N": 4096}, "seeds": 30, "grid": {"k_s": ["a"] * 6}}
    assert t.batch_runtime_min(block) == 144


def test_file_mem_mb_reads_the_file_size(tmp_path):
    path = tmp_path / "h.npy"
    path.write_bytes(b"\0" * 2**21)  # 2 MiB: about 1 M points
    assert t.file_mem_mb(path) == 300 + 160 * 8


def test_scene_targets_are_what_the_blocks_ask(targets):
    out = targets.scene_targets("demo")
    assert out[:4] == ["results/demo/aggregate/representativity.nc", "results/demo/aggregate/contact.nc",
                       "results/demo/fit/cel.nc", "results/demo/fit/cel.csv"]
    assert out[-4:] == [f"results/demo/report/{name}.rst" for name in ("result", "summary", "figures", "run")]
    assert "results/demo/figures/kappa.caption.rst" in out  # the caption true of the figure drawn
    figures = [p for p in out if "/figures/" in p]
    assert figures[:2] == ["results/demo/figures/representativity.png", "results/demo/figures/representativity.pdf"]
    adhesive = targets.scene_targets("adhesion")
    assert not any("/fit/" in p for p in adhesive)  # no CEL fit of adhesive contact
    # the run record waits for every other output, so that its CPU time is the whole run's
    record = targets.run_record_inputs(type("W", (), {"scene": "demo"})())
    assert record == out[:-1]
    assert targets.report_figure_inputs(type("W", (), {"scene": "demo"})())["caption"][-2:] == [
        "results/demo/figures/dpbar.caption.rst", "results/demo/figures/contact_map.caption.rst"]
    assert "results/accuracy/accuracy/summary.md" in targets.scene_targets("accuracy")


def test_an_adhesive_scene_without_unloading_asks_for_no_pull_off(targets, repo, shipped_config):
    """The hysteresis and pull-off figures and the pull-off table read the unloading branch's variables, which a
    scene with ``unloading: false`` does not compute: it asks for none of them (and still for no CEL fit)."""
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["adhesion"]["contact"]["effects"]["adhesion"]["unloading"] = False
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(repo)
        unloaded = Targets.from_config(cfg, variants, FIGURES)
    shipped, without = targets, unloaded
    assert {"hysteresis", "pull_off"} <= set(shipped.scene_figures(shipped.scenes["adhesion"]))
    assert not {"hysteresis", "pull_off"} & set(without.scene_figures(without.scenes["adhesion"]))
    assert not any("/fit/" in p for p in without.scene_targets("adhesion"))


def test_a_case_in_the_grid_passes(targets, case):
    block = targets.check_case(wildcards(**case), "contact")
    assert block is targets.scenes["demo"]["contact"]
    path = targets.case_input("contact", "surfaces")(wildcards(**case))
    assert path == f"results/demo/surfaces/kl{case['k_l']}_ks{case['k_s']}_H{case['H']}_s0.nc"
    assert targets.case_input("contact")(wildcards(**case)) == []


def test_a_case_outside_the_grid_names_the_allowed_values(targets, case):
    with pytest.raises(WorkflowError, match=r"wildcard k_l=999 is not in the scene; allowed: "):
        targets.check_case(wildcards(**{**case, "k_l": "999"}), "contact")
    with pytest.raises(WorkflowError, match=r"write H=0\.36\)"):
        targets.check_case(wildcards(**{**case, "H": "0.360"}), "contact")
    with pytest.raises(WorkflowError, match="without leading zeros"):
        targets.check_case(wildcards(**{**case, "seed": "01"}), "contact")
    with pytest.raises(WorkflowError, match="seeds 0..2"):
        targets.check_case(wildcards(**{**case, "seed": "3"}), "contact")


def test_a_batch_outside_the_grid_is_refused(targets):
    block = targets.scenes["demo"]["representativity"]
    good = wildcards(k_l=block["grid"]["k_l"][0], H=block["grid"]["H"][0])
    assert targets.batch_input("representativity")(good) == []
    with pytest.raises(WorkflowError, match="wildcard H=2 is not in the scene"):
        targets.batch_params("representativity", dict)(wildcards(k_l=good.k_l, H="2"))


def test_unknown_and_invalid_scenes(targets):
    with pytest.raises(WorkflowError, match="no scene 'nope' in the config; defined scenes: "):
        targets.scene_of("nope")
    broken = Targets({"scenes": {}, "scene": "x", "invalid": {"x": "scene 'x', field 'a': bad"}}, variants, FIGURES)
    with pytest.raises(WorkflowError, match="^invalid config: scene 'x', field 'a': bad$"):
        broken.scene_of("x")
    with pytest.raises(WorkflowError, match="declares no 'accuracy' block"):
        targets.study_block("demo", "accuracy")


def test_files_of_every_case_and_batch(targets):
    files = targets.case_files("demo", "contact", "contact")
    assert len(files) == 12 and all(f.startswith("results/demo/contact/kl") for f in files)
    assert targets.contact_files("demo") == files  # unbatched: one contact job, one file, a case
    assert len(targets.batch_files("demo", "representativity", "representativity")) == 3
    assert targets.case_list("contact")(wildcards())[0] == ["4", "32", "0.36", 0]
    assert targets.study_params("contact", len)(wildcards()) == len(targets.scenes["demo"]["contact"])


def test_named_cases(targets):
    names = targets.patch_names("measured")
    assert names and targets.patch_names("demo") == []
    w = wildcards("measured", topography=names[0])
    assert targets.topography_input("surfaces", "contact")(w) == f"results/measured/surfaces/{names[0]}.nc"
    assert targets.measured_mem_mb(w) == t.file_mem_mb(targets.topography_file(w))
    assert targets.topography_params()(w) == targets.scene_source("measured").reader_settings(
        targets.scenes["measured"], names[0])
    with pytest.raises(WorkflowError, match="is not one of its topography files; allowed: "):
        targets.check_topography(wildcards("measured", topography="nope.x3p"))
    with pytest.raises(WorkflowError, match="has no .* block, so it has no named case 'a.x3p'"):
        targets.check_topography(wildcards("demo", topography="a.x3p"))
    with pytest.raises(WorkflowError, match="its contact cases are named by topography file"):
        targets.check_case(wildcards("measured", k_l="4", k_s="32", H="0.8", seed="0"), "contact")


def test_figures(targets):
    assert targets.figure_inputs(wildcards(figure="area_load")) == {"agg": "results/demo/aggregate/contact.nc",
                                                                   "fit": "results/demo/fit/cel.nc"}
    with pytest.raises(WorkflowError, match="is not a figure of roughcontact"):
        targets.figure_spec(wildcards(figure="nope"))
    with pytest.raises(WorkflowError, match="does not ask for figure 'accuracy'"):
        targets.figure_spec(wildcards(figure="accuracy"))


def test_one_case_studies(targets):
    block = targets.scenes["accuracy"]["accuracy"]
    label = variants(block)[0]["label"]
    w = wildcards("accuracy", variant=label, k_l=block["k_l"], k_s=block["k_s"], H=block["H"][0], seed="0")
    assert targets.accuracy_setting(w)["label"] == label and targets.accuracy_input(w) == []
    files = targets.accuracy_files("accuracy", "{scene}/{label}/{stem}")
    assert files[0] == f"accuracy/{label}/kl{block['k_l']}_ks{block['k_s']}_H{block['H'][0]}_s0"
    with pytest.raises(WorkflowError, match="wildcard variant=nope is not one of its settings; allowed: "):
        targets.accuracy_setting(wildcards("accuracy", variant="nope"))
    with pytest.raises(WorkflowError, match=r"accuracy\.k_l: wildcard k_l=7 is not in the scene"):
        targets.accuracy_setting(wildcards("accuracy", variant=label, k_l="7", k_s=block["k_s"], H="0.8", seed="0"))
    gap = targets.scenes["kappa-gap"]["kappa_gap"]
    name = next(iter(gap["variants"]))
    w = wildcards("kappa-gap", variant=name, k_l=gap["k_l"], k_s=gap["k_s"], H=gap["H"][0], seed="0")
    assert targets.kappa_gap_input(w) == [] and targets.kappa_gap_setting(w) == gap["variants"][name]
    assert targets.kappa_gap_files("kappa-gap", "kappa_gap")[0].startswith(f"results/kappa-gap/kappa_gap/{name}/")
    with pytest.raises(WorkflowError, match="wildcard variant=nope is not one of its variants"):
        targets.kappa_gap_setting(wildcards("kappa-gap", variant="nope"))


def test_keeps_surfaces(targets):
    assert targets.keeps_surfaces("contact") is True  # the demo scene keeps them
