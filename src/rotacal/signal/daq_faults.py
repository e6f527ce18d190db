"""Samples a DAQ lost or wrote twice, found from the time stamps: gaps, duplicated times, repeated rows.

A logging DAQ that drops a buffer leaves a gap in ``time_s``; one that resends a buffer, or a
logger that writes a row twice, leaves the same time stamp twice. This module finds them in one
pass (whole array, or chunk by chunk with the last sample carried), so that an analysis can name
them in its ``warnings`` and refuse a record with too many of them:

- a *repeated row*: a sample whose time and value equal the previous sample's — dropped;
- a *duplicated time*: a sample whose time equals the previous one's but whose value differs —
  dropped (the first of the two is kept: which is right cannot be known);
- a *gap*: a step longer than :data:`GAP_STEPS` typical steps; it lost ``round(step/typical) − 1``
  samples. The samples on either side are kept (a least-squares fit needs no uniform grid);
- a step backwards in time is refused (:class:`~rotacal.errors.CaptureError`): the record's order
  is broken and reordering would be a guess.

The typical step is the median of the first :data:`TYPICAL_STEPS` positive steps. The fraction
of faulty samples, ``(missing + duplicated + repeated)/samples``, above :data:`MAX_FAULT_FRACTION`
is refused unless the user insists (``allow=True``, CLI ``--allow-gaps``).

References
----------
IEEE Std 1057-2017 §4.1.3 (the sine fit takes the samples' own times, so a gap does not bias it);
IEEE Std 1241-2010 §4.1.4.4 (missing codes/samples of a record named, not hidden).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rotacal.errors import CaptureError

__all__ = [
    "GAP_STEPS",
    "MAX_FAULT_FRACTION",
    "TYPICAL_STEPS",
    "DaqFaultFinder",
    "DaqFaults",
    "find_daq_faults",
]

#: A step longer than this many typical steps is a gap.
GAP_STEPS = 1.5
#: The typical step is the median of this many first positive steps.
TYPICAL_STEPS = 100_000
#: Above this fraction of faulty samples a record is refused unless ``allow``.
MAX_FAULT_FRACTION = 0.01
#: Sample numbers kept per kind of fault for the messages (the counts are complete).
_LISTED = 20


@dataclasses.dataclass(frozen=True)
class DaqFaults:
    """The DAQ faults of a record.

    Attributes
    ----------
    samples : int — samples in the record (faulty ones included).
    typical_step_s : float — the typical time step (s).
    gaps : tuple of int — the sample after each gap (first :data:`_LISTED`).
    gap_count : int — gaps found.
    missing : int — samples lost in the gaps (estimated from their lengths).
    duplicated : tuple of int — samples with a repeated time and another value (first ones).
    duplicated_count : int
    repeated : tuple of int — samples equal in time and value to the previous (first ones).
    repeated_count : int
    """

    samples: int
    typical_step_s: float
    gaps: tuple[int, ...]
    gap_count: int
    missing: int
    duplicated: tuple[int, ...]
    duplicated_count: int
    repeated: tuple[int, ...]
    repeated_count: int

    @property
    def fraction(self) -> float:
        """(missing + duplicated + repeated) / samples."""
        bad = self.missing + self.duplicated_count + self.repeated_count
        return bad / max(self.samples, 1)

    def warnings(self, name: str = "time_s") -> list[str]:
        """One line per kind of fault found, with the sample numbers (from 0) and the count."""
        out = []
        if self.gap_count:
            out.append(
                f"{name}: {self.gap_count} gap(s), about {self.missing} sample(s) missing, "
                f"before sample(s) {_listed(self.gaps, self.gap_count)}"
            )
        if self.duplicated_count:
            out.append(
                f"{name}: {self.duplicated_count} duplicated time stamp(s) with another value "
                f"at sample(s) {_listed(self.duplicated, self.duplicated_count)}; the first "
                "reading of each was kept"
            )
        if self.repeated_count:
            out.append(
                f"{name}: {self.repeated_count} repeated row(s) at sample(s) "
                f"{_listed(self.repeated, self.repeated_count)}, dropped"
            )
        return out

    def check(self, allow: bool, name: str = "time_s") -> None:
        """Refuse more than :data:`MAX_FAULT_FRACTION` faulty samples unless ``allow``."""
        if allow or self.fraction <= MAX_FAULT_FRACTION:
            return
        raise CaptureError(
            f"{name}: {self.fraction:.2%} of the samples are missing, duplicated or repeated "
            f"(more than {MAX_FAULT_FRACTION:.0%}; {'; '.join(self.warnings(name))}): fix the "
            "DAQ's logging, or pass --allow-gaps to analyse what is there"
        )


def _listed(first: tuple[int, ...], count: int) -> str:
    more = f" and {count - len(first)} more" if count > len(first) else ""
    return ", ".join(map(str, first)) + more


class DaqFaultFinder:
    """Finds :class:`DaqFaults` chunk by chunk; ``feed`` returns which samples to keep.

    The last sample (time and value) is carried from chunk to chunk; the typical step comes from
    the first chunk with a positive step (its first :data:`TYPICAL_STEPS`), so the result does
    not depend on the chunking once that chunk holds a representative stretch (the file readers'
    chunks hold 10⁶ rows).
    """

    def __init__(self, name: str = "time_s") -> None:
        self.name = name
        self._last: tuple[float, float] | None = None
        self._typical: float | None = None
        self._seen = 0
        self._lists: dict[str, list[int]] = {"gaps": [], "duplicated": [], "repeated": []}
        self._counts = {"gaps": 0, "duplicated": 0, "repeated": 0, "missing": 0}

    @property
    def seen(self) -> int:
        """Samples fed so far."""
        return self._seen

    def feed(self, t: np.ndarray, value: np.ndarray) -> np.ndarray:
        """The boolean mask of the chunk's samples to keep (repeated and duplicated dropped)."""
        t = np.asarray(t, dtype=np.float64)
        v = np.asarray(value)
        if t.size == 0:
            return np.ones(0, dtype=bool)
        if self._last is None:
            steps = np.diff(t)
            same = v[1:] == v[:-1]
            first_keep = [True]
        else:
            steps = np.diff(t, prepend=self._last[0])
            same = v == np.concatenate(([self._last[1]], v[:-1])).astype(v.dtype, copy=False)
            first_keep = []
        back = np.flatnonzero(steps < 0)
        if back.size:
            i = int(back[0]) + (1 if self._last is None else 0) + self._seen
            raise CaptureError(
                f"column '{self.name}' goes back in time at sample {i}: the record's order is "
                "broken; sort or split the file"
            )
        if self._typical is None:
            positive = steps[steps > 0][:TYPICAL_STEPS]
            if positive.size:  # else no step of this chunk can be a gap
                self._typical = float(np.median(positive))
        base = self._seen + (1 if self._last is None else 0)  # sample number of steps[0]'s end
        zero = steps == 0
        self._note("repeated", np.flatnonzero(zero & same), base)
        self._note("duplicated", np.flatnonzero(zero & ~same), base)
        gap = np.flatnonzero(steps > GAP_STEPS * (self._typical or np.inf))
        self._note("gaps", gap, base)
        if gap.size:
            lost = np.rint(steps[gap] / self._typical).astype(np.int64) - 1
            self._counts["missing"] += int(np.sum(np.maximum(lost, 1)))
        keep = np.concatenate((first_keep, ~zero)).astype(bool)
        self._last = (float(t[-1]), v[-1].item())
        self._seen += t.size
        return keep

    def _note(self, kind: str, where: np.ndarray, base: int) -> None:
        self._counts[kind] += int(where.size)
        room = _LISTED - len(self._lists[kind])
        if room > 0 and where.size:
            self._lists[kind].extend(int(i) + base for i in where[:room])

    def result(self) -> DaqFaults:
        """The faults of everything fed so far."""
        if self._seen > 1 and self._typical is None:
            raise CaptureError(f"column '{self.name}' does not advance: every time is the same")
        return DaqFaults(
            samples=self._seen,
            typical_step_s=float(self._typical or 0.0),
            gaps=tuple(self._lists["gaps"]),
            gap_count=self._counts["gaps"],
            missing=self._counts["missing"],
            duplicated=tuple(self._lists["duplicated"]),
            duplicated_count=self._counts["duplicated"],
            repeated=tuple(self._lists["repeated"]),
            repeated_count=self._counts["repeated"],
        )


def find_daq_faults(
    t: np.ndarray, value: np.ndarray, name: str = "time_s"
) -> tuple[DaqFaults, np.ndarray]:
    """The DAQ faults of a whole record and the mask of samples to keep (module docstring).

    Parameters
    ----------
    t : array, s — time stamps in record order.
    value : array — the reading logged with each (count or angle), to tell a repeated row
        from a duplicated time.
    name : the time column's name, for messages.

    Returns
    -------
    (DaqFaults, array of bool)
    """
    t = np.asarray(t, dtype=np.float64)
    value = np.asarray(value)
    if t.shape != value.shape or t.ndim != 1:
        raise CaptureError(f"{name} and the readings must be 1-D arrays of one length")
    finder = DaqFaultFinder(name)
    keep = finder.feed(t, value)
    return finder.result(), keep
