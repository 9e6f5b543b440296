"""Line scans (profiles) read from instrument files, prepared for the 1-D (plane-strain) contact solver.

:mod:`roughcontact.surfaces.topography` reads the file with SurfaceTopography; a channel that is a line
scan (SurfaceTopography's ``UniformLineScan`` or ``NonuniformLineScan``) comes here as its positions,
heights and undefined points, in the study's unit, and leaves as heights on a uniform grid:

1. **check** that the scan can be solved: at least :data:`MIN_PROFILE_POINTS` points, and positions
   that are finite and strictly increasing (a stylus that went back, or repeated positions, would make
   the profile two-valued);
2. **detrend** by least squares on the measured points (mean, line or parabola in x);
3. **fill** the undefined points: ``mean`` (the detrended measured mean) or ``harmonic`` (in 1-D the
   harmonic function between two measured neighbours is the straight line through them: linear
   interpolation, the ends held at their nearest measured height), the policy of the maps;
4. **resample** a non-uniform scan onto a uniform grid (:func:`uniform_profile`).

Every failure raises the caller's error class with a message naming the file and the remedy.
"""

from __future__ import annotations

import numpy as np

#: Fewest points of a profile the pipeline solves. The contact length fraction of an n-point profile moves in
#: steps of 1/n: with fewer than 16 points a step (>= 6 %) is coarser than half the CEL fit window
#: A/A0 in [0.01, 0.11], so no load curve could be fitted, and the forward second differences behind m4 and
#: Nayak's alpha average fewer than 14 values. 16 is also the number of heights of the smallest map (4 x 4).
MIN_PROFILE_POINTS = 16
#: How a non-uniform scan is brought to a uniform grid (recorded in the surface file).
RESAMPLING = "linear interpolation onto n evenly spaced points over the measured range (spacing: the mean spacing)"
#: Polynomial degree of each ``topography.detrend`` mode on a profile.
DETREND_DEGREE = {"center": 0, "height": 1, "curvature": 2}


def check_positions(name: str, x: np.ndarray, error=ValueError) -> None:
    """Stop unless ``x`` (n,) holds at least :data:`MIN_PROFILE_POINTS` finite, strictly increasing positions."""
    n = x.size
    if n < MIN_PROFILE_POINTS:
        raise error(f"{name}: the line scan has {n} points; a profile needs at least {MIN_PROFILE_POINTS} to be "
                    "solved and fitted (its contact length moves in steps of 1/n): measure a longer or denser scan")
    if not np.all(np.isfinite(x)):
        raise error(f"{name}: {int(np.sum(~np.isfinite(x)))} of the scan's {n} positions are not finite numbers; "
                    "every point needs its position x")
    steps = np.diff(x)
    if not np.all(steps > 0):
        i = int(np.flatnonzero(~(steps > 0))[0])
        raise error(f"{name}: the scan's positions do not increase strictly: x[{i}] = {x[i]:.6g} is followed by "
                    f"x[{i + 1}] = {x[i + 1]:.6g}; a profile is one height per position: sort the points by x and "
                    "remove repeated positions (or average them) before reading the file")


