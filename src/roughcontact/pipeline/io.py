"""NetCDF input and output at the edges of the pipeline.

Every file this package writes is a labelled xarray dataset with:

- ``units`` and ``long_name`` on every data variable and coordinate (checked on write);
- global attributes ``roughcontact_version``, ``roughcontact_stage``, ``scene``,
  ``scene_parameters`` (the scene's config as JSON) and ``config_hash``;
- strings (case names such as ``topography``, estimator labels) as CF character arrays
  ``name(..., name_strlen)`` of UTF-8 bytes, each string whole (:func:`_char_strings`), and
  ``units`` strings that UDUNITS-2 parses (:mod:`roughcontact.core.quantities`): ``cfchecks``
  (CF-1.8) finds no error in any of them;
- no timestamps, so a rerun with the same config gives byte-identical files;
- an atomic write: the data go to a temporary file in the target folder, which is
  renamed over the target only once complete, so an interrupted job never leaves a
  half-written file that looks valid.

Every other output (CSV, Markdown, figures) goes through the same helper,
:func:`roughcontact.core.files.atomic_output` (or ``write_text_atomic`` for text): the target either keeps
its previous complete content or gets the new complete content, and it gets the mode the
umask gives to a newly created file (``0o666 & ~umask``, e.g. 0644 under umask 022).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import resource
import sys
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import xarray as xr

from ..core.files import OutputFileError, atomic_output
from ..core.version import __version__

#: Stages whose files carry the ``roughcontact_stage`` attribute.
STAGES = ("surface", "representativity", "contact", "contact_batch", "aggregate", "fit", "accuracy", "kappa_gap")


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


def _string_names(ds: xr.Dataset) -> list[str]:
    """Names of the string variables of ``ds``; raises ``ValueError`` for an object array of non-strings."""
    names = []
    for name, var in ds.variables.items():
        if var.dtype.kind == "O" and not all(isinstance(v, str) for v in np.asarray(var.values).ravel()):
            raise ValueError(f"variable {name!r} holds objects that are not strings; cannot write it")
        if var.dtype.kind in "USO":
            names.append(str(name))
    return names


def _char_strings(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with every string variable encoded as a CF character array holding each string whole.

    CF (section 2.2) and its checker want strings as ``char`` arrays: ``name(..., name_strlen)``,
    UTF-8 bytes (attribute ``_Encoding``), not NetCDF-4 variable-length strings. The width
    ``name_strlen`` is the longest value's length in UTF-8 bytes, taken from all values: the
    width a variable read from NetCDF keeps in its encoding (``dtype <U3``, which ``xr.concat``
    keeps from the first dataset) is dropped, so a longer name of a later case is not cut
    ("frt2" -> "frt"), nor is a non-ASCII one ("Oberfläche": 11 bytes for 10 letters).

    A string dimension coordinate (``topography``, ``estimator``) is then a 2-D label variable,
    which CF reads as an auxiliary coordinate (section 6.1): every data variable along its
    dimension lists it in its ``coordinates`` attribute (with the auxiliary coordinates xarray
    lists), as CF requires. Its name stays that of its dimension, so xarray reads the file back
    with the strings as the dimension's index (CF only recommends other names for 2-D coordinates).
    """
    strings = _string_names(ds)
    for name in strings:
        var = ds.variables[name]
        for key in ("dtype", "char_dim_name", "_Encoding", "original_shape"):
            var.encoding.pop(key, None)
        var.encoding.update(dtype="S1", char_dim_name=f"{name}_strlen")
    labels = [name for name in strings if name in ds.dims]
    for name, var in ds.data_vars.items():
        var.encoding.pop("coordinates", None)
        listed = {c for c in labels if c in var.dims}
        if listed:
            listed |= {str(c) for c in ds.coords if c not in ds.dims and c != name and set(ds[c].dims) <= set(var.dims)}
            var.encoding["coordinates"] = " ".join(sorted(listed))
    return ds


