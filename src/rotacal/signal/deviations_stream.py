"""The modified Allan, Hadamard, time and total deviations of a rate record read in chunks.

:class:`ChunkedDeviation` is :func:`rotacal.signal.deviations.stability_deviation` at octave (or
decade) τ for a record too long to hold: ``add(rate)`` for each chunk in order, then
``result(fs=…)``; the result equals the in-memory one of the whole record to rounding (≤ 1e-9
relative, tested with chunks that split every τ's window). It builds on
:class:`~rotacal.signal.allan_stream.ChunkedAdev`: the phase (the rate's running integral) is
carried from chunk to chunk and written to a temporary file (8 bytes a sample), and

* MDEV/TDEV (NIST SP 1065 eq. (14)): each term Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i)
  spans the 3m phase points x_j … x_{j+3m−1}; HDEV (eq. (18)): each term
  x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i spans 3m + 1. Cluster sizes with 3m ≤ ``history`` are
  summed as the chunks arrive, each chunk adding the terms whose last point lies in it, from the
  carried tail of ``history`` phase values and the chunk. The few longer sizes are summed
  afterwards from the phase file with sequential readers (HDEV: at offsets 0, m, 2m, 3m; MDEV:
  the running sum C_k of the second differences read twice, m apart: term_j = C_{j+m−1} − C_{j−1},
  the same differences of the same running sum as the in-memory kernel).
* TOTDEV (eq. (25)): with the reflected extension x*, the terms at 1 ≤ i ≤ N−2 split into the
  interior ones (m ≤ i ≤ N−1−m), which are the overlapping Allan variance's second differences
  (summed as ChunkedAdev sums them), and the m − 1 terms at each end, which need only the first
  and last 2m phase points: read from the phase file once the record's end is known.

Every deviation here is unchanged by a straight line added to the phase (the differences, and
the reflection x*_{−j} = 2x_0 − x_j, carry a line into itself), so the streamed phase — the rate
less its first chunk's mean — gives the numbers of the in-memory phase with its best line
removed. (The in-memory HDEV also removes the rate's best line, a parabola in the phase that its
third differences annihilate; the streamed phase keeps it, whose rounding costs 3·10⁻¹⁰ relative
at most against a long-double sum for a 100 °/s ramp over 10⁸ samples:
``benchmarks/bench_deviations_stream.py``.) Memory: the carried tail (``history`` values, 32 MB by default), a chunk and its
temporaries, and the readers' blocks (~50 MB); not the record.
"""

from __future__ import annotations

from typing import Any, BinaryIO

import numpy as np

from rotacal.errors import ConfigError
from rotacal.signal._deviation_sums import combination_sums, modified_sums
from rotacal.signal.allan import (
    ONE_SIGMA,
    _check_confidence,
    _check_fs,
    _cluster_sizes,
)
from rotacal.signal.allan_stream import (
    DEFAULT_HISTORY,
    ChunkedAdev,
    Progress,
    _candidate_sizes,
    _PhaseCarry,
    check_streamed_record,
    deviation_of_streamed_sums,
)
from rotacal.signal.deviations import (
    DEVIATIONS,
    StabilityDeviation,
    _from_adev,
    deviation_from_sums,
    longest_cluster,
)

__all__ = ["ChunkedDeviation"]

#: Phase points read at a time from the phase file for the long cluster sizes.
_READ = 1 << 20
_HADAMARD = (-1.0, 3.0, -3.0, 1.0)


def _read(f: BinaryIO, start: int, count: int) -> np.ndarray:
    """``count`` phase values from index ``start`` of the phase file."""
    f.seek(8 * start)
    out = np.fromfile(f, dtype=np.float64, count=count)
    if out.size != count:  # the file is ours: a short read is a fault, not a user's error
        raise OSError(f"the phase file ended at {start + out.size}; expected {start + count}")
    return out


class _FamilyCarry(_PhaseCarry):
    """The running phase and the in-pass sums of the MDEV (``kind="mdev"``) or HDEV terms."""

    def __init__(self, kind: str, short_ms: np.ndarray, history: int, file: BinaryIO) -> None:
        self.kind = kind
        super().__init__(short_ms, history, file)

    def sum_terms(self, ext: np.ndarray, back: int, first: int) -> None:
        # a term that starts at phase index j ends at j + 3m − 1 (MDEV) or j + 3m (HDEV);
        # the terms ending in this chunk start at ext index lo … hi (ext[0] is index first − back)
        span = 3 * self.short_ms - (self.kind == "mdev")
        lo = np.maximum(back - span, back - first)
        hi = ext.size - 1 - span
        live = hi >= lo
        if not live.any():
            return
        if self.kind == "hdev":
            self.sums[live] += combination_sums(
                ext, self.short_ms[live], _HADAMARD, lo[live], hi[live] - lo[live] + 1
            )
            return
        for k in np.flatnonzero(live).tolist():
            m = int(self.short_ms[k])
            piece = ext[int(lo[k]) : int(hi[k]) + 3 * m]
            self.sums[k] += float(modified_sums(piece, np.array([m]))[0])


