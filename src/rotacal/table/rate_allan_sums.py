"""The sums behind s(φ): Σ(ω_{j+k} − ω_j)² over a pulse record, whole or chunk by chunk.

Cluster sizes from 2·:data:`ALLAN_FULL_CLUSTERS` pulses on are taken on the record decimated to
every d-th pulse (d a divisor of k, k/d ≥ :data:`ALLAN_FULL_CLUSTERS`): the overlapping Allan
variance of the pulses at stride d, of cluster size k/d (NIST SP 1065 §5.2.4: τ = k/d·(d·τ₀)).
Terms d pulses apart are nearly the same term when d ≪ k (they share all but 2d/k of their
pulses), so the estimate keeps its degrees of freedom (its edf is that of the decimated record,
Greenhall & Riley 2003) and the work falls from N per cluster size to N/d; above all, a cluster
of k pulses then needs only the last 2k/d decimated pulses, so a stream is summed with a bounded
carried state (:class:`AllanSums`) and gives the in-memory sums to rounding.

Whole-array NumPy here; the Numba twin (:mod:`rotacal.table._rate_allan_jit`) for long records
(:func:`rotacal._jit.use_numba`), both to ≤ 1e-12 relative.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from rotacal._jit import use_numba

__all__ = [
    "ALLAN_FULL_CLUSTERS",
    "AllanSums",
    "allan_stride",
    "allan_sum",
    "decimated_grid",
    "grid_stride",
]

FloatArray = NDArray[np.float64]

#: Cluster sizes below twice this are summed over every pulse; larger ones over every d-th pulse
#: with at least this many decimated pulses per cluster.
ALLAN_FULL_CLUSTERS = 64
#: Terms per block sum (the blocks are added exactly, ``math.fsum``).
ALLAN_BLOCK = 1 << 14


def allan_stride(k: int) -> int:
    """The stride d of cluster size k: its largest divisor with k/d ≥ :data:`ALLAN_FULL_CLUSTERS`
    (1 below twice that)."""
    limit = k // ALLAN_FULL_CLUSTERS
    if limit < 2:
        return 1
    i = np.arange(1, math.isqrt(k) + 1, dtype=np.int64)
    small = i[k % i == 0]
    divisors = np.concatenate((small, k // small))
    return int(divisors[divisors <= limit].max())


def decimated_grid(k: int) -> int:
    """k rounded to a multiple of the power of two 2^⌊log₂(k/K₀)⌋ (K₀ =
    :data:`ALLAN_FULL_CLUSTERS`), so that its stride keeps K₀ … 2K₀ decimated pulses per cluster
    (a change of k by less than 1/K₀ of itself: a point of a logarithmic grid)."""
    d = grid_stride(k)
    return d * max(1, round(k / d))


def grid_stride(k: int) -> int:
    """The power of two 2^⌊log₂(k/K₀)⌋ a grid point k is rounded to a multiple of (1 below 2K₀)."""
    if k < 2 * ALLAN_FULL_CLUSTERS:
        return 1
    return 1 << math.floor(math.log2(k / ALLAN_FULL_CLUSTERS))


def _block_sums_numpy(
    t: FloatArray, a: FloatArray, k: int, first: int, stop: int, block: int
) -> FloatArray:
    out = []
    for start in range(first, stop, block):
        end = min(start + block, stop)
        omega = (a[start + k : end + 2 * k] - a[start : end + k]) / (
            t[start + k : end + 2 * k] - t[start : end + k]
        )
        d = omega[k:] - omega[:-k]
        out.append(float(np.dot(d, d)))
    return np.asarray(out, dtype=np.float64)


def allan_sums(
    t: FloatArray,
    a: FloatArray,
    ks: Sequence[int],
    firsts: Sequence[int],
    stops: Sequence[int],
    *,
    jit: bool | None = None,
) -> list[float]:
    """Σ_{j=first}^{stop−1} (ω_{j+k} − ω_j)², ω_j = (a[j+k] − a[j])/(t[j+k] − t[j]), (deg/s)²,
    for every cluster size k with its own range of terms.

    Parameters
    ----------
    t, a : ndarray, s and deg
        Pulse times and angles (needs indices up to stop − 1 + 2k).
    ks : sequence of int
        Cluster sizes (pulses of t).
    firsts, stops : sequence of int
        The terms summed for each.
    jit : bool, optional
        Force (True) or refuse (False) the Numba twin (one pass over the record for all cluster
        sizes); default from the number of terms.

    References
    ----------
    Kokuyama et al. (2015), §5: ω_i = (θ_{i+k} − θ_i)/(kΔt), σ²(τ) = ½⟨(ω_{i+k} − ω_i)²⟩.
    """
    k_arr = np.asarray(ks, dtype=np.int64)
    lo = np.asarray(firsts, dtype=np.int64)
    hi = np.maximum(np.asarray(stops, dtype=np.int64), lo)
    if k_arr.size == 0:
        return []
    if use_numba(int(np.max(hi - lo)), jit):
        from rotacal.table._rate_allan_jit import block_sums

        parts = block_sums(t, a, k_arr, lo, hi, ALLAN_BLOCK)
        return [math.fsum(row) for row in parts.tolist()]
    return [
        math.fsum(_block_sums_numpy(t, a, int(k), int(f), int(s), ALLAN_BLOCK).tolist())
        for k, f, s in zip(k_arr, lo, hi, strict=True)
    ]


def allan_sum(
    t: FloatArray, a: FloatArray, k: int, first: int, stop: int, *, jit: bool | None = None
) -> float:
    """:func:`allan_sums` of one cluster size k over terms first … stop − 1."""
    return allan_sums(t, a, [k], [first], [stop], jit=jit)[0]


class AllanSums:
    """Σ(ω_{j+k} − ω_j)² and the number of terms, per cluster size, over a stream of pulses.

    Each stride d keeps the last 2·max(k/d) decimated pulses of the chunks seen (all a later term
    needs): memory bounded by the cluster sizes, whatever the record's length.

    Parameters
    ----------
    ks, strides : sequence of int
        Cluster sizes (pulses) and their strides (each divides its k).
    jit : bool, optional
        Force or refuse the Numba twin.
    """

    def __init__(self, ks: Sequence[int], strides: Sequence[int], jit: bool | None = None) -> None:
        self.ks = [int(k) for k in ks]
        self.strides = [int(d) for d in strides]
        self.jit = jit
        self.parts: list[list[float]] = [[] for _ in self.ks]
        self.counts = np.zeros(len(self.ks), dtype=np.int64)
        self._seen = 0  # pulses fed so far
        groups: dict[int, list[int]] = {}
        for idx, d in sorted(enumerate(self.strides), key=lambda x: x[1]):
            groups.setdefault(d, []).append(idx)
        self._groups = groups
        # each stride's pulses are taken from those of its largest divisor among the strides
        # (a record a fraction of the chunk's, in cache: not every stride across the whole chunk)
        self._parent = {
            d: max(p for p in (1, *groups) if p < d and d % p == 0) for d in groups if d > 1
        }
        # per stride: decimated tail (t, a), its first decimated index, next term per k
        self._tails = {d: (np.zeros(0), np.zeros(0), 0) for d in groups}
        self._next = [0] * len(self.ks)

    def update(self, t: FloatArray, a: FloatArray) -> None:
        """Add the next chunk of pulse times (s) and angles (deg).

        The record is the carried tail followed by the chunk's decimated pulses; terms that start
        in the tail are summed on the tail and the chunk's first 2·max(k/d) pulses, the others on
        the chunk itself (every pulse: a view, not a copy of the chunk).
        """
        decimated = {1: (0, t, a)}  # stride: its first pulse in the chunk, times, angles
        children = dict.fromkeys((1, *self._groups), 0)
        for p in self._parent.values():
            children[p] += 1
        for d, members in self._groups.items():
            first = (-self._seen) % d  # the chunk's first pulse whose index is a multiple of d
            ct, ca = t, a
            if d > 1:  # from the parent's pulses, with unit stride for the kernels
                p = self._parent[d]
                p_first, p_t, p_a = decimated[p]
                i0, step = (first - p_first) // p, d // p
                ct, ca = p_t[i0::step].copy(), p_a[i0::step].copy()
                children[p] -= 1
                if children[p] == 0:
                    del decimated[p]
                if children[d]:
                    decimated[d] = (first, ct, ca)
            tt, aa, base = self._tails[d]
            held = tt.size  # decimated index base + held is the chunk's first
            kds = [self.ks[idx] // d for idx in members]
            starts = [self._next[idx] - base for idx in members]
            stops = [held + ct.size - 2 * kd for kd in kds]
            reach = 2 * max(kds)
            head_t = np.concatenate((tt, ct[:reach]))
            head_a = np.concatenate((aa, ca[:reach]))
            in_head = allan_sums(
                head_t, head_a, kds, starts, [min(s, held) for s in stops], jit=self.jit
            )
            body = [max(s, held) - held for s in starts]
            in_body = allan_sums(ct, ca, kds, body, [s - held for s in stops], jit=self.jit)
            for i, idx in enumerate(members):
                if stops[i] > starts[i]:
                    self.parts[idx] += [in_head[i], in_body[i]]
                    self.counts[idx] += stops[i] - starts[i]
                    self._next[idx] = base + stops[i]
            keep = max(0, min(self._next[idx] for idx in members) - base)
            if keep >= held:
                self._tails[d] = (ct[keep - held :].copy(), ca[keep - held :].copy(), base + keep)
            else:
                self._tails[d] = (
                    np.concatenate((tt[keep:], ct)),
                    np.concatenate((aa[keep:], ca)),
                    base + keep,
                )
        self._seen += t.size

    @classmethod
    def starting_at(
        cls, ks: Sequence[int], strides: Sequence[int], first: int, jit: bool | None = None
    ) -> AllanSums:
        """Sums of a block of a record that starts at pulse ``first``: fed the block's pulses,
        they hold the terms that lie wholly inside it (:meth:`merge` adds the block, and the
        terms across its start, to the sums of the record before it)."""
        out = cls(ks, strides, jit)
        out._seen = int(first)
        for d in out._groups:
            start = -(-out._seen // d)  # the block's first decimated index
            out._tails[d] = (np.zeros(0), np.zeros(0), start)
            for idx in out._groups[d]:
                out._next[idx] = start
        return out

    def heads(self, t: FloatArray, a: FloatArray) -> dict[int, tuple[FloatArray, FloatArray]]:
        """Per stride, the first decimated pulses (times, angles) of the chunk that follows the
        pulses seen, as many as a term reaches past its start: what :meth:`merge` needs of it."""
        out = {}
        for d, members in self._groups.items():
            first = (-self._seen) % d
            reach = 2 * max(self.ks[idx] // d for idx in members)
            out[d] = (t[first::d][:reach].copy(), a[first::d][:reach].copy())
        return out

    def merge(self, block: AllanSums, heads: dict[int, tuple[FloatArray, FloatArray]]) -> None:
        """Add the sums of the block that follows the pulses seen (:meth:`starting_at` of
        them, fed the block; ``heads``: its :meth:`heads`): the terms that start in the carried
        tails are summed on them and the block's first pulses, as :meth:`update` would."""
        if block.ks != self.ks or block.strides != self.strides:
            raise ValueError("the block's cluster sizes are not these")
        for d, members in self._groups.items():
            tt, aa, base = self._tails[d]
            held = tt.size
            ht, ha = heads[d]
            count = -(-block._seen // d) - -(-self._seen // d)  # the block's decimated pulses
            kds = [self.ks[idx] // d for idx in members]
            starts = [self._next[idx] - base for idx in members]
            stops = [min(held + count - 2 * kd, held) for kd in kds]
            sums = allan_sums(
                np.concatenate((tt, ht)), np.concatenate((aa, ha)), kds, starts, stops, jit=self.jit
            )
            for i, idx in enumerate(members):
                if stops[i] > starts[i]:
                    self.parts[idx].append(sums[i])
                    self.counts[idx] += stops[i] - starts[i]
                done = max(starts[i], stops[i])
                # a term left in the tail needs pulses after the block: the block has none
                self._next[idx] = base + done if done < held else block._next[idx]
            keep = min(self._next[idx] for idx in members) - base
            if keep >= held:
                self._tails[d] = block._tails[d]
            else:  # the block is shorter than a term: all of it is in its head
                self._tails[d] = (
                    np.concatenate((tt[keep:], ht)),
                    np.concatenate((aa[keep:], ha)),
                    base + keep,
                )
        for idx, part in enumerate(block.parts):
            self.parts[idx] += part
        self.counts += block.counts
        self._seen = block._seen

    def mean_squares(self) -> FloatArray:
        """⟨(ω_{j+k} − ω_j)²⟩ per cluster size, (deg/s)² (NaN where no term was complete)."""
        sums = np.array([math.fsum(p) for p in self.parts])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.counts > 0, sums / np.maximum(self.counts, 1), np.nan)
