"""Perfect plasticity of the interface: the pressure is capped at the hardness."""

from __future__ import annotations

import numpy as np

from ..results import FRACTION_UNITS
from ..units import Units, check_range
from ..validation import check_positive
from .base import Effect, register


@register
class PlasticityCap(Effect):
    """Perfectly plastic interface: the pressure is capped at the hardness ``H``.

    As Tamaas' ``KatoSaturated``: ``0 <= p <= H``; nodes at the cap may
    interpenetrate (``g <= 0`` there). Each load step is solved for its load
    alone (no plastic history).

    Parameters
    ----------
    hardness : float
        Cap ``H`` [pressure], finite and > 0, and > every load.
    """

    name = "plasticity"

    def __init__(self, hardness: float):
        self.hardness = check_positive("hardness", hardness)
        self.pressure_cap = self.hardness
        self.upper_bound = None

    @classmethod
    def from_config(cls, block: dict, *, e_star: float) -> PlasticityCap:
        """``contact.effects.plasticity``: ``hardness`` relative to ``E*``."""
        return cls(block["hardness"] * e_star)

    def check_final_load(self, p0: float, e_star: float, load: str, fail) -> None:
        """The hardness must exceed the final load ``p0`` [pressure] (``load``: where it came from, p0/E* in its words).

        The one statement of the rule: the planner calls it with ``load.p_max`` (relative to E*, or times the
        generator's or each file's rms slope), a case with its own resolved final load
        (:meth:`roughcontact.case.LoadSchedule.check_final_load`).
        """
        if not p0 < self.hardness:
            fail(".hardness", f"{self.hardness / e_star:g} must exceed {load}: a pressure capped at the hardness "
                              "cannot carry a mean load p0 >= hardness; raise it or lower load.p_max")

    def check_surface(self, units: Units, periodic: bool) -> None:
        if units.flat and not periodic:
            raise ValueError(
                "hardness: a perfectly flat surface (all heights equal) on the free half-space is a rigid "
                "flat punch, whose edge pressures would reach any hardness; boundary='free' with a "
                "hardness is not supported for a flat surface (give hardness=None or a rough surface)")

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

    def finish(self, p: np.ndarray, p_int: np.ndarray | None, p0: float, gap: np.ndarray | None = None) -> dict:
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
