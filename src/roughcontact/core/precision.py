"""Numbers at their precision, for the report: a value rounded to its uncertainty.

A fitted constant printed as ``2.65988 [2.57646, 2.91696]`` claims six figures its interval does not
support. Every number the report prints with an uncertainty follows one rule:

1. The uncertainty (an interval's half-width, or a standard error) keeps two significant figures when
   its leading digit is 1 or 2 and one otherwise (the Particle Data Group's rule, simplified); one also
   when its second figure would be 0, so that the paper's 1.145 ± 0.002 stays as printed
   (:func:`decimals_for`).
2. The value and both ends of its interval are rounded to that decimal place, but the value keeps at most
   :data:`MAX_FIGURES` significant figures, however small its uncertainty.
3. A number that is not 0 is never printed as 0: a value, an end or an error that would round to 0 at
   that place keeps one significant figure instead (``%.1g``: positional down to 0.0001, then with an
   exponent). A value smaller than its interval's width thus reads ``1 [0.0003, 3100]``, not
   ``0 [0, 3100]``; a number that is 0 is printed as 0 at the common place.

4. A value at least as large as its interval's half-width that differs from both ends of the interval is not
   printed equal to either: where rule 2 would print
   ``0.8 [0.1, 0.8]`` for 0.78 in [0.1, 0.84], each gets one more place until they differ (``0.78 [0.10,
   0.84]``); a printed ``v [l, v]`` thus always means an interval that ends at its estimate.

So ``2.65988 [2.57646, 2.91696]`` (half-width 0.17) reads ``2.66 [2.58, 2.92]`` and
``1.0612 [1.0281, 1.1642]`` (half-width 0.068) ``1.06 [1.03, 1.16]``. A value without an interval keeps
:data:`BARE_FIGURES` significant figures; NaN is a dash.

>>> estimate(2.65988, 2.57646, 2.91696)
('2.66', '2.58', '2.92')
>>> estimate(1.47, 0.0003, 3100)
('1', '0.0003', '3100')
>>> plus_minus(0.0003511, 0.00011)
'0.00035 ± 0.00011'
"""

from __future__ import annotations

import math

#: Significant figures of a value printed without an uncertainty.
BARE_FIGURES = 3

#: Most significant figures a value is given, however small its uncertainty.
MAX_FIGURES = 5

#: What a missing number (NaN) is printed as.
MISSING = "—"


def _exponent(x: float, figures: int) -> int:
    """The decimal exponent of ``x`` once rounded to ``figures`` significant figures (0.096 at one: -1)."""
    return int(f"{x:.{figures - 1}e}".split("e")[1])


def decimals_for(uncertainty: float) -> int:
    """The decimal place to round to for an ``uncertainty`` > 0 (negative: tens, hundreds, ...).

    Two significant figures of the uncertainty when its leading digit is 1 or 2, one otherwise; one also
    when the second figure would be 0 (rule 1 of the module docstring).

    Parameters
    ----------
    uncertainty : float
        An interval's half-width or a standard error, finite and > 0, in the unit of the value.

    Returns
    -------
    int
        Decimal places: 2 for 0.17 (0.17), 2 for 0.068 (0.07), 3 for 0.002, -2 for 1559 (1600).

    Examples
    --------
    >>> [decimals_for(u) for u in (0.17, 0.25, 0.068, 0.0050133, 0.002, 0.096, 1559.0)]
    [2, 2, 2, 3, 3, 1, -2]
    """
    if not (math.isfinite(uncertainty) and uncertainty > 0):
        raise ValueError(f"an uncertainty must be finite and > 0, got {uncertainty!r}")
    mantissa = f"{uncertainty:.1e}".split("e")[0]  # two significant figures, e.g. "1.7", "6.8", "2.0"
    if mantissa[0] in "12" and not mantissa.endswith(".0"):
        return 1 - _exponent(uncertainty, 2)
    return -_exponent(uncertainty, 1)


