"""Conformity statements: a result, its expanded uncertainty and a limit give pass, fail or
indeterminate under a stated decision rule (ISO/IEC 17025:2017 §7.8.6; ILAC-G8:09/2019).

Two rules, as ILAC-G8 §4.2 describes them:

- **simple acceptance** (§4.2.1, guard band w = 0): pass when the measured value lies within the
  limits, fail otherwise. The risk of a false accept can reach 50 % at a limit; the certificate
  says so.
- **guarded acceptance** (§4.2.2, w = U): pass only when the whole interval value ± U (or the
  stated coverage interval of a biased quantity) lies within the limits, fail when it lies wholly
  outside, and indeterminate when it straddles a limit; the probability of a false accept is then
  below 2.5 % for k = 2 (a one-sided tail of a normal distribution).

The decision uses the numbers the certificate prints (ILAC-P14 rounded), so that a reader can check
it from the page.
"""

from __future__ import annotations

from decimal import Decimal

from rotacal.plan.model import Limit

from .content import Conformity, ReportedQuantity

__all__ = ["RULE_TEXT", "judge"]

#: The decision rules as the certificate states them.
RULE_TEXT = {
    "simple": "simple acceptance (ILAC-G8:09/2019 §4.2.1, guard band w = 0): pass when the "
    "measured value lies within the limits",
    "guarded": "guarded acceptance (ILAC-G8:09/2019 §4.2.2, guard band w = U): pass when the "
    "measured value ± U lies within the limits, fail when it lies wholly outside them, otherwise "
    "no statement of conformity can be made (indeterminate)",
}


def _decimal_text(x: float) -> str:
    """A limit as a reader wrote it: the shortest decimal text of the float (``repr``)."""
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def judge(quantity: ReportedQuantity, limit: Limit, rule: str) -> Conformity:
    """The conformity of ``quantity`` with ``limit`` under ``rule`` (``simple`` | ``guarded``).

    The value, U (or the coverage interval) and the limits are compared as the decimals the
    certificate prints, exactly (``decimal.Decimal``), so that no binary rounding turns a value on
    its limit the other way.

    References
    ----------
    ILAC-G8:09/2019 §4.2.1 (simple acceptance) and §4.2.2 (guarded acceptance, w = U);
    ISO/IEC 17025:2017 §7.8.6.
    """
    value = Decimal(quantity.value)
    big_u = Decimal(quantity.U)
    if quantity.interval is not None:
        low, high = (Decimal(x) for x in quantity.interval)
    else:
        low, high = value - big_u, value + big_u
    lo_lim = Decimal(_decimal_text(limit.min)) if limit.min is not None else None
    hi_lim = Decimal(_decimal_text(limit.max)) if limit.max is not None else None

    def within(x_low: Decimal, x_high: Decimal) -> bool:
        return (lo_lim is None or x_low >= lo_lim) and (hi_lim is None or x_high <= hi_lim)

    def outside(x_low: Decimal, x_high: Decimal) -> bool:
        return (lo_lim is not None and x_high < lo_lim) or (hi_lim is not None and x_low > hi_lim)

    if rule == "simple":
        verdict = "pass" if within(value, value) else "fail"
    elif within(low, high):
        verdict = "pass"
    elif outside(low, high):
        verdict = "fail"
    else:
        verdict = "indeterminate"
    return Conformity(
        key=quantity.key,
        name=quantity.name,
        unit=quantity.unit,
        value=quantity.value,
        U=quantity.U,
        limit_min=_decimal_text(limit.min) if limit.min is not None else "",
        limit_max=_decimal_text(limit.max) if limit.max is not None else "",
        decision_rule=rule,
        verdict=verdict,
        statement=_statement(quantity, limit, rule, verdict),
    )


def _statement(quantity: ReportedQuantity, limit: Limit, rule: str, verdict: str) -> str:
    unit = f" {quantity.unit}" if quantity.unit else ""
    if limit.min is not None and limit.max is not None:
        bounds = f"between {_decimal_text(limit.min)}{unit} and {_decimal_text(limit.max)}{unit}"
    elif limit.max is not None:
        bounds = f"at most {_decimal_text(limit.max)}{unit}"
    else:
        bounds = f"at least {_decimal_text(limit.min)}{unit}"  # type: ignore[arg-type]
    measured = (
        f"{quantity.value}{unit} (true value in [{quantity.interval[0]}, {quantity.interval[1]}]"
        f"{unit})"
        if quantity.interval is not None
        else f"{quantity.value}{unit} ± {quantity.U}{unit}"
    )
    said = {
        "pass": "conforms to",
        "fail": "does not conform to",
        "indeterminate": "cannot be stated to conform or not to conform to",
    }[verdict]
    rule_name = "simple acceptance" if rule == "simple" else "guarded acceptance, w = U"
    name = quantity.name[:1].upper() + quantity.name[1:]
    return f"{name}, {measured}, {said} the limit ({bounds}; {rule_name})."
