"""Fused passes of the single solve for the numpy backend: one pass (numba) where numpy made several.

The single solve's round (:class:`~roughcontact.solver.compressed.CompressedKernels`) passes over the whole
grid besides its transforms: ``w`` moved by the float32 product, the search for nodes off the contact set
that violate the gap, and ``t . K t`` from a spectrum. They are bound by memory traffic, not arithmetic
(1024²: 4-8 MiB a field, beyond a core's L2). :func:`move_field` moves ``w`` and finds, in that same pass,
the least ``w`` off the contact set, so that the next search runs only where some node can violate (on the
paper case at 1024², 326 of 637 measures: the 236 whose least was below ``gbar``, each of which found some, and the
90 where it was not known: a step's first measure, or one after ``w`` was recomputed in float64);
:func:`weighted_squares` sums ``t . K t`` in one pass, without numpy's passes through a buffer. A sparse load into a
transform's input (:func:`scatter_scaled`) and the remap of node indices to a padded layout (:func:`remap`) are one
pass each too. Each gives the bits of the numpy expressions it replaces (their floating-point operations in their order,
``fastmath`` off; a shift and a mask for an integer division by a power of two; ``tests/test_passes.py`` compares
them), so the solver's results do not change.

Examples
--------
>>> import numpy as np
>>> w = np.array([[0.5, -1.0], [2.0, 0.25]])
>>> r = np.array([[1.0, 1.0], [0.0, 4.0]], dtype=np.float32)
>>> mask = np.array([[False, True], [False, False]])
>>> move_field(w, r, np.float32(0.5), True, mask)  # w - 0.5 r; the least w off the mask
-1.75
>>> w
array([[ 0.  , -1.5 ],
       [ 2.  , -1.75]])
"""

from __future__ import annotations

import numpy as np
from numba import njit

_JIT = {"cache": True, "nogil": True}


@njit(**_JIT)
def move_field(w, r, c, subtract, mask):
    """``w -= r c`` (``subtract``) or ``w += r c`` in place; the least new ``w`` off ``mask`` (inf if none).

    ``w``: float64 ``(nx, ny)``; ``r``: float32 ``(nx, ny)``, maybe a strided view (padded rows); ``c``: a
    float32 number: ``r c`` is rounded to float32 first, as numpy's ``np.multiply(r, c, out=r)`` then
    ``w -= r`` (``r`` is left unchanged here). NaN never counts as the least value (as ``w < x`` is False for
    it). Shapes are not checked: the caller's fields share one shape.
    """
    nx, ny = w.shape
    least = np.inf
    for i in range(nx):
        for j in range(ny):
            d = np.float64(r[i, j] * c)
            v = w[i, j] - d if subtract else w[i, j] + d
            w[i, j] = v
            if v < least and not mask[i, j]:
                least = v
    return least


@njit(inline="always")
def _block(a, wt, s, n):
    # numpy's pairwise_sum for n <= 128 (loops_utils.h.src): eight accumulators, then the rest in order
    if n < 8:
        res = np.float32(0.0)
        for i in range(s, s + n):
            res += wt[i] * (a[i] * a[i])
        return res
    r0 = wt[s] * (a[s] * a[s])
    r1 = wt[s + 1] * (a[s + 1] * a[s + 1])
    r2 = wt[s + 2] * (a[s + 2] * a[s + 2])
    r3 = wt[s + 3] * (a[s + 3] * a[s + 3])
    r4 = wt[s + 4] * (a[s + 4] * a[s + 4])
    r5 = wt[s + 5] * (a[s + 5] * a[s + 5])
    r6 = wt[s + 6] * (a[s + 6] * a[s + 6])
    r7 = wt[s + 7] * (a[s + 7] * a[s + 7])
    i = s + 8
    end = s + n - n % 8
    while i < end:
        r0 += wt[i] * (a[i] * a[i])
        r1 += wt[i + 1] * (a[i + 1] * a[i + 1])
        r2 += wt[i + 2] * (a[i + 2] * a[i + 2])
        r3 += wt[i + 3] * (a[i + 3] * a[i + 3])
        r4 += wt[i + 4] * (a[i + 4] * a[i + 4])
        r5 += wt[i + 5] * (a[i + 5] * a[i + 5])
        r6 += wt[i + 6] * (a[i + 6] * a[i + 6])
        r7 += wt[i + 7] * (a[i + 7] * a[i + 7])
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < s + n:
        res += wt[i] * (a[i] * a[i])
        i += 1
    return res


@njit(**_JIT)
def _pairwise(a, wt, s, n):
    if n <= 128:
        return _block(a, wt, s, n)
    half = n // 2
    half -= half % 8  # (numpy's split: a multiple of the unrolling)
    return _pairwise(a, wt, s, half) + _pairwise(a, wt, s + half, n - half)


def weighted_squares(a, weights) -> float:
    """``sum(weights * a**2)`` over float32 arrays of one shape, as numpy's ``(a * a * weights).sum()``.

    The float32 terms summed in numpy's pairwise order (blocks of 128 with eight accumulators, halves
    split at multiples of 8), so the result is numpy's to the bit; one pass reading ``a`` and ``weights``,
    no temporary (numpy: two multiplies into a buffer, then the sum). Both must be C-contiguous float32.

    >>> a = np.arange(300, dtype=np.float32)
    >>> weighted_squares(a, np.full(300, 0.5, dtype=np.float32)) == float((a * a * np.float32(0.5)).sum())
    True
    """
    a, weights = a.reshape(-1), weights.reshape(-1)
    if a.dtype != np.float32 or weights.dtype != np.float32 or a.size != weights.size:
        raise ValueError(f"weighted_squares takes float32 arrays of one size; got {a.dtype} ({a.size}) and "
                         f"{weights.dtype} ({weights.size})")
    return float(_pairwise(a, weights, 0, a.size))  # (none: 0.0, as numpy's)


@njit(**_JIT)
def scatter_scaled(flat, pos, values, scale):
    """``flat[pos] = values * scale``, each product taken in float64 and rounded once to ``flat``'s dtype.

    numpy's ``np.multiply(values, scale, out=buffer of flat's dtype, casting="unsafe")`` then ``flat[pos] = buffer``,
    without the buffer and the fancy-index pass. ``flat``: 1-D; ``pos``: 1-D int; ``values``: 1-D float64 of
    ``pos``'s length. Nothing is checked (no bounds, no lengths) and no floating-point warning is given (a float32
    overflow rounds to inf silently): the caller (``SpectralProduct.load``) passes its own arrays.
    """
    for k in range(pos.size):
        flat[pos[k]] = values[k] * scale


@njit(**_JIT)
def remap(idx, n1, row):
    """``(idx // n1) * row + idx % n1`` for ``idx`` (1-D int), in one pass (a new array, ``idx``'s dtype): flat
    indices of a grid with rows of ``n1`` as those of a grid with rows of ``row``. Where ``n1`` is a power of two the
    division is a shift and the remainder a mask (the same values, negative ones too: both floor); elsewhere a
    division a node, which costs this pass most of its gain over numpy's."""
    out = np.empty_like(idx)
    if n1 > 0 and n1 & (n1 - 1) == 0:
        shift, mask = 0, n1 - 1
        while (1 << shift) < n1:
            shift += 1
        for k in range(idx.size):
            i = idx[k]
            out[k] = (i >> shift) * row + (i & mask)
        return out
    for k in range(idx.size):
        i = idx[k]
        out[k] = (i // n1) * row + i % n1
    return out
