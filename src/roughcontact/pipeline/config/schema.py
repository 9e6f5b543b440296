"""The config's JSON schema and what rides on it: loading, text coercion, defaults, merging, messages.

The schema ``config.schema.yaml`` is package data beside this module (:func:`load_schema` reads it with
:mod:`importlib.resources`, so an installed wheel finds it too); the Snakefile validates with the same file.
"""

from __future__ import annotations

import copy
import functools
import math
from importlib import resources
from pathlib import Path

import yaml

#: The studies of a scene that run over a grid of cases (the accuracy study has its own settings).
STUDIES = ("representativity", "contact")


#: Every block a scene may declare that computes something.
SCENE_STUDIES = (*STUDIES, "accuracy", "kappa_gap")


#: The schema, package data beside this module: the one copy, which the Snakefile loads too.
SCHEMA_RESOURCE = "config.schema.yaml"


def load_schema(path: str | Path | None = None) -> dict:
    """The config JSON schema as a dict: the package's own (:data:`SCHEMA_RESOURCE`) unless ``path`` names another."""
    if path is None:
        return copy.deepcopy(_package_schema())  # parsed once a process (~0.3 s), a fresh copy each call
    with open(path) as fh:
        return yaml.safe_load(fh)


@functools.cache
def _package_schema() -> dict:
    return yaml.safe_load(resources.files(__package__).joinpath(SCHEMA_RESOURCE).read_text(encoding="utf-8"))


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


def _enum_kind(values) -> str | None:
    """The JSON type every value of an ``enum`` list has (``[1, 2]``: integer), None for text or a mix."""
    if not values:
        return None
    if all(isinstance(v, bool) for v in values):
        return "boolean"
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return "integer"
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return "number"
    return None


def _scalar_kind(schema: dict, root: dict) -> str | None:
    """The one non-text scalar type (integer, number, boolean) ``schema`` takes, itself or in one of its
    ``oneOf``/``anyOf`` alternatives (``pixel_size``: a number or a pair), when it takes no text; else None."""
    if _admits_text(schema, root):
        return None
    kinds = {schema.get("type")} | {_resolve(sub, root).get("type") for key in ("oneOf", "anyOf")
                                      for sub in schema.get(key, ())}
    kinds.add(_enum_kind(schema.get("enum")))  # an enum of numbers (dimension: [1, 2]) without a type of its own
    kinds &= {"integer", "number", "boolean"}
    return kinds.pop() if len(kinds) == 1 else None


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
        kind = _scalar_kind(schema, root)
        return _from_text(instance.strip(), kind) if kind is not None else instance
    if isinstance(instance, list):
        lists = [b for b in (_resolve(b, root) for b in schema.get("oneOf", ())) if b.get("type") == "array"]
        items = schema.get("items") if not lists or "items" in schema else lists[0].get("items")
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


def fill_defaults(instance, schema: dict, root: dict):
    """Fill the schema's ``default`` values into ``instance`` and type its numbers, in place.

    Returns the (possibly retyped) instance: numbers are retyped, containers changed in place.
    """
    schema = _resolve(schema, root)
    if isinstance(instance, list) and isinstance(schema.get("items"), dict):
        instance[:] = [fill_defaults(item, schema["items"], root) for item in instance]
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
            instance[name] = fill_defaults(instance[name], sub, root)
    extra = schema.get("additionalProperties")
    if isinstance(extra, dict):
        for name, value in instance.items():
            if name not in props:
                instance[name] = fill_defaults(value, extra, root)
    return instance


def merge(base, delta):
    """``delta`` deep-merged over ``base`` (neither changed): mappings merge key by key,
    any other value replaces, and a ``None`` value removes the key."""
    if not isinstance(delta, dict):
        return copy.deepcopy(delta)
    if not isinstance(base, dict):
        base = {}
    out = copy.deepcopy(base)
    for key, value in delta.items():
        if value is None:
            out.pop(key, None)
        else:
            out[key] = merge(out.get(key), value) if isinstance(value, dict) else copy.deepcopy(value)
    return out


def has_path(tree, path) -> bool:
    """Whether the nested mappings and lists ``tree`` hold ``path`` (a sequence of keys and indices)."""
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
        else:  # a source block: ``null`` inside it removes the key too (there is no default to remove)
            out[key] = merge({}, value)
    if "fit" not in out and "fit" in defaults:
        out["fit"] = copy.deepcopy(defaults["fit"])
    return out


def field_name(path) -> str:
    """A validation error's path as the field name in messages (``contact.grid.k_s``; ``(top level)``)."""
    return ".".join(str(p) for p in path) or "(top level)"


def schema_message(err) -> str:
    """One line for a :mod:`jsonschema` error: what is wrong and the allowed values or range."""
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
    if err.validator in ("oneOf", "anyOf"):
        return _alternatives_message(err)
    kind = err.schema.get("type") if err.validator == "type" else None
    if kind in _TYPE_REMEDY and isinstance(err.instance, str):
        what, example = _TYPE_REMEDY[kind]
        return (f"{err.instance!r} is not {what} (schema type '{kind}'); write {what}, e.g. {example} (text "
                f"given with --config, which passes nested values as text, is read as {what} when it is one)")
    return err.message


#: What a value of each JSON schema type is, in words.
_TYPE_WORDS = {"number": "a number", "integer": "a whole number", "boolean": "true or false", "string": "text",
               "array": "a list", "object": "a mapping of keys", "null": "nothing"}


def _describe(schema: dict) -> str:
    """One alternative of a ``oneOf`` in words: its description, else its type (and length, for a list)."""
    if schema.get("description"):
        return schema["description"]
    kind = schema.get("type")
    words = _TYPE_WORDS.get(kind, f"a {kind}") if kind else "a value of another form"
    if kind == "array" and schema.get("minItems") is not None and schema.get("minItems") == schema.get("maxItems"):
        item = _TYPE_WORDS.get((schema.get("items") or {}).get("type"), "value")
        words = f"a list of {schema['minItems']} {item.removeprefix('a ').removeprefix('an ')}s"
    return words


def _type_name(value) -> str:
    """The YAML kind of a config value, for messages."""
    if value is None:
        return "null (nothing)"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return {bool: "a boolean", int: "a whole number", float: "a number", str: "text", dict: "a mapping"}.get(
        type(value), type(value).__name__)


def _alternatives_message(err) -> str:
    """``oneOf``/``anyOf`` failed: what the field takes (its description, or each alternative) and what it got."""
    what = err.schema.get("description") or " or ".join(_describe(b) for b in err.schema.get(err.validator, ()))
    got = _type_name(err.instance)
    hint = " (text that reads as a number is read as one)" if isinstance(err.instance, str) else ""
    return f"{err.instance!r} ({got}) is not what this field takes: {what}; write a value of that form{hint}"


#: What each schema type takes, and an example, for the message on a string that is none of them.
_TYPE_REMEDY = {"integer": ("a whole number", "4"), "number": ("a number", "0.005 or 1e-8"),
                "boolean": ("true or false", "true")}


def non_finite(tree, path=()):
    """Path and value of the first NaN or infinite number in ``tree``, or None."""
    if isinstance(tree, float) and not math.isfinite(tree):
        return path, tree
    items = tree.items() if isinstance(tree, dict) else enumerate(tree) if isinstance(tree, list) else ()
    for key, value in items:
        found = non_finite(value, (*path, key))
        if found:
            return found
    return None
