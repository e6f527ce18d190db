"""How rotacal writes a number for a person — on the terminal, in a report, on a certificate.

One style, rounded as ILAC-P14 says, in fixed notation (never ``1.2e-05``):

A quantity with an expanded uncertainty U reads ``value ± U unit (k = 1.96, p = 95 %)``: U kept to
two significant digits and the value rounded to the same decimal place (ILAC-P14:09/2020 §5.4, by
:func:`rotacal.uncertainty.round_ilac`), k with two decimals, p in percent. A quantity whose
coverage interval is not centred on it (a THD, a peak-to-peak near zero) reads ``value unit, true
value in [lo, hi] unit (p = 95 %)``. A quantity without an uncertainty reads ``value unit`` — never
a bare standard uncertainty. The JSON keeps full precision; only what a person reads is rounded.

A number is written in fixed notation with the digits it needs; one too small or too large for that
(below 10⁻⁴ or from 10⁹ on, where fixed notation would bury its digits in zeros) is written with a
power of ten, ``1.23 × 10⁻⁷``, as the SI Brochure (9th ed., §5.4.4) writes it — never E notation.
:func:`si_scaled` moves a quantity in an SI unit to the prefix that keeps its digits readable
(0.0012 s → 1.2 ms).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from rotacal.uncertainty import round_ilac

#: Significant digits of a value shown without an uncertainty.
PLAIN_DIGITS = 6
#: What the terminal shows for a quantity the analysis could not determine.
NOT_DETERMINED = "—"


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""


def coverage(k: float, p: float | None) -> str:
    """``(k = 1.96, p = 95 %)`` — k with two decimals, p in percent (as few digits as it needs)."""
    p_text = "" if p is None else f", p = {format(round(100.0 * p, 2), 'g')} %"
    return f"(k = {k:.2f}{p_text})"


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
#: Fixed notation is used for magnitudes in [FIXED_MIN, FIXED_MAX); a power of ten outside.
FIXED_MIN, FIXED_MAX = 1e-4, 1e9


def fixed(value: Any, digits: int = PLAIN_DIGITS, *, keep_zeros: bool = False) -> str:
    """``value`` with ``digits`` significant digits in fixed notation, no exponent.

    Trailing zeros after the decimal point are dropped (``2.50000`` → ``2.5``): a value without an
    uncertainty states no resolution. With ``keep_zeros`` they stay, for a number whose digits
    were chosen (an uncertainty rounded to two significant digits: ``1.0e-05`` → ``0.000010``).
    Magnitudes outside [10⁻⁴, 10⁹) are written ``m × 10ⁿ``.
    """
    if not _finite(value):
        return NOT_DETERMINED
    x = float(value)
    if x == 0.0:
        return "0"
    exponent = math.floor(math.log10(abs(x)))
    if not FIXED_MIN <= abs(x) < FIXED_MAX:
        mantissa = f"{x / 10.0**exponent:.{max(digits - 1, 0)}f}"
        if float(mantissa) in (10.0, -10.0):  # 9.9999… rounded up
            exponent += 1
            mantissa = f"{x / 10.0**exponent:.{max(digits - 1, 0)}f}"
        if "." in mantissa and not keep_zeros:
            mantissa = mantissa.rstrip("0").rstrip(".")
        return f"{mantissa} × 10{str(exponent).translate(_SUPERSCRIPT)}"
    text = f"{x:.{max(digits - 1 - exponent, 0)}f}"
    if "." in text and not keep_zeros:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


#: SI units that take a prefix (the unit as rotacal writes it). Degrees, arcsec, % and ppm do not.
SI_UNITS = frozenset({"s", "Hz", "V", "A", "m", "W", "Ω", "rad", "rad/s"})
_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"))


def si_scaled(value: float, unit: str, *, also: Sequence[float] = ()) -> tuple[float, str, float]:
    """The SI prefix that writes ``value`` (in ``unit``) with 1 to 3 digits before the point.

    Returns ``(factor, prefixed unit, value / factor)``; divide any companion (U, an interval, the
    values in ``also``) by ``factor`` too. Units outside :data:`SI_UNITS`, and values already
    between 0.01 and 10 000 in their unit, are left as they are (factor 1): a prefix helps a reader
    only where the plain unit needs many zeros.
    """
    x = abs(float(value)) if _finite(value) else 0.0
    if unit not in SI_UNITS or x == 0.0 or 1e-2 <= x < 1e4:
        return 1.0, unit, float(value) if _finite(value) else value
    for factor, prefix in _PREFIXES:
        if x >= factor:
            return factor, prefix + unit, float(value) / factor
    factor, prefix = _PREFIXES[-1]
    return factor, prefix + unit, float(value) / factor


def format_plain(value: Any, unit: str = "", *, digits: int = PLAIN_DIGITS) -> str:
    """A value without an uncertainty: ``digits`` significant digits in fixed notation, the unit."""
    if not _finite(value):
        return NOT_DETERMINED
    return f"{fixed(value, digits)}{_unit(unit)}"


def format_quantity(
    value: Any,
    unit: str = "",
    *,
    U: Any = None,
    k: Any = None,
    p: float | None = None,
    interval: Sequence[float] | None = None,
    digits: int = PLAIN_DIGITS,
    si_prefix: bool = False,
) -> str:
    """One measured quantity as a person reads it (the module's docstring gives the layout).

    Parameters
    ----------
    value : float
        The result, in ``unit`` (None or non-finite: shown as not determined).
    unit : str
        Its unit as shown (``"deg"``, ``"%"``, ``"arcsec"``; empty for none).
    U : float, optional
        Expanded uncertainty, in ``unit``. Missing, zero or non-finite: the value is shown alone.
    k : float, optional
        Coverage factor of ``U``.
    p : float, optional
        Coverage probability (a fraction, e.g. 0.95).
    interval : (float, float), optional
        The coverage interval for the true value when it is not ``value ± U``; U is then half its
        width and sets the decimal place of the value and the limits.
    digits : int
        Significant digits of a value shown without an uncertainty.
    si_prefix : bool
        Write a quantity in an SI unit with the prefix :func:`si_scaled` picks (reports do; the
        terminal keeps the unit the command states).

    References
    ----------
    ILAC-P14:09/2020, §5.2–5.4 (U with k and p, at most two significant digits, the value rounded
    to the same place); JCGM 100:2008 (GUM), §7.2.4 (reporting U, k and p).
    """
    if not _finite(value):
        return NOT_DETERMINED
    if si_prefix:
        factor, unit, value = si_scaled(float(value), unit)
        U = float(U) / factor if _finite(U) else U
        if interval is not None and all(_finite(x) for x in interval):
            interval = [float(x) / factor for x in interval]
    if not (_finite(U) and U > 0):
        return format_plain(value, unit, digits=digits)
    value_text, u_text = round_ilac(float(value), float(U))
    if interval is not None and all(_finite(x) for x in interval):
        decimals = len(u_text.split(".")[1]) if "." in u_text else 0
        low, high = (float(x) for x in interval)
        if low <= 0.0 <= float(value):  # a bounded quantity (a THD, an rms) is not negative
            low = max(low, 0.0)
        lo, hi = f"{low:.{decimals}f}", f"{high:.{decimals}f}"
        p_text = "" if p is None else f" (p = {format(round(100.0 * p, 2), 'g')} %)"
        return f"{value_text}{_unit(unit)}, true value in [{lo}, {hi}]{_unit(unit)}{p_text}"
    suffix = f" {coverage(float(k), p)}" if _finite(k) else ""
    return f"{value_text} ± {u_text}{_unit(unit)}{suffix}"


def quantity_of(
    data: Mapping[str, Any], key: str, unit: str = "", *, digits: int = PLAIN_DIGITS
) -> str:
    """``format_quantity`` of the JSON key ``key`` of a result's ``to_dict()``.

    Takes ``key``, ``key_U``, ``key_interval``, ``k[key]`` (or a number ``k``) and
    ``coverage_probability`` from ``data``: the keys every result with uncertainty budgets has.
    """
    k = data.get("k")
    return format_quantity(
        data.get(key),
        unit,
        U=data.get(f"{key}_U"),
        k=k.get(key) if isinstance(k, Mapping) else k,
        p=data.get("coverage_probability"),
        interval=data.get(f"{key}_interval"),
        digits=digits,
    )


def element_of(
    data: Mapping[str, Any],
    key: str,
    index: tuple[int, ...],
    unit: str = "",
    *,
    digits: int = PLAIN_DIGITS,
) -> str:
    """``format_quantity`` of one element (``index``) of an array quantity ``key`` of a result."""

    k = data.get("k")
    return format_quantity(
        _pick(data.get(key), index),
        unit,
        U=_pick(data.get(f"{key}_U"), index),
        k=_pick(k.get(key), index) if isinstance(k, Mapping) else k,
        p=data.get("coverage_probability"),
        interval=_pick(data.get(f"{key}_interval"), index),
        digits=digits,
    )


def elements_of(
    data: Mapping[str, Any],
    key: str,
    indices: Sequence[tuple[int, ...]],
    unit: str = "",
    *,
    digits: int = PLAIN_DIGITS,
    sep: str = "   ",
) -> str:
    """Several elements of an array quantity on one line (a row of a matrix, a vector).

    Each reads ``value ± U``; when they share one coverage factor (as shown, two decimals) the unit
    and ``(k = …, p = …)`` are said once at the end, otherwise after each element.
    """
    k = data.get("k")
    ks = k.get(key) if isinstance(k, Mapping) else k
    values, us = data.get(key), data.get(f"{key}_U")

    def factor(i: tuple[int, ...]) -> Any:
        return _pick(ks, i) if isinstance(ks, Sequence) else ks

    stated = [i for i in indices if _finite(_pick(us, i)) and _pick(us, i) > 0]
    if not stated:
        return sep.join(format_plain(_pick(values, i), digits=digits) for i in indices) + _unit(
            unit
        )
    factors = {f"{float(factor(i)):.2f}" if _finite(factor(i)) else "" for i in stated}
    intervals = data.get(f"{key}_interval")
    if len(factors) != 1 or any(_pick(intervals, i) is not None for i in indices):
        return sep.join(element_of(data, key, i, unit, digits=digits) for i in indices)
    text = sep.join(
        format_quantity(_pick(values, i), U=_pick(us, i), digits=digits) for i in indices
    )
    k_shared = factor(stated[0])
    if not _finite(k_shared) or not all(_finite(_pick(values, i)) for i in indices):
        return text + _unit(unit)
    return f"{text}{_unit(unit)} {coverage(float(k_shared), data.get('coverage_probability'))}"


def _pick(x: Any, index: tuple[int, ...]) -> Any:
    for i in index:
        if not isinstance(x, Sequence) or isinstance(x, str) or i >= len(x):
            return None
        x = x[i]
    return x
