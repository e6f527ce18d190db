"""Who performed a calibration and who approves its certificate: the plan's check of authorisation.

ISO/IEC 17025:2017 §7.8.1.1 has results reviewed and authorised before release, and §7.8.2.1 (o)
names the person(s) authorising the report. rotacal issues a certificate only when its plan names
at least one ``[[person]]`` with ``role = "approved"`` and at least one with ``role = "performed"``,
and it refuses a plan whose approver is also one of its performers: the authorisation is a review
by a second person (the "four eyes" a laboratory's quality manual asks for), and a record that
says someone approved their own work would not show one. Names are compared without regard to
case or spacing ("B.  Manager" is "b. manager").
"""

from __future__ import annotations

from collections.abc import Sequence

from rotacal.errors import ConfigError

from .model import PERSON_ROLES, Person, Plan

__all__ = ["approval_problem", "approvers", "check_approval", "performers"]


def performers(plan: Plan) -> tuple[str, ...]:
    """The names of the persons who performed the calibration, in the plan's order."""
    return tuple(p.name for p in plan.persons if p.role == "performed")


def approvers(plan: Plan) -> tuple[str, ...]:
    """The names of the persons who approve (authorise) the certificate, in the plan's order."""
    return tuple(p.name for p in plan.persons if p.role == "approved")


def _same(name: str) -> str:
    return " ".join(name.split()).casefold()


def approval_problem(persons: Sequence[Person]) -> tuple[str, str] | None:
    """What is wrong with the persons of a plan, as (key, message), or None: a role nobody has,
    or a person who is both performer and approver (the key is that ``person[i]``, from 1)."""
    for role in PERSON_ROLES:
        if not any(p.role == role for p in persons):
            return (
                "person",
                f'needs a [[person]] with role = "{role}" (ISO/IEC 17025 §7.8.2.1 names who '
                "performed the calibration and who authorised the certificate; a certificate is "
                "issued only when a person approves it)",
            )
    doers = {_same(p.name) for p in persons if p.role == "performed"}
    for i, p in enumerate(persons, start=1):
        if p.role == "approved" and _same(p.name) in doers:
            return (
                f"person[{i}]",
                f"{p.name} both performed the calibration and approves it; the approver must "
                "be another person, who reviews the results (ISO/IEC 17025 §7.8.1.1)",
            )
    return None


def check_approval(plan: Plan) -> None:
    """Refuse a plan without an approver, without a performer, or approved by its performer.

    Raises
    ------
    ConfigError
        One line naming the plan file and the ``[[person]]`` at fault.
    """
    problem = approval_problem(plan.persons)
    if problem is not None:
        key, message = problem
        raise ConfigError(f"{plan.path}: {key}: {message}")
