"""Calibration plans: one TOML file describes a calibration job (INTERFACE.md, "Calibration plans
and certificates"); reading and checking it, and running its measurements."""

from .model import Conditions, Contact, Item, Limit, Measurement, Person, Plan, Standard

__all__ = ["Conditions", "Contact", "Item", "Limit", "Measurement", "Person", "Plan", "Standard"]
