"""A reader's test of every shipped scene (issue 60): its report opened in a real browser, checked as a reader checks
it.

Every scene of the shipped config belongs to a family (:data:`conftest.FAMILIES`): scenes that differ only in grid,
seeds, resolution or loads share one tiny variant, which runs once per session (its fixture in conftest.py). A scene
that no family's variant covers (a study, an output, an effect, a source or a figure it lacks) fails
:func:`test_every_shipped_scene_belongs_to_a_family` and the browser test, naming the scene. For each family,
``snakemake --report`` is built and opened with Playwright driving the distribution's Chromium; the landing page and
every result's page (each figure: its caption, then the figure) are read from the page's text and DOM and checked
against the stored data (``fit/cel.csv``, the contact aggregate's pull-off, the case files):

- no number printed as 0 that is not 0; every interval contains its estimate; an interval that ends at its estimate
  is marked not constrained, in ``cel.csv`` and on the page; every printed interval and ``value ± error`` is one the
  stored data hold, at the precision of :mod:`roughcontact.studies.precision`'s rule (the half-width keeps two
  significant figures when its leading digit is 1 or 2, one otherwise), in one notation; legends and titles too;
- every caption names only what its figure drew (its record ``figures/{figure}.record.json``; where a figure has
  none, the figure drawn again from its inputs): each reference line, the fit and its route, the words of
  :data:`~roughcontact.figures.captions.CONDITIONAL_WORDS`, profiles (1-D) or maps, block averaging;
- the introduction names only the stages the scene ran; no contact evolution law where none is fitted;
- every maths element renders with a size, every overbar is drawn above its base and no index is set under it; no
  reStructuredText markup and no maths as plain text (``rho^2``, ``k_l``) outside maths and literals;
- no console error; every figure at one pixel density; every axis of every figure readable (two tick labels);
- a contact of fewer than :data:`UNRESOLVED_NODES` nodes is flagged unresolved in the files and said on the page.

Every problem of a family is collected and reported together, so that one run shows them all.
"""
from __future__ import annotations

import contextlib
import copy
import csv
import io
import json
import math
import os
import re
import shutil
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from matplotlib.backends.backend_agg import FigureCanvasAgg

from conftest import FAMILIES, FAMILY_PARAMETER, REPO, SceneRun, run_snakemake
from roughcontact import __version__
from roughcontact.figures.captions import CONDITIONAL_WORDS, LEFT_OUT, NOTES, PROFILES_GID, REFERENCES, drawn
from roughcontact.figures.registry import FIGURES, scene_figures
from roughcontact.pipeline.scenes import validate_config
from roughcontact.pipeline.sources import source_of
from roughcontact.studies.report import SCALES

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
try:
    from playwright.sync_api import TimeoutError as PlaywrightTimeout, sync_playwright
except ImportError:  # pragma: no cover - the test extra installs it
    sync_playwright = PlaywrightTimeout = None

#: Why the browser test cannot run here, or None. `make test` installs Playwright (the test extra) and, as root,
#: Debian's chromium (`make browser`); Playwright's own browser download is not used.
NO_BROWSER = ("playwright is not installed (pip install -e '.[test]')" if sync_playwright is None else
              "chromium is not installed (make browser installs it as root with apt-get)" if CHROMIUM is None else None)

#: Screenshots of four families' reports, full page (the README shows the landing page). The test writes them to its
#: temporary folder, and here when ROUGHCONTACT_UPDATE_SCREENSHOTS=1: they show a run's date and CPU time, so
#: rewriting them on every test run would leave the tree changed. The paper-like family's figure page too.
FIGURES_DIR = REPO / "docs" / "figures"
SCREENSHOTS = {"paper-like": FIGURES_DIR / "report_landing.png", "profiles": FIGURES_DIR / "report_profiles.png",
               "adhesion": FIGURES_DIR / "report_adhesion.png", "measured": FIGURES_DIR / "report_measured.png"}
#: The paper-like report's figure page screenshotted (its caption beside the figure).
FIGURE_SHOT = ("kappa", FIGURES_DIR / "report_figure.png")

#: Window of the browser: the result line must lie in its upper half.
WIDTH, HEIGHT = 1280, 1600

#: A contact of fewer nodes than this at a load step is unresolved whatever the patches (a few nodes at most).
UNRESOLVED_NODES = 3


# --------------------------------------------------------------------------------- scenes and families
@contextlib.contextmanager
def _cwd(path: Path):
    old = Path.cwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def _truthy_outputs(contact: dict) -> set[str]:
    return {key for key, value in contact.get("outputs", {}).items() if value}


def _features(scene: dict) -> dict:
    """What a validated scene computes, for matching it to a family: source, dimension, effects and solver kind must
    be the same; studies, outputs and figures a subset."""
    contact = scene.get("contact", {})
    solver = contact.get("solver", {})
    return {"source": source_of(scene).name, "dimension": contact.get("surface", {}).get("dimension", 2),
            "effects": frozenset(contact.get("effects", {})),
            "solver": (solver.get("method"), solver.get("boundary")),
            "studies": frozenset(k for k in scene if k in ("representativity", "contact", "accuracy", "kappa_gap")),
            "outputs": frozenset(_truthy_outputs(contact)), "figures": frozenset(scene_figures(scene))}


def _covers(variant: dict, scene: dict) -> bool:
    same = all(variant[k] == scene[k] for k in ("source", "dimension", "effects", "solver"))
    return same and all(scene[k] <= variant[k] for k in ("studies", "outputs", "figures"))


def _validated(config: dict, where: Path) -> dict:
    """Every scene of ``config``, validated (file paths relative to ``where``, the scene's working directory)."""
    with _cwd(where):
        return validate_config(copy.deepcopy(config))["scenes"]


def _family_features() -> dict[str, dict]:
    """What each family's tiny variant computes."""
    shipped = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    out = {}
    for name, family in FAMILIES.items():
        config = family.config() or copy.deepcopy(shipped)
        where = next(iter(family.files.values())).parent if family.files else REPO
        out[name] = _features(_validated(config, where)[family.scene])
    return out


def family_of(scene: dict, variants: dict[str, dict]) -> str | None:
    """The family of a validated scene: the first (conftest.FAMILIES' order) whose tiny variant covers what it
    computes."""
    features = _features(scene)
    return next((name for name, variant in variants.items() if _covers(variant, features)), None)


SHIPPED = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
SHIPPED_SCENES = _validated(SHIPPED, REPO)
VARIANTS = _family_features()
FAMILY_OF = {scene: family_of(block, VARIANTS) for scene, block in SHIPPED_SCENES.items()}
#: Families the browser test opens: those of the shipped scenes, and the real line scans the issue names; a scene of
#: no family stands as a parameter of its own, which fails naming it.
OPENED = sorted({f for f in FAMILY_OF.values() if f} | {"line-scans"}) + \
    [f"no family: {scene}" for scene, family in FAMILY_OF.items() if family is None]


