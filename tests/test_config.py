"""Scene validation: shipped scenes pass; each kind of bad config is named precisely."""
import copy

import pytest

from roughcontact.pipeline.case import load_schedule
from roughcontact.pipeline.config.files import ConfigError
from roughcontact.pipeline.config.schema import load_schema
from roughcontact.pipeline.scenes import cases, validate_config


def load_steps(block):
    """A contact block's loads (relative to E*)."""
    return load_schedule(block).pressures(block["solver"]["e_star"])

SCHEMA = load_schema()


def test_shipped_config_is_valid(shipped_config):
    cfg = validate_config(shipped_config, SCHEMA)
    assert cfg["scene"] == "demo"
    assert {"demo", "paper", "representative"} <= set(cfg["scenes"])


def test_paper_scene_grids_are_the_papers(shipped_config):
    paper = validate_config(shipped_config, SCHEMA)["scenes"]["paper"]
    rep, con = paper["representativity"], paper["contact"]
    assert rep["surface"] == {"N": 1024, "L": 1.0, "rms_height": 0.1, "plateau": False, "unit": "1"}
    assert rep["seeds"] == 30 and rep["grid"]["H"] == ["0.8"] and rep["n_bins"] == 500
    assert rep["grid"]["k_l"] == ["1", "2", "4", "8", "16"]
    assert rep["grid"]["k_s"] == ["32", "40", "64", "128", "256", "512"]
    assert con["surface"]["rms_slope"] == 0.1 and con["seeds"] == 12
    assert con["grid"]["k_l"] == ["1", "2", "8", "16"]
    assert con["grid"]["k_s"] == ["32", "64", "128", "256", "512"]
    assert con["grid"]["H"] == ["0.2", "0.36", "0.52", "0.68", "0.84"]
    assert len(cases(con)) == 4 * 5 * 5 * 12
    steps = load_steps(con)
    assert len(steps) == 30 and steps[-1] == pytest.approx(0.005) and steps[0] == pytest.approx(0.005 / 30)


def _demo(shipped_config):
    return copy.deepcopy(shipped_config)


def _edit(cfg, path, value):
    node = cfg["scenes"]["demo"]
    *head, last = path
    for key in head:
        node = node.setdefault(key, {})
    if value is KeyError:
        del node[last]
    else:
        node[last] = value
    return cfg


@pytest.mark.parametrize(
    "path, value, field, words",
    [
        (("contact", "grid", "k_l"), ["32"], "contact.grid.k_l", "must be < k_s"),
        (("contact", "grid", "k_s"), ["200"], "contact.grid.k_s", "N/2"),
        (("contact", "grid", "H"), ["1.2"], "contact.grid.H", "0 < H < 1"),
        (("contact", "grid", "H"), ["0"], "contact.grid.H", "> 0"),
        (("contact", "seeds"), 0, "contact.seeds", "minimum"),
        (("contact", "surface", "rms_slope"), -0.1, "contact.surface.rms_slope", "0"),
        (("contact", "solver", "tol"), 2.0, "contact.solver.tol", "1"),
        (("contact", "load", "n_steps"), 0, "contact.load.n_steps", "minimum"),
        (("contact", "bogus"), 1, "contact", "bogus"),
        (("contact", "effects"), {"magic": {}}, "contact.effects", "magic"),
        (("contact", "grid", "k_l"), [4], "contact.grid.k_l.0", "string"),
        (("contact", "outputs"), {"fields": [31]}, "contact.outputs.fields", "1..30"),
        (("representativity", "examples"), [{"k_l": "2", "k_s": "32"}], "representativity.examples[0]",
         "not in the grid"),
        (("fit", "window"), [0.2, 0.1], "fit.window", "low < high"),
        (("contact", "surface", "rms_height"), 0.1, "contact.surface", "exactly one"),
        (("contact", "solver", "array_backend"), "jax", "contact.solver.array_backend", "cupy"),
        (("contact", "effects"), {"plasticity": {"hardness": 0.5}}, "contact.solver.array_backend",
         "runs the elastic solver only, not the effects (plasticity)"),
    ],
)
def test_invalid_field_is_named(shipped_config, path, value, field, words):
    cfg = _edit(_demo(shipped_config), path, value)
    if "array_backend" in field and path[-1] != "array_backend":  # effects on the GPU backend
        cfg = _edit(cfg, ("contact", "solver", "array_backend"), "cupy")
    with pytest.raises(ConfigError) as info:
        validate_config(cfg, SCHEMA)
    msg = str(info.value)
    assert "scene 'demo'" in msg and field in msg and words in msg, msg


