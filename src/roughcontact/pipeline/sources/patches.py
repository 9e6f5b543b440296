"""Patch sources: surfaces given as named, non-periodic patches (files), one case each.

A patch source's scene block (``topography``, ``array``, ...) lists files under ``files``, each a
case named by its key. Every patch source shares the rest of the pipeline: the case wildcard
``topography`` (file stem ``{topography}``, dataset dimension ``topography``), one ``topography``
rule whose script calls the source's :meth:`PatchSource.read` builder, the per-topography fit
(all patches pooled as one surface type), the patch figures, the free boundary by default (a
patch is not periodic: the periodic half-space would glue its opposite edges together) and a
load relative to each surface's rms slope. The generator's study keys (``surface``, ``grid``,
``seeds``, ``examples``) do not apply: a scene that sets them itself is told so, and the values
it inherits from ``defaults`` are dropped.

A source here subclasses :class:`PatchSource` and supplies ``name``/``key``, ``check_files``
(its block checked and expanded), ``reader_settings`` and ``read``. Its reader settings name it
(``"source": name``): the ``topography`` rule's script finds the builder by that key, and a
measured file's settings, which omit it (files made before the registry record them so), by default.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ...analysis.aggregate import TOPOGRAPHY_DIM, add_derived, combine_topographies
from ...analysis.aggregate.combine import GRID_RTOL
from ...surfaces.synthetic import nonperiodic_moments
from ..case import contact_effects
from ..config.checks import check_profile_contact, check_target_nodes
from ..config.files import ConfigError
from ..measured import MeasuredConfigError, drop_generator_keys
from .base import Source


class PatchSource(Source):
    """Named patches: cases named by the keys of the source block's ``files``."""

    case_keys = (TOPOGRAPHY_DIM,)
    stem = "{" + TOPOGRAPHY_DIM + "}"
    case_dims = (TOPOGRAPHY_DIM,)
    record_key = "topography"
    fit = "topographies"
    figures = "patches"
    surface_rules = ("topography",)
    default_boundary = "free"
    relative_load = True
    #: A file's own entry under ``files`` (path, unit, size, format, pixel size) is its own, by design.
    per_case_settings = tuple(f"{TOPOGRAPHY_DIM}.{key}" for key in ("path", "file_unit", "physical_size", "format",
                                                                   "pixel_size", "sha256"))

    @classmethod
    def check_scene(cls, name: str, scene: dict, delta: Mapping | None = None, *, check_files: bool = True) -> dict:
        try:
            out = drop_generator_keys(name, scene, delta, cls.key)
        except MeasuredConfigError as err:
            raise ConfigError(str(err)) from None
        if "contact" in out:
            out["contact"]["solver"].setdefault("boundary", cls.default_boundary)
        out[cls.key] = cls.check_files(name, out[cls.key], check_files)
        return out

    @classmethod
    def check_contact_files(cls, name: str, scene: Mapping) -> None:
        """What the files allow the validated contact block, before any job (the scene that runs): see
        :meth:`_check_profiles`, :meth:`_check_shapes`, and each effect's rules on every file's final load and grid
        (:meth:`_check_final_loads`, :meth:`_check_effect_grids`)."""
        cls._check_profiles(name, scene)
        cls._check_shapes(name, scene)
        effects = contact_effects(scene["contact"])
        cls._check_final_loads(name, scene, effects)
        cls._check_effect_grids(name, scene, effects)

    @classmethod
    def _check_profiles(cls, name: str, scene: Mapping) -> None:
        """Line scans (profiles, solved in plane strain) and maps are not mixed in one scene (the fit pools every
        case as one surface type, and a profile's contact length fraction is not a map's area fraction); a scene
        of line scans asks nothing the 1-D solver cannot do (:func:`~..config.checks.check_profile_contact`)."""
        grids = cls.grids(name, scene)
        lines = sorted(case for case, (shape, _) in grids.items() if len(shape) == 1)
        if not lines:
            return
        maps = sorted(set(grids) - set(lines))
        if maps:
            raise ConfigError(f"scene {name!r}, field '{cls.key}.files': mixes line scans ({', '.join(lines)}) and "
                              f"maps ({', '.join(maps)}); a profile's contact (plane strain, a length fraction) and a "
                              "map's are fitted apart: put the line scans in a scene of their own")
        check_profile_contact(name, scene["contact"], f"{cls.what}s {', '.join(lines)} are line scans")

    @classmethod
    def _check_effect_grids(cls, name: str, scene: Mapping, effects) -> None:
        """Each map's grid against each effect's rule (:meth:`~roughcontact.solver.effects.Effect.check_grid`; with
        adhesion the process zone ``E* rho^2 / w``, lengths in the scene's unit), from the files' headers."""
        if not effects:
            return
        e_star, unit = scene["contact"]["solver"]["e_star"], scene[cls.key]["unit"]
        for case, ((nx, ny), (dx, dy)) in cls.grids(name, scene).items():
            for effect in effects:
                effect.check_grid(e_star, (nx * dx, ny * dy), (nx, ny), f"{dx:.4g} x {dy:.4g} {unit}",
                                  cls._effect_failure(name, effect, f"{cls.what} {case!r}: "))

    @staticmethod
    def _effect_failure(name: str, effect, where: str):
        """``fail(field, message)`` of ``effect``'s rules on one file (``where`` starts the message)."""
        def fail(field, msg):
            raise ConfigError(f"scene {name!r}, field 'contact.effects.{effect.name}{field}': {where}{msg}")

        return fail

    @classmethod
    def _check_shapes(cls, name: str, scene: Mapping) -> None:
        """Pressure fields (``outputs.fields``) are stacked on one grid by the aggregate, so every map has one
        shape and pixel size (within :data:`GRID_RTOL`: round-off of unit conversions); a ``target_area`` spans
        enough nodes of each map."""
        contact = scene["contact"]
        if not (contact["outputs"]["fields"] or "target_area" in contact["load"]):
            return
        grids = cls.grids(name, scene)
        for case, (shape, _) in grids.items():
            check_target_nodes(name, contact["load"], math.prod(shape),
                               f"{cls.what} {case!r} ({' x '.join(str(n) for n in shape)})")
        shape, pixel = next(iter(grids.values()))
        for other_shape, other_pixel in grids.values():
            if contact["outputs"]["fields"] and (other_shape != shape or not np.allclose(
                    other_pixel, pixel, rtol=GRID_RTOL, atol=0.0)):
                listed = ", ".join(f"{c} {' x '.join(str(n) for n in shape)} points of "
                                   f"{' x '.join(f'{d:.6g}' for d in pixel)}" for c, (shape, pixel) in grids.items())
                raise ConfigError(f"scene {name!r}, field 'contact.outputs.fields': the {cls.what}s' grids differ "
                                  f"({listed}), and the aggregate stacks every file's pressure and gap fields on one "
                                  "grid: remove outputs.fields, or give files of one grid (a scene each)")

    @classmethod
    def _check_final_loads(cls, name: str, scene: Mapping, effects) -> None:
        """Every file's final load p0/E* = p_max h' (``relative_to: rms_slope``) against each effect's rule
        (:meth:`~roughcontact.solver.effects.Effect.check_final_load`), when an effect caps the pressure (the one
        bound on a final load): each file is read as its surface job reads it, its rms slope measured as there."""
        load, e_star = scene["contact"]["load"], scene["contact"]["solver"]["e_star"]
        if not any(e.pressure_cap is not None for e in effects) or "target_area" in load or \
                load["relative_to"] != "rms_slope":
            return
        p_max = load["p_max"]
        for case in cls.names(scene):
            try:
                surface = cls.read(cls.reader_settings(scene, case))
            except ValueError as err:
                raise ConfigError(f"scene {name!r}, field '{cls.key}.files.{case}': {err}") from None
            slope = nonperiodic_moments(surface.heights, surface.length)["rms_slope"]
            words = (f"every case's final load p0/E* = load.p_max x its rms slope; {cls.what} {case!r}: "
                     f"{p_max:g} x {slope:.4g} = {p_max * slope:.4g}")
            for effect in effects:
                effect.check_final_load(p_max * slope * e_star, e_star, words, cls._effect_failure(name, effect, ""))

    @classmethod
    def grids(cls, name: str, scene: Mapping) -> dict[str, tuple]:
        """The grid ``((nx, ny), (dx, dy))`` of each case's map, by name, from the checked files (before any job)."""
        raise NotImplementedError

    @classmethod
    def check_files(cls, scene: str, block: dict, check: bool) -> dict:
        """The source block with its ``files`` resolved and (with ``check``) each file checked now."""
        raise NotImplementedError

    @classmethod
    def names(cls, scene: Mapping) -> list[str]:
        return list(scene[cls.key]["files"])

    @classmethod
    def cases(cls, scene: Mapping, study: str) -> list[dict]:
        return [{TOPOGRAPHY_DIM: name} for name in cls.names(scene)]

    @classmethod
    def case_list(cls, scene: Mapping, study: str) -> list:
        return cls.names(scene)

    @classmethod
    def input_file(cls, scene: Mapping, name: str) -> str:
        """The file the ``topography`` job of case ``name`` reads (its input: an edited file is read again)."""
        return scene[cls.key]["files"][name]["path"]

    @classmethod
    def reader_settings(cls, scene: Mapping, name: str) -> dict:
        """Everything reading case ``name`` depends on (the job's params, recorded in its file), canonical."""
        raise NotImplementedError

    @classmethod
    def read(cls, settings: Mapping):
        """The surface of one case (a :class:`roughcontact.surfaces.topography.MeasuredSurface`) from its settings."""
        raise NotImplementedError

    @classmethod
    def plan(cls, scene: Mapping) -> list[str]:
        n_files = len(cls.names(scene))
        parts = []
        for study in ("representativity", "contact"):
            if study in scene:
                steps = scene[study]["load"]["n_steps"] if study == "contact" else 0
                parts.append(f"{study} of {n_files} {cls.what}(s)" +
                             (f" x {steps} load steps = {n_files * steps} solves" if steps else ""))
        return parts

    #: What one case is, in the plan's words.
    what = "file"

    @staticmethod
    def aggregate(datasets, paths, cases, kind="contact"):
        """The per-case datasets of a study stacked along ``topography`` (``cases``: the names)."""
        ds = combine_topographies(datasets, paths, expected=cases, kind=kind)
        return add_derived(ds) if kind == "contact" else ds

    @staticmethod
    def unbatch(path: str, ds) -> list[tuple]:
        """A representativity file's cases with their labels: one a file."""
        return [(ds, path)]
