"""Names shared by the turntable report's modules: the GyroWheel study's symbols, and whether a
budget is of the study's own table.

References
----------
The GyroWheel study (Int. J. Aerospace Eng., article 6524782): Table 2 (symbols), Table 4.
"""

from __future__ import annotations

from rotacal.turntable.budget import TurntableBudget
from rotacal.turntable.seed001 import is_seed_table

__all__ = ["COMP_SYMBOL", "angle_symbol", "is_seed_budget", "symbol"]

_GREEK = {
    "phi": "φ",
    "alpha": "α",
    "eps": "ε",
    "epsilon": "ε",
    "eta": "η",
    "theta": "θ",
    "beta": "β",
    "delta": "δ",
    "gamma": "γ",
    "psi": "ψ",
}
COMP_SYMBOL = {"psi": "Δψ", "theta": "Δθ", "gamma": "Δγ"}


def symbol(name: str) -> str:
    """``phi_y1`` → ``Δφy1`` (the GyroWheel study's Table-2 notation); other names unchanged."""
    head, _, tail = name.partition("_")
    greek = _GREEK.get(head.lower())
    return f"Δ{greek}{tail}" if greek else name


def angle_symbol(name: str) -> str:
    """``phi1`` → ``φ1``: a table angle's name in the paper's Greek; other names unchanged."""
    head = name.rstrip("0123456789")
    greek = _GREEK.get(head.lower())
    return f"{greek}{name[len(head) :]}" if greek else name


def is_seed_budget(budget: TurntableBudget) -> bool:
    """True when the table's angular errors are the seed's χ (then Table 4 applies)."""
    return is_seed_table(budget._table) and budget.reproduction is not None
