"""A constant-rate result with its angle-window figures: one JSON (INTERFACE.md ``rate … --window-deg``).

:func:`with_windows` joins a :class:`~rotacal.table.rate.RateResult` and the
:class:`~rotacal.table.rate_windows.RateWindows` of the same pulse train, so that the rate
command writes the window keys (``rate_accuracy_percent``, ``rate_stability_percent``,
``rate_stability_peak_percent``, each a mapping keyed by the window, with ``_u``) beside the rate's
own, its notes after the rate's and its warnings with the rate's.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from rotacal.table.rate import RateResult
from rotacal.table.rate_windows import RateWindows

__all__ = ["RateWithWindows", "with_windows"]

#: Keys the window result shares with the rate result (the same values): the rate's stay.
_SHARED = ("warnings", "notes", "set_rate_deg_s", "compensated")


@dataclasses.dataclass(frozen=True)
class RateWithWindows(RateResult):
    """A :class:`RateResult` with the window figures of the same train (:attr:`windows`)."""

    _windows: RateWindows | None = dataclasses.field(repr=False, default=None)

    @property
    def windows(self) -> RateWindows | None:
        """The angle-window figures."""
        return self._windows

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        if self._windows is not None:
            extra = self._windows.to_dict()
            out.update({k: v for k, v in extra.items() if k not in _SHARED})
        return out


def with_windows(result: RateResult, windows: RateWindows) -> RateWithWindows:
    """``result`` with ``windows`` joined (their notes and warnings appended to the rate's)."""
    fields = {f.name: getattr(result, f.name) for f in dataclasses.fields(RateResult)}
    fields["notes"] = [*result.notes, *windows.notes]
    fields["warnings"] = tuple(dict.fromkeys((*result.warnings, *windows.warnings)))
    return RateWithWindows(**fields, _windows=windows)
