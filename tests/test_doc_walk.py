"""The documentation walked (issue 46): every option of config/README.md with every source, every command.

Each key of config/README.md's tables (parsed from the file, so a new row must bring its sample here) is
set, one at a time, in a tiny scene of each surface source (generated, measured, array; two seeds or two
files each): the scene either plans (the planning checks pass and everything the workflow asks of a valid
scene answers: the plan line, cases, file stems, job parameters, figures, planned solves, loads) or is
refused with a one-line ``ConfigError`` naming the scene; every key plans with at least one source. A few
combinations are dry-run by Snakemake, and two run for real (slow). Every ``python -m roughcontact...``
module the docs name is run on a missing path, an empty folder and a corrupt input: exit status 2, one
line on stderr, no traceback.
"""
import copy
import re
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr
import yaml

from conftest import REPO, copy_workflow, run_snakemake
from roughcontact.figures.registry import scene_figures
from roughcontact.pipeline import params, progress
from roughcontact.pipeline.case import load_schedule
from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.scenes import plan_summary, validate_config
from roughcontact.pipeline.sources import source_of
from roughcontact.studies.accuracy import variants as accuracy_variants

GRID = {"surface": {"N": 32}, "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5"]}, "seeds": 2}
#: The tiny scene of each source: two seeds, or two files.
BASES = {
    "generated": {"representativity": {**GRID, "surface": {"N": 32, "rms_height": 0.1}, "examples": []},
                  "contact": {**GRID, "load": {"n_steps": 3}}},
    "measured": {"topography": {"files": {"ground-a": "data/measured/ground-a.x3p",
                                          "ground-b": "data/measured/ground-b.nc"},
                                "unit": "um", "undefined": "harmonic"},
                 "representativity": {"n_bins": 20}, "contact": {"load": {"n_steps": 3}}},
    "array": {"array": {"files": {"a": {"path": "data/array/patch-a.npy", "pixel_size": 0.5},
                                  "b": {"path": "data/array/patch-b.npy", "pixel_size": [0.5, 0.6]}},
                        "unit": "um"},
              "representativity": {"n_bins": 20}, "contact": {"load": {"n_steps": 3}}},
}

#: Where each section's keys live in a scene (config/README.md's headings).
SECTIONS = {"Scene block": (), "Shared by both studies": ("contact",), "`representativity`": ("representativity",),
            "`contact`": ("contact",), "`topography`: your own measured surfaces": ("topography",),
            "`array`: surfaces from NumPy arrays": ("array",), "`accuracy`": ("accuracy",),
            "`kappa_gap`": ("kappa_gap",), "`fit`": ("fit",)}
#: Keys of the config's top level (the walk's own config uses each) and the shipped scenes (walked below).
TOP_LEVEL = ["scene", "defaults", "scenes"]


def _adhesion(key, value):
    return lambda scene: _put(scene, ("contact", "effects", "adhesion"),
                              {"law": "exponential", "work": 1e-5, "range": 1e-3, key: value})


def _put(scene, path, value):
    node = scene
    for part in path[:-1]:
        node = node.setdefault(part, {}) if isinstance(node.get(part), dict) or part not in node else node[part]
    node[path[-1]] = value


def _glob(scene):
    if "topography" in scene:
        scene["topography"].pop("files")
    _put(scene, ("topography", "glob"), "data/measured/ground-[ab].*")


def _format(scene):
    _put(scene, ("topography", "files"), {"ground-a": "data/measured/ground-a.x3p"})
    _put(scene, ("topography", "format"), "x3p")


def _block_pixel_size(scene):
    _put(scene, ("array", "files"), {"a": "data/array/patch-a.npy", "b": "data/array/patch-b.npy"})
    _put(scene, ("array", "pixel_size"), 0.25)


def _rms_height(scene):
    _put(scene, ("contact", "surface", "rms_slope"), None)
    _put(scene, ("contact", "surface", "rms_height"), 0.1)


def _p_min(scene):
    _put(scene, ("contact", "load", "schedule"), "geometric")
    _put(scene, ("contact", "load", "p_min"), 0.001)