@pytest.mark.parametrize("scene", sorted(SHIPPED["scenes"]))
def test_every_shipped_scene_belongs_to_a_family(scene):
    assert FAMILY_OF[scene] is not None, (
        f"shipped scene {scene!r} maps to no family of tests/conftest.py FAMILIES: no tiny variant computes what it "
        f"computes ({dict(_features(SHIPPED_SCENES[scene]))}); add one")


def test_a_scene_that_computes_more_than_every_variant_has_no_family():
    config = copy.deepcopy(SHIPPED)
    config["scenes"]["representative"]["contact"]["outputs"] = {"clusters": True, "fields": [30]}
    assert family_of(_validated(config, REPO)["representative"], VARIANTS) is None  # no variant has both
    assert FAMILY_OF["representative"] == "paper-like" and FAMILY_OF["percolation"] == "full-contact"
    assert FAMILY_OF["lines"] == "profiles" and FAMILY_OF["kappa-gap"] == "kappa-gap"


@pytest.fixture
def family_run(request) -> tuple[str, SceneRun]:
    """The family named by the parameter and its scene run (its session fixture, run once)."""
    name = request.param
    if name not in FAMILIES:
        pytest.fail(f"shipped scene {name.split(': ', 1)[1]!r} maps to no family of tests/conftest.py FAMILIES")
    if NO_BROWSER:
        pytest.skip(NO_BROWSER)
    family = FAMILIES[name]
    run = request.getfixturevalue(family.fixture)
    return name, run if isinstance(run, SceneRun) else SceneRun(run, family.scene)


# --------------------------------------------------------------------------------- numbers
NUM = r"[−-]?\d+(?:\.\d+)?(?:e[+−-]?\d+)?"
INTERVAL = re.compile(rf"(?<![\w.])({NUM})(?: \(on a bound\))? \[({NUM}|bound), ({NUM}|bound)\]")
PLUS_MINUS = re.compile(rf"(?<![\w.(])({NUM}) ± ({NUM})(?![\w.])")
SEEDS = re.compile(r"(?<![\w.])(\d+) seeds\b")
#: What marks a constant as not constrained after its interval.
NOT_CONSTRAINED = re.compile(r"^\s*(?:\\?\*|†|‡|\(?not constrained|\(?unconstrained)")


def _float(text: str) -> float:
    return float(text.replace("−", "-"))


def _decimals(text: str) -> set[int]:
    """The decimal places a printed number may have been rounded to (an integer ending in zeros: any of several)."""
    text = text.replace("−", "").lstrip("-")
    if "e" in text:
        mantissa, exponent = text.split("e")
        return {(len(mantissa.split(".")[1]) if "." in mantissa else 0) - int(exponent.replace("−", "-"))}
    if "." in text:
        return {len(text.split(".")[1])}
    zeros = len(text) - len(text.rstrip("0")) if text.strip("0") else 12
    return set(range(-zeros, 1))


def rule_decimals(width: float) -> set[int]:
    """The decimal places :mod:`roughcontact.studies.precision`'s rule allows for an uncertainty ``width`` > 0 (a
    half-width or a standard error): two significant figures when its leading digit is 1 or 2, one otherwise; one
    fewer where the last kept figure is 0 (the paper's 1.145 ± 0.002); a rounding that carries into the next power
    of ten (0.96 -> 1.0) read as the rounded value."""
    if not (math.isfinite(width) and width > 0):
        return set()
    exponent = math.floor(math.log10(width))
    lead = int(f"{width:.6e}"[0])
    d = (2 if lead in (1, 2) else 1) - 1 - exponent
    rounded = round(width, d)
    allowed = {d}
    if rounded > 0 and math.floor(math.log10(rounded)) != exponent:
        allowed |= rule_decimals(rounded)
    if round(rounded * 10 ** d) % 10 == 0:
        allowed.add(d - 1)
    return allowed


def _capped(decimals: set[int], value: float) -> set[int]:
    """``decimals`` with :data:`~roughcontact.studies.precision.MAX_FIGURES` (5) significant figures at most."""
    if value == 0 or not math.isfinite(value):
        return decimals
    top = 4 - math.floor(math.log10(abs(value)))
    return decimals | {min(d, top) for d in decimals}


def _notation(text: str) -> str:
    return "scientific" if "e" in text else "positional"


@dataclass
class Stored:
    """The numbers a scene stored that its pages print: cel.csv's constants (scaled as printed) and the paper's
    values, an adhesive scene's pull-off per group."""

    intervals: list[tuple[str, float, float, float]] = field(default_factory=list)  # (constant, value, low, high)
    pairs: list[tuple[float, float]] = field(default_factory=list)  # (value, error)
    rows: list[dict] = field(default_factory=list)
    seeds: int | None = None  # of each contact case group
    study_seeds: set[int] = field(default_factory=set)  # of each study's groups (contact, representativity)


def stored_numbers(out: Path) -> Stored:
    stored = Stored()
    cel = out / "fit" / "cel.csv"
    if cel.is_file():
        stored.rows = list(csv.DictReader(io.StringIO(cel.read_text())))
        for row in stored.rows:
            scale = SCALES[row["constant"]]
            values = [float(row[k]) / scale if row[k] else math.nan for k in ("value", "ci_low", "ci_high")]
            if math.isfinite(values[0]):
                stored.intervals.append((row["constant"], *values))
            if row["paper_value"] and row["paper_stderr"]:
                stored.pairs.append((float(row["paper_value"]) / scale, float(row["paper_stderr"]) / scale))
    rep = out / "aggregate" / "representativity.nc"
    if rep.is_file():
        with xr.open_dataset(rep) as ds:
            stored.study_seeds |= {int(ds.sizes["seed"])} if "seed" in ds.dims else set()
    agg = out / "aggregate" / "contact.nc"
    if agg.is_file():
        with xr.open_dataset(agg) as ds:
            if "seed" in ds.dims:
                stored.seeds = int(ds.sizes["seed"])
                stored.study_seeds.add(stored.seeds)
            if "pull_off_pressure" in ds:
                groups = ["topography"] if "topography" in ds.dims else ["k_l", "k_s", "H"]
                stacked = ds["pull_off_pressure"].stack(group=groups).transpose("group", ...)
                for values in stacked.values.reshape(stacked.sizes["group"], -1) / float(ds.attrs["e_star"]):
                    ok = values[np.isfinite(values)]
                    if ok.size > 1:
                        stored.pairs.append((float(ok.mean()), float(ok.std(ddof=1))))
    return stored


def _close(printed: str, value: float, decimals: set[int]) -> bool:
    return abs(_float(printed) - value) <= 0.5 * 10 ** -min(decimals) * (1 + 1e-9) + 1e-12 * abs(value)


