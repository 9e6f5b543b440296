"""Batches in the pipeline (issue 48, item 3; issue 64): ``contact.solver.batch`` from the config to one contact job
and one file a batch, a NetCDF group a case.

The grouping (:func:`roughcontact.pipeline.cases.contact_batches`), the config's refusals, ``run_case`` on a
batch against each case alone, the batch file's groups, the rules' functions, a dry run that shows the
grouped jobs, and (slow) a tiny scene run with ``batch: 4`` and without, compared file by file, then a seed
added and only its batch planned.
"""
import copy
import json
import logging
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr
from snakemake.exceptions import WorkflowError

from cfcheck import assert_cf_clean
from conftest import copy_workflow, edited_contact, run_snakemake
from roughcontact.case import ContactCase, run_case
from roughcontact.case.loading import LoadSchedule
from roughcontact.figures.registry import FIGURES
from roughcontact.pipeline import params
from roughcontact.pipeline.cases import ContactBatch, batch_index, batch_seeds, batch_size, contact_batches
from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.io import InputFileError, read_dataset, write_groups
from roughcontact.pipeline.progress import read_log_solves
from roughcontact.pipeline.scenes import validate_config
from roughcontact.pipeline.targets import Targets
from roughcontact.solver import PlasticityCap, SolverSettings
from roughcontact.studies.accuracy import variants
from roughcontact.surfaces.synthetic import generate_surface
from test_workflow import TINY, _jobs

#: The tiny scene with 5 seeds in batches of 4: per (k_l, k_s, H) a full batch (seeds 0-3) and a short one (4).
BATCHED = copy.deepcopy(TINY)
BATCHED["scenes"]["tiny"]["contact"].update(seeds=5, solver={"tol": 1e-8, "batch": 4})
#: The same scene unbatched.
SINGLE = copy.deepcopy(BATCHED)
del SINGLE["scenes"]["tiny"]["contact"]["solver"]["batch"]

HS = ("0.5", "0.8")
CONTACT = "results/tiny/contact/kl2_ks8_H{H}_s{seed}.nc"
BATCH = "results/tiny/contact/kl2_ks8_H{H}_b{index}.nc"
SURF = "results/tiny/surfaces/kl2_ks8_H{H}_s{seed}.nc"


def _contact(cfg=BATCHED, **edits):
    """The tiny scene's contact block validated, with ``edits`` applied first (``conftest.edited_contact``)."""
    return validate_config(edited_contact(cfg, **edits))["scenes"]["tiny"]["contact"]


# ------------------------------------------------------------------------------ the grouping
def test_batches_are_fixed_chunks_of_the_seeds():
    assert batch_seeds(0, 4, 10) == (0, 1, 2, 3) and batch_seeds(2, 4, 10) == (8, 9) and batch_seeds(3, 4, 10) == ()
    assert [batch_index(s, 4) for s in range(9)] == [0, 0, 0, 0, 1, 1, 1, 1, 2]
    assert batch_seeds(3, 1, 10) == (3,)
    with pytest.raises(ValueError, match="size >= 1"):
        batch_seeds(0, 0, 10)


def test_contact_batches_of_a_block():
    block = _contact()
    got = contact_batches(block)
    assert got == [ContactBatch("2", "8", h, i, seeds) for h in HS for i, seeds in ((0, (0, 1, 2, 3)), (1, (4,)))]
    assert got[1].stem == "kl2_ks8_H0.5_b1" and [c.stem for c in got[1].cases] == ["kl2_ks8_H0.5_s4"]
    # every case in exactly one batch, in seed order
    assert sorted((b.H, s) for b in got for s in b.seeds) == [(h, s) for h in HS for s in range(5)]


def test_a_new_seed_changes_only_the_batch_it_falls_in():
    before = contact_batches(_contact())
    for seeds, changed in ((6, {"kl2_ks8_H0.5_b1", "kl2_ks8_H0.8_b1"}), (9, {"kl2_ks8_H0.5_b1", "kl2_ks8_H0.8_b1",
                                                                             "kl2_ks8_H0.5_b2", "kl2_ks8_H0.8_b2"})):
        after = contact_batches(_contact(seeds=seeds))
        assert {b.stem for b in after if b not in before} == changed
        assert [b for b in before if b.index == 0] == [b for b in after if b.index == 0]


def test_unbatched_blocks_are_batches_of_one():
    block = _contact(**{"solver.batch": 1})
    assert batch_size(block) == 1 and "batch" not in block["solver"]
    assert [b.seeds for b in contact_batches(block)] == [(s,) for _ in HS for s in range(5)]