def test_a_bad_value_from_defaults_says_so_and_names_a_remedy_that_works(shipped_config):
    """A copy of `lines` without `examples` gets the defaults' 2-D examples (issue 62: the message said neither
    where the value came from nor that `examples: []` draws none)."""
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["mine"] = copy.deepcopy(cfg["scenes"]["lines"])
    del cfg["scenes"]["mine"]["representativity"]["examples"]
    cfg["scene"] = "mine"
    with pytest.raises(ConfigError, match=r"scene 'mine', field 'representativity.examples\[0\]' \(value from the "
                                          r"'defaults' block\): \(1, 40\) is not in the grid's k_l x k_s \(4, 16 x 64, "
                                          r"128\); pick pairs of the grid, or write examples: \[\] in the scene's "
                                          r"representativity block to draw none"):
        validate_config(cfg, SCHEMA)
    cfg["scenes"]["mine"]["representativity"]["examples"] = []  # the remedy works
    validate_config(cfg, SCHEMA)


def test_a_generated_profile_too_short_is_refused_before_any_job(shipped_config):
    """N = 8 points was accepted and its fit failed at the end (issue 62); measured scans under 16 are refused."""
    cfg = copy.deepcopy(shipped_config)
    cfg["scenes"]["lines"]["contact"]["surface"]["N"] = 8
    cfg["scenes"]["lines"]["contact"]["grid"] = {"k_l": ["1"], "k_s": ["4"], "H": ["0.5"]}
    cfg["scene"] = "lines"
    with pytest.raises(ConfigError, match=r"scene 'lines', field 'contact.surface.N': a profile of 8 points is too "
                                          r"short .* set surface.N >= 16"):
        validate_config(cfg, SCHEMA)


def test_an_enum_of_numbers_given_as_text_is_read_as_a_number(shipped_config):
    """`--config` passes nested values as text: `dimension: 2` arrived as '2' and failed with "'2' is not one of
    [1, 2]" (issue 62)."""
    cfg = _edit(_demo(shipped_config), ("contact", "surface", "dimension"), "2")
    assert validate_config(cfg, SCHEMA)["scenes"]["demo"]["contact"]["surface"]["dimension"] == 2
    cfg = _edit(_demo(shipped_config), ("contact", "surface", "dimension"), "3")
    with pytest.raises(ConfigError, match=r"field 'contact.surface.dimension': 3 is not one of \[1, 2\]"):
        validate_config(cfg, SCHEMA)


ADHESION = {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3}}


@pytest.mark.parametrize("outputs, edits, field, words", [
    ({"pressure_distribution": {"bins": 10, "max": 5}}, {("contact", "effects"): ADHESION},
     "contact.outputs.pressure_distribution", "compressive pressures only"),
    ({"full_contact_load": True}, {("contact", "solver", "boundary"): "free"}, "contact.outputs.full_contact_load",
     "periodic cell"),
    ({"full_contact_load": True}, {("contact", "effects"): {"plasticity": {"hardness": 0.5}}},
     "contact.outputs.full_contact_load", "not with effects (plasticity)"),
    ({"pressure_distribution": {"bins": 2.5, "max": 5}}, {}, "contact.outputs.pressure_distribution.bins", "integer"),
    ({"pressure_distribution": {"bins": 10}}, {}, "contact.outputs.pressure_distribution", "max"),
    ({"stiffness": 3}, {}, "contact.outputs.stiffness", "boolean"),
])
def test_observables_refused_where_they_do_not_hold(shipped_config, outputs, edits, field, words):
    cfg = _edit(_demo(shipped_config), ("contact", "outputs"), outputs)
    for path, value in edits.items():
        cfg = _edit(cfg, path, value)
    with pytest.raises(ConfigError) as info:
        validate_config(cfg, SCHEMA)
    msg = str(info.value)
    assert "scene 'demo'" in msg and field in msg and words in msg, msg


