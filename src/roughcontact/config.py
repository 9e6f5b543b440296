"""Scenes: validate the pipeline's config and expand it into cases.

A *scene* is a named block under ``scenes:`` that says what to compute. It is a small
delta over the optional ``defaults:`` block: each study the scene declares
(``representativity``, ``contact``, ``accuracy``; an empty block or ``null`` declares it
with the defaults) is the defaults' block of that study deep-merged with the scene's
(mappings merge key by key, anything else replaces; ``null`` removes a default, e.g.
``rms_slope: null`` to normalise by ``rms_height`` instead). Validation runs on the merged
scene, in two passes, both before Snakemake plans any job:

1. the JSON schema ``workflow/schemas/config.schema.yaml`` (types, ranges, unknown keys),
   whose ``default`` values are filled in;
2. the cross-field rules a schema cannot express (k_l < k_s <= N/2, 0 < H < 1, examples
   inside the grid, fit window ordered, field steps within the load schedule).

Every error is a :class:`ConfigError` whose message names the scene and the field
(``scene 'demo', field 'contact.grid.k_s': ...``) and the allowed range, and says when the
bad value came from ``defaults``.

The validated scene is canonical: schema defaults filled in, numbers typed as the schema
says (``N: 32.0`` becomes ``32``, ``L: 1`` becomes ``1.0``), so that two configs meaning the
same thing give the same job parameters (:mod:`roughcontact.params`). Snakemake's ``--config``
passes a nested value as text (``--config 'scenes={demo: {contact: {seeds: 4}}}'`` gives
``seeds: '4'``): before validation, text where the schema asks for an integer, a number or a
boolean is read as one when it reads unambiguously as one, and ``null`` where the schema takes
no text removes a default as in a file (:func:`coerce_strings`).

Config files are read as Snakemake reads them (:func:`load_config_files`: each file merged over
the ones before, ``config/config.yaml`` first), and a file that is not YAML is named with its
line and column (:func:`check_config_files`). ``python -m roughcontact.config [FILE ...]`` checks
the shipped config with these files added, as ``snakemake --configfile FILE ...`` would read it.
"""

from __future__ import annotations

import argparse
import copy
import itertools
import math
import re
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import yaml
from jsonschema import Draft202012Validator

from .measured import MeasuredConfigError, check_measured_scene, topography_names

#: The studies of a scene that run over a grid of cases (the accuracy study has its own settings).
STUDIES = ("representativity", "contact")

#: Every block a scene may declare that computes something.
SCENE_STUDIES = (*STUDIES, "accuracy", "kappa_gap")

#: File stem of one case: the config's own strings for k_l, k_s, H and the seed.
CASE_STEM = "kl{k_l}_ks{k_s}_H{H}_s{seed}"
#: File stem of one representativity batch: every k_s and seed of one (k_l, H) in one file.
BATCH_STEM = "kl{k_l}_H{H}"

#: Allowed scene names: they become folder names under results/.
SCENE_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")

DEFAULT_SCHEMA = Path(__file__).resolve().parents[2] / "workflow" / "schemas" / "config.schema.yaml"
#: The workflow's own config file (the Snakefile's ``configfile:``), relative to the working directory.
SHIPPED_CONFIG = Path("config") / "config.yaml"


class ConfigError(ValueError):
    """The config asks for something the pipeline cannot do; the message says what."""


@dataclass(frozen=True)
class Case:
    """One surface realisation: cutoffs and Hurst exponent as config strings, and a seed."""

    k_l: str
    k_s: str
    H: str
    seed: int

    @property
    def stem(self) -> str:
        """File stem ``kl{k_l}_ks{k_s}_H{H}_s{seed}`` built from the config strings."""
        return CASE_STEM.format(k_l=self.k_l, k_s=self.k_s, H=self.H, seed=self.seed)


