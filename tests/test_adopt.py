"""Adopting another run's contact cases: only identical cases of identical runs, and nothing downstream changes."""
import copy
import csv
import subprocess
import sys

import netCDF4
import numpy as np
import pytest
import xarray as xr
import yaml

from conftest import copy_workflow, run_snakemake
from roughcontact.pipeline import adopt
from roughcontact.pipeline.io import write_dataset
from roughcontact.pipeline.scenes import validate_config
from test_workflow import TINY, _jobs

# "big" holds every case of "small" and more: same surfaces, loads and solver
CONTACT = copy.deepcopy(TINY["scenes"]["tiny"]["contact"])
CONFIG = {
    "scene": "small",
    "scenes": {
        "small": {"contact": {**CONTACT, "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5"]}},
                  "fit": TINY["scenes"]["tiny"]["fit"]},
        "big": {"contact": CONTACT, "fit": TINY["scenes"]["tiny"]["fit"]},
    },
}
SCENES = validate_config(CONFIG)["scenes"]
LABEL = {"units": "1", "long_name": "a number"}


def _case_file(path, case, *, scene="small", parameters=None, value=0.5):
    """A contact case file as the contact rule writes it (its scene, its parameters), small."""
    kl, ks, h, seed = case
    coords = {name: xr.Variable(name, [v], LABEL) for name, v in zip(("k_l", "k_s", "H", "seed"), case, strict=True)}
    coords["step"] = xr.Variable("step", [1, 2], LABEL)
    dims = ("k_l", "k_s", "H", "seed", "step")
    ds = xr.Dataset({"area_fraction": xr.Variable(dims, np.full((1, 1, 1, 1, 2), value), LABEL)}, coords=coords,
                    attrs={"e_star": 1.0, "solver": "test"})
    write_dataset(ds, path, stage="contact", scene=scene,
                  scene_parameters=adopt.expected_parameters(SCENES["big"]) if parameters is None else parameters)
    return path


def _runs(tmp_path, source_cases, target_cases=(), **kwargs):
    src, dst = tmp_path / "results" / "small", tmp_path / "results" / "big"
    for case in source_cases:
        _case_file(src / "contact" / _name(case), case, **kwargs)
    for case in target_cases:
        _case_file(dst / "contact" / _name(case), case, scene="big")
    return src, dst


def _name(case):
    return f"kl2_ks8_H{case[2]}_s{case[3]}.nc"


CASES = [(2.0, 8.0, 0.5, 0), (2.0, 8.0, 0.5, 1), (2.0, 8.0, 0.8, 0)]


def test_adopts_the_missing_cases_with_only_scene_and_origin_changed(tmp_path):
    src, dst = _runs(tmp_path, CASES, CASES[:1])
    done = adopt.adopt(src, dst, "big", SCENES["big"])
    assert sorted(done.adopt) == [_name(c) for c in CASES[1:]] and done.common == [_name(CASES[0])]
    assert done.missing == ["kl2_ks8_H0.8_s1.nc"]
    for case in CASES[1:]:
        assert adopt.same_case(src / "contact" / _name(case), dst / "contact" / _name(case)) is None
        with netCDF4.Dataset(src / "contact" / _name(case)) as a, netCDF4.Dataset(dst / "contact" / _name(case)) as b:
            # every attribute in its place, scene the target's; the origin added at the end
            assert b.ncattrs() == [*a.ncattrs(), "adopted_from"]
            assert (a.scene, b.scene) == ("small", "big") and b.adopted_from == str(src / "contact" / _name(case))
    rows = list(csv.reader((dst / adopt.MANIFEST).open(), delimiter="\t"))
    assert rows[0] == ["case_file", "source_file", "source_sha256", "sha256"]
    assert [r[0] for r in rows[1:]] == [_name(c) for c in CASES[1:]]
    # again: nothing left to adopt, nothing rewritten
    before = {p.name: p.read_bytes() for p in dst.rglob("*") if p.is_file()}
    assert adopt.adopt(src, dst, "big", SCENES["big"]).adopt == {}
    assert {p.name: p.read_bytes() for p in dst.rglob("*") if p.is_file()} == before


