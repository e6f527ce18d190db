"""Optional Numba kernels (private): where they come from, and whether to use them.

Numba is never imported with the package: a caller asks :func:`use_numba` with the size of the
work, and only from its threshold on (:data:`MIN_SAMPLES` for a capture; the turntable Monte Carlo
has its own; where the ~0.5 s of importing Numba and loading the
cached machine code pays for itself) is the module of jitted kernels imported. Every kernel has a
NumPy twin that gives the same numbers to ≤ 1e-12 relative (the tests run both), so a machine
without Numba, or ``ROTACAL_NUMBA=0`` in the environment, gets the same results, only slower.

A process that runs one analysis and exits (a ``rotacal`` command) pays that load for the one
call: :func:`single_call` raises the threshold there to where one call repays it.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import sys
from collections.abc import Iterator

#: Below this many samples the NumPy path is used: importing Numba costs more than it saves.
MIN_SAMPLES = 4_000_000
#: Below this many samples one in-memory encoder calibration (demodulation, fit, residual sums)
#: runs faster on the NumPy path in a process that has not loaded Numba: loading it (import,
#: its CPU target, the cached kernels) costs 0.6–0.8 s of CPU and the compiled chain saves
#: ~2.5 ns a sample (measured at 2·10⁷ samples, 10 and 1000 periods: 0.31–0.36 s compiled
#: against 0.36–0.41 s NumPy once loaded, since the NumPy fit sums one residual by BLAS): one
#: call repays the load from ~2.5·10⁸ samples on, past the size the CLI reads whole.
#: To be measured again when the kernels change. ``benchmarks/bench_encoder_command.py`` shows the whole command.
ENCODER_CALL_SAMPLES = 250_000_000

_available: bool | None = None
_single_call_samples: int | None = None


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
    from ``threshold`` on (samples, or draws; :data:`MIN_SAMPLES` when not given, raised inside
    :func:`single_call`), where loading Numba and the kernels pays.
    """
    if not numba_available():
        return False
    if force is not None:
        return bool(force)
    if os.environ.get("ROTACAL_NUMBA", "").strip() == "1":
        return True
    if threshold is None:
        threshold = MIN_SAMPLES
        if _single_call_samples is not None and "numba" not in sys.modules:
            threshold = max(threshold, _single_call_samples)
    return n >= threshold


@contextlib.contextmanager
def single_call(samples: int) -> Iterator[None]:
    """Within: :func:`use_numba`'s default threshold is at least ``samples`` unless Numba is
    loaded in this process already — for a caller that runs one analysis and exits, so the
    load must pay within that one call (e.g. :data:`ENCODER_CALL_SAMPLES`). Explicit
    thresholds, ``force`` and ``ROTACAL_NUMBA`` keep their meaning."""
    global _single_call_samples
    before = _single_call_samples
    _single_call_samples = samples
    try:
        yield
    finally:
        _single_call_samples = before