class _UniqueKeyLoader(yaml.SafeLoader):
    """A YAML loader that refuses a key written twice in one mapping (YAML keeps the last)."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise ConfigError(f"{self.name}: key {key!r} appears twice in one mapping (lines {seen[key]} and "
                                  f"{key_node.start_mark.line + 1}); YAML would silently keep the last")
            seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep)


def _yaml_error(path, exc: yaml.YAMLError) -> ConfigError:
    """A :class:`ConfigError` naming ``path``, the line and column of a YAML error, and the remedy."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    context = getattr(exc, "context", None)
    context_mark = getattr(exc, "context_mark", None)
    if context and context_mark is not None:
        problem += f" ({context} at line {context_mark.line + 1}, column {context_mark.column + 1})"
    return ConfigError(f"{path}: not valid YAML{where}: {problem}; fix the file there: indent with spaces, "
                       "not tabs, put ': ' after each key, close every bracket and quote")


def read_config_file(path) -> dict:
    """One config file as a mapping; :class:`ConfigError` naming the file (and the line) if it is not one.

    Refuses what Snakemake would refuse without naming the file: text that is not YAML (line and
    column given), a key written twice in one mapping (YAML would keep the last silently) and a
    top level that is not a mapping of keys.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            data = yaml.load(fh, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise _yaml_error(path, exc) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot be read as a config file ({exc})") from None
    if not isinstance(data, dict):
        got = "nothing" if data is None else f"a {type(data).__name__}"
        raise ConfigError(f"{path}: a config file must be a mapping of keys (scene, scenes, defaults) at its "
                          f"top level, got {got}")
    return data


def check_config_files(paths) -> None:
    """Raise :class:`ConfigError` naming the file if a config file is not YAML or repeats a key."""
    for path in paths:
        read_config_file(path)


def update_config(config: dict, overwrite: Mapping) -> dict:
    """``overwrite`` merged into ``config`` in place, as Snakemake merges config files and ``--config``:
    mappings key by key, anything else replaced."""
    for key, value in overwrite.items():
        if isinstance(value, Mapping):
            base = config.get(key)
            config[key] = update_config(base if isinstance(base, dict) else {}, value)
        else:
            config[key] = copy.deepcopy(value)
    return config


def load_config_files(paths, base: str | Path | None = SHIPPED_CONFIG) -> dict:
    """The config Snakemake builds from ``base`` (the workflow's ``configfile:``) and ``--configfile paths``.

    Each file is merged over the ones before (:func:`update_config`), so a file holding only a scene
    adds it to the shipped config. Every file is checked by :func:`read_config_file` first.
    """
    files = ([Path(base)] if base is not None else []) + [Path(p) for p in paths]
    if base is not None and not Path(base).is_file():
        raise ConfigError(f"{base}: no such file; run from the workflow's folder (the one holding config/ "
                          "and results/)")
    config: dict = {}
    for path in files:
        update_config(config, read_config_file(path))
    return config


def load_schema(path: str | Path = DEFAULT_SCHEMA) -> dict:
    """The config JSON schema as a dict."""
    with open(path) as fh:
        return yaml.safe_load(fh)


def _resolve(schema: dict, root: dict) -> dict:
    ref = schema.get("$ref")
    if ref:
        node = root
        for part in ref.lstrip("#/").split("/"):
            node = node[part]
        merged = {**_resolve(node, root), **{k: v for k, v in schema.items() if k != "$ref"}}
        return merged
    return schema


def _admits_text(schema: dict, root: dict) -> bool:
    """Whether ``schema`` (resolved) may hold a string: its type, its enum or one of its alternatives."""
    schema = _resolve(schema, root)
    if schema.get("type") == "string" or any(isinstance(v, str) for v in schema.get("enum", ())):
        return True
    return any(_admits_text(sub, root) for key in ("oneOf", "anyOf") for sub in schema.get(key, ()))


def _from_text(text: str, kind: str):
    """``text`` read as the schema type ``kind`` (integer, number, boolean), or ``text`` if it is not one."""
    try:
        if kind == "integer":
            value = float(text)
            return int(value) if value.is_integer() else text
        if kind == "number":
            return float(text)
    except ValueError:
        return text
    if kind == "boolean":
        value = yaml.safe_load(text) if "\n" not in text else text
        return value if isinstance(value, bool) else text
    return text


def _properties(schema: dict, root: dict) -> dict:
    props: dict = {}
    for sub in schema.get("allOf", []):
        props.update(_properties(_resolve(sub, root), root))
    props.update({k: v for k, v in schema.get("properties", {}).items() if v is not True})
    return props


def coerce_strings(instance, schema: dict, root: dict | None = None):
    """``instance`` with text read as the type the schema asks for, where it reads as one (a copy).

    Snakemake's ``--config`` gives nested values as text; a string at a place whose schema type is
    ``integer``, ``number`` or ``boolean`` becomes that type when it reads as one (``"4"`` -> 4,
    ``"1e-9"`` -> 1e-9, ``"true"`` -> True), and ``null`` (or ``~``) where the schema takes no text
    becomes None (which removes a default). Anything else is left for validation to name.
    """
    root = schema if root is None else root
    schema = _resolve(schema, root)
    if isinstance(instance, str):
        if instance.strip() in ("null", "Null", "NULL", "~") and not _admits_text(schema, root):
            return None
        kind = schema.get("type")
        return _from_text(instance.strip(), kind) if kind in ("integer", "number", "boolean") else instance
    if isinstance(instance, list):
        items = schema.get("items")
        return [coerce_strings(v, items, root) for v in instance] if isinstance(items, dict) else instance
    if isinstance(instance, dict):
        branches = [b for b in (_resolve(b, root) for b in schema.get("oneOf", ())) if b.get("type") == "object"]
        if not schema.get("properties") and not schema.get("allOf") and len(branches) == 1:
            schema = branches[0]
        props, extra = _properties(schema, root), schema.get("additionalProperties")
        out = {}
        for key, value in instance.items():
            sub = props.get(key, extra if isinstance(extra, dict) else None)
            out[key] = coerce_strings(value, sub, root) if sub is not None else value
        return out
    return instance


def _coerce_number(value, schema: dict):
    """``value`` typed as the schema's ``number`` (float) or ``integer`` (int), else as is."""
    kind = schema.get("type")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return value
    if kind == "number":
        return float(value)
    if kind == "integer" and float(value).is_integer():
        return int(value)
    return value


def _complete(instance, schema: dict, root: dict):
    """Fill the schema's ``default`` values into ``instance`` and type its numbers, in place.

    Returns the (possibly retyped) instance: numbers are retyped, containers changed in place.
    """
    schema = _resolve(schema, root)
    if isinstance(instance, list) and isinstance(schema.get("items"), dict):
        instance[:] = [_complete(item, schema["items"], root) for item in instance]
        return instance
    if not isinstance(instance, dict):
        return _coerce_number(instance, schema)
    props: dict = {}
    for sub in schema.get("allOf", []):
        props.update(_resolve(sub, root).get("properties", {}))
    for name, sub in schema.get("properties", {}).items():
        if sub is True:
            continue
        props[name] = sub
    for name, sub in props.items():
        sub = _resolve(sub, root)
        if name not in instance and "default" in sub:
            instance[name] = copy.deepcopy(sub["default"])
        if name in instance:
            instance[name] = _complete(instance[name], sub, root)
    extra = schema.get("additionalProperties")
    if isinstance(extra, dict):
        for name, value in instance.items():
            if name not in props:
                instance[name] = _complete(value, extra, root)
    return instance


def merge(base, delta):
    """``delta`` deep-merged over ``base`` (neither changed): mappings merge key by key,
    any other value replaces, and a ``None`` value removes the key."""
    if not isinstance(base, dict) or not isinstance(delta, dict):
        return copy.deepcopy(delta)
    out = copy.deepcopy(base)
    for key, value in delta.items():
        if value is None:
            out.pop(key, None)
        else:
            out[key] = merge(out.get(key), value) if isinstance(value, dict) else copy.deepcopy(value)
    return out


def _has_path(tree, path) -> bool:
    for part in path:
        if isinstance(tree, dict) and part in tree:
            tree = tree[part]
        elif isinstance(tree, list) and isinstance(part, int) and part < len(tree):
            tree = tree[part]
        else:
            return False
    return True


def merge_scene(defaults: dict, scene: dict) -> dict:
    """The full scene: each block the scene declares merged over the same block of ``defaults``.

    A study block written as ``null`` or ``{}`` is declared with the defaults alone; a study
    the scene does not name is not computed, whatever ``defaults`` holds. ``fit`` is always
    merged (it applies only with ``contact``).
    """
    out = {}
    for key, value in scene.items():
        if key in (*SCENE_STUDIES, "fit"):
            out[key] = merge(defaults.get(key) or {}, value or {})
        else:
            out[key] = copy.deepcopy(value)
    if "fit" not in out and "fit" in defaults:
        out["fit"] = copy.deepcopy(defaults["fit"])
    return out


def _field(path) -> str:
    return ".".join(str(p) for p in path) or "(top level)"


def _schema_message(err) -> str:
    if err.validator == "additionalProperties" or err.validator == "unevaluatedProperties":
        allowed = sorted(_resolve(err.schema, {}).get("properties", {}) or [])
        return f"{err.message}" + (f"; allowed keys: {', '.join(allowed)}" if allowed else "")
    if err.validator == "oneOf" and "rms_slope" in str(err.schema):
        return "give exactly one of rms_slope or rms_height"
    if err.validator == "anyOf" and "representativity" in str(err.schema):
        return "a scene must declare at least one of 'representativity', 'contact', 'accuracy' or 'kappa_gap'"
    if err.validator == "type" and err.schema.get("type") == "string" and "pattern" in err.schema:
        return (f"{err.instance!r} must be written as a string (e.g. \"{err.instance}\") so that "
                "file names carry the config's text, not float formatting")
    if err.validator == "pattern":
        what = err.schema.get("description", f"text matching {err.schema['pattern']!r}")
        return f"{err.instance!r} is not {what}" + ("" if "spaces" in what else " (no spaces or line breaks)")
    kind = err.schema.get("type") if err.validator == "type" else None
    if kind in _TYPE_REMEDY and isinstance(err.instance, str):
        what, example = _TYPE_REMEDY[kind]
        return (f"{err.instance!r} is not {what} (schema type '{kind}'); write {what}, e.g. {example} (text "
                f"given with --config, which passes nested values as text, is read as {what} when it is one)")
    return err.message


#: What each schema type takes, and an example, for the message on a string that is none of them.
_TYPE_REMEDY = {"integer": ("a whole number", "4"), "number": ("a number", "0.005 or 1e-8"),
                "boolean": ("true or false", "true")}


def _non_finite(tree, path=()):
    """Path and value of the first NaN or infinite number in ``tree``, or None."""
    if isinstance(tree, float) and not math.isfinite(tree):
        return path, tree
    items = tree.items() if isinstance(tree, dict) else enumerate(tree) if isinstance(tree, list) else ()
    for key, value in items:
        found = _non_finite(value, (*path, key))
        if found:
            return found
    return None


def _duplicates_by_value(texts) -> list[str]:
    """Strings of ``texts`` that equal an earlier one as numbers ("2" and "2.0")."""
    seen, dups = {}, []
    for text in texts:
        value = float(text)
        if value in seen:
            dups.append(f"{seen[value]!r} and {text!r}")
        seen.setdefault(value, text)
    return dups


def _check_grid(scene: str, study: str, block: dict) -> None:
    """Cross-field rules of a generated study's grid (k_l < k_s <= N/2, 0 < H < 1, examples, seeds)."""
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field '{study}.{field}': {msg}")

    n = block["surface"]["N"]
    grid = block["grid"]
    for key in ("k_l", "k_s", "H"):
        for text in grid[key]:
            if float(text) <= 0:
                fail(f"grid.{key}", f"{text!r} must be > 0")
        dups = _duplicates_by_value(grid[key])
        if dups:
            fail(f"grid.{key}", f"{dups[0]} are the same number: each case would be computed twice")
    for text in grid["H"]:
        if not 0.0 < float(text) < 1.0:
            fail("grid.H", f"{text!r} is outside the allowed range 0 < H < 1")
    for text in grid["k_s"]:
        if float(text) > n / 2:
            fail("grid.k_s", f"{text!r} exceeds N/2 = {n / 2:g} (the Nyquist mode of N = {n})")
    # Every pair is run, so a pair with k_l >= k_s is an error rather than a silent skip.
    for kl, ks in itertools.product(grid["k_l"], grid["k_s"]):
        if float(kl) >= float(ks):
            fail("grid.k_l", f"k_l={kl} must be < k_s={ks} for every pair of the grid")
    for i, ex in enumerate(block.get("examples", [])):
        if ex["k_l"] not in grid["k_l"] or ex["k_s"] not in grid["k_s"]:
            fail(f"examples[{i}]", f"({ex['k_l']}, {ex['k_s']}) is not in the grid's k_l x k_s")
        if float(ex["k_l"]) >= float(ex["k_s"]):
            fail(f"examples[{i}]", f"k_l={ex['k_l']} must be < k_s={ex['k_s']}")
    if study == "contact" and block["seeds"] < 2:
        fail("seeds", f"{block['seeds']} is too few: the contact study's CEL fit resamples seeds and needs "
                      "at least 2")


def _check_contact(scene: str, block: dict) -> None:
    """Cross-field rules of a contact block: output steps, load schedule, effects."""
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg}")

    steps = block["load"]["n_steps"]
    bad = [s for s in block["outputs"]["fields"] if s > steps]
    if bad:
        fail("outputs.fields", f"steps {bad} exceed load.n_steps = {steps} (allowed 1..{steps})")
    load = block["load"]
    if "p_min" in load and load["schedule"] != "geometric":
        fail("load.p_min", f"only used by load.schedule: geometric (here {load['schedule']!r}); remove it")
    if "target_area" in load:
        _check_target_area(fail, load)
        return
    if "p_min" in load and not load["p_min"] < load["p_max"]:
        fail("load.p_min", f"{load['p_min']:g} must be < load.p_max = {load['p_max']:g}")
    relative = load.get("relative_to", "e_star")
    if relative == "e_star" and load["p_max"] > 1:
        fail("load.p_max", f"{load['p_max']:g} is p0/E* (load.relative_to: e_star) and must be <= 1")
    plastic = block["effects"].get("plasticity")
    # relative to the rms slope, p_max is compared with the hardness when each case's h' is known
    if plastic and relative == "e_star" and not plastic["hardness"] > block["load"]["p_max"]:
        fail("effects.plasticity.hardness", f"{plastic['hardness']:g} must exceed load.p_max = "
             f"{block['load']['p_max']:g}: a pressure capped at the hardness cannot carry a mean load p0 "
             ">= hardness")
    if "adhesion" in block["effects"]:
        _check_adhesion(fail, block)