# ------------------------------------------------------------------------------ the config
@pytest.mark.parametrize("value, words", [
    (0, "0 is less than the minimum of 1"), (-1, "-1 is less than the minimum of 1"),
    (2.5, "2.5 is not of type 'integer'"), ("x", "'x' is not a whole number"), (True, "True is not of type 'integer'"),
    (5000, "5000 is greater than the maximum of 4096"),
])
def test_a_bad_batch_is_named(value, words):
    with pytest.raises(ConfigError) as info:
        _contact(**{"solver.batch": value})
    assert "scene 'tiny', field 'contact.solver.batch'" in str(info.value) and words in str(info.value), info.value


@pytest.mark.parametrize("edits, field", [
    ({"outputs.fields": [1]}, "contact.outputs.fields"),
    ({"outputs.clusters": True}, "contact.outputs.clusters"),
    ({"outputs.pressure_distribution": {"bins": 10, "max": 5}}, "contact.outputs.pressure_distribution"),
    ({"effects.plasticity.hardness": 0.5}, "contact.effects"),
    ({"load.target_area": 0.1, "load.p_max": None}, "contact.load.target_area"),
    ({"load.relative_to": "rms_slope"}, "contact.load.relative_to"),
    ({"solver.boundary": "free"}, "contact.solver.boundary"),
])
def test_what_a_batch_cannot_compute_is_refused_before_any_job(edits, field):
    with pytest.raises(ConfigError) as info:
        _contact(**edits)
    msg = str(info.value)
    assert f"scene 'tiny', field '{field}'" in msg and "contact.solver.batch: 4" in msg, msg
    assert f"remove {field.removeprefix('contact.')} or solver.batch" in msg, msg
    assert _contact(SINGLE, **edits)  # the same block unbatched plans


def test_a_measured_scene_is_not_batched(shipped_config, repo, monkeypatch):
    monkeypatch.chdir(repo)
    cfg = copy.deepcopy(shipped_config)
    cfg["scene"] = "measured"
    cfg["scenes"]["measured"].setdefault("contact", {}).setdefault("solver", {}).update(batch=2, boundary="periodic")
    with pytest.raises(ConfigError, match=r"scene 'measured', field 'contact.solver.batch': batches generated cases.*"
                                          r"remove solver.batch"):
        validate_config(cfg)


def test_batch_one_is_the_unbatched_scene():
    assert params.contact(_contact(**{"solver.batch": 1})) == params.contact(_contact(SINGLE))
    assert params.contact(_contact())["solver"]["batch"] == 4


# ------------------------------------------------------------------------------ run_case on a batch
@pytest.fixture(scope="module")
def surfaces():
    """Three 32² surfaces of one grid, the third broadband and near half contact (more iterations)."""
    return np.stack([generate_surface(32, 2, 8, 0.8, seed=0, rms_slope=0.1),
                     generate_surface(32, 2, 8, 0.5, seed=1, rms_slope=0.1),
                     generate_surface(32, 2, 16, 0.2, seed=2, rms_slope=0.05)])


CASE = ContactCase(LoadSchedule(6, p_max=0.01), SolverSettings(tol=1e-9),
                   outputs={"fields": [], "clusters": False, "stiffness": True, "full_contact_load": True})


def test_run_case_on_a_batch_is_each_case_alone(surfaces):
    slopes = [0.1, 0.1, 0.05]
    batch = run_case(surfaces, CASE, length=1.0, rms_slope=slopes, name=["a", "b", "c"])
    assert len(batch) == 3
    for h, slope, got in zip(surfaces, slopes, batch, strict=True):
        [alone] = run_case(h, CASE, length=1.0, rms_slope=slope)
        assert set(got.variables) - set(alone.variables) == {"rounds"} and set(alone.variables) <= set(got.variables)
        assert set(got.attrs) - set(alone.attrs) == {"batch_size", "check_every"} and got.attrs["batch_size"] == 3
        for key, value in alone.attrs.items():  # the settings, the cell and the loads (load_pbar_max per case)
            assert got.attrs[key] == value, key
        np.testing.assert_allclose(got.area_fraction, alone.area_fraction, atol=2 / h.size)
        np.testing.assert_allclose(got.mean_gap, alone.mean_gap, rtol=1e-6)
        np.testing.assert_allclose(got.contact_stiffness, alone.contact_stiffness, rtol=1e-4)
        assert float(got.full_contact_pressure) == float(alone.full_contact_pressure)
        assert np.all(np.abs(got.iterations.values - alone.iterations.values) <= 1)
        assert got.converged.values.all() and alone.converged.values.all()
    assert batch[2].iterations.sum() > batch[1].iterations.sum() > 0  # the broadband one ran on after the others


