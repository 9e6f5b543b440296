"""Partial reruns: after each config edit `snakemake -n` plans exactly the jobs whose inputs changed."""
import copy
import re

import pytest
import yaml

from conftest import copy_workflow, run_snakemake
from test_workflow import TINY

# One real run of the tiny scene, then a dry run per edit: about 2.5 min on 2 cores.
# one xdist group (make test: --dist loadgroup): the module's workflow fixture then runs once, not once per
# worker (~110 s of setup on each of the two workers in the 2026-11-28 CI-like run)
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("rerun")]

SURF = "results/tiny/surfaces/kl2_ks8_H{H}_s{seed}.nc"
CONTACT = "results/tiny/contact/kl2_ks8_H{H}_s{seed}.nc"
DOWNSTREAM = {
    "results/tiny/aggregate/contact.nc",
    "results/tiny/fit/cel.nc",
    "results/tiny/figures/area_load.png",
    "results/tiny/figures/kappa.png",
    "results/tiny/figures/dpbar.png",
    "results/tiny/report/result.rst",
}
FIT_ON = {"results/tiny/fit/cel.nc", *(p for p in DOWNSTREAM if "figures" in p), "results/tiny/report/result.rst"}
ALL_CONTACT = {CONTACT.format(H=h, seed=s) for h in ("0.5", "0.8") for s in (0, 1)}


def _planned(stdout: str) -> set[str]:
    """The first output file of every job a dry run plans (the `all` target has none)."""
    return {m.group(1) for m in re.finditer(r"^\s+output: ([^,\s]+)", stdout, flags=re.MULTILINE)}


def _write(wd, cfg):
    with open(wd / "config" / "config.yaml", "w") as fh:
        yaml.safe_dump(cfg, fh, sort_keys=False)


def _edit(edit):
    cfg = copy.deepcopy(TINY)
    edit(cfg["scenes"]["tiny"])
    return cfg


def _reordered(cfg):
    """The same config with every mapping's keys in reverse order."""
    if isinstance(cfg, dict):
        return {k: _reordered(cfg[k]) for k in reversed(list(cfg))}
    return cfg


EDITS = [
    ("add a seed", lambda s: s["contact"].update(seeds=3),
     {SURF.format(H=h, seed=2) for h in ("0.5", "0.8")} | {CONTACT.format(H=h, seed=2) for h in ("0.5", "0.8")}
     | DOWNSTREAM),
    # the representativity study runs one job per (k_l, H) with all its k_s and seeds
    ("add a representativity seed", lambda s: s["representativity"].update(seeds=3),
     {f"results/tiny/representativity/kl{kl}_H0.8.nc" for kl in ("1", "4")}
     | {"results/tiny/aggregate/representativity.nc", "results/tiny/figures/representativity.png",
        "results/tiny/report/result.rst"}),
    # a new k_s joins every batch's file, so each batch reruns (the part takes ~1 min at N = 1024)
    ("add a representativity k_s", lambda s: s["representativity"]["grid"].update(k_s=["8", "12"]),
     {f"results/tiny/representativity/kl{kl}_H0.8.nc" for kl in ("1", "4")}
     | {"results/tiny/aggregate/representativity.nc", "results/tiny/figures/representativity.png",
        "results/tiny/report/result.rst"}),
    ("change representativity.n_bins", lambda s: s["representativity"].update(n_bins=30),
     {f"results/tiny/representativity/kl{kl}_H0.8.nc" for kl in ("1", "4")}
     | {"results/tiny/aggregate/representativity.nc", "results/tiny/figures/representativity.png",
        "results/tiny/report/result.rst"}),
    ("change solver.tol", lambda s: s["contact"]["solver"].update(tol=1e-9), ALL_CONTACT | DOWNSTREAM),
    ("change fit.window", lambda s: s["fit"].update(window=[0.02, 0.3]), FIT_ON),
    ("change the description", lambda s: s.update(description="another description"), set()),
    ("write defaults explicitly",
     lambda s: (s["contact"]["solver"].update(e_star=1, max_iter=10000), s["contact"]["surface"].update(L=1),
                s["fit"].update(rng_seed=2012), s["representativity"].update(keep_surfaces=True)), set()),
    ("whole numbers as floats", lambda s: s["contact"].update(seeds=2.0), set()),
]


@pytest.fixture(scope="module")
def done(tmp_path_factory):
    """A completed tiny scene."""
    wd = copy_workflow(tmp_path_factory.mktemp("rerun") / "wf", TINY)
    res = run_snakemake(wd, "-j2")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    return wd


def _with_report(planned: set[str]) -> set[str]:
    """``planned`` and the report jobs it sets off: the fit's HTML table when the fit reruns, the landing page's
    figures when a figure does, and the run record (written after every other output) when anything does."""
    figures = {"results/tiny/report/figures.rst"} if any("/figures/" in p for p in planned) else set()
    table = {"results/tiny/fit/cel.html"} if "results/tiny/fit/cel.nc" in planned else set()
    return planned | figures | table | ({"results/tiny/report/run.rst"} if planned else set())


@pytest.mark.parametrize("what, edit, expected", EDITS, ids=[e[0] for e in EDITS])
def test_dry_run_plans_exactly_what_changed(done, what, edit, expected):
    expected = _with_report(expected)
    _write(done, _edit(edit))
    try:
        res = run_snakemake(done, "-n")
    finally:
        _write(done, TINY)
    assert res.returncode == 0, res.stderr[-3000:]
    assert _planned(res.stdout + res.stderr) == expected, f"{what}: {res.stdout[-4000:]}"


def test_reordered_keys_plan_nothing(done):
    _write(done, _reordered(TINY))
    try:
        res = run_snakemake(done, "-n")
    finally:
        _write(done, TINY)
    assert res.returncode == 0 and _planned(res.stdout + res.stderr) == set(), res.stdout[-3000:]


def test_rerun_of_one_case_with_other_settings_is_recorded_per_case(done):
    """A targeted rerun at another tol: the aggregate says which case had which tol."""
    import xarray as xr

    target = CONTACT.format(H="0.5", seed=0)
    _write(done, _edit(lambda s: s["contact"]["solver"].update(tol=1e-9)))
    try:
        res = run_snakemake(done, "-j1", "-f", target)
        assert res.returncode == 0, res.stderr[-3000:]
        assert "Finished jobid" in res.stdout + res.stderr and _planned(res.stdout + res.stderr) <= {target}
        # only time stamps, not the changed settings of the other cases, decide what reruns now
        res = run_snakemake(done, "-j1", "--rerun-triggers", "mtime", "--", "results/tiny/aggregate/contact.nc")
        assert res.returncode == 0, res.stderr[-3000:]
    finally:
        _write(done, TINY)
    with xr.open_dataset(done / "results/tiny/aggregate/contact.nc") as agg:
        tol = agg["setting_solver_tol"]
        assert tol.sel(H=0.5, seed=0).item() == 1e-9
        assert {tol.sel(H=0.5, seed=1).item(), tol.sel(H=0.8, seed=0).item()} == {1e-8}
        assert "tol" not in agg.attrs["scene_parameters"] and agg.attrs["varying_parameters"] == "solver.tol"
    log = (done / "results/tiny/logs/aggregate_contact.log").read_text()
    assert "cases were solved with different settings: solver.tol" in log
