"""Errors a user can cause.

Every fault that comes from the user's input — a bad file, a missing column, NaNs, too little data,
an impossible setting — raises one of these with a message that names what to fix. The CLI turns
them into one line on stderr and exit code 2; the API lets them propagate as typed exceptions.
"""

from __future__ import annotations


class RotacalError(Exception):
    """Base class of every error rotacal raises on purpose."""


class CaptureError(RotacalError, ValueError):
    """The capture (file or arrays) cannot give a trustworthy result: say what is wrong with it."""


class ConfigError(RotacalError, ValueError):
    """A setting, option or configuration file is invalid."""


class StoreError(RotacalError):
    """The records store cannot do what was asked: it cannot be reached, it is locked, its schema
    is older or newer than this rotacal's, or the change would alter an issued record."""


class RecordImmutableError(StoreError):
    """An issued record was to be changed or deleted; issued records never change (a correction is
    a new certificate that supersedes the old one)."""


class AlreadyCertifiedError(ConfigError):
    """This plan and every capture it names were certified already (the same ``plan_sha256`` has
    an issued record); ``number`` is that certificate's number. A batch counts the plan as
    skipped; ``rotacal certify`` refuses it."""

    def __init__(self, message: str, number: str) -> None:
        super().__init__(message)
        self.number = number

    def __reduce__(self) -> tuple[type, tuple[str, str]]:  # pickled between Dask processes
        return (type(self), (str(self), self.number))
