"""The landing page of the Snakemake report (``snakemake --report``): pure text builders.

The report's global description (``workflow/report/workflow.rst``) only sees the config, so
the ``report_summary`` rule writes two reStructuredText fragments that the description includes:
``results/{scene}/report/result.rst``, the one line a reader looks for first (:func:`result_rst`: the
fitted CEL constants with their intervals beside the paper's, or an adhesive scene's pull-off), shown
above the figures, and ``summary.rst`` (:func:`summary_rst`: the fit table, the scene's tables and its
parameters, folded), shown below them; between them, ``figures.rst`` of the ``report_figures`` rule
(:func:`figures_rst`: every figure embedded with its caption). None carries a timestamp, so a rerun with the
same config, results and code writes the same bytes; the run's own record (versions, host, date, CPU time) is
:mod:`roughcontact.studies.run_record`'s. Numbers are rounded to their uncertainty
(:mod:`roughcontact.core.precision`).

Snakemake renders captions and the description with docutils. docutils' default HTML maths
needs a stylesheet the report does not carry, so the Snakefile calls
:func:`render_maths_as_mathml`, which points docutils at a config file that asks for MathML
(``workflow/report/docutils.conf``), writes ``\\bar`` as U+00AF (docutils' U+02C9 is dropped by
Chromium) and sets the subscript of an accented symbol beside the accent (``\\bar p_\\mathrm{off}``: docutils
set "off" under the bar); current browsers render MathML natively, and :data:`MATH_CSS`, which the landing page and
every caption carry, gives them a font with OpenType maths so that brackets stretch.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import os
import subprocess
from collections.abc import Mapping, Sequence

import numpy as np
from docutils.utils.math import latex2mathml

from ..analysis.fit import JOINT_LOWER, JOINT_UPPER, UNCONSTRAINED_RULE, at_bound
from ..core import precision
from ..pipeline.provenance import flatten
from ..theory.laws import KAPPA_BGT
from .rst import folded, heading, list_table, literal

#: What the commit is called when the code is not a git checkout (or git is missing).
UNKNOWN = "unknown"

#: Where docutils looks for its settings when ``DOCUTILSCONFIG`` is not set (docutils' own list).
DOCUTILS_STANDARD_CONFIGS = ("/etc/docutils.conf", "./docutils.conf", "~/.docutils")

#: The CEL constants in cel.csv's order, with their symbol in the fit table's header (kappa shown as
#: kappa/sqrt(2 pi), the form in which the paper states it: 1.145).
CONSTANTS = {"kappa": r":math:`\kappa/\sqrt{2\pi}`", "mu": r":math:`\mu`", "beta": r":math:`\beta`"}

#: The same, as plain text (the result line).
PLAIN_SYMBOLS = {"kappa": "κ/√(2π)", "mu": "μ", "beta": "β"}

#: What each constant is divided by for the report: kappa by the BGT kappa sqrt(2 pi).
SCALES = {"kappa": KAPPA_BGT, "mu": 1.0, "beta": 1.0}

#: The overbar docutils writes for ``\bar`` (U+02C9, which Chromium drops) and the one the report uses.
DOCUTILS_BAR, MACRON = "\u02c9", "\u00af"

#: The CSS rule that gives MathML a font with an OpenType MATH table, so that brackets and parentheses
#: stretch around fractions (Chromium stretches only with such a font). The landing page
#: (``workflow.rst``) and the caption templates (``figure.rst``, ``fit.rst``) each carry it in a ``<style>``.
MATH_CSS = ('math { font-family: "STIX Two Math", "Latin Modern Math", "DejaVu Math TeX Gyre", "Cambria Math", '
            'math; }')


def git_commit(directory: str | os.PathLike, *, timeout: float = 10.0) -> str:
    """The commit checked out in the git work tree holding ``directory``, or ``"unknown"``.

    The full hash, followed by ``" (uncommitted changes)"`` when a tracked file differs from
    that commit (as ``git describe --dirty`` counts them). ``"unknown"`` when ``directory`` is
    not in a git work tree, or git is missing or fails.
    """

    def git(*args: str) -> str | None:
        try:
            res = subprocess.run(["git", "-C", str(directory), *args], capture_output=True, text=True,
                                 timeout=timeout, check=False)
        except (OSError, subprocess.SubprocessError):
            return None
        return res.stdout.strip() if res.returncode == 0 else None

    commit = git("rev-parse", "--verify", "HEAD")
    if not commit:
        return UNKNOWN
    changes = git("status", "--porcelain", "--untracked-files=no")
    if changes is None:
        return UNKNOWN
    return f"{commit} (uncommitted changes)" if changes else commit


def docutils_config_path(ours: str | os.PathLike, environ: Mapping[str, str]) -> str:
    """The value for ``DOCUTILSCONFIG`` that adds the config file ``ours`` to docutils' settings.

    docutils reads every file of ``DOCUTILSCONFIG`` (``os.pathsep``-separated) in order, later
    ones overriding earlier ones, instead of its standard files. The result keeps what the user
    had (their ``DOCUTILSCONFIG``, else docutils' standard files) and reads ``ours`` last.
    """
    ours = os.fspath(ours)
    before = environ.get("DOCUTILSCONFIG")
    entries = before.split(os.pathsep) if before is not None else list(DOCUTILS_STANDARD_CONFIGS)
    entries = [e for e in entries if e and e != ours]
    return os.pathsep.join([*entries, ours])


def _script_beside_accent(handle_script):
    """docutils' ``handle_script_or_limit`` (``handle_script``), except that the subscript of an accented
    symbol goes beside the accent, as LaTeX sets it: ``\\bar p_\\mathrm{off}`` becomes
    ``<msub><mover>p ¯</mover>off</msub>``, where docutils 0.22 wrote ``<munderover>``, "off" under the p."""

    def handle(node, c, limits=""):
        child = node[-1] if len(node) else None
        if (c == "_" and not limits and isinstance(child, latex2mathml.mover)
                and child.get("accent") == "true"):
            new_node = latex2mathml.msub(node.pop())
            node.append(new_node)
            return new_node
        return handle_script(node, c, limits)

    handle.beside_accent = True
    return handle


def render_maths_as_mathml(config_file: str | os.PathLike) -> None:
    """Make docutils in this process read ``config_file`` (``math_output: MathML``) last.

    The Snakefile calls this, with ``workflow/report/docutils.conf``, before Snakemake renders
    the report's captions and landing page with docutils in the same process. It also makes docutils
    write ``\\bar`` as :data:`MACRON` (U+00AF) in ``<mover>``: its own U+02C9 is dropped by Chromium,
    which turned the caption's mean pressure into the applied one; and set the subscript of an accented
    symbol beside the accent, not under the symbol (:func:`_script_beside_accent`). Calling it again
    changes nothing more.
    """
    os.environ["DOCUTILSCONFIG"] = docutils_config_path(config_file, os.environ)
    latex2mathml.accents["bar"] = MACRON
    if not getattr(latex2mathml.handle_script_or_limit, "beside_accent", False):
        latex2mathml.handle_script_or_limit = _script_beside_accent(latex2mathml.handle_script_or_limit)


def parameters_table(parameters: Mapping) -> str:
    """The scene's parameters as a two-column RST table: dotted key, value (keys sorted)."""
    flat = flatten(parameters)
    if not flat:
        raise ValueError("no parameters to show")
    return list_table(["parameter", "value"], [[f"``{key}``", literal(flat[key])] for key in sorted(flat)])


#: Columns :func:`read_fit_csv` needs in the table of a generated scene (fit.fit_cel) and of a
#: measured one (fit.fit_topographies, told apart by its ``group`` column).
FIT_COLUMNS = ("k_l", "k_s", "H_group", "estimator", "constant", "value", "ci_low", "ci_high", "constrained",
               "n_seeds", "paper_value", "paper_stderr")
MEASURED_FIT_COLUMNS = ("group", "estimator", "constant", "value", "ci_low", "ci_high", "constrained",
                        "n_topographies", "paper_value", "paper_stderr")


def is_measured_fit(rows: Sequence[Mapping[str, str]]) -> bool:
    """Whether rows of a cel.csv come from a measured scene's fit (all topographies pooled)."""
    return bool(rows) and "group" in rows[0]


def read_fit_csv(text: str) -> list[dict[str, str]]:
    """Rows of a cel.csv (:func:`roughcontact.analysis.fit.to_csv_table`) as dictionaries of strings.

    Either layout: a generated scene's (``k_l, k_s, H_group, ...``) or a measured scene's
    (``group, ...``, one pooled group of topographies).
    """
    rows = list(csv.DictReader(io.StringIO(text)))
    if not rows:
        raise ValueError("the fit table has no rows")
    needed = set(MEASURED_FIT_COLUMNS if is_measured_fit(rows) else FIT_COLUMNS)
    missing = needed - set(rows[0])
    if missing:
        raise ValueError(f"the fit table lacks the column(s) {', '.join(sorted(missing))}")
    return rows


def _number(text: str) -> float:
    """A cel.csv cell as a float: NaN when empty."""
    return float(text) if text else float("nan")


#: The joint least squares' bounds as the report states them (kappa and beta as shown: kappa/sqrt(2 pi)).
BOUNDS_TEXT = (f"κ/√(2π) ≥ {JOINT_LOWER[0] / KAPPA_BGT:.1g}, {JOINT_LOWER[1]:g} ≤ μ ≤ 1 − {1 - JOINT_UPPER[1]:.1g}, "
               f"β ≥ {JOINT_LOWER[2]:g}")


def constant_estimate(row: Mapping[str, str]) -> tuple[str, set[str]]:
    """One constant of a cel.csv row as the report prints it, and the footnote marks it carries.

    The value and its 95 % bootstrap interval ``value [low, high]``, divided by :data:`SCALES` (kappa
    as kappa/sqrt(2 pi)) and rounded to the interval (:func:`roughcontact.core.precision.estimate`);
    an end of the interval on a bound of the joint fit is written ``bound`` and the value on one
    ``value (on a bound)``, marked ``‡``; ``*``: not constrained by the data, as the row's ``constrained``
    flag says (:func:`roughcontact.analysis.fit.constrained_flags`, the rule :data:`FOOTNOTES` prints);
    ``†``: no interval (a single measured topography). No value: a dash.
    """
    constant, estimator = row["constant"], row["estimator"]
    value, low, high = (_number(row[k]) for k in ("value", "ci_low", "ci_high"))
    if not np.isfinite(value):
        return "—", set()
    scale = SCALES[constant]
    v, lo, hi = precision.estimate(value / scale, low / scale, high / scale)
    marks = set()
    ends = []
    for raw, text in ((low, lo), (high, hi)):
        if np.isfinite(raw) and at_bound(estimator, constant, raw):
            text, _ = "bound", marks.add("‡")
        ends.append(text)
    if at_bound(estimator, constant, value):
        v = precision.bare(value / scale) + " (on a bound)"
        marks.add("‡")
    cell = f"{v} [{ends[0]}, {ends[1]}]" if ends[0] and ends[1] else v
    if row.get("constrained") == "no":
        marks.add("†" if not (row["ci_low"] and row["ci_high"]) else r"\*")
    return cell + "".join(f" {m}" for m in sorted(marks)), marks


def published_estimate(row: Mapping[str, str]) -> str:
    """The paper's value of a row's constant, ``value ± standard error`` as the report prints it."""
    value, stderr = _number(row["paper_value"]), _number(row["paper_stderr"])
    scale = SCALES[row["constant"]]
    return "—" if not np.isfinite(value) else precision.plus_minus(value / scale, stderr / scale)


#: What each footnote mark of the fit table says.
FOOTNOTES = {
    r"\*": f"not constrained by the data: {UNCONSTRAINED_RULE}.",
    "†": "no bootstrap interval: a single topography says nothing about the scatter between surfaces.",
    "‡": f"on a bound of the joint least-squares fit ({BOUNDS_TEXT}): the data do not bound the constant there.",
}


def fit_table(csv_text: str) -> str:
    """The CEL fit table as RST: one row per group and estimator, a column per constant.

    Groups are ``(k_l, k_s, H group)`` for a generated scene and the pooled topographies for a
    measured one. Each cell is :func:`constant_estimate` (kappa as kappa/sqrt(2 pi), rounded to its
    interval, marks for constants not constrained or on a bound), each mark explained under the
    table; the last column counts the group's surfaces (:func:`seed_count`, or the topographies). A last
    row, ``published``, gives the paper's values ``value ± standard error`` (:func:`published_estimate`).
    Rows keep cel.csv's order; every column of cel.csv is in the report's table of it.
    """
    rows = read_fit_csv(csv_text)
    measured = is_measured_fit(rows)
    keys = ("group", "estimator") if measured else ("k_l", "k_s", "H_group", "estimator")
    groups: dict[tuple[str, ...], dict[str, dict[str, str]]] = {}
    paper: dict[str, dict[str, str]] = {}
    for row in rows:
        if row["constant"] not in CONSTANTS:
            raise ValueError(f"unknown constant {row['constant']!r} in the fit table; expected {', '.join(CONSTANTS)}")
        groups.setdefault(tuple(row[k] for k in keys), {})[row["constant"]] = row
        paper.setdefault(row["constant"], row)
    marks = set()
    body = []
    for key, by_constant in groups.items():
        cells = list(key)
        for constant in CONSTANTS:
            row = by_constant.get(constant)
            cell, row_marks = constant_estimate(row) if row is not None else ("—", set())
            marks |= row_marks
            cells.append(cell)
        first = next(iter(by_constant.values()))
        cells.append(first["n_topographies"] if measured else seed_count(rows, first))
        body.append(cells)
    paper_cells = [published_estimate(paper[c]) if c in paper else "—" for c in CONSTANTS]
    body.append([""] * (len(keys) - 1) + ["published", *paper_cells, ""])
    header = ["surfaces", "estimator"] if measured else [":math:`k_l`", ":math:`k_s`", ":math:`H`", "estimator"]
    header += [*CONSTANTS.values(), "topographies" if measured else "surfaces"]
    text = list_table(header, body)
    for mark, note in FOOTNOTES.items():
        if mark in marks:
            text += f"\n{mark} {note}\n"
    return text


def seed_count(rows: Sequence[Mapping[str, str]], row: Mapping[str, str]) -> str:
    """The surfaces of ``row``'s group of a generated scene's cel.csv, as the report says them (RST).

    cel.csv's ``n_seeds`` counts the group's surfaces: a group pooled over H holds each H's seeds, so its
    count is read with the rows of the same ``(k_l, k_s)`` at each H: ``"3 seeds × 2 values of :math:`H`"``,
    ``"5 seeds: 3 at :math:`H` = 0.36, 2 at :math:`H` = 0.84"`` where the H differ, ``"3 seeds"`` for a
    group of one H (or pooled over one); ``"6 surfaces"`` where ``rows`` lack the groups by H.

    Parameters
    ----------
    rows : sequence of mapping
        The rows of cel.csv (:func:`read_fit_csv`), at least those of ``row``'s ``(k_l, k_s)``.
    row : mapping
        A row of the group.
    """
    n = int(row["n_seeds"])
    if row["H_group"] != "pooled":
        return f"{n} seed{'' if n == 1 else 's'}"
    per_h = {r["H_group"]: int(r["n_seeds"]) for r in rows
             if r["k_l"] == row["k_l"] and r["k_s"] == row["k_s"] and r["H_group"] != "pooled"}
    if not per_h or sum(per_h.values()) != n:
        return f"{n} surfaces"
    if len(set(per_h.values())) > 1:
        return f"{n} seeds: " + ", ".join(f"{c} at :math:`H` = {h}" for h, c in per_h.items())
    each = next(iter(per_h.values()))
    seeds = f"{each} seed{'' if each == 1 else 's'}"
    return seeds if len(per_h) == 1 else f"{seeds} × {len(per_h)} values of :math:`H`"


def csv_html(csv_text: str, title: str) -> str:
    """A CSV file as a complete HTML page holding one table (header row, cells as written, escaped), which the
    report shows when its eye icon is clicked: a browser downloads a CSV file instead of showing it."""
    rows = list(csv.reader(io.StringIO(csv_text)))
    if not rows:
        raise ValueError("the CSV is empty")

    def cells(row, tag):
        return "".join(f"<{tag}>{html.escape(c)}</{tag}>" for c in row)

    body = "\n".join(f"<tr>{cells(r, 'td')}</tr>" for r in rows[1:])
    style = ("body { font-family: sans-serif; font-size: 13px; } table { border-collapse: collapse; } "
             "th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; white-space: nowrap; } "
             "th { background: #eee; position: sticky; top: 0; }")
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{html.escape(title)}</title>"
            f"<style>{style}</style></head>\n<body><h3>{html.escape(title)}</h3>\n<table>\n"
            f"<thead><tr>{cells(rows[0], 'th')}</tr></thead>\n<tbody>\n{body}\n</tbody>\n</table>\n</body></html>\n")


