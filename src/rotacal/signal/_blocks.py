"""Block-moment compression of a capture for fast multi-harmonic fitting (private).

The time axis is cut into blocks of equal duration ``T_b`` on a grid fixed at the first sample.
For block ``b`` with centre ``c_b`` and the in-block coordinate ``u = (t − c_b)/(T_b/2) ∈ [−1, 1)``
the moments ``P_bk = Σ u^k`` and ``Q_bk = Σ (y − y0)·u^k`` (k = 0..K+1) are kept. For any
frequency, ``exp(j·m·ω·τ) = exp(j·m·ω·d_b)·Σ_l (j·m·ω·T_b/2)^l/l!·u^l`` (``d_b = c_b − t_ref``)
turns every exponential sum of the normal equations into a sum over blocks; the series is cut
where its terms fall below 1e-17, and the block length is chosen so that the highest phase
``2H·ω·T_b/2`` at 1.25·f is the largest the K stored moments hold (:func:`planned_phase`: 1.5 rad
for the default K = 22; fewer, longer blocks make every frequency's sums cheaper, see
:mod:`rotacal.signal._blocks_sums`). Moments add, so chunks can be fed one after another and a
block cut by a chunk boundary is simply summed twice. The moments are kept by
:class:`~rotacal.signal._blocks_store.MomentStore` (a full block's P row not repeated; past 8 MB
in a temporary file, so that memory stays flat however long the capture). For uniformly sampled chunks the moments of all
full blocks are one BLAS product of the (blocks × M) sample matrix with a fixed (M × K+2)
Vandermonde matrix.

A fit of a whole record at once (:func:`~rotacal.signal.sinefit.fit_harmonics`) plans by the
signal's speed: 22 moments for blocks of ≥ 128 samples, 28 (blocks 1.8× longer:
:func:`moments_for`) down to 24-sample blocks, and below that, on a uniform grid, no moments at
all (:func:`sums_from_samples`; :mod:`rotacal.signal._blocks_grid`); its moments stay in memory
up to the size of its samples.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rotacal._jit import use_numba
from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._blocks_grid import SQUARES_OVERFLOW, centred_square_sum, grid_sums
from rotacal.signal._blocks_store import MomentStore
from rotacal.signal._blocks_sums import SUM_ROWS, block_sums, taylor_terms, unit_powers
from rotacal.signal._checks import (
    as_pair,
    check_finite,
    check_frequency,
    check_harmonics,
    check_increasing,
    check_record,
    grid_tolerance,
    max_grid_deviation,
)
from rotacal.signal._freq import estimate_frequency_unchecked
from rotacal.signal._normal import NormalFit, SumsFn, solve_normal
from rotacal.signal._residual import residual_sums, residual_tau_sums
from rotacal.signal._result import SineFit, build_drift_check, build_sine_fit

_F_MARGIN = 1.25
_MAX_BLOCK = 4096
_MIN_BLOCK = 4
_SUB_BLOCKS = 256
_DEFAULT_MOMENTS = 22
_LONG_MOMENTS = 28
# below this block length (of the default plan) a one-shot fit takes _LONG_MOMENTS: at 10,000
# periods of 10⁷ samples (19-sample blocks) the fit took 210 ms with 22 moments, 131 ms with 28;
# at 1,000 periods (190-sample blocks) 42 and 38 ms (the whole fit of the encoder's angle, with
# its residual pass: 94 and 87 ms); at 100 periods (1,909) 20 and 32 ms
_SHORT_BLOCK = 256
# below this block length the samples themselves (10⁷ samples, 10 harmonics: ~100 ms CPU at any
# number of periods; with moments 78 ms at 5,000 periods (38-sample blocks), 142 ms at 10,000
# (19), 650 ms at 30,000 (6), 2.4 s at 100,000 (samples kept one by one))
_GRID_BLOCK = 24
_SUB_SAMPLES = 1 << 16
# The residual from the normal equations, yᵀy − bᵀp, loses its digits when it is this small a
# part of yᵀy; below it a fit that still has the samples sums the residual itself.
_RSS_ROUNDING = 1e-9


def planned_phase(n_moments: int) -> float:
    """Largest in-block phase (rad, on a 0.05 grid) of harmonic 2H at 1.25·f whose exponential
    series the ``n_moments`` stored moments hold to 1e-17: the block length is planned for it
    (1.5 rad for 22 moments; longer blocks, fewer of them, more terms each — fewer blocks win)."""
    x = 0.05
    while taylor_terms(x + 0.05, n_moments) <= n_moments:
        x += 0.05
    return x


def block_length(f_hz: float, harmonics: int, dt_s: float, n_moments: int) -> int:
    """Samples per block (1: samples kept as they are) that the plan gives a fundamental of
    ``f_hz`` (Hz) with ``harmonics`` harmonics, sampled every ``dt_s`` (s), ``n_moments`` moments:
    harmonic 2H at 1.25·f turns by :func:`planned_phase` over half a block, at most 4096 samples,
    and blocks of fewer than 4 samples are not worth their moments."""
    w = 2.0 * math.pi * f_hz * _F_MARGIN
    m = int(min(_MAX_BLOCK, 2.0 * planned_phase(n_moments) / (2 * harmonics * w * dt_s)))
    return 1 if m < _MIN_BLOCK else m


def moments_for(f_hz: float, harmonics: int, dt_s: float) -> int:
    """Moments per block for a record fitted in one go (all samples at hand; arguments as
    :func:`block_length`): the default 22, or 28 when 22 give blocks shorter than
    ``_SHORT_BLOCK`` samples (a fast signal: hundreds of thousands of blocks).

    With 28 the blocks are 1.8× longer (2.75 rad planned instead of 1.5), so the sums at each
    trial frequency read ~45 % fewer blocks (each with 6 more terms); the closed-form weights
    of :func:`~rotacal.signal._blocks_sums.grid_power_sums` still see a block phase
    θ = 2H·ω·T ≤ 2·2.8 rad < 2π (the sums refuse a frequency that needs more moments), where
    their denominators sin(θ/2) stay ≥ 0.33. Longer blocks would bring θ to 2π."""
    m = block_length(f_hz, harmonics, dt_s, _DEFAULT_MOMENTS)
    return _LONG_MOMENTS if _MIN_BLOCK <= m < _SHORT_BLOCK else _DEFAULT_MOMENTS


def sums_from_samples(f_hz: float, harmonics: int, dt_s: float) -> bool:
    """Whether a one-shot fit of a uniformly sampled record (arguments as :func:`block_length`)
    should sum its samples at each trial frequency (:meth:`HarmonicFitAccumulator._hold_grid`)
    rather than compress them into moments: when the default plan's blocks would hold fewer
    than ``_GRID_BLOCK`` samples. The samples cost O(N·H) per frequency whatever the number of
    periods; the moments' sums grow with the number of blocks."""
    return block_length(f_hz, harmonics, dt_s, _DEFAULT_MOMENTS) < _GRID_BLOCK


