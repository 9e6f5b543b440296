"""Measured topography files, read with SurfaceTopography into the contact solver's height array.

Every file format is read by SurfaceTopography (``open_topography`` picks the reader from the
file's contents); this module only checks that the data suits the solver (one 2-D uniform map,
any number of points along each axis, pixels of any aspect ratio; or one line scan, uniform or not,
prepared by :mod:`roughcontact.surfaces.linescan` for the 1-D solver), converts it to the study's
length unit and prepares it:

1. **read** the channel, in the file's own unit and size where it carries them (the scene's
   ``file_unit`` / ``physical_size`` are only used where it does not), then convert heights and
   sizes to ``unit`` with SurfaceTopography's ``to_unit``;
2. **detrend** on the full measured area, with the trend fitted to the measured (defined) points
   only. Detrending before filling keeps imputed values out of the fit, and places the filled
   points on the trend surface: filling a tilted scan with its global mean first would put
   spurious pits and peaks in the holes, which would then bias the fitted plane and become
   contact spots. Fitting before cropping uses every measured point for the instrument's tilt or
   form (a property of the whole scan), rather than re-levelling the cropped patch by itself;
3. **fill** the undefined (not measured) points of the detrended heights ("mean" or "harmonic");
4. **crop** to the centred largest square block when the map is not square and the scene asks for
   it (``non_square: crop``); by default (``keep``) the whole rectangular map is used.

Every failure raises :class:`TopographyError`, whose message starts with the file path, says
what is wrong and what is allowed, and names the config field (``topography.<key>``) to change.
"""

from __future__ import annotations

import functools
import numbers
import os
import warnings
import zipfile
from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np

from ..core.files import file_sha256
from .linescan import MIN_PROFILE_POINTS, prepare_profile
from .scales import checked_scales, length_problem

if TYPE_CHECKING:
    from SurfaceTopography import Topography

#: The study's allowed length units (CF/UDUNITS spellings: micrometres are "um", not "µm").
LENGTH_UNITS = ("m", "mm", "um", "nm")
#: What to do with points the instrument did not measure (config ``topography.undefined``).
UNDEFINED_MODES = ("reject", "mean", "harmonic")
#: SurfaceTopography detrend modes offered (config ``topography.detrend``); "none" keeps the heights.
DETREND_MODES = ("none", "center", "height", "curvature")
#: What to do with a map that is not square (config ``topography.non_square``): use it whole
#: (``keep``, the default), the centred largest square block (``crop``) or refuse it (``reject``).
NON_SQUARE_MODES = ("keep", "crop", "reject")
#: SurfaceTopography formats whose reader accepts a file by its size alone: random bytes of 7 sizes
#: (5000 to 131072) named .bin, .x3p and .txt were all read as HGT elevation maps when their size
#: was a square number of 16-bit values, and by no other reader (SurfaceTopography 1.27, 2026-11-25).
CONTENT_BLIND = ("hgt",)
#: Default largest fraction of undefined (not measured) points a file may have (config
#: ``topography.max_undefined``): above it the filled map would be mostly invented.
MAX_UNDEFINED = 0.5
#: Fraction of undefined points above which the scene's log warns (the filled points are recorded).
WARN_UNDEFINED = 0.1
#: Largest relative difference |dx/dy - 1| of the pixel sizes still taken as square (the cell's
#: sides are then recorded as one length, as for a generated surface).
PIXEL_RTOL = 1e-6