#: The group of cel.csv whose constants the result line gives: the paper's representative point.
RESULT_GROUP = {"k_l": 16.0, "k_s": 32.0}

#: The estimator of the result line: the paper's route, so that it compares like with like.
RESULT_ESTIMATOR = "paper"


def result_group(rows: Sequence[Mapping[str, str]]) -> list[dict[str, str]]:
    """The rows of cel.csv the result line gives: the H-pooled group at :data:`RESULT_GROUP` if fitted,
    else at the largest ``k_l`` (the most representative surfaces) and its largest ``k_s``; a
    measured scene's one pooled group. The :data:`RESULT_ESTIMATOR`'s rows, in cel.csv's order."""
    ours = [r for r in rows if r["estimator"] == RESULT_ESTIMATOR and r["value"]]
    if not ours:
        return []
    if is_measured_fit(ours):
        group = ours[0]["group"]
        return [r for r in ours if r["group"] == group]
    pooled = [r for r in ours if r["H_group"] == "pooled"] or ours
    at = [r for r in pooled if float(r["k_l"]) == RESULT_GROUP["k_l"] and float(r["k_s"]) == RESULT_GROUP["k_s"]]
    if not at:
        kl = max(float(r["k_l"]) for r in pooled)
        ks = max(float(r["k_s"]) for r in pooled if float(r["k_l"]) == kl)
        at = [r for r in pooled if float(r["k_l"]) == kl and float(r["k_s"]) == ks]
    first = at[0]
    return [r for r in at if r["H_group"] == first["H_group"]]