class HarmonicFitAccumulator:
    """Accumulate a long capture chunk by chunk, then fit a sine with harmonics to all of it.

    Memory stays flat: each chunk is reduced to block moments (K + 2 numbers per block of up to
    4096 samples; about 1/100 of its size for well-sampled signals) as it is added. ``fit()``
    gives the same least-squares solution as an explicit multi-harmonic fit of all samples (IEEE Std 1057-2017, §4.1.3; Feng et al. 2023,
    Sensors 23:4876, eq. (9)).

    Parameters
    ----------
    frequency_hz : float, optional
        Approximate fundamental frequency (Hz) used to size the blocks. If omitted it is
        estimated from the first chunk, which must then hold at least ~1 period.
    harmonics : int
        Largest number of harmonics that ``fit`` will be asked for (sizes the blocks).
    block_samples : int, optional
        Force the block length in samples (1 = no compression; mainly for tests).
    n_moments : int
        Moments kept per block (Taylor terms available at fit time).

    Examples
    --------
    >>> acc = HarmonicFitAccumulator(frequency_hz=0.5)          # doctest: +SKIP
    >>> for t, y in reader:                                     # doctest: +SKIP
    ...     acc.add(t, y)
    >>> fit = acc.fit(harmonics=10)                             # doctest: +SKIP
    """

    def __init__(
        self,
        frequency_hz: float | None = None,
        *,
        harmonics: int = 10,
        block_samples: int | None = None,
        n_moments: int = _DEFAULT_MOMENTS,
    ) -> None:
        self._f_hint = None if frequency_hz is None else check_frequency(frequency_hz)
        self._h_plan = check_harmonics(harmonics)
        if block_samples is not None and (
            isinstance(block_samples, bool)
            or not isinstance(block_samples, (int, np.integer))
            or block_samples < 1
        ):
            raise ConfigError(f"block_samples must be an integer ≥ 1; got {block_samples!r}.")
        self._block_req = None if block_samples is None else int(block_samples)
        if isinstance(n_moments, bool) or not isinstance(n_moments, (int, np.integer)):
            raise ConfigError(f"n_moments must be an integer in 4..40; got {n_moments!r}.")
        if not 4 <= n_moments <= 40:
            raise ConfigError(f"n_moments must be an integer in 4..40; got {n_moments}.")
        self._k = int(n_moments)
        self._ready = False
        self._explicit = False
        self._n = 0
        self._sum_y2 = 0.0
        self._t_first = math.nan
        self._t_last: float | None = None
        # the samples themselves when blocks of one sample (explicit), else the block moments
        self._records: list[tuple[np.ndarray, np.ndarray]] = []
        # a uniformly sampled record held as it is (t, y), summed at each frequency (_hold_grid)
        self._grid: tuple[np.ndarray, np.ndarray] | None = None
        self._store = MomentStore(n_moments + 2)
        # grid (set by _plan)
        self._t0 = 0.0
        self._dt = 0.0
        self._m = 1
        self._tb = 0.0
        self._tg = 0.0
        self._y0 = 0.0
        self._tol = 0.0
        self._v = np.zeros((1, 1))
        self._cumv = np.zeros((2, 1))

    # ------------------------------------------------------------------ properties
    @property
    def n_samples(self) -> int:
        """Number of samples added so far."""
        return self._n

    @property
    def block_samples(self) -> int:
        """Block length in samples (1 = samples kept individually); 0 before the first chunk."""
        return self._m if self._ready else 0

    # ------------------------------------------------------------------ adding data
    def add(self, t: Any, y: Any) -> None:
        """Add one chunk of samples: ``t`` in seconds (increasing, also across chunks), ``y``."""
        ta, ya = as_pair(t, y)
        self._add(ta, ya, uniform_dt=None)

    def _add(
        self, t: np.ndarray, y: np.ndarray, *, uniform_dt: float | None, y_checked: bool = False
    ) -> None:
        n = t.size
        if n == 0:
            return
        if self._grid is not None:
            raise ConfigError("an accumulator holding a whole record takes no more chunks.")
        if self._t_last is not None and not t[0] > self._t_last:
            check_increasing(t[:1], previous=self._t_last)
        if not self._ready:
            self._plan(t, y, uniform_dt, y_checked)
        if self._explicit:
            check_increasing(t, previous=self._t_last)
            check_finite("y", y)
            yc = y - self._y0
            self._records.append((t.copy(), yc))
            self._sum_y2 += float(yc @ yc)
        else:
            g0f = (float(t[0]) - self._t0) / self._dt
            g0 = round(g0f)
            on_grid = False
            # the rounding of a time stamp grows with |t|: a later chunk's own tolerance (with
            # the first chunk's, its stamps 10⁷ samples on were all "off the grid" by 1e-13 s)
            tol = max(
                self._tol, min(0.01 * self._dt, grid_tolerance(self._dt, self._t0, float(t[-1])))
            )
            if g0 >= 0 and abs(g0f - g0) * self._dt <= tol:
                if uniform_dt is not None and g0 == 0 and n > 1:
                    on_grid = abs(uniform_dt - self._dt) * (n - 1) <= tol
                if not on_grid:
                    dev = max_grid_deviation(t, self._t0, self._dt, g0)
                    on_grid = dev <= tol
            if on_grid:
                s2 = self._add_uniform(y, g0)
            else:
                check_increasing(t, previous=self._t_last)
                s2 = self._add_generic(t, y)
            if not math.isfinite(s2):
                check_finite("y", y)
                raise CaptureError(SQUARES_OVERFLOW)
            self._sum_y2 += s2
        if self._n == 0:
            self._t_first = float(t[0])
        self._n += n
        self._t_last = float(t[-1])

    def _hold_grid(self, t: np.ndarray, y: np.ndarray, dt: float) -> None:
        """Take a whole record on the uniform grid ``t[0] + i·dt`` (``y`` finite) by reference, no
        moments: the sums at each trial frequency come from the samples
        (:func:`~rotacal.signal._blocks_grid.grid_sums`). For a one-shot fit of a fast signal,
        whose blocks would hold fewer samples than moments; nothing can be added after it."""
        if self._n or t.size < 2:
            raise ConfigError("_hold_grid takes one whole record of ≥ 2 samples, nothing else.")
        self._ready = True
        self._grid = (t, y)
        self._t0 = self._t_first = float(t[0])
        self._t_last = float(t[-1])
        self._dt = dt
        self._y0 = float(np.mean(y[: min(y.size, 1 << 16)]))
        self._sum_y2 = centred_square_sum(y, self._y0)
        self._n = t.size

    def _plan(
        self, t: np.ndarray, y: np.ndarray, uniform_dt: float | None, y_checked: bool
    ) -> None:
        n = t.size
        if n < 2:
            raise CaptureError(
                "the first chunk must hold at least 2 samples to set the time grid; "
                "merge it with the next chunk."
            )
        if uniform_dt is not None:
            dt = uniform_dt
        else:
            check_increasing(t)
            dt = (float(t[-1]) - float(t[0])) / (n - 1)
        if not y_checked:
            check_finite("y", y)
        if self._block_req is not None:
            m = self._block_req
        else:
            f = self._f_hint
            if f is None:
                try:
                    f = estimate_frequency_unchecked(t, y)
                except CaptureError as exc:
                    reason = str(exc).split(":")[0].rstrip(".")
                    raise CaptureError(
                        f"could not estimate the frequency from the first chunk ({reason}); "
                        "pass frequency_hz= to HarmonicFitAccumulator."
                    ) from None
            m = block_length(f, self._h_plan, dt, self._k)
        self._ready = True
        self._t0 = float(t[0])
        self._dt = dt
        self._y0 = float(np.mean(y[: min(n, 1 << 16)]))
        self._tol = min(0.01 * dt, grid_tolerance(dt, float(t[0]), float(t[-1])))
        self._explicit = m == 1
        self._m = m
        self._tb = m * dt
        self._tg = self._t0 - 0.5 * dt
        if not self._explicit:
            u = (2.0 * np.arange(m) + 1.0) / m - 1.0
            self._v = np.vander(u, self._k + 2, increasing=True)
            self._cumv = np.vstack([np.zeros(self._k + 2), np.cumsum(self._v, axis=0)])

    def _add_uniform(self, y: np.ndarray, g0: int) -> float:
        m, v, y0 = self._m, self._v, self._y0
        n = y.size
        # (j, P or None for full blocks, Q) of the chunk's blocks, stored once all are finite
        parts: list[tuple[np.ndarray, np.ndarray | None, np.ndarray]] = []
        s2 = 0.0
        i = 0
        r0 = g0 % m
        if r0:
            i1 = min(n, m - r0)
            seg = y[:i1] - y0
            parts.append(
                (
                    np.array([g0 // m], dtype=np.int64),
                    (self._cumv[r0 + i1] - self._cumv[r0])[None, :],
                    (seg @ v[r0 : r0 + i1])[None, :],
                )
            )
            s2 += float(seg @ seg)
            i = i1
        nfull = (n - i) // m
        if nfull:
            jstart = (g0 + i) // m
            q = np.empty((nfull, v.shape[1]))
            if use_numba(nfull * m):
                from rotacal.signal._blocks_jit import block_moments

                s2 += block_moments(y[i : i + nfull * m], y0, v, q)
            else:
                for b in range(0, nfull, _SUB_BLOCKS):
                    e = min(nfull, b + _SUB_BLOCKS)
                    blk = y[i + b * m : i + e * m].reshape(e - b, m) - y0
                    q[b:e] = blk @ v
                    flat = blk.reshape(-1)
                    s2 += float(flat @ flat)
            parts.append((np.arange(jstart, jstart + nfull, dtype=np.int64), None, q))
            i += nfull * m
        if i < n:
            rest = n - i
            seg = y[i:] - y0
            parts.append(
                (
                    np.array([(g0 + i) // m], dtype=np.int64),
                    self._cumv[rest][None, :],
                    (seg @ v[:rest])[None, :],
                )
            )
            s2 += float(seg @ seg)
        if not all(np.isfinite(part[2]).all() for part in parts):
            return math.nan
        for part in parts:
            self._store.append(*part)
        return s2

    def _add_generic(self, t: np.ndarray, y: np.ndarray) -> float:
        kk = self._k + 2
        s2 = 0.0
        for s in range(0, t.size, _SUB_SAMPLES):
            e = min(t.size, s + _SUB_SAMPLES)
            x = (t[s:e] - self._tg) / self._tb
            j = np.floor(x)
            u = 2.0 * (x - j) - 1.0
            yc = y[s:e] - self._y0
            starts = np.concatenate([[0], np.flatnonzero(j[1:] != j[:-1]) + 1])
            p = np.empty((starts.size, kk))
            q = np.empty((starts.size, kk))
            pw = np.ones_like(u)
            for k in range(kk):
                p[:, k] = np.add.reduceat(pw, starts)
                q[:, k] = np.add.reduceat(yc * pw, starts)
                if k + 1 < kk:
                    pw *= u
            if not np.isfinite(q).all():
                return math.nan
            s2 += float(yc @ yc)
            self._store.append(j[starts].astype(np.int64), p, q)
        return s2

    def _block_means(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean time (s) and mean y of every block, the parts of a cut block merged."""
        p_full = self._cumv[self._m]
        j_l, p_l, q_l = [], [], []
        for j, p, q in self._store.records():
            j_l.append(j)
            p_l.append(np.broadcast_to(p_full[:2], (j.size, 2)) if p is None else p[:, :2])
            q_l.append(q[:, 0])
        jj = np.concatenate(j_l)
        pp = np.concatenate(p_l)
        qq = np.concatenate(q_l)
        starts = np.concatenate([[0], np.flatnonzero(jj[1:] != jj[:-1]) + 1])
        if starts.size < jj.size:
            jj = jj[starts]
            pp = np.add.reduceat(pp, starts, axis=0)
            qq = np.add.reduceat(qq, starts)
        half = 0.5 * self._tb
        return self._tg + (jj + 0.5) * self._tb + half * pp[:, 1] / pp[:, 0], qq / pp[:, 0]

    # ------------------------------------------------------------------ fitting
    def estimate_frequency(self) -> float:
        """Fundamental frequency (Hz) estimated from the block means (FFT + single-sine LS)."""
        if self._n == 0:
            raise CaptureError("no samples were added to the HarmonicFitAccumulator.")
        if self._grid is not None:
            return estimate_frequency_unchecked(*self._grid)
        if self._explicit:
            return estimate_frequency_unchecked(*self._samples())
        return estimate_frequency_unchecked(*self._block_means())

    def _samples(self) -> tuple[np.ndarray, np.ndarray]:
        """Every sample kept by an explicit accumulator: t and y − y0."""
        return (
            np.concatenate([r[0] for r in self._records]),
            np.concatenate([r[1] for r in self._records]),
        )

    def _sums_fn(self, nh: int, t_ref: float) -> Any:
        kmax_s = 2 * nh
        if self._grid is not None:
            return grid_sums(self._grid[1], self._y0, self._t0 - t_ref, self._dt, nh)
        if self._explicit:
            tt, yy = self._samples()

            def sums_explicit(
                omega: float, deriv: bool, y_deriv: bool = True
            ) -> tuple[np.ndarray, np.ndarray]:
                np_ = 3 if deriv else 1
                s = np.zeros((np_, kmax_s + 1), dtype=np.complex128)
                yv = np.zeros((2 if deriv and y_deriv else 1, nh + 1), dtype=np.complex128)
                for r in range(0, tt.size, SUM_ROWS):
                    d = tt[r : r + SUM_ROWS] - t_ref
                    ycs = yy[r : r + SUM_ROWS]
                    e = unit_powers(np.exp(1j * omega * d), kmax_s)
                    s[0] += e.sum(axis=0)
                    yv[0] += ycs @ e[:, : nh + 1]
                    if deriv:
                        de = d @ e
                        s[1] += de
                        s[2] += (d * d) @ e
                        if yv.shape[0] == 2:
                            yv[1] += (ycs * d) @ e[:, : nh + 1]
                return s, yv

            return sums_explicit
        p_full = self._cumv[self._m]

        def group_sums(group: tuple[np.ndarray, np.ndarray | None, np.ndarray]) -> SumsFn:
            return block_sums(group, p_full, self._tg - t_ref, self._tb, nh, self._k, self._m)

        # in memory: each group's sums prepared once; spilled: read back at each frequency
        held = [] if self._store.spilled else [group_sums(g) for g in self._store.groups(p_full)]

        def sums(omega: float, deriv: bool, y_deriv: bool = True) -> tuple[np.ndarray, np.ndarray]:
            # the sums are linear in the moments: the groups' sums add
            fns = held if not self._store.spilled else map(group_sums, self._store.groups(p_full))
            s_tot = y_tot = None
            for fn in fns:
                s, yv = fn(omega, deriv, y_deriv)
                s_tot = s if s_tot is None else s_tot + s
                y_tot = yv if y_tot is None else y_tot + yv
            assert s_tot is not None and y_tot is not None
            return s_tot, y_tot

        return sums

    def fit(
        self,
        frequency_hz: float | None = None,
        harmonics: int | None = None,
        refine_frequency: bool = True,
        *,
        max_iter: int = 50,
        rtol: float = 1e-12,
        drift: bool = False,
        drift_check: bool = False,
        _samples: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> SineFit:
        """Fit ``C + Σ_h a_h cos(2πhf(t−t_ref)) + b_h sin(...)`` to every sample added.

        Parameters
        ----------
        frequency_hz : float, optional
            Fundamental (Hz): the start value when ``refine_frequency``, else the fixed value.
            Estimated from the block means when omitted.
        harmonics : int, optional
            Number of harmonics H (default: the value given to the constructor).
        refine_frequency : bool
            Fit f as well (variable-projection Gauss–Newton).
        max_iter, rtol : iteration limit and relative step size (of f) that ends it.
        drift : bool
            Fit a linear term ``D·(t − t_ref)`` beside the harmonics (see :func:`fit_harmonics`);
            the block moments hold what it needs, so the chunks are added as without it.
        drift_check : bool
            Without ``drift``: refit with the drift term at the final frequency as well
            (``SineFit.drift_check``), at the cost of one more solve of the normal equations.
        _samples : (t, y), private
            Every sample added, when the caller still holds them: a residual sum of squares too
            small for the normal equations to resolve (a noise-free record) is then summed from
            the samples, so the fit's uncertainties are not rounded to 0.

        Returns
        -------
        SineFit
            Amplitudes and offset in the unit of y, frequency in Hz.

        References
        ----------
        IEEE Std 1057-2017, §4.1.3 (three-, four-parameter and multi-harmonic sine fits);
        Feng et al. 2023, Sensors 23:4876, eq. (9).
        """
        nh = self._h_plan if harmonics is None else check_harmonics(harmonics)
        if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)):
            raise ConfigError(f"max_iter must be an integer ≥ 1; got {max_iter!r}.")
        if max_iter < 1:
            raise ConfigError(f"max_iter must be an integer ≥ 1; got {max_iter}.")
        if not (isinstance(rtol, (int, float)) and math.isfinite(rtol) and rtol > 0):
            raise ConfigError(f"rtol must be a positive number; got {rtol!r}.")
        if self._n == 0 or self._t_last is None:
            raise CaptureError("no samples were added to the HarmonicFitAccumulator.")
        n_par = 2 * nh + 1 + (1 if refine_frequency else 0) + (1 if drift else 0)
        span = self._t_last - self._t_first
        if self._n < n_par + 1 or not span > 0:
            # too few samples: the message names the harmonics; a zero span: one period checked
            nh_named = nh if self._n < n_par + 1 else 1
            check_record(self._n, max(span, 1e-300), 1.0 / max(span, 1e-300), nh_named, n_par)
        f0 = self.estimate_frequency() if frequency_hz is None else check_frequency(frequency_hz)
        check_record(self._n, span, f0, nh, n_par)
        t_ref = 0.5 * (self._t_first + self._t_last)
        sol = solve_normal(
            self._sums_fn(nh, t_ref),
            self._sum_y2,
            self._n,
            f0,
            nh,
            refine=refine_frequency,
            max_iter=int(max_iter),
            rtol=float(rtol),
            drift=bool(drift),
            drift_check=bool(drift_check),
        )
        rss = sol.rss
        rss_d = sol.check[1] if sol.check is not None else 0.0
        if _samples is not None:
            rss, rss_d = self._summed_rss(sol, nh, drift, t_ref, _samples)
        check = None
        if sol.check is not None:
            p_d, _, inv_d = sol.check
            check = build_drift_check(
                params=p_d,
                offset=self._y0 + float(p_d[0]),
                rss=rss_d,
                n_samples=self._n,
                cov_unit=inv_d,
            )
        return build_sine_fit(
            frequency_hz=sol.frequency_hz,
            offset=self._y0 + float(sol.params[0]),
            cos_coefs=sol.params[1 : nh + 1],
            sin_coefs=sol.params[nh + 1 : 2 * nh + 1],
            t_ref_s=t_ref,
            rss=rss,
            n_samples=self._n,
            iterations=sol.iterations,
            cov_unit=sol.cov_unit,
            refined=refine_frequency,
            drift=float(sol.params[-1]) if drift else None,
            drift_check=check,
        )

    def _summed_rss(
        self,
        sol: NormalFit,
        nh: int,
        drift: bool,
        t_ref: float,
        samples: tuple[np.ndarray, np.ndarray],
    ) -> tuple[float, float]:
        """The RSS of the fit and of its drift check, each summed from the samples where the
        normal equations cannot resolve it (``yᵀy − bᵀp`` is rounding), else as they give it.

        Where both must be summed, one pass gives the fit's ``Σ r²`` and ``Σ r·τ``, and the
        check's RSS follows without a second pass: adding the column τ to a least-squares fit
        lowers its RSS by ``(τᵀr)²·[(ΦᵀΦ)⁻¹]_DD`` (Φ the check's columns, D the last; the
        partitioned inverse, e.g. Seber & Lee 2003, *Linear Regression Analysis*, §3.7) — unless
        that removes more than half of the RSS, where the check's own residual is summed.
        """
        rss = sol.rss
        rss_d = sol.check[1] if sol.check is not None else 0.0
        unresolved = _RSS_ROUNDING * self._sum_y2
        check_summed = sol.check is not None and rss_d <= unresolved
        t_s, y_s = samples
        if rss <= unresolved:
            fit_model = self._model(sol.params, nh, drift)
            rss, r_tau = residual_tau_sums(t_s, y_s, t_ref, sol.frequency_hz, fit_model)
            if check_summed:
                assert sol.check is not None
                lowered = r_tau * r_tau * float(sol.check[2][-1, -1])
                if 0.0 <= lowered <= 0.5 * rss:
                    return rss, rss - lowered
        if check_summed:
            assert sol.check is not None
            check_model = self._model(sol.check[0], nh, True)
            rss_d = residual_sums(t_s, y_s, t_ref, sol.frequency_hz, [check_model])[0]
        return rss, rss_d

    def _model(
        self, params: np.ndarray, nh: int, drift: bool
    ) -> tuple[float, np.ndarray, np.ndarray, float]:
        """``(const, a, b, D)`` of :func:`residual_sums` for parameters
        ``[C, a_1..a_H, b_1..b_H(, D)]`` relative to the accumulator's ``y0``."""
        return (
            self._y0 + float(params[0]),
            params[1 : nh + 1],
            params[nh + 1 : 2 * nh + 1],
            float(params[2 * nh + 1]) if drift else 0.0,
        )