def write_dataset(ds: xr.Dataset, path: str | os.PathLike, *, stage: str, scene: str,
                  scene_parameters: Mapping) -> Path:
    """Write ``ds`` atomically to ``path`` as NetCDF-4 with provenance attributes.

    Raises ``ValueError`` if a variable lacks ``units``/``long_name`` or holds NaN/inf
    where it is not allowed (float variables whose ``allow_nan`` attr is not set).
    """
    path = Path(path)
    out = _checked_output(ds, path, stage, scene, scene_parameters)
    with atomic_output(path) as tmp:
        _to_netcdf(out, tmp)
    return path


def write_groups(members: Mapping[str, tuple[xr.Dataset, Mapping]], path: str | os.PathLike, *, stage: str,
                 member_stage: str, scene: str, scene_parameters: Mapping) -> Path:
    """Write several datasets atomically as the groups of one NetCDF-4 file (a contact batch's cases).

    ``members`` maps each group's name to its dataset and that dataset's own ``scene_parameters``; each
    group is written as :func:`write_dataset` would write the dataset alone (the same checks and
    attributes, with stage ``member_stage``), so that :func:`read_dataset` with ``group=`` gives it back.
    The root group holds no variables: the provenance attributes of ``stage`` with ``scene_parameters``
    (the whole job's) and ``groups``, the members' names in order.
    """
    path = Path(path)
    outs = {name: _checked_output(ds, path, member_stage, scene, params) for name, (ds, params) in members.items()}
    root = xr.Dataset(attrs={**provenance_attrs(stage, scene, scene_parameters), "groups": " ".join(outs)})
    with atomic_output(path) as tmp:
        _to_netcdf(root, tmp)
        for name, out in outs.items():
            _to_netcdf(out, tmp, group=name)
    return path


def _checked_output(ds: xr.Dataset, path: Path, stage: str, scene: str, scene_parameters: Mapping) -> xr.Dataset:
    """``ds`` as it is written: labels and finite values checked, strings as characters, provenance attributes."""
    _check_labels(ds)
    for name, var in ds.data_vars.items():
        if np.issubdtype(var.dtype, np.floating) and not var.attrs.get("allow_nan", False):
            if not np.all(np.isfinite(var.values)):
                raise ValueError(f"variable {name!r} holds NaN or inf; refusing to write {path}")
    out = _char_strings(ds.copy())
    out.attrs = {**ds.attrs, **provenance_attrs(stage, scene, scene_parameters)}
    return out


def _to_netcdf(ds: xr.Dataset, tmp: Path, group: str | None = None) -> None:
    """``ds`` into the NetCDF-4 file ``tmp`` (a new file, or a group appended to it)."""
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", mode="w" if group is None else "a", group=group)
    except RuntimeError as exc:  # netCDF4's report of an I/O failure (e.g. "NetCDF: HDF error")
        raise OSError(str(exc)) from exc


def read_dataset(path: str | os.PathLike, *, stage: str,
                 variables: Iterable[str] = (), group: str | None = None) -> xr.Dataset:
    """Load a file this package wrote, checking that it is what ``stage`` expects.

    ``group``: one group of a file of :func:`write_groups` (listed in its root's ``groups``), whose own
    attributes are checked. Raises :class:`InputFileError` naming the file and what is wrong: missing,
    not NetCDF (e.g. truncated), written by something else, of another stage, lacking the group or a
    required variable. The data are loaded into memory and the file closed; :func:`lazy_dataset` reads
    only what is used.
    """
    with lazy_dataset(path, stage=stage, variables=variables, group=group) as handle:
        try:
            return handle.load()
        except Exception as exc:  # a header that reads but data that do not (a file cut short)
            raise InputFileError(_unreadable(Path(path), exc)) from None