def test_unknown_scene_is_named(shipped_config):
    cfg = _demo(shipped_config)
    cfg["scene"] = "nope"
    with pytest.raises(ConfigError, match="unknown scene 'nope'; defined scenes: .*demo"):
        validate_config(cfg, SCHEMA)


def test_scene_without_studies(shipped_config):
    cfg = _demo(shipped_config)
    cfg["scenes"]["demo"] = {"description": "nothing"}
    with pytest.raises(ConfigError, match="at least one of 'representativity', 'contact', 'accuracy' or 'kappa_gap'"):
        validate_config(cfg, SCHEMA)


def test_unknown_top_level_key(shipped_config):
    cfg = _demo(shipped_config)
    cfg["colour"] = "blue"
    with pytest.raises(ConfigError, match="colour"):
        validate_config(cfg, SCHEMA)


def test_defaults_filled(shipped_config):
    cfg = _demo(shipped_config)
    del cfg["defaults"]["contact"]["solver"]
    scenes = validate_config(cfg, SCHEMA)["scenes"]
    demo = scenes["demo"]
    assert demo["contact"]["solver"] == {"e_star": 1.0, "tol": 1e-8, "max_iter": 10000, "pressure_unit": "1",
                                         "boundary": "periodic"}
    # the demo stores its last step's fields (its contact map); a scene that names no outputs, none
    assert demo["contact"]["outputs"] == {"fields": [30], "clusters": False}
    assert scenes["representative"]["contact"]["outputs"] == {"fields": [], "clusters": False}


def test_scene_is_a_delta_over_defaults(shipped_config):
    scenes = validate_config(shipped_config, SCHEMA)["scenes"]
    demo, paper = scenes["demo"], scenes["paper"]
    # what the demo writes replaces, what it omits comes from defaults (mappings merge by key)
    assert demo["contact"]["surface"] == {"N": 256, "L": 1.0, "rms_slope": 0.1, "plateau": False, "unit": "1"}
    assert demo["contact"]["grid"]["k_l"] == ["4", "16"] and demo["contact"]["load"] == paper["contact"]["load"]
    assert demo["representativity"]["grid"]["H"] == ["0.8"]
    # a study the scene does not name is not computed, whatever defaults holds
    assert "accuracy" not in demo and "representativity" not in scenes["representative"]
    # an empty block declares the study with the defaults alone
    assert scenes["accuracy"]["accuracy"]["reference"] == {"N": "2048", "tol": "1e-10", "n_steps": "30"}


def test_null_removes_a_default(shipped_config):
    cfg = _demo(shipped_config)
    cfg["scenes"]["demo"]["contact"]["surface"].update(rms_slope=None, rms_height=0.05)
    surface = validate_config(cfg, SCHEMA)["scenes"]["demo"]["contact"]["surface"]
    assert surface["rms_height"] == 0.05 and "rms_slope" not in surface


def test_bad_default_is_named_as_such(shipped_config):
    cfg = _demo(shipped_config)
    cfg["defaults"]["contact"]["solver"]["tol"] = 5.0
    with pytest.raises(ConfigError, match=r"scene 'demo', field 'contact.solver.tol' \(value from the 'defaults' "
                       r"block\)"):
        validate_config(cfg, SCHEMA)
    cfg = _demo(shipped_config)
    cfg["defaults"]["colour"] = {}
    with pytest.raises(ConfigError, match="config field 'defaults': unknown block 'colour'"):
        validate_config(cfg, SCHEMA)


def test_same_meaning_same_canonical_scene(shipped_config):
    """Whole floats for integers, ints for floats, key order, explicit defaults: one canonical scene."""
    plain = validate_config(shipped_config, SCHEMA)["scenes"]["demo"]
    cfg = _demo(shipped_config)
    con = cfg["scenes"]["demo"]["contact"]
    con["surface"] = {"L": 1, "N": 256.0}
    con["seeds"] = 3.0
    con["solver"] = {"max_iter": 10000.0, "tol": 1e-8, "e_star": 1}
    con["load"] = {"n_steps": 30, "p_max": 0.005}
    other = validate_config(cfg, SCHEMA)["scenes"]["demo"]
    assert other == plain
    assert type(other["contact"]["surface"]["N"]) is int and type(other["contact"]["surface"]["L"]) is float
    assert type(other["contact"]["seeds"]) is int and type(other["contact"]["solver"]["max_iter"]) is int