def _check_adhesion(fail, block: dict) -> None:
    """``effects.adhesion``: the gap iteration runs on the periodic half-space and alone."""
    if "plasticity" in block["effects"]:
        fail("effects.adhesion", "cannot be combined with effects.plasticity (one effect on the gap iteration "
             "at a time); remove one of them")
    if block["solver"].get("boundary", "periodic") != "periodic":
        fail("effects.adhesion", f"needs solver.boundary: periodic (the adhesive iteration is periodic), got "
             f"{block['solver']['boundary']!r}")


def _check_target_area(fail, load: dict) -> None:
    """A ``load.target_area`` block: the final load is found per case (:func:`_resolve_load` dropped p_max)."""
    if "p_min" in load:
        fail("load.p_min", "not used with load.target_area: the geometric schedule then starts at "
                           "(final load) / n_steps; remove it")


#: A measured scene's final load when it says nothing: p0 / (E* h') = 0.05, the paper's regime
#: (about 10 % contact on its surfaces; p0/E* = 0.005 at their h' = 0.1).
MEASURED_P_MAX = 0.05


def _resolve_load(scene: str, load: dict, given: Mapping, measured: bool) -> None:
    """Fill ``load.relative_to`` in place from what the scene wrote (``given``: its own ``contact.load``).

    With ``target_area`` the final load is found per case, and ``p_max`` (inherited) is dropped. A
    measured scene that writes neither ``relative_to`` nor a load gets ``p_max: 0.05`` relative to
    each file's rms slope; one that writes ``p_max`` or ``p_min`` without ``relative_to`` is asked
    which it means, since the same number means a load ten times larger or smaller on a typical file.
    """
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field 'contact.{field}': {msg}")

    if "target_area" in load:
        for key in ("p_max", "relative_to"):
            if key in given:
                fail(f"load.{key}", f"not used with load.target_area (the final load is the one that gives "
                                    f"A/A0 = {load['target_area']:g} on each case); remove one of them")
            load.pop(key, None)
        return
    if measured and "relative_to" not in given:
        for key in ("p_max", "p_min"):
            if key in given:
                fail(f"load.{key}", "a measured scene's load is relative to each file's rms slope unless it says "
                                    "otherwise: add load.relative_to: rms_slope (the value is p0/(E* h'), the "
                                    "paper's pbar) or load.relative_to: e_star (p0/E*)")
        load["relative_to"], load["p_max"] = "rms_slope", MEASURED_P_MAX
    load.setdefault("relative_to", "e_star")


