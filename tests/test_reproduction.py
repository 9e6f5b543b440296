"""The reproduction's claim table and its regeneration from published aggregates alone."""
import numpy as np
import pytest
import xarray as xr

from roughcontact import reproduction


def _contact(kappa_of_area):
    """A contact aggregate whose kappa is a known function of A/A0 (two seeds, 10 steps)."""
    area = np.geomspace(0.01, 0.12, 10)
    shape = (1, 1, 1, 2, 10)
    a = np.broadcast_to(area, shape).copy()
    return xr.Dataset({"area_fraction": (("k_l", "k_s", "H", "seed", "step"), a),
                       "kappa": (("k_l", "k_s", "H", "seed", "step"), kappa_of_area(a))},
                      coords={"k_l": [16.0], "k_s": [32.0], "H": [0.8], "seed": [0, 1], "step": np.arange(1, 11)})


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
    for claim in ("representativity grows with k_l", "independent of H", "seed scatter", "κ rises",
                  "not confined", "kappa = paper value", "mu = paper value", "beta = paper value", "≈ 10 %"):
        assert claim in table
    assert table.count("\n| ") == 10  # ten claim rows after the header and the rule
    figures = {p.name for p in (out / "figures").glob("*.png")}
    assert figures == {f"{n}.png" for n in ("representativity", "surface_examples", "area_load", "kappa", "dpbar")}
    first = {p.name: p.read_bytes() for p in (out / "figures").glob("*.png")}
    # the documented command regenerates the same bytes from out/data only
    reproduction.main(["regenerate", str(out)])
    assert {p.name: p.read_bytes() for p in (out / "figures").glob("*.png")} == first
    assert (out / "claims.md").read_text() == table


PUBLISHED = __import__("pathlib").Path(__file__).resolve().parents[1] / "docs" / "reproduction"


@pytest.mark.skipif(not (PUBLISHED / "data").is_dir(), reason="no published reproduction in docs/reproduction")
def test_published_claims_and_figures_follow_from_the_published_data(tmp_path):
    # The documented command, on a copy: the claim table and figures in docs/reproduction are
    # exactly what its data give (nothing edited by hand, nothing stale).
    import shutil

    out = tmp_path / "repro"
    shutil.copytree(PUBLISHED / "data", out / "data")
    reproduction.main(["regenerate", str(out)])
    assert (out / "claims.md").read_text() == (PUBLISHED / "claims.md").read_text()
    for png in (PUBLISHED / "figures").glob("*.png"):
        assert (out / "figures" / png.name).read_bytes() == png.read_bytes(), png.name


@pytest.mark.skipif(not (PUBLISHED / "claims.md").is_file(), reason="no published reproduction in docs/reproduction")
def test_the_readme_shows_the_generated_claim_table():
    readme = (PUBLISHED / "README.md").read_text()
    for row in (PUBLISHED / "claims.md").read_text().splitlines():
        assert row in readme, f"docs/reproduction/README.md lacks the generated row {row[:60]!r}"
