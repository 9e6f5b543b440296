"""CF ``units`` strings of the study's quantities, from its declared length and pressure units.

A study declares one length unit (``surface.unit``: the unit of ``L``, the heights
and ``rms_height``) and one pressure unit (``contact.solver.pressure_unit``: the unit
of ``e_star`` and of every pressure); ``"1"`` (the default) declares nondimensional
values. Every dimensional quantity the package writes is a product of integer powers of
the two, e.g. a moment ``m4`` [length^-2], and :func:`cf_unit` spells that product::

    cf_unit("um", length_power=1)                            -> "um"
    cf_unit("um", length_power=-2)                           -> "um^-2"
    cf_unit("um", "MPa", length_power=-1, pressure_power=1)  -> "MPa um^-1"
    cf_unit("1", "1", length_power=-2, pressure_power=1)     -> "1"

The product is built and formatted by pint (``pint.Unit`` arithmetic and a registered
format, ``"~roughcontact_udunits"``, that writes UDUNITS-2 syntax: factors separated by a space,
integer powers as ``^n``, the ASCII micro prefix ``u``) and read back by pint to check it
means that unit; the tests parse every string the pipeline writes with UDUNITS-2
(``cf_units``, the CF conventions' reference) to the same size.

Fractional powers
-----------------
UDUNITS-2, and so CF (section 3.1), has integer exponents only: no ``units`` string means
length^-1/2, the unit of the representativity error ``epsilon``. ``"um^-0.5"`` is even
*accepted* by UDUNITS-2 but read as ``um^-0 . 5``, the number 5 (dimensionless, silently
wrong), and ``"um^(-1/2)"`` is rejected. :func:`cf_unit` therefore refuses a fractional
power, and such a quantity is written as a number: its value for lengths in units of one
reference length ``ell`` (1 of the study's length unit), which is dimensionless
(``units: "1"``), with ``ell`` recorded alongside (:func:`per_reference_length`). For
``epsilon`` of heights in um the number is eps in um^-1/2, i.e. ``eps * sqrt(1 um)``.
"""

from __future__ import annotations

import functools
from fractions import Fraction
from numbers import Real

#: Length units a study may declare (``surface.unit``); ``"1"``: nondimensional.
LENGTH_UNITS = ("1", "m", "mm", "um", "nm")
#: Pressure units a study may declare (``contact.solver.pressure_unit``); ``"1"``: nondimensional.
PRESSURE_UNITS = ("1", "Pa", "kPa", "MPa", "GPa")
#: Attributes of a value written as a number for lengths in a reference unit (:func:`per_reference_length`).
REFERENCE_ATTRS = ("reference_length_units", "reference_length_power")
#: The pint format (registered by :func:`_registry`) that writes a unit in UDUNITS-2 syntax.
UDUNITS_FORMAT = "roughcontact_udunits"


def _udunits_format(unit, registry, **options) -> str:
    """pint format ``"~roughcontact_udunits"``: ``{"MPa": 1, "µm": -1}`` -> ``"MPa um^-1"``; ``""`` if dimensionless.

    Integer powers only (UDUNITS-2 has no others); the micro sign becomes UDUNITS' ASCII ``u``.
    """
    factors = []
    for symbol, power in unit.items():
        if not float(power).is_integer():
            raise ValueError(f"UDUNITS-2 (and so CF) has integer powers only; {symbol}^{power} has no units "
                             "string: write the value for lengths in a reference unit instead "
                             "(roughcontact.core.quantities.per_reference_length)")
        name = str(symbol).replace("\N{MICRO SIGN}", "u").replace("\N{GREEK SMALL LETTER MU}", "u")
        factors.append(name if power == 1 else f"{name}^{int(power)}")
    return " ".join(factors)


@functools.cache
def _registry():
    """A pint unit registry, made on first use (about 0.4 s of CPU), with the format :data:`UDUNITS_FORMAT`."""
    import pint

    try:
        pint.register_unit_format(UDUNITS_FORMAT)(_udunits_format)
    except ValueError:  # registered already (pint's format table is global: a reloaded module)
        pass
    return pint.UnitRegistry()


