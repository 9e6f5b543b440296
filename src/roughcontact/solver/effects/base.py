"""What an effect supplies to the contact iteration, and the registry that finds one by name.

An effect changes the problem the iteration solves and what each step reports, without
living inside the iteration's loop (Tamaas' functionals added to a solver). Each effect is
one module in this package holding one :class:`Effect` subclass, registered with
:func:`register` under the name a scene uses (``contact.effects.<name>`` in the config).
The solver asks every effect it is given for

* ``check_surface(units, periodic)`` and ``check_loads(units, p, name)``: refuse a surface or
  loads the effect cannot act on, with a ``ValueError`` naming the argument;
* ``check_range(units)``: refuse parameters float64 cannot represent in internal units;
* ``bind(units)``: convert its parameters to the solver's internal units;
* ``upper_bound`` (internal) and ``pressure_cap`` (physical): a cap on the pressure, or
  ``None``; a cap makes the solver use the bounded iteration (:mod:`..box`);
* ``functional``: an interaction energy of the gap (with its gradient) for the gap iteration,
  or ``None``;
* ``finish(p, p_int, p0, gap=None)``: its per-step columns from the physical pressure ``p`` (which it
  may correct in place, e.g. exactly to the cap) and, from the gap iteration, the gap;
* ``variables(length_unit, pressure_unit)`` and ``attrs()``: its output variables (name ->
  (CF units, long name)) and the global attributes it adds;
* ``after_steps(solver, length_unit, pressure_unit)``: per-solve variables computed after the
  load steps (name -> :class:`xarray.Variable` with CF ``units`` or flags and ``long_name``), e.g. a
  pull-off force and the unloading branch;
* ``from_config(block, e_star=...)``: the effect from its config block (``contact.effects.<name>``,
  already schema-checked), ``e_star`` the modulus its relative parameters scale with; the only
  method that reads a config block, and only the effect's own.

What the pipeline asks of an effect instead of its name (declared here, so that a new effect
changes no planner, rule or report module to say what it needs and gives):

* ``needs_gap_iteration``: it supplies an interaction energy of the gap (``functional``), so the
  solver runs the gap iteration, which solves maps only and one such effect at a time;
* ``adds_tension``: its pressures can be tensile (an attractive traction), so an observable of
  compressive pressures alone (the pressure distribution P(p)) does not describe it;
* ``keeps_elastic_law``: contact with it still follows the contact evolution law of non-adhesive
  elastic contact, so the CEL fit, kappa and the non-adhesive theories apply (False: the
  pipeline runs no fit and draws none of its figures);
* ``figures`` and ``tables``: the report's figures (names of the figures registry,
  :data:`roughcontact.figures.registry.FIGURES` less a patch source's ``measured_`` prefix) and
  tables (``pull_off``) it brings;
* ``contact_name``, ``intro_fact`` and ``intro_text(fact)``: what the report calls contact with the
  effect ("adhesive contact"; "" leaves it "contact"), the JSON-able fact its introduction keeps
  of the parameters and the sentence it writes of that fact.

The cross-field rules a schema cannot express, each written once here and called by the planner
(:mod:`roughcontact.pipeline.config.checks`, a patch source's files), by the contact job and by
:meth:`roughcontact.case.LoadSchedule.check_final_load`, from numbers, never a scene's mapping;
``fail(field, message)`` reports one (``field`` after the effect's name: ``".hardness"``, or ``""``
for the effect itself):

* ``check_config(fail, others=..., boundary=...)``: what a scene may not ask of the effect, given
  the other effects' names and the half-space's boundary;
* ``check_grid(e_star, length, shape, pixel, fail, n_field=None, most_n=None)``: a grid of
  ``shape`` on a cell of ``length`` the effect cannot resolve (``n_field``: the config field that
  sets a square grid's N, when the remedy may name the N it needs, at most ``most_n``);
* ``check_final_load(p0, e_star, load, fail)``: a final mean load ``p0`` [pressure] the effect
  cannot carry, ``load`` saying where it came from.
"""

