"""The reproduction's claim table and its regeneration from published aggregates alone."""
import numpy as np
import pytest
import xarray as xr

from compare_outputs import assert_images_close, assert_text_close
from roughcontact.studies import reproduction


def _contact(kappa_of_area):
    """A contact aggregate whose kappa is a known function of A/A0 (two seeds, 10 steps)."""
    area = np.geomspace(0.01, 0.12, 10)
    shape = (1, 1, 1, 2, 10)
    a = np.broadcast_to(area, shape).copy()
    return xr.Dataset({"area_fraction": (("k_l", "k_s", "H", "seed", "step"), a),
                       "kappa": (("k_l", "k_s", "H", "seed", "step"), kappa_of_area(a))},
                      coords={"k_l": [16.0], "k_s": [32.0], "H": [0.8], "seed": [0, 1], "step": np.arange(1, 11)})


def _with_presence(con):
    con["case_present"] = xr.ones_like(con["kappa"].isel(step=0), dtype=bool)
    return con


@pytest.mark.parametrize("kappa, verdict", [(lambda a: 3.0 - 0.2 * np.log(a), "reproduced"),
                                            (lambda a: 2.0 + 0.2 * np.log(a), "not")])
def test_kappa_decreasing_row(kappa, verdict):
    assert reproduction._kappa_decreasing_row(_contact(kappa))["verdict"] == verdict


@pytest.mark.parametrize("level, verdict", [(1.7, "reproduced"), (1.5, "not")])
def test_persson_row_needs_every_kappa_above_its_asymptote(level, verdict):
    con = _with_presence(_contact(lambda a: level + 0 * a))
    row = reproduction._persson_row(con)
    assert row["verdict"] == verdict and f"{level:.3f}" in row["ours"]


def test_h_direction_row_over_non_representative_families():
    # kappa(0.05) per (k_l, k_s, H): falls with H everywhere but at the representative (16, 32)
    h = [0.2, 0.5, 0.8]
    vals = np.array([[[3.0, 2.8, 2.6], [3.2, 3.0, 2.9]], [[2.7, 2.7, 2.7], [2.9, 2.8, 2.7]]])
    mean = xr.DataArray(vals, dims=("k_l", "k_s", "H"), coords={"k_l": [1.0, 16.0], "k_s": [32.0, 128.0], "H": h})
    row = reproduction._h_direction_row(mean, 16.0, 32.0)
    assert row["verdict"] == "reproduced" and "falls in 3 of 3 families, monotonically in 3" in row["ours"]
    mean.loc[{"k_l": 1.0, "k_s": 128.0}] = [2.9, 3.0, 3.1]
    assert reproduction._h_direction_row(mean, 16.0, 32.0)["verdict"] == "partly"


def _grid(kappa, seeds=3):
    """A full contact grid k_l {1, 16} x k_s {32} x H {0.2, 0.8}: kappa(k_l, H, seed), constant in A/A0."""
    kl, ks, hs, steps = [1.0, 16.0], [32.0], [0.2, 0.8], 10
    shape = (len(kl), len(ks), len(hs), seeds, steps)
    area = np.broadcast_to(np.geomspace(0.01, 0.12, steps), shape).copy()
    k = np.array([[[[kappa(a, h, s)] * steps for s in range(seeds)] for h in hs] for a in kl])[:, None]
    dims = ("k_l", "k_s", "H", "seed", "step")
    con = xr.Dataset({"area_fraction": (dims, area), "kappa": (dims, k)},
                     coords={"k_l": kl, "k_s": ks, "H": hs, "seed": np.arange(seeds), "step": np.arange(1, steps + 1)})
    return _with_presence(con)


def _drop_cases(con, **where):
    """``con`` with the cases at ``where`` (coordinate values) missing, as a partial run leaves them."""
    out = con.copy(deep=True)
    out["case_present"].loc[where] = False
    for name in ("kappa", "area_fraction"):
        out[name] = out[name].where(out["case_present"])
    return out


def _rows(con):
    return {r["claim"]: r for r in reproduction.kappa_claims(con)}


