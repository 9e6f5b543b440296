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
    ("Q1a: the CEL holds toward full contact", "5 % crossing at A/A0 = 0.62 (interpolated); 4 % crossing at "
     "A/A0 = 0.55 (interpolated)", "yes"),
    ("Q1a: the CEL holds toward full contact", "5 % crossing at A/A0 = 0.526 (interpolated between the steps at "
     "0.500 and 0.591); 4 % crossing at A/A0 = 0.481 (interpolated)", "partly"),
    ("Q1a: the CEL holds toward full contact", "5 % crossing at A/A0 = 0.2; 4 % crossing at A/A0 = 0.1", "partly"),
    ("Q1a: the CEL holds toward full contact", "5 % crossing at A/A0 = 0 (the first step, 0.001, is beyond); "
     "4 % crossing at A/A0 = 0 (the first step)", "no"),
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
    ("Q4a: Persson's mean gap", "at A/A0 = 0.01: 0.95 [0.92, 0.99] (H=0.2), 1.2 [1.1, 1.3] (H=0.84); at A/A0 = "
     "0.1: 0.97 [0.95, 0.99] (H=0.2), 1.05 [1.0, 1.08] (H=0.84); mode count: none pending", "partly"),
    ("Q4a: Persson's mean gap", "at A/A0 = 0.01: 0.95 [0.92, 0.99] (H=0.2); at A/A0 = 0.1: 1.05 [1.0, 1.08] "
     "(H=0.84); mode count: k_l = 4: 1.02 [0.95, 1.09] (H=0.36)", "yes"),
    ("Q4a: Persson's mean gap", "at A/A0 = 0.01: 0.95 [0.92, 0.99] (H=0.2); mode count: pending: k_l = 4", "partly"),
    ("Q4b: Persson's contact stiffness", "at A/A0 = 0.01: 1.02 [0.89, 1.13] (H=0.2), 0.99 [0.88, 1.10] (H=0.36); "
     "mode count: k_l = 8: 1.0 [0.95, 1.05] (H=0.36)", "partly"),
    ("Q4b: Persson's contact stiffness", "at A/A0 = 0.01: 1.2 [1.1, 1.3] (H=0.2), 0.85 [0.8, 0.9] (H=0.36)", "no"),
    ("Q4c: Persson's P(p)", "L1 distance at A/A0 = 0.01: 0.3, at A/A0 = 0.1: 0.2, at A/A0 = 0.5: 0.05, "
     "at A/A0 = 0.9: 0.04", "partly"),
    ("Q4d: the contact area percolates at A/A0 ≈ 0.42", "threshold A/A0 = 0.41 ± 0.006 (60 surfaces)", "yes"),
    ("Q4d: the contact area percolates at A/A0 ≈ 0.42", "threshold A/A0 = 0.381 ± 0.037 (60 surfaces)", "partly"),
    ("Q4d: the contact area percolates at A/A0 ≈ 0.42", "threshold A/A0 = 0.38 ± 0.005 (60 surfaces)", "partly"),
    ("Q4d: the contact area percolates at A/A0 ≈ 0.42", "threshold A/A0 = 0.30 ± 0.005 (60 surfaces)", "no"),
    ("Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s",
     "slope = -0.045 ± 0.003, curvature = 0.002 ± 0.002 (√2π", "yes"),
    ("Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s",
     "slope = -0.045 ± 0.003, curvature = 0.012 ± 0.002 (√2π", "partly"),
    ("Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s",
     "slope = -0.005 ± 0.003, curvature = 0.0 ± 0.002 (√2π", "no"),
    ("Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s",
     "pixel-counted: slope = -0.044 ± 0.002, curvature = 0.003 ± 0.0015; perimeter-corrected: slope = -0.039 ± "
     "0.0015, curvature = 0.0006 ± 0.0012 (√2π", "yes"),
    ("Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s",
     "pixel-counted: slope = -0.044 ± 0.002, curvature = 0.0031 ± 0.0015; perimeter-corrected: slope = -0.039 ± "
     "0.0015, curvature = 0.0006 ± 0.0012 (√2π", "partly"),
    ("Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s",
     "pixel-counted: slope = -0.044 ± 0.002, curvature = 0.01 ± 0.001; perimeter-corrected: slope = -0.039 ± "
     "0.0015, curvature = 0.01 ± 0.001 (√2π", "partly"),
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
    assert v["holds_up_to"] == area[-1] and np.isnan(v["fails_at"]) and np.isnan(v["crossing"][0])
    assert cel_area(v["cel_full"], rms_slope=1.0, e_star=1.0, **const) == pytest.approx(1.0, rel=1e-12)
    assert pbar[np.argmax(area >= 1) - 1] < v["cel_full"] <= pbar[np.argmax(area >= 1)]


