"""Calibration plans: one TOML file describes a calibration job (INTERFACE.md, "Calibration plans
and certificates"); reading and checking it, and running its measurements."""

from .approval import approvers, check_approval, performers
from .model import Conditions, Contact, Item, Limit, Measurement, Person, Plan, Standard

__all__ = [
    "Conditions",
    "Contact",
    "Item",
    "Limit",
    "Measurement",
    "Person",
    "Plan",
    "Standard",
    "approvers",
    "check_approval",
    "performers",
]