def _at(x: float, decimals: int) -> str:
    """``x`` rounded to ``decimals`` places (negative: to tens, ...), without a spurious ``-0``; a number
    that is not 0 but would read 0 there keeps one significant figure (rule 3 of the module docstring)."""
    if decimals > 0:
        text = f"{x:.{decimals}f}"
    else:
        text = f"{round(x, decimals):.0f}"
    if float(text) == 0:
        return f"{x:.1g}" if x != 0 else text.lstrip("-")
    return text


def _capped(value: float, decimals: int) -> int:
    """``decimals``, lowered so that ``value`` shows at most :data:`MAX_FIGURES` significant figures."""
    if value == 0 or not math.isfinite(value):
        return decimals
    return min(decimals, MAX_FIGURES - 1 - math.floor(math.log10(abs(value))))


def bare(value: float) -> str:
    """A value without an uncertainty: :data:`BARE_FIGURES` significant figures (``"—"`` for NaN).

    >>> bare(2.65988), bare(-0.0), bare(1.2345e-7), bare(float("nan"))
    ('2.66', '0', '1.23e-07', '—')
    """
    if not math.isfinite(value):
        return MISSING
    return "0" if value == 0 else f"{value:.{BARE_FIGURES}g}"


def estimate(value: float, low: float | None = None, high: float | None = None) -> tuple[str, str, str]:
    """``(value, low, high)`` as text, rounded to the interval's half-width by the module's rule.

    Parameters
    ----------
    value, low, high : float
        An estimate and the ends of its interval, in one unit (``low``, ``high``: None or NaN when missing).

    Returns
    -------
    tuple of str
        The three as printed. Without a finite interval of positive width (or for a NaN value), each
        :func:`bare` (``low`` and ``high`` empty when missing).

    Examples
    --------
    >>> estimate(1.0612, 1.0281, 1.1642)  # half-width 0.068: one figure, two places
    ('1.06', '1.03', '1.16')
    >>> estimate(1.466, 1.167, 3120.)  # to hundreds, but 1.466 and 1.167 are not 0
    ('1', '1', '3100')
    >>> estimate(-0.004, -0.3, 0.4), estimate(0.0, -0.3, 0.4)
    (('-0.004', '-0.3', '0.4'), ('0.0', '-0.3', '0.4'))
    >>> estimate(3.14159)
    ('3.14', '', '')
    >>> estimate(0.78, 0.1, 0.84), estimate(1.87, 0.18, 1.87)  # rule 4; an end at the estimate stays
    (('0.78', '0.10', '0.84'), ('1.9', '0.2', '1.9'))
    """
    ends = [v for v in (low, high) if v is not None and math.isfinite(v)]
    if not math.isfinite(value) or len(ends) < 2 or high <= low:
        return bare(value), *("" if v is None or not math.isfinite(v) else bare(v) for v in (low, high))
    d = _capped(value, decimals_for((high - low) / 2))
    # rule 4: a value inside its interval is not printed equal to an end (a reader would take it for an interval
    # that ends at its estimate, which the report marks not constrained): one more place until they differ
    if abs(value) >= (high - low) / 2:  # not where rule 3 already keeps one figure of a value smaller than that
        while value not in (low, high) and _at(value, d) in (_at(low, d), _at(high, d)) and d < _capped(value, 99):
            d += 1
    return _at(value, d), _at(low, d), _at(high, d)


def plus_minus(value: float, error: float | None) -> str:
    """``value ± error``, both rounded to the error by the module's rule; the value alone (:func:`bare`)
    without a finite error > 0 or when the value is NaN.

    Examples
    --------
    >>> plus_minus(1.145, 0.002), plus_minus(0.000835, 1.3e-05)
    ('1.145 ± 0.002', '0.000835 ± 0.000013')
    >>> plus_minus(1000.0, 1e-4)  # the value keeps MAX_FIGURES figures, the error one
    '1000.0 ± 0.0001'
    >>> plus_minus(0.21, float("nan")), plus_minus(float("nan"), 0.1)
    ('0.21', '—')
    """
    if error is None or not (math.isfinite(error) and error > 0) or not math.isfinite(value):
        return bare(value)
    d = _capped(value, decimals_for(error))
    return f"{_at(value, d)} ± {_at(error, d)}"
