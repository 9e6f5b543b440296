"""A Snakemake run of this workflow returns when its work is done (roughcontact.pipeline.run_end).

Snakemake's job-rate limit leaves a non-daemon re-evaluation timer pending one timespan after each
round of job selection; the workflow's onsuccess/onerror hooks cancel it. The runs below set the
timespan to an hour: without the hooks each command would hold its process for that hour, and
run_snakemake's cap (10 min, a hang catcher, not a speed measurement) would fail the test.
"""
import threading

import pytest

from conftest import copy_workflow, run_snakemake
from roughcontact.pipeline.run_end import cancel_job_rate_timers, plain_text, where_it_is
from test_workflow import TINY

HOUR_LIMIT = ("--max-jobs-per-timespan", "10000/1h")
SURFACE = "results/tiny/surfaces/kl2_ks8_H0.5_s1.nc"


def test_cancels_only_the_scheduler_timers():
    def reevaluate():  # as Snakemake's scheduler defines it
        raise AssertionError("a cancelled timer ran")

    reevaluate.__module__ = "snakemake.scheduling.job_scheduler"
    other_ran = threading.Event()
    theirs, ours = threading.Timer(3600, reevaluate), threading.Timer(0.2, other_ran.set)
    theirs.start()
    ours.start()
    try:
        assert cancel_job_rate_timers() == 1
        theirs.join(timeout=10)
        assert not theirs.is_alive()
        assert other_ran.wait(timeout=10), "a timer that is not Snakemake's was cancelled"
    finally:
        theirs.cancel()
        ours.cancel()


@pytest.mark.slow
def test_a_run_returns_after_its_last_job_whether_it_succeeds_or_fails(tmp_path):
    wd = copy_workflow(tmp_path / "wf", TINY)
    res = run_snakemake(wd, "-j1", *HOUR_LIMIT, SURFACE, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    # it ends saying where the result is (issue 62): here one file was made, so no result yet
    said = [line for line in res.stderr.splitlines() if line.startswith("roughcontact: ")][-3:]
    assert said == [
        "roughcontact: Result: not made by this run (the whole scene makes it: snakemake -j2 --config scene=tiny)",
        "roughcontact: Figures: none yet under results/tiny/figures/",
        "roughcontact: Report: snakemake --report report.html --config scene=tiny (one HTML file: the result, every "
        "figure with its caption, the scene's tables, the run's provenance)"], res.stderr[-3000:]
    # a job that fails: the case's surface file replaced by one it cannot read (newer, so not remade)
    (wd / SURFACE).write_text("not a NetCDF file")
    res = run_snakemake(wd, "-j1", *HOUR_LIMIT, "results/tiny/contact/kl2_ks8_H0.5_s1.nc", timeout=600)
    assert res.returncode == 1 and "not a readable NetCDF file" in res.stderr, res.stderr[-3000:]


def test_where_it_is_gives_the_result_line_the_figures_and_the_report(tmp_path):
    """What a finished run says last (issue 62): the result line without markup, the figures, the command."""
    out = tmp_path / "results" / "demo"
    (out / "report").mkdir(parents=True)
    (out / "figures").mkdir()
    (out / "report" / "result.rst").write_text(
        "**Result** (:math:`\\lambda_l = L/16`, :math:`\\lambda_s = L/32`, :math:`H` pooled, 3 seeds): "
        "κ/√(2π) = 1.06 [1.03, 1.16], μ = 0.54 [0.15, 0.66] \\*; the paper: κ/√(2π) = 1.145 ± 0.002.\n\n"
        "\\* not constrained by the data.\n")
    for name in ("kappa", "dpbar"):
        (out / "figures" / f"{name}.png").write_bytes(b"png")
    result, figures, report = where_it_is(out, "demo")
    assert result == ("Result (λ_l = L/16, λ_s = L/32, H pooled, 3 seeds): κ/√(2π) = 1.06 [1.03, 1.16], "
                      "μ = 0.54 [0.15, 0.66] *; the paper: κ/√(2π) = 1.145 ± 0.002.")
    assert figures == f"Figures: {out / 'figures'}/ (2 figures, each as PNG and PDF with its caption)"
    assert report.startswith("Report: snakemake --report report.html --config scene=demo")
    assert plain_text(":math:`\\bar{p}_\\mathrm{off}/E^*`") == "p_off/E^*"
    # a scene that draws no figure (an adhesive scene without unloading) says so; an unfinished one, "none yet"
    empty = tmp_path / "results" / "bare"
    assert where_it_is(empty, "bare", drawn=0)[1] == "Figures: none (this scene draws no figure)"
    assert where_it_is(empty, "bare", drawn=3)[1].startswith("Figures: none yet under")
