"""The caption-truth check (issues 52, 60): a figure's caption names exactly the reference lines the figure shows,
each in a style of its own and above the data bands, and says exactly what the figure's record holds: the route of
each fit drawn, the notes of its layout, what profiles mean for its references. Used on the synthetic figures
(test_plots, test_figures, test_contact_map) and on the demo, measured, lines and adhesion scenes' outputs
(test_report, test_workflow, test_lines_scene, test_adhesion_scene), where the record the figure rule wrote
(``{figure}.record.json``) must be the record of the figure drawn again from its inputs."""
import json
from pathlib import Path

import numpy as np
import yaml
from matplotlib.collections import PolyCollection
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from conftest import REPO
from roughcontact.figures.captions import (
    CONDITIONAL_WORDS,
    LEFT_OUT,
    NOTES,
    PROFILE_2D_LAWS,
    REFERENCES,
    ROUTES,
    caption,
    drawn,
    in_view,
    reference_artists,
)
from roughcontact.figures.record import figure_record, record_json
from roughcontact.figures.registry import FIGURES
from roughcontact.figures.style import MAP_PIXELS
from roughcontact.pipeline.config.schema import load_schema
from roughcontact.pipeline.scenes import validate_config

REPORT_DIR = REPO / "workflow" / "report"


def lead_of(name: str) -> str:
    """The caption file of a registered figure (its lead); it may not promise what a rendering can leave out."""
    lead = (REPORT_DIR / FIGURES[name].caption).read_text()
    promised = [w for w in CONDITIONAL_WORDS if w in lead]
    assert not promised, f"{FIGURES[name].caption} names {promised}, which a rendering may not draw"
    return lead


def assert_caption_true(fig: Figure, text: str) -> list[str]:
    """``text`` names a reference line iff ``fig`` shows it; shown lines are in view, above the bands and
    styled apart. Returns the gids shown."""
    shown = drawn(fig)
    for gid, phrase in REFERENCES.items():
        assert (phrase in text) == (gid in shown), (gid, shown)
    for ax in fig.axes:
        lines = [a for a in reference_artists(fig) if a.axes is ax and hasattr(a, "get_linestyle")
                 and hasattr(a, "get_xydata") and in_view(a)]
        bands = [c.get_zorder() for c in ax.collections if isinstance(c, PolyCollection) and c.get_gid() is None]
        for line in lines:
            assert not bands or line.get_zorder() > max(bands), (line.get_gid(), line.get_zorder(), bands)
        for i, a in enumerate(lines):  # no two kinds of reference line look alike
            for b in lines[i + 1:]:
                if a.get_gid() != b.get_gid():
                    assert not _alike(a, b), f"reference lines drawn alike: {a.get_gid()}, {b.get_gid()}"
    return shown


#: The keys every record holds (the reader's test reads them).
RECORD_KEYS = {"figure", "title", "references", "fits", "window", "series", "profiles", "notes", "left_out"}


def assert_caption_says_the_record(record: dict, text: str) -> None:
    """``text`` says exactly what ``record`` holds: each reference phrase iff its gid is recorded, each fit's
    route iff a fit of that route is recorded, each note and left-out item iff recorded, the profiles' note
    (the 2-D laws drawn, named) only for profiles, and the window only with a fit."""
    assert RECORD_KEYS <= set(record), sorted(RECORD_KEYS - set(record))
    for gid, phrase in REFERENCES.items():
        assert (phrase in text) == (gid in record["references"]), (gid, record["references"])
    routes = {f["route"] for f in record["fits"]}
    for route, phrase in ROUTES.items():
        assert (phrase in text) == (route in routes), (route, record["fits"])
    for key, phrase in NOTES.items():
        assert (phrase.replace("{pixels}", str(MAP_PIXELS)) in text) == (key in record["notes"]), (key, record["notes"])
    for key, phrase in LEFT_OUT.items():
        assert (phrase in text) == (key in record["left_out"]), (key, record["left_out"])
    for gid, name in PROFILE_2D_LAWS.items():  # "the BGT limit ... drawn for comparison only" of a law drawn
        said = f"{name[0].upper()}{name[1:]} " in text or f" {name} " in text.split("Drawn with the data")[0]
        assert said == (record["profiles"] and gid in record["references"]), (gid, record["references"])
    assert (record["window"] is not None) == bool(record["fits"]), record
    if record["window"]:
        assert f"from {record['window'][0]:g} to {record['window'][1]:g}" in text


def _alike(a, b) -> bool:
    """Whether two lines look alike: near colours (each RGB channel within 0.25), the same dash pattern (a custom
    one reads "--" from get_linestyle: compare the pattern drawn) and widths within 0.5 pt."""
    colours = np.abs(np.array(to_rgb(a.get_color())) - np.array(to_rgb(b.get_color()))).max() < 0.25
    dashes = (a.get_linestyle(), str(getattr(a, "_dash_pattern", ""))) == (b.get_linestyle(),
                                                                          str(getattr(b, "_dash_pattern", "")))
    return bool(colours and dashes and abs(a.get_linewidth() - b.get_linewidth()) < 0.5)


def assert_scene_captions_true(workdir: Path, scene: str, config_file: Path | None = None) -> dict[str, list[str]]:
    """Every figure of ``results/{scene}`` under ``workdir``, drawn again from its inputs: its record file (the
    figure rule's) is the record of what it draws, its caption file the caption of that record, true of the
    figure and of the record. Returns the gids shown per figure."""
    with open(config_file or workdir / "config" / "config.yaml") as fh:
        config = yaml.safe_load(fh)
    validated = validate_config(config, load_schema())["scenes"][scene]
    out = workdir / "results" / scene
    shown = {}
    pngs = sorted((out / "figures").glob("*.png"))
    assert pngs, f"no figure in {out}"
    for png in pngs:
        name = png.stem
        paths = {role: [str(out / p) for p in v] if isinstance(v, list) else str(out / v)
                 for role, v in FIGURES[name].input_paths(validated).items()}
        fig = FIGURES[name].render(paths)
        record = figure_record(name, fig)
        written_record = png.with_suffix(".record.json").read_text()
        assert written_record == record_json(record), name
        assert json.loads(written_record) == record, name
        written = png.with_suffix(".caption.rst").read_text()
        assert written == caption(lead_of(name), record), name
        shown[name] = assert_caption_true(fig, written)
        assert_caption_says_the_record(record, written)
    return shown
