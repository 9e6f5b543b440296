"""The ``array`` source: surfaces from plain NumPy ``.npy`` files with their pixel size (scene block ``array``).

::

    array:
      files:
        patch-1: {path: data/array/patch-1.npy, pixel_size: 0.5}       # dx = dy
        patch-2: {path: data/array/patch-2.npy, pixel_size: [0.5, 0.25]}  # dx (axis 0), dy (axis 1)
      unit: um            # the length unit of the heights and pixel sizes, and the study's
      pixel_size: 0.5     # optional: for files that give none

Each file holds one 2-D array of finite real heights ``h[i, j]`` at ``x = i dx``, ``y = j dy``, in
``unit``; it is used as it is (no levelling, no filling, no cropping: prepare the array before
saving it). A plain array carries no instrument metadata, so it is taken as what a measurement
is: a non-periodic patch (:mod:`.patches`), solved with the scene's ``contact.solver.boundary``
(``free`` unless the scene sets ``periodic``, e.g. for an array that is one period of a periodic
surface), its load relative to its rms slope, and fitted and drawn as measured files are.

Every file is checked when the scene is validated, before any job: it must exist, be a ``.npy``
file NumPy reads without pickles, hold a 2-D real array of at least 4 x 4 finite values that are
not all equal, and have a positive pixel size; each error names the scene, the field, the file and the remedy.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ...core.files import file_sha256
from ...surfaces.scales import scale_problem
from ..config.files import ConfigError
from ..measured import MeasuredConfigError, check_name
from .base import register
from .patches import PatchSource

#: The first bytes of every .npy file.
NPY_MAGIC = b"\x93NUMPY"

#: Fewest points along each axis (the rms slope and curvature take differences inside the patch).
MIN_POINTS = 4


class ArrayError(ValueError):
    """A ``.npy`` file that cannot be used as a surface; the message names the file and the remedy."""


def check_pixel_size(path: str, pixel_size) -> tuple[float, float]:
    """``(dx, dy)`` of file ``path``, both positive and finite (``ArrayError`` otherwise)."""
    dx, dy = pixel_sizes(pixel_size)
    if not (np.isfinite([dx, dy]).all() and dx > 0 and dy > 0):
        raise ArrayError(f"{path!r}: pixel_size {pixel_size} must be positive and finite: give the spacing of the "
                         "points in the block's unit, one number (dx = dy) or [dx, dy]")
    return dx, dy


def load_heights(path: str, pixel_size, *, mmap: bool = False) -> np.ndarray:
    """The heights of ``path``, checked (``ArrayError`` naming the file and the remedy otherwise)."""
    pixel = check_pixel_size(path, pixel_size)
    where = Path(path)
    if where.suffix != ".npy":
        raise ArrayError(f"{path!r} is not a .npy file: save the heights with numpy.save(path, heights), "
                         "which writes a .npy file, and name that file")
    if not where.is_file():
        what = ("is a directory, not a file" if where.is_dir()
                else f"does not exist (paths are relative to {Path.cwd()})")
        raise ArrayError(f"{path!r} {what}: name an existing .npy file")
    with open(where, "rb") as fh:
        magic = fh.read(len(NPY_MAGIC))
    if magic != NPY_MAGIC:
        what = ("is empty" if not magic
                else "does not start as a .npy file does (\\x93NUMPY): it is text or another format")
        raise ArrayError(f"{path!r} {what}: save the heights with numpy.save(path, heights) and name that file "
                         "(a text or instrument file goes in a topography block)")
    try:
        h = np.load(where, mmap_mode="r" if mmap else None, allow_pickle=False)
    except (ValueError, OSError, EOFError) as err:
        raise ArrayError(f"{path!r} is not a .npy file NumPy can read without pickles ({err}): write it with "
                         "numpy.save(path, heights) from a plain float array") from None
    if h.ndim != 2 or min(h.shape) < MIN_POINTS:
        raise ArrayError(f"{path!r} holds an array of shape {h.shape}, not a 2-D height map of at least "
                         f"{MIN_POINTS} x {MIN_POINTS} points: save the map h[i, j] (x along axis 0, y along axis 1)")
    if h.dtype.kind not in "fiu":
        raise ArrayError(f"{path!r} holds {h.dtype} values, not real numbers: save heights.astype(float)")
    bad = int(np.size(h) - np.count_nonzero(np.isfinite(h)))
    if bad:
        raise ArrayError(f"{path!r}: {bad} of {h.size} heights are NaN or infinite: fill or crop them before "
                         "saving (a plain array has no undefined-point handling; a measured file with undefined "
                         "points can go in a topography block instead)")
    if not np.ptp(h) > 0:
        raise ArrayError(f"{path!r}: every height is {h.flat[0]}: a flat map has no roughness to study; "
                         "save the surface's heights")
    problem = scale_problem(h, pixel, float(np.finfo(h.dtype).eps) if h.dtype.kind == "f" else 0.0)
    if problem:
        raise ArrayError(f"{path!r}: {problem}")
    return h


def pixel_sizes(pixel_size) -> tuple[float, float]:
    """``(dx, dy)`` from one number or a pair."""
    if isinstance(pixel_size, (list, tuple)):
        return float(pixel_size[0]), float(pixel_size[1])
    return float(pixel_size), float(pixel_size)


@register
class Array(PatchSource):
    """Heights from ``.npy`` files, each a named, non-periodic patch."""

    name = "array"
    key = "array"
    what = "array file"

    @classmethod
    def check_files(cls, scene: str, block: dict, check: bool) -> dict:
        out = dict(block)
        out["files"] = {}
        for name, entry in sorted(block["files"].items()):
            field = f"array.files.{name}"
            try:
                check_name(scene, field, name)
            except MeasuredConfigError as err:
                raise ConfigError(str(err)) from None
            entry = {"path": entry} if isinstance(entry, str) else dict(entry)
            size = entry.get("pixel_size", block.get("pixel_size"))
            if size is None:
                raise ConfigError(f"scene {scene!r}, field '{field}.pixel_size': {entry['path']!r} has no pixel size: "
                                  "give pixel_size (one number, or [dx, dy]) in the file's entry or the array block")
            try:
                entry["pixel_size"] = list(check_pixel_size(entry["path"], size))
                if check:
                    load_heights(entry["path"], entry["pixel_size"], mmap=True)
            except ArrayError as err:
                raise ConfigError(f"scene {scene!r}, field '{field}': {err}") from None
            out["files"][name] = entry
        out.pop("pixel_size", None)
        return out

    @classmethod
    def grids(cls, name: str, scene: Mapping) -> dict[str, tuple]:
        return {case: (tuple(np.load(entry["path"], mmap_mode="r", allow_pickle=False).shape),
                       tuple(pixel_sizes(entry["pixel_size"]))) for case, entry in scene[cls.key]["files"].items()}

    @classmethod
    def reader_settings(cls, scene: Mapping, name: str) -> dict:
        entry = scene[cls.key]["files"][name]
        settings = {"path": entry["path"], "pixel_size": list(entry["pixel_size"]), "source": cls.name,
                    "unit": scene[cls.key]["unit"]}
        return {key: settings[key] for key in sorted(settings)}

    @classmethod
    def read(cls, settings: Mapping):
        from ...surfaces.topography import MeasuredSurface

        path, (dx, dy) = settings["path"], pixel_sizes(settings["pixel_size"])
        h = np.ascontiguousarray(load_heights(path, (dx, dy)), dtype=np.float64)
        (nx, ny) = h.shape
        lx = nx * dx
        ly = lx if nx == ny and dx == dy else ny * dy
        info = {"file": path, "sha256": file_sha256(path), "reader": "numpy.load", "unit": settings["unit"],
                "pixel_size": [dx, dy], "shape": [nx, ny]}
        return MeasuredSurface(heights=h, lengths=(lx, ly), unit=settings["unit"], info=info)