def test_the_law_reaches_full_contact_at_its_printed_constants():
    # issue 51: (1 - beta)^(1/(mu - 1)) / kappa with the page's printed constants
    assert analysis.cel_full_load({"kappa": 2.684, "mu": 0.389, "beta": 0.271}) == pytest.approx(0.625, abs=5e-4)
    assert np.isnan(analysis.cel_full_load({"kappa": 2.684, "mu": 0.389, "beta": 1.2}))


def test_a_tolerance_crossing_is_interpolated_between_the_steps_that_bound_it():
    area = np.array([0.1, 0.3, 0.5, 0.6, 0.7])
    dev = np.array([0.01, -0.02, 0.04, 0.06, 0.1])
    assert analysis.tolerance_crossing(area, dev, 0.05) == pytest.approx((0.55, 0.5, 0.6))
    assert analysis.tolerance_crossing(area, dev, 0.03) == pytest.approx((0.4, 0.3, 0.5))
    at, lo, hi = analysis.tolerance_crossing(area, dev, 0.2)
    assert np.isnan(at) and lo == 0.7 and np.isnan(hi)
    assert analysis.tolerance_crossing(area, dev, 0.001)[:1] == (0.0,)


def _wrapping_cases(first: dict[int, int], area_step=0.01):
    """An aggregate of one H whose seed ``s`` first wraps (in x, 4-connected) at step ``first[s]``."""
    steps = np.arange(1, 21)
    area = np.broadcast_to(0.3 + area_step * (steps - 1), (1, len(first), steps.size)).copy()
    codes = np.zeros((1, len(first), steps.size, 2), dtype=np.int8)
    for i, k in enumerate(first.values()):
        codes[0, i, k:, 0] = 1  # wraps in x from step index k on (4-connected)
        codes[0, i, k + 2:, 1] = 7  # and 8-connected, both directions, later
    return xr.Dataset({"area_fraction": (("H", "seed", "step"), area),
                       "cluster_wrapping": (("H", "seed", "step", "connectivity"), codes)},
                      coords={"H": [0.5], "seed": list(first), "step": steps, "connectivity": [4, 8]})


def test_percolation_reads_the_first_wrapping_step_and_its_bracket():
    ds = _wrapping_cases({0: 10, 1: 11, 2: 12})
    brackets = analysis.percolation_brackets(ds)
    assert brackets["method"] == "wrapping"
    assert brackets["below"] == pytest.approx([0.39, 0.40, 0.41])
    assert brackets["at"] == pytest.approx([0.40, 0.41, 0.42])
    th = analysis.percolation_threshold(brackets)
    assert th["threshold"] == pytest.approx(0.405) and th["half_step"] == pytest.approx(0.005)
    assert th["sem"] == pytest.approx(0.01 / np.sqrt(3)) and th["u"] == th["sem"] and th["n"] == 3
    assert analysis.percolation_brackets(ds, connectivity=8)["at"] == pytest.approx([0.42, 0.43, 0.44])