#: Samples per documented key (a value set at the key's place, or a function editing the scene): one or more.
SAMPLES = {
    "Scene block": {"description": ["a walk"], "representativity": [{"n_bins": 20}], "contact": [{}],
                    "accuracy": [{}], "kappa_gap": [{}], "fit": [{"n_boot": 20}],
                    "topography": [{"files": {"ground-a": "data/measured/ground-a.x3p"}, "unit": "um"}],
                    "array": [{"files": {"a": {"path": "data/array/patch-a.npy", "pixel_size": 1.0}}, "unit": "nm"}]},
    "Shared by both studies": {"surface.N": [64], "surface.L": [2.0], "surface.rms_slope": [0.2],
                               "surface.rms_height": [_rms_height], "surface.plateau": [True],
                               "surface.dimension": [1, 2],
                               "grid.k_l": [["1", "2"]], "grid.k_s": [["8", "16"]], "grid.H": [["0.3", "0.8"]],
                               "seeds": [3], "keep_surfaces": [False]},
    "`representativity`": {"n_bins": [20], "examples": [[{"k_l": "2", "k_s": "8"}]]},
    "`contact`": {
        "load.p_max": [0.01], "load.relative_to": ["rms_slope", "e_star"], "load.target_area": [0.05, 0.5],
        "load.n_steps": [5], "load.schedule": ["geometric"], "load.p_min": [_p_min], "solver.e_star": [2.0],
        "solver.tol": [1e-6], "solver.max_iter": [100], "solver.array_backend": ["numpy", "cupy"],
        "solver.batch": [2, 1], "solver.ranks": [2, 1],
        "outputs.fields": [[1]], "outputs.clusters": [True],
        "outputs.pressure_distribution": [{"bins": 10, "max": 5.0}], "outputs.stiffness": [True],
        "outputs.full_contact_load": [True], "effects.plasticity.hardness": [0.5, 0.004],
        "effects.adhesion.law": [_adhesion("law", "exponential")], "effects.adhesion.work": [_adhesion("work", 2e-5)],
        "effects.adhesion.range": [_adhesion("range", 2e-3)],
        "effects.adhesion.unloading": [_adhesion("unloading", False)],
        "effects.adhesion.pull_off_rtol": [_adhesion("pull_off_rtol", 1e-2)], "solver.boundary": ["free", "periodic"],
        # documented in prose (Units), not in the table
        "surface.unit": ["um"], "solver.pressure_unit": ["MPa"]},
    "`topography`: your own measured surfaces": {
        "files": [{"x": "data/measured/ground-a.x3p"}], "glob": [_glob], "unit": ["nm"], "file_unit": ["m"],
        "physical_size": [[100.0, 100.0]], "undefined": ["mean"], "detrend": ["curvature"],
        "non_square": ["crop", "reject"], "channel": [0], "format": [_format], "max_undefined": [0.2]},
    "`array`: surfaces from NumPy arrays": {
        "files": [{"x": {"path": "data/array/patch-a.npy", "pixel_size": 1.0}}], "unit": ["nm"],
        "pixel_size": [_block_pixel_size]},
    "`accuracy`": {"surface.L": [2.0], "surface.rms_slope": [0.2], "k_l": ["8"], "k_s": ["32"], "H": [["0.5"]],
                   "p_max": [0.01], "reference": [{"N": "1024", "tol": "1e-10", "n_steps": "30"}],
                   "defaults": [{"N": "512", "tol": "1e-8", "n_steps": "30"}], "axes.N": [["256"]],
                   "axes.tol": [["1e-6"]], "axes.n_steps": [["10"]], "seeds": [2], "seed_axis": [["1", "2"]],
                   "kappa_at": [0.1], "n_boot": [20]},
    "`kappa_gap`": {"surface.L": [2.0], "surface.rms_slope": [0.2], "k_l": ["8"], "k_s": ["32"], "H": [["0.5"]],
                    "gap_thresholds": [["1e-3"]], "variants.NAME.role": ["baseline"], "variants.NAME.N": ["2048"],
                    "variants.NAME.seeds": [2], "variants.NAME.method": ["bem"], "variants.NAME.tol": ["1e-6"],
                    "variants.NAME.p_max": [0.01], "variants.NAME.n_steps": [10],
                    "variants.NAME.schedule": ["geometric"]},
    "`fit`": {"window": [[0.02, 0.2]], "n_boot": [20], "rng_seed": [1], "include_unconverged": [True]},
}
#: Prose keys walked with the contact table's (config/README.md documents them under Units).
PROSE = {"surface.unit", "solver.pressure_unit"}


