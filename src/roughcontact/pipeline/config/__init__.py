"""Scenes: validate the pipeline's config and expand it into cases.

:mod:`.files` reads config files as Snakemake does, :mod:`.schema` applies the JSON schema (package data
``config.schema.yaml``), :mod:`.checks` the cross-field rules of each study block, and :mod:`.scenes`
validates whole scenes, expands them into cases and prints the plan (``python -m roughcontact.pipeline.config``).
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
from .scenes import (
    BATCH_STEM,
    CASE_STEM,
    SCENE_NAME,
    Case,
    batches,
    cases,
    plan_summary,
    validate_config,
    validate_scene,
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
    "CASE_STEM",
    "BATCH_STEM",
    "SCENE_NAME",
    "Case",
    "validate_scene",
    "validate_config",
    "batches",
    "cases",
    "plan_summary",
]
