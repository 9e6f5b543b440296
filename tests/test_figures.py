"""The figure registry: every figure has its caption, and a scene gets exactly the figures it asks for; every
registered figure is one width at one pixel density, with readable ticks, and records what it drew (issue 60)."""
import copy
import json

import pytest

import figure_builders
from caption_check import assert_caption_says_the_record, assert_caption_true, lead_of
from conftest import REPO
from roughcontact.figures.captions import caption
from roughcontact.figures.record import figure_record, record_json
from roughcontact.figures.registry import FIGURES, scene_figures
from roughcontact.figures.style import save_figure
from roughcontact.pipeline.config.schema import load_schema
from roughcontact.pipeline.scenes import validate_config


def test_every_registered_figure_has_a_caption_file():
    for name, spec in FIGURES.items():
        caption = REPO / "workflow" / "report" / spec.caption
        assert caption.is_file() and caption.read_text().strip(), name
        assert spec.study in ("representativity", "contact", "accuracy"), name


def test_scene_figures_follow_the_scene_blocks(shipped_config):
    scenes = validate_config(shipped_config, load_schema())["scenes"]
    assert scene_figures(scenes["demo"]) == ["representativity", "surface_examples", "area_load", "kappa", "dpbar",
                                             "contact_map"]
    assert scene_figures(scenes["representative"]) == ["area_load", "kappa", "dpbar"]
    assert scene_figures(scenes["accuracy"]) == ["accuracy"]
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["demo"]["representativity"]["examples"] = []
    demo = validate_config(cfg, load_schema())["scenes"]["demo"]
    assert "surface_examples" not in scene_figures(demo)


def test_inputs_are_relative_to_the_scene_folder(shipped_config):
    demo = validate_config(shipped_config, load_schema())["scenes"]["demo"]
    spec = FIGURES["surface_examples"]
    assert spec.inputs(demo["representativity"]) == {"surfaces": [
        "surfaces_rep/kl1_ks32_H0.8_s0.nc", "surfaces_rep/kl4_ks32_H0.8_s0.nc", "surfaces_rep/kl16_ks32_H0.8_s0.nc"]}
    assert FIGURES["kappa"].inputs(demo["contact"]) == {"agg": "aggregate/contact.nc", "fit": "fit/cel.nc"}


# ------------------------------------------------------------------ issue 60: every registered figure
@pytest.fixture(scope="module")
def drawn_figures():
    """Every registered figure, drawn twice from made-up data (tests/figure_builders.py), by name."""
    builders = figure_builders.builders()
    assert set(builders) == set(FIGURES), "a registered figure without a builder in tests/figure_builders.py"
    return {name: (build(), build) for name, build in builders.items()}


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_every_registered_figure_is_one_width_at_one_pixel_density(drawn_figures, tmp_path):
    """The pull-off figure was written at half the pixel width of the others, so its text showed twice the size
    (issue 60): every figure is one width class at one pixel density, whatever its data."""
    from PIL import Image

    sizes = {}
    for name, (fig, _) in drawn_figures.items():
        png, _pdf = save_figure(fig, tmp_path / name)
        with Image.open(png) as image:
            sizes[name] = (image.size[0], tuple(round(d) for d in image.info["dpi"]))
    assert set(sizes.values()) == {(2100, (300, 300))}, sizes


def test_every_registered_figure_records_what_it_drew_and_its_caption_says_it(drawn_figures):
    """The record (figures/{figure}.record.json) lists what the figure drew; the caption is built from it and says
    exactly that (tests/caption_check.py); the lead promises nothing a rendering may leave out; the record is
    the same text on a second rendering."""
    for name, (fig, build) in drawn_figures.items():
        record = figure_record(name, fig)
        assert record["figure"] == name and record["series"], name
        text = caption(lead_of(name), record)
        assert_caption_true(fig, text)
        assert_caption_says_the_record(record, text)
        assert record_json(record) == record_json(figure_record(name, build())), name
        assert json.loads(record_json(record)) == record


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_every_log_axis_of_every_registered_figure_shows_two_labelled_ticks(drawn_figures):
    """A log axis over less than a decade has no decade tick to label (issue 60): each shows at least two."""
    for name, (fig, _) in drawn_figures.items():
        fig.draw_without_rendering()
        axes = [ax for ax in fig.axes if ax.get_visible()]
        axes += [child for ax in axes for child in ax.child_axes]
        for ax in axes:
            for axis in (ax.xaxis, ax.yaxis):
                if axis.get_scale() == "log":
                    labels = figure_builders.labelled_ticks(axis)
                    assert len(labels) >= 2, (name, ax.get_title(), axis.axis_name, labels)
