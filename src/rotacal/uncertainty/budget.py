"""Uncertainty budgets and the rounding of reported results (GUM §7, ILAC-P14 §5.4).

An :class:`UncertaintyBudget` is what a calibration certificate shows for one measurand: the
value, its combined standard uncertainty u, the expanded uncertainty U = k·u with its coverage
factor and coverage probability, the effective degrees of freedom, and one :class:`BudgetRow` per
input quantity (value, distribution, standard uncertainty, sensitivity coefficient, contribution
c_i·u(x_i) and its share of u²). :meth:`rotacal.uncertainty.gum.GUMResult.budget` builds one from
a law-of-propagation result; a Monte Carlo result can be put into the same form.

:func:`round_ilac` rounds a reported pair (value, U) as ILAC-P14:09/2020 §5.4 asks: U to at most two
significant digits, the value to the same decimal place.

References
----------
JCGM 100:2008 (GUM), §7.2 (reporting: 7.2.2 the combined and 7.2.4 the expanded uncertainty,
7.2.6 rounding); ILAC-P14:09/2020, §5.4 (rounding of the expanded uncertainty and of the result).
"""

from __future__ import annotations

import dataclasses
import decimal
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import Result

__all__ = ["BudgetRow", "UncertaintyBudget", "result_keys", "round_ilac", "uncertainty_keys"]

#: Cell shown in a budget table where a number does not apply (e.g. the second-order row).
_DASH = "—"


# ------------------------------------------------------------------------------------ rounding
def _as_decimal(x: float) -> decimal.Decimal:
    """The shortest decimal that round-trips to ``x`` (what the user wrote, e.g. 1.25 → 1.25)."""
    return decimal.Decimal(repr(float(x)))


def _plain(d: decimal.Decimal) -> str:
    """Fixed-point text of ``d`` (never exponent notation), with ``-0`` shown as ``0``."""
    text = format(d, "f")
    if text.startswith("-") and d.is_zero():
        text = text[1:]
    return text


