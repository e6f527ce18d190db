"""Small edits of a finished :class:`~rotacal.uncertainty.UncertaintyBudget`: notes and rows.

Every family ends its budgets the same way — adds the sentences a reader needs, leaves out the
rows of inputs that do not enter the quantity (the outputs of one multi-output model share its
input list, GUM H.2) and the note on truncating ν_eff where that truncation does not move k.
These helpers are that one way; the standard note texts themselves ("no instrument specification
stated: Type A only", "corrected for the stated mean …") live in :mod:`rotacal.uncertainty.specs`.

References
----------
JCGM 100:2008 (GUM) §7.2.7 (what a budget states), G.4.1 note 1 (truncating ν_eff).
"""

from __future__ import annotations

import dataclasses
import math

from rotacal.uncertainty.budget import UncertaintyBudget
from rotacal.uncertainty.gum import coverage_factor

__all__ = ["drop_truncation_note", "drop_unused_rows", "tidy", "with_notes"]

#: Relative change of k below which the note on truncating ν_eff is left out.
TRUNCATION_NOTE_REL = 1e-3


def with_notes(
    budget: UncertaintyBudget, *notes: str | None, method: str | None = None
) -> UncertaintyBudget:
    """The budget with ``notes`` appended (empty or None ones skipped), and ``method`` replaced
    when given (``"GUM"``, ``"Monte Carlo"`` or ``"GUM, validated by Monte Carlo"``).

    Parameters
    ----------
    budget : UncertaintyBudget
    *notes : str or None
        Sentences to add, in order.
    method : str, optional
        The method that now states the uncertainty (e.g. after a Monte Carlo validation).

    Returns
    -------
    UncertaintyBudget
    """
    added = tuple(n for n in notes if n)
    return dataclasses.replace(
        budget, notes=(*budget.notes, *added), method=method or budget.method
    )


def drop_unused_rows(budget: UncertaintyBudget) -> UncertaintyBudget:
    """The budget without the rows whose sensitivity is exactly 0 (inputs of a shared model that
    do not enter this output); all rows are kept if every one is 0 (an exact result).

    u, U and k are unchanged: a row with c_i = 0 contributes nothing (GUM eq. (10)).
    """
    rows = tuple(r for r in budget.rows if r.sensitivity != 0.0) or budget.rows
    return dataclasses.replace(budget, rows=rows)


def drop_truncation_note(
    budget: UncertaintyBudget, *, rel: float = TRUNCATION_NOTE_REL
) -> UncertaintyBudget:
    """The budget without the note on truncating ν_eff to an integer when that truncation moves
    k by less than ``rel`` (relative): k = t_p(⌊ν_eff⌋) against t_p(ν_eff).

    References
    ----------
    JCGM 100:2008 (GUM) G.4.1 note 1.
    """
    nu = float(budget.dof_eff)
    if not (math.isfinite(nu) and nu >= 1.0):
        return budget
    k_t = coverage_factor(nu, budget.p)
    k_f = coverage_factor(nu, budget.p, truncate=False)
    if abs(k_t / k_f - 1.0) >= rel:
        return budget
    return dataclasses.replace(
        budget, notes=tuple(n for n in budget.notes if "truncated to" not in n)
    )


def tidy(budget: UncertaintyBudget, *notes: str | None) -> UncertaintyBudget:
    """:func:`drop_unused_rows`, :func:`drop_truncation_note`, then :func:`with_notes`."""
    return with_notes(drop_truncation_note(drop_unused_rows(budget)), *notes)