def test_percolation_falls_back_on_the_largest_cluster_share_without_wrapping_data():
    ds = _wrapping_cases({0: 10, 1: 10}).drop_vars("cluster_wrapping")
    share = np.where(np.arange(20) >= 10, 0.8, 0.2)
    ds["cluster_max_area"] = ds["area_fraction"] * share
    brackets = analysis.percolation_brackets(ds)
    assert brackets["method"] == "share" and brackets["at"] == pytest.approx([0.40, 0.40])
    assert analysis.percolation_threshold(brackets)["u"] == pytest.approx(0.005)  # no seed spread: the step


def test_log_curvature_finds_a_saturating_fall():
    alpha = np.geomspace(1.5, 200, 12)
    x = np.log(alpha)
    c, e = kappa.log_curvature(alpha, 1.0 - 0.06 * x + 0.008 * x**2, np.full(12, 0.002))
    assert c == pytest.approx(0.008) and e < 0.002
    assert abs(kappa.log_curvature(alpha, 1.0 - 0.05 * x, np.full(12, 0.002))[0]) < 1e-12


def test_the_measured_spectrum_is_the_surface_s_own():
    ds = xr.Dataset({"rms_slope": (("H", "seed"), [[0.1]])}, coords={"H": [0.5], "seed": [3], "k_l": 4.0,
                                                                      "k_s": 8.0}, attrs={"n": 64, "length": 1.0})
    q, c = analysis.measured_spectrum(ds, 0.5, 3)
    q_exp, c_exp = analysis.spectrum_of(ds, 0.5)
    assert np.sum(q * q * c) == pytest.approx(0.01) and np.allclose(q, q_exp)
    assert not np.allclose(c, c_exp, rtol=0.1)  # one draw of the noise, not its expectation


def test_publish_refuses_an_unknown_further_run(tmp_path):
    with pytest.raises(ValueError, match="--run takes FILE=RUN"):
        page.publish(tmp_path, tmp_path, tmp_path, tmp_path, {"other.nc": tmp_path})


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


@pytest.mark.skipif(not (DOCS / page.REPRODUCTION["grid"]).is_file(), reason="the paper grid is not published")
def test_the_whole_range_row_fits_every_point_and_reads_pending_without_its_run():
    grid = page._reproduction(DOCS)["grid"]
    question = "Q2e: κ(α) over the whole range, N = 1024 to 4096 at 32 px per λ_s"
    assert page.range_row(grid, None, None)["verdict"] == "pending"
    r = page.range_row(grid, None, grid)  # the paper grid's k_s = 128 column stands in for the N = 4096 cells
    assert r["claim"] == question and r["verdict"] == judge(question, r["paper"], r["ours"], RULES)
    assert "over 40 points" in r["ours"] and r["ours"].count("slope = ") == 2  # pixel-counted and corrected


def test_the_alpha_figure_draws_the_models_over_every_point_and_shows_where_they_fall():
    from roughcontact.studies.open_questions import figures

    def points(alpha, k_l):
        alpha = np.asarray(alpha, float)
        return {"alpha": alpha, "kappa": np.full(alpha.size, 0.9), "sem": np.full(alpha.size, 0.01),
                "k_l": np.full(alpha.size, k_l), "H": np.full(alpha.size, 0.36),
                "bgt": 1.0 - 0.12 * np.log(alpha), "greenwood": 1.02 - 0.12 * np.log(alpha)}

    small, big = points([2.0, 10.0, 48.0], 4.0), points([5.0, 250.0], 16.0)
    fig = figures.alpha_figure(small, small, pixel_4096=big, corrected_4096=big)
    for ax in fig.axes:
        models = [line for line in ax.get_lines() if line.get_label() in ("BGT", "Greenwood")]
        assert len(models) == 2 and all(line.get_xdata().max() == 250.0 for line in models)
        assert ax.get_ylim()[0] <= 1.0 - 0.12 * np.log(250.0)  # the models' lowest value is in view
