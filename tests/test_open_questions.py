"""docs/open-questions/: the answers' numbers, their printed rules, and the page regenerated from its data."""

import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from compare_outputs import assert_images_close, assert_text_close
from roughcontact.studies.open_questions import RULES, analysis, kappa, page
from roughcontact.studies.verdicts import check_table, judge
from roughcontact.theory import cel_area

DOCS = Path(__file__).resolve().parents[1] / "docs"
PUBLISHED = DOCS / "open-questions"


@pytest.mark.parametrize("question, measured, verdict", [
    ("Q1a: the CEL holds toward full contact", "within 5 % up to A/A0 = 0.62; first step beyond", "yes"),
    ("Q1a: the CEL holds toward full contact", "within 5 % up to A/A0 = 0.2; first step beyond", "partly"),
    ("Q1a: the CEL holds toward full contact", "within 5 % up to A/A0 = 0; first step beyond", "no"),
    ("Q1b: Persson's erf curve holds toward full contact",
     "at A/A0 = 0.01: -30.0 %, at A/A0 = 0.1: -20.0 %, at A/A0 = 0.5: -4.0 %, at A/A0 = 0.9: +1.0 %", "partly"),
    ("Q1c: full contact begins at the exact full-contact load", "consistent in 59 of 60 cases", "no"),
    ("Q1d: the approach to full contact is H-independent", "z ≤ 3 at 3 of 4 steps; largest z = 5", "partly"),
    ("Q1e: Persson's erfc(√2 p̄) gives 1 − A/A0 near full contact", "ratio from 0.4 to 0.9 over 3 steps", "no"),
    ("Q2a: κ depends on α at fixed resolution (pixel-counted area)", "slope = -0.03 ± 0.011 (√2π", "no"),
    ("Q2c: BGT and Greenwood give κ at the surfaces' own α",
     "within 5 % of BGT at 3 of 20 points, within 5 % of Greenwood at 12 of 20 points", "partly"),
    ("Q2d: at equal α, λ_l = L/8 and L/4 cells (N = 2048) follow the N = 1024 trend",
     "z = +0.50 (λ_l = L/8, H = 0.36, α = 4.2, κ/√2π = 0.950), z = -2.50 (λ_l = L/4, H = 0.84, α = 12.7, "
     "κ/√2π = 0.880); scatter s = 0.0100", "partly"),
    ("Q3a: κ is the same on L and 2L cells", "abs(z) ≤ 2 at 6 of 6 points", "yes"),
    ("Q3b: κ's seed scatter halves on a 2L cell",
     "s.d. ratio 2L/L of κ(0.05): 0.55 [0.32, 0.95] at H = 0.36, 0.6 [0.35, 1.04] at H = 0.84", "partly"),
    ("Q4a: Persson's mean gap", "at A/A0 = 0.01: 0.95 (H=0.2), 1.2 (H=0.84); at A/A0 = 0.1: 0.97 (H=0.2), "
     "1.05 (H=0.84)", "partly"),
    ("Q4c: Persson's P(p)", "L1 distance at A/A0 = 0.01: 0.3, at A/A0 = 0.1: 0.2, at A/A0 = 0.5: 0.05, "
     "at A/A0 = 0.9: 0.04", "partly"),
    ("Q4d: the contact area percolates at A/A0 ≈ 0.42", "at A/A0 = 0.45 ± 0.01 (60 surfaces)", "yes"),
])
def test_each_verdict_follows_its_rule(question, measured, verdict):
    assert judge(question, "", measured, RULES) == verdict


def test_a_verdict_looser_than_its_rule_is_caught():
    table = page.markdown_table([{"claim": "Q1c: full contact begins at the exact full-contact load", "paper": "-",
                                  "ours": "consistent in 59 of 60 cases", "verdict": "yes",
                                  "test": RULES["Q1c: full contact begins at the exact full-contact load"].test}])
    assert check_table(table, RULES) == ["'Q1c: full contact begins at the exact full-contact load': printed "
                                         "verdict 'yes', its rule on its numbers gives 'no'"]