def round_ilac(
    value: float, U: float, *, digits: int = 2, round_up: bool = False
) -> tuple[str, str]:
    """Round a result and its expanded uncertainty for reporting (ILAC-P14 §5.4, GUM §7.2.6).

    The expanded uncertainty ``U`` keeps at most ``digits`` significant digits and the value is
    rounded to the same decimal place. Both come back as fixed-point text (no exponent), so that
    trailing zeros that carry meaning are kept: ``U = 0.0996`` → ``"0.10"``.

    Rounding rule (stated, as ILAC-P14 §5.4 asks for "the usual rules for rounding"): round to
    nearest, and an exact tie goes to the even digit (ISO 80000-1:2009 Annex B, rule B; the
    IEEE 754 default), so ``1.25`` → ``"1.2"`` and ``1234.5`` (U = 96) → ``"1234"``. Ties are
    judged on the shortest decimal text of the float (``repr``), i.e. on the number as written,
    not on its binary approximation. With ``round_up=True`` the uncertainty alone is rounded up
    (away from zero), as GUM §7.2.6 allows for reported results (``0.0934`` → ``"0.094"``); the
    value is still rounded to nearest.

    Parameters
    ----------
    value : float
        The measurement result (any unit; finite).
    U : float
        Its expanded uncertainty (same unit as ``value``; finite and > 0).
    digits : int, optional
        Significant digits kept in ``U`` (ILAC-P14: at most 2; GUM §7.2.6 allows keeping more to
        avoid round-off in later calculations). Default 2.
    round_up : bool, optional
        Round ``U`` up instead of to nearest. Default False.

    Returns
    -------
    (value_str, U_str) : tuple of str
        The rounded value and the rounded U, in the unit of the inputs.

    Raises
    ------
    ConfigError
        When ``U`` is zero, negative, NaN or infinite, ``value`` is not finite, or ``digits`` < 1.

    References
    ----------
    ILAC-P14:09/2020, §5.4 (U to at most two significant digits; the result rounded to the same
    decimal place; the usual rules for rounding). JCGM 100:2008 (GUM), §7.2.6 (rounding up;
    example y = 10.057 62 Ω with u = 27 mΩ → 10.058 Ω). ISO 80000-1:2009, Annex B (ties).
    """
    if isinstance(digits, bool) or not isinstance(digits, (int, np.integer)) or digits < 1:
        raise ConfigError(f"digits must be an integer ≥ 1 (ILAC-P14 asks for ≤ 2); got {digits!r}.")
    try:
        uf = float(U)
        vf = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"round_ilac needs numbers; got value = {value!r}, U = {U!r}.") from None
    if math.isnan(uf) or math.isinf(uf):
        raise ConfigError(
            f"the expanded uncertainty U = {uf!r} is not finite; an unbounded U cannot be rounded — "
            "check the coverage factor (ν_eff) and the inputs."
        )
    if uf <= 0.0:
        raise ConfigError(
            f"the expanded uncertainty U = {uf!r} is not positive; ILAC rounding needs U > 0 "
            "(report an exact value without an uncertainty statement)."
        )
    if not math.isfinite(vf):
        raise ConfigError(f"the value {vf!r} is not finite; nothing to round.")

    ud = _as_decimal(uf)
    ctx = decimal.Context(prec=60)
    exponent = ud.adjusted() - int(digits) + 1  # decimal place of the last kept digit of U
    mode_u = decimal.ROUND_UP if round_up else decimal.ROUND_HALF_EVEN
    ur = ud.quantize(decimal.Decimal(1).scaleb(exponent), rounding=mode_u, context=ctx)
    if ur.adjusted() > ud.adjusted():  # 0.0996 → 0.100: one significant digit too many
        exponent += 1
        ur = ud.quantize(decimal.Decimal(1).scaleb(exponent), rounding=mode_u, context=ctx)
    quantum = decimal.Decimal(1).scaleb(exponent)
    vr = _as_decimal(vf).quantize(quantum, rounding=decimal.ROUND_HALF_EVEN, context=ctx)
    return _plain(vr), _plain(ur)


# ------------------------------------------------------------------------------------ budgets
@dataclasses.dataclass(frozen=True)
class BudgetRow:
    """One input quantity of an uncertainty budget (one line of the GUM's budget table).

    Attributes
    ----------
    source : name of the input quantity (or ``"second-order terms (GUM §5.1.2 note)"``).
    value : its estimate x_i (unit ``unit``).
    unit : unit of x_i and u(x_i).
    distribution : the assigned distribution, e.g. ``"rectangular ±2e-06"`` or ``"normal"``.
    u : standard uncertainty u(x_i) (unit ``unit``).
    sensitivity : c_i = ∂f/∂x_i (unit of the measurand per ``unit``).
    contribution : c_i·u(x_i) (unit of the measurand; signed).
    share : (c_i·u(x_i))² / u_c²(y) (fraction; sums to 1 over the rows for uncorrelated inputs).
    dof : degrees of freedom ν_i (``math.inf`` when the input is taken as exactly characterised).
    origin : where the input's knowledge comes from (certificate, Type A, …); may be empty.
    """

    source: str
    value: float
    unit: str
    distribution: str
    u: float
    sensitivity: float
    contribution: float
    share: float
    dof: float
    origin: str = ""


def _fmt(x: float, spec: str) -> str:
    """``x`` with the significant digits of ``spec`` (``".3g"``), in fixed notation (no E)."""
    from rotacal.numbers import fixed  # numbers rounds with round_ilac from this module

    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    return _DASH if not math.isfinite(x) else fixed(x, int(spec.strip(".g")))


def _with_unit(text: str, unit: str) -> str:
    return f"{text} {unit}" if unit and text != _DASH else text