def check_intervals(text: str, stored: Stored, where: str) -> list[str]:
    """Every ``value [low, high]`` of ``text``: one of the stored intervals, containing its value, at precision, a
    value not 0 never printed 0, one that touches an end marked not constrained."""
    problems = []
    for m in INTERVAL.finditer(text):
        shown, v, lo, hi = m.group(0), m.group(1), m.group(2), m.group(3)
        on_bound = "(on a bound)" in shown
        ends = [e for e in (lo, hi) if e != "bound"]
        if len({_notation(x) for x in ([] if on_bound else [v]) + ends}) > 1:
            problems.append(f"{where}: {shown!r} mixes positional and scientific notation")
        if lo != "bound" and _float(v) < _float(lo) or hi != "bound" and _float(v) > _float(hi):
            problems.append(f"{where}: {shown!r}: the interval does not contain its estimate")
        candidates = [s for s in stored.intervals if _close(v, s[1], _decimals(v))
                      and all(e == "bound" or _close(e, x, _decimals(e)) for e, x in ((lo, s[2]), (hi, s[3])))]
        # a number printed with few places matches several intervals: the nearest is the one printed
        match = min(candidates, key=lambda s: abs(_float(v) - s[1]) + sum(
            abs(_float(e) - x) for e, x in ((lo, s[2]), (hi, s[3])) if e != "bound"), default=None)
        if match is None:
            problems.append(f"{where}: {shown!r} is no interval of the stored fit (cel.csv) as printed")
            continue
        constant, value, low, high = match
        if _float(v) == 0 and value != 0:
            problems.append(f"{where}: {shown!r} prints as 0 the {constant} of cel.csv, {value:.4g}")
        if math.isfinite(low) and math.isfinite(high) and high > low and not on_bound:
            allowed = _capped(rule_decimals((high - low) / 2), value)
            if abs(value) >= (high - low) / 2 and value not in (low, high):
                # the rule's 4th point: a value inside its interval gets more places until it differs from both ends
                d = min(allowed)
                while d < 12 and round(value, d) in (round(low, d), round(high, d)):
                    d += 1
                allowed = allowed | set(range(min(allowed), d + 1))

            def one_figure(x, allowed=allowed):  # not 0 but would read 0 at the common place: one figure kept
                if x == 0 or abs(x) >= 0.5 * 10 ** -min(allowed):
                    return set()
                first = -math.floor(math.log10(abs(x)))
                return {first, first - 1}

            kept = [_decimals(e) for e, x in zip((lo, hi), (low, high), strict=True)
                    if e != "bound" and not _decimals(e) & one_figure(x)]
            at = set.intersection(*kept) if kept else allowed
            small = set()  # a value smaller than its interval's half-width may keep one significant figure
            if value and abs(value) < (high - low) / 2:
                first = -math.floor(math.log10(abs(value)))
                small = {first, first - 1}
            if not at & allowed or not _decimals(v) & (at & allowed | small):
                problems.append(f"{where}: {shown!r} is rounded to {sorted(_decimals(v))} decimal places, its ends to "
                                f"{sorted(at)}; the half-width {(high - low) / 2:.3g} asks for {sorted(allowed)}")
        # printed equal to an end: the rule prints that only for an interval that does end at its estimate (or one
        # wider than twice the value, marked not constrained anyway)
        touches = value in (low, high) or not low < value < high or _float(v) in {_float(e) for e in ends}
        marked = NOT_CONSTRAINED.match(text[m.end():m.end() + 20]) or \
            re.search(r"(?:not constrained|unconstrained)[^\[\]]{0,30}$", text[max(0, m.start() - 40):m.start()])
        if touches and not on_bound and not marked:
            problems.append(f"{where}: {shown!r} ends at its own estimate and is not marked not constrained")
    return problems


def check_plus_minus(text: str, stored: Stored, where: str) -> list[str]:
    """Every ``value ± error`` of ``text``: stored, at the error's precision, in one notation, not a false 0."""
    problems = []
    for m in PLUS_MINUS.finditer(text):
        shown, v, e = m.group(0), m.group(1), m.group(2)
        if _notation(v) != _notation(e):
            problems.append(f"{where}: {shown!r} mixes positional and scientific notation")
        common = _decimals(v) & _decimals(e)
        allowed = _capped(rule_decimals(_float(e)), _float(v)) if _float(e) > 0 else set()
        if not common & allowed:
            problems.append(f"{where}: {shown!r}: value and error rounded to {sorted(_decimals(v))} and "
                            f"{sorted(_decimals(e))} decimal places; the error asks for {sorted(allowed)}")
        tolerance = _decimals(v) | _decimals(e)
        match = next((p for p in stored.pairs if _close(v, p[0], tolerance) and _close(e, p[1], tolerance)), None)
        if match is None:
            problems.append(f"{where}: {shown!r} is no value ± error the scene stored (cel.csv's published values, "
                            "the pull-off of a group)")
        elif _float(v) == 0 and match[0] != 0:
            problems.append(f"{where}: {shown!r} prints as 0 the stored {match[0]:.4g}")
    return problems


def check_seeds(text: str, seeds: set[int], where: str) -> list[str]:
    """``N seeds`` gives the seeds of each group of cases (an aggregate's seed axis), not seeds times H values."""
    if not seeds:
        return []
    return [f"{where}: says {m.group(0)!r}; each group has {' or '.join(map(str, sorted(seeds)))} seeds (the "
            "aggregate's seed axis)" for m in SEEDS.finditer(text) if int(m.group(1)) not in seeds]


def check_stored_flags(out: Path) -> list[str]:
    """cel.csv (and cel.nc): an interval that ends at or excludes its own estimate is not constrained."""
    problems = []
    for row in stored_numbers(out).rows:
        if not (row["value"] and row["ci_low"] and row["ci_high"]):
            continue
        value, low, high = (float(row[k]) for k in ("value", "ci_low", "ci_high"))
        if not low < value < high and row["constrained"] != "no":
            group = row.get("H_group", row.get("group"))
            problems.append(f"cel.csv: {row['constant']} ({row.get('estimator')}, {group})"
                            f" = {row['value']} [{row['ci_low']}, {row['ci_high']}] marked constrained "
                            f"{row['constrained']!r}: its interval ends at (or excludes) its estimate")
    nc = out / "fit" / "cel.nc"
    if nc.is_file():
        with xr.open_dataset(nc) as ds:
            if {"value", "ci_low", "ci_high", "constrained"} <= set(ds.variables):
                value, low, high = (ds[k].values for k in ("value", "ci_low", "ci_high"))
                bad = np.isfinite(value) & np.isfinite(low) & np.isfinite(high) & ~((low < value) & (value < high)) \
                    & (ds["constrained"].values == 1)
                if bad.any():
                    problems.append(f"cel.nc: {int(bad.sum())} constant(s) flagged constrained whose interval ends at "
                                    "(or excludes) the estimate")
    return problems