def test_kappa_claims_on_a_grid_hole_compare_only_complete_cells():
    # kappa falls with H at k_l = 1 (2.4 -> 2.0) and rises at k_l = 16 (2.3 -> 2.4): on the full grid
    # kappa rises with k_l (2.2 -> 2.35)
    def kappa(kl, h, seed):
        slope = 0.1 if kl == 16 else -0.4
        return (2.3 if kl == 16 else 2.4) + (h - 0.2) / 0.6 * slope + 0.01 * seed

    full = _grid(kappa)
    assert _rows(full)["κ rises as λ_l falls (k_l rises)"]["verdict"] == "reproduced"
    # (k_l, H) = (1, 0.8) not run: the k_l comparison uses H = 0.2 alone (2.41 against 2.31, each
    # the mean of 3 seeds 0.01 apart: standard error 0.01 / sqrt(3)), not 2.41 against 2.36
    hole = _rows(_drop_cases(full, k_l=1.0, H=0.8))
    row = hole["κ rises as λ_l falls (k_l rises)"]
    assert row["ours"].startswith("κ(0.05): 2.410 ± 0.006 (k_l=1), 2.310 ± 0.006 (k_l=16)")
    assert row["verdict"] == "not"
    # the H spread at k_l = 1 needs every H there: pending, naming the family
    h_row = hole["κ(A/A0) independent of H for representative smooth surfaces, H-dependent otherwise"]
    assert h_row["verdict"] == "pending" and "(1, 32)" in h_row["ours"]


@pytest.mark.parametrize("sem, verdict", [(0.02, "partly"), (0.002, "not")])
def test_kappa_against_k_l_reads_a_plateau_inside_the_scatter_as_partly(sem, verdict):
    # 2.20 -> 2.50 -> 2.49: the last step falls by 0.01, inside two standard errors only when sem = 0.02
    coords = {"k_l": [1.0, 8.0, 16.0], "k_s": [32.0], "H": [0.2]}
    mean = xr.DataArray(np.array([2.20, 2.50, 2.49]).reshape(3, 1, 1), dims=("k_l", "k_s", "H"), coords=coords)
    row = reproduction._kl_row(mean, xr.full_like(mean, sem))
    assert row["verdict"] == verdict and f"2.490 ± {sem:.3f} (k_l=16)" in row["ours"]
    rising = mean.copy(data=np.array([2.20, 2.49, 2.50]).reshape(3, 1, 1))
    assert reproduction._kl_row(rising, xr.full_like(mean, sem))["verdict"] == "reproduced"


def test_kappa_against_k_l_averages_the_standard_error_over_cells():
    # two independent cells of sem 0.02 each: their mean has sem 0.02 / sqrt(2)
    coords = {"k_l": [1.0, 16.0], "k_s": [32.0, 64.0], "H": [0.2]}
    mean = xr.DataArray(np.array([[2.2, 2.2], [2.5, 2.5]]).reshape(2, 2, 1), dims=("k_l", "k_s", "H"), coords=coords)
    row = reproduction._kl_row(mean, xr.full_like(mean, 0.02))
    assert f"2.500 ± {0.02 / np.sqrt(2):.3f} (k_l=16)" in row["ours"]


def test_a_cell_missing_one_seed_is_left_out():
    # seed 2 alone at (16, 0.8) is far off: with it missing the cell drops out instead of averaging two seeds
    def kappa(kl, h, seed):
        return 2.0 + 0.1 * kl / 16 + (1.0 if (kl, h, seed) == (16, 0.8, 2) else 0.0)

    con = _drop_cases(_grid(kappa), k_l=16.0, H=0.8, seed=2)
    mean, _ = reproduction._seed_stats(reproduction.kappa_at(con), con)
    assert np.isnan(float(mean.sel(k_l=16.0, H=0.8, k_s=32.0)))
    assert np.isfinite(mean.sel(H=0.2)).all()
    # the asymptote row counts its fraction over the cells present, not over the grid
    row = reproduction._asymptote_claim(con)[0]
    assert "for 0 % of" in row["ours"]


