"""CF ``units`` strings of the study's quantities, from its declared length and pressure units.

A study declares one length unit (``surface.unit``: the unit of ``L``, the heights
and ``rms_height``) and one pressure unit (``contact.solver.pressure_unit``: the unit
of ``e_star`` and of every pressure); ``"1"`` (the default) declares nondimensional
values. Every dimensional quantity the package writes is a product of powers of the
two, e.g. a moment ``m4`` [length^-2] or the representativity error ``epsilon``
[length^-1/2], and :func:`cf_unit` spells that product::

    cf_unit("um", length_power=1)                       -> "um"
    cf_unit("um", length_power=-2)                      -> "um^-2"
    cf_unit("um", "MPa", length_power=-1, pressure_power=1)  -> "MPa um^-1"
    cf_unit("um", length_power=Fraction(-1, 2))         -> "um^(-1/2)"
    cf_unit("1", "1", length_power=-2, pressure_power=1) -> "1"

Which tool reads which string
-----------------------------
* Integer powers (``"um"``, ``"um^2"``, ``"um^-2"``, ``"MPa"``, ``"MPa um^-1"``,
  ``"1"``): UDUNITS-2 (``cf_units.Unit``, the CF conventions' reference) and ``pint``
  (``pint.UnitRegistry().parse_units``) both parse them to the intended unit.
* Fractional powers (``epsilon``: ``"um^(-1/2)"``): only ``pint`` parses them
  (``1 / micrometer ** 0.5``). UDUNITS-2 has integer exponents only, so no spelling
  of ``um^-1/2`` exists there: ``"um^-0.5"`` is *accepted* by it but read as
  ``um^-0 . 5``, the number 5 (dimensionless, silently wrong), and ``"um^-1/2"`` as
  ``um^-1 / 2``. The parenthesised rational exponent is what ``cf_units`` rejects
  with an error instead of misreading, and what ``pint`` reads exactly.
  Nondimensional studies write ``"1"`` there as everywhere.
"""

from __future__ import annotations

from fractions import Fraction
from numbers import Real

#: Length units a study may declare (``surface.unit``); ``"1"``: nondimensional.
LENGTH_UNITS = ("1", "m", "mm", "um", "nm")
#: Pressure units a study may declare (``contact.solver.pressure_unit``); ``"1"``: nondimensional.
PRESSURE_UNITS = ("1", "Pa", "kPa", "MPa", "GPa")


def _power(name: str, value) -> Fraction:
    if isinstance(value, bool) or not isinstance(value, (Real, Fraction)):
        raise ValueError(f"{name} must be a rational number, got {value!r}")
    exact = Fraction(value).limit_denominator(64)
    if float(exact) != float(value):
        raise ValueError(f"{name} must be a rational number with a small denominator, got {value!r}")
    return exact


def _factor(unit: str, power: Fraction) -> str:
    if unit == "1" or power == 0:
        return ""
    if power == 1:
        return unit
    if power.denominator == 1:
        return f"{unit}^{power.numerator}"
    return f"{unit}^({power.numerator}/{power.denominator})"


def cf_unit(length: str = "1", pressure: str = "1", *, length_power=0, pressure_power=0) -> str:
    """The ``units`` string of ``pressure^pressure_power * length^length_power``.

    Parameters
    ----------
    length : str
        The study's length unit, one of :data:`LENGTH_UNITS` (``"1"``: nondimensional).
    pressure : str
        The study's pressure unit, one of :data:`PRESSURE_UNITS` (``"1"``: nondimensional).
    length_power, pressure_power : int, float or fractions.Fraction
        Exponents, e.g. ``2`` for an area or ``Fraction(-1, 2)`` (or ``-0.5``) for
        ``epsilon``.

    Returns
    -------
    str
        Factors separated by a space, pressure first: ``"um"``, ``"um^-2"``,
        ``"MPa um^-1"``, ``"um^(-1/2)"``; ``"1"`` when nothing dimensional remains.
        Integer powers parse with UDUNITS-2 (``cf_units``) and ``pint``, fractional ones
        with ``pint`` only (module docstring).

    Raises
    ------
    ValueError
        For a unit outside the declared sets or a power that is not a simple rational.
    """
    if length not in LENGTH_UNITS:
        raise ValueError(f"length unit must be one of {list(LENGTH_UNITS)}, got {length!r}")
    if pressure not in PRESSURE_UNITS:
        raise ValueError(f"pressure unit must be one of {list(PRESSURE_UNITS)}, got {pressure!r}")
    factors = [_factor(pressure, _power("pressure_power", pressure_power)),
               _factor(length, _power("length_power", length_power))]
    return " ".join(f for f in factors if f) or "1"
