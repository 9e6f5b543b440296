"""One case over MPI ranks in the pipeline (issue 50, item 2): ``contact.solver.ranks`` from the config to the file.

The config's refusals (each named, before any job), MPI asked for but not installed, ``ranks: 1`` dropped,
the rules' functions and resources, the launcher (:func:`~roughcontact.case.mpi_command`),
:func:`~roughcontact.case.run_case` over ranks against it in one process
on the same surface file, the MPI solver's own refusal passed on as one line, a dry run under the SLURM
profile (an MPI job: ``mpi``, ``tasks`` = ranks, ``launcher=srun``) and (slow) a tiny scene with ``ranks: 2`` against
the same scene in one process, file by file. The runs skip, saying why, where mpi4py or ``mpiexec`` is
missing (the ``test`` extra brings them).
"""
from __future__ import annotations

import copy
import importlib.util
import json
import logging
import re
import runpy
import subprocess
import sys
import tracemalloc
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr
from snakemake.exceptions import WorkflowError

import roughcontact.case as case_module
from conftest import REPO, copy_workflow, edited_contact, load_script, run_snakemake
from roughcontact.case import ContactCase, case_document, case_from_document, mpi_command, run_case
from roughcontact.case.loading import LoadSchedule
from roughcontact.figures.registry import FIGURES
from roughcontact.pipeline import params
from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.contact_jobs import (
    MPI_MEMORY_MARGIN,
    contact_mpi_mem_mb,
    contact_mpi_runtime_min,
    contact_runtime_min,
)
from roughcontact.pipeline.datasets import SAMPLE_ROWS, surface_grid, surface_heights
from roughcontact.pipeline.io import lazy_dataset, read_dataset
from roughcontact.pipeline.scenes import validate_config
from roughcontact.pipeline.targets import Targets
from roughcontact.solver import PlasticityCap, SolverSettings
from roughcontact.studies.accuracy import variants
from roughcontact.surfaces.synthetic import generate_surface
from test_solver_mpi import CAP, MPIEXEC, heights_reads, needs_mpi
from test_workflow import TINY

#: The tiny scene (contact only, N = 64) split over 2 ranks, and the same scene in one process.
SPLIT = copy.deepcopy(TINY)
del SPLIT["scenes"]["tiny"]["representativity"]
SPLIT["scenes"]["tiny"]["contact"].update(surface={"N": 64, "rms_slope": 0.1}, solver={"tol": 1e-8, "ranks": 2},
                                          outputs={"stiffness": True})
SINGLE = copy.deepcopy(SPLIT)
del SINGLE["scenes"]["tiny"]["contact"]["solver"]["ranks"]

HS = ("0.5", "0.8")
CONTACT = "results/tiny/contact/kl2_ks8_H{H}_s{seed}.nc"
#: Two of its cases (the runs' time is Snakemake's and the processes' start-up, not the solves').
TARGETS = [CONTACT.format(H=h, seed=0) for h in HS]


def _contact(cfg=SPLIT, **edits):
    return validate_config(edited_contact(cfg, **edits))["scenes"]["tiny"]["contact"]


# ------------------------------------------------------------------------------ the config
@pytest.mark.parametrize("edits, field, why", [
    ({"solver.batch": 4}, "solver.batch", "a batch solves several cases in one process"),
    ({"solver.boundary": "free"}, "solver.boundary", "periodic half-space only"),
    ({"solver.array_backend": "cupy"}, "solver.array_backend", "runs on numpy"),
    ({"effects": {"plasticity": {"hardness": 0.5}}}, "effects", "without effects"),
    ({"outputs.fields": [12]}, "outputs.fields", "stores no fields"),
    ({"outputs.clusters": True}, "outputs.clusters", "whole contact mask"),
    ({"outputs.pressure_distribution": {"bins": 10, "max": 3}}, "outputs.pressure_distribution", "pressure field"),
    ({"outputs.full_contact_load": True}, "outputs.full_contact_load", "whole surface"),
    ({"load": {"target_area": 0.1}}, "load.target_area", "again and again"),
    ({"solver.ranks": 65}, "solver.ranks", "at most 64"),
    ({"surface.dimension": 1}, "surface.dimension", "profiles"),
])
def test_what_a_case_over_ranks_cannot_do_is_refused_naming_the_field(edits, field, why):
    with pytest.raises(ConfigError) as err:
        _contact(**edits)
    msg = str(err.value)
    assert f"field 'contact.{field}'" in msg and why in msg and "contact.solver.ranks: " in msg, msg
    assert "remove" in msg