def documented_keys() -> dict[str, list[str]]:
    """The keys of each table of config/README.md, by section heading (``.x`` cells expand their prefix)."""
    out, section = {}, None
    for line in (REPO / "config" / "README.md").read_text().splitlines():
        heading = re.match(r"^#{2,3} (.*)", line)
        if heading:
            section = heading.group(1)
        elif line.startswith("| `"):
            prefix = ""
            for token in re.findall(r"`([^`]+)`", line.split("|")[1]):
                if token.startswith("."):
                    token = prefix + token[1:]
                prefix = token.rsplit(".", 1)[0] + "." if "." in token else ""
                out.setdefault(section, []).append(token)
    return out


def test_every_documented_key_has_a_sample():
    keys = documented_keys()
    assert keys.pop("Top level") == TOP_LEVEL
    shipped = keys.pop("Shipped scenes")
    assert set(shipped) <= set(yaml.safe_load((REPO / "config" / "config.yaml").read_text())["scenes"])
    assert set(keys) == set(SECTIONS), "a new section of config/README.md: add it to SECTIONS and SAMPLES"
    for section, names in keys.items():
        missing = set(names) - set(SAMPLES[section])
        assert not missing, f"config/README.md documents {sorted(missing)} ({section}): add a sample to SAMPLES"
        assert set(SAMPLES[section]) - set(names) <= PROSE, f"SAMPLES[{section!r}] has keys the docs do not list"


def _apply(base, section, key, sample):
    scene = copy.deepcopy(base)
    if callable(sample):
        sample(scene)
        return scene
    path = (*SECTIONS[section], *key.replace("NAME", "baseline").split("."))
    if section == "`kappa_gap`" and key.startswith("variants."):  # one variant of the defaults' replaced
        _put(scene, ("kappa_gap", "variants", "baseline"), {"role": "baseline", "N": "1024", "seeds": 1})
    _put(scene, path, copy.deepcopy(sample))
    return scene


def _plans(name, scene):
    """Everything the workflow asks of a valid scene before its jobs: nothing may raise."""
    source = source_of(scene, name)
    assert plan_summary(name, scene).startswith(f"roughcontact: scene {name!r} plans")
    for study in ("representativity", "contact"):
        if study in scene:
            assert source.stems(scene, study) and source.case_list(scene, study)
            source.batch_stems(scene, study)
            params.representativity(scene[study]) if study == "representativity" else params.contact(scene[study])
    if "contact" in scene:
        block = scene["contact"]
        if "surface" in block:
            params.surface(block)
        if "target_area" not in block["load"]:
            loads = load_schedule(block).pressures(block["solver"]["e_star"], rms_slope=0.1)
            assert len(loads) == block["load"]["n_steps"] and loads[-1] > 0
        assert progress.planned_solves(scene) > 0
        params.fit(scene)
    if "accuracy" in scene:
        assert accuracy_variants(scene["accuracy"])
    if "kappa_gap" in scene:
        for label in scene["kappa_gap"]["variants"]:
            params.kappa_gap_case(scene["kappa_gap"], label)
    scene_figures(scene)
    params.summary(scene)


