"""Whether a height map's numbers can be studied: sizes, heights and slopes inside float64's range, roughness
above round-off.

A measured or saved map may hold heights of any scale (a unit mistaken, a map written as float32 around a
large offset). :func:`scale_problem` says what a surface job would later stumble on (an overflowing moment,
a NaN rms height, a "roughness" made of rounding errors) so that it is named, with its remedy, before any
job runs (:mod:`roughcontact.pipeline.sources.array`) or when the file is read
(:mod:`roughcontact.surfaces.topography`).
"""

from __future__ import annotations

import math

import numpy as np

from .synthetic import LENGTH_RANGE, RMS_HEIGHT_RANGE, nonperiodic_moments

#: A map whose rms roughness is below this many times the resolution of its numbers (float eps x the largest
#: height) is round-off, not roughness.
ROUND_OFF_FACTOR = 100.0


def length_problem(shape: tuple[int, ...], pixel: tuple[float, ...], unit: str = "") -> str | None:
    """Pixel sizes and sides of a ``shape`` map (or (n,) profile) outside :data:`LENGTH_RANGE`, in words; None if
    inside."""
    lo, hi = LENGTH_RANGE
    axes = "xy"[:len(shape)]  # a profile's (n,) and (dx,) has x alone
    values = [(f"pixel size d{a}", d) for a, d in zip(axes, pixel, strict=True)]
    values += [(f"side n{a} d{a}", n * d) for a, n, d in zip(axes, shape, pixel, strict=True)]
    for what, value in values:
        if not lo <= value <= hi:
            return f"{what} = {value:g}{' ' + unit if unit else ''} is outside [{lo:g}, {hi:g}], the range of " \
                   "lengths float64 can study"
    return None


def scale_problem(heights: np.ndarray, pixel: tuple[float, float], resolution: float | None = None) -> str | None:
    """What makes ``heights`` (a 2-D map, pixels ``pixel = (dx, dy)``; a profile (n,), ``pixel = (dx,)``)
    unusable, in words with the remedy, or None.

    ``resolution``: the relative precision of the numbers as stored (``numpy.finfo(dtype).eps``; default
    float64's). Checks, in order: pixel sizes and the patch's sides in :data:`LENGTH_RANGE`, the largest
    height and the rms height in :data:`RMS_HEIGHT_RANGE`, the rms roughness above :data:`ROUND_OFF_FACTOR`
    times the resolution of the largest height, and finite statistics (moments, rms slope) of the patch.
    """
    h = np.asarray(heights)
    problem = length_problem(h.shape, pixel)
    if problem:
        return problem + "; give the pixel size in another unit (unit and pixel_size)"
    top = float(np.max(np.abs(h)))
    if not math.isfinite(top) or top > RMS_HEIGHT_RANGE[1]:
        return (f"its largest height {top:g} is beyond {RMS_HEIGHT_RANGE[1]:g}, outside the range float64 can "
                "study (squares and moments overflow); save the heights in a larger unit")
    scaled = np.asarray(h, dtype=np.float64) / top  # the mean square of the scaled map cannot overflow
    rms = float(np.sqrt(np.mean((scaled - scaled.mean()) ** 2))) * top
    if not rms >= RMS_HEIGHT_RANGE[0]:
        return (f"its rms height {rms:g} is below {RMS_HEIGHT_RANGE[0]:g}, outside the range float64 can study; "
                "save the heights in a smaller unit")
    eps = float(np.finfo(np.float64).eps) if resolution is None else resolution
    if rms <= ROUND_OFF_FACTOR * eps * top:
        return (f"its heights vary by {rms:g} (rms) about a level of {top:g}: {rms / top:.2g} of it, within "
                f"{ROUND_OFF_FACTOR:g} times the numbers' resolution ({eps:.2g}); that is round-off, not roughness: "
                "subtract the mean level (in float64) before saving, or check that the map is the one meant")
    try:
        with np.errstate(all="ignore"):
            sides = tuple(n * d for n, d in zip(h.shape, pixel, strict=True))
            stats = nonperiodic_moments(np.asarray(h, dtype=np.float64), sides if h.ndim == 2 else sides[0])
    except (ZeroDivisionError, OverflowError) as err:
        stats = {"rms_slope": float("nan"), "error": f"{type(err).__name__}: {err}"}
    keys = ("rms_height", "rms_slope", "m2", "m4", "alpha")
    bad = [key for key in keys if not (math.isfinite(stats.get(key, math.nan)) and stats.get(key, 0) > 0)]
    if bad:
        return (f"its statistics ({', '.join(bad)}) are not finite numbers > 0 for these heights and pixel sizes "
                f"(rms slope {stats['rms_slope']:g}): the heights and the pixel sizes are too far apart in scale; "
                "give them in units closer to each other")
    return None


def checked_scales(label: str, heights: np.ndarray, pixel: tuple[float, float], error=ValueError) -> np.ndarray:
    """``heights`` if :func:`scale_problem` finds nothing wrong, else ``error("<label>: <problem>")``."""
    problem = scale_problem(heights, pixel)
    if problem:
        raise error(f"{label}: {problem}")
    return heights