#: What the report says of a scene of profiles (1-D surfaces, plane strain), after its result and its fit.
PROFILES_TEXT = ("These cases are profiles (1-D surfaces in plane strain: :math:`A/A_0` is the contact length "
                 "fraction, :math:`h'` the profile's rms slope). The paper's constants, shown for comparison, were "
                 "fitted to 2-D surfaces and make no prediction for a profile; no constant small-load :math:`\\kappa` "
                 "is known for line contacts (van Dokkum et al. 2018, Tribol. Lett. 66, 115). A constant shown as — is "
                 "one whose fit failed, often because the law's form does not fit a profile's curve (the fit's log "
                 "says why).\n")


def result_rst(csv_text: str | None, *, pull_off: str | None = None, profiles: bool = False,
               unfitted: str | None = None) -> str:
    """The result a reader looks for first, as RST: one paragraph headed **Result**.

    With a fit (``csv_text``, cel.csv): the fitted kappa/sqrt(2 pi), mu and beta of :func:`result_group`
    with their 95 % bootstrap intervals (:func:`constant_estimate`) against the paper's values. An
    adhesive scene (``pull_off``, :func:`~roughcontact.studies.report_tables.pull_off_table`) leads with its
    pull-off table; ``unfitted`` names the contact of a scene whose effects the law does not describe and
    that brings no result table (an adhesive scene without unloading): its result line says so and where its
    per-step results are; a scene without a contact study says where its result is. With ``profiles`` (the
    cases are 1-D surfaces) the result is followed by :data:`PROFILES_TEXT`.
    """
    text = _result_text(csv_text, pull_off, unfitted)
    return text + "\n" + PROFILES_TEXT if profiles and csv_text is not None else text