@functools.cache
def surface_topography() -> SimpleNamespace:
    """The parts of SurfaceTopography this module uses, imported when a file is first read or checked.

    Imported here rather than at the top because SurfaceTopography imports matplotlib: the library's
    layers import without matplotlib and snakemake (``tests/test_library_alone.py``), and only a
    measured scene reads files.
    """
    try:
        from SurfaceTopography import Topography
        from SurfaceTopography.Exceptions import CannotDetectFileFormat, CorruptFile
        from SurfaceTopography.IO import open_topography, readers
        from SurfaceTopography.Support.UnitConversion import get_unit_conversion_factor, mangle_length_unit_ascii
    except ImportError as err:  # the library installed without its `topography` extra
        raise ImportError(f"reading topography files needs SurfaceTopography ({err}): install it with "
                          "`pip install 'roughcontact[topography]'`") from err

    return SimpleNamespace(Topography=Topography, CannotDetectFileFormat=CannotDetectFileFormat,
                           CorruptFile=CorruptFile, open_topography=open_topography, readers=readers,
                           get_unit_conversion_factor=get_unit_conversion_factor,
                           mangle_length_unit_ascii=mangle_length_unit_ascii)


class TopographyError(ValueError):
    """A topography file that cannot be used; the message names the file and what is allowed."""


@dataclass(frozen=True)
class MeasuredSurface:
    """A measured surface on the contact solver's grid.

    Attributes
    ----------
    heights : np.ndarray
        Heights, float64, shape (nx, ny), C-contiguous, finite everywhere, in ``unit``; axis 0 is
        the file's x axis, axis 1 its y axis. A line scan's: shape (n,), on a uniform grid.
    lengths : (float, float) or (float,)
        Sides (Lx, Ly) of the patch, in ``unit``; pixels ``dx = Lx / nx``, ``dy = Ly / ny``. A
        profile's: its length (L,), pixel ``L / n``.
    unit : str
        The study's length unit, one of :data:`LENGTH_UNITS`.
    info : dict
        JSON-serialisable provenance (file, sha256, reader, channel, units, sizes, steps applied).
    """

    heights: np.ndarray
    lengths: tuple[float, float]
    unit: str
    info: dict

    @property
    def square(self) -> bool:
        """Whether the cell is square with square pixels (nx == ny and |dx/dy - 1| <= PIXEL_RTOL); a profile's
        one length is one side (True)."""
        if self.dimension == 1:
            return True
        (nx, ny), (lx, ly) = self.heights.shape, self.lengths
        return nx == ny and abs(lx / ly - 1.0) <= PIXEL_RTOL

    @property
    def dimension(self) -> int:
        """1 for a profile (a line scan), 2 for a map."""
        return self.heights.ndim

    @property
    def length(self) -> float | tuple[float, float]:
        """The solver's ``length`` argument: the side L of a square cell, else the pair (Lx, Ly)."""
        return self.lengths[0] if self.square else self.lengths