@contextmanager
def lazy_dataset(path: str | os.PathLike, *, stage: str,
                 variables: Iterable[str] = (), group: str | None = None) -> Iterator[xr.Dataset]:
    """A file this package wrote, opened without reading its data and checked as :func:`read_dataset` checks it.

    Opening reads the file's header only: dimensions, global and variable attributes, each variable's
    name, dimensions and type, and the dimension coordinates (1-D: N values each). A data variable is
    read when its values are used, and only the part selected first: ``ds["heights"].isel(x=slice(a, b))``
    reads rows ``a .. b-1`` from the file (one hyperslab read of ``(b - a) ny`` values), so a check of
    a surface of 65536² (34 GB) reads what it looks at, not the field
    (:func:`roughcontact.pipeline.datasets.surface_grid`). Values read are decoded as :func:`read_dataset`
    decodes them (the same numbers, bit for bit).

    Use it as a context manager: the file is closed when the ``with`` block ends, so read what is needed
    inside it. Raises :class:`InputFileError` on opening as :func:`read_dataset` does (the same messages).
    """
    handle = _open_checked(Path(path), stage, variables, group)
    try:
        yield handle
    finally:
        handle.close()


def _unreadable(path: Path, exc: Exception) -> str:
    return f"{path}: not a readable NetCDF file (truncated or foreign?): {exc}"


def _open_checked(path: Path, stage: str, variables: Iterable[str], group: str | None) -> xr.Dataset:
    """The file opened lazily, its stage, group and required variables checked (closed again if refused)."""
    if path.is_dir():
        raise InputFileError(f"{path}: is a directory, not a file")
    if not path.is_file():
        raise InputFileError(f"{path}: file does not exist")
    try:
        if group is not None:
            with xr.open_dataset(path, engine="netcdf4") as root:
                if group not in root.attrs.get("groups", "").split():
                    raise InputFileError(f"{path}: holds no group {group!r}; its groups: "
                                         f"{root.attrs.get('groups') or 'none'}")
        handle = xr.open_dataset(path, engine="netcdf4", group=group)
    except InputFileError:
        raise
    except Exception as exc:  # netCDF4 raises OSError, RuntimeError or ValueError
        raise InputFileError(_unreadable(path, exc)) from None
    try:
        found = handle.attrs.get("roughcontact_stage")
        if found is None:
            raise InputFileError(f"{path}: not written by roughcontact (no 'roughcontact_stage' attribute)")
        if found != stage:
            raise InputFileError(f"{path}{'' if group is None else f' (group {group})'}: holds stage {found!r}, "
                                 f"expected {stage!r}")
        lacking = [v for v in variables if v not in handle.variables]
        if lacking:
            raise InputFileError(f"{path}: lacks required variable(s) {', '.join(lacking)}")
    except InputFileError:
        handle.close()
        raise
    return handle


#: The last line :func:`run_logged` writes to a finished job's log: the job process's exact
#: CPU time and peak memory. Snakemake's benchmark files sample a job every 30 s after its
#: first 15 s (snakemake/snakemake#851), so their ``cpu_time`` misses up to 30 s of CPU a
#: job; :mod:`roughcontact.pipeline.runcost` reads this line instead where a log has it.
JOB_COST_FORMAT = "job cost: {cpu:.3f} s CPU, {rss:.1f} MiB peak RSS"


JOB_COST_PATTERN = re.compile(r"job cost: (\d+\.\d+) s CPU, (\d+\.\d+) MiB peak RSS$")


def job_cost() -> tuple[float, float]:
    """This process's CPU time [s] (user + system, its waited-for children included) and peak RSS [MiB]."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime
    # ru_maxrss is in KiB on Linux, in bytes on macOS
    rss = max(own.ru_maxrss, kids.ru_maxrss) / (2**20 if sys.platform == "darwin" else 2**10)
    return cpu, rss


def run_logged(log_path: str | os.PathLike, main) -> None:
    """Run ``main(logger)`` for a workflow script, logging to ``log_path``.

    Errors the user can act on (:class:`ValueError`, including :class:`InputFileError`
    and config errors, and :class:`OutputFileError`: a full disk, a missing permission)
    are logged as one clear line and end the process with status 1
    instead of a traceback from deep inside a library; anything else is logged with its
    traceback and re-raised. A job that succeeds ends its log with :data:`JOB_COST_FORMAT`.
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
    except (ValueError, OutputFileError) as exc:
        logger.error("%s", exc)
        sys.exit(1)
    except Exception:
        logger.exception("unexpected failure")
        raise
    cpu, rss = job_cost()
    logger.info(JOB_COST_FORMAT.format(cpu=cpu, rss=rss))
