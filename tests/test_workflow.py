"""The Snakemake workflow: dry runs of every scene, bad input stops early, a tiny real run."""
import copy
import re
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
import yaml

from caption_check import assert_scene_captions_true
from cfcheck import assert_cf_clean
from conftest import TINY, copy_workflow, run_snakemake

#: Jobs of `snakemake -n --forceall --config scene=paper` (each text that gives the paper DAG's size must say this).
PAPER_JOBS = 2421


def _jobs(stdout):
    """Job counts from the 'Job stats' table of a dry run."""
    counts, table = {}, False
    for line in stdout.splitlines():
        if line.startswith("job "):
            table = True
            continue
        if table:
            parts = line.split()
            if parts and parts[0] == "total":
                break
            if len(parts) == 2 and parts[1].isdigit():
                counts[parts[0]] = int(parts[1])
    return counts


@pytest.mark.parametrize("scene", ["demo", pytest.param("paper", marks=pytest.mark.slow), "representative",
                                   "kappa-gap", "adhesion", "array", "lines"])
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_dry_run_every_shipped_scene(repo, scene):
    # --forceall: the full job list, whatever a local results/ already holds
    res = run_snakemake(repo, "-n", "--forceall", "--config", f"scene={scene}", timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    jobs = _jobs(res.stdout)
    if scene == "paper":
        # 900 representativity surfaces in one job per k_l (H = 0.8 only), each all 6 k_s x 30 seeds
        assert jobs["contact"] == 1200 and jobs["representativity"] == 5
        assert sum(jobs.values()) == PAPER_JOBS, jobs
    if scene == "representative":
        assert jobs["contact"] == 60 and "representativity" not in jobs
    if scene == "kappa-gap":
        # every variant's seeds x 3 H, one summary, and nothing of the other studies
        assert jobs["kappa_gap_case"] == 63 and jobs["kappa_gap_summary"] == 1 and "contact" not in jobs
    if scene == "lines":
        # profiles (surface.dimension: 1): the generator's rules, one surface per case
        assert jobs["contact"] == 16 and jobs["surface"] == 16 and jobs["representativity"] == 2
    if scene == "array":
        # two .npy patches: their own surface rule, no generated surfaces
        assert jobs["contact"] == 2 and "surface" not in jobs and "contact_topography" not in jobs
    # the dry run says what the scene computes before anything runs
    solves = {"demo": "12 contact cases x 30 load steps = 360 solves at N=256",
              "paper": "1200 contact cases x 30 load steps = 36000 solves at N=1024",
              "representative": "60 contact cases x 30 load steps = 1800 solves at N=1024",
              "kappa-gap": "the kappa-gap study (63 solves in 9 variants)",
              "adhesion": "4 contact cases x 10 load steps = 40 solves at N=128",
              "array": "contact of 2 array file(s) x 30 load steps = 60 solves",
              "lines": "16 contact cases x 30 load steps = 480 solves at profiles of N=4096 points"}[scene]
    assert f"roughcontact: scene '{scene}' plans" in res.stderr + res.stdout and solves in res.stderr + res.stdout
    # the contact map is planned only where the scene stores fields (outputs.fields: of these, demo and lines)
    planned = f"output: results/{scene}/figures/contact_map.png" in res.stdout + res.stderr
    assert planned == (scene in ("demo", "lines"))


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_representativity_only_scene_plans_no_contact(tmp_path):
    wd = copy_workflow(tmp_path / "wf", {**TINY, "scene": "reponly"})
    res = run_snakemake(wd, "-n")
    assert res.returncode == 0, res.stderr[-3000:]
    jobs = _jobs(res.stdout)
    # one job for the grid point's two seeds; a surface file only for the example figure
    assert jobs["representativity"] == 1
    assert not {"contact", "surface", "fit_cel", "aggregate_contact"} & set(jobs)


@pytest.mark.parametrize(
    "edit, words",
    [
        (lambda c: c["scenes"]["tiny"]["contact"]["grid"].update(k_s=["17"]), "field 'contact.grid.k_s'"),
        (lambda c: c["scenes"]["tiny"]["contact"].update(seeds=0), "field 'contact.seeds'"),
        (lambda c: c.update(scene="nosuch"), "unknown scene 'nosuch'"),
    ],
)
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_invalid_config_stops_before_any_job(tmp_path, edit, words):
    cfg = copy.deepcopy(TINY)
    edit(cfg)
    wd = copy_workflow(tmp_path / "wf", cfg)
    res = run_snakemake(wd, "-j1")
    assert res.returncode != 0
    log = res.stdout + res.stderr
    assert words in log and "scene '" in log
    assert not (wd / "results").exists()


@pytest.fixture(scope="module")
def shipped_copy(tmp_path_factory):
    """A copy of the workflow with the shipped config (every shipped scene), for dry runs."""
    return copy_workflow(tmp_path_factory.mktemp("shipped") / "wf")


# A target outside its scene, for every wildcard and kind of output: the words its error must hold
# (the wildcard, the value and the scene's allowed values). The issue's cases run in make test-fast.
MISTYPED = [
    ("results/demo/contact/kl5_ks32_H0.36_s0.nc",
     "contact.grid.k_l: wildcard k_l=5 is not in the scene; allowed: 4, 16"),
    ("results/demo/contact/kl4_ks32_H0.360_s0.nc",
     "wildcard H=0.360 is not in the scene; allowed: 0.36, 0.84 (file names carry the config's text verbatim: "
     "write H=0.36)"),
    ("results/demo/representativity/kl2_H0.8.nc",
     "representativity.grid.k_l: wildcard k_l=2 is not in the scene; allowed: 1, 4, 16"),
    pytest.param("results/demo/surfaces/kl4_ks33_H0.36_s0.nc", "wildcard k_s=33 is not in the scene; allowed: 32",
                 marks=pytest.mark.slow),
    pytest.param("results/demo/surfaces_rep/kl1_ks32_H0.5_s0.nc", "wildcard H=0.5 is not in the scene; allowed: 0.8",
                 marks=pytest.mark.slow),
    pytest.param("results/demo/representativity/kl1_H0.80.nc", "write H=0.8", marks=pytest.mark.slow),
    pytest.param("results/demo/contact/kl4_ks32_H0.36_s3.nc", "wildcard seed=3 is not one of the scene's seeds 0..2",
                 marks=pytest.mark.slow),
    # a seed with a leading zero would be a second file for seed 0
    pytest.param("results/demo/contact/kl4_ks32_H0.36_s00.nc", "wildcard seed=00 is not one of the scene's seeds 0..2 "
                 "(written without leading zeros)", marks=pytest.mark.slow),
    pytest.param("results/nosuch/contact/kl4_ks32_H0.36_s0.nc",
                 "wildcard scene=nosuch: no scene 'nosuch' in the config; defined scenes: demo, paper",
                 marks=pytest.mark.slow),
    pytest.param("results/accuracy/surfaces/kl4_ks32_H0.36_s0.nc", "scene 'accuracy' declares no 'contact' block",
                 marks=pytest.mark.slow),
    pytest.param("results/measured/contact/ground-d.nc", "wildcard topography=ground-d is not one of its topography "
                 "files; allowed: ground-a, ground-b, ground-c", marks=pytest.mark.slow),
    pytest.param("results/measured/contact/kl4_ks32_H0.36_s0.nc", "scene 'measured' runs on measured surfaces",
                 marks=pytest.mark.slow),
    pytest.param("results/demo/contact/ground-a.nc", "scene 'demo' has no topography block", marks=pytest.mark.slow),
    pytest.param("results/demo/figures/nosuch.png", "wildcard figure=nosuch is not a figure of roughcontact",
                 marks=pytest.mark.slow),
    pytest.param("results/accuracy/accuracy/N512_tol1e-8_steps30/kl16_ks32_H0.5_s0.nc",
                 "accuracy.H: wildcard H=0.5 is not in the scene; allowed: 0.36, 0.84", marks=pytest.mark.slow),
    pytest.param("results/kappa-gap/kappa_gap/N8192/kl16_ks32_H0.2_s0.nc",
                 "wildcard variant=N8192 is not one of its variants; allowed: baseline, load-0.05, N512, N1024",
                 marks=pytest.mark.slow),
    pytest.param("results/kappa-gap/kappa_gap/N4096/kl16_ks32_H0.2_s2.nc",
                 "kappa_gap variant N4096: wildcard seed=2 is not one of the scene's seeds 0..1",
                 marks=pytest.mark.slow),
    pytest.param("results/accuracy/accuracy/N513_tol1e-8_steps30/kl16_ks32_H0.36_s0.nc",
                 "wildcard variant=N513_tol1e-8_steps30 is not one of its settings; allowed: N2048_tol1e-10_steps30",
                 marks=pytest.mark.slow),
]


@pytest.mark.parametrize("target, words", MISTYPED)
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_a_target_outside_its_scene_is_named_with_the_allowed_values(shipped_copy, target, words):
    res = run_snakemake(shipped_copy, "-n", target)
    log = res.stdout + res.stderr
    assert res.returncode != 0 and words in log, log[-3000:]
    assert "MissingRuleException" not in log and "Job stats" not in log


@pytest.mark.slow
def test_mistyped_target_fails_at_once(tmp_path):
    wd = copy_workflow(tmp_path / "wf", TINY)
    # H=0.7 is in no scene's grid: named with the grid's values
    res = run_snakemake(wd, "-n", "results/tiny/contact/kl2_ks8_H0.7_s0.nc")
    assert res.returncode != 0 and "wildcard H=0.7 is not in the scene; allowed: 0.5, 0.8" in res.stdout + res.stderr
    # seed 5 matches the pattern but is outside the scene's seeds: named with the range.
    res = run_snakemake(wd, "-n", "results/tiny/contact/kl2_ks8_H0.5_s5.nc")
    assert res.returncode != 0 and "seed=5 is not one of the scene's seeds 0..1" in res.stdout + res.stderr
    # a figure the scene does not ask for is named, with the scene's figures
    res = run_snakemake(wd, "-n", "--config", "scene=reponly", "--", "results/reponly/figures/kappa.png")
    assert res.returncode != 0
    assert "scene 'reponly' does not ask for figure 'kappa'; its figures: representativity" in res.stdout + res.stderr


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_nested_config_values_on_the_command_line_are_read_as_the_schema_types(shipped_copy):
    """`--config 'scenes={demo: {contact: {seeds: 4}}}'`: Snakemake passes '4', the scene gets 4 seeds."""
    res = run_snakemake(shipped_copy, "-n", "--config", "scenes={demo: {contact: {seeds: 4, solver: {tol: 1e-9}}}}")
    log = res.stdout + res.stderr
    assert res.returncode == 0, log[-3000:]
    assert "16 contact cases x 30 load steps" in log and _jobs(res.stdout)["contact"] == 16
    res = run_snakemake(shipped_copy, "-n", "--config", "scenes={demo: {contact: {seeds: four}}}")
    log = res.stdout + res.stderr
    assert res.returncode != 0 and "field 'contact.seeds': 'four' is not a whole number" in log, log[-3000:]
    assert "write a whole number, e.g. 4" in log and "not of type" not in log


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_malformed_yaml_is_named_with_file_line_and_column(tmp_path):
    wd = copy_workflow(tmp_path / "wf")
    config = wd / "config" / "config.yaml"
    lines = config.read_text().splitlines()
    at = lines.index("scene: demo")
    lines[at] = "scene: demo: x"  # a second ': ' on one line
    config.write_text("\n".join(lines) + "\n")
    res = run_snakemake(wd, "-n")
    log = res.stdout + res.stderr
    assert res.returncode != 0 and f"config/config.yaml: not valid YAML at line {at + 1}, column 12" in log, log[-3000:]
    assert "close every bracket and quote" in log and "Config file is not valid JSON or YAML" not in log
    # a --configfile is read by Snakemake before the workflow's code runs: its own message, then the
    # documented check names the file and the line
    (wd / "my_scene.yaml").write_text("scenes:\n  mine:\n\tcontact: {}\n")
    config.write_text("\n".join(lines[:at] + ["scene: demo"] + lines[at + 1:]) + "\n")
    res = run_snakemake(wd, "-n", "--configfile", "my_scene.yaml")
    assert res.returncode != 0 and "Config file is not valid JSON or YAML" in res.stdout + res.stderr
    res = subprocess.run([sys.executable, "-m", "roughcontact.pipeline.config", "my_scene.yaml"], cwd=wd,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "my_scene.yaml: not valid YAML at line 3, column 1" in res.stderr, res.stderr


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_own_scene_in_its_own_file(tmp_path):
    """`--configfile my_scene.yaml --config scene=mine`: a user's scene beside the shipped ones."""
    wd = copy_workflow(tmp_path / "wf")
    (wd / "my_scene.yaml").write_text(yaml.safe_dump({"scenes": {"mine": {
        "contact": {"surface": {"N": 64}, "grid": {"k_l": ["2"], "k_s": ["16"], "H": ["0.7"]}, "seeds": 2},
    }}}))
    res = run_snakemake(wd, "-n", "--configfile", "my_scene.yaml", "--config", "scene=mine")
    assert res.returncode == 0, res.stderr[-3000:]
    jobs = _jobs(res.stdout)
    assert jobs["contact"] == 2 and jobs["surface"] == 2 and "representativity" not in jobs
    assert "results/mine/contact/kl2_ks16_H0.7_s1.nc" in res.stdout + res.stderr


@pytest.mark.slow
def test_tiny_real_run(tmp_path):
    wd = copy_workflow(tmp_path / "wf", TINY)
    res = run_snakemake(wd, "-j2")
    assert res.returncode == 0, res.stderr[-5000:]
    out = wd / "results" / "tiny"
    surf = xr.open_dataset(out / "surfaces" / "kl2_ks8_H0.5_s1.nc")
    assert surf.heights.dims == ("k_l", "k_s", "H", "seed", "x", "y")
    assert surf.heights.shape == (1, 1, 1, 1, 32, 32)
    assert float(surf.H[0]) == 0.5 and int(surf.seed[0]) == 1
    assert float(surf.rms_slope.squeeze()) == pytest.approx(0.1, rel=1e-6)
    for name in ("roughcontact_version", "scene_parameters", "config_hash"):
        assert name in surf.attrs
    for var in list(surf.data_vars) + list(surf.coords):
        assert {"units", "long_name"} <= set(surf[var].attrs), var
    rep = xr.open_dataset(out / "aggregate" / "representativity.nc")
    assert rep.epsilon.sizes == {"k_l": 2, "k_s": 1, "H": 1, "seed": 2}
    con = xr.open_dataset(out / "aggregate" / "contact.nc")
    assert con.area_fraction.dims == ("k_l", "k_s", "H", "seed", "step")
    assert con.area_fraction.shape == (1, 1, 2, 2, 12)
    assert np.all(np.isfinite(con.area_fraction.values))
    assert np.all(np.diff(con.area_fraction.values, axis=-1) >= 0)
    # a scene that asks for no fields writes none
    case = xr.open_dataset(out / "contact" / "kl2_ks8_H0.5_s0.nc")
    assert "contact_pressure" not in case and "gap" not in case
    for fig in ("representativity", "surface_examples", "area_load", "kappa", "dpbar"):
        for ext in ("png", "pdf"):
            assert (out / "figures" / f"{fig}.{ext}").stat().st_size > 1000
    assert "kappa" in (out / "fit" / "cel.csv").read_text()
    # one file of every kind: no error or warning of the CF checker (tests/cfcheck.py)
    assert_cf_clean([out / "surfaces" / "kl2_ks8_H0.5_s1.nc", out / "surfaces_rep" / "kl1_ks8_H0.8_s0.nc",
                     out / "representativity" / "kl1_H0.8.nc", out / "contact" / "kl2_ks8_H0.5_s0.nc",
                     out / "aggregate" / "contact.nc", out / "aggregate" / "representativity.nc",
                     out / "fit" / "cel.nc"], tmp_path / "tables")
    # nothing left to do, and a rerun of one case by its file name works
    again = run_snakemake(wd, "-n")
    assert "Nothing to be done" in again.stdout + again.stderr
    target = "results/tiny/contact/kl2_ks8_H0.8_s1.nc"
    before = (wd / target).read_bytes()
    res = run_snakemake(wd, "-j1", "-f", target)
    assert res.returncode == 0, res.stderr[-3000:]
    assert (wd / target).read_bytes() == before, "outputs must be byte-identical across reruns"
    assert (res.stdout + res.stderr).count("Finished jobid") == 1, "-f FILE reruns that one job only"


@pytest.mark.slow
def test_demo_scene_produces_every_figure_and_the_fit_table(demo_run):
    # The shipped default scene, exactly as `make run` runs it (the demo_run fixture), then every
    # job again (about 1.5 min each on 2 cores).
    wd = demo_run
    out = wd / "results" / "demo"
    for fig in ("representativity", "surface_examples", "area_load", "kappa", "dpbar", "contact_map"):
        for ext in ("png", "pdf"):
            assert (out / "figures" / f"{fig}.{ext}").stat().st_size > 1000, fig
    # each caption names exactly the reference lines its figure drew: the demo's families differ in bandwidth,
    # so no asperity model at "the surfaces' own" alpha is drawn, nor promised (issue 52)
    shown = assert_scene_captions_true(wd, "demo")
    assert "asperity_bgt_paper" in shown["area_load"] and "asperity_bgt_own" not in shown["area_load"]
    assert {"cel_fit", "cel_paper", "fit_window"} <= set(shown["kappa"]) and shown["representativity"] == []
    table = (out / "fit" / "cel.csv").read_text().splitlines()
    assert table[0].startswith("k_l,k_s,H_group,estimator,constant,value")
    assert any(",pooled,paper,kappa," in row for row in table)
    assert "git commit: ``unknown``" in (out / "report" / "run.rst").read_text()  # not a git checkout
    # A second run of every job writes the same bytes: NetCDF, CSV, figures and the report's fragments.
    first = _output_bytes(out)
    assert {p.suffix for p in first} == {".nc", ".csv", ".png", ".pdf", ".rst", ".html"}
    res = run_snakemake(wd, "-j2", "--forceall")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    second = _output_bytes(out)
    differ = sorted(str(p) for p in first if first[p] != second.get(p))
    assert not differ and first.keys() == second.keys(), f"rerun changed {len(differ)} file(s): {differ[:10]}"


#: The run record (roughcontact.studies.run_record): the date, host and CPU time of the run, which a rerun
#: changes by design; the one output not byte-identical across reruns.
RUN_RECORD = "report/run.rst"


def _output_bytes(root):
    """Bytes of every result file (NetCDF, CSV, figures, report fragments but the run record) under ``root``."""
    return {p.relative_to(root): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and p.suffix in (".nc", ".csv", ".png", ".pdf", ".rst", ".html")
            and p.relative_to(root).as_posix() != RUN_RECORD}


@pytest.mark.slow
def test_unconverged_steps_are_flagged_counted_and_excluded(tmp_path):
    cfg = copy.deepcopy(TINY)
    del cfg["scenes"]["tiny"]["representativity"]
    cfg["scenes"]["tiny"]["contact"]["solver"] = {"tol": 1e-12, "max_iter": 3}
    wd = copy_workflow(tmp_path / "wf", cfg)
    res = run_snakemake(wd, "-j2")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    out = wd / "results" / "tiny"
    case = xr.open_dataset(out / "contact" / "kl2_ks8_H0.5_s0.nc")
    assert not bool(case.converged.all()) and np.all(np.isfinite(case.residual.values))
    assert "did not converge" in (out / "logs" / "contact" / "kl2_ks8_H0.5_s0.log").read_text()
    agg = xr.open_dataset(out / "aggregate" / "contact.nc")
    assert float(agg.n_unconverged.min()) > 0
    assert "excluding 4 case(s) with unconverged steps" in (out / "logs" / "fit_cel.log").read_text()
    fitted = xr.open_dataset(out / "fit" / "cel.nc")
    assert bool(fitted["value"].isnull().all()), "no converged case: nothing may be fitted"


@pytest.mark.slow
def test_a_file_made_for_another_case_or_scene_is_refused(tmp_path):
    """A surface of N=64 put into an N=32 scene, or seed 1's surface named as seed 0's: named, not used."""
    big = copy.deepcopy(TINY)
    big["scenes"]["tiny"]["contact"]["surface"]["N"] = 64
    src = copy_workflow(tmp_path / "big", big)
    made = ["results/tiny/surfaces/kl2_ks8_H0.5_s0.nc", "results/tiny/surfaces/kl2_ks8_H0.5_s1.nc"]
    assert run_snakemake(src, "-j1", *made).returncode == 0
    wd = copy_workflow(tmp_path / "wf", TINY)
    (wd / "results/tiny/surfaces").mkdir(parents=True)
    target = "results/tiny/contact/kl2_ks8_H0.5_s0.nc"
    (wd / made[0]).write_bytes((src / made[0]).read_bytes())
    res = run_snakemake(wd, "-j1", target)
    log = res.stdout + res.stderr
    assert res.returncode != 0 and f"{made[0]}: was made with surface = " in log and "'N': 64" in log, log[-3000:]
    assert not (wd / target).exists()
    (wd / made[0]).write_bytes((src / made[1]).read_bytes())
    res = run_snakemake(wd, "-j1", target)
    log = res.stdout + res.stderr
    assert res.returncode != 0 and "holds seed=[1], but this job is for seed=0" in log, log[-3000:]


@pytest.mark.slow
def test_contact_jobs_log_one_line_per_load_step(demo_run):
    # a long N = 1024 job is not silent: each load step is logged as it finishes
    log = next((demo_run / "results" / "demo" / "logs" / "contact").glob("*.log")).read_text()
    lines = [line for line in log.splitlines() if " step " in line and "/30: p0 = " in line]
    assert len(lines) == 30 and "step 30/30" in lines[-1] and "iterations" in lines[0]
    # and each job ends with the scene's progress: the last to finish has seen every other contact job done (its
    # own benchmark file is written after it ends), with an estimate of what is left
    logs = [p.read_text() for p in (demo_run / "results" / "demo" / "logs" / "contact").glob("*.log")]
    assert all(re.search(r"scene 'demo': \d+ of \d+ jobs done \(contact \d+ of 12\)", text) for text in logs)
    assert any("(contact 11 of 12): about " in text for text in logs)


@pytest.mark.slow  # ~1 min: make test (CI) runs it, make test-fast does not
def test_measured_scene_runs_end_to_end(measured_run, tmp_path):
    """The shipped `measured` scene: three files in three formats through every stage (the session's run, shared with
    test_reader), then every job again (~1 min each)."""
    from roughcontact.pipeline.io import read_dataset
    from test_units import assert_all_units_parse

    wd, root = measured_run.wd, measured_run.out
    agg = read_dataset(root / "aggregate" / "contact.nc", stage="aggregate")
    assert list(agg["topography"].values) == ["ground-a", "ground-b", "ground-c"]
    assert agg.attrs["boundary"] == "free" and agg["pressure"].attrs["units"] == "MPa"
    assert bool(agg["converged"].all()) and np.all(np.isfinite(agg["kappa"].values))
    # ground-c (160 x 128 text, no unit or size) is solved whole, 128 x 160 points over 100 x 125 um;
    # ground-b's holes filled
    c = read_dataset(root / "surfaces" / "ground-c.nc", stage="surface")
    assert (c.sizes["x"], c.sizes["y"]) == (128, 160) and c["heights"].attrs["units"] == "um"
    assert (c.attrs["length_x"], c.attrs["length_y"]) == (100.0, 125.0)
    assert read_dataset(root / "contact" / "ground-c.nc", stage="contact").attrs["ny"] == 160
    # each file is loaded to the paper's regime of its own slope: p0 / (E* h') = 0.05 at the last step
    for name in agg["topography"].values:
        con = read_dataset(root / "contact" / f"{name}.nc", stage="contact")
        assert con.attrs["load_relative_to"] == "rms_slope" and con.attrs["load_p_max"] == 0.05
        last, slope = float(con["pressure"].isel(step=-1).squeeze()), float(con["rms_slope"].squeeze())
        assert last == pytest.approx(0.05 * 1e5 * slope, rel=1e-12)
        assert con.attrs["load_pbar_max"] == pytest.approx(0.05, rel=1e-12)
    assert '"n_undefined": 42' in read_dataset(root / "surfaces" / "ground-b.nc", stage="surface").attrs["source"]
    rep = read_dataset(root / "aggregate" / "representativity.nc", stage="aggregate")
    assert rep["epsilon"].attrs["units"] == "1" and rep["epsilon"].attrs["reference_length_units"] == "um"
    assert rep.sizes["topography"] == 3
    for path in sorted(root.rglob("*.nc")):  # every variable of every file: CF/pint-parseable units
        assert_all_units_parse(xr.open_dataset(path))
    # one file of every kind: no error or warning of the CF checker (tests/cfcheck.py)
    assert_cf_clean([root / f"{kind}/ground-c.nc" for kind in ("surfaces", "representativity", "contact")]
                    + [root / "aggregate/contact.nc", root / "aggregate/representativity.nc", root / "fit/cel.nc"],
                    tmp_path / "tables")
    assert "pooled (3 topographies)" in (root / "fit" / "cel.csv").read_text()
    for name in ("topographies", "measured_area_load", "measured_kappa"):
        assert (root / "figures" / f"{name}.png").stat().st_size > 10_000
    shown = assert_scene_captions_true(wd, "measured")  # captions true of what each figure drew
    assert "asperity_bgt_own" in shown["measured_kappa"] and shown["topographies"] == []
    again = run_snakemake(wd, "-n", "--config", "scene=measured")
    assert "Nothing to be done" in again.stdout + again.stderr
    # every output, remade from scratch, has the same bytes
    outputs = [root / p for p in _output_bytes(root)]
    before = {p: p.read_bytes() for p in outputs}
    res = run_snakemake(wd, "-j2", "--forceall", "--config", "scene=measured")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert [p for p in outputs if p.read_bytes() != before[p]] == []