def _long_hadamard_sums(f: BinaryIO, n_phase: int, m: int) -> float:
    """Σ_{i=0}^{N−3m−1} (x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i)² from the phase file."""
    total = 0.0
    count = n_phase - 3 * m
    for i in range(0, count, _READ):
        c = min(_READ, count - i)
        d = _read(f, i + 3 * m, c)
        d -= _read(f, i, c)
        d += 3.0 * (_read(f, i + m, c) - _read(f, i + 2 * m, c))
        total += float(np.dot(d, d))
    return total


class _RunningSecondDifferences:
    """C_k = Σ_{i≤k} (x_{i+2m} − 2x_{i+m} + x_i), k = 0, 1, …, read from the phase file in order."""

    def __init__(self, f: BinaryIO, m: int) -> None:
        self.f, self.m, self.k, self.carried = f, m, 0, 0.0

    def take(self, count: int) -> np.ndarray:
        """The next ``count`` (≤ a block) values of C."""
        k, m = self.k, self.m
        c = _read(self.f, k + m, count)
        c *= -2.0
        c += _read(self.f, k, count)
        c += _read(self.f, k + 2 * m, count)
        np.cumsum(c, out=c)
        c += self.carried
        self.carried = float(c[-1])
        self.k += count
        return c


def _long_modified_sums(f: BinaryIO, n_phase: int, m: int) -> float:
    """Σ_{j=0}^{N−3m} (Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i))² from the phase file, as
    C_{j+m−1} − C_{j−1} of the running sum C of the second differences (two readers m apart)."""
    lead = _RunningSecondDifferences(f, m)
    for i in range(0, m - 1, _READ):  # lead to C_{m−1}
        lead.take(min(_READ, m - 1 - i))
    lag = _RunningSecondDifferences(f, m)
    before = 0.0  # C_{−1}
    total = 0.0
    count = n_phase - 3 * m + 1
    for i in range(0, count, _READ):
        c = min(_READ, count - i)
        d = lead.take(c)
        d[0] -= before
        behind = lag.take(c)
        d[1:] -= behind[:-1]
        before = float(behind[-1])
        total += float(np.dot(d, d))
    return total


def _total_ends(f: BinaryIO, n_phase: int, m: int) -> float:
    """The squares of the total variance's terms at 1 ≤ i ≤ m−1 and N−m ≤ i ≤ N−2, whose
    second differences reach into the reflected extension x*_{−j} = 2x_0 − x_j,
    x*_{N−1+j} = 2x_{N−1} − x_{N−1−j} (NIST SP 1065 §5.2.11)."""
    total = 0.0
    last = n_phase - 1
    x0, xn = float(_read(f, 0, 1)[0]), float(_read(f, last, 1)[0])
    for i in range(1, m, _READ):
        c = min(_READ, m - i)  # i … i + c − 1
        # left: x*_{i−m} − 2x_i + x_{i+m}, x*_{i−m} = 2x_0 − x_{m−i}
        d = _read(f, i + m, c) - 2.0 * _read(f, i, c)
        d += 2.0 * x0
        d -= _read(f, m - i - c + 1, c)[::-1]
        total += float(np.dot(d, d))
        # right, at i' = N − 1 − i: x_{i'−m} − 2x_{i'} + 2x_{N−1} − x_{N−1−(i'+m−N+1)}, which
        # is x_{N−1−i−m} − 2x_{N−1−i} + 2x_{N−1} − x_{N−1+i−m}
        d = _read(f, last - i - m - c + 1, c)[::-1] - 2.0 * _read(f, last - i - c + 1, c)[::-1]
        d += 2.0 * xn
        d -= _read(f, last + i - m, c)
        total += float(np.dot(d, d))
    return total