# --------------------------------------------------------------------------------- captions
#: The route of a fit as a caption names it (the estimators of cel.csv).
ROUTES = {"paper": "paper's route", "joint": "joint least-squares"}

#: Which reference lines (gids of REFERENCES) each conditional word stands for.
WORD_GIDS = {"BGT": ("bgt_limit", "asperity_bgt_paper", "asperity_bgt_own"),
             "Greenwood": ("asperity_greenwood_paper", "asperity_greenwood_own"),
             "Persson": ("persson_limit", "persson_erf"),
             "evolution law": ("cel_paper", "cel_fit"),
             "asperity": ("asperity_bgt_paper", "asperity_greenwood_paper", "asperity_bgt_own",
                          "asperity_greenwood_own"),
             "power law": ("dpbar_paper", "dpbar_fit"),
             "fit's window": ("fit_window",)}
assert set(WORD_GIDS) <= set(CONDITIONAL_WORDS), "a conditional word of figures.captions needs its gids here"
#: The other conditional words (figures.captions: a lead may not use them) name a fit's route or a layout: checked
#: against the record's fits (ROUTES) and notes (figures.captions.NOTES, :func:`check_notes`).


def _plain_key(phrase: str) -> str:
    """The longest run of plain words of a REFERENCES phrase (between its maths): how the page shows it."""
    parts = re.split(r":math:`[^`]*`", phrase)
    return max((p.strip(" ,;:(") for p in parts), key=len)


def _render(name: str, run: SceneRun, scene: dict):
    """Figure ``name`` drawn again from its inputs, as the figure rule draws it (the record's stand-in)."""
    spec = FIGURES[name]
    paths = {role: [str(run.out / p) for p in v] if isinstance(v, list) else str(run.out / v)
             for role, v in spec.input_paths(scene).items()}
    fig = spec.render(paths)
    FigureCanvasAgg(fig).draw()  # tick labels and legends as the PNG shows them
    return fig


@dataclass
class Drawn:
    """What a figure drew: from its record (``figures/{figure}.record.json``), or, where it has none, from the figure
    drawn again (its tagged reference lines, a fit by its tag, profiles by the figure's gid or the scene's surfaces)."""

    references: set[str]
    fits: list[dict]
    window: bool
    profiles: bool  # the caption must say the cases are profiles
    profiles_allowed: bool  # it may
    from_record: bool
    notes: tuple[str, ...] = ()  # the layout notes of figures.captions.NOTES the record holds
    left_out: tuple[str, ...] = ()  # what it says it leaves out (figures.captions.LEFT_OUT)


def what_was_drawn(name: str, out: Path, fig, profiles: bool) -> Drawn:
    """``profiles``: the scene's cases are profiles (1-D surfaces)."""
    record = out / "figures" / f"{name}.record.json"
    if record.is_file():
        rec = json.loads(record.read_text())
        return Drawn(set(rec.get("references", [])), list(rec.get("fits", [])), bool(rec.get("window")),
                     bool(rec.get("profiles")), bool(rec.get("profiles")), True, tuple(rec.get("notes", ())),
                     tuple(rec.get("left_out", ())))
    gids = set(drawn(fig))
    fits = [{"route": None, "label": None} for g in ("cel_fit", "dpbar_fit") if g in gids]
    return Drawn(gids, fits, "fit_window" in gids, fig.get_gid() == PROFILES_GID, profiles, False)


def check_caption(name: str, caption: str, what: Drawn, max_side: int, where: str) -> list[str]:
    """The caption names exactly what the figure drew."""
    problems = []
    for gid, phrase in REFERENCES.items():
        shown = gid in what.references
        if (_plain_key(phrase) in caption) != shown:
            problems.append(f"{where}: the caption {'omits' if shown else 'names'} {_plain_key(phrase)!r}, which the "
                            f"figure {'drew' if shown else 'did not draw'} ({gid})")
    for key in what.left_out:  # "The asperity models are not drawn: ...": a word said of what was left out
        sentence = LEFT_OUT[key].split(":")[0]
        if sentence not in caption:
            problems.append(f"{where}: the record leaves out {key!r}; the caption does not say so")
        caption = caption.replace(sentence, "")
    for word, gids in WORD_GIDS.items():
        implied = set(gids) & what.references or (word == "evolution law" and what.fits) or \
            (word == "fit's window" and what.window)
        if word in caption and not implied:
            problems.append(f"{where}: the caption says {word!r}; the figure drew none of {', '.join(gids)}")
    routes = {f["route"] for f in what.fits}
    if what.from_record:
        for route, words in ROUTES.items():
            if (words in caption) != (route in routes):
                problems.append(f"{where}: the caption {'names' if route not in routes else 'omits'} the {words} "
                                f"(fits recorded: {sorted(routes) or 'none'})")
        for route in routes - set(ROUTES):
            if route not in caption:
                problems.append(f"{where}: the caption does not name the fit's route {route!r}")
    elif what.fits and not any(words in caption for words in ROUTES.values()):
        problems.append(f"{where}: the figure draws a fitted law; the caption names no route "
                        f"({', '.join(ROUTES.values())}): figures/{name}.record.json absent, checked against the "
                        "figure drawn again")
    if what.from_record:
        problems += check_notes(caption, what.notes, where)
    says_profiles = bool(re.search(r"\bprofiles?\b|\b1-D\b", caption))
    if says_profiles and not what.profiles_allowed:
        problems.append(f"{where}: the caption speaks of profiles (1-D); the figure is of 2-D surfaces")
    if what.profiles and not says_profiles:
        problems.append(f"{where}: the caption does not say that the cases are profiles (1-D)")
    if "block-averag" in caption and max_side <= 512:
        problems.append(f"{where}: the caption speaks of block averaging; no surface of the scene has over 512 points"
                        f" a side (at most {max_side})")
    return problems


def check_notes(caption: str, notes, where: str) -> list[str]:
    """Each layout note of figures.captions.NOTES (its first plain words) in the caption iff the record holds it."""
    problems = []
    for key, text in NOTES.items():
        plain = re.split(r":math:`[^`]*`", text)[0]
        plain = plain.split("{pixels}", 1)[-1]  # "Maps of more than {pixels} points a side are drawn/shown ..."
        words = " ".join(plain.split()[:5])
        if (words in caption) != (key in notes):
            problems.append(f"{where}: the caption {'omits' if key in notes else 'says'} {words!r} (note {key!r}), "
                            f"{'recorded' if key in notes else 'which the record does not hold'}")
    return problems