def _outcome(shipped_config, scene) -> str:
    # the shipped defaults and this scene alone (every shipped scene is walked once, below)
    cfg = {"defaults": copy.deepcopy(shipped_config["defaults"]), "scenes": {"walk": scene}, "scene": "walk"}
    try:
        valid = validate_config(cfg)["scenes"]["walk"]
    except ConfigError as err:
        msg = str(err)
        assert "\n" not in msg and msg.startswith("scene 'walk'"), msg
        return "refused"
    _plans("walk", valid)
    return "plans"


CASES = [(section, key, i) for section, keys in SAMPLES.items() for key, values in keys.items()
         for i in range(len(values))]


@pytest.mark.parametrize("section, key, i", CASES, ids=[f"{s.split('`')[1] if '`' in s else s}:{k}:{i}"
                                                        for s, k, i in CASES])
def test_each_option_with_each_source_plans_or_is_refused(shipped_config, monkeypatch, section, key, i):
    monkeypatch.chdir(REPO)
    sample = SAMPLES[section][key][i]
    outcomes = {src: _outcome(shipped_config, _apply(base, section, key, sample)) for src, base in BASES.items()}
    documented_error = (section, key, i) in {("`contact`", "effects.plasticity.hardness", 1),
                                             ("`contact`", "solver.array_backend", 1),
                                             ("`topography`: your own measured surfaces", "non_square", 1)}
    assert "plans" in outcomes.values() or documented_error, f"{key} = {sample!r} plans with no source: {outcomes}"


def test_each_base_scene_plans(shipped_config, monkeypatch):
    monkeypatch.chdir(REPO)
    for src, base in BASES.items():
        assert _outcome(shipped_config, copy.deepcopy(base)) == "plans", src


@pytest.mark.parametrize("scene", documented_keys()["Shipped scenes"])
def test_each_shipped_scene_plans_as_the_one_run(shipped_config, monkeypatch, scene):
    monkeypatch.chdir(REPO)
    valid = validate_config({**copy.deepcopy(shipped_config), "scene": scene})
    assert not valid["invalid"]
    _plans(scene, valid["scenes"][scene])


# --- Snakemake's own planning on a few combinations, and an invalid scene beside them ----------------------

OUTPUTS = {"clusters": True, "pressure_distribution": {"bins": 10, "max": 5.0}, "stiffness": True}
#: Tiny scenes bundling the documented options each source takes (two seeds, two files each), and one invalid.
WALK_SCENES = {
    "gen-target": {"contact": {**GRID, "surface": {"N": 32}, "load": {"target_area": 0.3, "n_steps": 8},
                               "effects": {"plasticity": {"hardness": 0.01}}}, "fit": {"window": [0.01, 0.3]}},
    "gen-all": {"representativity": {**GRID, "surface": {"N": 32, "rms_height": 0.1, "plateau": True}, "n_bins": 20,
                                     "examples": [{"k_l": "2", "k_s": "8"}]},
                "contact": {**GRID, "surface": {"N": 32, "L": 2.0, "unit": "um"},
                            "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5", "0.8"]},
                            "load": {"n_steps": 4, "schedule": "geometric", "p_min": 0.001},
                            "solver": {"tol": 1e-6, "e_star": 2.0, "pressure_unit": "MPa"},
                            "outputs": {**OUTPUTS, "fields": [4], "full_contact_load": True}},
                "fit": {"n_boot": 20, "window": [0.01, 0.3], "include_unconverged": True}},
    "gen-plastic": {"contact": {**GRID, "load": {"n_steps": 4, "relative_to": "rms_slope", "p_max": 0.05},
                                "effects": {"plasticity": {"hardness": 0.5}}, "outputs": {"clusters": True,
                                                                                          "fields": [2]},
                                "keep_surfaces": False}},
    "gen-adhesion": {"contact": {**GRID, "load": {"n_steps": 3}, "outputs": {"clusters": True, "stiffness": True},
                                 "effects": {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3}}}},
    # per-file settings, one in metres and one in nanometres cropped square: one grid within round-off
    "files": {"topography": {"files": {"ground-a": {"path": "data/measured/ground-a.x3p", "file_unit": "m"},
                                       "ground-c": {"path": "data/measured/ground-c.txt", "file_unit": "nm",
                                                    "physical_size": [100000.0, 125000.0]}},
                             "unit": "um", "non_square": "crop", "detrend": "curvature"},
              "representativity": {"n_bins": 20},
              "contact": {"load": {"n_steps": 4}, "outputs": {**OUTPUTS, "fields": [4]}}},
    "files-target": {"topography": {"glob": "data/measured/ground-[ab].*", "unit": "um", "undefined": "mean",
                                    "max_undefined": 0.2},
                     "contact": {"load": {"n_steps": 3, "target_area": 0.1},
                                 "effects": {"plasticity": {"hardness": 0.5}}}},
    "array-all": {"array": {"files": {"a": "data/array/patch-a.npy", "b": "data/array/patch-a.npy"}, "unit": "um",
                            "pixel_size": 0.5},
                  "representativity": {"n_bins": 20},
                  "contact": {"load": {"n_steps": 3, "target_area": 0.1}, "effects": {"plasticity": {"hardness": 0.5}},
                              "outputs": {**OUTPUTS, "fields": [3]}}},
    "array-periodic": {"array": {"files": {"b": {"path": "data/array/patch-b.npy", "pixel_size": [0.5, 0.6]}},
                                 "unit": "um"},
                       "contact": {"load": {"n_steps": 3, "relative_to": "e_star", "p_max": 0.005},
                                   "solver": {"boundary": "periodic", "e_star": 1e5, "pressure_unit": "MPa"},
                                   "outputs": {"full_contact_load": True, "stiffness": True}}},
    "broken": {"contact": {**GRID, "seeds": 0}},
}


