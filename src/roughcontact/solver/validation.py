"""Checks of the solver's arguments: each error names the argument and its allowed range."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from ..core.cell import check_length, is_pair_form

#: Boundary conditions of the elastic half-space, the ``boundary`` argument of the
#: solver: ``"periodic"`` (the default; the cell is one period of an infinite surface)
#: or ``"free"`` (the patch is all there is; no periodic images).
BOUNDARIES = ("periodic", "free")


def real_scalar(name: str, value, expected: str) -> float:
    """``float(value)`` for a real number; strings, bools and the like are refused."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or (
            isinstance(value, np.ndarray) and (value.ndim != 0 or value.dtype.kind not in "iuf")):
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__} {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__} {value!r}") from None


def check_positive(name: str, value) -> float:
    v = real_scalar(name, value, "a finite real number > 0")
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a finite real number > 0, got {value!r}")
    return v


#: Fewest points of a profile (1-D heights), as of a map's side.
MIN_PROFILE_POINTS = 4


def validate_heights(heights, name: str = "heights", square: bool = True, profile: bool = False) -> np.ndarray:
    """``heights`` as a C-contiguous float64 array, checked: 2-D, at least 4 x 4, finite.

    ``square=True`` asks for a square array ``(n, n)`` (the grid of a float ``length``);
    ``square=False`` accepts any ``(nx, ny)`` with ``nx, ny >= 4`` (a rectangular cell, whose
    ``length`` is then checked against the shape by :func:`validate_length`); ``profile=True``
    also accepts a profile, 1-D ``(n,)`` with ``n >= 4`` (:data:`MIN_PROFILE_POINTS`).
    """
    if isinstance(heights, (str, bytes)):
        raise ValueError(f"{name} must be a real numeric array, got the string {heights!r}")
    try:
        a = np.asarray(heights)
    except Exception as exc:  # ragged lists and the like
        raise ValueError(f"{name} must be a real 2-D square array of finite numbers (or (nx, ny) with "
                         f"length=(Lx, Ly)): {exc}") from None
    if a.dtype == object or a.dtype.kind not in "iuf":
        if a.dtype.kind == "c":
            raise ValueError(f"{name} must be real, got complex dtype {a.dtype}")
        raise ValueError(f"{name} must be a real numeric array, got dtype {a.dtype}")
    if profile and a.ndim == 1:
        if a.size < MIN_PROFILE_POINTS:
            raise ValueError(f"{name}: a profile (1-D heights) needs at least {MIN_PROFILE_POINTS} points, got "
                             f"{a.size}")
        return finite_float64(a, name)
    if a.ndim != 2 or (square and a.shape[0] != a.shape[1]):
        line = ", or a 1-D profile (n,)" if profile else ""
        raise ValueError(f"{name} must be a 2-D square array (n, n), or (nx, ny) with length=(Lx, Ly){line}, "
                         f"got shape {a.shape}")
    if min(a.shape) < 4:
        raise ValueError(f"{name} must be at least 4 x 4 (nx, ny >= 4), got shape {a.shape}")
    return finite_float64(a, name)


