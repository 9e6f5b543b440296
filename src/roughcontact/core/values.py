"""Equality of attribute and variable values, as two files compare them.
"""

from __future__ import annotations

import numpy as np


def same_value(a, b) -> bool:
    """Whether two attribute or variable values are equal: strings as strings, anything else
    as arrays of one shape with equal elements, NaN equal to NaN (a NaN is the same value
    in two files, not a difference)."""
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    a, b = np.asarray(a), np.asarray(b)
    floats = np.issubdtype(a.dtype, np.floating) and np.issubdtype(b.dtype, np.floating)
    return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=floats))
