"""Whole scenes: the pipeline's config validated (schema, then cross-field rules) and expanded into cases.

A *scene* is a named block under ``scenes:`` that says what to compute. It is a small
delta over the optional ``defaults:`` block: each study the scene declares
(``representativity``, ``contact``, ``accuracy``; an empty block or ``null`` declares it
with the defaults) is the defaults' block of that study deep-merged with the scene's
(mappings merge key by key, anything else replaces; ``null`` removes a default, e.g.
``rms_slope: null`` to normalise by ``rms_height`` instead). Validation runs on the merged
scene, in two passes, both before Snakemake plans any job:

1. the JSON schema ``config.schema.yaml`` (package data, :mod:`roughcontact.pipeline.config.schema`; types,
   ranges, unknown keys),
   whose ``default`` values are filled in;
2. the cross-field rules a schema cannot express (k_l < k_s <= N/2, 0 < H < 1, examples
   inside the grid, fit window ordered, field steps within the load schedule).

Every error is a :class:`ConfigError` whose message names the scene and the field
(``scene 'demo', field 'contact.grid.k_s': ...``) and the allowed range, and says when the
bad value came from ``defaults``. An invalid scene stops only a run of that scene:
:func:`validate_config` raises the error of the scene that runs and keeps the others' under
``invalid`` (the workflow logs them, and stops a target in such a scene with its message).
The scene that runs also has its files and physical ranges checked (``active``).

The validated scene is canonical: schema defaults filled in, numbers typed as the schema
says (``N: 32.0`` becomes ``32``, ``L: 1`` becomes ``1.0``), so that two configs meaning the
same thing give the same job parameters (:mod:`roughcontact.pipeline.params`). Snakemake's ``--config``
passes a nested value as text (``--config 'scenes={demo: {contact: {seeds: 4}}}'`` gives
``seeds: '4'``): before validation, text where the schema asks for an integer, a number or a
boolean is read as one when it reads unambiguously as one, and ``null`` where the schema takes
no text removes a default as in a file (:func:`coerce_strings`).

Config files are read as Snakemake reads them (:func:`load_config_files`: each file merged over
the ones before, ``config/config.yaml`` first), and a file that is not YAML is named with its
line and column (:func:`check_config_files`). ``python -m roughcontact.pipeline.config [FILE ...]`` checks
the shipped config with these files added, as ``snakemake --configfile FILE ...`` would read it.
"""

from __future__ import annotations

import argparse
import copy
import re
import sys
from collections.abc import Mapping
from pathlib import Path

from jsonschema import Draft202012Validator

from .cases import BATCH_STEM, CASE_STEM, Case, batches, cases
from .config.checks import (
    check_accuracy,
    check_against_fit,
    check_backend,
    check_batch,
    check_contact,
    check_kappa_gap,
    check_mpi,
    check_ranks,
    resolve_load,
)
from .config.files import ConfigError, load_config_files
from .config.schema import (
    SCENE_STUDIES,
    coerce_strings,
    field_name,
    fill_defaults,
    has_path,
    load_schema,
    merge_scene,
    non_finite,
    schema_message,
)
from .sources import source_of

#: Allowed scene names: they become folder names under results/.
SCENE_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")

#: Re-exported: the generated study's grid of cases (:mod:`roughcontact.pipeline.cases`).
__all__ = ["BATCH_STEM", "CASE_STEM", "SCENE_NAME", "Case", "batches", "cases", "plan_summary", "validate_config",
           "validate_scene"]


def validate_scene(name: str, scene: dict, schema: dict, delta: dict | None = None, *, active: bool = True) -> dict:
    """Validate one (merged) scene and return a canonical copy: defaults filled, numbers typed.

    ``delta`` is the scene as written, before :func:`merge_scene`; a bad field that it does
    not hold came from the ``defaults`` block, and the message says so. ``active``: whether this
    is the scene that runs (only its topography files must exist now). Raises
    :class:`ConfigError` naming ``name`` and the offending field.
    """
    bad = non_finite(scene)
    if bad:
        raise ConfigError(f"scene {name!r}, field '{field_name(bad[0])}': {bad[1]} is not a finite number")
    source = source_of(scene, name)
    for study in ("accuracy", "kappa_gap"):
        if study in scene and study not in source.studies:
            raise ConfigError(f"scene {name!r}, field '{study}': the {study} study runs on generated surfaces only; "
                              f"remove it from a scene with a{'n' if source.key[0] in 'aeiou' else ''} {source.key} "
                              "block")
    scene_schema = {**schema["$defs"]["scene"], "$defs": schema["$defs"]}
    validator = Draft202012Validator(scene_schema)
    errors = sorted(validator.iter_errors(scene), key=lambda e: (len(e.path), list(e.path)))
    if errors:
        err = errors[0]
        origin = ""
        if delta is not None and err.path and not has_path(delta, err.path) and has_path(scene, err.path):
            origin = " (value from the 'defaults' block)"
        raise ConfigError(f"scene {name!r}, field '{field_name(err.path)}'{origin}: {schema_message(err)}")
    out = fill_defaults(copy.deepcopy(scene), scene_schema, scene_schema)
    out = source.check_scene(name, out, delta, check_files=active)
    if "contact" in out:
        given = ((delta or {}).get("contact") or {}).get("load") or {}
        resolve_load(name, out["contact"]["load"], given, source.relative_load)
        check_contact(name, out["contact"])
        check_batch(name, out["contact"], source.key)
        check_ranks(name, out["contact"], source.key)
        check_against_fit(name, out["contact"], out["fit"])
        if active:
            check_backend(name, out["contact"])
            check_mpi(name, out["contact"])
            source.check_contact_files(name, out)
    if "accuracy" in out:
        check_accuracy(name, out["accuracy"])
    if "kappa_gap" in out:
        check_kappa_gap(name, out["kappa_gap"])
    lo, hi = out["fit"]["window"]
    if not lo < hi:
        raise ConfigError(f"scene {name!r}, field 'fit.window': needs low < high, got [{lo}, {hi}]")
    return out