def test_the_claim_table_says_when_the_grid_is_incomplete():
    con = _grid(lambda kl, h, seed: 2.5 + 0.01 * seed)
    con["pressure"] = con["area_fraction"] * 0.04
    con["rms_slope"] = xr.full_like(con["kappa"].isel(step=0), 0.1)
    fit = _fit(32.0, [reproduction.PAPER_KAPPA, 0.55, 0.21], 0.01)
    rep = xr.Dataset({"epsilon": (("k_l", "k_s", "H", "seed"), np.ones((2, 1, 1, 2)))},
                     coords={"k_l": [1.0, 16.0], "k_s": [32.0], "H": [0.8], "seed": [0, 1]})
    rep["case_present"] = rep["epsilon"] > 0
    rep.attrs.update(scene_parameters='{"surface": {"N": 32}}', n_bins=10)  # the noise floor's maps and bins
    complete = reproduction.claims(rep, con, fit)
    assert not any("incomplete grid" in r["ours"] for r in complete)
    partial = reproduction.claims(rep, _drop_cases(con, k_l=1.0, H=0.2, seed=0), fit)
    noted = [r for r in partial if "incomplete grid: 11 of 12 cases" in r["ours"]]
    assert noted and all(r["verdict"] != "pending" for r in noted)
    assert not any("incomplete" in r["ours"] for r in partial[:3])  # representativity rows: another aggregate


def _lambda_l_equal_l(area_of_p0, scatter):
    """Contact cases at k_l = 1, H = 0.68, 12 seeds: A/A0 = area_of_p0(p0) x (1 + scatter x seed offset)."""
    from roughcontact.theory.asperity import asperity_area  # noqa: F401  (the model the row compares with)

    p0 = np.linspace(0.005 / 30, 0.005, 30)
    offsets = np.linspace(-1, 1, 12)
    area = area_of_p0(p0)[None, :] * (1 + scatter * offsets[:, None])
    shape = (1, 1, 1, 12, 30)
    con = xr.Dataset({"area_fraction": (("k_l", "k_s", "H", "seed", "step"), area.reshape(shape)),
                      "pressure": (("k_l", "k_s", "H", "seed", "step"), np.broadcast_to(p0, shape).copy()),
                      "kappa": (("k_l", "k_s", "H", "seed", "step"), (area * 0.1 / p0).reshape(shape)),
                      "rms_slope": (("k_l", "k_s", "H", "seed"), np.full(shape[:4], 0.1))},
                     coords={"k_l": [1.0], "k_s": [32.0], "H": [0.68], "seed": np.arange(12), "step": np.arange(1, 31)},
                     attrs={"e_star": 1.0})
    return _with_presence(con)


def test_asperity_row_inside_and_outside_the_seed_scatter():
    from roughcontact.theory.asperity import asperity_area

    def bgt(p):
        return asperity_area(p, alpha=2.0, rms_slope=0.1, e_star=1.0, model="bgt")

    # BGT itself with a 10 % seed scatter: Greenwood lies within a few % of it at alpha = 2
    assert reproduction._asperity_row(_lambda_l_equal_l(bgt, 0.1))["verdict"] == "reproduced"
    # twice the area with a 1 % scatter: neither model inside
    row = reproduction._asperity_row(_lambda_l_equal_l(lambda p: 2 * bgt(p), 0.01))
    assert row["verdict"] == "not" and "BGT 0 %" in row["ours"]
    # no k_l = 1 in the aggregate: pending
    con = _lambda_l_equal_l(bgt, 0.1).assign_coords(k_l=[16.0])
    assert reproduction._asperity_row(con)["verdict"] == "pending"


def test_asperity_row_skips_a_family_without_cases():
    # a grid hole (k_s = 64, no case present) has no loads: it drops out, nothing raises
    from roughcontact.theory.asperity import asperity_area

    def bgt(p):
        return asperity_area(p, alpha=2.0, rms_slope=0.1, e_star=1.0, model="bgt")

    full = _lambda_l_equal_l(bgt, 0.1)
    hole = full.assign_coords(k_s=[64.0])
    for name in ("area_fraction", "pressure", "kappa", "rms_slope"):
        hole[name] = hole[name] * np.nan
    hole["case_present"] = ~hole["case_present"]
    both = xr.concat([full, hole], dim="k_s")
    assert reproduction._asperity_row(both) == reproduction._asperity_row(full)


