"""Scenes of measured surfaces: the ``topography`` block of a scene, checked and expanded.

A scene with a ``topography`` block takes its surfaces from files (read by
:mod:`roughcontact.surfaces.topography` with SurfaceTopography) instead of the generator. Each file
is a case named by its key under ``files`` (or by its file stem when ``glob`` lists them),
and every study of the scene runs on each: representativity (eps of the heights' PDF) and
contact (the load steps), then the aggregate, the fit (all files pooled as one surface
type) and the figures. The scene's source (:mod:`roughcontact.pipeline.sources.measured`) calls
these checks; the rest of the pipeline asks the source. The studies' generator keys
(``surface``, ``grid``, ``seeds``, ``examples``) do not apply; a scene that sets them itself
is told so, and the values it inherits from ``defaults`` are dropped. Mixing generated and
measured cases in one scene is not supported.

Everything here runs when the config is validated, before Snakemake plans a job: a file
that does not exist, a glob that matches nothing, or a name that could be mistaken for a
generated case stops the run with a message naming the scene and the field.
"""

from __future__ import annotations

import copy
import glob as globbing
import re
from collections.abc import Mapping
from pathlib import Path

#: Allowed case names (they become file names under results/{scene}/).
NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")
#: Names that a generated case's or batch's file stem could take (``kl16_ks32_H0.8_s0``, ``kl16_H0.8``).
_GENERATED_STEM = re.compile(r"^kl[^_]*(_ks[^_]*)?_H[^_]*(_s\d+)?$")
#: Keys of a study block that only the generator uses.
GENERATOR_KEYS = ("surface", "grid", "seeds", "examples")
#: Per-file reader settings a ``files`` entry may override.
FILE_KEYS = ("file_unit", "physical_size", "format")
#: Reader settings shared by every file of the scene.
SCENE_KEYS = ("unit", "file_unit", "physical_size", "undefined", "detrend", "non_square", "channel", "max_undefined",
              "format")


class MeasuredConfigError(ValueError):
    """A ``topography`` block that cannot be run; the message names scene and field."""


def _fail(scene: str, field: str, msg: str):
    raise MeasuredConfigError(f"scene {scene!r}, field '{field}': {msg}")


def check_name(scene: str, field: str, name: str) -> None:
    """Stop unless ``name`` can name a case's files: :data:`NAME`'s letters, and not a generated case's stem."""
    if not NAME.match(name):
        _fail(scene, field, f"name {name!r} is not allowed: names start with a letter or digit and hold only "
                            "letters, digits, '.', '_' and '-' (they become file names)")
    if _GENERATED_STEM.match(name):
        _fail(scene, field, f"name {name!r} looks like a generated case's or batch's file "
                            "(kl.._ks.._H.._s.., kl.._H..); choose another name")


def _from_glob(scene: str, pattern: str, check: bool) -> dict[str, dict]:
    paths = sorted(p for p in globbing.glob(pattern) if Path(p).is_file())
    if not paths and check:
        _fail(scene, "topography.glob", f"{pattern!r} matches no file (relative to {Path.cwd()})")
    files = {}
    for path in paths:
        name = Path(path).stem
        check_name(scene, "topography.glob", name)
        if name in files:
            _fail(scene, "topography.glob", f"{files[name]['path']!r} and {path!r} have the same stem {name!r}; "
                                            "list them under topography.files with distinct names")
        files[name] = {"path": path}
    return files


def _check_path(scene: str, field: str, path: str) -> None:
    """A regular file at ``path``, or an error saying what is there instead."""
    where = Path(path)
    if where.is_file():
        return
    if where.is_dir():
        what = "is a directory, not a file: name one file in it, or list them with topography.glob"
    elif where.exists():
        what = "is not a regular file (a device, pipe or socket): name a topography file"
    else:
        what = f"does not exist (paths are relative to {Path.cwd()})"
    _fail(scene, field, f"{path!r} {what}")