def read_topography(path, *, unit: str, file_unit: str | None = None,
                    physical_size: tuple[float, float] | None = None, undefined: str = "reject",
                    detrend: str = "none", non_square: str = "keep", channel: int = 0,
                    max_undefined: float = MAX_UNDEFINED, format: str | None = None) -> MeasuredSurface:
    """Read a measured topography file into a height array in the study's unit.

    Parameters
    ----------
    path : str or os.PathLike
        Topography file in any format SurfaceTopography reads (detected from its contents).
    unit : str
        The study's length unit (one of :data:`LENGTH_UNITS`); heights and length are converted to it.
    file_unit : str, optional
        Length unit of the heights and sizes of a file that carries none (one of :data:`LENGTH_UNITS`).
        Ignored (and recorded so in ``info["ignored"]``) when the file has a unit.
    physical_size : (float, float) or (float,), optional
        Size (Lx, Ly) along the array's axes 0 and 1 (a line scan: (L,)), in the file's unit, for a
        file that carries none. Ignored (and recorded so) when the file has a size.
    undefined : str
        Undefined (not measured) points: "reject", "mean" (the mean of the defined detrended
        heights) or "harmonic" (SurfaceTopography's harmonic interpolation).
    detrend : str
        "none", "center" (mean), "height" (best plane) or "curvature" (best quadric), fitted to the
        defined points of the full measured area, before filling and cropping.
    non_square : str
        "keep" a map with nx != ny whole, "crop" it to the centred min(nx, ny) square, or "reject" it.
    channel : int
        Index of the data channel in a multi-channel file (0: the first).
    max_undefined : float
        Largest accepted fraction of undefined points, in [0, 1] (recorded: ``info["undefined_fraction"]``).
    format : str, optional
        SurfaceTopography's name of the file's format (e.g. "x3p"). Without it the format is
        detected from the contents and must be one that uses the file's extension.

    Returns
    -------
    MeasuredSurface
        Heights (nx, ny) and sides (Lx, Ly) in ``unit`` (a line scan: heights (n,) on a uniform grid
        and (L,), :mod:`~.linescan`), and provenance ``info``.

    Raises
    ------
    TopographyError
        On bad arguments and on any file that is missing, unreadable or unsuitable.
    """
    name = os.fspath(path)
    physical_size = _check_arguments(name, unit, file_unit, physical_size, undefined, detrend, non_square, channel)
    _check_fraction(name, max_undefined)
    info = {"file": name, "sha256": _sha256(name)}
    topo = _load(name, info, unit=unit, file_unit=file_unit, physical_size=physical_size, channel=channel,
                 fmt=_check_format(name, format))
    if isinstance(topo, _LineScan):  # non_square does not apply
        return _profile(name, topo, info, unit, undefined=undefined, detrend=detrend, max_undefined=max_undefined)
    dx, dy = _check_grid(name, topo, non_square)
    heights = _detrend_and_fill(name, topo, info, undefined=undefined, detrend=detrend, max_undefined=max_undefined)
    heights, info["crop"] = _crop(heights) if non_square == "crop" else (heights, None)
    nx, ny = checked_scales(name, heights, (dx, dy), TopographyError).shape
    lx = nx * dx
    ly = lx if nx == ny and abs(dx / dy - 1.0) <= PIXEL_RTOL else ny * dy  # square: one side, exactly
    return MeasuredSurface(heights=heights, lengths=(lx, ly), unit=unit, info=info)


def _profile(name, scan, info, unit, **settings) -> MeasuredSurface:
    """A line scan prepared for the 1-D solver (:func:`~.linescan.prepare_profile`), its scales checked."""
    heights, length = prepare_profile(name, scan.x, scan.heights, scan.undefined, uniform=scan.uniform,
                                      length=scan.length, info=info, error=TopographyError, **settings)
    checked_scales(name, heights, (length / heights.size,), TopographyError)
    return MeasuredSurface(heights=np.ascontiguousarray(heights), lengths=(length,), unit=unit, info=info)


def check_header(path, *, unit: str, file_unit: str | None = None,
                 physical_size: tuple[float, float] | None = None, undefined: str = "reject",
                 detrend: str = "none", non_square: str = "keep", channel: int = 0,
                 max_undefined: float = MAX_UNDEFINED, format: str | None = None) -> tuple:
    """The checks of :func:`read_topography` that need only the file's header, without its heights; the grid
    ``((nx, ny), (dx, dy))`` of the map it would return (after ``non_square: crop``), in ``unit``; a line
    scan's ``((n,), (dx,))`` (a non-uniform one's as it will be resampled), with at least
    :data:`~.linescan.MIN_PROFILE_POINTS` points.

    Readable by SurfaceTopography, the channel present and holding a 2-D uniform height map, a unit
    and a size (the file's or the scene's), the unit convertible to ``unit``, the sizes positive,
    and a square map when ``non_square`` is ``reject``. Run when a scene is checked, before any job
    is planned (a few tens of ms a file); raises :class:`TopographyError` as the reader would.
    """
    name = os.fspath(path)
    physical_size = _check_arguments(name, unit, file_unit, physical_size, undefined, detrend, non_square, channel)
    _check_fraction(name, max_undefined)
    fmt = _check_format(name, format)
    if not os.path.isfile(name):
        raise TopographyError(f"{name}: the topography file does not exist (or is not a regular file)")
    with warnings.catch_warnings():
        # as in _load: the NetCDF reader's close warns about its memory map, harmlessly
        warnings.filterwarnings("ignore", message="Cannot close a netcdf_file", category=RuntimeWarning)
        shape, pixel = _check_header(name, _open(name, fmt), unit, file_unit, physical_size, non_square, channel)
    if len(shape) == 1:  # a line scan: (n,) and (dx,); non_square does not apply
        return shape, pixel
    return ((min(shape),) * 2 if non_square == "crop" else shape), pixel


