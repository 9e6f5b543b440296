"""The ``measured`` source: topography files read with SurfaceTopography (scene block ``topography``).

The block's checks and expansion live in :mod:`roughcontact.pipeline.measured` (files or glob,
reader settings, every file's header checked before any job); the files are read by
:func:`roughcontact.surfaces.topography.read_topography`. A patch source (:mod:`.patches`).
"""

from __future__ import annotations

from collections.abc import Mapping

from .. import measured
from ..config.files import ConfigError
from .base import register
from .patches import PatchSource


@register
class Measured(PatchSource):
    """Instrument files (x3p, NetCDF, text, ...), each a named, non-periodic patch."""

    name = "measured"
    key = "topography"
    what = "topography file"

    @classmethod
    def check_scene(cls, name: str, scene: dict, delta: Mapping | None = None, *, check_files: bool = True) -> dict:
        try:
            out = measured.check_measured_scene(name, scene, delta, check_files=check_files)
        except measured.MeasuredConfigError as err:
            raise ConfigError(str(err)) from None
        return out

    @classmethod
    def grids(cls, name: str, scene: Mapping) -> dict[str, tuple]:
        try:
            return measured.check_headers(name, scene)
        except measured.MeasuredConfigError as err:
            raise ConfigError(str(err)) from None

    @classmethod
    def reader_settings(cls, scene: Mapping, name: str) -> dict:
        return measured.reader_settings(scene, name)

    @classmethod
    def read(cls, settings: Mapping):
        from ...surfaces.topography import read_topography  # SurfaceTopography: only for measured scenes

        s = settings
        return read_topography(
            s["path"], unit=s["unit"], file_unit=s.get("file_unit"), physical_size=s.get("physical_size"),
            undefined=s["undefined"], detrend=s["detrend"], non_square=s["non_square"], channel=s["channel"],
            max_undefined=s["max_undefined"], format=s.get("format"),
        )