@pytest.mark.parametrize("case, words", [
    (ContactCase(LoadSchedule(3, p_max=0.01), outputs={"fields": [2], "clusters": False}), "outputs['fields']"),
    (ContactCase(LoadSchedule(3, p_max=0.01), outputs={"fields": [], "clusters": True}), "outputs['clusters']"),
    (ContactCase(LoadSchedule(3, p_max=0.01), outputs={"fields": [], "clusters": False,
                                                       "pressure_distribution": {"bins": 4, "max": 5}}),
     "outputs['pressure_distribution']"),
    (ContactCase(LoadSchedule(3, p_max=0.01), SolverSettings(effects=(PlasticityCap(0.5),))), "effects (plasticity)"),
    (ContactCase(LoadSchedule(3, target_area=0.2)), "schedule.target_area"),
    (ContactCase(LoadSchedule(3, p_max=0.01), warm_start="scaled"), "warm_start='scaled'"),
])
def test_what_a_batch_cannot_compute_is_named_by_run_case(surfaces, case, words):
    with pytest.raises(ValueError, match=re.escape(words) + ".*run each case with 2-D heights"):
        run_case(surfaces, case, length=1.0, rms_slope=0.1)


def test_a_batch_logs_one_line_a_step_that_counts_its_cases(surfaces, caplog):
    log = logging.getLogger("roughcontact.test_batch")
    with caplog.at_level(logging.INFO, logger=log.name):
        run_case(surfaces, CASE, length=1.0, rms_slope=0.1, log=log)
    solves = read_log_solves(caplog.text)
    assert [cases for cases, _ in solves] == [3] * 6, caplog.text  # scene progress counts 3 solves a step
    assert "batch of 3 cases (case 0 .. case 2): p0 from" in caplog.text


def test_a_batch_needs_one_load_schedule(surfaces):
    per_slope = ContactCase(LoadSchedule(3, p_max=0.05, relative_to="rms_slope"))
    with pytest.raises(ValueError, match="one load schedule, but c resolves to other loads than a"):
        run_case(surfaces, per_slope, length=1.0, rms_slope=[0.1, 0.1, 0.3], name=["a", "b", "c"])
    assert len(run_case(surfaces, per_slope, length=1.0, rms_slope=0.1)) == 3  # equal slopes: equal loads
    with pytest.raises(ValueError, match="3 surfaces needs 3 rms_slope values"):
        run_case(surfaces, CASE, length=1.0, rms_slope=[0.1, 0.1])
    with pytest.raises(ValueError, match="observers"):
        run_case(surfaces, CASE, length=1.0, rms_slope=0.1, observers=[object()])


# ------------------------------------------------------------------------------ the batch file
def _labelled(value):
    return xr.Dataset({"a": ("step", [value, 2.0], {"units": "1", "long_name": "a"})},
                      coords={"step": ("step", [1, 2], {"units": "1", "long_name": "step"})})


def test_a_batch_file_holds_each_case_as_its_own_file_would(tmp_path):
    path = tmp_path / "b.nc"
    write_groups({"one": (_labelled(1.0), {"p": 1}), "two": (_labelled(3.0), {"p": 2})}, path, stage="contact_batch",
                 member_stage="contact", scene="s", scene_parameters={"p": [1, 2]})
    two = read_dataset(path, stage="contact", group="two")
    assert two.a.values.tolist() == [3.0, 2.0] and json.loads(two.attrs["scene_parameters"]) == {"p": 2}
    root = read_dataset(path, stage="contact_batch")
    assert root.attrs["groups"] == "one two" and not root.data_vars
    with pytest.raises(InputFileError, match="holds no group 'three'; its groups: one two"):
        read_dataset(path, stage="contact", group="three")
    with pytest.raises(InputFileError, match=r"\(group one\): holds stage 'contact', expected 'surface'"):
        read_dataset(path, stage="surface", group="one")
    first = path.read_bytes()
    write_groups({"one": (_labelled(1.0), {"p": 1}), "two": (_labelled(3.0), {"p": 2})}, path, stage="contact_batch",
                 member_stage="contact", scene="s", scene_parameters={"p": [1, 2]})
    assert path.read_bytes() == first  # no timestamps: a rerun gives the same bytes