def _power(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (Real, Fraction)):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    exact = Fraction(value).limit_denominator(64)
    if float(exact) != float(value):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    if exact.denominator != 1:
        raise ValueError(f"{name} = {exact}: UDUNITS-2 (and so CF) has integer powers only; write the value "
                         "for lengths in a reference unit instead (roughcontact.core.quantities.per_reference_length)")
    return exact.numerator


def _unit(name: str, allowed: tuple[str, ...], kind: str):
    if name not in allowed:
        raise ValueError(f"{kind} unit must be one of {list(allowed)}, got {name!r}")
    ureg = _registry()
    return ureg.dimensionless if name == "1" else ureg.Unit(name)


def cf_unit(length: str = "1", pressure: str = "1", *, length_power=0, pressure_power=0) -> str:
    """The ``units`` string of ``pressure^pressure_power * length^length_power``.

    Parameters
    ----------
    length : str
        The study's length unit, one of :data:`LENGTH_UNITS` (``"1"``: nondimensional).
    pressure : str
        The study's pressure unit, one of :data:`PRESSURE_UNITS` (``"1"``: nondimensional).
    length_power, pressure_power : int (or an integral float or fractions.Fraction)
        Exponents, e.g. ``2`` for an area, ``-1`` for a perimeter density.

    Returns
    -------
    str
        UDUNITS-2 syntax, pressure first: ``"um"``, ``"um^-2"``, ``"MPa um^-1"``; ``"1"`` when
        nothing dimensional remains. Built and formatted by pint, read back by pint to the
        same unit.

    Raises
    ------
    ValueError
        For a unit outside the declared sets, or a power that is not an integer (UDUNITS-2
        cannot write it: use :func:`per_reference_length`).
    """
    unit = _registry().dimensionless
    for name, allowed, kind, power in ((pressure, PRESSURE_UNITS, "pressure", pressure_power),
                                       (length, LENGTH_UNITS, "length", length_power)):
        base, exponent = _unit(name, allowed, kind), _power(f"{kind}_power", power)
        if exponent:  # pint keeps a factor of power 0 ("MPa^0"), which it then cannot read back
            unit = unit * base**exponent
    text = format(unit, "~" + UDUNITS_FORMAT) or "1"
    back = _registry().parse_units(text) if text != "1" else _registry().dimensionless
    if back != unit:  # pragma: no cover - a format that pint itself misreads
        raise ValueError(f"units {text!r} read back by pint as {back}, not {unit}")
    return text


def per_reference_length(length: str, power) -> dict:
    """CF attributes of a quantity of dimension length^``power`` (any rational) written as a number.

    The value is written for lengths in units of the reference length ``ell`` = 1 ``length``
    (the study's length unit), i.e. the quantity times ``ell^-power``: a pure number, so
    ``units`` is ``"1"``, which UDUNITS-2 and CF accept. Where ``power`` is an integer,
    :func:`cf_unit` writes the unit itself; this is for the fractional ones it cannot write.

    Parameters
    ----------
    length : str
        The study's length unit, one of :data:`LENGTH_UNITS` (``"1"``: the lengths are
        nondimensional already).
    power : int, float or fractions.Fraction
        The quantity's power of length, e.g. ``Fraction(-1, 2)`` for ``epsilon``.

    Returns
    -------
    dict
        ``units`` ``"1"``; ``reference_length_units``, the unit of ``ell`` (a UDUNITS-2 string:
        ``cf_unit(length, length_power=1)``); ``reference_length_power``, ``power`` as a
        fraction text (``"-1/2"``). The quantity in (``reference_length_units``)^power is the
        number itself: ``epsilon`` ``0.8`` with ``"um"``, ``"-1/2"`` is 0.8 um^-1/2.
    """
    if isinstance(power, bool) or not isinstance(power, (Real, Fraction)) or \
            float(Fraction(power).limit_denominator(64)) != float(power):
        raise ValueError(f"power must be a rational number with a small denominator, got {power!r}")
    return {"units": "1", "reference_length_units": cf_unit(length, length_power=1),
            "reference_length_power": str(Fraction(power).limit_denominator(64))}