def test_an_exact_cel_holds_everywhere_and_reaches_full_contact_where_it_says():
    pbar = np.geomspace(1e-3, 2.0, 30)
    const = {"kappa": 2.6, "mu": 0.5, "beta": 0.3}
    area = cel_area(pbar, rms_slope=1.0, e_star=1.0, **const)
    v = analysis.cel_validity({"pbar": pbar, "area": area}, const)
    assert v["holds_up_to"] == area[-1] and np.isnan(v["fails_at"])
    assert v["cel_full"] == pbar[np.argmax(area >= 1)]


def test_log_slope_of_a_straight_line_and_its_error():
    alpha = np.geomspace(1.5, 50, 8)
    kap = 1.0 - 0.05 * np.log(alpha)
    assert kappa.log_slope(alpha, kap) == pytest.approx((-0.05, 0.0))
    m, e = kappa.log_slope(alpha, kap + 0.01 * (-1) ** np.arange(8), np.full(8, 0.001))
    assert m == pytest.approx(-0.05, abs=0.01) and e > 0.001 / 3  # scatter beyond the errors widens them


def test_a_point_on_the_trend_line_has_no_z():
    alpha = np.geomspace(1.5, 50, 10)
    base = {"alpha": alpha, "kappa": 1.0 - 0.04 * np.log(alpha) + 0.005 * (-1) ** np.arange(10),
            "sem": np.full(10, 0.005)}
    new = {"alpha": np.array([5.0, 5.0]), "kappa": 1.0 - 0.04 * np.log([5.0, 5.0]) + np.array([0.0, 0.05]),
           "sem": np.full(2, 0.005)}
    test = kappa.trend_test(base, new)
    assert test["scatter"] == pytest.approx(0.005 * np.sqrt(10 / 8), rel=0.05)  # the line absorbs a little
    assert abs(test["z"][0]) < 0.1 and test["z"][1] > 5


def _cells(seed_scale):
    rng = np.random.default_rng(1)
    area = np.geomspace(0.005, 0.15, 12)
    kap = 2.5 - 2.0 * area + seed_scale * rng.standard_normal((1, 12, 1))
    data = {"area_fraction": (("H", "seed", "step"), np.broadcast_to(area, (1, 12, 12)).copy()),
            "kappa": (("H", "seed", "step"), np.broadcast_to(kap, (1, 12, 12)).copy())}
    return xr.Dataset(data, coords={"H": [0.5], "seed": np.arange(12), "step": np.arange(1, 13)})


def test_cell_size_comparison_reads_halved_scatter():
    rows = kappa.cell_size_comparison(_cells(0.02), _cells(0.01))
    ratio, lo, hi = rows[1]["sd_ratio"]
    assert ratio == pytest.approx(0.5) and lo < 0.5 < hi < 1.0
    assert all(abs(r["z"]) < 2 for r in rows)


@pytest.mark.skipif(not (PUBLISHED / "data").is_dir(), reason="docs/open-questions not published")
def test_the_readme_quotes_the_generated_table_and_every_verdict_follows_its_rule():
    table = (PUBLISHED / "claims.md").read_text()
    readme = (PUBLISHED / "README.md").read_text()
    for line in table.splitlines():
        assert line in readme, f"README lacks the generated row {line[:60]!r}"
    assert check_table(table, RULES) == []


@pytest.mark.slow  # ~15 s: four aggregates read, seven figures drawn
@pytest.mark.skipif(not (PUBLISHED / "data").is_dir(), reason="docs/open-questions not published")
def test_the_published_page_follows_from_the_published_data(tmp_path):
    out = tmp_path / "open-questions"
    shutil.copytree(PUBLISHED / "data", out / "data")
    page.main(["regenerate", str(out), "--docs", str(DOCS)])
    assert_text_close((out / "claims.md").read_text(), (PUBLISHED / "claims.md").read_text(),
                      where=str(PUBLISHED / "claims.md"))
    pngs = sorted((PUBLISHED / "figures").glob("*.png"))
    assert {p.name for p in (out / "figures").glob("*.png")} == {p.name for p in pngs}
    for png in pngs:
        assert_images_close(out / "figures" / png.name, png)
