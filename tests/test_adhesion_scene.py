"""An adhesive scene computes and shows adhesion: the load cycle, the pull-off, and no CEL fit.

The contact evolution law and the theories of Fig. 2 describe contact without adhesion, so an adhesive
scene runs no fit and draws none of the non-adhesive figures; it draws the hysteresis and the pull-off,
and its report shows a pull-off table instead of a fit row.
"""
import copy
import os
import re

import numpy as np
import pytest
import xarray as xr

from caption_check import assert_scene_captions_true
from cfcheck import assert_cf_clean
from conftest import REPO, copy_workflow, run_snakemake
from roughcontact.figures.registry import scene_figures
from roughcontact.pipeline.scenes import validate_config
from test_workflow import TINY, _jobs

ADHESION = {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3}}


def _adhesive(**contact_extra) -> dict:
    cfg = copy.deepcopy(TINY)
    del cfg["scenes"]["tiny"]["representativity"]  # not what this file tests
    contact = cfg["scenes"]["tiny"]["contact"]
    contact.update({"effects": copy.deepcopy(ADHESION), "load": {"p_max": 0.005, "n_steps": 4}}, **contact_extra)
    return cfg


def test_adhesive_scene_asks_for_the_adhesion_figures_only():
    scene = validate_config(_adhesive())["scenes"]["tiny"]
    figures = scene_figures(scene)
    assert {"hysteresis", "pull_off"} <= set(figures)
    assert not {"area_load", "kappa", "dpbar"} & set(figures)
    plain = validate_config(copy.deepcopy(TINY))["scenes"]["tiny"]
    assert {"area_load", "kappa", "dpbar"} <= set(scene_figures(plain))
    assert not {"hysteresis", "pull_off"} & set(scene_figures(plain))


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_adhesive_scene_plans_no_fit(tmp_path):
    wd = copy_workflow(tmp_path / "plan", _adhesive())
    res = run_snakemake(wd, "-n")
    assert res.returncode == 0, res.stderr[-2000:]
    jobs = _jobs(res.stdout)
    assert "fit_cel" not in jobs and jobs.get("contact") == 4


@pytest.mark.slow
def test_adhesive_scene_draws_the_cycle_and_the_pull_off(adhesion_run, tmp_path):
    """The `adhesion` scene's tiny variant (the session's run; the contact block of :func:`_adhesive`)."""
    wd, out = adhesion_run.wd, adhesion_run.out
    for name in ("hysteresis", "pull_off"):
        assert (out / "figures" / f"{name}.png").stat().st_size > 10_000
    assert not (out / "fit").exists() and not (out / "figures" / "kappa.png").exists()
    summary = (out / "report" / "summary.rst").read_text()
    result = (out / "report" / "result.rst").read_text()
    assert "pull-off pressure of each group" in result and "No contact evolution law is fitted" in result
    assert "Contact evolution law fit" not in summary
    assert "published" not in summary + result and "contact.effects.adhesion.law" in summary
    intro = (out / "report" / "intro.rst").read_text()  # the page opens with what the scene computes (issue 60)
    assert "**adhesive contact**" in intro and "evolution law" not in intro and "representativity" not in intro
    shown = assert_scene_captions_true(wd, adhesion_run.scene)  # no reference line promised
    assert shown == {"hysteresis": [], "pull_off": []}
    with xr.open_dataset(out / "aggregate" / "contact.nc") as agg:
        pull = agg["pull_off_pressure"].values
        assert agg["pull_off_status"].dims == ("k_l", "k_s", "H", "seed")
        assert np.all(np.isfinite(pull) == (agg["pull_off_status"].values == 0)) and np.isfinite(pull).all()
        assert "unload_step" not in agg.dims  # the branch stays in each case's file
    case = out / "contact" / "kl2_ks8_H0.5_s0.nc"
    with xr.open_dataset(case) as ds:
        assert ds.sizes["unload_step"] > 4 and float(ds["adhesive_zone_cells"].squeeze()) == pytest.approx(3.2)
    assert_cf_clean([case, out / "aggregate" / "contact.nc"], tmp_path / "tables")