@pytest.mark.parametrize("name", ["../../escape", "a b", "x/y", "", "9lives"])
def test_unsafe_scene_names_are_refused(shipped_config, name):
    cfg = _demo(shipped_config)
    cfg["scenes"][name] = cfg["scenes"]["demo"]
    with pytest.raises(ConfigError, match="scene name .* is not allowed"):
        validate_config(cfg, SCHEMA)


def test_scene_that_is_not_a_string(shipped_config):
    cfg = _demo(shipped_config)
    cfg["scene"] = ["demo"]
    with pytest.raises(ConfigError, match="config field 'scene': unknown scene"):
        validate_config(cfg, SCHEMA)


@pytest.mark.parametrize(
    "path, value, field, words",
    [
        (("contact", "load", "p_max"), float("nan"), "contact.load.p_max", "not a finite number"),
        (("contact", "surface", "rms_slope"), float("inf"), "contact.surface.rms_slope", "not a finite number"),
        (("fit", "window"), [0.01, float("nan")], "fit.window.1", "not a finite number"),
        (("contact", "load", "p_max"), 1e308, "contact.load.p_max", "maximum"),
        (("contact", "surface", "L"), 1e300, "contact.surface.L", "maximum"),
        (("contact", "solver", "e_star"), 1e300, "contact.solver.e_star", "maximum"),
        (("contact", "seeds"), 1, "contact.seeds", "at least 2"),
        (("contact", "load", "n_steps"), 2, "contact.load.n_steps", "minimum of 3"),
        (("contact", "effects"), {"plasticity": {"hardness": 0.005}}, "contact.effects.plasticity.hardness",
         "must exceed load.p_max"),
        (("contact", "effects"), {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3},
                                  "plasticity": {"hardness": 0.5}}, "contact.effects.adhesion",
         "cannot be combined with effects.plasticity"),
        (("contact", "effects"), {"adhesion": {"law": "dugdale", "work": 1e-5, "range": 1e-3}},
         "contact.effects.adhesion.law", "is not one of"),
        (("contact", "effects"), {"adhesion": {"law": "exponential", "work": 0, "range": 1e-3}},
         "contact.effects.adhesion.work", "less than or equal to the minimum"),
        (("contact", "effects"), {"adhesion": {"law": "exponential", "work": 1e-5}},
         "contact.effects.adhesion", "'range' is a required property"),
        (("contact", "effects"), {"adhesion": {"law": "maugis-dugdale", "work": 1e-5, "range": 1e-3}},
         "contact.effects.adhesion.law", "does not converge with the grid"),
        # the process zone E* rho^2 / w = 1e-5 L spans 0.0026 cells of L / 256: refused, with the N it needs
        (("contact", "effects"), {"adhesion": {"law": "exponential", "work": 1e-3, "range": 1e-4}},
         "contact.effects.adhesion", "spans 0.00256 grid cells of L / N = 1 / 256, fewer than 1.5"),
        # ... and no allowed grid resolves it (N = 150000 > 16384): the remedy is a wider zone, which works (issue 62)
        (("contact", "effects"), {"adhesion": {"law": "exponential", "work": 1e-3, "range": 1e-4}},
         "contact.effects.adhesion", "it needs surface.N >= 150000, beyond the largest grid a scene allows (N = "
                                     "16384); widen the process zone E* rho^2 / w to >= 9.16e-05 instead: range >= "
                                     "0.000303, or work <= 0.000109, or a smaller cell L"),
        (("contact", "effects"), {"adhesion": {"law": "exponential", "work": 1e-5, "range": 1e-3,
                                               "pull_off_rtol": 0}},
         "contact.effects.adhesion.pull_off_rtol", "less than or equal to the minimum"),
        (("representativity", "examples"), [{"k_l": "1", "k_s": "32"}] * 7, "representativity.examples",
         "too long"),
        (("fit", "window"), [0.0, 0.1], "fit.window.0", "less than or equal to the minimum of 0"),
        (("fit", "window"), [0.01, 1.5], "fit.window.1", "maximum"),
        (("contact", "grid", "k_l"), ["4", "4.0"], "contact.grid.k_l", "'4' and '4.0' are the same number"),
        (("contact", "grid", "H"), ["0.36", "0.360"], "contact.grid.H", "same number"),
        (("contact", "grid", "H"), ["0.36\n"], "contact.grid.H.0", "no spaces or line breaks"),
        (("contact", "grid", "H"), [" 0.36"], "contact.grid.H.0", "no spaces or line breaks"),
    ],
)
def test_hostile_values_are_named_before_planning(shipped_config, path, value, field, words):
    cfg = _edit(_demo(shipped_config), path, value)
    with pytest.raises(ConfigError) as info:
        validate_config(cfg, SCHEMA)
    msg = str(info.value)
    assert "scene 'demo'" in msg and f"field '{field}'" in msg and words in msg, msg


