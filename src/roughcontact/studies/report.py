"""The landing page of the Snakemake report (``snakemake --report``): pure text builders.

The report's global description (``workflow/report/workflow.rst``) only sees the config, so
the ``report_summary`` rule writes a reStructuredText fragment, ``results/{scene}/report/
summary.rst``, that the description includes: the scene's parameters, the package version and
git commit, and the contact-evolution-law fit table (``fit/cel.csv``) as a table. The fragment
carries no timestamp, so a rerun with the same config, results and code writes the same bytes.

Snakemake renders captions and the description with docutils. docutils' default HTML maths
needs a stylesheet the report does not carry, so the Snakefile calls
:func:`render_maths_as_mathml`, which points docutils at a config file that asks for MathML
(``workflow/report/docutils.conf``); current browsers render MathML natively.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import os
import subprocess
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..core.cell import sides_of
from ..pipeline.provenance import flatten

#: What the commit is called when the code is not a git checkout (or git is missing).
UNKNOWN = "unknown"

#: Where docutils looks for its settings when ``DOCUTILSCONFIG`` is not set (docutils' own list).
DOCUTILS_STANDARD_CONFIGS = ("/etc/docutils.conf", "./docutils.conf", "~/.docutils")

#: The CEL constants in cel.csv's order, with their symbol in the fit table's header.
CONSTANTS = {"kappa": r":math:`\kappa`", "mu": r":math:`\mu`", "beta": r":math:`\beta`"}


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


def render_maths_as_mathml(config_file: str | os.PathLike) -> None:
    """Make docutils in this process read ``config_file`` (``math_output: MathML``) last.

    The Snakefile calls this, with ``workflow/report/docutils.conf``, before Snakemake renders
    the report's captions and landing page with docutils in the same process.
    """
    os.environ["DOCUTILSCONFIG"] = docutils_config_path(config_file, os.environ)


def _literal(value) -> str:
    """A parameter value as RST inline literal text: strings bare, lists joined, the rest JSON."""
    if isinstance(value, str):
        text = value
    elif isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        text = ", ".join(value)
    else:
        text = json.dumps(value, sort_keys=True, separators=(", ", ": "))
    if not text:
        return "(empty)"
    if "`" in text or "\\" in text or text != text.strip() or "\n" in text:  # not as a literal: escaped text
        return "".join(c if c.isalnum() else " " if c.isspace() else "\\" + c for c in text)
    return f"``{text}``"


def _list_table(header: Sequence[str], rows: Sequence[Sequence[str]], *, widths: str = "auto") -> str:
    """An RST ``list-table`` with one header row; cells are RST text (one line each)."""
    lines = [".. list-table::", "   :header-rows: 1", f"   :widths: {widths}", ""]
    for row in [header, *rows]:
        if len(row) != len(header):
            raise ValueError(f"row {row!r} has {len(row)} cells, the header {len(header)}")
        for i, cell in enumerate(row):
            if "\n" in cell:
                raise ValueError(f"table cell {cell!r} spans lines")
            marker = "* -" if i == 0 else "  -"
            lines.append(f"   {marker} {cell}".rstrip())
    return "\n".join(lines) + "\n"


def parameters_table(parameters: Mapping) -> str:
    """The scene's parameters as a two-column RST table: dotted key, value (keys sorted)."""
    flat = flatten(parameters)
    if not flat:
        raise ValueError("no parameters to show")
    return _list_table(["parameter", "value"], [[f"``{key}``", _literal(flat[key])] for key in sorted(flat)])


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


def _estimate(value: str, low: str, high: str) -> str:
    """``value [low, high]`` as the CSV writes them; no interval: the value alone; no value: a dash."""
    if not value:
        return "—"
    return f"{value} [{low}, {high}]" if low and high else value


def fit_table(csv_text: str) -> str:
    """The CEL fit table as RST: one row per group and estimator, a column per constant.

    Groups are ``(k_l, k_s, H group)`` for a generated scene and the pooled topographies for a
    measured one. Each cell is the value and its 95 % bootstrap interval ``value [ci_low,
    ci_high]``, exactly as cel.csv writes them, marked ``*`` where the data do not constrain the
    constant (the interval is wider than the value); in a measured table a value without an
    interval (a single topography: no bootstrap) is marked ``†`` instead. A last row,
    ``published``, gives the paper's values ``value ± standard error``. Rows keep cel.csv's order.
    """
    rows = read_fit_csv(csv_text)
    measured = is_measured_fit(rows)
    keys, count = (("group", "estimator"), "n_topographies") if measured else \
        (("k_l", "k_s", "H_group", "estimator"), "n_seeds")
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
            if row is None:
                cells.append("—")
                continue
            cell = _estimate(row["value"], row["ci_low"], row["ci_high"])
            if row["value"] and row["constrained"] == "no":
                mark = "†" if measured and not (row["ci_low"] and row["ci_high"]) else r"\*"
                cell += " " + mark
                marks.add(mark)
            cells.append(cell)
        cells.append(next(iter(by_constant.values()))[count])
        body.append(cells)
    paper_cells = []
    for c in CONSTANTS:
        value, stderr = (paper[c]["paper_value"], paper[c]["paper_stderr"]) if c in paper else ("", "")
        paper_cells.append("—" if not value else f"{value} ± {stderr}" if stderr else value)
    body.append([""] * (len(keys) - 1) + ["published", *paper_cells, ""])
    header = ["surfaces", "estimator"] if measured else [":math:`k_l`", ":math:`k_s`", ":math:`H`", "estimator"]
    header += [*CONSTANTS.values(), "topographies" if measured else "seeds"]
    text = _list_table(header, body)
    if r"\*" in marks:
        text += "\n\\* not constrained by the data: the bootstrap interval is wider than the value.\n"
    if "†" in marks:
        text += "\n† no bootstrap interval: a single topography says nothing about the scatter between surfaces.\n"
    return text


