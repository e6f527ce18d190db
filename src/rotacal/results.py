"""The common base of result objects: frozen dataclasses that turn into plain JSON."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from typing import Any, TypeVar

import numpy as np


def to_jsonable(value: Any) -> Any:
    """Turn NumPy scalars/arrays, dataclasses, tuples and non-finite floats into JSON-ready values.

    NaN and ±inf become ``None`` (JSON has no such numbers).
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        if hasattr(value, "to_dict"):
            out = value.to_dict()
            # a nested result (a requirement check, a budget) says nothing unless it has something
            # to say: the top-level result always carries ``warnings``
            if isinstance(out, dict) and out.get("warnings") == []:
                del out["warnings"]
            return out
        return {f.name: to_jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        if set(map(type, value)) <= {float}:  # a curve of floats: no call per number
            return list(value) if all(map(math.isfinite, value)) else [_finite(v) for v in value]
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return _finite(float(value))
    return value


def _finite(f: float) -> float | None:
    return f if math.isfinite(f) else None


@dataclasses.dataclass(frozen=True)
class Result:
    """Base of every calibration result: frozen, with ``to_dict()`` giving the JSON of INTERFACE.md.

    Fields whose name starts with an underscore are kept for figures and reports but left out of
    the JSON (for example long arrays of samples).

    ``warnings`` (keyword-only, every result has it) lists what the user must know before
    trusting the numbers — a precondition the user chose to override (``--allow-clipped``), drift
    seen in the residual, implausible settings. It is empty when there is nothing to say; the CLI
    prints each line on stderr as ``warning: …`` and the report shows them at the top.
    """

    warnings: tuple[str, ...] = dataclasses.field(default=(), kw_only=True)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            if f.name.startswith("_") or not f.repr:
                continue
            out[f.name] = to_jsonable(getattr(self, f.name))
        return out


R = TypeVar("R", bound=Result)


def with_warnings(result: R, lines: Iterable[str]) -> R:
    """A copy of ``result`` with ``lines`` appended to its ``warnings`` (duplicates dropped)."""
    new = tuple(dict.fromkeys((*result.warnings, *lines)))
    if new == result.warnings:
        return result
    return dataclasses.replace(result, warnings=new)
