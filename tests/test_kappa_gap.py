"""The κ-gap study: its pieces against exact answers, a tiny run end to end, the published page."""
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from cfcheck import assert_cf_clean
from compare_outputs import assert_text_close
from conftest import KAPPA_GAP, run_snakemake
from roughcontact.analysis.fit.estimators import PAPER_CEL
from roughcontact.studies import kappa_gap
from roughcontact.studies.kappa_gap.analysis import closes

REPO = Path(__file__).resolve().parents[1]
PUBLISHED = REPO / "docs" / "reproduction"


def _cel_area(x, kappa, mu, beta):
    return (beta + (kappa * x) ** (mu - 1.0)) ** (1.0 / (mu - 1.0))


def test_kappa_at_areas_of_a_linear_law_is_its_constant():
    p0 = np.linspace(1e-4, 5e-3, 30)
    area = 2.3 * p0 / 0.1           # A/A0 = κ p0 / h', κ = 2.3
    k = kappa_gap.kappa_at_areas(area, p0, 0.1, areas=(0.01, 0.05, 0.1))
    np.testing.assert_allclose(k, 2.3, rtol=1e-12)
    assert np.isnan(kappa_gap.kappa_at_areas(area, p0, 0.1, areas=(0.5,))[0])


def test_paper_kappa_inverts_the_cel():
    kappa, mu, beta = (PAPER_CEL[c][0] for c in ("kappa", "mu", "beta"))
    x = np.array([0.004, 0.01, 0.03])
    a = _cel_area(x, kappa, mu, beta)
    np.testing.assert_allclose(kappa_gap.paper_kappa(a), a / x, rtol=1e-12)
    # κ_eff tends to κ at small areas and falls with A (the paper's Fig. 3)
    k = kappa_gap.paper_kappa((1e-6, 0.01, 0.1))
    assert abs(k[0] / kappa - 1) < 1e-3 and k[0] > k[1] > k[2]


def test_fit_kappa_recovers_the_constant_with_mu_beta_held():
    mu, beta = PAPER_CEL["mu"][0], PAPER_CEL["beta"][0]
    x = np.linspace(0.002, 0.05, 30)
    slopes = np.array([0.1, 0.12])
    area = np.stack([_cel_area(x, 2.7, mu, beta)] * 2)
    p0 = x[None, :] * slopes[:, None]
    assert kappa_gap.fit_kappa(area, p0, slopes) == pytest.approx(2.7, rel=1e-7)


def test_richardson_recovers_limit_and_order():
    n = np.array([512, 1024, 2048, 4096])
    v = 2.4 + 0.7 * (1024 / n) ** 1.3
    limit, order = kappa_gap.richardson(v)
    assert limit == pytest.approx(2.4, rel=1e-12) and order == pytest.approx(1.3, rel=1e-10)
    limit, order = kappa_gap.richardson([1.0, 1.1, 1.0])   # differences that grow or flip sign
    assert limit == 1.0 and math.isnan(order)


@pytest.mark.parametrize("shift, se, verdict", [
    ([0.03, 0.03], [0.001, 0.001], "**yes**"),     # moves κ up by the gap's size
    ([0.01, 0.0], [0.001, 0.001], "**part**"),     # up by > 2 s.e. and ≥ 10 % of the gap somewhere, short of it
    ([0.002, 0.0], [0.0001, 0.0001], "**no**"),    # significant but under 10 % of the gap: negligible
    ([0.001, -0.02], [0.001, 0.001], "**no**"),    # within noise upward, or down
    ([np.nan, 0.01], [np.nan, 0.001], "**part**"),  # an area not reached counts for nothing
])
def test_closes_follows_its_printed_rule(shift, se, verdict):
    gap = np.array([0.03, 0.03])   # the paper's κ lies 3 % above ours
    assert closes(np.array(shift), np.array(se), gap, np.array([0.002, 0.002])) == verdict


TINY = KAPPA_GAP


