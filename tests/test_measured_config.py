"""Scenes of measured surfaces: the topography block is checked before any job is planned."""
import copy
import shutil
from pathlib import Path

import pytest

from roughcontact.pipeline.config.files import ConfigError
from roughcontact.pipeline.measured import reader_settings, topography_names
from roughcontact.pipeline.scenes import plan_summary, validate_config

EXAMPLES = Path(__file__).resolve().parents[1] / "data" / "measured"


def _config(tmp_path, topography=None, **scene_blocks):
    # real files: each header is read when the scene is checked
    for name, example in (("a.x3p", "ground-a.x3p"), ("b.nc", "ground-b.nc")):
        shutil.copyfile(EXAMPLES / example, tmp_path / name)
    topo = topography or {"files": {"a": str(tmp_path / "a.x3p"), "b": {"path": str(tmp_path / "b.nc"),
                                                                       "file_unit": "nm",
                                                                       "physical_size": [1.0, 2.0]}},
                          "unit": "um"}
    scene = {"topography": topo, **(scene_blocks or {"contact": {}})}
    return {
        "scene": "m",
        "defaults": {"contact": {"surface": {"N": 64, "rms_slope": 0.1},
                                 "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5"]}, "seeds": 2}},
        "scenes": {"m": scene, "gen": {"contact": {}}},
    }


def test_measured_scene_is_expanded_and_generator_keys_dropped(tmp_path):
    scene = validate_config(_config(tmp_path))["scenes"]["m"]
    assert topography_names(scene) == ["a", "b"]
    assert not {"surface", "grid", "seeds"} & set(scene["contact"])
    assert scene["contact"]["solver"]["boundary"] == "free"
    assert scene["topography"]["undefined"] == "reject" and scene["topography"]["non_square"] == "keep"
    # a file's own unit and size override the scene's; each job's params hold only its file's settings
    got = reader_settings(scene, "b")
    assert got["file_unit"] == "nm" and got["physical_size"] == [1.0, 2.0] and got["path"].endswith("b.nc")
    assert "file_unit" not in reader_settings(scene, "a")
    assert "2 topography file(s) x 30 load steps = 60 solves" in plan_summary("m", scene)


def test_generated_scenes_default_to_the_periodic_half_space(tmp_path):
    scene = validate_config(_config(tmp_path))["scenes"]["gen"]
    assert scene["contact"]["solver"]["boundary"] == "periodic"


def test_boundary_can_be_chosen(tmp_path):
    cfg = _config(tmp_path, contact={"solver": {"boundary": "periodic"}})
    assert validate_config(cfg)["scenes"]["m"]["contact"]["solver"]["boundary"] == "periodic"
    cfg["scenes"]["gen"] = {"contact": {"solver": {"boundary": "sideways"}}}
    with pytest.raises(ConfigError, match=r"scene 'gen', field 'contact.solver.boundary'.*periodic.*free"):
        validate_config(cfg, strict=True)


def test_glob_names_cases_by_file_stem(tmp_path):
    cfg = _config(tmp_path, topography={"glob": str(tmp_path / "*.*"), "unit": "nm"})
    scene = validate_config(cfg)["scenes"]["m"]
    assert topography_names(scene) == ["a", "b"] and "glob" not in scene["topography"]


@pytest.mark.parametrize("edit, words", [
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update(c=str(t / "missing.x3p")),
     r"scene 'm', field 'topography.files.c': '.*missing.x3p' does not exist"),
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update(c=str(t)),
     r"field 'topography.files.c': '.*' is a directory, not a file: name one file in it, or list them with "
     r"topography.glob"),
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update(c="/dev/null"),
     r"field 'topography.files.c': '/dev/null' is not a regular file \(a device, pipe or socket\)"),
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update({"../evil": str(t / "a.x3p")}),
     r"field 'topography.files': '../evil' is not a case name: .*no '/', spaces or leading '.'\)$"),
    (lambda c, t: c["scenes"]["m"].update(topography={"glob": str(t / "*.sur"), "unit": "um"}),
     r"field 'topography.glob': '.*\*.sur' matches no file"),
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update({"kl2_ks8_H0.5_s0": str(t / "a.x3p")}),
     r"looks like a generated case"),
    # a representativity batch's file stem
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update({"kl2_H0.5": str(t / "a.x3p")}),
     r"looks like a generated case"),
    (lambda c, t: c["scenes"]["m"]["topography"]["files"].update({"bad name": str(t / "a.x3p")}),
     r"field 'topography.files'"),
    (lambda c, t: c["scenes"]["m"]["topography"].update(unit="1"),
     r"field 'topography.unit'.*'m', 'mm', 'um', 'nm'"),
    (lambda c, t: c["scenes"]["m"]["topography"].update(undefined="zero"),
     r"field 'topography.undefined'.*reject.*mean.*harmonic"),
    (lambda c, t: c["scenes"]["m"]["topography"].update(physical_size=[1.0, -2.0]),
     r"field 'topography.physical_size.1'"),
    (lambda c, t: c["scenes"]["m"]["contact"].update(grid={"k_l": ["1"], "k_s": ["8"], "H": ["0.5"]}),
     r"field 'contact.grid': not used with a topography block"),
    (lambda c, t: c["scenes"]["m"].update(accuracy={}),
     r"field 'accuracy': the accuracy study runs on generated surfaces only"),
])
def test_bad_topography_blocks_name_the_field(tmp_path, edit, words):
    cfg = _config(tmp_path)
    edit(cfg, tmp_path)
    with pytest.raises(ConfigError, match=words):
        validate_config(cfg)