def _check_header(name, reader, unit, file_unit, physical_size, non_square, channel) -> tuple:
    """:func:`check_header` on an open ``reader``, which it closes."""
    try:
        chan = _channel(name, reader, channel)
        kwargs = _metadata(name, chan, {}, file_unit=file_unit, physical_size=physical_size)
        file_unit = surface_topography().mangle_length_unit_ascii(kwargs.get("unit", chan.unit))
        try:
            factor = surface_topography().get_unit_conversion_factor(file_unit, unit)
        except ValueError as err:
            raise TopographyError(f"{name}: the file's unit {file_unit!r} cannot be converted to {unit!r} "
                                  f"({err})") from err
        if chan.dim == 1:
            return _check_profile_header(name, chan, kwargs, factor)
        (nx, ny), sizes = chan.nb_grid_pts, kwargs.get("physical_sizes", chan.physical_sizes)
        pixel = _check_grid(name, _Header((nx, ny), tuple(float(v) * factor for v in sizes), unit), non_square)
        return (int(nx), int(ny)), pixel
    finally:
        _close(reader)


def _check_profile_header(name, chan, kwargs, factor) -> tuple:
    """A line scan's header: enough points, a positive size; its grid ``((n,), (dx,))`` in the study's unit
    (a non-uniform scan's as :func:`roughcontact.surfaces.linescan.uniform_profile` will resample it)."""
    (n,), (size,) = chan.nb_grid_pts, kwargs.get("physical_sizes", chan.physical_sizes)
    size = float(size) * factor
    if n < MIN_PROFILE_POINTS:
        raise TopographyError(f"{name}: the line scan has {n} points; a profile needs at least {MIN_PROFILE_POINTS} "
                              "to be solved and fitted (its contact length moves in steps of 1/n): measure a longer "
                              "or denser scan")
    if not (np.isfinite(size) and size > 0):
        raise TopographyError(f"{name}: the scan's length {size} is not positive and finite")
    # a non-uniform scan's size is its measured range, over n - 1 spacings
    dx = size / n if chan.is_uniform else size / (n - 1)
    problem = length_problem((n,), (dx,))
    if problem:
        raise TopographyError(f"{name}: {problem}; check the file's unit and size (topography.file_unit, "
                              "physical_size) or choose another topography.unit")
    return (int(n),), (dx,)


@dataclass(frozen=True)
class _LineScan:
    """A line scan as read (:func:`_load`), in the study's unit: positions, heights, undefined points."""

    x: np.ndarray
    heights: np.ndarray
    undefined: np.ndarray
    uniform: bool
    length: float | None


@dataclass(frozen=True)
class _Header:
    """What :func:`_check_grid` reads of a topography: grid, sizes and unit."""

    nb_grid_pts: tuple[int, int]
    physical_sizes: tuple[float, float]
    unit: str


def _check_arguments(name, unit, file_unit, physical_size, undefined, detrend, non_square, channel):
    """Validate the reader settings; returns ``physical_size`` as a (Lx, Ly) float tuple or None."""
    choices = {"unit": (unit, LENGTH_UNITS), "undefined": (undefined, UNDEFINED_MODES),
               "detrend": (detrend, DETREND_MODES), "non_square": (non_square, NON_SQUARE_MODES)}
    if file_unit is not None:
        choices["file_unit"] = (file_unit, LENGTH_UNITS)
    for key, (value, allowed) in choices.items():
        if value not in allowed:
            raise TopographyError(f"{name}: topography.{key} {value!r} is not allowed; use one of {', '.join(allowed)}")
    if isinstance(channel, bool) or not isinstance(channel, int | np.integer) or channel < 0:
        raise TopographyError(f"{name}: topography.channel {channel!r} is not allowed; use an integer >= 0")
    if physical_size is None:
        return None
    try:
        size = tuple(float(s) for s in physical_size)
    except (TypeError, ValueError):
        size = ()
    if len(size) not in (1, 2) or not all(np.isfinite(s) and s > 0 for s in size):
        raise TopographyError(f"{name}: topography.physical_size {physical_size!r} is not allowed; "
                              "use two finite numbers > 0, (Lx, Ly) in the file's unit ([L] for a line scan)")
    return size