def check_figure_text(name: str, fig, stored: Stored, what: Drawn, where: str) -> list[str]:
    """A figure's titles, legends and fit labels: seeds, numbers at the precision of the stored fit; every axis
    readable: at least two tick labels where it shows any."""
    problems = []
    texts = [fig._suptitle.get_text() if getattr(fig, "_suptitle", None) else ""]
    labels = [f["label"] for f in what.fits if f.get("label")]
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        texts.append(ax.get_title())
        legend = ax.get_legend()
        if legend is not None:
            labels += [t.get_text() for t in legend.get_texts()]
        for axis, (lo, hi) in ((ax.xaxis, sorted(ax.get_xlim())), (ax.yaxis, sorted(ax.get_ylim()))):
            if not (ax.axison and axis.get_visible()):
                continue
            ticks = [t for t in axis.get_major_ticks() + axis.get_minor_ticks()
                     if lo - 1e-9 * abs(hi - lo) <= t.get_loc() <= hi + 1e-9 * abs(hi - lo)]
            shown = [t for t in ticks if (t.label1.get_visible() and t.label1.get_text())
                     or (t.label2.get_visible() and t.label2.get_text())]
            hidden_on_purpose = not any(t.label1.get_visible() or t.label2.get_visible() for t in ticks)
            if ticks and not hidden_on_purpose and len({t.get_loc() for t in shown}) < 2:  # no ticks: none wanted
                problems.append(f"{where}: an axis of panel {ax.get_label() or ax.get_title() or fig.axes.index(ax)} "
                                f"shows {len(shown)} tick label(s): "
                                f"{[t.label1.get_text() or t.label2.get_text() for t in shown]}")
    for legend in fig.legends:
        labels += [t.get_text() for t in legend.get_texts()]
    plain = [re.sub(r"[$\\{}]|mathrm|mu|beta|kappa", lambda m: {"mu": "μ", "beta": "β", "kappa": "κ"}.get(
        m.group(0), ""), t) for t in texts + labels]
    problems += check_seeds(" ".join(plain[:len(texts)]), stored.study_seeds, f"{where} title")
    for label in plain[len(texts):]:
        for symbol, constant in (("μ", "mu"), ("β", "beta"), ("κ", "kappa")):
            for m in re.finditer(rf"{symbol}(?:/√\(2π\)|/\s*sqrt\(?2\s*π\)?)?\s*=\s*({NUM})", label):
                printed = m.group(1)
                rows = [s for s in stored.intervals if s[0] == constant and _close(printed, s[1], _decimals(printed))
                        and math.isfinite(s[2]) and math.isfinite(s[3]) and s[3] > s[2]]
                allowed = [_capped(rule_decimals((s[3] - s[2]) / 2), s[1]) for s in rows]
                if rows and not any(_decimals(printed) & a for a in allowed):
                    problems.append(f"{where}: legend {label!r} gives {constant} = {printed}; its interval "
                                    f"{rows[0][2]:.3g}-{rows[0][3]:.3g} asks for {sorted(allowed[0])} places")
    return problems


# --------------------------------------------------------------------------------- the page
#: Text of the elements matching a selector: maths as its text (or left out), some elements dropped.
TEXT_JS = """([selector, drop, maths]) => [...document.querySelectorAll(selector)].map(root => {
  const c = root.cloneNode(true);
  c.querySelectorAll("style, script" + (drop ? ", " + drop : "")).forEach(e => e.remove());
  c.querySelectorAll("math").forEach(m =>
    m.replaceWith(document.createTextNode(maths ? " " + m.textContent + " " : " ")));
  return c.textContent.replace(/\\s+/g, " ").trim();
}).join(" \\n ")"""

#: Every maths element's size, every overbar (a <mover> over U+00AF, U+02C9 or a combining macron) and whether it
#: is drawn above its base, every index set under a symbol (<munder>, <munderover> on an identifier).
MATHS_JS = """(root) => {
  const folded = [...document.querySelectorAll("#app details")].filter(d => !d.open);
  folded.forEach(d => d.open = true);
  const bar = e => ["\\u00af", "\\u02c9", "\\u0304"].includes(e.textContent.trim());
  const text = e => e.textContent.replace(/\\s+/g, "");
  const all = s => [...document.querySelectorAll(root.split(",").map(r => r + " " + s).join(", "))];
  const sizes = all("math").map(m => {
    const r = m.getBoundingClientRect(); return [text(m), r.width, r.height]; });
  const bars = all("mover").filter(m => m.children.length == 2 && bar(m.children[1]));
  const undrawn = bars.filter(m => {
    const b = m.children[0].getBoundingClientRect(), o = m.children[1].getBoundingClientRect();
    return !(o.width > 0 && o.height > 0 && o.bottom <= b.top + 0.6 * b.height); }).map(text);
  const under = [...all("munder"), ...all("munderover")].filter(m =>
    m.children[0].tagName.toLowerCase() == "mi").map(m => text(m.closest("math")));
  folded.forEach(d => d.open = false);
  return {sizes, bars: bars.length, undrawn, under};
}"""

#: The landing page's figures: name, natural and drawn width.
IMAGES_JS = """() => [...document.querySelectorAll("#app .document img")]
  .filter(i => i.src.startsWith("data:image/png")).map(i => [i.alt, i.naturalWidth, i.getBoundingClientRect().width])"""

#: The height the whole page needs (the app scrolls inside the window: the sidebar and the main area).
HEIGHT_JS = """() => Math.max(document.documentElement.scrollHeight,
  ...[...document.querySelectorAll("#app nav, #app .overflow-auto")]
    .map(e => e.scrollHeight + e.getBoundingClientRect().top))"""

#: Text of the sidebar cut at its edge (the breadcrumb's path, the result's path: Snakemake's sidebar narrows when a
#: figure is shown).
CUT_JS = """() => { const nav = document.querySelector("#app nav"); if (!nav) return [];
  const right = nav.getBoundingClientRect().right;
  return [...nav.querySelectorAll("*")].filter(e => [...e.childNodes].some(n => n.nodeType == 3 && n.textContent.trim())
    && e.getBoundingClientRect().right > right + 1).map(e => e.textContent.trim()); }"""

#: reStructuredText markup a reader must never see.
MARKUP = [re.compile(p) for p in (r":[a-z]+:`", r"``", r"(?<!\w)\.\. [a-z-]+::", r"System Message", r"\\n",
                                  r"\*\*\w", r"`_\b", r"\|\w+\|")]
#: Maths typed as text (outside maths, literals and links): a power, an index, a TeX command.
PLAIN_MATHS = [re.compile(p) for p in (r"\b[A-Za-z]+\^[\w({]",
                                       r"(?<![\w./-])[A-Za-z]{1,4}_[A-Za-z0-9]{1,4}\b(?![./-]\w)", r"\\[a-zA-Z]{2,}")]
