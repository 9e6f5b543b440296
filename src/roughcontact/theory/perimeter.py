"""The perimeter correction of a pixel-counted contact area.

Pixel-counted area is biased high, to first order in the grid spacing: every boundary
pixel counts whole. Yastrebov, Anciaux & Molinari (Tribol. Int. 114, 161, 2017) correct
it with the contact perimeter P: A ~ A_pix - c P dx. Here P is the length of the pixel
edges between contact and non-contact nodes (the solver's ``contact_perimeter``, per
unit area) and ``c`` defaults to :data:`PERIMETER_C`.
"""

from __future__ import annotations

import math

import numpy as np

#: Default coefficient of the perimeter correction, (pi - 1 + ln 2) / 24 (Yastrebov et
#: al. 2017 as we read it); :func:`fit_perimeter_c` measures the best value for a study.
PERIMETER_C = (math.pi - 1.0 + math.log(2.0)) / 24.0


def perimeter_corrected_area(area_fraction, perimeter, dx: float, c: float = PERIMETER_C):
    """Perimeter-corrected contact-area fraction A_pix/A0 - c * P * dx [1].

    ``area_fraction`` and ``perimeter`` (contact boundary length per unit nominal area
    [1/length]) broadcast together; ``dx`` is the grid spacing L/N [length]. Clipped at 0.
    """
    if not dx > 0:
        raise ValueError(f"dx must be > 0, got {dx!r}")
    return np.maximum(np.asarray(area_fraction) - c * np.asarray(perimeter) * dx, 0.0)