def _check_fraction(name, max_undefined) -> None:
    if isinstance(max_undefined, bool) or not isinstance(max_undefined, numbers.Real) \
            or not 0.0 <= float(max_undefined) <= 1.0:
        raise TopographyError(f"{name}: topography.max_undefined {max_undefined!r} is not allowed; use a number "
                              "in [0, 1] (the largest accepted fraction of undefined points)")


def _sha256(name: str) -> str:
    """Hex SHA-256 of the file's bytes; a missing or unreadable file is a TopographyError."""
    if not os.path.isfile(name):
        raise TopographyError(f"{name}: the topography file does not exist (or is not a regular file)")
    try:
        return file_sha256(name)
    except OSError as err:
        raise TopographyError(f"{name}: the topography file cannot be read ({err})") from err


def _load(name, info, *, unit, file_unit, physical_size, channel, fmt=None) -> Topography:
    """Read one channel with SurfaceTopography; returns a plain Topography in ``unit``.

    Undefined points (masked by the reader, or non-finite) are masked in the result. ``info`` gets
    the reader's provenance. The reader is closed before returning.
    """
    with warnings.catch_warnings():
        # SurfaceTopography's NetCDF reader closes scipy's memory-mapped file while its variables
        # still exist, which only warns; the heights have been copied by then.
        warnings.filterwarnings("ignore", message="Cannot close a netcdf_file", category=RuntimeWarning)
        reader = _open(name, fmt)
        try:
            chan = _channel(name, reader, channel)
            kwargs = _metadata(name, chan, info, file_unit=file_unit, physical_size=physical_size)
            raw = chan.topography(**kwargs)
            if raw.dim == 1:
                return _line_scan(name, raw, info, unit, reader, chan)
            if not raw.is_uniform:
                raise TopographyError(f"{name}: channel {chan.name!r} is not a 2-D uniform map")
            scaled = _to_unit(name, raw, unit)
            heights = scaled.heights()
            # A copy, as the reader may hand out views of a file it is about to close.
            data = np.array(np.ma.getdata(heights), dtype=np.float64, order="C")
        except TopographyError:
            raise
        except Exception as err:  # readers of ~40 formats raise anything from deep inside
            raise TopographyError(f"{name}: SurfaceTopography's {type(reader).__name__} could not read channel "
                                  f"{channel} ({type(err).__name__}: {err})") from err
        finally:
            _close(reader)
    mask = np.ma.getmaskarray(heights) | ~np.isfinite(data)
    st = surface_topography()
    info.update(reader=type(reader).__name__, format=reader.format(), channel=chan.name,
                file_unit=st.mangle_length_unit_ascii(raw.unit), original_shape=[int(n) for n in data.shape],
                original_physical_size=[float(s) for s in scaled.physical_sizes], periodic=bool(raw.is_periodic))
    return st.Topography(np.ma.masked_array(data, mask=mask) if mask.any() else data, scaled.physical_sizes,
                         periodic=bool(raw.is_periodic), unit=unit)


def _line_scan(name, raw, info, unit, reader, chan) -> _LineScan:
    """A ``UniformLineScan`` or ``NonuniformLineScan`` in ``unit``: positions, heights and undefined points (copies)."""
    scaled = _to_unit(name, raw, unit)
    x, heights = scaled.positions_and_heights()
    data = np.array(np.ma.getdata(heights), dtype=np.float64)
    undefined = np.ma.getmaskarray(heights) | ~np.isfinite(data)
    uniform = bool(raw.is_uniform)
    info.update(reader=type(reader).__name__, format=reader.format(), channel=chan.name,
                file_unit=surface_topography().mangle_length_unit_ascii(raw.unit), original_shape=[int(data.size)],
                original_physical_size=[float(s) for s in scaled.physical_sizes], periodic=bool(raw.is_periodic),
                line_scan="uniform" if uniform else "nonuniform")
    return _LineScan(np.array(x, dtype=np.float64), data, undefined, uniform,
                     float(scaled.physical_sizes[0]) if uniform else None)