def _study_failure(scene: str, study: str):
    """A function raising the ConfigError of one field of a study block."""
    def fail(field, msg):
        raise ConfigError(f"scene {scene!r}, field '{study}.{field}': {msg}")

    return fail


def _check_one_case(block: dict, fail) -> float:
    """The cutoffs and H list of a one-case study (accuracy, kappa_gap); returns k_s."""
    k_l, k_s = float(block["k_l"]), float(block["k_s"])
    if not k_l < k_s:
        fail("k_l", f"k_l={block['k_l']} must be < k_s={block['k_s']}")
    for text in block["H"]:
        if not 0.0 < float(text) < 1.0:
            fail("H", f"{text!r} is outside the allowed range 0 < H < 1")
    dups = _duplicates_by_value(block["H"])
    if dups:
        fail("H", f"{dups[0]} are the same number: each case would be computed twice")
    return k_s


def _check_accuracy(scene: str, block: dict) -> None:
    fail = _study_failure(scene, "accuracy")
    k_s = _check_one_case(block, fail)
    settings = [("reference", block["reference"]), ("defaults", block["defaults"])]
    settings += [(f"axes.{axis}", {axis: v}) for axis, vals in block["axes"].items() for v in vals]
    for where, setting in settings:
        if "N" in setting and k_s > int(setting["N"]) / 2:
            fail(where, f"N={setting['N']} is too coarse for k_s={block['k_s']} (needs N >= {2 * k_s:g})")
        if "tol" in setting and not 0.0 < float(setting["tol"]) < 1.0:
            fail(where, f"tol={setting['tol']} is outside the allowed range 0 < tol < 1")
        if "n_steps" in setting and int(setting["n_steps"]) < 1:
            fail(where, f"n_steps={setting['n_steps']} must be >= 1")
    if max(int(s) for s in block["seed_axis"]) < 1:
        fail("seed_axis", "needs at least one entry >= 1")