def test_a_measured_scene_over_ranks_is_refused(shipped_config, repo, monkeypatch):
    monkeypatch.chdir(repo)
    cfg = copy.deepcopy(shipped_config)
    cfg["scene"] = "measured"
    cfg["scenes"]["measured"].setdefault("contact", {}).setdefault("solver", {}).update(ranks=2, boundary="periodic")
    with pytest.raises(ConfigError, match=r"scene 'measured', field 'contact.solver.ranks': splits generated maps.*"
                                          r"python -m roughcontact.solver.mpi --surface FILE.*remove solver.ranks"):
        validate_config(cfg)


@pytest.mark.parametrize("value", [0, -2, 2.5, "two", 70000])
def test_bad_ranks_values_are_named(value):
    with pytest.raises(ConfigError, match=r"field 'contact.solver.ranks'"):
        _contact(**{"solver.ranks": value})


def test_a_grid_beyond_one_process_only_over_ranks():
    """N above 16384 (one process's largest map, ~50 GB) plans only as contact maps split over ranks (issue 63's
    cmc-32768 scene); anything that holds a whole surface in one process is refused naming surface.N."""
    assert _contact(**{"surface.N": 32768})["surface"]["N"] == 32768  # ranks: 2
    assert _contact(**{"surface.N": 65536})["surface"]["N"] == 65536
    with pytest.raises(ConfigError, match=r"field 'contact.surface.N': 32768 is above 16384, the largest map one "
                                          r"process solves .*contact.solver.ranks, or lower surface.N"):
        _contact(SINGLE, **{"surface.N": 32768})
    with pytest.raises(ConfigError, match=r"field 'contact.surface.N': 32768 is above 16384, the most points of a "
                                          r"profile"):
        _contact(**{"surface.N": 32768, "surface.dimension": 1})
    with pytest.raises(ConfigError, match=r"field 'contact.surface.N': .*maximum of 65536"):
        _contact(**{"surface.N": 65537})
    cfg = copy.deepcopy(TINY)
    cfg["scenes"]["tiny"]["representativity"]["surface"]["N"] = 32768
    with pytest.raises(ConfigError, match=r"field 'representativity.surface.N': 32768 is above 16384: the "
                                          r"representativity study makes and analyses each whole surface in one"):
        validate_config(cfg)


def test_the_adhesion_remedy_stays_within_one_process():
    """An adhesive case is never split over ranks, so its remedy's largest grid is one process's: the planner gives
    the effect's rule MAX_ONE_PROCESS_N, the one copy of that limit."""
    from roughcontact.pipeline.config.checks import MAX_ONE_PROCESS_N

    assert MAX_ONE_PROCESS_N == 16384
    # the zone E* rho^2 / w = 1e-5 L needs N = 150000: beyond one process, the remedy widens the zone instead
    adhesive = {"law": "exponential", "work": 1e-3, "range": 1e-4}
    with pytest.raises(ConfigError, match=rf"beyond the largest grid a scene allows \(N = {MAX_ONE_PROCESS_N}\)"):
        _contact(SINGLE, effects={"adhesion": adhesive})


def test_ranks_one_is_dropped_so_it_changes_no_job():
    assert "ranks" not in _contact(SINGLE, **{"solver.ranks": 1})["solver"]
    assert params.contact(_contact(SINGLE, **{"solver.ranks": 1})) == params.contact(_contact(SINGLE))
    assert _contact()["solver"]["ranks"] == 2


def test_mpi_asked_for_but_not_installed_is_refused_before_any_job(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "mpi4py" else real(name, *a))
    with pytest.raises(ConfigError, match=r"field 'contact.solver.ranks': 2 MPI ranks need mpi4py.*"
                                          r"roughcontact\[mpi\]"):
        validate_config(SPLIT)
    validate_config(SINGLE)  # one process needs no MPI


# ------------------------------------------------------------------------------ the rules' functions
def _targets(cfg=SPLIT) -> Targets:
    return Targets.from_config(copy.deepcopy(cfg), variants, FIGURES)


def _w(seed="0"):
    return SimpleNamespace(scene="tiny", group=f"kl2_ks8_H0.5_s{seed}")