def validate_config(config: dict, schema: dict | None = None, *, strict: bool = False) -> dict:
    """Validate the whole config (every scene) and return it with defaults filled in.

    Each scene is merged over ``config['defaults']`` first (:func:`merge_scene`);
    ``config['scene']`` must name one of ``config['scenes']``. An invalid scene stops only a run of
    that scene: the active scene's error (and one in the config's structure) is raised, another
    scene's is kept under ``invalid`` (scene name -> message; a run of it stops with that message).
    ``strict``: raise the first invalid scene's error whichever scene it is.
    """
    schema = schema or load_schema()
    defaults = _check_structure(config)
    scene_schema = {**schema["$defs"]["scene"], "$defs": schema["$defs"]}
    defaults = coerce_strings(defaults, scene_schema)
    default = config.get("scene")
    validated, invalid = {}, {}
    for name, block in config["scenes"].items():
        if not isinstance(name, str) or not SCENE_NAME.match(name):
            raise ConfigError(f"config field 'scenes': scene name {name!r} is not allowed; names start with "
                              "a letter and hold only letters, digits, '_' and '-' (they become folder names)")
        try:
            if not isinstance(block or {}, dict):
                raise ConfigError(f"scene {name!r}: must be a mapping of blocks, got {type(block).__name__}")
            block = coerce_strings(block, scene_schema)
            validated[name] = validate_scene(name, merge_scene(defaults, block or {}), schema, delta=block or {},
                                             active=name == default)
        except ConfigError as err:
            if strict or name == default:
                raise
            invalid[name] = str(err)
    if not isinstance(default, str) or default not in validated:
        raise ConfigError(
            f"config field 'scene': unknown scene {default!r}; defined scenes: {', '.join(sorted(config['scenes']))}"
        )
    return {"scene": default, "scenes": validated, "invalid": invalid}


def _check_structure(config) -> dict:
    """The config's top level checked (keys, ``scenes`` a mapping, ``defaults`` blocks); returns ``defaults``."""
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
    return defaults


def _load_summary(load: Mapping) -> str:
    """The final load in words: what a case receives (:mod:`roughcontact.case.loading`)."""
    if "target_area" in load:
        return (f"final load: the p0 giving A/A0 = {load['target_area']:g} on each case, found first "
                f"(a few extra solves a case)")
    if load["relative_to"] == "rms_slope":
        return f"final load p0/(E* h') = {load['p_max']:g}, h' each surface's rms slope"
    return f"final load p0/E* = {load['p_max']:g}"


def plan_summary(scene_name: str, scene: dict) -> str:
    """One line saying how much a validated scene computes (shown by ``snakemake -n``)."""
    parts = source_of(scene, scene_name).plan(scene)
    if "contact" in scene:
        parts.append(_load_summary(scene["contact"]["load"]))
    if "accuracy" in scene:
        parts.append("the accuracy study")
    if "kappa_gap" in scene:
        kg = scene["kappa_gap"]
        n_jobs = sum(v["seeds"] for v in kg["variants"].values()) * len(kg["H"])
        parts.append(f"the kappa-gap study ({n_jobs} solves in {len(kg['variants'])} variants)")
    return f"roughcontact: scene {scene_name!r} plans " + ("; ".join(parts) or "nothing") + "."


def main(argv=None) -> None:
    """``python -m roughcontact.pipeline.config [FILE ...]``: check config files as ``snakemake --configfile``
    reads them."""
    ap = argparse.ArgumentParser(prog="python -m roughcontact.pipeline.config",
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
    for message in valid["invalid"].values():
        sys.stderr.write(f"warning: {message} (a run of that scene would stop here; the others run)\n")
    sys.stdout.write(plan_summary(valid["scene"], valid["scenes"][valid["scene"]]) + "\n")


if __name__ == "__main__":
    main()