#: Columns of :func:`topographies_table`, and what each row of it must give.
TOPOGRAPHY_COLUMNS = ("name", "file", "points", "size", "rms slope h'", "undefined", "final p0/(E* h')",
                      "final A/A0", "converged steps")


def topography_row(name: str, surface, contact=None) -> list[str]:
    """One measured case as a row of :func:`topographies_table`, as RST text.

    ``surface``: its surface dataset (``heights``, ``rms_slope``, ``undefined_fraction``, the cell's
    attributes and ``source``); ``contact``: its slice of the contact aggregate (``pressure``,
    ``area_fraction``, ``converged`` over ``step``, attribute ``e_star``) or None without a contact study.
    """
    source = json.loads(surface.attrs.get("source", "{}"))
    nx, ny = (int(surface.sizes[d]) for d in ("x", "y"))
    lx, ly = sides_of(surface.attrs)
    unit = surface.attrs.get("length_units", "1")
    # a case's file holds its name as a length-1 dimension: its scalars have that one element
    slope = float(surface["rms_slope"].squeeze())
    undefined = float(surface["undefined_fraction"].squeeze()) if "undefined_fraction" in surface else 0.0
    row = [f"``{name}``", _literal(Path(source.get("file", "?")).name), f"{nx} x {ny}", f"{lx:.4g} x {ly:.4g} {unit}",
           f"{slope:.3g}", f"{100 * undefined:.1f} %"]
    if contact is None:
        return row + ["", "", ""]
    p_last = float(contact["pressure"].isel(step=-1)) / (float(contact.attrs["e_star"]) * slope)
    conv = contact["converged"].values.astype(bool)
    return row + [f"{p_last:.3g}", f"{float(contact['area_fraction'].isel(step=-1)):.3g}",
                  f"{int(conv.sum())} of {conv.size}"]


def topographies_table(rows: Sequence[Sequence[str]]) -> str:
    """The measured cases of a scene (:func:`topography_row` each) as an RST table, with a lead-in."""
    return ("Each topography file, as read (size and unit after conversion, undefined points filled) and "
            "as loaded: the last load step's p0/(E* h') and contact area fraction, and the load steps "
            "that converged.\n\n" + _list_table(list(TOPOGRAPHY_COLUMNS), rows))


#: Columns of :func:`pull_off_table`.
PULL_OFF_COLUMNS = ("case", "pull-off p_off/E* (mean ± s.d.)", "trusted", "left out (why)", "process zone [cells]",
                    "final A/A0")


def pull_off_table(agg) -> str:
    """An adhesive scene's pull-off per group of cases, as RST, with a lead-in saying what it is.

    ``agg`` is the contact aggregate (``pull_off_pressure``, ``pull_off_status``,
    ``adhesive_zone_cells``, ``area_fraction``, attribute ``e_star``), over ``(k_l, k_s, H, seed)``
    or ``topography``. A row per ``(k_l, k_s, H)`` (the seeds pooled: mean ± sample standard
    deviation of the trusted pull-offs) or per topography; the cases whose pull-off is NaN are
    counted by their status.
    """
    e_star = float(agg.attrs["e_star"])
    meanings = agg["pull_off_status"].attrs["flag_meanings"].split()
    measured = "topography" in agg.dims
    groups = ["topography"] if measured else ["k_l", "k_s", "H"]
    rows = []
    for key, part in _groups(agg, groups):
        present = (part["case_present"].values.astype(bool).ravel() if "case_present" in part
                   else np.ones(part["pull_off_status"].size, dtype=bool))
        pull = _flat(part["pull_off_pressure"])[present] / e_star
        codes = _flat(part["pull_off_status"])[present].astype(int)
        if codes.size == 0:
            continue
        ok = np.isfinite(pull)
        value = "—" if not ok.any() else (f"{pull[ok].mean():.4g} ± {pull[ok].std(ddof=1):.2g}" if ok.sum() > 1
                                          else f"{pull[ok][0]:.4g}")
        why = ", ".join(f"{int((codes == c).sum())} {meanings[c].replace('_', ' ')}" for c in sorted(set(codes[~ok])))
        zone = _flat(part["adhesive_zone_cells"])[present]
        area = _flat(part["area_fraction"].isel(step=-1))[present]
        rows.append([key, value, f"{int(ok.sum())} of {codes.size}", why or "—", f"{zone.min():.3g}",
                     f"{np.nanmean(area):.3g}"])
    lead = ("The pull-off pressure: minus the most tensile mean pressure on unloading under displacement control "
            "from the last load step, the step refined near the minimum until it moves by less than its tolerance. "
            "It is trusted only where the grid resolves the adhesive process zone E* rho^2 / w (at least 1.5 "
            "cells), the last load step converged, the surfaces separated and the steps beside the minimum "
            "converged; other cases are left out, counted by reason. No contact evolution law is fitted to an "
            "adhesive scene: the law and its theories describe contact without adhesion.\n\n")
    return lead + _list_table(list(PULL_OFF_COLUMNS), rows)