def _check_kappa_gap(scene: str, block: dict) -> None:
    fail = _study_failure(scene, "kappa_gap")
    k_s = _check_one_case(block, fail)
    variants = block["variants"]
    for label, v in variants.items():
        if k_s > int(v["N"]) / 2:
            fail(f"variants.{label}.N", f"N={v['N']} is too coarse for k_s={block['k_s']} (needs N >= {2 * k_s:g})")
        if not 0.0 < float(v["tol"]) < 1.0:
            fail(f"variants.{label}.tol", f"tol={v['tol']} is outside the allowed range 0 < tol < 1")
    roles = [v["role"] for v in variants.values()]
    if roles.count("baseline") != 1:
        fail("variants", f"needs exactly one variant with role: baseline, got {roles.count('baseline')}")
    if 0 < roles.count("resolution") < 3:
        fail("variants", "a continuum series (role: resolution) needs at least three N")
    sk = [v for v in variants.values() if v["role"] == "solver" and v["method"] == "stanley-kato"]
    refs = {v["N"] for v in variants.values() if v["role"] == "solver" and v["method"] == "bem"}
    for v in sk:
        if v["N"] not in refs:
            fail("variants", f"a Stanley & Kato variant at N={v['N']} needs a role: solver variant with method: bem "
                             "at the same N to be compared with")