@pytest.fixture(scope="module")
def walk_workflow(tmp_path_factory):
    wd = copy_workflow(tmp_path_factory.mktemp("walk") / "wf")
    (wd / "walk.yaml").write_text(yaml.safe_dump({"scenes": WALK_SCENES}))
    return wd


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_dry_runs_plan_beside_an_invalid_scene(walk_workflow):
    res = run_snakemake(walk_workflow, "-n", "--configfile", "walk.yaml", "--config", "scene=gen-target")
    out = res.stdout + res.stderr
    assert res.returncode == 0, out[-3000:]
    assert "scene 'broken', field 'contact.seeds'" in out and "Traceback" not in out
    res = run_snakemake(walk_workflow, "-n", "results/broken/fit/cel.nc", "--configfile", "walk.yaml")
    out = res.stdout + res.stderr  # a target's error comes through Snakemake's input-function report
    assert res.returncode != 0 and "invalid config: scene 'broken', field 'contact.seeds'" in out, out[-3000:]


@pytest.mark.slow
def test_the_bundled_options_run_with_each_source(walk_workflow):
    # every scene of WALK_SCENES but the broken one through its fit (and representativity): about 1 min on 2 cores
    runs = [name for name in WALK_SCENES if name != "broken"]
    # an adhesive scene runs no CEL fit: its aggregate is its end (with its figures)
    targets = [f"results/{name}/{'aggregate/contact' if 'adhesion' in name else 'fit/cel'}.nc" for name in runs]
    targets += [f"results/{name}/aggregate/representativity.nc" for name in runs
                if "representativity" in WALK_SCENES[name]]
    res = run_snakemake(walk_workflow, "-j2", *targets, "--configfile", "walk.yaml", timeout=900)
    assert res.returncode == 0, (res.stdout + res.stderr)[-4000:]
    # the files' pressure fields stacked on one grid (one in metres, one in nanometres: equal within round-off)
    assert xr.open_dataset(walk_workflow / "results/files/aggregate/contact.nc")["contact_pressure"].sizes["x"] == 128
    # target_area with two seeds and a hardness below the search's first probe: the fit runs on each seed's
    # own schedule; files with per-file settings: no warning that cases were solved differently
    # the search's first probe, target E* h' / 2 = 0.015, is above the hardness 0.01: it stays below it
    contact_log = (walk_workflow / "results/gen-target/logs/contact/kl2_ks8_H0.5_s0.log").read_text()
    assert "target A/A0 = 0.3: p0 = " in contact_log and "not within tolerance" not in contact_log
    fit = xr.open_dataset(walk_workflow / "results/gen-target/fit/cel.nc")
    assert fit.attrs["paper_average"] == "none"  # (N = 32 is too coarse for CEL constants: NaN, logged)
    fit_log = (walk_workflow / "results/gen-target/logs/fit_cel.log").read_text()
    assert "the paper route fits every (case, step) point on each case's own schedule" in fit_log
    log = (walk_workflow / "results/files/logs/aggregate_contact.log").read_text()
    assert "INFO cases were solved with different settings: topography.file_unit, topography.path" in log
    assert "WARNING" not in log


