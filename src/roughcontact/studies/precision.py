"""Numbers at their precision, for the report: a value rounded to its uncertainty.

A fitted constant printed as ``2.65988 [2.57646, 2.91696]`` claims six figures its interval does not
support. The report prints it as ``2.66 [2.58, 2.92]``: the interval's half-width keeps two significant
figures when its leading digit is 1 or 2 and one otherwise (the Particle Data Group's rule, simplified), and
the value and both ends are rounded to the same decimal place. A value without an interval keeps three
significant figures; a published value with its standard error is written ``value ± error`` by the same rule.
"""

from __future__ import annotations

import math

#: Significant figures of a value printed without an uncertainty.
BARE_FIGURES = 3

#: Most significant figures a value is given, however small its uncertainty.
MAX_FIGURES = 5


def decimals_for(uncertainty: float) -> int:
    """The decimal place to round to for an ``uncertainty`` > 0 (negative: tens, hundreds, ...).

    Two significant figures of the uncertainty, one when the second is 0: 0.17 keeps 2 places, 0.0050133
    (0.0050) and 0.002 keep 3, as the paper prints 1.145 ± 0.002.
    """
    if not (math.isfinite(uncertainty) and uncertainty > 0):
        raise ValueError(f"an uncertainty must be finite and > 0, got {uncertainty!r}")
    mantissa, exponent = f"{uncertainty:.1e}".split("e")  # two significant figures, e.g. "5.0", "-03"
    return (0 if mantissa.endswith(".0") else 1) - int(exponent)


def _at(x: float, decimals: int) -> str:
    """``x`` rounded to ``decimals`` places (negative: to tens, ...), without a spurious ``-0``."""
    if decimals > 0:
        text = f"{x:.{decimals}f}"
    else:
        text = f"{round(x, decimals):.0f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def _capped(value: float, decimals: int) -> int:
    """``decimals``, lowered so that ``value`` shows at most :data:`MAX_FIGURES` significant figures."""
    if value == 0 or not math.isfinite(value):
        return decimals
    return min(decimals, MAX_FIGURES - 1 - math.floor(math.log10(abs(value))))


def bare(value: float) -> str:
    """A value without an uncertainty: :data:`BARE_FIGURES` significant figures (``"—"`` for NaN)."""
    return "—" if not math.isfinite(value) else f"{value:.{BARE_FIGURES}g}"


def estimate(value: float, low: float | None = None, high: float | None = None) -> tuple[str, str, str]:
    """``(value, low, high)`` as text, rounded to the interval's half-width (:func:`decimals_for`).

    Without a finite interval of positive width, each is given to :data:`BARE_FIGURES` significant
    figures (``low`` and ``high`` empty when missing).
    """
    ends = [v for v in (low, high) if v is not None and math.isfinite(v)]
    if not math.isfinite(value) or len(ends) < 2 or high <= low:
        return bare(value), *("" if v is None or not math.isfinite(v) else bare(v) for v in (low, high))
    d = _capped(value, decimals_for((high - low) / 2))
    return _at(value, d), _at(low, d), _at(high, d)


def plus_minus(value: float, error: float | None) -> str:
    """``value ± error``, both rounded to the error (:func:`decimals_for`); the value alone without one."""
    if error is None or not (math.isfinite(error) and error > 0):
        return bare(value)
    d = _capped(value, decimals_for(error))
    return f"{_at(value, d)} ± {_at(error, d)}"