def _fit(k_s, values, ci):
    consts = ["kappa", "mu", "beta"]
    shape = (1, 1, 1, 1, 3)
    dims = ("k_l", "k_s", "H_group", "estimator", "constant")
    v = np.array(values).reshape(shape)
    return xr.Dataset({"value": (dims, v), "ci_low": (dims, v - ci), "ci_high": (dims, v + ci),
                       "constrained": (dims, np.ones(shape, dtype="int8"))},
                      coords={"k_l": [16.0], "k_s": [k_s], "H_group": ["pooled"], "estimator": ["paper"],
                              "constant": consts})


def test_rough_cel_row_compares_all_three_constants():
    kappa = reproduction.PAPER_KAPPA
    assert reproduction._rough_cel_row(_fit(128.0, [kappa, 0.56, 1.15], 0.01))["verdict"] == "reproduced"
    assert reproduction._rough_cel_row(_fit(128.0, [kappa, 0.56, 0.3], 0.01))["verdict"] == "partly"
    assert reproduction._rough_cel_row(_fit(32.0, [kappa, 0.56, 1.15], 0.01))["verdict"] == "pending"


def test_cel_rows_at_the_representative_point():
    con = _with_presence(_contact(lambda a: 2.5 + 0 * a))
    con["pressure"] = con["area_fraction"] * 0.04
    rows = reproduction.cel_claims(_fit(32.0, [reproduction.PAPER_KAPPA, 0.55, 0.21], 0.01), con)
    assert [r["verdict"] for r in rows[:3]] == ["reproduced"] * 3
    rows = reproduction.cel_claims(_fit(32.0, [reproduction.PAPER_KAPPA * 0.8, 0.55, 0.4], 0.01), con)
    assert [r["verdict"] for r in rows[:3]] == ["not", "reproduced", "not"]


def test_kappa_at_interpolates_in_log_area():
    # kappa linear in log A is interpolated exactly
    con = _contact(lambda a: 3.0 - 0.2 * np.log(a))
    k = reproduction.kappa_at(con, 0.05)
    assert k.dims == ("k_l", "k_s", "H", "seed")
    np.testing.assert_allclose(k.values, 3.0 - 0.2 * np.log(0.05), rtol=1e-12)


def test_kappa_at_outside_the_loads_is_nan():
    con = _contact(lambda a: 2.5 + 0 * a)
    assert np.isnan(reproduction.kappa_at(con, 0.5).values).all()
    assert np.isnan(reproduction.kappa_at(con, 0.001).values).all()


def test_markdown_table_has_one_row_per_claim():
    rows = [reproduction._row("c1", "p", "o", "reproduced", "t"), reproduction._row("c2", "p", "o", "not", "t")]
    text = reproduction.markdown_table(rows)
    assert text.count("\n") == 4 and "**not**" in text and "**reproduced**" in text


@pytest.mark.slow
def test_publish_then_regenerate_from_the_published_files_alone(demo_run, tmp_path):
    out = tmp_path / "repro"
    reproduction.main(["publish", str(demo_run / "results" / "demo"), str(out)])
    table = (out / "claims.md").read_text()
    for claim in ("representativity grows with k_l", "independent of H", "higher H gives smaller κ", "seed scatter",
                  "κ rises", "not confined", "κ decreases with A/A0", "Persson's small-load asymptote",
                  "BGT and Greenwood (α = 2)", "kappa = paper value", "mu = paper value", "beta = paper value",
                  "λ_s = L/128", "≈ 10 %", "ε decreases with k_s"):
        assert claim in table
    assert table.count("\n| ") == 16  # sixteen claim rows after the header and the rule
    figures = {p.name for p in (out / "figures").glob("*.png")}
    assert figures == {f"{n}.png" for n in ("representativity", "surface_examples", "area_load", "kappa", "dpbar")}
    first = {p.name: p.read_bytes() for p in (out / "figures").glob("*.png")}
    # the documented command regenerates the same bytes from out/data only
    reproduction.main(["regenerate", str(out)])
    assert {p.name: p.read_bytes() for p in (out / "figures").glob("*.png")} == first
    assert (out / "claims.md").read_text() == table


