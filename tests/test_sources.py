"""Surface sources (roughcontact.pipeline.sources): the registry, a scene's source, the array source."""
import copy

import numpy as np
import pytest

from roughcontact.pipeline.config import ConfigError
from roughcontact.pipeline.progress import planned_solves
from roughcontact.pipeline.scenes import plan_summary, validate_config
from roughcontact.pipeline.sources import SOURCES, PatchSource, Source, for_case, for_dims, register, source_of
from roughcontact.surfaces.synthetic import generate_surface

GENERATED_CONTACT = {"surface": {"N": 32, "rms_slope": 0.1}, "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5"]},
                     "seeds": 2}


def _heights(n=32, seed=0):
    return np.asarray(generate_surface(n, 2.0, 8.0, 0.7, seed, length=float(n), rms_slope=0.1))


@pytest.fixture
def arrays(tmp_path, monkeypatch):
    """Two good .npy files in the working directory (a square one and a rectangular one)."""
    monkeypatch.chdir(tmp_path)
    np.save("a.npy", _heights())
    np.save("b.npy", _heights(seed=1)[:, :24])
    return tmp_path


def _config(block, **studies):
    scene = {"array": block, "contact": {"load": {"n_steps": 4}}, **studies}
    return {"scene": "s", "scenes": {"s": scene}}


GOOD = {"files": {"a": {"path": "a.npy", "pixel_size": 0.5}, "b": {"path": "b.npy", "pixel_size": [0.5, 0.25]}},
        "unit": "um"}


# ------------------------------------------------------------------------------ the registry
def test_the_registry_holds_the_three_sources_generator_first():
    assert list(SOURCES)[:2] == ["generated", "measured"] and "array" in SOURCES
    for cls in SOURCES.values():
        assert issubclass(cls, Source) and cls.name and cls.case_keys and cls.case_dims and cls.stem
        assert cls.fit in ("grid", "topographies") and cls.figures in ("grid", "patches")
    assert SOURCES["generated"].key is None
    assert {SOURCES["measured"].key, SOURCES["array"].key} == {"topography", "array"}
    assert issubclass(SOURCES["array"], PatchSource) and issubclass(SOURCES["measured"], PatchSource)


def test_a_name_is_registered_once():
    with pytest.raises(ValueError, match="already registered"):
        register(type("Again", (Source,), {"name": "array"}))


def test_source_of_a_scene_is_the_one_that_applies():
    assert source_of({"contact": GENERATED_CONTACT}).name == "generated"
    assert source_of({"topography": {}, "contact": {}}).name == "measured"
    assert source_of({"array": {}, "contact": {}}).name == "array"


def test_two_source_blocks_in_one_scene_are_refused_naming_both():
    with pytest.raises(ConfigError, match=r"scene 'x': takes its surfaces from 2 sources at once "
                                          r"\(measured, array; blocks topography, array\)"):
        source_of({"topography": {}, "array": {}}, "x")
    cfg = _config(GOOD)
    cfg["scenes"]["s"]["topography"] = {"files": {"a": "a.npy"}, "unit": "um"}
    with pytest.raises(ConfigError, match="scene 's': takes its surfaces from 2 sources"):
        validate_config(cfg)


def test_lookups_by_dimensions_and_wildcards():
    assert for_dims(("k_l", "k_s", "H", "seed", "step")).name == "generated"
    assert for_dims(("topography", "step")).fit == "topographies"
    assert for_case(["k_l", "k_s", "H", "seed"]).record_key == "surface"
    assert for_case(["topography"]).record_key == "topography"
    with pytest.raises(ValueError, match="no surface source"):
        for_dims(("step",))


# ------------------------------------------------------------------------------ the array source
def test_an_array_scene_is_validated_and_expanded(arrays):
    scene = validate_config(_config(GOOD, representativity={}))["scenes"]["s"]
    src = source_of(scene)
    assert src.name == "array" and src.names(scene) == ["a", "b"]
    assert scene["array"]["files"]["a"]["pixel_size"] == [0.5, 0.5]
    assert scene["contact"]["solver"]["boundary"] == "free"
    assert scene["contact"]["load"]["relative_to"] == "rms_slope"
    assert "grid" not in scene["contact"] and "surface" not in scene["representativity"]
    assert src.reader_settings(scene, "b") == {"path": "b.npy", "pixel_size": [0.5, 0.25], "source": "array",
                                               "unit": "um"}
    assert planned_solves(scene) == 2 * 4
    assert "contact of 2 array file(s) x 4 load steps = 8 solves" in plan_summary("s", scene)
    surface = src.read(src.reader_settings(scene, "b"))
    assert surface.heights.shape == (32, 24) and surface.lengths == (16.0, 6.0) and surface.unit == "um"
    assert surface.info["sha256"] and surface.info["reader"] == "numpy.load"


def test_an_array_scene_may_ask_for_the_periodic_boundary(arrays):
    cfg = _config(GOOD)
    cfg["scenes"]["s"]["contact"]["solver"] = {"boundary": "periodic"}
    assert validate_config(cfg)["scenes"]["s"]["contact"]["solver"]["boundary"] == "periodic"


def _bad(tmp_path, name, value):
    path = tmp_path / name
    if isinstance(value, np.ndarray):
        np.save(path, value)
    elif value is not None:
        path.write_bytes(value)
    return name