#: Elements whose text is not prose: maths, literals, links (file names), code.
#: Elements whose text is not prose: literals, links (file names), code, and the files shown as written when unfolded
#: (a CSV's columns, the parameters' keys).
NOT_PROSE = "tt, code, pre, a, kbd, .docutils.literal, details table"


def _png_dpi(path: Path) -> float | None:
    data = path.read_bytes()
    at = data.find(b"pHYs")
    if at < 0:
        return None
    x, _, unit = struct.unpack(">IIB", data[at + 4:at + 13])
    return round(x * 0.0254, 1) if unit == 1 else None


@dataclass
class Page:
    """One browser tab on a report, with everything the console said."""

    page: object
    console: list[str] = field(default_factory=list)

    def text(self, selector: str, drop: str = "", maths: bool = True) -> str:
        return self.page.evaluate(TEXT_JS, [selector, drop, maths])

    def shot(self, path: Path) -> None:
        """A screenshot of the whole page, the window as tall as the content (no sidebar cut short)."""
        height = int(self.page.evaluate(HEIGHT_JS))
        self.page.set_viewport_size({"width": WIDTH, "height": max(HEIGHT, height)})
        self.page.wait_for_timeout(300)
        self.page.screenshot(path=str(path), full_page=True)
        self.page.set_viewport_size({"width": WIDTH, "height": HEIGHT})


def check_page_common(page: Page, where: str, scene: str, description: str | None,
                      root: str = "#app .document") -> tuple[list[str], int]:
    """What every page must be: maths drawn, no markup, no maths as text (in ``root``'s prose: the landing page's, or
    a result's caption), nothing cut. Also the overbars' count."""
    problems = []
    maths = page.page.evaluate(MATHS_JS, root)
    problems += [f"{where}: maths {t!r} renders at {w:.0f} x {h:.0f} px" for t, w, h in maths["sizes"]
                 if w <= 0 or h <= 0]
    problems += [f"{where}: the overbar of {t!r} is not drawn above its base" for t in maths["undrawn"]]
    problems += [f"{where}: an index is set under its symbol in {t!r} (write \\bar{{p}}_\\mathrm{{off}})"
                 for t in maths["under"]]
    shown = page.text("#app")
    for pattern in MARKUP:
        problems += [f"{where}: reStructuredText markup on screen: {m.group(0)!r} in "
                     f"{shown[max(0, m.start() - 40):m.end() + 40]!r}" for m in pattern.finditer(shown)]
    prose = _description_free(page.text(root, NOT_PROSE, maths=False), scene, description)
    for pattern in PLAIN_MATHS:
        problems += [f"{where}: maths as plain text: {m.group(0)!r} in {prose[max(0, m.start() - 40):m.end() + 40]!r}"
                     for m in pattern.finditer(prose)]
    problems += check_cut(page, where)
    if "\u02c9" in page.page.content():
        problems.append(f"{where}: an overbar written as U+02C9, which Chromium drops (the report uses U+00AF)")
    return problems, maths["bars"]


def check_cut(page: Page, where: str) -> list[str]:
    """No text of the sidebar cut at its edge (once its width has settled: it changes in a CSS transition)."""
    with contextlib.suppress(PlaywrightTimeout):
        page.page.wait_for_function(f"() => ({CUT_JS})().length == 0", timeout=2000)
    return [f"{where}: text cut at the sidebar's edge: {t!r}" for t in page.page.evaluate(CUT_JS)]


def _description_free(text: str, scene: str, description: str | None) -> str:
    """``text`` without the scene's description (the user's own words, shown as written)."""
    return text.replace(f"Scene {scene}: {description}", " ") if description else text


# --------------------------------------------------------------------------------- the test
def _cases(out: Path) -> list[Path]:
    return sorted((out / "contact").glob("*.nc"))


def _dimension(out: Path) -> int:
    """The scene's surfaces' dimension (1: profiles), from its case files."""
    cases = _cases(out)
    if not cases:
        return 2
    with xr.open_dataset(cases[0]) as ds:
        return int(ds.attrs.get("surface_dimension", 2))


def _max_side(out: Path) -> int:
    sides = [0]
    for path in _cases(out):
        with xr.open_dataset(path) as ds:
            sides += [int(ds.attrs.get("nx", 0)), int(ds.attrs.get("ny", 0))]
    return max(sides)


def _unresolved_flags(ds: xr.Dataset) -> list[str]:
    """Variables of ``ds`` over the load steps that are CF flags with a meaning that says unresolved."""
    return [v for v in ds.data_vars
            if "step" in ds[v].dims and "unresolved" in str(ds[v].attrs.get("flag_meanings", ""))]


def check_unresolved(out: Path, landing: str) -> list[str]:
    """A contact of fewer than UNRESOLVED_NODES nodes at a step: flagged in its file or the contact aggregate (a CF
    flag over the steps with a meaning that says unresolved) and said on the page."""
    problems = []
    aggregate = out / "aggregate" / "contact.nc"
    with contextlib.ExitStack() as stack:
        in_aggregate = aggregate.is_file() and bool(_unresolved_flags(stack.enter_context(xr.open_dataset(aggregate))))
    for path in _cases(out):
        with xr.open_dataset(path) as ds:
            if "area_fraction" not in ds or "step" not in ds["area_fraction"].dims:
                continue
            nodes = np.rint(ds["area_fraction"].values * int(ds.attrs["nx"]) * int(ds.attrs.get("ny", 1)))
            few = (nodes > 0) & (nodes < UNRESOLVED_NODES)
            if not few.any():
                continue
            steps = ds["step"].values[few.reshape(-1, ds.sizes["step"]).any(axis=0)]
            if not (_unresolved_flags(ds) or in_aggregate):
                problems.append(f"{path.name}: the contact spans {int(nodes[few].min())} node(s) at step(s) "
                                f"{steps.tolist()}: no flag of its file says unresolved")
            if "unresolved" not in landing:
                problems.append(f"the page does not say that {path.stem}'s contact at step(s) {steps.tolist()} "
                                f"({int(nodes[few].min())} node(s)) is unresolved")
    return problems


def check_introduction(text: str, out: Path, cel_math: bool) -> list[str]:
    """The introduction (before the result) names only the stages the scene ran; no law where none is fitted."""
    problems = []
    intro = text.split("Result", 1)[0]
    fitted = (out / "fit" / "cel.csv").is_file()
    summary = out / "accuracy" / "summary.nc"
    if not fitted and summary.is_file():  # the accuracy study fits the law per setting: its errors of the constants
        with xr.open_dataset(summary) as ds:
            fitted = {"err_cel_kappa", "err_cel_mu", "err_cel_beta"} <= set(ds.variables)
    if cel_math and not fitted:
        problems.append("the page writes the contact evolution law (a formula with κ, μ and β) and the scene fits "
                        "none (no fit/cel.csv, no accuracy summary of the law's constants)")
    stages = {"representativity": (out / "aggregate" / "representativity.nc").is_file()}
    for words, ran in stages.items():
        said = [m for m in re.finditer(re.escape(words), intro)
                if not re.search(r"\b(?:no|not|nor|without)\b[^.;]{0,40}$", intro[:m.start()], re.IGNORECASE)]
        if said and not ran:
            problems.append(f"the introduction names {words!r}, a stage the scene did not run")
    cases = _cases(out)
    with contextlib.ExitStack() as stack:
        generated = bool(cases) and "k_l" in stack.enter_context(xr.open_dataset(cases[0])).dims
    if ("white noise" in intro or "FFT filtering" in intro) and cases and not generated:
        problems.append("the introduction says the surfaces were made by FFT filtering of white noise; this scene's "
                        "are files")
    return problems