def test_an_interrupted_adoption_lists_every_copy_it_made(tmp_path, monkeypatch):
    src, dst = _runs(tmp_path, CASES, CASES[:1])
    copy, calls = adopt.copy_case, []

    def copy_then_fail(*args):
        if calls:
            raise KeyboardInterrupt
        calls.append(args)
        copy(*args)

    monkeypatch.setattr(adopt, "copy_case", copy_then_fail)
    with pytest.raises(KeyboardInterrupt):
        adopt.adopt(src, dst, "big", SCENES["big"])
    rows = list(csv.reader((dst / adopt.MANIFEST).open(), delimiter="\t"))[1:]
    assert [r[0] for r in rows] == [_name(CASES[1])] and (dst / "contact" / _name(CASES[1])).is_file()
    assert not (dst / "contact" / _name(CASES[2])).exists()


def test_refuses_a_source_made_with_other_parameters(tmp_path):
    other = copy.deepcopy(adopt.expected_parameters(SCENES["big"]))
    other["solver"]["tol"] = 1e-6
    src, dst = _runs(tmp_path, CASES, CASES[:1], parameters=other)
    with pytest.raises(adopt.AdoptError, match=r"kl2_ks8_H0.5_s0.nc: made with parameters .*1e-06.* would use"):
        adopt.adopt(src, dst, "big", SCENES["big"])
    assert not (dst / "contact" / _name(CASES[1])).exists()


def test_refuses_when_a_case_of_both_runs_differs(tmp_path):
    src, dst = _runs(tmp_path, CASES)
    _case_file(dst / "contact" / _name(CASES[0]), CASES[0], scene="big", value=0.5 + 1e-15)
    with pytest.raises(adopt.AdoptError, match="kl2_ks8_H0.5_s0.nc: the two runs computed this case differently "
                                               r"\(values of area_fraction\)"):
        adopt.adopt(src, dst, "big", SCENES["big"])
    assert sorted(p.name for p in (dst / "contact").iterdir()) == [_name(CASES[0])]


def test_without_a_case_in_common_it_needs_trust(tmp_path):
    src, dst = _runs(tmp_path, CASES)
    with pytest.raises(adopt.AdoptError, match="no case computed by both runs"):
        adopt.adopt(src, dst, "big", SCENES["big"])
    assert len(adopt.adopt(src, dst, "big", SCENES["big"], trust_code=True).adopt) == 3


def test_refuses_a_file_holding_another_case(tmp_path):
    src, dst = _runs(tmp_path, [], CASES[:1])
    _case_file(src / "contact" / _name(CASES[1]), CASES[0])
    with pytest.raises(adopt.AdoptError, match=r"kl2_ks8_H0.5_s1.nc: holds case .* its name says"):
        adopt.adopt(src, dst, "big", SCENES["big"])


def _cli(cwd, *args):
    return subprocess.run([sys.executable, "-m", "roughcontact.pipeline.adopt", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_cli_dry_run_and_a_held_working_directory(tmp_path):
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text(yaml.safe_dump(CONFIG))
    _runs(tmp_path, CASES, CASES[:1])
    res = _cli(tmp_path, "results/small", "--scene", "big", "--dry-run")
    assert res.returncode == 0, res.stderr
    assert "would adopt 2 case(s)" in res.stdout and "1 computed by both runs agree" in res.stdout
    assert not (tmp_path / "results" / "big" / "contact" / _name(CASES[1])).exists()
    (tmp_path / ".snakemake" / "locks").mkdir(parents=True)
    (tmp_path / ".snakemake" / "locks" / "0.input.lock").write_text("")
    res = _cli(tmp_path, "results/small", "--scene", "big")
    assert res.returncode == 2 and "a Snakemake run holds" in res.stderr
    res = _cli(tmp_path, "results/small", "--scene", "nosuch", "--dry-run")
    assert res.returncode == 2 and "nosuch" in res.stderr


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_cli_refuses_a_target_it_cannot_write_before_copying(tmp_path):
    """results/<scene> blocked by a file: the command says so before it checks or copies a case (issue 62)."""
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text(yaml.safe_dump(CONFIG))
    src, _ = _runs(tmp_path, CASES)
    (tmp_path / "results" / "big").write_text("not a folder")
    res = _cli(tmp_path, "results/small", "--scene", "big")
    assert res.returncode == 2, res.stderr
    assert res.stderr.startswith("error: results/big/adopted.tsv: cannot be written: results/big is a file, not a "
                                 "folder"), res.stderr
    assert "Traceback" not in res.stderr


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_cli_configfile_adds_to_the_shipped_config_as_snakemake_does(tmp_path):
    """A scene kept in its own file, written over the shipped `defaults`, is adopted into as it is run."""
    shipped = {"scene": "small", "defaults": {"contact": CONTACT, "fit": TINY["scenes"]["tiny"]["fit"]},
               "scenes": {"small": {"contact": {"grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5"]}}}}}
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text(yaml.safe_dump(shipped))
    (tmp_path / "big.yaml").write_text("scenes:\n  big:\n    contact: {}\n")  # the defaults' contact block
    assert validate_config({**shipped, "scenes": {"big": {"contact": {}}}, "scene": "big"})["scenes"]["big"] == \
        SCENES["big"]
    _runs(tmp_path, CASES, CASES[:1])
    res = _cli(tmp_path, "results/small", "--scene", "big", "--configfile", "big.yaml", "--dry-run")
    assert res.returncode == 0, res.stderr
    assert "would adopt 2 case(s)" in res.stdout and "1 computed by both runs agree" in res.stdout
    # a file that is not YAML is named with its line and column
    (tmp_path / "broken.yaml").write_text("scenes:\n  big: {contact: {}\n")
    res = _cli(tmp_path, "results/small", "--scene", "big", "--configfile", "broken.yaml", "--dry-run")
    assert res.returncode == 2 and "error: broken.yaml: not valid YAML at line 3, column 1" in res.stderr, res.stderr


