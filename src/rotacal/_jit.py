"""Optional Numba kernels (private): where they come from, and whether to use them.

Numba is never imported with the package: a caller asks :func:`use_numba` with the size of the
work, and only from its threshold on (:data:`MIN_SAMPLES` for a capture; the turntable Monte Carlo
has its own; where the ~0.5 s of importing Numba and loading the
cached machine code pays for itself) is the module of jitted kernels imported. Every kernel has a
NumPy twin that gives the same numbers to ≤ 1e-12 relative (the tests run both), so a machine
without Numba, or ``ROTACAL_NUMBA=0`` in the environment, gets the same results, only slower.
"""

from __future__ import annotations

import importlib.util
import os

#: Below this many samples the NumPy path is used: importing Numba costs more than it saves.
MIN_SAMPLES = 4_000_000

_available: bool | None = None


def numba_available() -> bool:
    """True when Numba can be imported and ``ROTACAL_NUMBA`` is not ``0`` (checked, not imported)."""
    global _available
    if os.environ.get("ROTACAL_NUMBA", "1").strip() == "0":
        return False
    if _available is None:
        _available = importlib.util.find_spec("numba") is not None
    return _available


def use_numba(n: int, force: bool | None = None, *, threshold: int | None = None) -> bool:
    """Whether work over ``n`` samples (or draws) should run the Numba twin.

    Without Numba, or with ``ROTACAL_NUMBA=0`` in the environment: never. Otherwise ``force``
    when given (tests and benchmarks run both paths), else always with ``ROTACAL_NUMBA=1``, else
    from ``threshold`` on (samples, or draws; :data:`MIN_SAMPLES` when not given), where loading
    Numba and the kernels pays.
    """
    if not numba_available():
        return False
    if force is not None:
        return bool(force)
    if os.environ.get("ROTACAL_NUMBA", "").strip() == "1":
        return True
    return n >= (MIN_SAMPLES if threshold is None else threshold)