from __future__ import annotations

import numpy as np

from ...core.registry import registrar
from ..units import Units

#: The effects a scene can name, by name (filled by :func:`register`).
EFFECTS: dict[str, type[Effect]] = {}


#: Class decorator: make a class available to scenes under its ``name``.
register = registrar(EFFECTS, "effect")


class Effect:
    """An effect that does nothing: the defaults every effect starts from."""

    name = ""
    #: internal cap on the pressure after :meth:`bind`, or None
    upper_bound: float | None = None
    #: physical cap on the pressure [pressure], or None
    pressure_cap: float | None = None
    #: interaction energy of the gap for the gap iteration, or None
    functional = None

    def check_surface(self, units: Units, periodic: bool) -> None:
        """Refuse a surface the effect cannot act on (``ValueError`` naming the argument)."""

    def check_loads(self, units: Units, p: np.ndarray, name: str) -> None:
        """Refuse loads ``p`` (the argument ``name``) the effect cannot carry."""

    def check_range(self, units: Units) -> None:
        """Refuse parameters outside what float64 represents in internal units."""

    def bind(self, units: Units) -> None:
        """Convert the parameters to the solver's internal units."""

    def finish(self, p: np.ndarray, p_int: np.ndarray | None, p0: float, gap: np.ndarray | None = None) -> dict:
        """The effect's per-step columns from the physical pressure ``p`` (n, n) (and the gap, if known)."""
        return {}

    def variables(self, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        """Output variables: name -> (CF units, long name)."""
        return {}

    def attrs(self) -> dict:
        """Global attributes the effect adds to the output."""
        return {}

    def after_steps(self, solver, length_unit: str = "1", pressure_unit: str = "1") -> dict:
        """Variables of the whole solve, after its load steps: name -> :class:`xarray.Variable`."""
        return {}

    #: contact with the effect follows the contact evolution law of non-adhesive elastic contact
    keeps_elastic_law = True
    #: its pressures can be tensile (an attractive traction)
    adds_tension = False
    #: the report's figures it brings (the figures registry's names)
    figures: tuple[str, ...] = ()
    #: the report's tables it brings
    tables: tuple[str, ...] = ()
    #: what the report calls contact with the effect ("" leaves it "contact")
    contact_name = ""

    @property
    def needs_gap_iteration(self) -> bool:
        """Whether the effect supplies an interaction energy of the gap: the solver runs the gap iteration."""
        return self.functional is not None

    @property
    def intro_fact(self):
        """What the report's introduction keeps of the parameters (JSON-able), or None."""
        return None

    @classmethod
    def intro_text(cls, fact) -> str:
        """The introduction's words on contact with the effect ("with ..."), from its :attr:`intro_fact`."""
        return ""

    def check_config(self, fail, *, others=(), boundary: str = "periodic") -> None:
        """Refuse what a scene may not ask of the effect, given the other effects' names and the boundary."""

    def check_grid(self, e_star: float, length, shape, pixel: str, fail, *, n_field: str | None = None,
                   most_n: int | None = None) -> None:
        """Refuse a grid of ``shape`` on a cell of ``length`` (``pixel`` names its pixel) the effect cannot resolve."""

    def check_final_load(self, p0: float, e_star: float, load: str, fail) -> None:
        """Refuse a final mean load ``p0`` [pressure] the effect cannot carry (``load``: where it came from)."""

    @classmethod
    def from_config(cls, block: dict, *, e_star: float) -> Effect:
        """The effect from its schema-checked config block."""
        raise NotImplementedError(f"effect {cls.name!r} has no config block")


def effects_from_config(blocks: dict, *, e_star: float) -> tuple[Effect, ...]:
    """The effects a scene's ``contact.effects`` mapping names, in its order."""
    unknown = sorted(set(blocks) - set(EFFECTS))
    if unknown:
        raise ValueError(f"contact.effects: unknown effect(s) {unknown}; known: {sorted(EFFECTS)}")
    return tuple(EFFECTS[name].from_config(block, e_star=e_star) for name, block in blocks.items())