# ------------------------------------------------------------------------------ the rules' functions
@pytest.fixture(scope="module")
def targets():
    return Targets.from_config(copy.deepcopy(BATCHED), variants, FIGURES)


def _w(group):
    return SimpleNamespace(scene="tiny", group=group)


def test_a_batch_is_one_contact_job_and_its_file_holds_its_cases(targets):
    group = targets.contact_group(_w("kl2_ks8_H0.8_b0"))
    assert group.kind == "batch" and [c.seed for c in group.members] == [0, 1, 2, 3]
    assert targets.contact_input(_w("kl2_ks8_H0.8_b0")) == [SURF.format(H="0.8", seed=s) for s in range(4)]
    assert targets.contact_input(_w("kl2_ks8_H0.8_b1")) == [SURF.format(H="0.8", seed=4)]
    assert targets.contact_cases(_w("kl2_ks8_H0.8_b1")) == [{"k_l": "2", "k_s": "8", "H": "0.8", "seed": "4"}]
    assert targets.contact_params(params.contact)(_w("kl2_ks8_H0.8_b1"))["solver"]["batch"] == 4
    assert targets.contact_kind(_w("kl2_ks8_H0.8_b1")) == "batch"  # a batch even of one seed
    assert targets.contact_tasks(_w("kl2_ks8_H0.8_b0")) is None and targets.contact_threads(_w("kl2_ks8_H0.8_b0")) == 1
    assert targets.contact_bundle(_w("kl2_ks8_H0.8_b0")) == "solve"
    single = Targets.from_config(copy.deepcopy(SINGLE), variants, FIGURES)
    assert single.contact_input(_w("kl2_ks8_H0.8_s3")) == [SURF.format(H="0.8", seed=3)]
    assert single.contact_job_mem_mb(_w("kl2_ks8_H0.8_s3")) < targets.contact_job_mem_mb(_w("kl2_ks8_H0.8_b0"))
    # the aggregate reads each case from its batch's file, in the order of the cases
    members = targets.contact_members_of("tiny")
    assert [m[1] for m in members][:5] == [f"kl2_ks8_H0.5_s{s}" for s in range(5)]
    assert members[4] == [BATCH.format(H="0.5", index=1), "kl2_ks8_H0.5_s4"]
    assert targets.contact_files("tiny") == [BATCH.format(H=h, index=i) for h in HS for i in (0, 1)]
    assert single.contact_members_of("tiny")[0] == [CONTACT.format(H="0.5", seed=0), None]


@pytest.mark.parametrize("group, words", [
    ("kl2_ks8_H0.8_b2", "batch 2 of kl2_ks8_H0.8_b2 is not one of the scene's batches 0..1 (5 seeds in batches of 4"),
    ("kl2_ks8_H0.8_b01", "batch 01 of kl2_ks8_H0.8_b01 is not one of the scene's batches"),
    ("kl2_ks9_H0.8_b0", "wildcard k_s=9 is not in the scene"),
    ("kl2_ks8_H0.8_s3", "case kl2_ks8_H0.8_s3 has no file of its own: it is a group of "
                        "results/tiny/contact/kl2_ks8_H0.8_b0.nc"),
    ("kl2_ks8_H0.8_s7", "wildcard seed=7 is not one of the scene's seeds 0..4"),
    ("surface", "scene 'tiny' has no topography block nor array block, so it has no named case 'surface'; its "
                "contact files are named kl{k_l}_ks{k_s}_H{H}_b{batch}.nc (its seeds in batches of 4"),
])
def test_a_group_outside_the_scene_is_named(targets, group, words):
    with pytest.raises(WorkflowError, match=re.escape(words)):
        targets.contact_input(_w(group))


def test_an_unbatched_scene_has_no_batch_files():
    single = Targets.from_config(copy.deepcopy(SINGLE), variants, FIGURES)
    with pytest.raises(WorkflowError, match=r"solves each contact case alone \(contact.solver.batch is 1\)"):
        single.contact_input(_w("kl2_ks8_H0.8_b0"))