def _open(name: str, fmt: str | None = None):
    """SurfaceTopography's reader for the file: of format ``fmt``, else detected from the contents.

    A format detected without looking at the contents (:data:`CONTENT_BLIND`) must be one whose
    reader uses the file's extension: random bytes named ``a.x3p`` would otherwise be read as a
    height map. (Other readers' extension lists are incomplete, e.g. .di files and .txt columns.)
    """
    if os.path.getsize(name) == 0:
        raise TopographyError(f"{name}: the file is empty (0 bytes)")
    reader = _open_reader(name, fmt)
    ext = os.path.splitext(name)[1].lower().lstrip(".")
    own = _extensions(type(reader))
    if fmt is None and reader.format() in CONTENT_BLIND and ext not in own:
        detected = reader.format()
        _close(reader)
        claimed = sorted({r.format() for r in surface_topography().readers if ext in _extensions(r)})
        what = f"that of {', '.join(repr(c) for c in claimed)}" if claimed else "not one of them"
        raise TopographyError(f"{name}: SurfaceTopography reads it only as {detected!r} data (extensions "
                              f"{', '.join('.' + e for e in own)}), but its extension .{ext} is {what}: the file is "
                              "damaged or misnamed; give it its format's extension, or name the format in "
                              "topography.format")
    return reader


def _check_format(name: str, fmt) -> str | None:
    """``fmt`` if it is None or one of SurfaceTopography's formats, else a TopographyError."""
    formats = sorted(r.format() for r in surface_topography().readers)
    if fmt is not None and fmt not in formats:
        raise TopographyError(f"{name}: topography.format {fmt!r} is not allowed; use one of {', '.join(formats)}")
    return fmt


def _extensions(reader) -> list[str]:
    """The file extensions a SurfaceTopography reader class claims (lower case, no dot)."""
    return [e.lower() for e in (getattr(reader, "_file_extensions", None) or [])]


def _open_reader(name: str, fmt: str | None):
    """``open_topography``, its failures as :class:`TopographyError`."""
    try:
        return surface_topography().open_topography(name, format=fmt)
    except surface_topography().CannotDetectFileFormat as err:
        # Its message lists every reader's complaint; the chained exception keeps them.
        archive = _archive(name)
        if archive:
            raise TopographyError(f"{name}: {archive}") from err
        formats = ", ".join(sorted(r.format() for r in surface_topography().readers))
        raise TopographyError(f"{name}: not a topography file SurfaceTopography can read (unknown or unsupported "
                              f"format, or a damaged file); formats read: {formats}") from err
    except surface_topography().CorruptFile as err:
        raise TopographyError(f"{name}: the file is damaged ({err})") from err
    except Exception as err:
        raise TopographyError(f"{name}: SurfaceTopography cannot open the file ({type(err).__name__}: {err})") from err


def _archive(name: str) -> str | None:
    """What to do with a compressed file or an archive that no reader takes; None for other files."""
    with open(name, "rb") as fh:
        magic = fh.read(2)
    if magic == b"\x1f\x8b":
        return "the file is gzip-compressed; decompress it (gunzip) and name the decompressed file"
    if not zipfile.is_zipfile(name):
        return None
    try:
        with zipfile.ZipFile(name) as archive:
            members = [m for m in archive.namelist() if not m.endswith("/")]
    except (OSError, zipfile.BadZipFile):
        return None
    data = [m for m in members if m != "meta.yml" and not os.path.basename(m).upper().startswith("LICENSE")]
    kind = ("a SurfaceTopography container (meta.yml) of several measurements" if "meta.yml" in members
            else "a zip archive")
    shown = ", ".join(data[:6]) + (", ..." if len(data) > 6 else "")
    return (f"{kind}, not one topography file; unzip it and name the data file you want in topography.files "
            f"(its files: {shown or 'none'})")


