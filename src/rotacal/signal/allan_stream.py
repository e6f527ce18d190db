"""Overlapping Allan deviation at octave (or decade) τ of a rate record read in chunks.

:func:`octave_adev_chunks` takes the record as an iterable of rate chunks (any sizes) and gives
the :class:`~rotacal.signal.allan.AllanDeviation` that
``overlapping_adev(whole, fs=fs, taus="octave")`` gives, to rounding (≤ 1e-9 relative, tested),
holding a few chunks and a carried history instead of the record. :class:`ChunkedAdev` does the
same fed chunk by chunk, with the sampling rate given only at the end (a time column's rate is
known once the whole column has been read), and ``taus="decade"`` too:

* The phase (the rate's running integral, x_0 = 0) is carried from chunk to chunk: each chunk's
  rate, less the first chunk's mean (an offset the second difference annihilates; it keeps the
  phase small), is summed onto the last phase value (in blocks, as the in-memory phase:
  :func:`~rotacal.signal._phase.running_sum`), in units of rate × sample interval (the sums
  are divided by fs² at the end: the sampling rate need not be known while reading).
* Cluster sizes with 2m ≤ ``history`` are summed as the chunks arrive: the last ``history``
  phase values are carried, and each chunk adds the second differences x_{i+2m} − 2x_{i+m} + x_i
  whose last point x_{i+2m} lies in it.
* The phase is also written to a temporary file (8 bytes a sample, deleted at the end); the
  few longer cluster sizes (m > history/2, each with fewer than N/m ≤ N·2/history clusters) are
  summed afterwards in one pass over that file, with a sequential reader at each offset 0, m
  and 2m.

Memory: the carried history (``history`` phase values, 32 MB by default), a chunk and its
temporaries; not the record. Every τ (``taus="all"``) or the log grid (which depends on the
record's length and costs a pass per τ) are not available here.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable, Iterable
from typing import Any, BinaryIO

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._allan_fast import direct_sums
from rotacal.signal._phase import running_sum
from rotacal.signal._values import check_magnitudes
from rotacal.signal.allan import (
    MIN_SAMPLES,
    ONE_SIGMA,
    AllanDeviation,
    _check_alpha,
    _check_confidence,
    _check_fs,
    _cluster_sizes,
    deviation_from_sums,
)

__all__ = [
    "DEFAULT_HISTORY",
    "STREAMED_TAUS",
    "ChunkedAdev",
    "check_streamed_record",
    "deviation_of_streamed_sums",
    "octave_adev_chunks",
]

#: Phase values carried between chunks: cluster sizes up to half of it are summed in the pass.
DEFAULT_HISTORY = 1 << 22
#: Samples read at a time from the phase file for the long cluster sizes.
_READ = 1 << 20
#: The τ grids a record read in chunks can have (they do not depend on the record's length).
STREAMED_TAUS = ("octave", "decade")

Progress = Callable[[int], None]


def _candidate_sizes(taus: str, largest: int) -> np.ndarray:
    """Every cluster size of the ``taus`` grid up to ``largest`` (the record's length unknown)."""
    if taus == "octave":
        ms = 2 ** np.arange(int(math.log2(largest)) + 1, dtype=np.int64)
    else:  # decade: 1, 2, 4, 10, 20, 40, … as rotacal.signal.allan._cluster_sizes
        dec = 10 ** np.arange(int(math.log10(largest)) + 1, dtype=np.int64)
        ms = (dec[:, None] * np.array([1, 2, 4])).ravel()
    return np.unique(ms[ms <= largest])


class _PhaseCarry:
    """The running phase, its carried tail, and the sums of the short cluster sizes."""

    def __init__(self, short_ms: np.ndarray, history: int, phase_file: BinaryIO) -> None:
        self.history = history
        self.short_ms = short_ms
        self.sums = np.zeros(self.short_ms.size)
        self.tail = np.zeros(1)  # x_0 = 0: the phase before the first sample
        self.count = 1  # phase points so far
        self.offset: float | None = None
        self.low = math.inf
        self.high = -math.inf
        self.file = phase_file
        self.file.write(self.tail.tobytes())

    def add(self, rate: np.ndarray) -> None:
        if self.offset is None:
            self.offset = float(np.mean(rate))
        self.low = min(self.low, float(rate.min()))
        self.high = max(self.high, float(rate.max()))
        back = self.tail.size
        ext = np.empty(back + rate.size)
        ext[:back] = self.tail
        phase = ext[back:]
        np.subtract(rate, self.offset, out=phase)
        running_sum(phase, float(self.tail[-1]))  # in rate × sample interval: fs comes at the end
        phase.tofile(self.file)
        self.sum_terms(ext, back, self.count)
        self.count += phase.size
        self.tail = ext[-self.history :].copy()

    def sum_terms(self, ext: np.ndarray, back: int, first: int) -> None:
        """Add to ``sums`` the terms whose last point lies in the chunk: ``ext`` is the carried
        tail (``back`` values) and the chunk's phase, whose first value has global index
        ``first``. Here the second differences x_{i+2m} − 2x_{i+m} + x_i (i ≥ 0): from ext
        index max(back − 2m, back − first) on; all sizes in one pass over the chunk."""
        ms = self.short_ms
        firsts = np.maximum(back - 2 * ms, back - first)
        live = firsts + 2 * ms < ext.size
        if live.any():
            self.sums[live] += direct_sums(ext, ms[live], firsts=firsts[live])


def _long_sums(
    f: BinaryIO, n_phase: int, ms: list[int], progress: Progress | None = None
) -> np.ndarray:
    """S(m) of the long cluster sizes in one pass over the phase file: one sequential reader at
    each offset 0, m and 2m (shared between the sizes), ``_READ`` points at a time."""
    offsets = sorted({0, *ms, *(2 * m for m in ms)})
    sums = np.zeros(len(ms))
    end = n_phase - 2 * min(ms)
    for i in range(0, end, _READ):
        at = {}
        for o in offsets:
            f.seek(8 * (i + o))
            count = max(0, min(_READ, n_phase - i - o))  # offsets past the end read nothing
            at[o] = np.fromfile(f, dtype=np.float64, count=count)
        for k, m in enumerate(ms):
            c = min(_READ, n_phase - 2 * m - i)  # terms of this block: i + j < N − 2m
            if c <= 0:
                continue
            d = at[2 * m][:c] - 2.0 * at[m][:c]
            d += at[0][:c]
            sums[k] += float(np.dot(d, d))
        if progress is not None:
            progress(min(end, i + _READ))
    return sums


class ChunkedAdev:
    """Overlapping Allan deviation of a rate record fed in chunks (bounded memory).

    ``add(rate)`` for each chunk in order (rate in any unit u: °/s, fractional frequency, …),
    then ``result(fs=…)``; use it as a context manager (it holds a temporary phase file, deleted
    on exit). The result is ``overlapping_adev(whole, fs=fs, taus=taus)``'s, to rounding
    (≤ 1e-9 relative, tested): see the module for how.

    Parameters
    ----------
    taus : "octave" or "decade" — the τ grid (:data:`STREAMED_TAUS`).
    history : int — phase values carried between chunks (a power of two ≥ 4); longer cluster
        sizes are summed from the temporary phase file.
    column : str — the column's name, for messages.
    progress : callable, optional — called with the samples done so far (the reading pass, then
        the pass over the phase file for the long cluster sizes: 2·N in all at most).
    """

    def __init__(
        self,
        *,
        taus: str = "octave",
        history: int = DEFAULT_HISTORY,
        column: str = "data",
        progress: Progress | None = None,
    ) -> None:
        if taus not in STREAMED_TAUS:
            raise ConfigError(
                f"taus must be 'octave' or 'decade' for a record read in chunks; got {taus!r} "
                "(every τ, or the log grid, needs the whole record in memory)."
            )
        if history < 4 or history & (history - 1):
            raise ConfigError(
                f"history must be a power of two of at least 4 phase values; got {history!r}."
            )
        self.taus = taus
        self.history = history
        self.column = column
        self.progress = progress
        self._file = tempfile.TemporaryFile(prefix="rotacal-phase-")
        self._carry = self._make_carry()

    def _make_carry(self) -> _PhaseCarry:
        """The carried state: cluster sizes with 2m ≤ history are summed as the chunks arrive."""
        return _PhaseCarry(_candidate_sizes(self.taus, self.history // 2), self.history, self._file)

    def __enter__(self) -> ChunkedAdev:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Delete the temporary phase file."""
        self._file.close()

    @property
    def n_samples(self) -> int:
        """Rate samples fed so far."""
        return self._carry.count - 1

    def add(self, chunk: Any) -> None:
        """Feed the next rate samples (1-D; NaN/inf and out-of-range values are refused, the
        sample counted from the start of the record)."""
        rate = np.asarray(chunk, dtype=np.float64)
        if rate.ndim != 1:
            raise CaptureError(
                f"{self.column} must be one-dimensional; a chunk has shape {rate.shape}."
            )
        if not rate.size:
            return
        check_magnitudes(self.column, rate, what="rate data", offset=self.n_samples)
        self._carry.add(rate)
        if self.progress is not None:
            self.progress(self.n_samples)

    def result(
        self, *, fs: float, confidence: float = ONE_SIGMA, noise_alpha: Any = 0
    ) -> AllanDeviation:
        """The deviation of everything fed (fs in Hz; ±1σ interval and white-FM edf by default).

        Raises
        ------
        CaptureError — fewer than 10 phase points, a constant record.
        ConfigError — a bad fs, confidence or α.
        """
        fs_hz = _check_fs(fs)
        conf = _check_confidence(confidence)
        n_phase = self._carry.count
        check_streamed_record(n_phase, self._carry.low, self._carry.high)
        ms, notes = _cluster_sizes(self.taus, n_phase, fs_hz)
        sums = self.cluster_sums(ms)
        return deviation_of_streamed_sums(
            sums, ms, notes, n_phase=n_phase, fs_hz=fs_hz, confidence=conf, noise_alpha=noise_alpha
        )

    def cluster_sums(self, ms: np.ndarray) -> np.ndarray:
        """S(m) = Σ_{i=0}^{N−2m−1} (x_{i+2m} − 2x_{i+m} + x_i)² of everything fed, for the
        cluster sizes ``ms`` of the τ grid (in (rate × sample interval)²: divide by fs²)."""
        carry = self._carry
        sums = np.empty(ms.size)
        self._file.flush()
        short = ms <= carry.short_ms[-1]
        index = {m: k for k, m in enumerate(carry.short_ms.tolist())}
        sums[short] = carry.sums[[index[m] for m in ms[short].tolist()]]
        if not short.all():
            done = self.progress
            n_samples = carry.count - 1
            report = None if done is None else (lambda i: done(n_samples + i))
            sums[~short] = _long_sums(self._file, carry.count, ms[~short].tolist(), report)
        return sums


def check_streamed_record(n_phase: int, low: float, high: float) -> None:
    """Refuse a record streamed in pieces that is too short or constant (``low``/``high``: its
    smallest and largest rate sample).

    Raises
    ------
    CaptureError — fewer than 10 phase points, a constant record.
    """
    n_samples = n_phase - 1
    if n_phase < MIN_SAMPLES:
        raise CaptureError(
            f"the record holds {n_samples} rate samples; the Allan deviation needs at least "
            f"{MIN_SAMPLES - 1}: supply a longer record."
        )
    if low == high:
        raise CaptureError(
            f"the rate record is constant ({high!r} in all {n_samples} samples): the sensor is "
            "stuck or saturated, or the column is a set value; supply the sensor output."
        )


def deviation_of_streamed_sums(
    sums: np.ndarray,
    ms: np.ndarray,
    notes: list[str],
    *,
    n_phase: int,
    fs_hz: float,
    confidence: float,
    noise_alpha: Any,
) -> AllanDeviation:
    """The deviation from the sums S(m) of a rate record's second differences, summed in units
    of rate × sample interval (phase x_i = Σ_{k<i} rate_k): divided by fs² here."""
    return deviation_from_sums(
        sums / (fs_hz * fs_hz),
        ms,
        n_phase=n_phase,
        n_samples=n_phase - 1,
        fs_hz=fs_hz,
        data_type="rate",
        confidence=confidence,
        alphas=_check_alpha(noise_alpha, ms.size),
        notes=tuple(notes),
        warnings=(),
        n_direct=int(ms.size),
    )


def octave_adev_chunks(
    chunks: Iterable[Any],
    *,
    fs: float,
    confidence: float = ONE_SIGMA,
    noise_alpha: Any = 0,
    history: int = DEFAULT_HISTORY,
    column: str = "data",
) -> AllanDeviation:
    """Overlapping Allan deviation at octave τ (m = 1, 2, 4, …) of a rate record in chunks.

    σ²(τ) = Σ_{i=0}^{N−2m−1} (x_{i+2m} − 2x_{i+m} + x_i)² / (2·τ²·(N − 2m)), τ = m/fs, x the
    running integral of the rate (x_0 = 0), as :func:`rotacal.signal.allan.overlapping_adev`
    with ``data_type="rate"`` and ``taus="octave"``; see the module for how it is streamed.

    Parameters
    ----------
    chunks : iterable of array_like
        Consecutive pieces of one rate record (°/s, rad/s, fractional frequency, …), 1-D.
    fs : float
        Sampling rate (Hz).
    confidence : float
        Confidence level of ``adev_low``/``adev_high`` (default ±1σ).
    noise_alpha : int
        Noise type for the edf (2 white PM … −2 random-walk FM; 0 white rate noise).
    history : int
        Phase values carried between chunks (a power of two ≥ 4); longer cluster sizes are
        summed from the temporary phase file.
    column : str
        The column's name, for messages.

    Returns
    -------
    AllanDeviation
        As ``overlapping_adev(whole, fs=fs, taus="octave")``; ``method`` is "direct".

    Raises
    ------
    CaptureError
        NaN/inf or out-of-range samples (the sample is named), fewer than 10 samples, a constant
        record.
    ConfigError
        A bad fs, confidence or α.

    References
    ----------
    NIST SP 1065 (Riley 2008), eq. (11) (overlapping ADEV from phase data) and §5.3 (edf);
    IEEE Std 952-1997, Annex C.
    """
    fs_hz = _check_fs(fs)
    _check_confidence(confidence)
    with ChunkedAdev(taus="octave", history=history, column=column) as acc:
        for chunk in chunks:
            acc.add(chunk)
        return acc.result(fs=fs_hz, confidence=confidence, noise_alpha=noise_alpha)
