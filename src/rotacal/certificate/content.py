"""What a certificate states, in the form both renderers (PDF and DCC XML) and ``results.json``
read, so that all three print the same numbers.

Every number a reader sees is held here as the decimal text it is printed as (ILAC-P14 rounded:
:func:`rotacal.uncertainty.budget.round_ilac`); the PDF may lay it out (digit groups, a power of
ten), the DCC writes it as it is, ``results.json`` as the same number.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from rotacal.plan.model import Plan

__all__ = [
    "VERDICTS",
    "CaptureRef",
    "CertificateContent",
    "Conformity",
    "Figure",
    "MeasurementResult",
    "ReportedQuantity",
]

#: The outcomes of a conformity statement (INTERFACE.md): within the limits, outside them, or
#: neither can be said at the decision rule's confidence (ILAC-G8:09/2019 §4.2.2).
VERDICTS = ("pass", "fail", "indeterminate")


@dataclasses.dataclass(frozen=True)
class ReportedQuantity:
    """One reported result: ``value`` ± ``U`` ``unit`` (k, p), rounded as ILAC-P14:09/2020 §5.4 asks.

    Attributes
    ----------
    key : str
        The result's key in the command's JSON (its ``uncertainty_budgets`` key), e.g.
        ``"scale_factor"`` or ``"scale_misalignment[0][1]"``; limits in a plan name it.
    name : str
        The quantity as a reader names it ("scale factor S").
    unit : str
        The unit as printed ("V/(°/s)", "%FS", "°/√h"); "" for a dimensionless number.
    dsi_unit : str
        The same unit in D-SI notation for the DCC (``\\volt\\second\\per\\degree``).
    value, U : str
        The value and its expanded uncertainty as decimal text in ``unit``, U with two
        significant digits and the value to the same decimal place.
    k : str
        Coverage factor, three significant digits ("1.96").
    p : str
        Coverage probability as a fraction ("0.95").
    interval : tuple of str, optional
        For a biased, bounded quantity (a THD or nonlinearity near zero): the coverage interval
        ``(low, high)`` for the true value, rounded to the decimal place of U; the certificate
        states it instead of ± U.
    note : str
        What a reader must know to use the number (e.g. "of full scale 300 °/s").
    """

    key: str
    name: str
    unit: str
    dsi_unit: str
    value: str
    U: str
    k: str
    p: str
    interval: tuple[str, str] | None = None
    note: str = ""


@dataclasses.dataclass(frozen=True)
class Conformity:
    """The conformity statement for one quantity with a limit (ISO/IEC 17025 §7.8.6).

    ``limit_min``/``limit_max`` are the plan's limits as decimal text ("" where absent), in the
    quantity's unit; ``decision_rule`` is ``simple`` or ``guarded``; ``verdict`` one of
    :data:`VERDICTS`; ``statement`` the sentence the certificate prints.
    """

    key: str
    name: str
    unit: str
    value: str
    U: str
    limit_min: str
    limit_max: str
    decision_rule: str
    verdict: str
    statement: str


@dataclasses.dataclass(frozen=True)
class Figure:
    """A figure of the certificate: its file in the output folder (SVG) and its caption."""

    file: str
    caption: str


@dataclasses.dataclass(frozen=True)
class CaptureRef:
    """A capture a measurement read: its path as the plan names it, SHA-256 and size in bytes."""

    path: str
    sha256: str
    bytes: int


@dataclasses.dataclass(frozen=True)
class MeasurementResult:
    """One measurement of the plan, done.

    ``method`` is the sentence that names the method and its source (seed and equation, IEEE Std
    clause); ``references`` the full entries it cites; ``results`` the command's own JSON;
    ``quantities`` what the certificate reports of it; ``conformity`` one statement per limited
    quantity; ``figures`` filled in when the figures are drawn.
    """

    index: int
    name: str
    command: str
    method: str
    references: tuple[str, ...]
    captures: tuple[CaptureRef, ...]
    options: Mapping[str, Any]
    results: Mapping[str, Any]
    quantities: tuple[ReportedQuantity, ...]
    conformity: tuple[Conformity, ...]
    decision_rule: str
    figures: tuple[Figure, ...] = ()
    warnings: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True)
class CertificateContent:
    """Everything a certificate states: the plan's administrative data, the results, the
    conformity statements, the software, and the hash that ties them to the plan and captures."""

    number: str
    plan: Plan
    plan_sha256: str
    software_version: str
    measurements: tuple[MeasurementResult, ...]
