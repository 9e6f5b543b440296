"""NetCDF input and output at the edges of the pipeline.

Every file this package writes is a labelled xarray dataset with:

- ``units`` and ``long_name`` on every data variable and coordinate (checked on write);
- global attributes ``roughcontact_version``, ``roughcontact_stage``, ``scene``,
  ``scene_parameters`` (the scene's config as JSON) and ``config_hash``;
- no timestamps, so a rerun with the same config gives byte-identical files;
- an atomic write: the data go to a temporary file in the target folder, which is
  renamed over the target only once complete, so an interrupted job never leaves a
  half-written file that looks valid.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from . import __version__

#: Stages whose files carry the ``roughcontact_stage`` attribute.
STAGES = ("surface", "representativity", "contact", "aggregate", "fit", "accuracy")


class InputFileError(ValueError):
    """An input NetCDF file is missing, unreadable, foreign or incomplete."""


def canonical_json(obj) -> str:
    """JSON with sorted keys and no whitespace variation: the basis of config hashes."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def config_hash(obj) -> str:
    """First 16 hex digits of the SHA-256 of :func:`canonical_json` of ``obj``."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:16]


def _check_labels(ds: xr.Dataset) -> None:
    missing = [
        name for name, var in list(ds.data_vars.items()) + list(ds.coords.items())
        if "units" not in var.attrs or "long_name" not in var.attrs
    ]
    if missing:
        raise ValueError(f"variables without units/long_name attrs: {', '.join(map(str, missing))}")


def provenance_attrs(stage: str, scene: str, scene_parameters: Mapping) -> dict:
    """Global attributes shared by every output file of ``stage`` for ``scene``."""
    if stage not in STAGES:
        raise ValueError(f"unknown stage {stage!r}; allowed: {', '.join(STAGES)}")
    return {
        "roughcontact_version": __version__,
        "roughcontact_stage": stage,
        "scene": scene,
        "scene_parameters": canonical_json(scene_parameters),
        "config_hash": config_hash(scene_parameters),
        "Conventions": "CF-1.8",
        "reference": "Yastrebov, Anciaux & Molinari, Phys. Rev. E 86, 035601 (2012)",
    }


def write_dataset(ds: xr.Dataset, path: str | os.PathLike, *, stage: str, scene: str,
                  scene_parameters: Mapping) -> Path:
    """Write ``ds`` atomically to ``path`` as NetCDF-4 with provenance attributes.

    Raises ``ValueError`` if a variable lacks ``units``/``long_name`` or holds NaN/inf
    where it is not allowed (float variables whose ``allow_nan`` attr is not set).
    """
    _check_labels(ds)
    for name, var in ds.data_vars.items():
        if np.issubdtype(var.dtype, np.floating) and not var.attrs.get("allow_nan", False):
            if not np.all(np.isfinite(var.values)):
                raise ValueError(f"variable {name!r} holds NaN or inf; refusing to write {path}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    out = ds.copy()
    out.attrs = {**ds.attrs, **provenance_attrs(stage, scene, scene_parameters)}
    # A job killed mid-write leaves its temporary file behind; only this job writes
    # this target, so its stale temporaries are safe to remove.
    for stale in path.parent.glob(f".{path.name}.*.tmp"):
        stale.unlink(missing_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        out.to_netcdf(tmp, engine="netcdf4", format="NETCDF4")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_dataset(path: str | os.PathLike, *, stage: str,
                 variables: Iterable[str] = ()) -> xr.Dataset:
    """Load a file this package wrote, checking that it is what ``stage`` expects.

    Raises :class:`InputFileError` naming the file and what is wrong: missing,
    not NetCDF (e.g. truncated), written by something else, of another stage, or
    lacking a required variable. The data are loaded into memory and the file closed.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError(f"{path}: file does not exist")
    try:
        with xr.open_dataset(path, engine="netcdf4") as handle:
            ds = handle.load()
    except Exception as exc:  # netCDF4 raises OSError, RuntimeError or ValueError
        raise InputFileError(
            f"{path}: not a readable NetCDF file (truncated or foreign?): {exc}"
        ) from None
    found = ds.attrs.get("roughcontact_stage")
    if found is None:
        raise InputFileError(f"{path}: not written by roughcontact (no 'roughcontact_stage' attribute)")
    if found != stage:
        raise InputFileError(f"{path}: holds stage {found!r}, expected {stage!r}")
    lacking = [v for v in variables if v not in ds.variables]
    if lacking:
        raise InputFileError(f"{path}: lacks required variable(s) {', '.join(lacking)}")
    return ds


def run_logged(log_path: str | os.PathLike, main) -> None:
    """Run ``main(logger)`` for a workflow script, logging to ``log_path``.

    Errors the user can act on (:class:`ValueError`, including :class:`InputFileError`
    and config errors) are logged as one clear line and end the process with status 1
    instead of a traceback from deep inside a library; anything else is logged with its
    traceback and re-raised.
    """
    logger = logging.getLogger("roughcontact")
    logger.setLevel(logging.INFO)
    logger.handlers.clear()
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(message)s")
    for handler in (logging.FileHandler(log_path, mode="w"), logging.StreamHandler(sys.stderr)):
        handler.setFormatter(fmt)
        logger.addHandler(handler)
    try:
        main(logger)
    except ValueError as exc:
        logger.error("%s", exc)
        sys.exit(1)
    except Exception:
        logger.exception("unexpected failure")
        raise