def finite_float64(a: np.ndarray, name: str) -> np.ndarray:
    """``a`` (real, any shape) as a C-contiguous float64 array; a ValueError naming ``name`` if any value is
    NaN or infinite."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must contain only finite values (found NaN or inf)")
    return a


def validate_length(length, shape: tuple[int, int], name: str = "heights"):
    """The cell's sides for the array ``name`` of ``shape`` ``(nx, ny)``: a float ``L`` or a pair ``(Lx, Ly)``.

    A float (a real scalar) means the square cell ``Lx = Ly = L`` and needs ``nx == ny``; a pair
    (tuple, list or 1-D array of two real numbers) gives the sides along x (axis 0) and y (axis 1),
    pixels ``dx = Lx / nx`` and ``dy = Ly / ny``. Every side must be finite and > 0
    (:func:`roughcontact.core.cell.check_length` parses it); a profile (``shape == (n,)``) has one length.

    Returns
    -------
    float or (float, float)
        ``L`` for a square cell (``nx == ny`` and ``Lx == Ly``: a pair ``(L, L)`` on an ``n x n``
        grid is returned as the float ``L``, so that it is the same problem bit for bit), else
        the pair ``(Lx, Ly)`` of floats.
    """
    if len(shape) == 1:  # a profile: one length
        if is_pair_form(length):
            raise ValueError(f"length: a profile ({name} 1-D, {shape[0]} points) has one length L, a finite real "
                             f"number > 0; got {length!r}")
        return check_positive("length", length)
    nx, ny = shape
    value = check_length(length)
    if isinstance(value, tuple):
        lx, ly = value
        return lx if (nx == ny and lx == ly) else value
    if nx != ny:
        raise ValueError(
            f"length: a single float means a square cell, and {name} must be a 2-D square array (n, n) "
            f"for it; got length={length!r} and {name} of shape {(nx, ny)}: for a rectangular cell give "
            f"length=(Lx, Ly), the sides along x (axis 0) and y (axis 1). A 2-D array is one map: {nx} profiles "
            f"of {ny} points are not solved at once; solve each row as a profile (a 1-D array), one call each")
    return value


def validate_pressures(pressures) -> np.ndarray:
    if isinstance(pressures, (str, bytes)):
        raise ValueError(
            f"pressures must be a 1-D sequence of finite numbers > 0, got the string {pressures!r}")
    try:
        raw = np.asarray(pressures)
    except (TypeError, ValueError):
        raise ValueError(
            f"pressures must be a 1-D sequence of finite numbers > 0, got {pressures!r}"
        ) from None
    if raw.dtype == object or raw.dtype.kind not in "iuf":
        # strings, bools, complex numbers, ragged or mixed sequences
        raise ValueError(
            f"pressures must be a 1-D sequence of finite real numbers > 0, got {pressures!r} "
            f"(dtype {raw.dtype})"
        )
    p = raw.astype(np.float64)
    if p.ndim == 0:
        raise ValueError(
            f"pressures must be a non-empty 1-D sequence of mean pressures p0 > 0, got the scalar {pressures!r}"
        )
    if p.ndim != 1 or p.size == 0:
        raise ValueError(
            f"pressures must be a non-empty 1-D sequence of mean pressures p0 > 0, got shape {p.shape}"
        )
    if not np.all(np.isfinite(p)) or np.any(p <= 0):
        raise ValueError(f"pressures must all be finite and > 0, got {p.tolist()}")
    return p


def validate_threads(threads) -> int:
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
        raise ValueError(f"threads must be an integer >= 1, got {threads!r}")
    return int(threads)


def validate_solver_args(e_star, length, tol, max_iter, threads, shape=None):
    """The solver's scalar arguments, checked; ``length`` against the heights' ``shape``
    (:func:`validate_length`; a float ``> 0`` when ``shape`` is None)."""
    e_star = check_positive("e_star", e_star)
    length = check_positive("length", length) if shape is None else validate_length(length, shape)
    tol_f = real_scalar("tol", tol, "a number in the open interval (0, 1)")
    if not (0.0 < tol_f < 1.0):
        raise ValueError(f"tol must be a number in the open interval (0, 1), got {tol!r}")
    if isinstance(max_iter, (bool, np.bool_)) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    return e_star, length, tol_f, int(max_iter), validate_threads(threads)


def validate_store(store_fields, n_steps: int) -> set[int]:
    if isinstance(store_fields, (bool, np.bool_)):
        return set(range(1, n_steps + 1)) if store_fields else set()
    if isinstance(store_fields, Iterable) and not isinstance(store_fields, (str, bytes)):
        steps = set()
        for s in store_fields:
            if isinstance(s, (bool, np.bool_)) or not isinstance(s, (int, np.integer)) or not 1 <= s <= n_steps:
                raise ValueError(
                    f"store_fields must be a bool or an iterable of step numbers in 1..{n_steps}, got {s!r}"
                )
            steps.add(int(s))
        return steps
    raise ValueError(
        f"store_fields must be a bool or an iterable of step numbers in 1..{n_steps}, got {store_fields!r}"
    )


def validate_flag(name: str, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)


def validate_boundary(boundary) -> str:
    if not isinstance(boundary, str) or boundary not in BOUNDARIES:
        allowed = ", ".join(repr(b) for b in BOUNDARIES)
        raise ValueError(f"boundary must be one of {allowed}, got {type(boundary).__name__} {boundary!r}")
    return str(boundary)
