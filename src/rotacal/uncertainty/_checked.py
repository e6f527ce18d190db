"""Small checks shared by the GUM modules: a number the user gave, an array a result keeps."""

from __future__ import annotations

from typing import Any

import numpy as np

from rotacal.errors import ConfigError


def _number(value: Any, what: str) -> float:
    """``value`` as a float; ConfigError naming ``what`` when it is no number (a bool is none)."""
    if isinstance(value, bool):
        raise ConfigError(f"{what} = {value!r} is not a number; give a float.")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} = {value!r} is not a number; give a float.") from None


def _frozen(a: np.ndarray) -> np.ndarray:
    """A contiguous float64 copy-or-view of ``a`` that cannot be written (a result's array)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a
