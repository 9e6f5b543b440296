"""The transpose of a slab's blocks between the rows' and the columns' layouts (:mod:`.slabs`): a tiled copy."""

from __future__ import annotations

from numba import njit

#: Side of the square tiles :func:`copy_transposed` copies one at a time (32 x 32 complex64 values: 8 KiB read and
#: 8 KiB written, well inside a core's L1 cache).
TILE = 32


@njit(cache=True, nogil=True)
def copy_transposed(dst, src, tile=TILE):
    """``dst[b, j, i] = src[b, i, j]`` for ``src`` of shape ``(B, m, k)`` and ``dst`` ``(B, k, m)``, tile by tile.

    Either may be a strided view (a block of a slab's columns). numpy's ``np.copyto(dst, src.transpose(0, 2, 1))``
    walks one of the two across its rows at every value: the backward transform's block of 2 ranks took 2.3 ms
    at 2048^2 against 0.6 ms here, 15.7 against 2.7 ms at 4096^2 (one process, 2026-12-04; benchmarks/README.md,
    "The slab transforms' plans and transposes"). A copy: the values are the same bits either way.
    """
    B, m, k = src.shape
    for b in range(B):
        for i0 in range(0, m, tile):
            i1 = min(i0 + tile, m)
            for j0 in range(0, k, tile):
                j1 = min(j0 + tile, k)
                for j in range(j0, j1):
                    for i in range(i0, i1):
                        dst[b, j, i] = src[b, i, j]
