"""Effects that act on the contact iteration without living inside its loop.

An effect changes the problem the iteration solves (today: a bound on the
pressure) and what each step reports. The solver asks its effects for

* ``check_loads(units, p, name)``: refuse loads the effect cannot carry, with
  a ``ValueError`` naming the argument;
* ``bind(units)``: convert its parameters to the solver's internal units;
* ``upper_bound``: an internal cap on the pressure, or ``None``; a cap makes the
  solver use the bounded iteration (:mod:`.box`), whose free set excludes the
  capped nodes and whose gradient-projection steps release them;
* ``finish(p, p_int)``: its per-step columns from the physical pressure ``p``
  (which it may correct in place, e.g. exactly to the cap);
* ``variables(length_unit="1", pressure_unit="1")`` and ``attrs()``: the output
  variables (name -> (units, long name), units composed from the caller's length and
  pressure units with :func:`roughcontact.quantities.cf_unit`) and the global
  attributes it adds (a pressure there is in the dataset's ``pressure_units``).

Adhesion, for example, would be a second effect of this kind.
"""

from __future__ import annotations

import numpy as np

from .results import FRACTION_UNITS
from .units import Units, check_range


class PlasticityCap:
    """Perfectly plastic interface: the pressure is capped at the hardness ``H``.

    As Tamaas' ``KatoSaturated``: ``0 <= p <= H``; nodes at the cap may
    interpenetrate (``g <= 0`` there). Each load step is solved for its load
    alone (no plastic history).

    Parameters
    ----------
    hardness : float
        Cap ``H`` [pressure], > 0 (validated by the caller) and > every load.
    """

    name = "plasticity"

    def __init__(self, hardness: float):
        self.hardness = float(hardness)
        self.upper_bound = None

    def check_loads(self, units: Units, p: np.ndarray, name: str) -> None:
        label = "p0" if name == "p0" else "every p0"
        if np.any(p >= self.hardness):
            bad = float(p.max())
            raise ValueError(
                f"{name}: {label} must be in the open interval (0, hardness) = (0, {self.hardness!r}): a "
                f"pressure capped at the hardness cannot carry a mean load >= hardness (every applied mean "
                f"pressure must be < hardness); got {name if name == 'p0' else 'max p0'} = {bad!r}")

    def check_range(self, units: Units) -> None:
        check_range(units, "hardness", "hardness", self.hardness)

    def bind(self, units: Units) -> None:
        self.upper_bound = None if units.flat else units.to_internal(self.hardness)

    def finish(self, p: np.ndarray, p_int: np.ndarray, p0: float) -> dict:
        """Set capped nodes exactly to ``H``; the plastic area and load fractions."""
        n2 = p.size
        if self.upper_bound is not None:
            p[p_int >= self.upper_bound] = self.hardness  # exactly the cap in physical units too
            np.minimum(p, self.hardness, out=p)
        n_sat = int(np.count_nonzero(p >= self.hardness))
        return {"plastic_area_fraction": n_sat / n2,
                "plastic_load_fraction": self.hardness * n_sat / (p0 * n2)}

    def variables(self, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        # both fractions are dimensionless whatever the units
        return {"plastic_area_fraction": (FRACTION_UNITS, "fraction of nodes at the hardness cap"),
                "plastic_load_fraction": (FRACTION_UNITS,
                                          "share of the load carried by nodes at the hardness cap")}

    def attrs(self) -> dict:
        return {"hardness": self.hardness}
