"""Readings of a position test arranged as approaches: x[direction, run, position] (ISO 230-2 test).

A position test visits the same target positions in every run, in one direction of approach or
in both (ISO 230-2:2014, the standard test cycle). The rows of a capture name, for each reading,
the target position (``position_deg``), optionally the run and the direction of approach. This
module checks that every run and direction visited the same positions once each, and puts the
readings in a (D, R, P) array — the shape the ISO 230-2 statistics, the polygon's
cross-calibration and the harmonic fit all read.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import CaptureError

__all__ = ["POSITION_DECIMALS", "Approaches", "arrange_approaches"]

#: Target positions are grouped after rounding to this many decimals of a degree (0.0036″):
#: commanded positions are exact numbers, so anything finer is the file's float formatting.
POSITION_DECIMALS = 6

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class Approaches:
    """Readings arranged as ``values[d, r, p]``.

    ``positions_deg`` (P,) are the target positions in ascending order; ``directions`` (D,)
    holds +1 (approach in the positive sense, ISO 230-2 ↑) and/or −1 (↓); ``runs`` (R,) the run
    labels (the file's ``run`` column, or 0, 1, … counted as the k-th reading at each position
    when there is none); ``rows[d, r, p]`` the capture row of each reading.
    """

    values: FloatArray
    positions_deg: FloatArray
    directions: tuple[int, ...]
    runs: tuple[int, ...]
    rows: NDArray[np.int64]
    runs_from_column: bool


def _labels(values: ArrayLike, name: str) -> NDArray[np.int64]:
    a = np.asarray(values, dtype=np.float64)
    bad = np.flatnonzero(~np.isfinite(a) | (a != np.round(a)))
    if bad.size:
        raise CaptureError(
            f"column {name}: row {int(bad[0])} holds {a[bad[0]]!r}; {name} must be a whole number"
        )
    return a.astype(np.int64)


def _direction_signs(direction: ArrayLike | None, n: int) -> NDArray[np.int64]:
    if direction is None:
        return np.ones(n, dtype=np.int64)
    d = np.asarray(direction, dtype=np.float64)
    zero = np.flatnonzero(~(d > 0) & ~(d < 0))
    if zero.size:
        raise CaptureError(
            f"column direction: row {int(zero[0])} holds {d[zero[0]]!r}; give +1 for an approach "
            "in the positive sense and -1 for the negative sense"
        )
    return np.where(d > 0, 1, -1).astype(np.int64)


def _name(position: float) -> str:
    return f"{position:g}°"


def _refuse_different_sets(
    present: NDArray[np.int64],
    targets: FloatArray,
    run_labels: NDArray[np.int64],
    directions: tuple[int, ...],
) -> None:
    """Name the first run (and direction) whose positions differ from the most common set."""
    sets, inverse, counts = np.unique(present > 0, axis=0, return_inverse=True, return_counts=True)
    usual = sets[int(np.argmax(counts))]
    odd = int(np.flatnonzero(inverse.ravel() != int(np.argmax(counts)))[0])
    d, r = divmod(odd, run_labels.size)
    missing = targets[usual & ~(present[odd] > 0)]
    extra = targets[~usual & (present[odd] > 0)]
    parts = []
    if missing.size:
        parts.append("no reading at " + ", ".join(map(_name, missing[:4])))
    if extra.size:
        parts.append("readings at " + ", ".join(map(_name, extra[:4])) + " that the others lack")
    raise CaptureError(
        f"run {int(run_labels[r])} in direction {directions[d]:+d} has {' and '.join(parts)}: "
        "every run and direction must measure the same positions (ISO 230-2 test cycle; without "
        "a run column, run k is the k-th reading at each position)"
    )


def arrange_approaches(
    position_deg: ArrayLike,
    values: ArrayLike,
    *,
    run: ArrayLike | None = None,
    direction: ArrayLike | None = None,
) -> Approaches:
    """Arrange the readings ``values`` (any unit) of a position test by direction, run, position.

    Parameters
    ----------
    position_deg : array_like, deg
        Target (commanded or indicated) position of each reading.
    values : array_like
        The reading at each row (a deviation in arcsec, or a reference angle).
    run : array_like of int, optional
        Run of each row. Without it the k-th reading at a position (in a direction) is run k.
    direction : array_like, optional
        Sign of each row's approach (> 0: positive sense, < 0: negative). Default: all positive.

    Raises
    ------
    CaptureError
        A run/direction that misses a position or reads one twice (every run must visit the
        same positions once: ISO 230-2's test cycle), fewer than one position, bad labels.
    """
    pos = np.asarray(position_deg, dtype=np.float64)
    vals = np.asarray(values, dtype=np.float64)
    n = pos.size
    if n == 0:
        raise CaptureError("the capture holds no readings")
    if vals.shape != pos.shape:
        raise CaptureError("position_deg and the readings differ in length")
    targets, p_index = np.unique(np.round(pos, POSITION_DECIMALS), return_inverse=True)
    signs = _direction_signs(direction, n)
    directions = tuple(int(d) for d in sorted(set(signs.tolist()), reverse=True))
    d_index = np.where(signs == directions[0], 0, 1)
    runs_from_column = run is not None
    if run is not None:
        labels = _labels(run, "run")
        run_labels, r_index = np.unique(labels, return_inverse=True)
    else:
        # the k-th reading of each (direction, position) in row order is run k
        key = d_index * targets.size + p_index
        order = np.argsort(key, kind="stable")
        sorted_key = key[order]
        starts = np.r_[0, np.flatnonzero(np.diff(sorted_key)) + 1]
        counts = np.diff(np.r_[starts, n])
        rank = np.arange(n) - np.repeat(starts, counts)
        r_index = np.empty(n, dtype=np.int64)
        r_index[order] = rank
        run_labels = np.arange(int(r_index.max()) + 1)
    shape = (len(directions), run_labels.size, targets.size)
    cell = np.ravel_multi_index((d_index, r_index, p_index), shape)
    count = np.bincount(cell, minlength=int(np.prod(shape))).reshape(shape)
    if np.any(count > 1):
        d, r, p = (int(i[0]) for i in np.nonzero(count > 1))
        raise CaptureError(
            f"run {int(run_labels[r])} reads position {_name(targets[p])} "
            f"{int(count[d, r, p])} times in direction {directions[d]:+d}: one reading per "
            "approach (average repeated readings before, or number the runs in a run column)"
        )
    if np.any(count == 0):
        _refuse_different_sets(count.reshape(-1, targets.size), targets, run_labels, directions)
    arranged = np.empty(shape)
    arranged.flat[cell] = vals
    rows = np.empty(shape, dtype=np.int64)
    rows.flat[cell] = np.arange(n)
    return Approaches(
        values=arranged,
        positions_deg=targets.astype(np.float64),
        directions=directions,
        runs=tuple(int(r) for r in run_labels),
        rows=rows,
        runs_from_column=runs_from_column,
    )