BAD_FILES = [
    ("missing.npy", None, 0.5, "does not exist", "name an existing .npy file"),
    ("heights.txt", b"1 2\n3 4\n", 0.5, "is not a .npy file", "numpy.save"),
    ("broken.npy", b"not numpy at all", 0.5, "does not start as a .npy file does", "numpy.save"),
    ("truncated.npy", b"\x93NUMPY\x01\x00", 0.5, "NumPy can read", "numpy.save"),
    ("line.npy", np.zeros(16), 0.5, "shape (16,)", "2-D height map"),
    ("cube.npy", np.zeros((4, 4, 4)), 0.5, "shape (4, 4, 4)", "2-D height map"),
    ("nan.npy", np.where(np.eye(8) > 0, np.nan, 0.0), 0.5, "8 of 64 heights are NaN or infinite", "fill or crop"),
    ("inf.npy", np.full((8, 8), np.inf), 0.5, "64 of 64 heights are NaN or infinite", "fill or crop"),
    ("flat.npy", np.ones((8, 8)), 0.5, "every height is 1.0: a flat map has no roughness", "save the surface"),
    ("complex.npy", np.zeros((8, 8), complex), 0.5, "complex128 values", "astype(float)"),
    ("zero-pixel.npy", np.zeros((8, 8)), [0.5, 0.0], "pixel_size [0.5, 0.0] must be positive", "[dx, dy]"),
    ("negative-pixel.npy", np.zeros((8, 8)), -1.0, "pixel_size -1.0 must be positive", "[dx, dy]"),
]


@pytest.mark.parametrize(("name", "content", "pixel", "what", "remedy"), BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_a_bad_array_file_is_refused_naming_the_file_and_the_remedy(arrays, name, content, pixel, what, remedy):
    _bad(arrays, name, content)
    block = copy.deepcopy(GOOD)
    block["files"]["bad"] = {"path": name, "pixel_size": pixel}
    with pytest.raises(ConfigError) as err:
        validate_config(_config(block))
    msg = str(err.value)
    assert msg.startswith("scene 's', field 'array.files.bad': ") and what in msg
    assert repr(name) in msg and remedy in msg


def test_a_non_positive_pixel_size_is_refused_by_the_file_check_too(arrays):
    from roughcontact.pipeline.sources.array import ArrayError, load_heights

    with pytest.raises(ArrayError, match=r"'a.npy': pixel_size \[0.5, -1.0\] must be positive.*\[dx, dy\]"):
        load_heights("a.npy", [0.5, -1.0])


def test_a_file_without_pixel_size_is_refused(arrays):
    block = {"files": {"a": "a.npy"}, "unit": "um"}
    with pytest.raises(ConfigError, match=r"field 'array.files.a.pixel_size': 'a.npy' has no pixel size: give "):
        validate_config(_config(block))
    block["pixel_size"] = 2.0
    scene = validate_config(_config(block))["scenes"]["s"]
    assert scene["array"]["files"]["a"] == {"path": "a.npy", "pixel_size": [2.0, 2.0]}


def test_generator_keys_and_generated_studies_are_refused_in_an_array_scene(arrays):
    cfg = _config(GOOD)
    cfg["scenes"]["s"]["contact"]["seeds"] = 3
    with pytest.raises(ConfigError, match=r"field 'contact.seeds': not used with an array block"):
        validate_config(cfg)
    cfg = _config(GOOD, accuracy={})
    with pytest.raises(ConfigError, match=r"field 'accuracy': the accuracy study runs on generated surfaces only; "
                                          r"remove it from a scene with an array block"):
        validate_config(cfg)


def test_a_case_name_like_a_generated_file_is_refused(arrays):
    block = {"files": {"kl2_ks8_H0.5_s0": {"path": "a.npy", "pixel_size": 1.0}}, "unit": "um"}
    with pytest.raises(ConfigError, match="looks like a generated case"):
        validate_config(_config(block))


def test_files_of_a_scene_that_does_not_run_are_not_read(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = _config({"files": {"a": {"path": "absent.npy", "pixel_size": 1.0}}, "unit": "um"})
    cfg["scenes"]["other"] = {"contact": GENERATED_CONTACT}
    cfg["scene"] = "other"
    assert validate_config(cfg)["scenes"]["s"]["array"]["files"]["a"]["path"] == "absent.npy"


# ------------------------------------------------------------------------------ end to end
@pytest.mark.slow
def test_an_array_scene_runs_through_contact_aggregate_fit_and_figures(array_run):
    """The shipped `array` scene's two files (one rectangular) through every stage, 8 load steps (the session's run,
    shared with test_reader; ~40 s)."""
    from roughcontact.pipeline.io import read_dataset

    wd, root = array_run.wd, array_run.out
    agg = read_dataset(root / "aggregate" / "contact.nc", stage="aggregate")
    assert list(agg["topography"].values) == ["patch-a", "patch-b"] and agg.attrs["boundary"] == "free"
    assert bool(agg["converged"].all()) and np.all(np.isfinite(agg["kappa"].values))
    b = read_dataset(root / "surfaces" / "patch-b.nc", stage="surface")
    assert (b.sizes["x"], b.sizes["y"]) == (96, 80) and (b.attrs["length_x"], b.attrs["length_y"]) == (48.0, 48.0)
    assert np.array_equal(b["heights"].values.squeeze(), np.load(wd / "data/array/patch-b.npy"))
    assert read_dataset(root / "aggregate" / "representativity.nc", stage="aggregate").sizes["topography"] == 2
    assert "pooled (2 topographies)" in (root / "fit" / "cel.csv").read_text()
    for name in ("topographies", "measured_area_load", "measured_kappa"):
        assert (root / "figures" / f"{name}.png").is_file()
    assert "Topographies" in (root / "report" / "summary.rst").read_text()
