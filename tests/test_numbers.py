"""The one terminal style of a measured quantity, against hand-worked ILAC-P14 §5.4 roundings.

Each expected string was worked by hand: U to two significant digits (round half to even, as
round_ilac states), the value rounded to the same decimal place, k with two decimals, p in %.
"""

from __future__ import annotations

import pytest

from rotacal.numbers import (
    NOT_DETERMINED,
    element_of,
    elements_of,
    format_plain,
    format_quantity,
    quantity_of,
)


@pytest.mark.parametrize(
    ("value", "U", "k", "unit", "expected"),
    [
        # GUM §7.2.6's value 10.057 62 Ω with U = 0.0534 Ω: U → 0.053, value to 3 decimals
        (10.05762, 0.0534, 2.0, "ohm", "10.058 ± 0.053 ohm (k = 2.00, p = 95 %)"),
        # U = 0.0996 rounds up into a new digit: 0.10, so the value keeps two decimals
        (1.23456, 0.0996, 1.96, "deg", "1.23 ± 0.10 deg (k = 1.96, p = 95 %)"),
        # a tie goes to the even digit: U = 1.25 → 1.2; the value 3.14159 → 3.1
        (3.14159, 1.25, 2.0, "%", "3.1 ± 1.2 % (k = 2.00, p = 95 %)"),
        # large numbers: U = 1234 → 1200, the value to hundreds
        (56789.0, 1234.0, 2.0, "Hz", "56800 ± 1200 Hz (k = 2.00, p = 95 %)"),
        # value tie to even at the place of U = 96: 1234.5 → 1234
        (1234.5, 96.0, 2.0, "", "1234 ± 96 (k = 2.00, p = 95 %)"),
        # a negative value, a small U: −0.0013 ± 0.0011
        (-0.0012749, 0.00108, 12.78, "deg/s", "-0.0013 ± 0.0011 deg/s (k = 12.78, p = 95 %)"),
        # trailing zeros that carry meaning are kept
        (0.5, 3.0e-7, 1.959964, "deg", "0.50000000 ± 0.00000030 deg (k = 1.96, p = 95 %)"),
    ],
)
def test_value_with_U(value, U, k, unit, expected):
    assert format_quantity(value, unit, U=U, k=k, p=0.95) == expected


def test_coverage_probability_keeps_the_digits_it_needs():
    assert (
        format_quantity(1.0, "V", U=0.2, k=2.0, p=0.9545)
        == "1.00 ± 0.20 V (k = 2.00, p = 95.45 %)"  # 2 digits of U
    )
    assert format_quantity(1.0, "V", U=0.25, k=3.0, p=0.99) == "1.00 ± 0.25 V (k = 3.00, p = 99 %)"


@pytest.mark.parametrize("U", [None, 0.0, float("nan"), float("inf"), -1.0])
def test_without_an_uncertainty_the_value_stands_alone(U):
    assert format_quantity(0.123456789, "deg", U=U, k=2.0, p=0.95) == "0.123457 deg"


def test_a_quantity_not_determined():
    assert format_quantity(None, "deg/h") == NOT_DETERMINED
    assert format_quantity(float("nan"), "deg/h", U=1.0, k=2.0) == NOT_DETERMINED
    assert format_plain(None) == NOT_DETERMINED


def test_an_interval_not_centred_on_the_value():
    """NL 0.01891 %FS, interval [0.01711, 0.02024]: U = half the width = 0.001565 → 0.0016, so the
    value and the limits go to four decimals."""
    text = format_quantity(
        0.01891, "%FS", U=0.001565, k=3.09, p=0.95, interval=(0.017107, 0.020238)
    )
    assert text == "0.0189 %FS, true value in [0.0171, 0.0202] %FS (p = 95 %)"


def test_an_interval_of_a_bounded_quantity_starts_at_zero():
    """A THD of 0.000116 % whose interval reaches below zero: a THD is not negative."""
    text = format_quantity(0.000116, "%", U=5.2e-5, k=2.4, p=0.95, interval=(-1e-6, 0.000104))
    assert text == "0.000116 %, true value in [0.000000, 0.000104] % (p = 95 %)"


RESULT = {
    "scale_factor": 0.012499841,
    "scale_factor_U": 8.245e-08,
    "bias": 2.50016,
    "k": {"scale_factor": 1.96004, "bias": 1.96, "K": [[1.96, 2.45], [1.96, 1.96]]},
    "coverage_probability": 0.95,
    "K": [[1.004981, -0.002042], [0.002461, 1.002035]],
    "K_U": [[5.4e-05, 0.00016], [5.5e-05, 5.5e-05]],
}


def test_quantity_of_reads_the_keys_of_a_result():
    assert (
        quantity_of(RESULT, "scale_factor", "V/(deg/s)")
        == "0.012499841 ± 0.000000082 V/(deg/s) (k = 1.96, p = 95 %)"
    )
    assert quantity_of(RESULT, "bias", "V") == "2.50016 V"  # no bias_U: no ±


def test_elements_of_an_array_quantity():
    assert element_of(RESULT, "K", (0, 1)) == "-0.00204 ± 0.00016 (k = 2.45, p = 95 %)"
    # one k for the row: said once
    assert (
        elements_of(RESULT, "K", [(1, 0), (1, 1)], "V/(deg/s)")
        == "0.002461 ± 0.000055   1.002035 ± 0.000055 V/(deg/s) (k = 1.96, p = 95 %)"
    )
    # two k in the row: each element says its own
    assert elements_of(RESULT, "K", [(0, 0), (0, 1)]) == (
        "1.004981 ± 0.000054 (k = 1.96, p = 95 %)   -0.00204 ± 0.00016 (k = 2.45, p = 95 %)"
    )
    assert elements_of({"v": [1.5, 2.25]}, "v", [(0,), (1,)], "deg") == "1.5   2.25 deg"