def _sensitivity_unit(out_unit: str, in_unit: str) -> str:
    if out_unit == in_unit:
        return ""
    if not in_unit:
        return out_unit
    for per in ("1/", "/"):  # "1/°C" or "/°C": per unit → multiply
        if in_unit.startswith(per) and in_unit[len(per) :]:
            return f"{out_unit}·{in_unit[len(per) :]}" if out_unit else in_unit[len(per) :]
    if any(ch in in_unit for ch in "/· *"):
        in_unit = f"({in_unit})"
    return f"{out_unit or '1'}/{in_unit}"


def _dof_text(dof: float) -> str:
    if math.isinf(dof):
        return "∞"
    if math.isnan(dof):
        return _DASH
    return format(dof, ".4g")


def _percent(p: float) -> str:
    return format(round(100.0 * p, 2), "g")


@dataclasses.dataclass(frozen=True)
class UncertaintyBudget(Result):
    """The uncertainty statement and budget of one measurand.

    Attributes
    ----------
    quantity : name of the measurand (e.g. ``"l"``).
    unit : unit of ``value``, ``u`` and ``U``.
    value : the estimate y.
    u : combined standard uncertainty u_c(y).
    dof_eff : effective degrees of freedom ν_eff (``math.inf`` when every input is exactly
        characterised; JSON ``null``).
    k : coverage factor, so that U = k·u.
    p : coverage probability (fraction, e.g. 0.95).
    U : expanded uncertainty.
    rows : one :class:`BudgetRow` per input (and one for second-order terms when they were added).
    method : ``"GUM"``, ``"Monte Carlo"`` or ``"GUM, validated by Monte Carlo"``.
    notes : sentences a reader of the budget needs (correlations, truncation of ν_eff, …).

    References
    ----------
    JCGM 100:2008 (GUM), §7.2.2–7.2.7 (what a reported uncertainty states); ILAC-P14:09/2020 §5.
    """

    quantity: str
    unit: str
    value: float
    u: float
    dof_eff: float
    k: float
    p: float
    U: float
    rows: tuple[BudgetRow, ...]
    method: str = "GUM"
    notes: tuple[str, ...] = ()
    #: The coverage interval for the true value when it is not value ± U — a biased, bounded
    #: quantity near its bound (a THD or a peak-to-peak near zero): then the statement gives the
    #: interval, and U is half its width (JCGM 101 §7.7; JCGM 102 for a magnitude near zero).
    interval: tuple[float, float] | None = None

    def rounded(self, *, round_up: bool = False) -> tuple[str, str]:
        """``(value_str, U_str)`` rounded by :func:`round_ilac` (ILAC-P14:09/2020 §5.4).

        Both in the budget's ``unit``. Raises ConfigError when U is 0 (an exact result).
        """
        return round_ilac(self.value, self.U, round_up=round_up)

    def statement(self, *, round_up: bool = False) -> str:
        """The sentence of a certificate, e.g. ``"l = 50000839 nm ± 92 nm (k = 2.92, p ≈ 99 %)"``.

        Value and U are rounded by :meth:`rounded` (ILAC-P14 §5.4); k is shown with three
        significant digits, p in percent. An exact result (U = 0) is stated without "±".

        References
        ----------
        JCGM 100:2008 (GUM), §7.2.4 (reporting U, k and the level of confidence); ILAC-P14:09/2020,
        §5.2–5.4.
        """
        unit = f" {self.unit}" if self.unit else ""
        if self.U == 0.0 and self.u == 0.0:
            return f"{self.quantity} = {self.value!r}{unit} (exact: every input has u = 0)"
        value_str, u_str = self.rounded(round_up=round_up)
        if self.interval is not None:
            lo, hi = (float(v) for v in self.interval)
            # Round the limits to the decimal place of U, as the value is (ILAC-P14 §5.4).
            decimals = len(u_str.split(".")[1]) if "." in u_str else 0
            lo_str = f"{max(lo, 0.0) if lo <= 0.0 <= self.value else lo:.{decimals}f}"
            return (
                f"{self.quantity} = {value_str}{unit}; the true value lies in "
                f"[{lo_str}, {hi:.{decimals}f}]{unit} (p ≈ {_percent(self.p)} %, "
                f"interval not centred on the value)"
            )
        return (
            f"{self.quantity} = {value_str}{unit} ± {u_str}{unit} "
            f"(k = {self.k:.3g}, p ≈ {_percent(self.p)} %)"
        )

    def table(self) -> tuple[list[str], list[list[str]]]:
        """The budget as text: ``(header, rows)``, ready for a terminal, HTML or PDF table.

        Columns: source, value, distribution, u, sensitivity, contribution, share, dof. Values
        carry their units; the sensitivity carries ``unit of y / unit of x_i`` (nothing when the
        two are the same); the share is in percent; ∞ marks an infinite ν.
        """
        header = [
            "source",
            "value",
            "distribution",
            "u",
            "sensitivity",
            "contribution",
            "share",
            "dof",
        ]
        body: list[list[str]] = []
        for row in self.rows:
            source = f"{row.source} ({row.origin})" if row.origin else row.source
            body.append(
                [
                    source,
                    _with_unit(_fmt(row.value, ".10g"), row.unit),
                    row.distribution or _DASH,
                    _with_unit(_fmt(row.u, ".3g"), row.unit),
                    _with_unit(
                        _fmt(row.sensitivity, ".4g"), _sensitivity_unit(self.unit, row.unit)
                    ),
                    _with_unit(_fmt(row.contribution, ".3g"), self.unit),
                    _DASH if not math.isfinite(row.share) else f"{100.0 * row.share:.1f} %",
                    _dof_text(row.dof),
                ]
            )
        return header, body