def test_only_the_running_scene_needs_its_files(tmp_path):
    cfg = _config(tmp_path)
    cfg["scenes"]["m"]["topography"]["files"]["gone"] = str(tmp_path / "gone.x3p")
    with pytest.raises(ConfigError, match="gone.x3p' does not exist"):
        validate_config(cfg)
    other = copy.deepcopy(cfg)
    other["scene"] = "gen"
    assert "gone" in validate_config(other)["scenes"]["m"]["topography"]["files"]


@pytest.mark.parametrize("block, key, words", [
    ("surface", "unit", r"field 'contact.surface.unit': 'inch' is not one of \['1', 'm', 'mm', 'um', 'nm'\]"),
    ("solver", "pressure_unit", r"field 'contact.solver.pressure_unit': 'inch' is not one of \['1', 'Pa'"),
])
def test_unknown_units_name_the_field_and_the_allowed_units(tmp_path, block, key, words):
    cfg = _config(tmp_path)
    cfg["scenes"]["gen"] = {"contact": {block: {key: "inch"}}}
    with pytest.raises(ConfigError, match=words):
        validate_config(cfg, strict=True)


@pytest.mark.parametrize("spoil, words", [
    (lambda p: p.write_bytes(b"\x00" * 37), "not a topography file SurfaceTopography can read"),
    (lambda p: shutil.copyfile(EXAMPLES / "ground-c.txt", p), "the file carries no length unit; give "
                                                             "topography.file_unit"),
])
def test_a_file_header_is_checked_before_any_job(tmp_path, spoil, words):
    # Each file's header (readable, channel, unit, size, grid) is read when the scene is checked, so
    # that a bad file stops the run before planning, naming the scene, the field, the file and the remedy.
    config = _config(tmp_path)
    bad = tmp_path / "c.dat"
    spoil(bad)
    config["scenes"]["m"]["topography"]["files"]["c"] = str(bad)
    with pytest.raises(ConfigError) as err:
        validate_config(config)
    assert f"scene 'm', field 'topography.files.c': {bad}: " in str(err.value) and words in str(err.value)


def test_measured_loads_default_to_each_files_rms_slope(tmp_path):
    load = validate_config(_config(tmp_path))["scenes"]["m"]["contact"]["load"]
    assert load["relative_to"] == "rms_slope" and load["p_max"] == 0.05
    assert "final load p0/(E* h') = 0.05, h' each surface's rms slope" in plan_summary(
        "m", validate_config(_config(tmp_path))["scenes"]["m"])
    # generated scenes keep p0/E*
    gen = validate_config(_config(tmp_path))["scenes"]["gen"]["contact"]["load"]
    assert gen["relative_to"] == "e_star" and gen["p_max"] == 0.005
    cfg = _config(tmp_path, contact={"load": {"relative_to": "e_star", "p_max": 0.002}})
    load = validate_config(cfg)["scenes"]["m"]["contact"]["load"]
    assert load["relative_to"] == "e_star" and load["p_max"] == 0.002


@pytest.mark.parametrize("load, field, words", [
    ({"p_max": 0.01}, "contact.load.p_max", "add load.relative_to: rms_slope"),
    ({"target_area": 0.1, "p_max": 0.01}, "contact.load.p_max", "not used with load.target_area"),
    ({"target_area": 0.1, "schedule": "geometric", "p_min": 0.001}, "contact.load.p_min",
     "not used with load.target_area"),
    ({"relative_to": "e_star", "p_max": 2.0}, "contact.load.p_max", "p0/E\\* .* must be <= 1"),
    ({"target_area": 1.0}, "contact.load.target_area", "maximum"),
])
def test_ambiguous_or_conflicting_loads_are_refused(tmp_path, load, field, words):
    with pytest.raises(ConfigError, match=rf"scene 'm', field '{field}'.*{words}"):
        validate_config(_config(tmp_path, contact={"load": load}))


def test_target_area_drops_the_inherited_p_max(tmp_path):
    load = validate_config(_config(tmp_path, contact={"load": {"target_area": 0.1}}))["scenes"]["m"]["contact"]["load"]
    assert load["target_area"] == 0.1 and "p_max" not in load and "relative_to" not in load