def validate_scene(name: str, scene: dict, schema: dict, delta: dict | None = None, *, active: bool = True) -> dict:
    """Validate one (merged) scene and return a canonical copy: defaults filled, numbers typed.

    ``delta`` is the scene as written, before :func:`merge_scene`; a bad field that it does
    not hold came from the ``defaults`` block, and the message says so. ``active``: whether this
    is the scene that runs (only its topography files must exist now). Raises
    :class:`ConfigError` naming ``name`` and the offending field.
    """
    bad = _non_finite(scene)
    if bad:
        raise ConfigError(f"scene {name!r}, field '{_field(bad[0])}': {bad[1]} is not a finite number")
    for study in ("accuracy", "kappa_gap"):
        if "topography" in scene and study in scene:
            raise ConfigError(f"scene {name!r}, field '{study}': the {study} study runs on generated surfaces only; "
                              "remove it from a scene with a topography block")
    scene_schema = {**schema["$defs"]["scene"], "$defs": schema["$defs"]}
    validator = Draft202012Validator(scene_schema)
    errors = sorted(validator.iter_errors(scene), key=lambda e: (len(e.path), list(e.path)))
    if errors:
        err = errors[0]
        origin = ""
        if delta is not None and err.path and not _has_path(delta, err.path) and _has_path(scene, err.path):
            origin = " (value from the 'defaults' block)"
        raise ConfigError(f"scene {name!r}, field '{_field(err.path)}'{origin}: {_schema_message(err)}")
    out = _complete(copy.deepcopy(scene), scene_schema, scene_schema)
    if "topography" in out:
        try:
            out = check_measured_scene(name, out, delta, check_files=active)
        except MeasuredConfigError as err:
            raise ConfigError(str(err)) from None
    else:
        for study in STUDIES:
            if study in out:
                _check_grid(name, study, out[study])
        if "contact" in out:
            out["contact"]["solver"].setdefault("boundary", "periodic")
    if "contact" in out:
        given = ((delta or {}).get("contact") or {}).get("load") or {}
        _resolve_load(name, out["contact"]["load"], given, "topography" in out)
        _check_contact(name, out["contact"])
    if "accuracy" in out:
        _check_accuracy(name, out["accuracy"])
    if "kappa_gap" in out:
        _check_kappa_gap(name, out["kappa_gap"])
    lo, hi = out["fit"]["window"]
    if not lo < hi:
        raise ConfigError(f"scene {name!r}, field 'fit.window': needs low < high, got [{lo}, {hi}]")
    return out