PUBLISHED = __import__("pathlib").Path(__file__).resolve().parents[1] / "docs" / "reproduction"
#: Every published run: docs/reproduction itself and any sub-folder with its own data/ (e.g. paper-grid).
PUBLICATIONS = [p.parent for p in [PUBLISHED / "data", *sorted(PUBLISHED.glob("*/data"))] if p.is_dir()]


@pytest.mark.slow  # 15-20 s each on a quiet machine (figures and the noise floor): make test runs them
@pytest.mark.skipif(not PUBLICATIONS, reason="no published reproduction in docs/reproduction")
@pytest.mark.parametrize("published", PUBLICATIONS, ids=lambda p: p.name)
def test_published_claims_and_figures_follow_from_the_published_data(published, tmp_path):
    # The documented command, on a copy: the claim table and figures of a publication are
    # what its data give (nothing edited by hand, nothing stale). They were drawn on another
    # machine, so numbers compare to their last printed digit and figures within rendering
    # noise (tests/compare_outputs.py); byte identity of a rerun here is the test above.
    import shutil

    out = tmp_path / "repro"
    shutil.copytree(published / "data", out / "data")
    reproduction.main(["regenerate", str(out)])
    assert_text_close((out / "claims.md").read_text(), (published / "claims.md").read_text(),
                      where=str(published / "claims.md"))
    pngs = sorted((published / "figures").glob("*.png"))
    assert pngs, f"{published}: no figures"
    assert {p.name for p in (out / "figures").glob("*.png")} == {p.name for p in pngs}
    for png in pngs:
        assert_images_close(out / "figures" / png.name, png)


@pytest.mark.skipif(not PUBLICATIONS, reason="no published reproduction in docs/reproduction")
@pytest.mark.parametrize("published", PUBLICATIONS, ids=lambda p: p.name)
def test_the_readme_shows_the_generated_claim_table(published):
    # Each publication's README quotes its generated table verbatim: no row edited or stale.
    readme = (published / "README.md").read_text()
    for row in (published / "claims.md").read_text().splitlines():
        assert row in readme, f"{published / 'README.md'} lacks the generated row {row[:60]!r}"


@pytest.mark.skipif(not PUBLICATIONS, reason="no published reproduction in docs/reproduction")
@pytest.mark.parametrize("published", PUBLICATIONS, ids=lambda p: p.name)
def test_every_published_verdict_follows_its_printed_rule_and_numbers(published):
    # Read from the published text alone: each row's printed test is its claim's rule, and that
    # rule applied to the row's printed numbers gives the printed verdict.
    from roughcontact.studies.verdicts import check_table

    assert check_table((published / "claims.md").read_text()) == []


def test_a_verdict_looser_than_its_rule_is_caught():
    from roughcontact.studies.verdicts import RULES, check_table

    claim = "kappa = paper value (λ_l = L/16, λ_s = L/32, pooled H)"
    row = (f"| {claim} | (1.145 ± 0.002)·√(2π) | 1.066·√(2π), 95 % bootstrap interval [1.037, 1.089] | "
           f"**{{}}** | {RULES[claim].test} |")
    head = "| claim | paper | ours | verdict | test |\n|---|---|---|---|---|\n"
    assert check_table(head + row.format("not")) == []
    # the old 10 % rule's "partly", and a reproduced on an interval that misses the paper's range
    assert "gives 'not'" in check_table(head + row.format("partly"))[0]
    overlap = row.replace("[1.037, 1.089]", "[1.037, 1.144]")
    assert check_table(head + overlap.format("reproduced")) == []
    assert "printed test is not the rule's" in check_table(head + row.format("not").replace("not otherwise (",
                                                                                              "else ("))[0]
    assert "no rule" in check_table(head + row.format("not").replace(claim, "a new claim"))[0]