def _flat(da) -> np.ndarray:
    """A variable's values as a flat float64 array."""
    return np.asarray(da.values, dtype=float).ravel()


def _groups(agg, dims: Sequence[str]):
    """``(label, part)`` for each combination of ``dims``' values (seeds stay in ``part``)."""
    axes = [agg[d].values for d in dims]
    for values in itertools.product(*axes):
        part = agg.sel(dict(zip(dims, values, strict=True)))
        label = str(values[0]) if len(dims) == 1 else ", ".join(
            f"{d} = {v:g}" for d, v in zip(dims, values, strict=True))
        yield f"``{label}``" if len(dims) == 1 else label, part


def _heading(title: str, underline: str = "-") -> str:
    return f"{title}\n{underline * len(title)}\n"


def summary_rst(scene: str, parameters: Mapping, *, version: str, commit: str,
                fit_csv: str | None = None, topographies: str | None = None, pull_off: str | None = None) -> str:
    """The report's landing-page fragment for ``scene``: code, parameters and the CEL fit.

    Parameters
    ----------
    scene : str
        The scene's name.
    parameters : mapping
        Its parameters (:func:`roughcontact.pipeline.params.summary`), shown flattened to dotted keys.
    version, commit : str
        The package version and the git commit (:func:`git_commit`) of the code.
    fit_csv : str, optional
        The text of the scene's ``fit/cel.csv``; ``None`` for a scene without a contact study.
    topographies : str, optional
        A measured scene's :func:`topographies_table`, shown after the parameters.
    pull_off : str, optional
        An adhesive scene's :func:`pull_off_table`, in place of the fit (an adhesive scene has none).
    """
    if not version or not commit:
        raise ValueError("the version and the commit must be given (the commit may be 'unknown')")
    parts = [
        _heading("Code"),
        f"- roughcontact version: ``{version}``\n- git commit: ``{commit}``\n",
        _heading(f"Parameters of scene {scene}"),
        "Each study of the scene merged over the config's ``defaults``, every default filled in (its "
        "description and ``keep_surfaces`` aside: they change no result).\n",
        parameters_table(parameters),
    ]
    if topographies is not None:
        parts += [_heading("Topographies"), topographies]
    if pull_off is not None:
        parts += [_heading("Adhesion: pull-off"), pull_off]
    if fit_csv is not None and not list(csv.DictReader(io.StringIO(fit_csv))):
        # a fit with no row: every case was excluded (e.g. unconverged steps) or none fitted
        parts += [_heading("Contact evolution law fit"),
                  "No constant was fitted: the fit table ``fit/cel.csv`` has no row (every case excluded, "
                  "e.g. for unconverged load steps, or no fit converged; the fit's log says which).\n"]
    elif fit_csv is not None and is_measured_fit(list(csv.DictReader(io.StringIO(fit_csv)))):
        parts += [
            _heading("Contact evolution law fit"),
            r"Fit of :math:`A/A_0 = \left(\beta + [\kappa p_0/(h' E^*)]^{\mu-1}\right)^{1/(\mu-1)}` over the "
            "scene's window of :math:`A/A_0`, all measured topographies pooled as one surface type, by the paper's "
            "route and by a joint least-squares fit: each constant's value and, in brackets, its 95 % bootstrap "
            "interval (resampling whole topographies; none for a single topography). The estimators' own "
            "standard errors, which understate the scatter between surfaces, are in ``cel.csv``.\n",
            fit_table(fit_csv),
        ]
    elif fit_csv is not None:
        parts += [
            _heading("Contact evolution law fit"),
            r"Fit of :math:`A/A_0 = \left(\beta + [\kappa p_0/(h' E^*)]^{\mu-1}\right)^{1/(\mu-1)}` over the "
            "scene's window of :math:`A/A_0`, per long and short cutoff (:math:`k_l`, :math:`k_s`) and Hurst "
            "exponent (or pooled over :math:`H`), by the paper's route and by a joint least-squares fit: each "
            "constant's value and, in brackets, its 95 % bootstrap interval (resampling whole seeds). The "
            "estimators' own standard errors, which understate the scatter between surfaces, are in "
            "``cel.csv``.\n",
            fit_table(fit_csv),
        ]
    return "\n".join(parts)