def validate_config(config: dict, schema: dict | None = None) -> dict:
    """Validate the whole config (every scene) and return it with defaults filled in.

    Each scene is merged over ``config['defaults']`` first (:func:`merge_scene`);
    ``config['scene']`` must name one of ``config['scenes']``.
    """
    schema = schema or load_schema()
    if not isinstance(config, dict):
        raise ConfigError("config must be a mapping with keys 'scene' and 'scenes'")
    unknown = sorted(set(config) - {"scene", "scenes", "defaults"})
    if unknown:
        raise ConfigError(f"unknown top-level config key(s) {unknown}; allowed: defaults, scene, scenes")
    scenes = config.get("scenes")
    if not isinstance(scenes, dict) or not scenes:
        raise ConfigError("config field 'scenes' must be a non-empty mapping of scene blocks")
    defaults = config.get("defaults") or {}
    if not isinstance(defaults, dict):
        raise ConfigError("config field 'defaults' must be a mapping of study blocks")
    allowed = (*SCENE_STUDIES, "fit")
    for key in defaults:
        if key not in allowed:
            raise ConfigError(f"config field 'defaults': unknown block {key!r}; allowed: {', '.join(allowed)}")
    scene_schema = {**schema["$defs"]["scene"], "$defs": schema["$defs"]}
    defaults = coerce_strings(defaults, scene_schema)
    validated = {}
    for name, block in scenes.items():
        if not isinstance(name, str) or not SCENE_NAME.match(name):
            raise ConfigError(f"config field 'scenes': scene name {name!r} is not allowed; names start with "
                              "a letter and hold only letters, digits, '_' and '-' (they become folder names)")
        if not isinstance(block or {}, dict):
            raise ConfigError(f"scene {name!r}: must be a mapping of blocks, got {type(block).__name__}")
        block = coerce_strings(block, scene_schema)
        validated[name] = validate_scene(name, merge_scene(defaults, block or {}), schema, delta=block or {},
                                         active=name == config.get("scene"))
    default = config.get("scene")
    if not isinstance(default, str) or default not in validated:
        raise ConfigError(
            f"config field 'scene': unknown scene {default!r}; defined scenes: {', '.join(sorted(validated))}"
        )
    return {"scene": default, "scenes": validated}


