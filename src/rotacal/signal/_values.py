"""Checks of a column's numbers that every analysis shares (private).

A capture column can be finite and still make a method degenerate: values near 1e300 overflow the
squares and sums of squares every least-squares fit, variance and Allan sum forms; values near
1e-300 underflow them to zero; a constant column, or a column that is an exact copy of another,
carries no information, and a method fed with it reports a "perfect" or meaningless number. These
checks refuse such columns with one sentence that names the column and the problem, before the
arithmetic runs. They only raise: a column that passes is used unchanged, so the results of valid
captures stay the same to the last bit.

The working range is [SMALLEST, LARGEST] for the largest magnitude of a column (zero allowed):
the squares of 1e100 summed over 10¹⁰ samples stay below 1e210, far inside float64's 1.8e308, and
the squares of 1e-100 stay far above its smallest normal number 2.2e-308; any physical quantity in
any unit a capture may use lies inside it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError

#: Largest magnitude accepted in a column or numeric setting (see the module docstring).
LARGEST = 1e100
#: A column whose largest non-zero magnitude is below this is refused (its squares underflow).
SMALLEST = 1e-100
#: Time stamps must resolve the sample interval to this fraction: float64 spacing at the
#: capture's largest |time| above it quantises every time stamp by a visible share of a step.
TIME_RESOLUTION = 0.01


def _first_bad(x: np.ndarray) -> tuple[int, float]:
    i = int(np.flatnonzero(~np.isfinite(x))[0])
    return i, float(x[i])


def _describe(value: float) -> str:
    return "NaN" if math.isnan(value) else ("+inf" if value > 0 else "-inf")


def in_working_range(x: np.ndarray) -> bool:
    """True when the sum of squares of ``x`` shows it finite and inside the working range.

    One BLAS pass, as cheap as a sum: NaN/inf make it non-finite, one value beyond LARGEST makes it
    exceed LARGEST², a column of values all below SMALLEST makes it fall below SMALLEST². False
    does not yet mean a fault (an all-zero column, or very many values just inside the range):
    :func:`check_magnitudes` then looks at the samples.
    """
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        # vdot, not dot: a column memory-mapped from an NPZ member is rarely 8-byte aligned,
        # and dot then leaves BLAS for a loop ~10x slower; vdot stays fast (same sum, no copy)
        power = float(np.vdot(x, x))
    return SMALLEST * SMALLEST <= power <= LARGEST * LARGEST


def check_magnitudes(
    name: str,
    values: Any,
    *,
    what: str = "a sensor signal",
    offset: int = 0,
    largest: float = LARGEST,
) -> None:
    """Refuse NaN/inf and magnitudes outside float64's working range in column ``name``.

    One BLAS pass (the sum of squares) decides for ordinary columns; only when it is not finite or
    outside [SMALLEST², LARGEST²] are the samples searched for the culprit. An all-zero column
    passes (constancy is :func:`check_not_constant`'s business).

    Parameters
    ----------
    name : str — the column's name, for the message.
    values : array — the column (1-D).
    what : str — what the column should hold, for the message ("a sensor signal", "pulse times").
    offset : int — index of ``values[0]`` in the whole capture (chunked reading), for the message.
    largest : float — a tighter bound where the method's arithmetic needs one (angles in sin/cos).

    Raises
    ------
    CaptureError
        A NaN or inf (first sample named), a value beyond LARGEST in magnitude (its sample and
        value named), or a non-zero column whose largest magnitude is below SMALLEST.
    """
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    if x.size == 0 or (largest == LARGEST and in_working_range(x)):
        return
    if not np.isfinite(x).all():
        i, v = _first_bad(x)
        raise CaptureError(
            f"column '{name}' has a {_describe(v)} at sample {offset + i}; remove or interpolate "
            "the non-finite samples."
        )
    big_i = int(np.argmax(np.abs(x)))
    big = abs(float(x[big_i]))
    if big > largest:
        reason = (
            "their squares overflow float64 arithmetic"
            if largest == LARGEST
            else f"float64 arithmetic of the method carries magnitudes up to {largest:g}"
        )
        raise CaptureError(
            f"column '{name}' holds {float(x[big_i]):.6g} at sample {offset + big_i}: values near "
            f"1e{int(math.log10(big))} are not {what} ({reason}); check the file and the "
            "column's unit."
        )
    if 0.0 < big < SMALLEST:
        raise CaptureError(
            f"column '{name}' holds only values below {SMALLEST:g} in magnitude (the largest is "
            f"{big:.3g}): too small to be {what} (their squares underflow float64 arithmetic); "
            "check the column's unit."
        )


def check_not_constant(
    name: str, values: Any, why: str = "it carries no signal; check that the column is mapped right"
) -> None:
    """Refuse a column whose samples are all equal (a stuck sensor, a set value, a blank column).

    Parameters
    ----------
    name : str — the column's name, for the message.
    values : array — the column (1-D, finite).
    why : str — what the constancy means for the method, for the message.
    """
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    if x.size > 1 and float(np.min(x)) == float(np.max(x)):
        raise CaptureError(f"column '{name}' is constant (all {float(x[0]):.6g}): {why}.")


def check_signal(
    name: str,
    values: Any,
    *,
    what: str = "a sensor signal",
    why: str = "it carries no signal; check that the column is mapped right",
) -> None:
    """:func:`check_magnitudes` and :func:`check_not_constant` for one column."""
    check_magnitudes(name, values, what=what)
    check_not_constant(name, values, why)


def check_not_copies(columns: Mapping[str, Any], why: str) -> None:
    """Refuse two columns that are exact copies of each other (or one the negative of the other).

    Measured channels always differ by noise at least; an exact copy means the same data were
    written twice, and a method comparing the two would report a perfect (or meaningless) result.
    The first samples are compared first, so distinct columns cost almost nothing. Two equal
    constant columns are let through: what is wrong with them is that they are constant, which
    :func:`check_not_constant` or the method itself reports.

    Parameters
    ----------
    columns : mapping of name to array — the columns that must differ, in order.
    why : str — what a copy means for the method, for the message.
    """
    items = [(n, np.asarray(v, dtype=np.float64).reshape(-1)) for n, v in columns.items()]
    for i, (name_a, a) in enumerate(items):
        for name_b, b in items[i + 1 :]:
            if a.size != b.size or a.size < 2:
                continue
            for sign, label in ((1.0, "an identical copy"), (-1.0, "the negative")):
                head = min(a.size, 64)
                if np.array_equal(a[:head], sign * b[:head]) and np.array_equal(a, sign * b):
                    if float(np.ptp(a)) == 0.0:
                        break  # two constant columns: the constancy is the fault, not the copy
                    raise CaptureError(f"column '{name_b}' is {label} of column '{name_a}': {why}.")


def check_time_span(
    name: str, first: float, last: float, step: float, interval: str = "sample interval"
) -> None:
    """Refuse time stamps beyond float64's working range or too coarsely resolved by it.

    Parameters
    ----------
    name : str — the time column's name, for the message.
    first, last : float, s — the first and last time stamps of an increasing column.
    step : float, s — the typical sample interval (> 0).
    interval : str — what ``step`` is, for the message ("pulse interval").

    Raises
    ------
    CaptureError
        |time| beyond LARGEST s or all below SMALLEST s, or time stamps whose float64 spacing at
        the largest |time| exceeds TIME_RESOLUTION of a sample interval (e.g. 1e12 s sampled
        every 0.5 ms: each time stamp is then rounded to 0.12 ms).
    """
    big = max(abs(first), abs(last))
    if big > LARGEST or 0.0 < big < SMALLEST:
        raise CaptureError(
            f"column '{name}' runs from {first:.6g} s to {last:.6g} s: time stamps near "
            f"{big:.1e} s are beyond what float64 arithmetic of the analysis carries; give the time "
            "in seconds since the start of the record."
        )
    spacing = float(np.spacing(big))
    if spacing > TIME_RESOLUTION * step:
        raise CaptureError(
            f"column '{name}': time stamps near {big:.6g} s are resolved only to {spacing:.3g} s "
            f"in float64, {100 * spacing / step:.3g} % of the {interval} {step:.3g} s; give "
            "the time in seconds since the start of the record."
        )


def check_setting(option: str, value: Any, *, positive: bool = True, unit: str = "") -> float:
    """Return a numeric setting as float; refuse NaN/inf, and magnitudes outside the working range.

    Parameters
    ----------
    option : str — the setting as the user names it (``--radius-mm``), for the message.
    value : number — the setting.
    positive : bool — refuse values ≤ 0 too.
    unit : str — the setting's unit, for the message.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{option} must be a number, got {value!r}.") from None
    u = f" {unit}" if unit else ""
    if not math.isfinite(v):
        raise ConfigError(f"{option} must be a finite number, got {v!r}.")
    if positive and not v > 0:
        raise ConfigError(f"{option} must be > 0{u}, got {v:g}.")
    if abs(v) > LARGEST or 0.0 < abs(v) < SMALLEST:
        raise ConfigError(
            f"{option} = {v:g}{u} is beyond what float64 arithmetic of the analysis carries "
            f"(magnitudes from {SMALLEST:g} to {LARGEST:g}); check the value and its unit."
        )
    return v
