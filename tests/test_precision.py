"""Numbers at their precision (roughcontact.core.precision): one rule for every number the report prints."""
import doctest
import itertools

import pytest

from roughcontact.core import precision
from roughcontact.theory.laws import KAPPA_BGT


def test_the_docstrings_examples_hold():
    assert doctest.testmod(precision).failed == 0


@pytest.mark.parametrize(("uncertainty", "decimals"), [
    (0.17, 2),  # leading digit 1: two figures
    (0.25, 2),  # leading digit 2: two figures
    (0.068, 2),  # leading digit 6: one figure (the demo's "1.061 [1.028, 1.164]", half-width 0.068)
    (0.0050133, 3),  # one figure
    (0.002, 3),  # its second figure is 0: one figure (the paper's 1.145 +- 0.002)
    (0.0296, 2),  # rounds to 0.030: leading digit 3, one figure
    (0.096, 1),  # rounds to 0.1: one figure
    (1559.0, -2),  # to hundreds
])
def test_the_half_width_keeps_two_figures_only_when_it_leads_with_1_or_2(uncertainty, decimals):
    assert precision.decimals_for(uncertainty) == decimals


@pytest.mark.parametrize(("value", "low", "high", "shown"), [
    (1.0612, 1.0281, 1.1642, ("1.06", "1.03", "1.16")),  # the demo's fit table: half-width 0.068
    (1.47, 0.0003, 3100.0, ("1", "0.0003", "3100")),  # a value and an end that would read 0 keep one figure
    # the lines scene's kappa = 3.67558 [2.92474, 7819.49] as kappa/sqrt(2 pi): it read "0 [0, 3100]"
    (3.67558 / KAPPA_BGT, 2.92474 / KAPPA_BGT, 7819.49 / KAPPA_BGT, ("1", "1", "3100")),
    (-0.004, -0.3, 0.4, ("-0.004", "-0.3", "0.4")),  # a negative value below the interval's place
    (0.0, -0.3, 0.4, ("0.0", "-0.3", "0.4")),  # a value that is 0 is printed as 0
    (0.096, 0.001, 10.0, ("0.1", "0.001", "10")),  # one figure, rounded up
    (float("nan"), 1.0, 2.0, ("—", "1", "2")),
])
def test_no_number_that_is_not_zero_reads_zero(value, low, high, shown):
    assert precision.estimate(value, low, high) == shown


@pytest.mark.parametrize(("value", "error", "shown"), [
    (0.0003511, 0.00011, "0.00035 ± 0.00011"),  # the adhesion scene's pull-off: it read "0.0003511 ± 0.00011"
    (0.000835, 1.3e-05, "0.000835 ± 0.000013"),  # it read "0.000835 ± 1.3e-05"
    (0.0003, 3100.0, "0.0003 ± 3000"),  # a value far below its error keeps one figure
    (1000.0, 1e-4, "1000.0 ± 0.0001"),  # an error far below the value's MAX_FIGURES keeps one figure
    (-2.0, 0.17, "-2.00 ± 0.17"),
    (0.0, 0.17, "0.00 ± 0.17"),
    (1.0612, 0.068, "1.06 ± 0.07"),
    (float("nan"), 0.1, "—"),
])
def test_plus_minus_follows_the_same_rule(value, error, shown):
    assert precision.plus_minus(value, error) == shown


@pytest.mark.parametrize(("value", "shown"), [(1.2345e-7, "1.23e-07"), (-0.0, "0"), (0.0, "0"),
                                              (-3.14159, "-3.14"), (float("nan"), "—")])
def test_a_bare_value_keeps_three_figures(value, shown):
    assert precision.bare(value) == shown


def test_over_many_magnitudes_a_printed_number_is_zero_only_if_it_is():
    magnitudes = [10.0 ** k for k in range(-7, 7)]
    for v, lo, hi in itertools.product([0.0, 3.7e-6, -0.0042, 1.47, 812.0],
                                       [-m for m in magnitudes[::3]] + magnitudes[::3],
                                       magnitudes[1::2]):
        if hi <= lo:
            continue
        for raw, text in zip((v, lo, hi), precision.estimate(v, lo, hi), strict=True):
            assert (float(text) == 0) == (raw == 0), (v, lo, hi, text)
        text = precision.plus_minus(v, hi)
        shown_value, shown_error = (float(t) for t in text.split(" ± "))
        assert (shown_value == 0) == (v == 0) and shown_error > 0, (v, hi, text)
        if v != 0:  # the value keeps at most MAX_FIGURES significant figures
            digits = precision.estimate(v, lo, hi)[0].lstrip("-").replace(".", "").lstrip("0")
            assert 1 <= len(digits) <= precision.MAX_FIGURES, (v, lo, hi)


@pytest.mark.parametrize(("value", "low", "high", "shown"), [
    (2.65988, 2.57646, 2.91696, ("2.66", "2.58", "2.92")),  # the example: half-width 0.17
    (0.41, 1e-6, 0.62, ("0.4", "1e-06", "0.6")),  # half-width 0.31: one figure; 1e-6 is not 0
    (1234.5, 1000.0, 1500.0, ("1230", "1000", "1500")),  # rounded to tens
    (1.0, 1.0, 1.0, ("1", "1", "1")),  # no width: three figures
    (-0.0, -0.1, 0.1, ("0.0", "-0.1", "0.1")),  # no "-0.0"
    (-0.0001, -0.1, 0.1, ("-0.0001", "-0.1", "0.1")),  # not 0: one figure
    (3.14159, float("nan"), float("nan"), ("3.14", "", "")),
])
def test_a_value_is_rounded_to_its_interval(value, low, high, shown):
    assert precision.estimate(value, low, high) == shown


def test_published_values_keep_the_figures_of_their_error():
    assert precision.plus_minus(2.87009, 0.00501326) == "2.870 ± 0.005"
    assert precision.plus_minus(1.145, 0.002) == "1.145 ± 0.002"
    assert precision.plus_minus(0.55, 0.02) == "0.55 ± 0.02"
    assert precision.plus_minus(2.0, 0.17) == "2.00 ± 0.17"
    assert precision.plus_minus(0.21, float("nan")) == "0.21"
    with pytest.raises(ValueError, match="finite and > 0"):
        precision.decimals_for(0.0)


@pytest.mark.parametrize(("value", "low", "high", "shown"), [
    (0.78, 0.1, 0.84, ("0.78", "0.10", "0.84")),   # rule 2 alone: 0.8 [0.1, 0.8], which reads as touching
    (0.2, 0.19996, 0.5, ("0.20000", "0.19996", "0.50000")),  # as many places as it takes, up to MAX_FIGURES
    (1.87, 0.18, 1.87, ("1.9", "0.2", "1.9")),      # it does touch: left as it is (and marked by the report)
    (1.466, 1.167, 3120.0, ("1", "1", "3100")),     # a value under its half-width: rule 3, not rule 4
])
def test_a_value_inside_its_interval_is_not_printed_equal_to_an_end(value, low, high, shown):
    """Issue 60's demo: 0.8 [0.1, 0.8] for a value strictly inside; a reader takes it for an interval that ends at
    its estimate."""
    assert precision.estimate(value, low, high) == shown