def test_a_case_over_ranks_is_one_mpi_contact_job():
    t = _targets()
    assert t.contact_group(_w()).kind == "ranks"
    assert t.contact_input(_w("1")) == ["results/tiny/surfaces/kl2_ks8_H0.5_s1.nc"]
    assert t.contact_tasks(_w()) == 2 and t.contact_mpi(_w()) == 1 and t.contact_threads(_w()) == 2
    assert t.contact_bundle(_w()) is None  # an MPI job, in no SLURM bundle
    # 2 ranks of 1.1 x (270 MiB + 0.6 MiB x 2 ranks + 170 B x 32 rows x 64) = 298.7 MiB, rounded up
    assert t.contact_job_mem_mb(_w()) == contact_mpi_mem_mb(64, 2) == 2 * 299
    assert t.contact_job_runtime_min(_w()) == contact_mpi_runtime_min(64, 12, 2) == 10  # 4 x the 5-min floor, / 2
    assert contact_mpi_runtime_min(8192, 30, 4) == int(np.ceil(4 * contact_runtime_min(8192, 30) / 4))
    assert t.contact_params(params.contact)(_w()) == params.contact(t.scenes["tiny"]["contact"])
    with pytest.raises(WorkflowError, match="seed=5"):
        t.contact_input(_w("5"))
    single = _targets(SINGLE)
    assert single.contact_group(_w()).kind == "case" and single.contact_threads(_w()) == 1
    assert single.contact_tasks(_w()) is None and single.contact_mpi(_w()) is None  # not an MPI job
    assert single.contact_bundle(_w()) == "solve"


def test_a_case_written_as_plain_values_is_the_same_case():
    case = ContactCase(LoadSchedule(6, "geometric", p_max=0.01, p_min=0.001, relative_to="rms_slope"),
                       SolverSettings(tol=1e-9, length=(1.0, 2.0), length_unit="um", pressure_unit="MPa"),
                       outputs={"fields": [], "clusters": False, "stiffness": True}, ranks=3)
    doc = json.loads(json.dumps(case_document(case)))
    assert case_from_document(doc) == case
    with pytest.raises(ValueError, match=r"effects \(plasticity\)"):
        case_document(replace(case, settings=SolverSettings(effects=(PlasticityCap(0.5),))))


# ------------------------------------------------------------------------------ the launcher and the runner
def test_the_launcher_is_found_or_named(monkeypatch):
    if MPIEXEC is not None:
        cmd = mpi_command("mpiexec", 3)
        assert Path(cmd[0]).name == "mpiexec" and cmd[1:] == ["-n", "3"]
    assert mpi_command(f"{sys.executable} --flag", 2)[1:] == ["--flag", "-n", "2"]
    with pytest.raises(ValueError, match=r"'no-such-launcher' \(the rule's 'launcher' resource\) is not found.*"
                                         r"roughcontact\[mpi\]"):
        mpi_command("no-such-launcher", 2)
    with pytest.raises(ValueError, match="launcher .* is empty"):
        mpi_command("  ", 2)


