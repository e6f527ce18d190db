"""Certificates of a plan's results: the PDF a person signs (ISO/IEC 17025 §7.8) and the PTB
Digital Calibration Certificate (DCC v3.1.2), both from one :class:`CertificateContent`."""

from .content import (
    CaptureRef,
    CertificateContent,
    Conformity,
    Figure,
    MeasurementResult,
    ReportedQuantity,
)

__all__ = [
    "CaptureRef",
    "CertificateContent",
    "Conformity",
    "Figure",
    "MeasurementResult",
    "ReportedQuantity",
]
