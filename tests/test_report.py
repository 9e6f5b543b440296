"""The Snakemake report: its landing page (roughcontact.studies.report) and captions. Every shipped scene's report
in a browser: tests/test_reader.py."""
import base64
import datetime
import os
import re
import shutil
import subprocess
from pathlib import Path

import jinja2
import numpy as np
import pytest
import xarray as xr
from docutils.core import publish_parts

from conftest import REPO
from roughcontact.analysis import fit
from roughcontact.studies import report, run_record
from roughcontact.studies.rst import folded

REPORT_DIR = REPO / "workflow" / "report"
DOCUTILS_CONF = REPORT_DIR / "docutils.conf"
GIT = shutil.which("git")


@pytest.fixture
def mathml(monkeypatch):
    """docutils configured as the Snakefile configures it for the report (undone afterwards)."""
    monkeypatch.delenv("DOCUTILSCONFIG", raising=False)
    report.render_maths_as_mathml(DOCUTILS_CONF)
    assert os.environ["DOCUTILSCONFIG"].endswith(os.pathsep + str(DOCUTILS_CONF))


def _html(rst: str) -> str:
    """``rst`` rendered as Snakemake renders captions; fails on any docutils message."""
    html = publish_parts(rst, writer="html", settings_overrides={"report_level": 1, "halt_level": 2})["body"]
    assert "system-message" not in html, html
    return html


# --------------------------------------------------------------------------------- git commit
def _git(cwd, *args):
    subprocess.run([GIT, "-c", "user.name=t", "-c", "user.email=t@example.org", *args], cwd=cwd, check=True,
                   capture_output=True)


@pytest.mark.skipif(GIT is None, reason="git is not installed")
def test_git_commit_names_the_checkout_and_its_uncommitted_changes(tmp_path):
    assert report.git_commit(tmp_path) == "unknown"  # not a git checkout
    _git(tmp_path, "init", "-q")
    assert report.git_commit(tmp_path) == "unknown"  # no commit yet
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "code.py").write_text("x = 1\n")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "commit", "-q", "-m", "first")
    head = subprocess.run([GIT, "rev-parse", "HEAD"], cwd=tmp_path, capture_output=True, text=True).stdout.strip()
    assert len(head) == 40
    assert report.git_commit(tmp_path / "sub") == head  # any folder of the work tree
    (tmp_path / "untracked.txt").write_text("results, a user's scene file\n")
    assert report.git_commit(tmp_path) == head  # untracked files are not changes to the code
    (tmp_path / "sub" / "code.py").write_text("x = 2\n")
    assert report.git_commit(tmp_path) == f"{head} (uncommitted changes)"


