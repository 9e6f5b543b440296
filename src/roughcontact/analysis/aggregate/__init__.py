"""Combine per-case datasets, differentiate load curves, derive quantities, reduce over seeds.

Per-case datasets (one rough surface = one ``(k_l, k_s, H, seed)`` case, or one measured topography)
are stacked by :mod:`.combine`; :mod:`.derivatives` holds the load derivatives (finite differences and
windowed slopes); :mod:`.derived` adds ``kappa``, ``dpbar_dp0`` and ``n_unconverged``; :mod:`.seeds` reduces
over seeds. Every variable these functions create has ``units`` and ``long_name`` attributes.
"""

from .combine import (
    CASE_DIMS,
    CONTACT_REQUIRED,
    REPRESENTATIVITY_REQUIRED,
    TOPOGRAPHY_DIM,
    combine_cases,
    combine_topographies,
    is_profiles,
)
from .derivatives import (
    DERIVATIVE_VARIABLES,
    fd_weights,
    load_derivative,
    log_window_edges,
    windowed_load_slope,
)
from .derived import (
    add_derived,
    aggregate_contact,
)
from .seeds import (
    SEED_STAT_VARIABLES,
    representativity_statistics,
    scale_free_statistics,
    seed_reduce,
    seed_statistics,
)

__all__ = [
    "CASE_DIMS",
    "TOPOGRAPHY_DIM",
    "CONTACT_REQUIRED",
    "REPRESENTATIVITY_REQUIRED",
    "combine_cases",
    "combine_topographies",
    "is_profiles",
    "fd_weights",
    "DERIVATIVE_VARIABLES",
    "load_derivative",
    "log_window_edges",
    "windowed_load_slope",
    "add_derived",
    "aggregate_contact",
    "SEED_STAT_VARIABLES",
    "seed_reduce",
    "seed_statistics",
    "representativity_statistics",
    "scale_free_statistics",
]