def result_keys(name: str, budget: UncertaintyBudget) -> dict[str, float]:
    """The uncertainty keys of a result's JSON: ``{name_u: u, name_U: U, "k": k}``.

    Parameters
    ----------
    name : str
        JSON key of the quantity (e.g. ``"scale_factor"``).
    budget : UncertaintyBudget
        Its budget; ``u`` and ``U`` are in ``budget.unit``.

    Returns
    -------
    dict
        ``{f"{name}_u": u, f"{name}_U": U, "k": k}`` as plain floats.

    References
    ----------
    JCGM 100:2008 (GUM), §7.2.2 (u_c) and §7.2.4 (U and k).
    """
    return {f"{name}_u": float(budget.u), f"{name}_U": float(budget.U), "k": float(budget.k)}


def uncertainty_keys(budgets: Mapping[str, UncertaintyBudget]) -> dict[str, Any]:
    """The uncertainty keys of a result's JSON, for several quantities at once.

    For every ``name`` in ``budgets``: ``name_u`` (standard uncertainty) and ``name_U`` (expanded),
    in the unit of the quantity, and ``name_interval`` when the budget states a coverage interval
    that is not centred on the value; then ``k`` mapping each name to its coverage factor,
    ``coverage_probability`` (the p all of them are stated for) and ``uncertainty_budgets`` (each
    budget in full: rows, ν_eff, method, notes).

    Parameters
    ----------
    budgets : mapping of str to UncertaintyBudget
        JSON key of the quantity → its budget.

    Returns
    -------
    dict

    References
    ----------
    JCGM 100:2008 (GUM), §7.2.2 (u_c), §7.2.4 (U, k and p).
    """
    out: dict[str, Any] = {}
    for name, b in budgets.items():
        out[f"{name}_u"] = float(b.u)
        out[f"{name}_U"] = float(b.U)
        if b.interval is not None:
            out[f"{name}_interval"] = [float(b.interval[0]), float(b.interval[1])]
    out["k"] = {name: float(b.k) for name, b in budgets.items()}
    ps = {float(b.p) for b in budgets.values()}
    out["coverage_probability"] = ps.pop() if len(ps) == 1 else None
    out["uncertainty_budgets"] = {name: b.to_dict() for name, b in budgets.items()}
    return out