class _FamilyAdev(ChunkedAdev):
    """ChunkedAdev's reading pass and phase file, with the in-pass sums of ``kind``."""

    def __init__(self, kind: str, **options: Any) -> None:
        self.kind = kind
        super().__init__(**options)

    def _make_carry(self) -> _PhaseCarry:
        if self.kind in ("adev", "totdev"):
            return super()._make_carry()
        kind = "hdev" if self.kind == "hdev" else "mdev"
        sizes = _candidate_sizes(self.taus, self.history // 3)
        return _FamilyCarry(kind, sizes, self.history, self._file)

    def family_sums(self, ms: np.ndarray) -> np.ndarray:
        """The deviation's sums of squares (NIST SP 1065 eqs. (14), (18), (25)) over the phase
        in rate × sample interval."""
        carry = self._carry
        n_phase = carry.count
        if self.kind in ("adev", "totdev"):
            sums = self.cluster_sums(ms)
            if self.kind == "totdev":
                sums += [_total_ends(self._file, n_phase, m) for m in ms.tolist()]
            return sums
        self._file.flush()
        index = {m: k for k, m in enumerate(carry.short_ms.tolist())}
        long = _long_hadamard_sums if self.kind == "hdev" else _long_modified_sums
        return np.array(
            [
                carry.sums[index[m]] if m in index else long(self._file, n_phase, m)
                for m in ms.tolist()
            ]
        )


class ChunkedDeviation:
    """One deviation of the Allan family of a rate record fed in chunks (bounded memory).

    ``add(rate)`` for each chunk in order (rate in any unit u), then ``result(fs=…)``; use it
    as a context manager (it holds a temporary phase file, deleted on exit). The result is
    ``stability_deviation(whole, fs=fs, kind=kind, taus=taus)``'s to rounding (≤ 1e-9
    relative, tested): see the module for how.

    Parameters
    ----------
    kind : "adev", "mdev", "hdev", "tdev" or "totdev".
    taus : "octave" or "decade".
    history : int — phase values carried between chunks (a power of two ≥ 4); MDEV/TDEV/HDEV
        cluster sizes with 3m > history, and the TOTDEV's ends, are summed from the phase file.
    column : str — the column's name, for messages.
    progress : callable, optional — called with the samples read so far.
    """

    def __init__(
        self,
        kind: str = "mdev",
        *,
        taus: str = "octave",
        history: int = DEFAULT_HISTORY,
        column: str = "data",
        progress: Progress | None = None,
    ) -> None:
        if kind not in DEVIATIONS:
            raise ConfigError(f"kind must be one of {', '.join(DEVIATIONS)}; got {kind!r}.")
        self.kind = kind
        self._acc = _FamilyAdev(kind, taus=taus, history=history, column=column, progress=progress)

    def __enter__(self) -> ChunkedDeviation:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Delete the temporary phase file."""
        self._acc.close()

    @property
    def n_samples(self) -> int:
        """Rate samples fed so far."""
        return self._acc.n_samples

    def add(self, chunk: Any) -> None:
        """Feed the next rate samples (1-D; NaN/inf and out-of-range values are refused, the
        sample counted from the start of the record)."""
        self._acc.add(chunk)

    def result(
        self, *, fs: float, confidence: float = ONE_SIGMA, noise_alpha: Any = 0
    ) -> StabilityDeviation:
        """The deviation of everything fed (fs in Hz; ±1σ interval and white-FM edf by default).

        Raises
        ------
        CaptureError — fewer than 10 phase points, a constant record.
        ConfigError — a bad fs, confidence or α; a record too short for any τ of the kind.
        """
        fs_hz = _check_fs(fs)
        conf = _check_confidence(confidence)
        kind = self.kind
        carry = self._acc._carry
        n_phase = carry.count
        check_streamed_record(n_phase, carry.low, carry.high)
        top, listed = longest_cluster(kind, n_phase)
        ms, notes = _cluster_sizes(self._acc.taus, n_phase, fs_hz, top, listed)
        # n_phase ≥ 10 (checked above) leaves m = 1 and 2 for every kind: ms is never empty
        if kind == "adev":
            adev = deviation_of_streamed_sums(
                self._acc.cluster_sums(ms),
                ms,
                notes,
                n_phase=n_phase,
                fs_hz=fs_hz,
                confidence=conf,
                noise_alpha=noise_alpha,
            )
            return _from_adev(adev)
        return deviation_from_sums(
            kind,
            self._acc.family_sums(ms) / (fs_hz * fs_hz),
            ms,
            n_phase=int(n_phase),
            n_samples=n_phase - 1,
            fs_hz=fs_hz,
            data_type="rate",
            confidence=conf,
            noise_alpha=noise_alpha,
            notes=tuple(notes),
        )