@pytest.mark.slow
def test_tiny_kappa_gap_scene_end_to_end(kappa_gap_run, tmp_path):
    """The tiny kappa-gap study (the session's run, shared with test_reader)."""
    wd = kappa_gap_run.wd
    out = kappa_gap_run.out / "kappa_gap"
    data = xr.open_dataset(out / "kappa-gap.nc")
    assert sorted(data.variant.values) == sorted(TINY["scenes"]["kg"]["kappa_gap"]["variants"])
    assert data.sizes["case"] == 4 and int(data["stopped"].sel(variant="baseline").sum()) == 4 * 30
    # p > 0 is the smallest of the definitions that count touching nodes; the corrected one is smaller still
    base = data.sel(variant="baseline")
    assert np.all(base["area_gap_1em3"] >= base["area_gap_1em4"])
    assert np.all(base["area_gap_1em4"] >= base["area_pressure"])
    assert np.all(base["area_corrected"] < base["area_pressure"])
    page = (out / "kappa-gap.md").read_text()
    for words in ("## The gap to explain", "Stanley & Kato, stopped at tol = 1e-3", "**Conclusion.**",
                  "continuum limit of the perimeter-corrected area"):
        assert words in page
    # CF-clean, the table and a case of each solver (variable names hold no '-': area_gap_1em4)
    assert_cf_clean([out / "kappa-gap.nc", out / "sk" / "kl2_ks8_H0.5_s0.nc", out / "ref" / "kl2_ks8_H0.5_s0.nc"],
                    tmp_path / "tables")
    # a case solved again, and the table made again from the cases, write the same bytes (no timing
    # inside: a job's wall time is its benchmark's)
    case, table = out / "sk" / "kl2_ks8_H0.5_s0.nc", out / "kappa-gap.nc"
    first = {path: path.read_bytes() for path in (case, table)}
    case.unlink()
    assert run_snakemake(wd, "-j1", "-R", "kappa_gap_summary", "--", str(case.relative_to(wd)),
                         str(table.relative_to(wd))).returncode == 0
    assert {path: path.read_bytes() for path in (case, table)} == first
    page = (out / "kappa-gap.md").read_text()
    # the page is a pure function of the data file: regenerate it elsewhere, byte for byte
    pub = tmp_path / "pub"
    kappa_gap.publish(wd / "results" / "kg", pub)
    assert (pub / "kappa-gap.md").read_text() == page
    assert (pub / "data" / "kappa-gap.nc").read_bytes() == (out / "kappa-gap.nc").read_bytes()


@pytest.mark.skipif(not (PUBLISHED / "data" / "kappa-gap.nc").exists(), reason="no published kappa-gap data")
def test_published_page_follows_from_the_published_data(tmp_path):
    # The page was generated on another machine: numbers compare to their last printed digit
    # (tests/compare_outputs.py); byte identity of a rerun on one machine is the tiny scene's test.
    shutil.copytree(PUBLISHED / "data", tmp_path / "data")
    page = kappa_gap.regenerate(tmp_path)
    assert_text_close(page.read_text(), (PUBLISHED / "kappa-gap.md").read_text(),
                      where=str(PUBLISHED / "kappa-gap.md"))


def _numbers(cell: str) -> tuple[float, float]:
    """A printed shift "+1.23 ± 0.45" (percent) as fractions; "—" as NaN; no "±" as s.e. NaN."""
    if cell.strip() == "—":
        return math.nan, math.nan
    m, _, e = cell.partition("±")
    return float(m) / 100, (float(e) / 100 if e.strip() else math.nan)


@pytest.mark.skipif(not (PUBLISHED / "kappa-gap.md").exists(), reason="no published kappa-gap page")
def test_published_verdicts_follow_their_printed_rule():
    # Each "closes the gap?" verdict re-derived from the printed shifts and the printed gap alone.
    lines = (PUBLISHED / "kappa-gap.md").read_text().splitlines()
    gap_rows = [ln for ln in lines if re.match(r"^\| 0\.\d+ \| ", ln)]
    gap = np.array([_numbers(ln.split("|")[4]) for ln in gap_rows])
    needed = 1 / (1 + gap[:, 0]) - 1
    needed_se = gap[:, 1] / (1 + gap[:, 0]) ** 2
    rows = [ln for ln in lines if re.match(r"^\| \d\. (solver|contact|continuum|convention) \|", ln)]
    assert len(rows) >= 8 and len(gap_rows) == len(kappa_gap.TARGET_AREAS)
    for ln in rows:
        cells = ln.split("|")[1:-1]
        shifts = np.array([_numbers(c) for c in cells[2:2 + len(kappa_gap.TARGET_AREAS)]])
        printed = cells[-1].strip()
        # an area the row's loads never reach is "—": it can be no part of the gap's closing
        assert closes(shifts[:, 0], shifts[:, 1], needed, needed_se) == printed, ln