def build_report(run: SceneRun, tmp_path: Path) -> Path:
    report = tmp_path / "report.html"
    res = run_snakemake(run.wd, "--report", str(report), "--config", f"scene={run.scene}", timeout=600)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    return report


def _scene_block(run: SceneRun) -> dict:
    config = yaml.safe_load((run.wd / "config" / "config.yaml").read_text())
    config["scene"] = run.scene
    return _validated(config, run.wd)[run.scene]


def open_report(playwright, report: Path) -> Page:
    browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
    tab = Page(browser.new_page(viewport={"width": WIDTH, "height": HEIGHT}))
    tab.page.on("console", lambda m: tab.console.append(f"{m.type}: {m.text}") if m.type == "error" else None)
    tab.page.on("pageerror", lambda e: tab.console.append(f"page error: {e}"))
    tab.page.goto(report.as_uri())
    tab.page.wait_for_function("() => typeof app !== 'undefined' && document.querySelector('#app .document')")
    tab.page.wait_for_timeout(500)
    return tab


def check_landing(tab: Page, run: SceneRun, stored: Stored, description: str | None) -> list[str]:
    """The landing page: the result first, the figures at one density, the introduction, every number."""
    out, problems = run.out, []
    text = tab.text("#app .document")
    assert f"Parameters of scene {run.scene}" in text, f"the app did not render the landing page: {text[:500]!r}"
    top = tab.page.evaluate("""() => { const r = [...document.querySelectorAll("#app .document strong")]
        .find(e => e.textContent.trim() === "Result"); return r ? r.getBoundingClientRect().top : null; }""")
    if top is None or not 0 <= top < HEIGHT / 2:
        problems.append(f"the result line is at {top} px, not in the upper half of a {HEIGHT} px window")
    numbers = _description_free(text, run.scene, description)
    problems += check_intervals(numbers, stored, "landing page")
    problems += check_plus_minus(numbers, stored, "landing page")
    result = numbers.split("Result", 1)[-1].split("Figures", 1)[0]
    problems += check_seeds(result, {stored.seeds} - {None}, "the result")
    cel_math = any(all(s in t for s in "κμβ") for t, _, _ in tab.page.evaluate(MATHS_JS, "#app")["sizes"])
    problems += check_introduction(text, out, cel_math)
    # every figure embedded with its caption, at one pixel density on screen and in its file
    figures = sorted(p.stem for p in (out / "figures").glob("*.png"))
    images = tab.page.evaluate(IMAGES_JS)
    if sorted(name for name, _, _ in images) != figures:
        problems.append(f"the landing page shows {sorted(n for n, _, _ in images)}; the scene drew {figures}")
    scales = {name: drawn_w / natural for name, natural, drawn_w in images if natural}
    if scales and max(scales.values()) > 1.02 * min(scales.values()):
        problems.append(f"figures at different pixel densities on screen (drawn/natural width): "
                        f"{ {k: round(v, 3) for k, v in scales.items()} }")
    dpis = {name: _png_dpi(out / "figures" / f"{name}.png") for name in figures}
    if len(set(dpis.values())) > 1:
        problems.append(f"figures saved at different resolutions (dpi): {dpis}")
    # the parameters folded, the code and the run recorded
    if "parameters (click to show)" not in text:
        problems.append("the parameters are not folded")
    for shown in (f"roughcontact version: {__version__}", "git commit: unknown", "numpy", "pyFFTW", "FFTW", "host:",
                  "run recorded:", "total CPU time of the run's jobs:"):
        if shown not in text:
            problems.append(f"the provenance lacks {shown!r}")
    for pdf in sorted((out / "figures").glob("*.pdf")):
        if not re.search(rf"{re.escape(pdf.name)} \([^)]*vector PDF\)", text):
            problems.append(f"{pdf.name} is not listed as the vector PDF")
    if (out / "fit" / "cel.csv").is_file() and "cel.html (Fit)" not in text:
        problems.append("the fit table (cel.html) is not listed")
    problems += check_unresolved(out, text)
    return problems


def check_figure_page(tab: Page, run: SceneRun, name: str, scene: dict, stored: Stored,
                      max_side: int) -> tuple[list[str], int]:
    """A figure's page (its caption), then the figure itself (the eye icon); the caption against what it drew.
    Also the page's overbars' count."""
    where = f"{name}.png"
    path = f"results/{run.scene}/figures/{name}.png"
    tab.page.evaluate("(p) => app.showResultInfo(p)", path)
    tab.page.wait_for_selector("#app nav li.prose")
    tab.page.wait_for_timeout(500)  # the sidebar widens (a CSS transition)
    caption = tab.text("#app nav li.prose")
    problems, bars = check_page_common(tab, f"{where} page", run.scene, scene.get("description"), "#app nav li.prose")
    if f"scene={run.scene}, figure={name}" not in tab.text("#app nav"):
        problems.append(f"{where} page: the job's parameters (scene={run.scene}, figure={name}) are not shown")
    eye = tab.page.locator("#app nav a[iconname=eye]")
    if eye.count() != 1:
        problems.append(f"{where} page: no eye icon to show the figure")
    else:
        eye.click()
        tab.page.wait_for_timeout(500)
        shown = tab.page.evaluate("""() => [...document.querySelectorAll("#app img")].filter(i => i.naturalWidth > 0
            && i.getBoundingClientRect().width > 0 && !i.closest("nav") && !i.closest(".document")).length""")
        if not shown:
            problems.append(f"{where} page: the eye icon shows no figure")
        problems += check_cut(tab, f"{where} shown")
    try:
        fig = _render(name, run, scene)
    except Exception as exc:  # noqa: BLE001 - said, not hidden
        return problems + [f"{where}: could not be drawn again from its inputs: {exc!r}"], bars
    what = what_was_drawn(name, run.out, fig, _dimension(run.out) == 1)
    problems += check_caption(name, caption, what, max_side, f"{where} caption")
    problems += check_figure_text(name, fig, stored, what, where)
    return problems, bars