def _close(reader) -> None:
    """Close SurfaceTopography's reader and the file it holds."""
    reader.close()
    # NPYReader.close() (SurfaceTopography 1.27.1) leaves its NuMPI file open, which warns when collected.
    mpi_file = getattr(reader, "mpi_file", None)
    if mpi_file is not None:
        mpi_file.close()


def _channel(name, reader, index):
    """The ``index``-th data channel; it must hold 2-D uniform heights."""
    channels = reader.channels
    if not channels:  # e.g. a misnamed file that another format's reader accepts (nms-2.nms is read as .mat)
        raise TopographyError(f"{name}: SurfaceTopography reads it as {reader.format()!r} data "
                              f"({type(reader).__name__}) but finds no data channel in it: the file holds no "
                              "height map, or is damaged or misnamed; if it is in another format, name that "
                              "format in topography.format")
    names = ", ".join(f"{i}: {c.name!r}" for i, c in enumerate(channels))
    if index >= len(channels):
        raise TopographyError(f"{name}: topography.channel {index} is out of range; the file's channels are {names}")
    chan = channels[index]
    if not chan.is_height_channel:
        raise TopographyError(f"{name}: channel {index} ({chan.name!r}) holds {chan.data_kind.value} data in "
                              f"{chan.data_unit!r}, not heights; the file's channels are {names}")
    if chan.dim == 2 and chan.is_uniform is False:
        raise TopographyError(f"{name}: channel {index} ({chan.name!r}) is a non-uniformly sampled 2-D map; maps must "
                              "be on a uniform grid (line scans may be non-uniform: they are resampled): "
                              "interpolate the map onto a grid first")
    return chan


def _metadata(name, chan, info, *, file_unit, physical_size) -> dict:
    """Keyword arguments for ``chan.topography``: the scene's unit and size where the file has none.

    SurfaceTopography refuses to override metadata the file carries (MetadataAlreadyFixedByFile), and
    the file's own values are the measurement's, so they win; a scene value they replace is recorded
    in ``info["ignored"]``.
    """
    kwargs, ignored = {}, []
    if chan.unit is None:
        if file_unit is None:
            raise TopographyError(f"{name}: the file carries no length unit; give topography.file_unit "
                                  f"(one of {', '.join(LENGTH_UNITS)}), the unit of its heights and sizes")
        kwargs["unit"] = file_unit
    elif file_unit is not None:
        ignored.append("file_unit")
    if chan.physical_sizes is None:
        if physical_size is None:
            raise TopographyError(f"{name}: the file has no physical size; give topography.physical_size "
                                  "[Lx, Ly], the size of the measured area in the file's unit")
        if len(physical_size) != chan.dim:
            what, remedy = ("a line scan", "[L], its length") if chan.dim == 1 else ("a map", "[Lx, Ly]")
            raise TopographyError(f"{name}: topography.physical_size {list(physical_size)} has {len(physical_size)} "
                                  f"value(s), but channel {chan.name!r} is {what}: give {remedy} in the file's unit")
        kwargs["physical_sizes"] = physical_size
    elif physical_size is not None:
        ignored.append("physical_size")
    info.update(unit_from="scene" if "unit" in kwargs else "file", ignored=ignored,
                physical_size_from="scene" if "physical_sizes" in kwargs else "file")
    return kwargs


def _to_unit(name, topo, unit):
    """``topo`` converted to the study's ``unit`` by SurfaceTopography (heights and sizes)."""
    try:
        surface_topography().get_unit_conversion_factor(topo.unit, unit)
    except ValueError as err:
        raise TopographyError(f"{name}: the file's unit {topo.unit!r} cannot be converted to {unit!r} ({err})") from err
    return topo.to_unit(unit)


