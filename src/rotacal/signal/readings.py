"""Angle or counter readings streamed clean: the DAQ's doubled samples dropped, a counter unwrapped.

:class:`CleanReadings` turns a chunk source of ``(time_s, reading)`` into fresh passes of
``(offset, t, θ)`` over the cleaned record (offsets count the kept samples): time stamps checked
finite, a counter unwrapped with the last reading carried (:mod:`rotacal.signal.counter`; θ in
degrees from the first reading), an angle checked finite, repeated rows and duplicated times
dropped (:mod:`rotacal.signal.daq_faults`). Every pass starts the carried state afresh, so every
pass gives the same record; after a full pass :attr:`CleanReadings.faults` holds its DAQ faults.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal.counter import CounterUnwrapper, infer_register
from rotacal.signal.daq_faults import DaqFaultFinder, DaqFaults

__all__ = ["CleanReadings", "ReadingChunks", "counter_register"]

#: A chunk source: each call starts a fresh pass of ``(time_s, reading)`` chunks in record order.
ReadingChunks = Callable[[], Iterator[tuple[np.ndarray, np.ndarray]]]


def counter_register(
    chunks: Iterable[tuple[Any, np.ndarray]], bits: int | None, signed: bool | None
) -> tuple[int, bool]:
    """The register ``(bits, signed)``: as given, else by :func:`infer_register` from the range of
    every reading (one pass over ``chunks`` only when something is to be inferred)."""
    if bits is not None and signed is not None:
        return int(bits), bool(signed)
    lo, hi = np.inf, -np.inf
    for _, c in chunks:
        if np.size(c):
            lo, hi = min(lo, float(np.min(c))), max(hi, float(np.max(c)))
    if not lo <= hi:
        raise CaptureError("column count is empty")
    guess_bits, guess_signed = infer_register(np.array([lo, hi]))
    return (guess_bits if bits is None else int(bits)), (
        guess_signed if signed is None else bool(signed)
    )


class CleanReadings:
    """Fresh passes of ``(offset, t, θ)`` over cleaned readings (module docstring).

    Parameters
    ----------
    chunks : ReadingChunks — ``chunks()`` starts a pass of ``(time_s, reading)`` (s; deg or counts).
    counts_per_rev : float, optional — N: the readings are counts, θ = 360·(count − first)/N.
    bits, signed : the counter's register (:func:`counter_register`); needed with counts.
    """

    def __init__(
        self,
        chunks: ReadingChunks,
        counts_per_rev: float | None = None,
        bits: int | None = None,
        signed: bool | None = None,
    ) -> None:
        if not callable(chunks):
            raise ConfigError("chunks must be a callable that starts a fresh pass of the capture")
        if counts_per_rev is not None and bits is None:
            raise ConfigError("the counter's register width is needed to unwrap counts in chunks")
        self._chunks = chunks
        self._cpr = counts_per_rev
        self._bits = bits
        self._signed = signed
        self.faults: DaqFaults | None = None

    def __call__(self) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        finder = DaqFaultFinder()
        unwrap = None
        if self._cpr is not None:
            assert self._bits is not None
            unwrap = CounterUnwrapper(self._bits, self._signed)
        origin: int | None = None
        off = 0
        for t, value in self._chunks():
            t = np.asarray(t, dtype=np.float64)
            if t.size == 0:
                continue
            _finite(t, "'time_s'", finder.seen)
            if unwrap is not None:
                true = unwrap.feed(value)
                origin = int(true[0]) if origin is None else origin
                x = (true - origin).astype(np.float64) * (360.0 / float(self._cpr))  # type: ignore[arg-type]
            else:
                x = np.asarray(value, dtype=np.float64)
                _finite(x, "angle_deg", finder.seen)
            keep = finder.feed(t, x)
            if not keep.all():
                t, x = t[keep], x[keep]
            yield off, t, x
            off += t.size
        self.faults = finder.result()

    @property
    def register(self) -> tuple[int, bool] | None:
        """The counter's ``(bits, signed)`` (None for angle readings)."""
        if self._cpr is None or self._bits is None:
            return None
        return self._bits, bool(self._signed)


def _finite(x: np.ndarray, name: str, seen: int) -> None:
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        raise CaptureError(f"column {name} has a NaN or inf at sample {seen + int(bad[0])}")
