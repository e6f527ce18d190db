"""Optional Numba kernels (private): where they come from, and whether to use them.

Numba is never imported with the package: a caller asks :func:`use_numba` with the size of the
work, and only above :data:`MIN_SAMPLES` (where the ~0.5 s of importing Numba and loading the
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


def use_numba(n_samples: int, force: bool | None = None) -> bool:
    """Whether a kernel over ``n_samples`` samples should run the Numba twin.

    ``force=True``/``False`` overrides the size rule (tests and benchmarks run both paths);
    True without Numba installed still answers False.
    """
    if not numba_available():
        return False
    if force is not None:
        return bool(force)
    return n_samples >= MIN_SAMPLES
