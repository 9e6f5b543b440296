"""Config files read as Snakemake reads them: each file merged over the ones before, ``config/config.yaml`` first.

A file that is not YAML, or that repeats a key, is a :class:`ConfigError` naming its line and column
(:func:`check_config_files`).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path

import yaml

#: The workflow's own config file (the Snakefile's ``configfile:``), relative to the working directory.
SHIPPED_CONFIG = Path("config") / "config.yaml"


class ConfigError(ValueError):
    """The config asks for something the pipeline cannot do; the message says what."""


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