def _result_text(csv_text: str | None, pull_off: str | None, unfitted: str | None = None) -> str:
    """:func:`result_rst` without the profiles' note."""
    if pull_off is not None:
        return "**Result**: the pull-off pressure of each group of cases.\n\n" + pull_off
    if csv_text is None and unfitted:
        return (f"**Result**: this scene computes {unfitted}, which the contact evolution law does not describe, so "
                "no law is fitted, and it asks for no table of its own (such as a pull-off, which needs the unloading "
                "branch); its per-step results (A/A0, the mean gap and the effects' columns) are in "
                "``aggregate/contact.nc``.\n")
    if csv_text is None:
        return "**Result**: this scene has no contact study; its result is the figures below.\n"
    rows = list(csv.DictReader(io.StringIO(csv_text)))
    chosen = result_group(rows) if rows else []
    if not chosen:
        return ("**Result**: no constant of the contact evolution law was fitted (every case excluded, e.g. for "
                "unconverged load steps, or no fit converged; the fit's log says which).\n")
    where = (f"{chosen[0]['group']}" if is_measured_fit(chosen) else
             rf":math:`\lambda_l = L/{float(chosen[0]['k_l']):g}`, :math:`\lambda_s = L/{float(chosen[0]['k_s']):g}`, "
             rf":math:`H` {chosen[0]['H_group']}, {seed_count(rows, chosen[0])}")
    ours, marks = [], set()
    for r in chosen:
        cell, m = constant_estimate(r)
        ours.append(f"{PLAIN_SYMBOLS[r['constant']]} = {cell}")
        marks |= m
    paper = [f"{PLAIN_SYMBOLS[r['constant']]} = {published_estimate(r)}" for r in chosen]
    text = (f"**Result** ({where}, the paper's route, 95 % bootstrap intervals): " + ", ".join(ours)
            + "; the paper: " + ", ".join(paper) + ".\n")
    for mark, note in FOOTNOTES.items():
        if mark in marks:
            text += f"\n{mark} {note}\n"
    return text


