"""The report's introduction (roughcontact.studies.report_intro): it names exactly the stages each shipped scene runs
and gives the contact evolution law only where the scene fits it (issue 60: the adhesion page opened with the CEL
formula and "their representativity", though the scene has neither)."""
import copy

import pytest
from docutils.core import publish_parts

from roughcontact.figures.registry import FIGURES
from roughcontact.pipeline.config.schema import load_schema
from roughcontact.pipeline.scenes import validate_config
from roughcontact.pipeline.targets import Targets
from roughcontact.studies.accuracy import variants
from roughcontact.studies.report_intro import CEL_MATH, STAGE_TITLES, intro_facts, intro_rst, scene_stages


@pytest.fixture(scope="module")
def shipped(repo, shipped_config):
    """The shipped scenes, validated, and the targets each asks for (the measured scene's files are relative to the
    workflow's folder)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(repo)
        scenes = validate_config(shipped_config, load_schema())["scenes"]
        targets = Targets.from_config(shipped_config, variants, FIGURES)
        return scenes, {name: targets.scene_targets(name) for name in targets.scenes}


def _expected(scene, targets) -> set[str]:
    """The stages of a scene, read from its blocks and the files it asks for, not from report_intro."""
    out = set()
    if any("/aggregate/representativity.nc" in t for t in targets):
        out |= {"surfaces", "representativity"}
    if any("/aggregate/contact.nc" in t for t in targets):
        out |= {"surfaces", "adhesion" if "adhesion" in scene["contact"].get("effects", {}) else "contact"}
    if any("/fit/cel.nc" in t for t in targets):
        out.add("fit")
    if any("/accuracy/summary.nc" in t for t in targets):
        out.add("accuracy")
    if any("/kappa_gap/" in t for t in targets):
        out.add("kappa_gap")
    return out


def test_every_shipped_scene_names_exactly_the_stages_it_runs(shipped):
    scenes, targets = shipped
    assert {"demo", "paper", "lines", "measured", "array", "adhesion", "accuracy", "kappa-gap", "full-contact",
            "percolation"} <= set(scenes)
    for name, scene in scenes.items():
        facts = intro_facts(scene)
        stages = scene_stages(facts)
        assert set(stages) == _expected(scene, targets[name]), name
        text = intro_rst(name, facts)
        for stage, title in STAGE_TITLES.items():
            assert (f"**{title}**" in text) == (stage in stages), (name, stage)
        fits_the_law = "fit" in stages or "accuracy" in stages  # the accuracy study fits the law at each setting
        assert (CEL_MATH in text) == fits_the_law, name
        assert ("evolution law" in text) == fits_the_law, name
        assert f"Scene **{name}**" in text
        html = publish_parts(text, writer="html", settings_overrides={"report_level": 1, "halt_level": 2})["body"]
        assert "system-message" not in html and html.count("<li>") == len(stages), name


def test_the_adhesion_scene_names_adhesion_and_neither_representativity_nor_the_law(shipped):
    scenes, _ = shipped
    text = intro_rst("adhesion", intro_facts(scenes["adhesion"]))
    assert "**adhesive contact**" in text and "pull-off" in text and "exponential adhesion law" in text
    assert "representativity" not in text and "evolution law" not in text and ".. math::" not in text
    # without unloading it says so, and promises no pull-off
    block = copy.deepcopy(scenes["adhesion"])
    block["contact"]["effects"]["adhesion"]["unloading"] = False
    loaded_only = intro_rst("adhesion", intro_facts(block))
    assert "not unloaded: no pull-off is computed" in loaded_only and "to the pull-off pressure" not in loaded_only


def test_the_intro_says_what_each_scene_is_made_of(shipped):
    """Profiles for the lines scene, files for the patch sources, the stored outputs of a contact study."""
    scenes, _ = shipped
    text = {name: intro_rst(name, intro_facts(scenes[name])) for name in ("lines", "measured", "array", "demo",
                                                                          "full-contact")}
    assert "profiles (1-D surfaces, in plane strain)" in text["lines"]
    assert "3 files of measured topography" in text["measured"] and "2 files of heights" in text["array"]
    assert "fields at load step 30" in text["demo"] and "profiles" not in text["demo"]
    assert "the contact clusters at every step" in text["full-contact"]
    assert "from 0.01 to 0.11" in text["demo"]


def test_the_landing_page_includes_the_intro_and_states_no_law_of_its_own(repo):
    """workflow.rst shows the intro fragment; the law's formula is only in the fragment (where a scene fits it)."""
    page = (repo / "workflow" / "report" / "workflow.rst").read_text()
    assert 'fragment("intro.rst")' in page and ".. math::" not in page and r"\frac{A}{A_0}" not in page
