"""What a case computes besides the solver's per-step columns: its observers and its after-solve variables.

:func:`observers` makes the observers a case's ``outputs`` asks for (the pressure distribution P(p)); the
cluster statistics are :class:`~roughcontact.statistics.clusters.ClusterObserver`'s. :func:`full_contact_variable`
is the exact load of full contact, added to the case's dataset after the solve.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from ..statistics.pressure import PressureDistribution, pressure_bins
from ..theory.full_contact import full_contact_load
from ..theory.profiles import full_contact_load_profile


def contact_observers(outputs: Mapping, scale: float) -> list:
    """The solve's observers that ``outputs`` asks for (``scale`` = E* h' [pressure]).

    ``outputs["pressure_distribution"]`` (``{"bins": int, "max": float}``, pressures over ``scale``) gives a
    :class:`~roughcontact.statistics.pressure.PressureDistribution`; nothing else here observes a step.
    """
    spec = outputs.get("pressure_distribution")
    if not spec:
        return []
    return [PressureDistribution(pressure_bins(spec["bins"], spec["max"]), scale)]


def full_contact_variable(heights, length, e_star: float, pressure_units: str) -> xr.DataArray:
    """``full_contact_pressure``: the exact mean pressure of full contact of the periodic ``heights`` (a map, or a
    profile (n,) of period ``length``: :func:`roughcontact.theory.profiles.full_contact_load_profile`)."""
    load = full_contact_load_profile if np.ndim(heights) == 1 else full_contact_load
    return xr.DataArray(load(heights, e_star, length), attrs={
        "units": pressure_units,
        "long_name": "mean pressure at which the periodic surface is in full contact (exact: "
                     "-min (E*/2) F^-1[|q| h_hat])"})