@pytest.mark.slow
def test_a_results_folder_the_run_cannot_write_is_one_line(tmp_path):
    wd = copy_workflow(tmp_path / "wf")
    (wd / "results").mkdir()
    (wd / "results" / "demo").write_text("in the way")  # root writes anywhere: a file, not a mode, blocks it
    res = run_snakemake(wd, "-j1", "results/demo/surfaces/kl4_ks32_H0.36_s0.nc", timeout=300)
    out = res.stdout + res.stderr
    assert res.returncode == 1 and "Traceback" not in out, out[-3000:]
    assert "roughcontact: results/demo/logs: Not a directory; the run writes under results/demo/" in out


# --- every command the docs name, at its edge --------------------------------------------------------------

def _truncated(folder: Path, names, source: Path):
    (folder / "data").mkdir(parents=True)
    for name in names:
        (folder / "data" / name).write_bytes((source / name).read_bytes()[:3000])
    return folder


def _corrupt_bench(tmp):
    (tmp / "benchmarks").mkdir()
    (tmp / "benchmarks" / "fit.tsv").write_text("s\tmax_rss\tmean_load\tcpu_time\n-1\t10\t50\t1\n")
    return tmp


def _corrupt_plan(tmp):
    (tmp / "logs").mkdir()
    (tmp / "logs" / "plan.json").write_text("[]")
    return tmp


def _corrupt_case(tmp):
    (tmp / "contact").mkdir()
    (tmp / "contact" / "kl4_ks32_H0.36_s0.nc").write_bytes(b"not netcdf")
    return tmp


def _not_netcdf(tmp):
    (tmp / "h.nc").write_bytes(b"not netcdf")
    return tmp / "h.nc"


def _mpi_argv(surface, out):
    """The MPI solver's command line (one rank, no mpiexec) on ``surface``, writing ``out``."""
    return ["--surface", str(surface), "--p-max", "0.005", "--out", str(out)]


def _list_yaml(tmp):
    (tmp / "list.yaml").write_text("- a\n- b\n")
    return tmp / "list.yaml"