@pytest.mark.parametrize("adhesion", [{"range": 3.03e-4}, {"work": 1.09e-4}])
def test_the_remedy_for_a_zone_no_grid_resolves_works(shipped_config, adhesion):
    """The message above names a range or a work at which N = 16384 resolves the zone: each is accepted there."""
    cfg = _edit(_demo(shipped_config), ("contact", "effects"),
                {"adhesion": {"law": "exponential", "work": 1e-3, "range": 1e-4, **adhesion}})
    cfg = _edit(cfg, ("contact", "surface", "N"), 16384)
    cfg = _edit(cfg, ("contact", "grid"), {"k_l": ["4"], "k_s": ["32"], "H": ["0.5"]})
    cfg = _edit(cfg, ("contact", "outputs"), {})
    validate_config(cfg, SCHEMA)


@pytest.mark.parametrize(
    "edit, field, words",
    [
        (lambda a: a["axes"].update(tol=["1.2.3"]), "accuracy.axes.tol.0", "tolerance written as a string"),
        (lambda a: a["axes"].update(N=["0"]), "accuracy.axes.N.0", "whole number written as a string"),
        (lambda a: a["axes"].update(N=["512 "]), "accuracy.axes.N.0", "no spaces"),
        (lambda a: a.update(seed_axis=["1", "x"]), "accuracy.seed_axis.1", "whole number"),
        (lambda a: a.update(H=["0.36", "0.360"]), "accuracy.H", "same number"),
    ],
)
def test_malformed_accuracy_settings_are_named(shipped_config, edit, field, words):
    _assert_study_error_named(shipped_config, "accuracy", "accuracy", edit, field, words)


def _assert_study_error_named(shipped_config, study, scene, edit, field, words):
    """``edit`` the defaults' ``study`` block: a run of ``scene`` stops with an error naming ``scene``, ``field``
    and ``words``; a run of another scene plans, and keeps the error for a target in ``scene``."""
    cfg = copy.deepcopy(shipped_config)
    edit(cfg["defaults"][study])
    assert validate_config(cfg, SCHEMA)["invalid"][scene] == (msg := _error(cfg, scene))
    assert f"scene '{scene}'" in msg and f"field '{field}'" in msg and words in msg, msg


def _error(cfg, scene):
    """The error that stops a run of ``scene``."""
    with pytest.raises(ConfigError) as info:
        validate_config({**cfg, "scene": scene}, SCHEMA)
    return str(info.value)


def test_duplicate_yaml_keys_are_named(tmp_path):
    from roughcontact.pipeline.config.files import check_config_files

    good = tmp_path / "good.yaml"
    good.write_text("scene: demo\nscenes: {demo: {contact: {seeds: 2}}}\n")
    check_config_files([good])
    bad = tmp_path / "bad.yaml"
    bad.write_text("scene: demo\nscenes:\n  demo:\n    contact: {seeds: 2}\n    contact: {seeds: 3}\n")
    with pytest.raises(ConfigError, match=r"bad.yaml: key 'contact' appears twice in one mapping \(lines 4 and 5\)"):
        check_config_files([bad])
    broken = tmp_path / "broken.yaml"
    broken.write_text("scenes: [unclosed\n")
    with pytest.raises(ConfigError, match="broken.yaml: not valid YAML"):
        check_config_files([broken])


