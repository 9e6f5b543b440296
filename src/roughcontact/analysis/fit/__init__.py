"""Fitting the contact evolution law (CEL) to aggregated contact data.

:mod:`.estimators` holds the two estimators (the paper's route and the joint fit, see its docstring),
:mod:`.bootstrap` one group's fit with its bootstrap over seeds, :mod:`.grid` the fit of a generated
scene per ``(k_l, k_s, H)``, :mod:`.topographies` that of a measured scene, :mod:`.cases` which cases
and steps enter, :mod:`.settings` the checked settings and shared output variables, :mod:`.table` the CSV table.

Steps: a fit takes the converged steps whose contact the grid resolves (:func:`.cases.usable_steps`). A step
whose largest contact patch holds fewer than 4 nodes (``contact_resolved`` False,
:mod:`roughcontact.statistics.patches`) is left out as an unconverged one is: its A/A0 is the grid's, flat while
the load rises, not the surface's; the fit job logs how many it left out of the window and the figures mark them.
"""

from .cases import (
    exclude_unconverged,
    unresolved_in_window,
    usable_steps,
)
from .estimators import (
    BOUND_RTOL,
    CONSTANTS,
    JOINT_LOWER,
    JOINT_UPPER,
    METHODS,
    PAPER_CEL,
    POOLED,
    TOUCH_RTOL,
    UNCONSTRAINED_RULE,
    FitError,
    at_bound,
    constrained_flags,
)
from .grid import (
    fit_cel,
)
from .table import (
    TOPOGRAPHY_CSV_COLUMNS,
    to_csv_table,
)
from .topographies import (
    fit_topographies,
)

__all__ = [
    "CONSTANTS",
    "METHODS",
    "PAPER_CEL",
    "POOLED",
    "FitError",
    "JOINT_LOWER",
    "JOINT_UPPER",
    "BOUND_RTOL",
    "TOUCH_RTOL",
    "UNCONSTRAINED_RULE",
    "at_bound",
    "constrained_flags",
    "exclude_unconverged",
    "unresolved_in_window",
    "usable_steps",
    "fit_cel",
    "fit_topographies",
    "to_csv_table",
    "TOPOGRAPHY_CSV_COLUMNS",
]
