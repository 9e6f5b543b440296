"""The pipeline's config: its files, its schema and the cross-field rules of each study block.

:mod:`.files` reads config files as Snakemake does, :mod:`.schema` applies the JSON schema (package data
``config.schema.yaml``), :mod:`.checks` the cross-field rules of each study block. Whole scenes are
validated, expanded into cases and planned one level up, in :mod:`roughcontact.pipeline.scenes`, which also
asks each scene's surface source (:mod:`roughcontact.pipeline.sources`); the sources use this package's
rules, so this package imports neither (``python -m roughcontact.pipeline.config`` runs
:func:`roughcontact.pipeline.scenes.main`).
"""

from .checks import (
    MEASURED_P_MAX,
)
from .files import (
    SHIPPED_CONFIG,
    ConfigError,
    check_config_files,
    load_config_files,
    read_config_file,
    update_config,
)
from .schema import (
    SCENE_STUDIES,
    SCHEMA_RESOURCE,
    STUDIES,
    coerce_strings,
    load_schema,
    merge,
    merge_scene,
)

__all__ = [
    "SHIPPED_CONFIG",
    "ConfigError",
    "read_config_file",
    "check_config_files",
    "update_config",
    "load_config_files",
    "STUDIES",
    "SCENE_STUDIES",
    "SCHEMA_RESOURCE",
    "load_schema",
    "coerce_strings",
    "merge",
    "merge_scene",
    "MEASURED_P_MAX",
]