#: Characters of an embedded image's data URI per line of RST.
URI_LINE = 100


def figures_rst(figures: Sequence[tuple[str, bytes, str]]) -> str:
    """The landing page's figures as RST: a ``Figures`` section with, for each ``(name, png, caption)``, a
    link to the report's item ``{name}.png``, the image embedded (a data URI: the report is one file) and its
    caption (RST, as the figure rule wrote it). A scene that draws none says so.
    """
    if not figures:
        return "\n".join([heading("Figures"), "This scene draws no figure.\n"])
    parts = [heading("Figures"), "Each figure with its caption; its name opens it in the report, with its PDF "
             "beside it in the results folder.\n"]
    for name, png, caption in figures:
        if not png.startswith(b"\x89PNG"):
            raise ValueError(f"figure {name!r} is not a PNG")
        # docutils joins the lines of a URI (and refuses a line over 10 000 characters)
        uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        lines = "\n".join("   " + uri[i:i + URI_LINE] for i in range(0, len(uri), URI_LINE))
        parts += [f"`{name}.png`_\n", f".. image::\n{lines}\n   :width: 100%\n   :alt: {name}\n",
                  caption.rstrip() + "\n"]
    return "\n".join(parts)


#: The law as the fit sections write it.
CEL_MATH = r":math:`A/A_0 = \left(\beta + \left[\kappa p_0/(h' E^*)\right]^{\mu-1}\right)^{1/(\mu-1)}`"