def test_git_commit_is_unknown_without_git(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # no git on it
    assert report.git_commit(REPO) == "unknown"


# --------------------------------------------------------------------------------- maths
def test_docutils_config_adds_ours_last_and_keeps_the_users():
    ours = "/w/workflow/report/docutils.conf"
    standard = os.pathsep.join(report.DOCUTILS_STANDARD_CONFIGS)
    assert report.docutils_config_path(ours, {}) == standard + os.pathsep + ours
    assert report.docutils_config_path(ours, {"DOCUTILSCONFIG": "/mine.conf"}) == "/mine.conf" + os.pathsep + ours
    # a second parse of the Snakefile (e.g. in a cluster job) does not add it twice
    again = report.docutils_config_path(ours, {"DOCUTILSCONFIG": standard + os.pathsep + ours})
    assert again == standard + os.pathsep + ours


def test_maths_renders_as_mathml_with_the_shipped_docutils_config(mathml):
    html = _html(r"The law :math:`\kappa = \sqrt{2\pi}`." + "\n\n" + r".. math:: \frac{A}{A_0} = \beta^{\mu}" + "\n")
    assert html.count("<math") == 2 and "<msqrt>" in html and "<mfrac>" in html
    assert 'display="block"' in html


def test_without_it_docutils_maths_needs_a_stylesheet_the_report_lacks(monkeypatch, tmp_path):
    monkeypatch.setenv("DOCUTILSCONFIG", str(tmp_path / "none.conf"))
    html = _html(r":math:`\frac{a}{b}`")
    assert "<math" not in html and 'class="fraction"' in html  # laid out only by docutils' math.css


@pytest.mark.parametrize("caption", sorted(p.name for p in REPORT_DIR.glob("*.rst")))
def test_every_caption_renders_cleanly(caption, mathml):
    """Captions without Jinja render without docutils messages; their maths becomes MathML."""
    text = (REPORT_DIR / caption).read_text()
    if "{{" in text or "{%" in text:
        pytest.skip("a Jinja template: rendered by the report (test_landing_page_template_renders, test_reader)")
    html = _html(text)
    assert html.count("<math") == text.count(":math:") + text.count(".. math::")


# --------------------------------------------------------------------------------- tables
PARAMETERS = {"contact": {"grid": {"H": ["0.36", "0.84"], "k_l": ["4"]}, "outputs": {"fields": []},
                          "effects": {}, "seeds": 3, "solver": {"tol": 1e-8}},
              "fit": {"window": [0.01, 0.11], "include_unconverged": False}}


def test_parameters_table_lists_every_dotted_key_sorted(mathml):
    rst = report.parameters_table(PARAMETERS)
    html = _html(rst)
    keys = ["contact.effects", "contact.grid.H", "contact.grid.k_l", "contact.outputs.fields", "contact.seeds",
            "contact.solver.tol", "fit.include_unconverged", "fit.window"]
    assert [line.split("``")[1] for line in rst.splitlines() if line.startswith("   * - ``")] == keys
    for shown in ("0.36, 0.84", "1e-08", "[0.01, 0.11]", "false", "(empty)", "{}"):
        assert shown in html, shown
    with pytest.raises(ValueError, match="no parameters"):
        report.parameters_table({})
    odd = _html(report.parameters_table({"x": "a`b\\c *d*_ "}))  # not a literal: escaped text, shown as written
    assert "<td>a`b\\c *d*_</td>" in odd.replace("\n", "")


def _fit_result(n_seeds=3, ci=True, hs=("0.36",)):
    """A small dataset shaped like roughcontact.analysis.fit.fit_cel's result, for fit.to_csv_table: ``n_seeds``
    seeds at each H of ``hs``, pooled over them."""
    coords = {"k_l": [4.0, 16.0], "k_s": [32.0], "H_group": [*hs, "pooled"], "estimator": ["paper", "joint"],
              "constant": list(fit.CONSTANTS)}
    dims = tuple(coords)
    shape = tuple(len(v) for v in coords.values())
    value = np.arange(np.prod(shape), dtype=float).reshape(shape) / 10 + 1
    value[1, 0, 0, 1, 2] = np.nan  # a group/estimator/constant without a fit
    constrained = np.ones(shape, dtype=int)
    constrained[0, 0, 1, 0, 1] = 0
    lo, hi = (value - 0.5, value + 0.5) if ci else (np.full(shape, np.nan),) * 2
    return xr.Dataset(
        {"value": (dims, value), "stderr": (dims, value / 100), "bootstrap_stderr": (dims, value / 10),
         "ci_low": (dims, lo), "ci_high": (dims, hi), "constrained": (dims, constrained),
         "n_points": (dims, np.full(shape, 25)),
         "n_seeds": (dims[:3], np.where(np.array(coords["H_group"]) == "pooled", n_seeds * len(hs), n_seeds)
                     * np.ones(shape[:3], dtype=int)),
         "n_boot_ok": (dims[:4], np.full(shape[:4], 200)),
         "paper_value": (("constant",), [2.87009, 0.55, 0.21]), "paper_stderr": (("constant",), [0.005, 0.02, 0.005])},
        coords=coords)


def test_fit_table_shows_every_constant_rounded_to_its_interval(mathml):
    csv_text = fit.to_csv_table(_fit_result())
    rows = report.read_fit_csv(csv_text)
    html = _html(report.fit_table(csv_text))
    assert html.count("<table") == 1
    # one table row per group and estimator, a header row and the published values
    assert html.count("<tr") == 1 + len(rows) // 3 + 1
    # kappa 1 [0.5, 1.5] is shown as kappa/sqrt(2 pi) = 0.399 [0.199, 0.598]: to the interval's one figure
    assert "<td>0.4 [0.2, 0.6]</td>" in html and "<td>1.1 [0.6, 1.6]</td>" in html
    assert "0.39894" not in html and "1.1 [0.6, 1.6]" in html
    assert "—" in html  # the constant without a fit
    assert html.count(" *</td>") == 1 and "not constrained by the data" in html
    # the paper's kappa = (2.87009 +- 0.00501326) as it states it: 1.145 +- 0.002
    assert "1.145 ± 0.002" in html and "0.55 ± 0.02" in html and "0.210 ± 0.005" in html and "published" in html
    assert html.count("<math") == 6  # k_l, k_s, H, kappa/sqrt(2 pi), mu, beta in the header
    assert "<msqrt>" in html.split("</thead>")[0]


def test_fit_table_names_a_constant_or_an_interval_on_a_bound_of_the_fit(mathml):
    result = _fit_result()
    # the joint fit's mu interval down to its lower bound (1e-6); its beta value on the lower bound
    where = {"k_l": 4.0, "k_s": 32.0, "H_group": "0.36", "estimator": "joint"}
    result["ci_low"].loc[{**where, "constant": "mu"}] = fit.JOINT_LOWER[1]
    result["value"].loc[{**where, "constant": "beta"}] = fit.JOINT_LOWER[2]
    html = _html(report.fit_table(fit.to_csv_table(result)))
    assert "<td>1.4 [bound, 1.9] ‡</td>" in html and "<td>1e-12 (on a bound) [1.0, 2.0] ‡</td>" in html
    assert "1e-06" not in html.split("</table>")[0]
    assert "‡ on a bound of the joint least-squares fit" in html and "μ ≤ 1 − 1e-06" in html
    # the paper's route has no bounds: the same number there is just a number
    paper = {**where, "estimator": "paper"}
    result = _fit_result()
    result["ci_low"].loc[{**paper, "constant": "mu"}] = fit.JOINT_LOWER[1]
    assert "‡" not in _html(report.fit_table(fit.to_csv_table(result)))


def test_fit_table_without_bootstrap_shows_the_values_alone(mathml):
    csv_text = fit.to_csv_table(_fit_result(ci=False))
    html = _html(report.fit_table(csv_text))
    assert "[" not in html.split("</thead>")[1].split("published")[0]
    assert "<td>1.1</td>" in html and "<td>0.399</td>" in html  # three figures without an interval


def test_fit_table_refuses_what_is_not_a_cel_table():
    with pytest.raises(ValueError, match="no rows"):
        report.fit_table("k_l,k_s\n")
    with pytest.raises(ValueError, match="lacks the column"):
        report.fit_table("k_l,k_s\n4,32\n")
    good = fit.to_csv_table(_fit_result())
    with pytest.raises(ValueError, match="unknown constant 'gamma'"):
        report.fit_table(good.replace(",kappa,", ",gamma,"))


def test_result_line_gives_the_representative_group_against_the_paper(mathml):
    csv_text = fit.to_csv_table(_fit_result())
    html = _html(report.result_rst(csv_text))
    # k_l = 16, k_s = 32, H pooled, the paper's route: kappa 2.8 [2.3, 3.3] / sqrt(2 pi), mu 2.9, beta 3.0
    assert "<strong>Result</strong>" in html and "</math> pooled, 3 seeds" in html
    assert "<mi>λ</mi>" in html and "<mn>16</mn>" in html and "<mn>32</mn>" in html
    assert "κ/√(2π) = 1.1 [0.9, 1.3], μ = 2.9 [2.4, 3.4], β = 3.0 [2.5, 3.5]" in html
    assert "the paper: κ/√(2π) = 1.145 ± 0.002, μ = 0.55 ± 0.02, β = 0.210 ± 0.005" in html
    # without the representative point: the largest k_l and its largest k_s
    four = "\n".join(line for line in csv_text.splitlines() if not line.startswith("16,"))
    assert r"\lambda_l = L/4`, :math:`\lambda_s = L/32`, :math:`H` pooled" in report.result_rst(four)
    assert "no constant of the contact evolution law was fitted" in report.result_rst(csv_text.splitlines()[0])
    assert "no contact study" in report.result_rst(None)
    # an adhesive scene without unloading: no fit, no pull-off table, and a contact study all the same
    unloaded = report.result_rst(None, unfitted="adhesive contact")
    assert "no contact study" not in unloaded and "computes adhesive contact" in unloaded
    assert "aggregate/contact.nc" in unloaded
    assert report.result_rst(csv_text, pull_off="TABLE").endswith("TABLE")


def _lines_like():
    """cel.csv of a fit like the lines scene's at (k_l, k_s) = (16, 32), H pooled, the paper's route: kappa
    3.67558 [2.92474, 7819.49] (kappa/sqrt(2 pi) = 1.47 [1.17, 3120]), mu below its interval, beta on its upper
    end; 4 seeds at each of two H; flagged as the fit flags them."""
    result = _fit_result(n_seeds=4, hs=("0.36", "0.84"))
    where = {"k_l": 16.0, "k_s": 32.0, "H_group": "pooled", "estimator": "paper"}
    for c, (v, lo, hi) in {"kappa": (3.67558, 2.92474, 7819.49), "mu": (0.00763363, 0.00788074, 0.84936),
                           "beta": (1.87413, 0.181539, 1.87413)}.items():
        for var, x in (("value", v), ("ci_low", lo), ("ci_high", hi)):
            result[var].loc[{**where, "constant": c}] = x
    result["constrained"].values = fit.constrained_flags(result["value"].values, result["ci_low"].values,
                                                         result["ci_high"].values, result["estimator"].values)
    return fit.to_csv_table(result)


def test_result_line_prints_no_number_as_zero_and_marks_what_the_data_do_not_bound(mathml):
    rst = report.result_rst(_lines_like())
    # it read "κ/√(2π) = 0 [0, 3100]" and "β = 1.87 [0.18, 1.87]" without a mark
    assert "κ/√(2π) = 1 [1, 3100] \\*, μ = 0.008 [0.008, 0.8] \\*, β = 1.9 [0.2, 1.9] \\*;" in rst, rst
    assert "0 [0," not in rst
    footnote = "\\* not constrained by the data: " + fit.UNCONSTRAINED_RULE + "."
    assert footnote in rst
    # the pooled group's seeds as they are: 4 seeds at each of 2 values of H (it read "8 seeds")
    assert ":math:`H` pooled, 4 seeds × 2 values of :math:`H`," in rst
    html = _html(rst)
    assert "4 seeds × 2 values of" in html and "8 seeds" not in html


def test_fit_table_marks_an_interval_that_touches_its_estimate(mathml):
    text = report.fit_table(_lines_like())
    rows = [[c.strip() for c in row.split("\n     - ")] for row in text.split("</table>")[0].split("   * - ")[1:]]
    cells = next(r for r in rows if r[:4] == ["16", "32", "pooled", "paper"])
    assert cells[2:] == ["pooled", "paper", "1 [1, 3100] \\*", "0.008 [0.008, 0.8] \\*", "1.9 [0.2, 1.9] \\*",
                         "4 seeds × 2 values of :math:`H`"], cells
    assert "\\* not constrained by the data: " + fit.UNCONSTRAINED_RULE + "." in text
    assert "4 seeds\n" in text  # a group of one H: its seeds
    _html(text)


def test_a_seed_count_says_how_many_values_of_h_were_pooled():
    rows = report.read_fit_csv(fit.to_csv_table(_fit_result(n_seeds=3, hs=("0.36", "0.84"))))
    pooled = next(r for r in rows if r["H_group"] == "pooled")
    assert report.seed_count(rows, pooled) == "3 seeds × 2 values of :math:`H`"
    assert report.seed_count(rows, rows[0]) == "3 seeds"
    uneven = [dict(r, n_seeds="2") if r["H_group"] == "0.84" else dict(r, n_seeds="5") if r is pooled
              or r["H_group"] == "pooled" else r for r in rows]
    assert report.seed_count(uneven, next(r for r in uneven if r["H_group"] == "pooled")) == (
        "5 seeds: 3 at :math:`H` = 0.36, 2 at :math:`H` = 0.84")
    one = report.read_fit_csv(fit.to_csv_table(_fit_result(n_seeds=1)))
    assert report.seed_count(one, one[0]) == "1 seed"


#: Symbols typed as plain text: A/A0, p0, E*, h', k_l, rho^2 (a report writes them as :math:).
PLAIN_MATHS = re.compile(r"A/A0|\bp0\b|\bE\*|\bh'|\bk_[ls]\b|\w\^\d|\brho\b")


def _prose(rst: str) -> str:
    """``rst`` without its maths, literals and directives' options."""
    return re.sub(r":math:`[^`]*`|``[^`]*``|^\s*:\w+:.*$", "", rst, flags=re.M)


def test_the_reports_prose_writes_its_symbols_as_maths(mathml):
    from roughcontact.studies import report_tables

    csv_text = fit.to_csv_table(_fit_result())
    texts = {"profiles": report.PROFILES_TEXT, "topographies": report_tables.topographies_table(
        [["``a``", "``a.x3p``", "64", "1 um", "0.1", "0.0 %", "", "", ""]]),
             "summary": report.summary_rst("demo", PARAMETERS, fit_csv=csv_text, profiles=True),
             "result": report.result_rst(_lines_like(), profiles=True)}
    for name, text in texts.items():
        assert not PLAIN_MATHS.search(_prose(text)), (name, PLAIN_MATHS.search(_prose(text)))
        _html(text)
    assert PLAIN_MATHS.search("the last step's p0/(E* h')")  # the check finds what it looks for


def test_summary_has_the_fit_then_the_parameters_folded(mathml):
    csv_text = fit.to_csv_table(_fit_result())
    rst = report.summary_rst("demo", PARAMETERS, fit_csv=csv_text)
    assert rst == report.summary_rst("demo", PARAMETERS, fit_csv=csv_text), "deterministic"
    html = _html(rst)
    for text in ("Contact evolution law fit", "published", "Parameters of scene demo", "contact.solver.tol",
                 "β ≥ 1e-12", "8 parameters (click to show)"):
        assert text in html, text
    assert html.index("published") < html.index("<details>") < html.index("contact.solver.tol") < html.index(
        "</details>")
    assert html.count("<details>") == 1  # only the parameters are folded
    without_fit = _html(report.summary_rst("rep", PARAMETERS))
    assert "Contact evolution law" not in without_fit and "Each study of the scene" in without_fit
    with pytest.raises(ValueError, match="one line of plain text"):
        folded("a <b>", "x")


def test_summary_of_a_fit_with_no_row_says_so(mathml):
    # every case excluded (unconverged steps): cel.csv holds its header only; the report still builds
    header = fit.to_csv_table(_fit_result()).splitlines()[0] + "\n"
    html = _html(report.summary_rst("tiny", PARAMETERS, fit_csv=header))
    assert "Contact evolution law fit" in html and "No constant was fitted" in html


def test_cel_csv_caption_shows_the_file_as_a_table(tmp_path, monkeypatch, mathml):
    monkeypatch.chdir(tmp_path)
    Path("cel.csv").write_text(fit.to_csv_table(_fit_result()))
    text = jinja2.Template((REPORT_DIR / "fit.rst").read_text()).render(
        snakemake=type("Snakemake", (), {"output": type("Output", (), {"csv": "cel.csv"})}))
    html = _html(text)
    assert html.count("<table") == 1 and "<th" in html and "bootstrap_stderr" in html
    assert html.count("<tr") == 1 + len(report.read_fit_csv(Path("cel.csv").read_text()))


def test_cel_csv_caption_states_the_rule_of_its_constrained_column():
    assert " ".join(fit.UNCONSTRAINED_RULE.split()) in " ".join((REPORT_DIR / "fit.rst").read_text().split())


def test_cel_csv_is_also_an_html_table_the_report_shows():
    csv_text = fit.to_csv_table(_fit_result()).replace("paper,kappa", "paper <&>,kappa", 1)
    page = report.csv_html(csv_text, "fit/cel.csv of scene demo")
    assert page == report.csv_html(csv_text, "fit/cel.csv of scene demo"), "deterministic"
    assert page.startswith("<!DOCTYPE html>") and page.count("<table>") == 1
    assert page.count("<tr>") == len(csv_text.splitlines()) and page.count("<th>") == 16
    assert "<td>paper &lt;&amp;&gt;</td>" in page and "<td>2.87009</td>" in page
    with pytest.raises(ValueError, match="empty"):
        report.csv_html("", "x")


def test_figures_are_embedded_with_their_captions(mathml):
    png = (REPO / "docs" / "figures" / "demo_kappa.png").read_bytes()
    rst = report.figures_rst([("kappa", png, r"The caption, :math:`\bar p`." + "\n")])
    html = _html(rst + "\n.. _kappa.png: #kappa\n")
    assert html.count("<img") == 1 and 'src="data:image/png;base64,' in html and 'href="#kappa"' in html
    assert base64.b64decode(html.split("base64,")[1].split('"')[0]) == png
    assert "The caption" in html and max(len(line) for line in rst.splitlines()) < 200
    with pytest.raises(ValueError, match="not a PNG"):
        report.figures_rst([("kappa", b"GIF89a", "")])
    # a scene that draws no figure (an adhesive scene without unloading) says so, promising none
    none = report.figures_rst([])
    assert "draws no figure" in none and "Each figure" not in none


def test_bar_is_a_macron_that_chromium_draws(mathml):
    html = _html(r":math:`\partial\bar p/\partial p_0`")
    assert report.MACRON in html and report.DOCUTILS_BAR not in html and "<mover" in html


def test_a_subscript_of_a_barred_symbol_sits_beside_the_bar(mathml):
    """LaTeX sets the subscript of \\bar p beside the bar; docutils set it under p (munderover)."""
    for tex in (r"\bar p_\mathrm{off}", r"\bar{p}_\mathrm{off}", r"{\bar p}_\mathrm{off}"):
        html = _html(f":math:`{tex}`").replace("\n", "").replace(" ", "")
        assert "<munderover>" not in html, tex
        assert re.search(r"<msub><mover[^>]*><mi>p</mi><mo[^>]*>\u00af</mo></mover><mi>off</mi></msub>", html), html
    # an accent's superscript, and a limit's subscript, stay as they were
    assert "<msup><mover" in _html(r":math:`\bar p^2`").replace("\n", "").replace(" ", "")
    assert "<munder>" in _html(r":math:`\sum_{i}`").replace("\n", "").replace(" ", "")


def test_every_template_gives_maths_a_font_that_stretches_brackets():
    for name in ("workflow.rst", "figure.rst", "fit.rst"):
        assert report.MATH_CSS.replace(" ", "") in (REPORT_DIR / name).read_text().replace(" ", "").replace(
            "\n", ""), name


# --------------------------------------------------------------------------------- run record
def test_run_record_gives_the_code_the_libraries_the_host_the_date_and_the_cpu(tmp_path, mathml):
    versions = run_record.library_versions()
    assert list(versions)[:4] == ["Python", "numpy", "scipy", "pyFFTW"] and re.fullmatch(r"3\.\d+\.\d+",
                                                                                         versions["FFTW"])
    when = datetime.datetime(2026, 11, 28, 3, 4, tzinfo=datetime.UTC)
    rst = run_record.run_record_rst(version="1.2", commit="abc (uncommitted changes)", versions=versions,
                                    host="box (Linux)", when=when, cpu=run_record.cpu_text(4000.0, 39, 0))
    html = _html(rst)
    assert rst.startswith("Provenance\n----------\n")
    for text in ("<tt class=\"docutils literal\">abc</tt>", "uncommitted changes", "numpy",
                 versions["numpy"], "FFTW", "box (Linux)", "2026-11-28 03:04 UTC", "66.7 min over 39 jobs"):
        assert text in html, text
    assert "clean" in run_record.run_record_rst(version="1", commit="abc", versions={}, host="h", when=when, cpu="")
    assert "not a git checkout" in run_record.run_record_rst(version="1", commit="unknown", versions={}, host="h",
                                                             when=when, cpu="")
    with pytest.raises(ValueError, match="timezone-aware"):
        run_record.run_record_rst(version="1", commit="a", versions={}, host="h", when=when.replace(tzinfo=None),
                                  cpu="")
    assert run_record.cpu_text(30.0, 1, 1) == "at least 30 s over 1 job; 1 of them sampled by Snakemake, a lower bound"
    # the run's CPU from its benchmark files and job logs (roughcontact.pipeline.runcost)
    bench = tmp_path / "benchmarks"
    bench.mkdir()
    (bench / "fit_cel.tsv").write_text("s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\t"
                                       "cpu_time\n2.0\t0:00:02\t100\t1\t1\t1\t0\t0\t50\t1.5\n")
    assert run_record.total_cpu(tmp_path) == (1.5, 1, 1)


# --------------------------------------------------------------------------------- landing page
class _Category:
    def __init__(self, name):
        self.name, self.is_other = name or "Other", name is None

    def __lt__(self, other):
        return self.name < other.name


class _Result:
    def __init__(self, path, caption):
        self.path, self.target, self.caption = Path(path), Path(path).name, caption


def _landing_page(config, results):
    """workflow.rst rendered as Snakemake 9 renders the global description (jinja2 then docutils)."""
    categories = {}
    for category, res in results:
        categories.setdefault(_Category(category), {}).setdefault(_Category(None), []).append(res)
    files = [res for _, res in results]
    links = "\n\n" + "\n".join(f".. _{res.target}: javascript:app.showResultInfo('{res.path}')" for res in files)
    env = jinja2.Environment(trim_blocks=True, lstrip_blocks=True)
    text = env.from_string((REPORT_DIR / "workflow.rst").read_text() + links).render(
        snakemake=type("Snakemake", (), {"config": config}), categories=categories, files=files)
    html = publish_parts(text, writer="html")["html_body"]  # warnings and errors shown, as in Snakemake
    assert "system-message" not in html, html
    return html


def test_landing_page_leads_with_the_result_then_the_figures(tmp_path, monkeypatch, mathml):
    monkeypatch.chdir(tmp_path)  # Snakemake renders the report from the working directory
    root = Path("results/demo/report")
    root.mkdir(parents=True)
    csv_text = fit.to_csv_table(_fit_result())
    png = (REPO / "docs" / "figures" / "demo_kappa.png").read_bytes()
    (root / "result.rst").write_text(report.result_rst(csv_text))
    (root / "figures.rst").write_text(report.figures_rst([("kappa", png, "The kappa caption :math:`\\kappa`.")]))
    (root / "summary.rst").write_text(report.summary_rst("demo", PARAMETERS, fit_csv=csv_text))
    when = datetime.datetime(2026, 11, 28, tzinfo=datetime.UTC)
    (root / "run.rst").write_text(run_record.run_record_rst(version="9.9", commit="unknown", versions={"numpy": "2"},
                                                            host="h", when=when, cpu="1 s over 1 job"))
    config = {"scene": "demo", "scenes": {"demo": {"description": "A *star*, k_l and `ticks` stay text."}}}
    figure = _Result("results/demo/figures/kappa.png", "<p>The kappa caption <math><mi>κ</mi></math>.</p>")
    table = _Result("results/demo/fit/cel.csv", "<p>The fit, every row.</p>")
    pdf = _Result("results/demo/figures/kappa.pdf", "")  # no caption: listed without an "about"
    html = _landing_page(config, [("Contact", figure), ("Contact", pdf), ("Fit", table)])
    assert "kappa.pdf</a> (Contact)" in html and "about kappa.pdf" not in html
    assert "A *star*, k_l and `ticks` stay text." in html
    order = ["<strong>Result</strong>", "Figures</h", "<img", "The kappa caption", "Contact evolution law fit</h",
             "published", "Parameters of scene demo", "<details>", "contact.solver.tol", "Other results</h",
             "cel.csv</a> (Fit)", "The fit, every row.", "Provenance</h", "9.9"]
    at = [html.find(text) for text in order]
    assert -1 not in at and at == sorted(at), dict(zip(order, at, strict=True))
    assert "kappa.png</a> (Contact)" not in html  # a figure is shown, not listed again
    assert html.count("<math") >= 3  # the law, the figure's caption, the fit's header
    assert "safe center" in html  # the page keeps its top when taller than the window
    for name in ("result.rst", "run.rst"):
        (root / name).unlink()
    html = _landing_page({"scene": "demo", "scenes": {"demo": {}}}, [("Contact", figure)])
    assert "No result of this scene yet" in html and "No record of the run yet" in html