@pytest.mark.parametrize(
    "text, words",
    [
        ("scene: demo\nscenes:\n  demo:\n\tcontact: {}\n",
         "tabbed.yaml: not valid YAML at line 4, column 1: found character '\\t' that cannot start any token"),
        ("scene: demo: x\n", "tabbed.yaml: not valid YAML at line 1, column 12: mapping values are not allowed here"),
        ("scenes: {demo: [1, 2}\n", "tabbed.yaml: not valid YAML at line 1, column 21"),
        ("- scene\n- demo\n",
         "tabbed.yaml: a config file must be a mapping of keys (scene, scenes, defaults) at its top level, got a list"),
        ("", "got nothing"),
    ],
)
def test_malformed_yaml_is_named_with_line_column_and_remedy(tmp_path, text, words):
    from roughcontact.pipeline.config.files import check_config_files

    bad = tmp_path / "tabbed.yaml"
    bad.write_text(text)
    with pytest.raises(ConfigError) as info:
        check_config_files([bad])
    assert words in str(info.value), str(info.value)
    if "not valid YAML" in words:
        assert "indent with spaces, not tabs" in str(info.value)


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_config_files_add_to_the_shipped_config_as_snakemake_reads_them(tmp_path, monkeypatch, shipped_config):
    """``--configfile mine.yaml`` adds its scene to config/config.yaml (mappings merged key by key)."""
    import subprocess
    import sys

    import yaml

    from roughcontact.pipeline.config.files import load_config_files

    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text(yaml.safe_dump(shipped_config))
    (tmp_path / "mine.yaml").write_text("scenes:\n  mine:\n    contact:\n      surface: {N: 128}\n"
                                        "      grid: {k_l: ['4'], k_s: ['64'], H: ['0.5']}\n      seeds: 2\n"
                                        "  demo: {contact: {seeds: 4}}\n")
    monkeypatch.chdir(tmp_path)
    cfg = load_config_files(["mine.yaml"])
    assert set(cfg["scenes"]) == set(shipped_config["scenes"]) | {"mine"}
    assert cfg["defaults"] == shipped_config["defaults"] and cfg["scene"] == "demo"
    assert cfg["scenes"]["demo"]["contact"]["seeds"] == 4  # merged into the shipped demo, its grid kept
    assert cfg["scenes"]["demo"]["contact"]["grid"] == shipped_config["scenes"]["demo"]["contact"]["grid"]
    scenes = validate_config({**cfg, "scene": "mine"}, SCHEMA)["scenes"]
    assert scenes["mine"]["contact"]["load"]["n_steps"] == 30  # from the shipped defaults
    res = subprocess.run([sys.executable, "-m", "roughcontact.pipeline.config", "mine.yaml", "--scene", "mine"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0 and "scene 'mine' plans 2 contact cases" in res.stdout, res.stderr
    (tmp_path / "broken.yaml").write_text("scenes:\n  mine: {contact: {seeds: 2}\n")
    res = subprocess.run([sys.executable, "-m", "roughcontact.pipeline.config", "broken.yaml"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "error: broken.yaml: not valid YAML at line 3, column 1" in res.stderr, res.stderr


def test_text_is_read_as_the_type_the_schema_asks_for(shipped_config):
    """Snakemake's --config gives nested values as text: read as integer, number, boolean or null where
    the schema asks for one, grid strings and descriptions left as text."""
    cfg = _demo(shipped_config)
    demo = cfg["scenes"]["demo"]
    demo["description"] = "null"
    demo["contact"].update(seeds="4", solver={"tol": "1e-9", "max_iter": "500.0"},
                           outputs={"fields": ["1", "30"], "clusters": "true"}, load={"schedule": "geometric"},
                           surface={"N": "256", "rms_slope": "null", "rms_height": "0.1"})
    demo["fit"] = {"window": ["0.02", "0.3"], "include_unconverged": "False"}
    cfg["defaults"]["contact"]["load"] = {"p_max": "0.005", "n_steps": "30"}
    scene = validate_config(cfg, SCHEMA)["scenes"]["demo"]
    con = scene["contact"]
    assert con["seeds"] == 4 and con["solver"]["tol"] == 1e-9 and con["solver"]["max_iter"] == 500
    assert con["outputs"] == {"fields": [1, 30], "clusters": True}
    assert con["surface"] == {"N": 256, "L": 1.0, "rms_height": 0.1, "plateau": False, "unit": "1"}
    assert con["load"]["p_max"] == 0.005 and con["load"]["n_steps"] == 30 and con["load"]["schedule"] == "geometric"
    assert scene["fit"]["window"] == [0.02, 0.3] and scene["fit"]["include_unconverged"] is False
    assert con["grid"]["H"] == ["0.36", "0.84"] and scene["description"] == "null"


@pytest.mark.parametrize(
    "path, value, words",
    [
        (("contact", "seeds"), "four", "field 'contact.seeds': 'four' is not a whole number (schema type 'integer'); "
                                       "write a whole number, e.g. 4"),
        (("contact", "seeds"), "4.5", "'4.5' is not a whole number"),
        (("contact", "solver", "tol"), "small", "field 'contact.solver.tol': 'small' is not a number"),
        (("contact", "outputs"), {"clusters": "maybe"}, "'maybe' is not true or false (schema type 'boolean')"),
    ],
)
def test_text_that_is_not_the_schemas_type_is_named_with_the_remedy(shipped_config, path, value, words):
    cfg = _edit(_demo(shipped_config), path, value)
    with pytest.raises(ConfigError) as info:
        validate_config(cfg, SCHEMA)
    assert words in str(info.value) and "--config" in str(info.value), str(info.value)


def test_geometric_load_schedule(shipped_config):
    cfg = _edit(_demo(shipped_config), ("contact", "load"), {"p_max": 0.005, "n_steps": 30,
                                                             "schedule": "geometric"})
    con = validate_config(cfg, SCHEMA)["scenes"]["demo"]["contact"]
    steps = load_steps(con)
    assert len(steps) == 30 and steps[0] == pytest.approx(0.005 / 30) and steps[-1] == 0.005
    ratios = [b / a for a, b in zip(steps[:-1], steps[1:], strict=True)]
    assert max(ratios) == pytest.approx(min(ratios), rel=1e-12)  # equal ratios
    uniform = load_steps(validate_config(shipped_config, SCHEMA)["scenes"]["demo"]["contact"])
    # more steps at small loads than the uniform schedule: 10 of 30 below p_max/10
    assert sum(p < 0.0005 for p in steps) > 3 * sum(p < 0.0005 for p in uniform)
    con["load"]["p_min"] = 1e-4
    steps = load_steps(con)
    assert steps[0] == pytest.approx(1e-4) and steps[-1] == 0.005


@pytest.mark.parametrize(
    "load, words",
    [
        ({"schedule": "geometric", "p_min": 0.01}, "must be < load.p_max"),
        ({"p_min": 0.001}, "only used by load.schedule: geometric"),
        ({"schedule": "log"}, "schedule"),
    ],
)
def test_bad_load_schedule_is_named(shipped_config, load, words):
    cfg = _edit(_demo(shipped_config), ("contact", "load"), {"p_max": 0.005, "n_steps": 30, **load})
    with pytest.raises(ConfigError, match="contact.load") as err:
        validate_config(cfg, SCHEMA)
    assert words in str(err.value)


@pytest.mark.parametrize(
    "edit, field, words",
    [
        (lambda k: k["variants"]["N512"].update(N="32"), "kappa_gap.variants.N512.N", "too coarse for k_s=32"),
        (lambda k: k["variants"]["N512"].update(role="baseline"), "kappa_gap.variants",
         "exactly one variant with role: baseline"),
        (lambda k: k["variants"].pop("bem-N512"), "kappa_gap.variants",
         "needs a role: solver variant with method: bem"),
        (lambda k: [k["variants"].pop(v) for v in ("N512", "N1024")], "kappa_gap.variants", "at least three N"),
        (lambda k: k["variants"]["N512"].update(method="cg"), "kappa_gap.variants.N512.method", "bem"),
        (lambda k: k["variants"].update({"a b": {"role": "load", "N": "64", "seeds": 1}}), "kappa_gap.variants",
         "a variant name"),
    ],
)
def test_malformed_kappa_gap_settings_are_named(shipped_config, edit, field, words):
    _assert_study_error_named(shipped_config, "kappa_gap", "kappa-gap", edit, field, words)


def test_kappa_gap_job_params_leave_out_seeds_and_role(shipped_config):
    # adding seeds to a variant must not rerun its finished surfaces
    from roughcontact.pipeline import params

    block = validate_config(shipped_config, SCHEMA)["scenes"]["kappa-gap"]["kappa_gap"]
    one = params.kappa_gap_case(block, "N4096")
    block["variants"]["N4096"]["seeds"] = 7
    assert params.kappa_gap_case(block, "N4096") == one and "seeds" not in one["setting"]