def _surface_file(path: Path, n=64, seed=0) -> tuple[Path, np.ndarray]:
    h = generate_surface(n, 1, n // 4, 0.8, seed, rms_slope=0.1)
    xr.Dataset({"heights": (("x", "y"), h)}).to_netcdf(path)
    return path, h


def test_run_case_asks_for_the_file_and_the_runner_refuses_what_ranks_cannot_compute(tmp_path):
    path, h = _surface_file(tmp_path / "s.nc")
    case = ContactCase(LoadSchedule(4, p_max=0.005), ranks=2)
    with pytest.raises(ValueError, match="give the surface's file"):
        run_case(h, case, length=1.0, rms_slope=0.1)
    with pytest.raises(ValueError, match="only a case over MPI ranks reads"):
        run_case(path, replace(case, ranks=1), length=1.0, rms_slope=0.1)
    for changed, named in ((dict(outputs={"fields": [4], "clusters": False}), "outputs['fields']"),
                           (dict(settings=SolverSettings(boundary="free")), "boundary='free'"),
                           (dict(settings=SolverSettings(effects=(PlasticityCap(0.5),))), "effects (plasticity)"),
                           (dict(schedule=LoadSchedule(4, target_area=0.1)), "target_area")):
        bad = replace(case, **changed)
        with pytest.raises(ValueError, match=re.escape(named)):
            run_case(path, bad, length=1.0, rms_slope=0.1, shape=h.shape)


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_run_case_over_ranks_gives_run_cases_answers(tmp_path, caplog):
    path, h = _surface_file(tmp_path / "s.nc")
    case = ContactCase(LoadSchedule(6, p_max=0.005), SolverSettings(length_unit="um", pressure_unit="MPa"),
                       outputs={"fields": [], "clusters": False, "stiffness": True})
    log = logging.getLogger("test_pipeline_mpi")
    with caplog.at_level(logging.INFO, logger="test_pipeline_mpi"):
        [got] = run_case(path, replace(case, ranks=2), length=(1.0, 1.0), rms_slope=0.1, log=log, name="s")
    [ref] = run_case(h, case, length=(1.0, 1.0), rms_slope=0.1)
    assert got.attrs["mpi_ranks"] == 2 and bool(got.converged.all())
    assert np.max(np.abs(got.area_fraction.values - ref.area_fraction.values)) <= 2.0 / h.size
    np.testing.assert_allclose(got.mean_gap.values, ref.mean_gap.values, rtol=1e-6)
    np.testing.assert_allclose(got.contact_stiffness.values, ref.contact_stiffness.values, rtol=1e-4)
    assert np.all(np.abs(got.iterations.values - ref.iterations.values) <= 2)
    assert {k: got.attrs[k] for k in ("load_p0_max", "load_p_max")} == {k: ref.attrs[k] for k in
                                                                         ("load_p0_max", "load_p_max")}
    for name in ("pressure", "mean_gap", "contact_stiffness"):
        assert got[name].attrs["units"] == ref[name].attrs["units"], name
    lines = [r.getMessage() for r in caplog.records]
    assert sum(line.startswith("step ") for line in lines) == 6 and any("over 2 MPI ranks" in x for x in lines)


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_the_mpi_solvers_refusal_comes_back_as_its_one_line(tmp_path):
    path, h = _surface_file(tmp_path / "s.nc", n=8)
    case = ContactCase(LoadSchedule(3, p_max=0.005), ranks=9)  # 9 ranks for 8 rows
    with pytest.raises(ValueError, match=r"^ranks: 9 MPI ranks for 8 rows|each rank needs at least one row"):
        run_case(path, case, length=1.0, rms_slope=0.1, shape=h.shape)


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_processes_the_launcher_started_but_mpi_did_not_join_are_refused(tmp_path):
    """A launcher that starts R unconnected processes (srun without the MPI library's PMI does: R one-rank worlds,
    each solving the whole case) is an error naming the cause, not R copies of the solve."""
    path, h = _surface_file(tmp_path / "s.nc")
    fake = tmp_path / "unjoined"
    # drops "-n R", starts two singletons, exits with the failing one's status
    fake.write_text('#!/bin/sh\nshift 2\n"$@" & pid=$!\n"$@"; s=$?\nwait $pid || s=$?\nexit $s\n')
    fake.chmod(0o755)
    case = ContactCase(LoadSchedule(3, p_max=0.005), ranks=2)
    with pytest.raises(ValueError, match=r"ranks: 2 MPI ranks were asked for, but this process sees a world of 1.*"
                                         r"srun --mpi=pmi2"):
        run_case(path, case, shape=h.shape, length=1.0, rms_slope=0.1, launcher=str(fake))
    fake.write_text("#!/bin/sh\nexit 0\n")  # a wrapper that runs nothing and says all is well
    with pytest.raises(RuntimeError, match="ended with status 0 but wrote no file"):
        run_case(path, case, shape=h.shape, length=1.0, rms_slope=0.1, launcher=str(fake))


# ------------------------------------------------------------------------------ the reads of a contact job over ranks
def _run_job(script: str, tmp_path: Path, block, surface_file: Path, out: Path | None = None) -> Path:
    """``workflow/scripts/<script>`` run in this process as Snakemake runs it (its ``snakemake`` object), for case
    kl2_ks8_H0.5_s0 of the validated contact block ``block``; its log file."""
    log = tmp_path / f"{script}.log"
    case = {"k_l": "2", "k_s": "8", "H": "0.5", "seed": "0"}
    job = SimpleNamespace(wildcards=SimpleNamespace(scene="tiny", group="kl2_ks8_H0.5_s0", **case),
                          input=[str(surface_file)], output=[str(out or surface_file)], log=[str(log)],
                          params=SimpleNamespace(settings=params.contact(block), surface=params.surface(block),
                                                 cases=[case], kind="ranks"),
                          resources=SimpleNamespace(launcher="mpiexec"), threads=1)
    try:
        runpy.run_path(str(REPO / "workflow" / "scripts" / script), init_globals={"snakemake": job})
    finally:  # run_logged's handlers: closed, so that the next job logs to its own file only
        for handler in logging.getLogger("roughcontact").handlers:
            handler.close()
        logging.getLogger("roughcontact").handlers.clear()
    return log


class _Launched(Exception):
    """Where the stand-in for run_case stops the job: what the job checked is all it read."""


def test_the_mpi_jobs_check_reads_the_header_and_a_sample_of_rows(tmp_path, monkeypatch):
    """A contact job over ranks (its script, run here) reads SAMPLE_ROWS rows of a 1024² surface from the file, one read
    each, and nothing else of the heights (xarray's netCDF4 reads counted), its peak memory far below the field's
    8 MiB (tracemalloc), and passes on the grid, the cell and the rms slope the whole field gives."""
    block = _contact(**{"surface.N": 1024})
    surface = tmp_path / "surface.nc"
    _run_job("generate_surface.py", tmp_path, block, surface)
    launched = {}

    def stand_in(path, case, **kw):
        launched.update(kw, path=path, ranks=case.ranks)
        raise _Launched

    monkeypatch.setattr(case_module, "run_case", stand_in)
    reads = heights_reads(monkeypatch)
    tracemalloc.start()
    try:
        with pytest.raises(_Launched):
            _run_job("contact.py", tmp_path, block, surface, out=tmp_path / "contact.nc")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert reads == [1024] * SAMPLE_ROWS, reads
    assert peak < 8 * 1024**2 / 4, peak
    whole = read_dataset(surface, stage="surface")
    heights, length = surface_heights(whole, surface)
    assert {k: launched[k] for k in ("path", "ranks", "shape", "length", "rms_slope")} == {
        "path": str(surface), "ranks": 2, "shape": heights.shape, "length": length,
        "rms_slope": float(whole.rms_slope.squeeze())}


@needs_mpi
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_a_nan_outside_the_checked_rows_ends_every_rank_naming_the_file(tmp_path):
    """A NaN in rank 1's rows that the job's sample misses: the check passes, the ranks refuse the file in one line
    naming it, its rows and the remedy (exit status 2 within the cap, no traceback, no step), and the job logs that
    line and ends with status 1, writing nothing."""
    block = _contact()
    surface = tmp_path / "surface.nc"
    _run_job("generate_surface.py", tmp_path, block, surface)
    with xr.open_dataset(surface) as ds:
        spoilt = ds.load()
    spoilt["heights"][..., 40, 5] = np.nan  # N = 64 on 2 ranks: rank 1's rows 32..63; sampled: 0, 9, .., 36, 45, ..
    spoilt.to_netcdf(tmp_path / "spoilt.nc")
    surface = tmp_path / "spoilt.nc"
    with lazy_dataset(surface, stage="surface") as ds:
        assert surface_grid(ds, surface) == ((64, 64), 1.0)
    message = (f"{surface}: 'heights' holds 1 NaN or infinite value(s) in rows 32..63 (rank 1's); every height must "
               "be finite: remake the file (a pipeline's surface file: remove it, or rerun with -f), or fill those "
               "points")
    out = tmp_path / "c.nc"
    res = subprocess.run([MPIEXEC, "-n", "2", sys.executable, "-m", "roughcontact.solver.mpi", "--surface",
                          str(surface), "--p-max", "0.005", "--steps", "2", "--out", str(out)],
                         capture_output=True, text=True, timeout=CAP)
    assert res.returncode == 2, res.stderr
    assert [line for line in res.stderr.splitlines() if "error" in line.lower()] == [f"error: {message}"], res.stderr
    assert "Traceback" not in res.stderr and "step 1:" not in res.stderr and not out.exists()
    out = tmp_path / "contact.nc"
    with pytest.raises(SystemExit) as end:
        _run_job("contact.py", tmp_path, block, surface, out=out)
    assert end.value.code == 1 and not out.exists()
    errors = [line for line in (tmp_path / "contact.py.log").read_text().splitlines() if " ERROR " in line]
    assert len(errors) == 1 and errors[0].endswith(f"ERROR {message}"), errors


# ------------------------------------------------------------------------------ the workflow
@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_the_slurm_profile_makes_it_an_mpi_job(tmp_path):
    """Under profiles/slurm a contact job over ranks carries ``mpi`` and ``tasks=2`` (the executor's MPI job: one
    allocation of 2 tasks) and ``launcher=srun`` (srun inside it), 1 thread per task, and joins no group; locally
    ``launcher=mpiexec`` and 2 threads. One-process contact jobs carry neither ``mpi`` nor ``tasks`` (the executor
    would submit them, and their group job with its tasks added up, as MPI jobs)."""
    if importlib.util.find_spec("snakemake_executor_plugin_slurm") is None:
        pytest.skip("snakemake-executor-plugin-slurm not installed (pip install -e '.[slurm]')")
    if importlib.util.find_spec("mpi4py") is None:
        pytest.skip("mpi4py not installed (pip install 'roughcontact[mpi]'): the scene is refused before planning")
    wd = copy_workflow(tmp_path / "wf", SPLIT)
    target = CONTACT.format(H="0.5", seed=0)
    res = run_snakemake(wd, "-n", "--workflow-profile", "profiles/slurm", *TARGETS)
    assert res.returncode == 0, res.stderr[-3000:]
    job = res.stdout.split("rule contact:")[1].split("\n\n")[0]
    assert "mpi=1" in job and "tasks=2" in job and "launcher=srun" in job and "threads:" not in job, job
    mem = contact_mpi_mem_mb(64, 2)
    assert f"mem_mb={mem}," in job and f"mem_mb_per_cpu={-(-mem // 2)}," in job, job  # 1 CPU a rank
    # each MPI job an allocation of its own: in no group job (a grouped job's rule line is indented under it)
    assert res.stdout.count("\nrule contact:") == 2 and "Group job solve" not in res.stdout, res.stdout[-3000:]
    # one-process cases are bundled (group-components: 10 a SLURM job)
    single = copy_workflow(tmp_path / "single", SINGLE)
    res = run_snakemake(single, "-n", "--workflow-profile", "profiles/slurm", *TARGETS)
    assert res.returncode == 0, res.stderr[-3000:]
    bundle = res.stdout.split("Group job solve")[1].split("Job stats")[0]
    assert bundle.count("    rule contact:") == 2 and "launcher=srun" in bundle, bundle
    assert "mpi=" not in bundle and "tasks=" not in bundle and "mem_mb_per_cpu" not in bundle, bundle
    res = run_snakemake(wd, "-n", target)
    job = res.stdout.split("rule contact:")[1].split("\n\n")[0]
    assert "launcher=mpiexec" in job and "tasks=2" in job and "threads: 2" in job, job
    assert f"mem_mb_per_cpu={-(-mem // 4)}," in job, job  # 2 ranks of 2 threads


def test_an_mpi_job_asks_slurm_for_its_memory_per_cpu_not_per_node():
    """SLURM grants ``--mem`` per node, so an MPI job whose ranks span nodes would ask each node for the memory of
    all; the contact job over ranks gives ``mem_mb_per_cpu`` (its memory over ``ranks x threads``), which the SLURM
    executor turns into ``--mem-per-cpu`` in place of ``--mem`` (checked on the executor's own submit command); a
    job in one process keeps ``--mem``. 256 ranks at N = 32768 ask 1214 MB a CPU, not 311 GB a node."""
    t, single = _targets(), _targets(SINGLE)
    mem = t.contact_job_mem_mb(_w())
    assert t.contact_job_mem_mb_per_cpu(_w(), threads=1) == -(-mem // 2)
    assert t.contact_job_mem_mb_per_cpu(_w(), threads=3) == -(-mem // 6)
    assert single.contact_job_mem_mb_per_cpu(_w()) is None
    # 1.1 x (270 + 0.6 x 256 + 170 B x 128 rows x 32768 / 2^20) = 1.1 x 1103.6 = 1213.96 MiB, rounded up
    assert -(-contact_mpi_mem_mb(32768, 256) // 256) == 1214
    if importlib.util.find_spec("snakemake_executor_plugin_slurm") is None:
        pytest.skip("snakemake-executor-plugin-slurm not installed (pip install -e '.[slurm]')")
    from snakemake_executor_plugin_slurm.submit_string import get_submit_command

    class Resources(dict):
        __getattr__ = dict.__getitem__

    def submit(resources):
        job = SimpleNamespace(resources=Resources({k: v for k, v in resources.items() if v is not None}), threads=1)
        params = dict(run_uuid="u", slurm_logfile="l", comment_str="c", account="", partition="", workdir=None)
        return get_submit_command(job, params)

    mpi_job = submit(dict(mem_mb=mem, mem_mb_per_cpu=t.contact_job_mem_mb_per_cpu(_w()), tasks=2, mpi=1))
    assert f"--mem-per-cpu {-(-mem // 2)}" in mpi_job and "--mem " not in mpi_job and "--ntasks=2" in mpi_job, mpi_job
    one = submit(dict(mem_mb=single.contact_job_mem_mb(_w()), mem_mb_per_cpu=single.contact_job_mem_mb_per_cpu(_w())))
    assert f"--mem {single.contact_job_mem_mb(_w())}" in one and "--mem-per-cpu" not in one, one


@pytest.mark.skipif(not Path("/proc/self/pagemap").exists(), reason="/proc/self/pagemap is Linux's")
def test_the_pages_a_process_maps_are_counted_page_by_page():
    """benchmarks/mpi/scaling.py's ``mapped_bytes`` (the other ranks' shared pages a rank maps, counted apart from its
    own memory): a shared mapping of 16 pages, 3 of them written (one at each end, one inside a range that starts
    mid-page), counts 3 pages in all and only the touched ones in each range."""
    import ctypes
    import mmap
    import os

    scaling = load_script(REPO / "benchmarks" / "mpi" / "scaling.py", "mpi_scaling")
    page = os.sysconf("SC_PAGE_SIZE")
    m = mmap.mmap(-1, 16 * page, flags=mmap.MAP_SHARED)
    base = ctypes.addressof(ctypes.c_char.from_buffer(m))
    try:
        assert scaling.mapped_bytes([(base, 16 * page)]) == 0
        for k in (0, 7, 15):
            m[k * page + 5] = 1
        assert scaling.mapped_bytes([(base, 16 * page)]) == 3 * page
        assert scaling.mapped_bytes([(base + page // 2, page)]) == page  # pages 0 and 1: page 0 written
        assert scaling.mapped_bytes([(base + page, 6 * page), (base + 15 * page, page)]) == page
    finally:
        m.close()


def test_a_tiled_grid_is_planned_in_place_from_its_measured_plans(tmp_path, monkeypatch):
    """benchmarks/mpi/scaling.py's ``measured_plans`` (one rank on a tiled grid, the weak scaling's serial
    reference): the grid's 2-D pairs are measured into a copy of the shipped wisdom, with a record of them, and the
    process then plans that grid in place from the copy, as a square grid's; the shipped file is left unchanged."""
    pytest.importorskip("pyfftw")
    from roughcontact.core import fft
    from roughcontact.solver.mpi import slabs

    scaling = load_script(REPO / "benchmarks" / "mpi" / "scaling.py", "mpi_scaling")
    shape = (128, 64)
    shipped = fft.WISDOM_FILE.read_bytes()
    monkeypatch.setattr(fft, "WISDOM_FILE", fft.WISDOM_FILE)  # restored after: measured_plans points it at the copy
    monkeypatch.setattr(fft, "has_shipped_plans", fft.has_shipped_plans)
    assert not fft.has_shipped_plans(shape)
    try:
        scaling.measured_plans(shape, tmp_path)
        assert fft.WISDOM_FILE == tmp_path / "wisdom.json"
        assert fft.has_shipped_plans(shape) and fft.has_shipped_plans((64, 64)) and not fft.has_shipped_plans((64, 128))
        data = json.loads(fft.WISDOM_FILE.read_text())
        chosen = data["machines"].get(fft.machine_key(), data["machines"][data["default"]])
        assert chosen["benchmark"] == f"{shape} on one rank"
        import pyfftw

        for real in (np.float32, np.float64):
            plans = slabs.SlabPlans(slabs.Slabs(shape, 1, 0), 1, real, 1)
            assert plans.in_place == (real == np.float32)
            # the copy's plans hold this grid, both precisions and directions: planning from them alone succeeds
            with fft.shipped_wisdom_only():
                only = ("FFTW_ESTIMATE", "FFTW_WISDOM_ONLY")
                pyfftw.FFTW(plans.real_in, plans.row_spec, axes=(1, 2), flags=only)
                pyfftw.FFTW(plans.row_spec, plans.real_out, axes=(1, 2), direction="FFTW_BACKWARD", flags=only)
    finally:
        fft.shipped_wisdom.cache_clear()
    assert (REPO / "src" / "roughcontact" / "core" / "fftw_wisdom.json").read_bytes() == shipped


#: ``benchmarks/mpi/memory.py run``'s output, as run on 2026-12-05 with the shared-memory windows and the slab
#: transforms in place (the raw lines in a results file).
MEMORY_RUN = REPO / "benchmarks" / "results" / "2026-12-05_mpi_memory_per_rank.md"


def test_each_rank_asks_more_than_any_measured_rank_held():
    """The rule's share of a rank (``contact_mpi_mem_mb`` over the ranks) against what the fullest rank of every run of
    ``benchmarks/mpi/memory.py run`` held of its own (its peak RSS less the other ranks' shared-memory pages it mapped;
    the raw lines in the results file, 1-64 ranks, 256²-8192²): above each by 5 % at least (no measured rank would
    have met its limit where the machine charges a shared page once, as a memory cgroup does) and at most a third
    (no node asked for in vain); what each held 0.85-1.02 of the model without its margin (``rank_memory_mib``;
    one rank, whose 2-D pair runs in place with no exchange buffers, from 0.8); the fit of those lines at most the
    model's constants and within 10 % of them (the model was fitted to the runs of 2026-12-03, before the windows and
    the slab transforms in place, which held 0-5 % more). The other ranks' pages a rank maps are those the layout
    predicts (``memory.peer_pages``) within 2 % from 2048² up (the lines print MiB, too coarse below)."""
    from roughcontact.solver.mpi import memory

    fit = load_script(REPO / "benchmarks" / "mpi" / "memory.py", "mpi_memory")
    text = MEMORY_RUN.read_text()
    runs = fit.runs(text)
    assert {r[2] for r in runs} >= {1, 2, 4, 8, 16, 32, 64} and {r[0] for r in runs} >= {256, 2048, 4096, 8192}
    for nx, ny, ranks, held, _rss in runs:
        held_mib = held * 1024
        assert (0.85 if ranks > 1 else 0.8) <= held_mib / memory.rank_memory_mib((nx, ny), ranks) <= 1.02, (nx, ranks)
        share = contact_mpi_mem_mb(nx, ranks) / ranks
        assert 0.75 * share <= held_mib <= share / 1.05, (nx, ranks, held, share)
    a, c, b = fit.fit(runs)
    assert 0.9 * memory.RANK_MIB <= a <= memory.RANK_MIB and 0.5 * memory.PER_RANK_OF_JOB_MIB <= c
    assert c <= memory.PER_RANK_OF_JOB_MIB and 0.9 * memory.BYTES_PER_NODE <= b <= memory.BYTES_PER_NODE
    assert MPI_MEMORY_MARGIN == 1.1
    checked = 0
    for m in filter(None, (fit.LINE.search(line.strip()) for line in text.splitlines())):
        nx, ny, ranks = int(m[1]), int(m[2]), int(m[3])
        if nx >= 2048 and ranks > 1:
            measured = [float(v) * 2**30 for v in m[5].split()]
            for got, want in zip(measured, fit.peer_pages((nx, ny), ranks), strict=True):
                assert got == pytest.approx(want, rel=0.02), (nx, ranks)
            checked += 1
    assert checked >= 10


@needs_mpi
@pytest.mark.slow  # one tiny run (2 + 2 cases at N = 64, contact files only) and a rerun: ~1.5 min on 2 busy cores
def test_ranks_2_equals_the_run_in_one_process(tmp_path):
    # both scenes in one workflow, their cases solved side by side in one Snakemake run
    cfg = copy.deepcopy(SPLIT)
    cfg["scenes"]["single"] = copy.deepcopy(SINGLE["scenes"]["tiny"])
    wd = copy_workflow(tmp_path / "wf", cfg)
    single = [t.replace("results/tiny/", "results/single/") for t in TARGETS]
    res = run_snakemake(wd, "-j2", *TARGETS, *single)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert sorted(p.name for p in (wd / "results/tiny/contact").iterdir()) == sorted(Path(t).name for t in TARGETS)
    assert [p.name for p in (wd / "results/tiny").iterdir() if p.name.startswith("contact")] == ["contact"]
    for target, other in zip(TARGETS, single, strict=True):
        with xr.open_dataset(wd / target) as a, xr.open_dataset(wd / other) as b:
            a, b = a.load(), b.load()
        assert set(a.variables) == set(b.variables), target
        assert a.attrs["mpi_ranks"] == 2 and a.attrs["fft_backend"] == "mpi-slab", target
        recorded_a, recorded_b = json.loads(a.attrs["scene_parameters"]), json.loads(b.attrs["scene_parameters"])
        assert recorded_a["solver"].pop("ranks") == 2 and recorded_a == recorded_b, target
        np.testing.assert_allclose(a.area_fraction, b.area_fraction, atol=2 / 64**2, err_msg=target)
        np.testing.assert_allclose(a.mean_gap, b.mean_gap, rtol=1e-6, err_msg=target)
        np.testing.assert_allclose(a.kappa, b.kappa, rtol=1e-4, err_msg=target)
        assert np.all(np.abs(a.iterations.values - b.iterations.values) <= 2) and a.converged.values.all(), target
    # the MPI solves again: byte-identical
    first = {t: (wd / t).read_bytes() for t in TARGETS}
    solved = [wd / t for t in TARGETS]
    stamps = [p.stat().st_mtime_ns for p in solved]
    res = run_snakemake(wd, "-j2", "-R", "contact", *TARGETS)
    assert res.returncode == 0, res.stderr[-3000:]
    assert all(p.stat().st_mtime_ns != t for p, t in zip(solved, stamps, strict=True))  # solved again
    assert {t: (wd / t).read_bytes() for t in TARGETS} == first
