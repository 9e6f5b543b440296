"""A profile's contact solved as the y-invariant map ``(n, 4)``: the plane-strain problem exactly, shaped as the
1-D solver's result (issue 49). Used to test what follows the solve (run_case's outputs, the contact file, the
aggregate and the fit) independently of the 1-D solver, and to check that solver against it.

A surface invariant along y makes the periodic half-space's problem the half-plane's: its spectrum lives on
``q_y = 0``, where ``|q| = |q_x|``, the plane-strain compliance ``2 / (E* |q|)`` of a profile. The map's pixel
edges counted along x, each ``dy = L / 4`` long, per area ``L^2``, are the contact intervals' ends per unit length.
"""

from __future__ import annotations

import numpy as np

from roughcontact.solver import solve_contact

NY = 4


def profile_solve(heights, pressures, *, length: float = 1.0, **options):
    """``solve_contact`` of profile ``heights`` (n,) of length ``length`` as a 1-D result: dims (step[, x])."""
    h = np.asarray(heights, dtype=float)
    result = solve_contact(np.repeat(h[:, None], NY, axis=1), pressures, length=(float(length), float(length)),
                           **options)
    out = result.isel(y=0, drop=True) if "y" in result.dims else result
    attrs = {k: v for k, v in result.attrs.items() if k not in ("length_x", "length_y", "ny")}
    attrs.update(length=float(length), n=h.size, nx=h.size, surface_dimension=1)
    return out.drop_attrs(deep=False).assign_attrs(attrs)