def batches(block: dict) -> list[tuple[str, str]]:
    """The ``(k_l, H)`` batches of a study block's grid: one representativity job each."""
    grid = block["grid"]
    return list(itertools.product(grid["k_l"], grid["H"]))


def cases(block: dict) -> list[Case]:
    """All cases of a study block: k_l x k_s x H x seeds (seeds 0..seeds-1)."""
    grid = block["grid"]
    return [
        Case(kl, ks, h, seed)
        for kl, ks, h in itertools.product(grid["k_l"], grid["k_s"], grid["H"])
        for seed in range(block["seeds"])
    ]


def _load_summary(load: Mapping) -> str:
    """The final load in words: what a case receives (:mod:`roughcontact.loading`)."""
    if "target_area" in load:
        return (f"final load: the p0 giving A/A0 = {load['target_area']:g} on each case, found first "
                f"(a few extra solves a case)")
    if load["relative_to"] == "rms_slope":
        return f"final load p0/(E* h') = {load['p_max']:g}, h' each surface's rms slope"
    return f"final load p0/E* = {load['p_max']:g}"


def plan_summary(scene_name: str, scene: dict) -> str:
    """One line saying how much a validated scene computes (shown by ``snakemake -n``)."""
    parts = []
    if "topography" in scene:
        n_files = len(topography_names(scene))
        for study in ("representativity", "contact"):
            if study in scene:
                steps = scene[study]["load"]["n_steps"] if study == "contact" else 0
                parts.append(f"{study} of {n_files} topography file(s)" +
                             (f" x {steps} load steps = {n_files * steps} solves" if steps else ""))
        if "contact" in scene:
            parts.append(_load_summary(scene["contact"]["load"]))
        return f"roughcontact: scene {scene_name!r} plans " + "; ".join(parts) + "."
    if "representativity" in scene:
        rep = scene["representativity"]
        n_surfaces = len(cases(rep))
        parts.append(f"{n_surfaces} representativity surfaces at N={rep['surface']['N']} "
                     f"in {len(batches(rep))} jobs")
    if "contact" in scene:
        con = scene["contact"]
        n_cases, n_steps = len(cases(con)), con["load"]["n_steps"]
        parts.append(f"{n_cases} contact cases x {n_steps} load steps = {n_cases * n_steps} solves at "
                     f"N={con['surface']['N']}")
        parts.append(_load_summary(con["load"]))
    if "accuracy" in scene:
        parts.append("the accuracy study")
    if "kappa_gap" in scene:
        kg = scene["kappa_gap"]
        n_jobs = sum(v["seeds"] for v in kg["variants"].values()) * len(kg["H"])
        parts.append(f"the kappa-gap study ({n_jobs} solves in {len(kg['variants'])} variants)")
    return f"roughcontact: scene {scene_name!r} plans " + ("; ".join(parts) or "nothing") + "."


def main(argv=None) -> None:
    """``python -m roughcontact.config [FILE ...]``: check config files as ``snakemake --configfile`` reads them."""
    ap = argparse.ArgumentParser(prog="python -m roughcontact.config",
                                 description="Check config/config.yaml with FILEs added (as snakemake --configfile "
                                             "FILE ... reads them): YAML syntax with file, line and column, repeated "
                                             "keys, and every scene. Run from the workflow's folder.")
    ap.add_argument("files", nargs="*", type=Path, help="config files added to config/config.yaml, in order")
    ap.add_argument("--scene", help="the scene to run (as --config scene=NAME); default: the config's `scene`")
    args = ap.parse_args(argv)
    try:
        config = load_config_files(args.files)
        if args.scene is not None:
            config["scene"] = args.scene
        valid = validate_config(config)
    except ConfigError as exc:
        ap.exit(2, f"error: {exc}\n")
    sys.stdout.write(plan_summary(valid["scene"], valid["scenes"][valid["scene"]]) + "\n")


if __name__ == "__main__":
    main()