def _check_grid(name, topo, non_square) -> tuple[float, float]:
    """Check the sizes and (with ``non_square: reject``) a square map; the pixel sizes (dx, dy) in ``unit``."""
    (nx, ny), (lx, ly) = topo.nb_grid_pts, topo.physical_sizes
    if min(nx, ny) < 4:
        raise TopographyError(f"{name}: the map is {nx} x {ny} points; the contact solver needs at least 4 x 4")
    if not all(np.isfinite(s) and s > 0 for s in (lx, ly)):
        raise TopographyError(f"{name}: the physical size ({lx}, {ly}) {topo.unit} is not positive and finite")
    problem = length_problem((nx, ny), (lx / nx, ly / ny), topo.unit)
    if problem:
        raise TopographyError(f"{name}: {problem}; check the file's unit and size (topography.file_unit, "
                              "physical_size) or choose another topography.unit")
    if nx != ny and non_square == "reject":
        raise TopographyError(f"{name}: the map is {nx} x {ny} points, not square, and topography.non_square is "
                              f"reject: set it to keep to use the whole map, or to crop to use the centred "
                              f"{min(nx, ny)} x {min(nx, ny)} block")
    return lx / nx, ly / ny


def _detrend_and_fill(name, topo, info, *, undefined, detrend, max_undefined=MAX_UNDEFINED) -> np.ndarray:
    """Detrend (fit on the defined points), then fill the undefined points; returns finite heights (nx, ny)."""
    n_undefined = int(np.ma.getmaskarray(topo.heights()).sum())
    size = topo.heights().size
    info.update(n_undefined=n_undefined, undefined_fraction=n_undefined / size, undefined=undefined, detrend=detrend)
    if n_undefined > max_undefined * size and undefined != "reject":
        raise TopographyError(f"{name}: {n_undefined} of {size} points ({n_undefined / size:.1%}) are undefined (not "
                              f"measured), more than topography.max_undefined = {max_undefined:g}: the filled map "
                              "would be mostly invented; raise max_undefined if this is the map you want")
    if n_undefined and undefined == "reject":
        raise TopographyError(f"{name}: {n_undefined} of {size} points ({n_undefined / size:.3%}) are undefined "
                              "(not measured); set topography.undefined to mean or harmonic to fill them")
    if n_undefined == size:
        raise TopographyError(f"{name}: all {size} points are undefined (not measured)")
    try:
        if detrend != "none":
            topo = topo.detrend(detrend_mode=detrend)
        if n_undefined and undefined == "mean":
            topo = topo.fill_undefined_data(fill_value=float(topo.mean()))
        elif n_undefined:
            topo = topo.interpolate_undefined_data(method="harmonic")
        # The harmonic filter returns a masked array with nothing masked; anything still masked is NaN here.
        heights = np.ma.filled(topo.heights(), np.nan).astype(np.float64, order="C")
    except Exception as err:
        raise TopographyError(f"{name}: detrend {detrend!r} / filling {undefined!r} failed "
                              f"({type(err).__name__}: {err})") from err
    n_bad = int(np.count_nonzero(~np.isfinite(heights)))
    if n_bad:
        raise TopographyError(f"{name}: {n_bad} heights are not finite after detrend {detrend!r} and filling "
                              f"{undefined!r}; the contact solver needs finite heights everywhere")
    if not heights.max() > heights.min():
        raise TopographyError(f"{name}: the map is flat (every height equal after detrend {detrend!r}): it has no "
                              "roughness to study")
    return heights


def _crop(heights: np.ndarray) -> tuple[np.ndarray, list[int] | None]:
    """The centred largest square block of ``heights`` (nx, ny) and its [i0, j0, n], or None if already square."""
    nx, ny = heights.shape
    if nx == ny:
        return heights, None
    n = min(nx, ny)
    i0, j0 = (nx - n) // 2, (ny - n) // 2
    return np.ascontiguousarray(heights[i0:i0 + n, j0:j0 + n]), [i0, j0, n]
