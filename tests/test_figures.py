"""The figure registry: every figure has its caption, and a scene gets exactly the figures it asks for."""
import copy

from conftest import REPO
from roughcontact.figures.registry import FIGURES, scene_figures
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