def topography_files(scene: str, block: Mapping, check: bool = True) -> dict[str, dict]:
    """The files of a ``topography`` block: ``{name: {"path": ..., [file_unit, physical_size]}}``.

    Sorted by name. With ``check``, every path must exist (and a glob match something) now, so
    that a typo fails before any job; only the scene that runs is checked, so that a missing
    file of another scene does not stop it.
    """
    if "glob" in block:
        files = _from_glob(scene, block["glob"], check)
    else:
        files = {}
        for name, entry in block["files"].items():
            check_name(scene, f"topography.files.{name}", name)
            files[name] = {"path": entry} if isinstance(entry, str) else dict(entry)
    for name, entry in files.items():
        if check:
            _check_path(scene, f"topography.files.{name}", entry["path"])
    return dict(sorted(files.items()))


def drop_generator_keys(name: str, scene: dict, delta: Mapping | None, key: str = "topography") -> dict:
    """A copy of ``scene`` without the generator's study keys; one the scene sets itself is an error.

    ``delta`` is the scene as written; ``key`` the block whose files are the cases (``topography``,
    ``array``), named in the error.
    """
    out = copy.deepcopy(scene)
    delta = delta or {}
    for study in ("representativity", "contact"):
        if study not in out:
            continue
        for field in GENERATOR_KEYS:
            if field in (delta.get(study) or {}):
                article = "an" if key[0] in "aeiou" else "a"
                _fail(name, f"{study}.{field}", f"not used with {article} {key} block (the cases are its files); "
                                                "remove it")
            out[study].pop(field, None)
    return out


def check_measured_scene(name: str, scene: dict, delta: Mapping | None = None, *, check_files: bool = True) -> dict:
    """A validated scene with a ``topography`` block, expanded: files resolved, generator keys dropped.

    ``delta`` is the scene as written; a generator key it sets itself is an error (it would be
    ignored). ``check_files``: whether the files must exist (see :func:`topography_files`).
    The contact solver's ``boundary`` defaults to ``free``: a measured patch is not periodic,
    and the periodic half-space would glue its opposite edges together.
    """
    out = drop_generator_keys(name, scene, delta)
    if "contact" in out:
        out["contact"]["solver"].setdefault("boundary", "free")
    out["topography"]["files"] = topography_files(name, out["topography"], check_files)
    out["topography"].pop("glob", None)
    if check_files:
        check_headers(name, out)
    return out


def check_headers(name: str, scene: Mapping) -> dict[str, tuple]:
    """Every file's header checked now (:func:`roughcontact.surfaces.topography.check_header`), before any job;
    the grid ``((nx, ny), (dx, dy))`` of each file's map, by case name.

    A file SurfaceTopography cannot read, a missing channel, unit or size, or a map the scene
    refuses fails here with the file, what is wrong and the remedy, instead of in its job.
    """
    from ..surfaces.topography import TopographyError, check_header  # SurfaceTopography: only for measured scenes

    block = scene["topography"]
    defaults = {key: block[key] for key in SCENE_KEYS if key in block}
    grids = {}
    for file in block["files"]:
        settings = {**defaults, **reader_settings(scene, file)}
        path = settings.pop("path")
        try:
            grids[file] = check_header(path, **settings)
        except TopographyError as err:
            _fail(name, f"topography.files.{file}", str(err))
    return grids


def topography_names(scene: Mapping) -> list[str]:
    """The case names of a validated measured scene, sorted."""
    return list(scene["topography"]["files"])


def reader_settings(scene: Mapping, name: str) -> dict:
    """Everything reading file ``name`` depends on (a topography job's params), canonical.

    The file's own ``file_unit`` / ``physical_size`` override the scene's.
    """
    block = scene["topography"]
    entry = block["files"][name]
    settings = {key: block[key] for key in SCENE_KEYS if key in block}
    settings.update({key: entry[key] for key in FILE_KEYS if key in entry})
    settings["path"] = entry["path"]
    return {key: settings[key] for key in sorted(settings)}