def _aggregate():
    """A made-up aggregate of 2 H x 2 seeds: one case untrusted (zone unresolved), its pull-off NaN."""
    from roughcontact.solver.adhesion import PULL_OFF_STATUS

    dims = ("k_l", "k_s", "H", "seed")
    pull = np.array([1e-4, 3e-4, 2e-4, np.nan]).reshape(1, 1, 2, 2)
    status = np.array([0, 0, 0, 1], dtype=np.int8).reshape(1, 1, 2, 2)
    flags = {"flag_values": np.arange(len(PULL_OFF_STATUS), dtype=np.int8), "flag_meanings": " ".join(PULL_OFF_STATUS)}
    return xr.Dataset({
        "pull_off_pressure": (dims, pull, {"units": "1"}),
        "pull_off_status": (dims, status, {"units": "1", **flags}),
        "adhesive_zone_cells": (dims, np.full((1, 1, 2, 2), 12.8)),
        "area_fraction": (dims + ("step",), np.full((1, 1, 2, 2, 3), 0.1)),
        "case_present": (dims, np.ones((1, 1, 2, 2), dtype=bool)),
    }, coords={"k_l": [4.0], "k_s": [32.0], "H": [0.36, 0.84], "seed": [0, 1], "step": [1, 2, 3]},
        attrs={"e_star": 2.0})


def test_pull_off_table_pools_the_trusted_seeds_and_counts_the_others():
    from roughcontact.studies.report_tables import pull_off_table

    text = pull_off_table(_aggregate())
    # H = 0.36: both seeds, (1e-4 + 3e-4) / 2 / E* = 1e-4 +- s.d. 1.414e-4 / 2 = 7.1e-5, rounded to the s.d.'s one
    # figure (core.precision); H = 0.84: one of two (three figures), the other said why
    assert "0.00010 ± 0.00007" in text and "2 of 2" in text
    assert "0.0001\n" in text and "1 of 2" in text and "1 adhesive zone unresolved" in text
    assert "No contact evolution law is fitted" in text


def test_pull_off_table_prints_its_numbers_at_their_precision_and_its_maths_as_maths():
    """The adhesion scene's table read "0.0003511 ± 0.00011", "0.000835 ± 1.3e-05", "E* rho^2 / w", "k_l = 4, k_s = 32"
    and set p_off's "off" under the bar."""
    from docutils.core import publish_parts

    from roughcontact.studies import report
    from roughcontact.studies.report_tables import pull_off_table

    agg = _aggregate()
    e_star = agg.attrs["e_star"]
    pulls = [[0.000835 - 0.92e-5, 0.000835 + 0.92e-5], [0.0003511 - 0.78e-4, 0.0003511 + 0.78e-4]]
    agg["pull_off_pressure"].values = np.array(pulls).reshape(1, 1, 2, 2) * e_star
    agg["pull_off_status"].values[...] = 0
    text = pull_off_table(agg)
    assert "0.000835 ± 0.000013" in text and "0.00035 ± 0.00011" in text, text
    assert not re.search(r"\de[-+]\d", text) and "E* rho" not in text and "p_off/E*" not in text
    assert r":math:`E^* \rho^2 / w`" in text
    assert r":math:`k_l = 4`, :math:`k_s = 32`, :math:`H = 0.36`" in text
    assert r"pull-off :math:`\bar p_\mathrm{off}/E^*` (mean ± s.d.)" in text
    old = os.environ.get("DOCUTILSCONFIG")
    try:
        report.render_maths_as_mathml(REPO / "workflow" / "report" / "docutils.conf")
        html = publish_parts(text, writer="html", settings_overrides={"report_level": 1, "halt_level": 2})["body"]
    finally:
        os.environ.pop("DOCUTILSCONFIG") if old is None else os.environ.update(DOCUTILSCONFIG=old)
    flat = html.replace("\n", "").replace(" ", "")
    assert "<munderover>" not in flat and "<msub><mover" in flat  # "off" beside the bar, not under it
    assert flat.count("<msub><mi>k</mi><mi>l</mi></msub>") == 2  # k_l of each row's group


def test_pull_off_figure_says_what_it_left_out():
    from roughcontact.figures.adhesion import fig_pull_off

    fig = fig_pull_off(_aggregate(), ("k_l", "k_s", "H", "seed"))
    title = fig.axes[0].get_title()
    assert title == "3 of 4 cases trusted; left out: 1 adhesive zone unresolved"