# ------------------------------------------------------------------------------ Snakemake
def _planned(stdout: str) -> set[str]:
    """The first output file of every job a dry run plans."""
    return {m.group(1) for m in re.finditer(r"^\s+output: ([^,\s]+)", stdout, flags=re.MULTILINE)}


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_a_dry_run_shows_the_grouped_jobs(tmp_path):
    wd = copy_workflow(tmp_path / "wf", BATCHED)
    res = run_snakemake(wd, "-n", timeout=300)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert "120 solves at N=32, in 4 batches of up to 4 cases" in res.stderr + res.stdout
    jobs = _jobs(res.stdout)
    assert jobs["contact"] == 4 and jobs["surface"] == 10 and "contact_batch" not in jobs, jobs
    planned = _planned(res.stdout)
    assert {BATCH.format(H=h, index=i) for h in HS for i in (0, 1)} <= planned
    assert not {CONTACT.format(H=h, seed=s) for h in HS for s in range(5)} & planned  # no file a case
    # unbatched: a job a case
    wd = copy_workflow(tmp_path / "single", SINGLE)
    res = run_snakemake(wd, "-n", timeout=300)
    assert res.returncode == 0 and _jobs(res.stdout)["contact"] == 10


def _contact_targets():
    return [CONTACT.format(H=h, seed=s) for h in HS for s in range(5)]


def _batch_targets(seeds=5):
    return [BATCH.format(H=h, index=i) for h in HS for i in range(-(-seeds // 4))]


@pytest.mark.slow  # two tiny runs (10 cases each, only the contact files) and three dry runs: ~3 min on 2 cores
def test_batch_4_equals_the_unbatched_run_and_a_new_seed_solves_only_its_batch(tmp_path):
    runs = {}
    for name, cfg, targets in (("batched", BATCHED, _batch_targets()), ("single", SINGLE, _contact_targets())):
        wd = copy_workflow(tmp_path / name, cfg)
        res = run_snakemake(wd, "-j2", *targets)
        assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
        runs[name] = wd
    batched = runs["batched"]
    assert sorted(p.name for p in (batched / "results/tiny/contact").iterdir()) == [
        f"kl2_ks8_H{h}_b{i}.nc" for h in HS for i in (0, 1)]  # each case written once: in its batch's file
    for target in _contact_targets():
        seed = int(target.split("_s")[-1].removesuffix(".nc"))
        path = batched / BATCH.format(H=target.split("_H")[1].split("_")[0], index=seed // 4)
        a = read_dataset(path, stage="contact", group=Path(target).stem)
        with xr.open_dataset(runs["single"] / target) as b:
            b = b.load()
        assert set(a.variables) - set(b.variables) == {"rounds"} and set(b.variables) <= set(a.variables), target
        differ = {k for k in set(a.attrs) | set(b.attrs) if a.attrs.get(k) != b.attrs.get(k)}
        assert differ == {"batch_size", "check_every", "scene_parameters", "config_hash"}, (target, differ)
        assert a.attrs["batch_size"] == (1 if target.endswith("_s4.nc") else 4)
        recorded_a, recorded_b = json.loads(a.attrs["scene_parameters"]), json.loads(b.attrs["scene_parameters"])
        assert recorded_a["solver"].pop("batch") == 4 and recorded_a == recorded_b, target
        tol = b.attrs["tol"]
        np.testing.assert_allclose(a.area_fraction, b.area_fraction, atol=2 / (32 * 32), err_msg=target)
        np.testing.assert_allclose(a.mean_gap, b.mean_gap, rtol=tol * 100, err_msg=target)
        np.testing.assert_allclose(a.kappa, b.kappa, rtol=1e-6, err_msg=target)
        assert np.all(np.abs(a.iterations.values - b.iterations.values) <= 1) and a.converged.values.all(), target
    assert_cf_clean([batched / BATCH.format(H="0.5", index=0)], tmp_path / "tables")
    # the batches solved again: byte-identical
    first = {t: (batched / t).read_bytes() for t in _batch_targets()}
    res = run_snakemake(batched, "-j2", "-R", "contact", *_batch_targets())
    assert res.returncode == 0, res.stderr[-3000:]
    assert {t: (batched / t).read_bytes() for t in _batch_targets()} == first
    # nothing left to do; then a sixth seed joins batch 1 of each (k_l, k_s, H): only that batch reruns
    res = run_snakemake(batched, "-n", *_batch_targets())
    assert res.returncode == 0 and "Nothing to be done" in res.stdout + res.stderr, res.stdout[-2000:]
    more = copy.deepcopy(BATCHED)
    more["scenes"]["tiny"]["contact"]["seeds"] = 6
    copy_workflow(batched, more)
    res = run_snakemake(batched, "-n", *_batch_targets(6))
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert _planned(res.stdout) == ({BATCH.format(H=h, index=1) for h in HS}
                                    | {SURF.format(H=h, seed=5) for h in HS}), sorted(_planned(res.stdout))