@pytest.mark.slow
def test_adopted_cases_leave_every_downstream_byte_as_a_full_run_makes_it(tmp_path):
    # small runs; big runs one shared case (s1), adopts the other (s0, the first input of the aggregate,
    # whose attributes it starts from), runs the rest: its aggregate and fit are byte for byte those
    # of big run from scratch in another copy of the workflow
    # only the files compared and what they need (the figures and report of both scenes are other tests')
    outs = ("aggregate/contact.nc", "fit/cel.nc", "fit/cel.csv")
    targets = [f"results/big/{out}" for out in outs]
    wd = copy_workflow(tmp_path / "wf", CONFIG)
    for args in (["-j2", "--config", "scene=small", "--", *(f"results/small/contact/kl2_ks8_H0.5_s{s}.nc"
                                                              for s in (0, 1))],
                 ["-j1", "--config", "scene=big", "--", "results/big/contact/kl2_ks8_H0.5_s1.nc"]):
        res = run_snakemake(wd, *args)
        assert res.returncode == 0, res.stderr[-3000:]
    res = _cli(wd, "results/small", "--scene", "big")
    assert res.returncode == 0 and "adopted 1 case(s)" in res.stdout, res.stderr
    res = run_snakemake(wd, "-n", "--config", "scene=big")
    # neither the adopted case's solve nor its surface (kept by this scene, never made here) is planned
    assert res.returncode == 0 and _jobs(res.stdout)["contact"] == 2, res.stdout[-3000:]
    assert _jobs(res.stdout)["surface"] == 2, res.stdout[-3000:]
    assert run_snakemake(wd, "-j2", "--config", "scene=big", "--", *targets).returncode == 0
    fresh = copy_workflow(tmp_path / "fresh", CONFIG)
    assert run_snakemake(fresh, "-j2", "--config", "scene=big", "--", *targets).returncode == 0
    for out in outs:
        assert (wd / "results/big" / out).read_bytes() == (fresh / "results/big" / out).read_bytes(), out


def test_a_scene_whose_contact_map_reads_surfaces_is_refused_naming_outputs_fields():
    """Issue 62: adopting into a scene with outputs.fields said "adopted", then the next run re-solved the mapped
    cases (their surfaces made again, newer than the adopted files)."""
    scene = validate_config({**CONFIG, "scenes": {**CONFIG["scenes"], "big": {
        "contact": {**CONTACT, "outputs": {"fields": [2]}}, "fit": TINY["scenes"]["tiny"]["fit"]}},
        "scene": "big"})["scenes"]["big"]
    with pytest.raises(adopt.AdoptError, match=r"scene 'big' stores fields \(contact.outputs.fields: \[2\]\), and its "
                                               r"contact map reads each mapped case's surface file, .*adopt into a "
                                               r"scene without outputs.fields, or run the scene itself"):
        adopt.check_adoptable("big", scene)
    adopt.check_adoptable("big", SCENES["big"])  # without fields: adoptable