def prepare_profile(name: str, x: np.ndarray, heights: np.ndarray, undefined_mask: np.ndarray, *, uniform: bool,
                    length: float | None, info: dict, undefined: str, detrend: str, max_undefined: float,
                    error=ValueError) -> tuple[np.ndarray, float]:
    """A line scan's heights, detrended, filled and on a uniform grid: ``(heights (n_out,), length)``.

    Parameters
    ----------
    name : str
        The file, at the start of every message.
    x, heights, undefined_mask : numpy.ndarray, shape (n,)
        Positions [u], heights [u] (any value where undefined) and the points not measured.
    uniform : bool
        Whether the file's scan is uniform (SurfaceTopography's ``UniformLineScan``): then ``length`` is its
        physical size [u] (n pixels of ``length / n``) and no point moves.
    length : float or None
        A uniform scan's length [u]; ignored for a non-uniform one, whose length is ``n`` times the spacing.
    info : dict
        Provenance, updated in place: undefined points, detrending, and for a non-uniform scan
        ``resampled`` (method, spacing rule, spacing, original points and spacings).
    undefined, detrend, max_undefined
        As for a map (``topography.undefined``, ``.detrend``, ``.max_undefined``).
    error : type
        The exception class raised.
    """
    check_positions(name, x, error)
    h = np.array(heights, dtype=np.float64)
    bad = np.asarray(undefined_mask, dtype=bool) | ~np.isfinite(h)
    _check_undefined(name, int(bad.sum()), h.size, info, undefined=undefined, max_undefined=max_undefined,
                     error=error)
    info["detrend"] = detrend
    if detrend != "none":
        u = (x - x.mean()) / np.ptp(x)  # centred and scaled: a well-conditioned fit at any unit
        coeffs = np.polyfit(u[~bad], h[~bad], DETREND_DEGREE[detrend])
        h = h - np.polyval(coeffs, u)
    if bad.any():
        h[bad] = float(h[~bad].mean()) if undefined == "mean" else np.interp(x[bad], x[~bad], h[~bad])
    if not h.max() > h.min():
        raise error(f"{name}: the profile is flat (every height equal after detrend {detrend!r}): it has no roughness "
                    "to study")
    if uniform:
        return h, float(length)
    return uniform_profile(x, h, info)


def uniform_profile(x: np.ndarray, heights: np.ndarray, info: dict) -> tuple[np.ndarray, float]:
    """A non-uniform scan linearly interpolated onto ``n`` evenly spaced points over its measured range.

    The spacing is the mean spacing ``(x[-1] - x[0]) / (n - 1)``, so the profile keeps its number of points:
    no resolution is invented or discarded on the whole. The median spacing would drop points where an
    instrument rounds its positions: SurfaceTopography's ``dektak-1.csv`` (a 0.156 um stylus step written to
    0.1 um, spacings alternating 0.1 and 0.2) would lose 22 % of its 9600 points at the median's 0.2, and
    the smallest spacing (0.1) would invent 56 % more. Linear interpolation (not a spline) adds no
    overshoot: every height stays between two measured ones, so no new peak touches first.
    Returns ``(heights (n,), length = n dx)`` [u]; ``info["resampled"]`` records the method and spacings.
    """
    n = x.size
    steps = np.diff(x)
    dx = float((x[-1] - x[0]) / (n - 1))
    grid = x[0] + dx * np.arange(n)
    grid[-1] = x[-1]  # the last point exactly, not past the measured range by round-off
    info["resampled"] = {"method": RESAMPLING, "original_points": int(n), "spacing": dx,
                         "original_spacing_min": float(steps.min()), "original_spacing_median": float(np.median(steps)),
                         "original_spacing_max": float(steps.max()), "x_start": float(x[0])}
    return np.interp(grid, x, heights), n * dx


def _check_undefined(name, n_undefined, size, info, *, undefined, max_undefined, error) -> None:
    """The maps' policy on undefined points, for a profile (``info`` records the count and fraction)."""
    info.update(n_undefined=n_undefined, undefined_fraction=n_undefined / size, undefined=undefined)
    if n_undefined == size:
        raise error(f"{name}: all {size} points are undefined (not measured)")
    if n_undefined and undefined == "reject":
        raise error(f"{name}: {n_undefined} of {size} points ({n_undefined / size:.3%}) are undefined (not measured, "
                    "or NaN); set topography.undefined to mean or harmonic to fill them")
    if n_undefined > max_undefined * size:
        raise error(f"{name}: {n_undefined} of {size} points ({n_undefined / size:.1%}) are undefined (not measured), "
                    f"more than topography.max_undefined = {max_undefined:g}: the filled profile would be mostly "
                    "invented; raise max_undefined if this is the profile you want")