def read_report(family: str, run: SceneRun, tmp_path: Path) -> list[str]:
    """Every problem a reader meets in the family's report: its landing page and every figure's page in Chromium,
    against the stored data; the screenshots taken (written to docs/figures with ROUGHCONTACT_UPDATE_SCREENSHOTS=1)."""
    report = build_report(run, tmp_path)
    scene = _scene_block(run)
    stored = stored_numbers(run.out)
    max_side = _max_side(run.out)
    problems = check_stored_flags(run.out)
    with sync_playwright() as playwright:
        tab = open_report(playwright, report)
        tab.shot(tmp_path / "landing.png")
        problems += check_landing(tab, run, stored, scene.get("description"))
        found, bars = check_page_common(tab, "landing page", run.scene, scene.get("description"))
        problems += found
        if family == "paper-like" and bars < 2:  # p-bar in the result's law and the fit's header: the check ran
            problems.append(f"the landing page shows {bars} overbar(s); the paper-like report has at least 2")
        for name in sorted(p.stem for p in (run.out / "figures").glob("*.png")):
            found, bars = check_figure_page(tab, run, name, scene, stored, max_side)
            problems += found
            if family == "paper-like" and name == FIGURE_SHOT[0]:
                tab.shot(tmp_path / "figure.png")
                if bars < 1:
                    problems.append(f"{name}.png page: no overbar (its caption writes p-bar)")
        problems += [f"console: {line}" for line in tab.console]
    shots = {SCREENSHOTS[family]: tmp_path / "landing.png"} if family in SCREENSHOTS else {}
    if family == "paper-like":
        shots[FIGURE_SHOT[1]] = tmp_path / "figure.png"
    for path, shot in shots.items():
        if not (shot.is_file() and shot.read_bytes().startswith(b"\x89PNG") and shot.stat().st_size > 50_000):
            problems.append(f"the screenshot for {path.name} is not a PNG of a page")
        elif os.environ.get("ROUGHCONTACT_UPDATE_SCREENSHOTS") == "1":
            shutil.copyfile(shot, path)
        if not path.is_file():
            problems.append(f"{path} is missing: rerun with ROUGHCONTACT_UPDATE_SCREENSHOTS=1")
    return problems


@pytest.mark.slow
@pytest.mark.parametrize(FAMILY_PARAMETER, OPENED, indirect=True)
def test_every_scene_as_a_reader_sees_it(family_run, tmp_path):
    """The family's report in Chromium: the landing page and every figure's page, every problem listed at once."""
    family, run = family_run
    problems = read_report(family, run, tmp_path)
    assert not problems, f"{family} ({run.scene}): {len(problems)} problem(s) a reader sees:\n" + "\n".join(problems)


# --------------------------------------------------------------------------------- the checks themselves
def _stored(*rows: tuple[str, float, float, float], pairs=(), seeds=None) -> Stored:
    return Stored(intervals=list(rows), pairs=list(pairs), seeds=seeds, study_seeds={seeds} - {None})


def test_the_checks_catch_what_the_issue_saw():
    """Each row of issue 60's table as the page printed it, against the stored data it printed: the checks say so."""
    kappa = 3.67558 / SCALES["kappa"]  # lines: cel.csv's kappa = 3.68, its interval [2.9, 7819]
    lines = check_intervals("κ/√(2π) = 0 [0, 3100] *", _stored(("kappa", kappa, 2.92474 / SCALES["kappa"],
                                                                  7819.49 / SCALES["kappa"])), "fit table")
    assert any("prints as 0" in p for p in lines), lines
    beta = check_intervals("β = 1.87 [0.18, 1.87];", _stored(("beta", 1.87413, 0.181539, 1.87413)), "result")
    assert any("not marked not constrained" in p for p in beta), beta
    assert check_intervals("β = 1.87 [0.18, 1.87] *;", _stored(("beta", 1.87413, 0.181539, 1.87413)), "r") == [
        "r: '1.87 [0.18, 1.87]' is rounded to [2] decimal places, its ends to [2]; the half-width 0.846 asks for [1]"]
    demo = check_intervals("1.061 [1.028, 1.164]", _stored(("kappa", 1.0611, 1.0282, 1.1641)), "fit table")
    assert any("asks for [2]" in p for p in demo), demo
    assert check_intervals("1.06 [1.03, 1.16]", _stored(("kappa", 1.0611, 1.0282, 1.1641)), "fit table") == []
    assert check_intervals("0.5 [0.6, 0.9]", _stored(("mu", 0.5, 0.6, 0.9)), "t")[0].endswith(
        "the interval does not contain its estimate")
    pull = _stored(pairs=[(0.00035108, 0.000110), (0.000835, 0.0000131)])
    adhesion = check_plus_minus("0.0003511 ± 0.00011 and 0.000835 ± 1.3e-05", pull, "pull-off")
    assert len([p for p in adhesion if "rounded to" in p]) == 1 and any("notation" in p for p in adhesion), adhesion
    assert check_plus_minus("0.00035 ± 0.00011 and 0.000835 ± 0.000013", pull, "pull-off") == []
    assert check_seeds("H pooled, 6 seeds, the paper's route", {3}, "result") == [
        "result: says '6 seeds'; each group has 3 seeds (the aggregate's seed axis)"]


def test_the_caption_check_names_what_was_not_drawn():
    lead = ("These cases are profiles. The BGT limit and the paper's contact evolution law and power law are laws of "
            "2-D surfaces; the contact evolution law fitted to this run (dark grey long dashes).")
    what = Drawn({"cel_fit"}, [{"route": "joint", "label": "CEL, joint"}], False, True, True, True)
    problems = check_caption("area_load", lead, what, 256, "area_load")
    assert any("'BGT'" in p for p in problems) and any("'power law'" in p for p in problems)
    assert any("omits the joint least-squares" in p for p in problems), problems
    assert check_caption("contact_map", "On a 1-D profile ... maps of more than 512 points a side are block-averaged",
                         Drawn(set(), [], False, False, False, True), 256, "contact_map") == [
        "contact_map: the caption speaks of profiles (1-D); the figure is of 2-D surfaces",
        "contact_map: the caption speaks of block averaging; no surface of the scene has over 512 points a side "
        "(at most 256)"]


def test_the_precision_rule_is_the_documented_one():
    """precision.py's rule: two significant figures of the uncertainty when its leading digit is 1 or 2, one
    otherwise (and the paper's 1.145 ± 0.002)."""
    assert rule_decimals(0.068) == {2} and rule_decimals(0.255) == {2} and rule_decimals(0.005) == {3}
    assert rule_decimals(0.002) == {3, 4} and rule_decimals(1.3e-5) == {6} and rule_decimals(1550) == {-2}
    assert rule_decimals(0.96) == {0, 1}  # rounds to 1.0
    assert _decimals("3100") == {0, -1, -2} and _decimals("1.3e-05") == {6} and _decimals("0.0350") == {4}