def summary_rst(scene: str, parameters: Mapping, *, fit_csv: str | None = None,
                topographies: str | None = None, profiles: bool = False) -> str:
    """The report's landing-page fragment shown below the figures: the CEL fit, the scene's tables and
    its parameters (folded).

    Parameters
    ----------
    scene : str
        The scene's name.
    parameters : mapping
        Its parameters (:func:`roughcontact.pipeline.params.summary`), shown flattened to dotted keys, last
        and folded.
    fit_csv : str, optional
        The text of the scene's ``fit/cel.csv``; ``None`` for a scene without a fit (no contact study, or
        an adhesive one: its pull-off is in :func:`result_rst`). Shown as :func:`fit_table`.
    topographies : str, optional
        A measured scene's :func:`~roughcontact.studies.report_tables.topographies_table`, shown after the fit.
    profiles : bool
        The cases are profiles (1-D surfaces): the fit is followed by :data:`PROFILES_TEXT`.
    """
    parts = []
    if fit_csv is not None and not list(csv.DictReader(io.StringIO(fit_csv))):
        # a fit with no row: every case was excluded (e.g. unconverged steps) or none fitted
        parts += [heading("Contact evolution law fit"),
                  "No constant was fitted: the fit table ``fit/cel.csv`` has no row (every case excluded, "
                  "e.g. for unconverged load steps, or no fit converged; the fit's log says which).\n"]
    elif fit_csv is not None:
        pooled = ("all measured topographies pooled as one surface type" if
                  is_measured_fit(list(csv.DictReader(io.StringIO(fit_csv)))) else
                  "per long and short cutoff (:math:`k_l`, :math:`k_s`) and Hurst exponent (or pooled over "
                  ":math:`H`)")
        unit = "topographies" if "pooled as one" in pooled else "seeds"
        parts += [
            heading("Contact evolution law fit"),
            f"Fit of {CEL_MATH} over the scene's window of :math:`A/A_0`, {pooled}, by the paper's route and "
            f"by a joint least-squares fit (bounds: {BOUNDS_TEXT}): each constant's value and, in brackets, its "
            f"95 % bootstrap interval (resampling whole {unit}), rounded to that interval; :math:`\\kappa` "
            "divided by :math:`\\sqrt{2\\pi}`, as the paper gives it. The estimators' own standard errors, which "
            "understate the scatter between surfaces, are in ``cel.csv`` (its panel shows it whole).\n",
            fit_table(fit_csv),
        ] + ([PROFILES_TEXT] if profiles else [])
    if topographies is not None:
        parts += [heading("Topographies"), topographies]
    flat = flatten(parameters)
    parts += [
        heading(f"Parameters of scene {scene}"),
        "Each study of the scene merged over the config's ``defaults``, every default filled in (its "
        "description and ``keep_surfaces`` aside: they change no result).\n",
        folded(f"{len(flat)} parameters (click to show)", parameters_table(parameters)),
    ]
    return "\n".join(parts)