OQ = REPO / "docs" / "open-questions" / "data"
RP = REPO / "docs" / "reproduction" / "data"
#: Each documented module: argv for (missing path, empty folder, corrupt input), the last built in a tmp folder.
COMMANDS = {
    "roughcontact.pipeline.config": (lambda p: [str(p)], lambda p: [str(p)], lambda p: [str(_list_yaml(p))]),
    "roughcontact.pipeline.adopt": (lambda p: [str(p), "--scene", "demo", "--dry-run"],
                                    lambda p: [str(p), "--scene", "demo", "--dry-run"],
                                    lambda p: [str(_corrupt_case(p)), "--scene", "demo", "--dry-run"]),
    "roughcontact.pipeline.runcost": (lambda p: [str(p)], lambda p: [str(p)], lambda p: [str(_corrupt_bench(p))]),
    "roughcontact.pipeline.progress": (lambda p: [str(p)], lambda p: [str(p)], lambda p: [str(_corrupt_plan(p))]),
    # an output folder, made if missing: only a file in its place is bad input
    "roughcontact.pipeline.examples": (None, None, lambda p: [str(_list_yaml(p))]),
    "roughcontact.studies.kappa_gap": (
        lambda p: ["regenerate", str(p)], lambda p: ["regenerate", str(p)],
        lambda p: ["regenerate", str(_truncated(p, ["kappa-gap.nc"], REPO / "docs" / "reproduction" / "data"))]),
    "roughcontact.studies.open_questions": (
        lambda p: ["regenerate", str(p)], lambda p: ["regenerate", str(p)],
        lambda p: ["regenerate", str(_truncated(p, ["full-contact.nc", "full-contact-cel.nc"], OQ)),
                   "--docs", str(REPO / "docs")]),
    "roughcontact.studies.reproduction": (
        lambda p: ["regenerate", str(p)], lambda p: ["regenerate", str(p)],
        lambda p: ["regenerate", str(_truncated(p, ["representativity.nc", "contact.nc", "cel.nc"], RP))]),
    # a surface file, not a folder: the "empty folder" case gives the folder itself as the surface
    # the ranks' program of a case over MPI ranks: its one argument is the job file run_case writes
    "roughcontact.case": (lambda p: [str(p / "case.json")], lambda p: [str(p)], lambda p: [str(_list_yaml(p))]),
    "roughcontact.solver.mpi": (lambda p: _mpi_argv(p / "h.nc", p.parent / "out.nc"),
                                lambda p: _mpi_argv(p, p / "out.nc"),
                                lambda p: _mpi_argv(_not_netcdf(p), p / "out.nc")),
}


def documented_modules() -> set[str]:
    """Every ``python -m roughcontact...`` module named in the repository's Markdown and docstrings."""
    found = set()
    for path in [*REPO.glob("*.md"), *REPO.glob("[cdbt]*/**/*.md"), *(REPO / "src").rglob("*.py")]:
        found |= set(re.findall(r"python -m (roughcontact[\w.]*\w)", path.read_text(errors="replace")))
    return found


def test_every_documented_module_is_walked():
    assert documented_modules() == set(COMMANDS), "a module the docs name: add its bad inputs to COMMANDS"


def _main(module):
    """The ``main`` that ``python -m module`` runs (a package's from its __main__'s import)."""
    if module == "roughcontact.solver.mpi":  # its main returns the exit code (each MPI rank exits with it)
        from roughcontact.solver.mpi.__main__ import main

        return lambda argv: sys.exit(main(argv))
    if module == "roughcontact.case":  # the same: its main returns each rank's exit code
        from roughcontact.case.__main__ import main as case_main

        return lambda argv: sys.exit(case_main(argv))
    where = {"roughcontact.pipeline.config": "roughcontact.pipeline.scenes",
             "roughcontact.studies.kappa_gap": "roughcontact.studies.kappa_gap.page",
             "roughcontact.studies.open_questions": "roughcontact.studies.open_questions.page"}.get(module, module)
    return __import__(where, fromlist=["main"]).main


CLI_CASES = [(m, i) for m, builders in COMMANDS.items() for i, b in enumerate(builders) if b is not None]


@pytest.mark.parametrize("module, i", CLI_CASES, ids=[f"{m.rsplit('.', 1)[1]}-{('missing', 'empty', 'corrupt')[i]}"
                                                      for m, i in CLI_CASES])
def test_each_command_on_bad_input_says_one_line(module, i, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(REPO)  # the commands that read the config run from the workflow's folder
    where = tmp_path / "missing" if i == 0 else tmp_path
    argv = COMMANDS[module][i](where)
    with pytest.raises(SystemExit) as stop:
        _main(module)(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.startswith("error: ") and err.count("\n") == 1, (argv, err)
    assert "Traceback" not in err
    assert not (tmp_path / "missing").exists()  # nothing made in a missing path


@pytest.mark.slow
@pytest.mark.parametrize("module", sorted(m for m in COMMANDS if COMMANDS[m][0] is not None))
def test_each_command_as_run_from_the_shell(module, tmp_path):
    res = subprocess.run([sys.executable, "-m", module, *COMMANDS[module][0](tmp_path / "missing")], cwd=REPO,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "Traceback" not in res.stderr, res.stderr
