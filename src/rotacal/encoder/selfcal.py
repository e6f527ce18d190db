"""Self-calibration of a multi-head rotary encoder by the equal-division-averaged method (Kokuyama et al. 2015).

n read heads sit at equal intervals around one scale of m lines. Head i reads the same scale
deviation a(k) as head 0, shifted by m·i/n lines: a_i(k) = a(k + m·i/n) (Kokuyama et al., §3;
Masuda & Kajitani 1993; Watanabe et al. 2005). Comparing every head with head 0 at the same
instant gives, for each head-0 pulse j, the angle difference

    D_i(j) = a(j + s_i) − a(j) + c_i,        s_i = round(i·m/n),

with c_i the head's small placement error (a constant). Averaging the n shifted copies cancels every
Fourier order of a(k) except the multiples of n, which no arrangement of n equally spaced heads can
see — the equal-division-averaged (EDA) method.

rotacal solves the same equations per Fourier order as a generalised least-squares fit that takes
into account that every difference shares head 0's noise: for equally spaced heads it reduces
exactly to the EDA average of the shifted copies ("each head's difference curve, shifted back by its
head's offset, averaged over all heads"), and it also honours shifts s_i that are not exactly i·m/n
(m not divisible by n). Orders where the heads give no information (the multiples of n for equal
spacing) are set to zero and listed.

Heads are compared in time, not by pulse index: the angle between head 0's pulse j and the nearest
pulse of head i is their time difference times the local rate (estimated from the head-averaged
pulse times, in which the deviation cancels), so late-starting heads and rate fluctuations do not
bias the curve. The deviation is the average over every whole revolution the heads share, and the
repeatability is each revolution's curve minus that average (Kokuyama et al.'s Figure 5).

Uncertainty (GUM, JCGM 100; Monte Carlo, JCGM 101). The estimator is circulant — the same linear
fit per Fourier order — so its noise has the same variance at every line: the standard uncertainty
of each point is the revolutions' spread pooled over the lines (Type A; ν from the spread of every
detectable order, Welch–Satterthwaite), plus, when the lab states it, the orders no n-head
arrangement can see (``encoder.undetectable_harmonics_arcsec``, Type B). The peak-to-peak and rms
of the curve are max/rms-type: noise biases them upward, so their budgets
(:mod:`rotacal.uncertainty.summaries`) state the plain value, the noise's bias beside it, and a
95 % interval for the true value (closed form for the rms, Monte Carlo for the peak-to-peak), the
noise drawn with the spectrum the revolutions show.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import fft as sp_fft
from scipy.signal import find_peaks

from rotacal.encoder.plausibility import selfcal_warnings
from rotacal.encoder.pulses import (
    check_heads_not_copies,
    check_pulse_times,
    check_pulses_per_rev,
    head_columns,
    pair_heads,
)
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.uncertainty import (
    Input,
    InstrumentSpecs,
    UncertaintyBudget,
    coverage_factor,
    propagate,
    uncertainty_keys,
)
from rotacal.uncertainty.specs import TYPE_A_ONLY_NOTE, spec_input
from rotacal.uncertainty.summaries import (
    COVERAGE,
    CirculantError,
    ErrorProcess,
    drop_large_dof_notes,
    mc_budget,
    rms_budget,
)

__all__ = [
    "UNDETECTABLE_SPEC",
    "DeviationNoise",
    "SelfCalibration",
    "head_shifts",
    "noise_gain",
    "self_calibrate",
    "undetectable_input",
    "undetectable_orders",
]

FloatArray = NDArray[np.float64]

#: Half-width (pulses) of the window that gives the local rate used to turn delays into angles.
RATE_WINDOW = 32
#: Information (relative to n, what equally spaced heads give every detectable order) below which
#: a Fourier order counts as undetectable: its noise would be amplified more than tenfold.
_UNDETECTABLE_TOL = 1e-2
#: Correlation thresholds of the pulses-per-revolution check (see _check_period).
_PERIODIC = 0.8
#: Specification of the deviation at the orders the heads cannot see.
UNDETECTABLE_SPEC = "encoder.undetectable_harmonics_arcsec"
#: Half-width (orders) of the moving average that smooths the noise spectrum of the curve.
_SPECTRUM_SMOOTH = 8


def undetectable_input(specs: InstrumentSpecs | None) -> tuple[Input | None, str | None]:
    """The budget row of ``encoder.undetectable_harmonics_arcsec`` and, when its stated mean is
    not 0, the note on how it is used; (None, None) when it is not stated.

    The specification is the rms of the scale's deviation at the orders no head arrangement sees.
    Their phases are unknown, so a stated mean cannot be a correction of the curve: the rms used
    is √(mean² + u²), the root mean square of the stated distribution (GUM §3.2.4 asks to correct
    for a known systematic effect; here the known part raises the rms the truth holds).
    """
    inp = spec_input(
        specs,
        UNDETECTABLE_SPEC,
        name="orders no head arrangement sees (multiples of n)",
        unit="arcsec",
    )
    if inp is None or inp.value == 0.0:
        return inp, None
    rms = math.hypot(inp.value, inp.u)
    note = (
        f"{UNDETECTABLE_SPEC} is stated with mean {inp.value:g} arcsec: the orders' phases are "
        f"unknown, so it is not a correction of the curve; their rms is taken as "
        f"√(mean² + u²) = {rms:.3g} arcsec (the row shows the stated mean and u)."
    )
    return dataclasses.replace(inp, u=rms, description=f"{inp.description}; rms {rms:.3g}"), note


def _order_weights(m: int) -> FloatArray:
    """Weight of each rfft order in a sum of squares over the lines (Parseval): 2, 1 at 0, m/2."""
    w = np.full(m // 2 + 1, 2.0)
    w[0] = 1.0
    if m % 2 == 0:
        w[-1] = 1.0
    return w


@dataclasses.dataclass(frozen=True)
class DeviationNoise:
    """What the error of a self-calibrated deviation curve may be, order by order.

    The curve's estimator is the same linear fit at every Fourier order, so its error is a
    stationary random curve: Gaussian rfft coefficients, independent between orders, whose
    variances say everything. The error at the orders no head arrangement can see is a second,
    independent curve with a stated rms (Type B).

    Attributes
    ----------
    pulses_per_rev : int
        m.
    variance : ndarray, shape (m//2 + 1,), arcsec²
        E|ε_q|² of the rfft coefficient (numpy's unnormalised rfft) of the measured curve's error
        at order q; 0 at the undetectable orders and at order 0 (the curve has zero mean).
    undetectable : ndarray of bool, shape (m//2 + 1,)
        Orders the heads cannot see (their part of the true deviation is not in the curve).
    undetectable_u : float, arcsec
        Standard deviation, at any line, of the true deviation's part at those orders (0: not
        stated).
    """

    pulses_per_rev: int
    variance: FloatArray
    undetectable: NDArray[np.bool_]
    undetectable_u: float = 0.0

    @property
    def point_u(self) -> float:
        """Standard deviation (arcsec) of the detectable error at any line: √(Σ w_q v_q)/m."""
        m = self.pulses_per_rev
        return math.sqrt(float(np.sum(_order_weights(m) * self.variance))) / m

    @classmethod
    def white(
        cls, pulses_per_rev: int, point_u: float, undetectable_u: float = 0.0
    ) -> DeviationNoise:
        """A white error curve of standard deviation ``point_u`` (arcsec) at every line (all
        orders but 0), when only the per-point uncertainty is known (a selfcal JSON)."""
        m = pulses_per_rev
        w = _order_weights(m)
        var = np.full(m // 2 + 1, 1.0)
        var[0] = 0.0
        var *= (point_u * m) ** 2 / float(np.sum(w * var))
        return cls(m, var, np.zeros(m // 2 + 1, dtype=bool), float(undetectable_u))

    def undetectable_variance(self) -> FloatArray:
        """E|c_q|² of a curve at the undetectable orders with rms ``undetectable_u`` (white
        across them; every order but 0 when none is marked)."""
        m = self.pulses_per_rev
        mask = self.undetectable.copy()
        mask[0] = False
        if not mask.any():
            mask = np.ones_like(mask)
            mask[0] = False
        w = _order_weights(m)
        return np.where(mask, (self.undetectable_u * m) ** 2 / float(np.sum(w[mask])), 0.0)

    def autocov(self, *, undetectable: bool = False) -> FloatArray:
        """Autocovariance c(k), k = 0 … m − 1 (arcsec²), of the curve's error along the lines
        (``undetectable``: of the true deviation's part at the undetectable orders)."""
        var = self.undetectable_variance() if undetectable else self.variance
        return np.fft.irfft(var, self.pulses_per_rev) / self.pulses_per_rev


@dataclasses.dataclass(frozen=True)
class SelfCalibration(Result):
    """Scale deviation of a multi-head encoder by self-calibration (INTERFACE.md ``selfcal``).

    Attributes
    ----------
    deviation_arcsec : ndarray, shape (m,), arcsec
        The scale's deviation; the true rotation from head-0 pulse 0 to head-0 pulse j
        (0 ≤ j < m, counted from the first head-0 pulse in the capture) is
        ``j·360/m + (deviation[j] − deviation[0])/3600`` deg. Zero mean; orders that are
        multiples of n are zero (undetectable).
    heads, pulses_per_rev : int
    deviation_pp_arcsec, deviation_rms_arcsec : float, arcsec
        Plain peak-to-peak and rms of ``deviation_arcsec`` (also the budgets' values).
    undetectable_harmonics_note : str
    undetectable_orders : list of int
        Fourier orders (per revolution, 1 … m/2) the heads cannot see.
    revolutions_used : int
        Whole revolutions averaged.
    repeatability_rms_arcsec, repeatability_pp_arcsec : float or None, arcsec
        Spread of the single-revolution curves about their mean (None with one revolution).
    deviation_u_arcsec : float or None, arcsec
        Standard uncertainty of every point of the curve (the same at every line): the
        revolutions' spread pooled over the lines (rms over the lines of std/√R), combined with
        the stated ``encoder.undetectable_harmonics_arcsec`` when given. The same number as each
        element of the JSON ``deviation_arcsec_u``. None with one revolution and no
        specification (with one revolution and the specification: the specification alone).
    deviation_dof : float or None
        Effective degrees of freedom of ``deviation_u_arcsec`` (Welch–Satterthwaite).
    deviation_pp_arcsec_bias, deviation_rms_arcsec_bias : float or None, arcsec
        How much the curve's noise (Type A, from the revolutions) raises the plain peak-to-peak
        and rms; None with one revolution (the noise is then unknown).
    deviation_pp_arcsec_bias_corrected, deviation_rms_arcsec_bias_corrected : float or None
        The plain values less that bias (arcsec). The 95 % interval for the true value (which
        also holds the undetectable orders when their specification is stated) is the JSON
        ``deviation_pp_arcsec_interval`` / ``deviation_rms_arcsec_interval``.
    closure_residual_rms_arcsec : float, arcsec
        rms of what the fitted curve leaves unexplained in the head differences (noise, rate
        changes within a pitch, head misnumbering).
    head_offsets_arcsec : list of float, arcsec
        Each head's placement against its nominal i·360/n, modulo one pitch.
    head_offsets_arcsec_u : list of float or None, arcsec
        Standard uncertainty of each placement (Type A): the spread over the whole revolutions of
        that revolution's mean head difference, s/√R, as the curve's u is made from the
        revolutions; 0 for head 0 (the reference, by definition). None with one revolution.
    head_offsets_dof : float or None
        Degrees of freedom of ``head_offsets_arcsec_u``: R − 1.
    harmonic_amplitudes_arcsec : list of float, arcsec
        Amplitude of orders 1 … min(m/2, 100) of the deviation.
    rotation : str
        ``"forward"`` (head i is i·360/n ahead in the sense of rotation) or ``"reverse"``.
    head_line_shifts : list of int
        The scale line each head sees at the moment head 0 sees line 0 (modulo m).
    first_pulse_time_s, last_pulse_time_s : float, s
        Times of head 0's first (index 0 of ``deviation_arcsec``) and last pulse.
    head0_pulses : int
        Pulses of head 0 in the capture (with the two times: which capture this curve indexes).
    notes : list of str

    ``to_dict()`` adds the uncertainty keys: ``deviation_arcsec_u`` and ``deviation_arcsec_U``
    (arrays of m values, arcsec), ``deviation_pp_arcsec_u``/``_U`` and
    ``deviation_rms_arcsec_u``/``_U``/``_interval`` (arcsec; u the standard deviation of the
    summary's error, U half the interval's width), ``k`` (per quantity), ``coverage_probability``
    and ``uncertainty_budgets``.
    """

    deviation_arcsec: FloatArray
    heads: int
    pulses_per_rev: int
    deviation_pp_arcsec: float
    deviation_rms_arcsec: float
    undetectable_harmonics_note: str
    undetectable_orders: list[int]
    revolutions_used: int
    repeatability_rms_arcsec: float | None
    repeatability_pp_arcsec: float | None
    deviation_u_arcsec: float | None
    deviation_dof: float | None
    deviation_pp_arcsec_bias: float | None
    deviation_pp_arcsec_bias_corrected: float | None
    deviation_rms_arcsec_bias: float | None
    deviation_rms_arcsec_bias_corrected: float | None
    closure_residual_rms_arcsec: float
    head_offsets_arcsec: list[float]
    harmonic_amplitudes_arcsec: list[float]
    rotation: str
    head_line_shifts: list[int]
    first_pulse_time_s: float
    last_pulse_time_s: float
    head0_pulses: int
    notes: list[str]
    _per_revolution_arcsec: FloatArray = dataclasses.field(repr=False)
    _spectrum_arcsec: FloatArray = dataclasses.field(repr=False)
    head_offsets_arcsec_u: list[float] | None = None
    head_offsets_dof: float | None = None
    _noise: DeviationNoise | None = dataclasses.field(repr=False, default=None)
    _point_budget: UncertaintyBudget | None = dataclasses.field(repr=False, default=None)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(repr=False, default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out.update(uncertainty_keys(self._budgets))
        pb = self._point_budget
        if pb is None:
            out["deviation_arcsec_u"] = out["deviation_arcsec_U"] = None
        else:
            m = self.pulses_per_rev
            out["deviation_arcsec_u"] = [pb.u] * m
            out["deviation_arcsec_U"] = [pb.U] * m
            out["k"]["deviation_arcsec"] = pb.k
            out["uncertainty_budgets"]["deviation_arcsec"] = pb.to_dict()
            if out["coverage_probability"] is None:
                out["coverage_probability"] = pb.p
        out["head_offsets_arcsec_U"] = self.head_offsets_arcsec_U
        if self.head_offsets_arcsec_U is not None:
            out["k"]["head_offsets_arcsec"] = self.head_offsets_k
        return out

    @property
    def head_offsets_k(self) -> float | None:
        """Coverage factor of the placements' U: t_95(R − 1) (GUM G.3.2); None with one revolution."""
        if self.head_offsets_dof is None:
            return None
        return coverage_factor(self.head_offsets_dof, 0.95)

    @property
    def head_offsets_arcsec_U(self) -> list[float] | None:
        """Expanded uncertainty of each head placement (arcsec, p = 95 %), None with one revolution."""
        k = self.head_offsets_k
        if k is None or self.head_offsets_arcsec_u is None:
            return None
        return [k * u for u in self.head_offsets_arcsec_u]

    @property
    def budgets(self) -> dict[str, UncertaintyBudget]:
        """Uncertainty budgets by JSON key (``deviation_pp_arcsec``, ``deviation_rms_arcsec``)."""
        return dict(self._budgets)

    @property
    def point_budget(self) -> UncertaintyBudget | None:
        """The budget of one point of the curve (any line; its ``value`` is 0: the budget's
        inputs are errors), None with one revolution and no specification."""
        return self._point_budget

    @property
    def deviation_arcsec_u(self) -> FloatArray | None:
        """Standard uncertainty of every point of ``deviation_arcsec`` (arcsec), or None."""
        pb = self._point_budget
        return None if pb is None else np.full(self.pulses_per_rev, pb.u)

    @property
    def deviation_arcsec_U(self) -> FloatArray | None:
        """Expanded uncertainty (p = 95 %) of every point of ``deviation_arcsec`` (arcsec)."""
        pb = self._point_budget
        return None if pb is None else np.full(self.pulses_per_rev, pb.U)

    @property
    def per_revolution_arcsec(self) -> FloatArray:
        """Each whole revolution's curve, shape (R, m), indexed like ``deviation_arcsec``."""
        return self._per_revolution_arcsec

    @property
    def repeatability_arcsec(self) -> FloatArray:
        """Each revolution minus the mean of all (Kokuyama et al.'s Figure 5), shape (R, m)."""
        return self._per_revolution_arcsec - self.deviation_arcsec

    @property
    def spectrum_arcsec(self) -> FloatArray:
        """Amplitude (arcsec) of every order 0 … m/2 of the deviation."""
        return self._spectrum_arcsec


def head_shifts(heads: int, pulses_per_rev: int, rotation: str = "forward") -> NDArray[np.int64]:
    """Line shift of each head against head 0: s_i = round(i·m/n) (negated for reverse rotation).

    Heads must sit within half a pitch of their nominal i·360/n positions.
    """
    i = np.arange(heads)
    s = np.rint(i * pulses_per_rev / heads).astype(np.int64)
    return s if rotation == "forward" else (-s) % pulses_per_rev


def _information(shifts: NDArray[np.int64], m: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-order GLS weights g_i = exp(2πi q s_i/m) − 1 (heads 1 … n−1) and the information."""
    q = np.arange(m // 2 + 1)
    g = np.exp(2j * np.pi * np.outer(shifts[1:], q) / m) - 1.0
    n = shifts.size
    info = np.sum(np.abs(g) ** 2, axis=0) - np.abs(np.sum(g, axis=0)) ** 2 / n
    return g, info


def undetectable_orders(
    heads: int, pulses_per_rev: int, shifts: NDArray[np.int64] | None = None
) -> list[int]:
    """Fourier orders 1 … m/2 of the deviation that the heads cannot measure.

    For n equally spaced heads on m lines, m divisible by n, these are the multiples of n (seed
    004, §3: "the n-th and its multiple Fourier components … cannot be extracted in principle").
    With other line shifts (``shifts``, one per head, 0 for head 0) an order counts as undetectable
    when the heads carry less than 1 % of the usual information on it (noise gain above 10).
    """
    if shifts is None:
        shifts = head_shifts(heads, pulses_per_rev)
    _, info = _information(shifts, pulses_per_rev)
    bad = info <= _UNDETECTABLE_TOL * heads
    bad[0] = False
    return [int(q) for q in np.flatnonzero(bad)]


def noise_gain(shifts: ArrayLike, pulses_per_rev: int, head: int) -> NDArray[np.complex128]:
    """How one head's own angle noise enters the self-calibrated curve, order by order.

    The fit per order is â(q) = [Σ g_i*·D_i − (Σ g_i*)(Σ D_i)/n]/I(q); head 0's noise N₀ enters
    every D_i with −1, head k's N_k enters D_k with +1 at the head-0 pulse it pairs with, i.e. at
    the line it reads shifted by s_k. So a head's noise at the line it reads appears in the curve
    at that line with the gain κ(q) = −Σ g_i*/(n·I) (head 0) or (g_k* − Σ g_i*/n)/I·e^(2πiqs_k/m)
    (head k) — 1/n at every detectable order for equally spaced heads — averaged over the
    revolutions. A rate from the same head, compensated with this curve, therefore carries that
    head's timing noise twice, partly cancelling.

    Parameters
    ----------
    shifts : array_like of int
        The heads' line shifts s_i (``SelfCalibration.head_line_shifts``).
    pulses_per_rev : int
        m.
    head : int
        The head whose noise is followed.

    Returns
    -------
    ndarray of complex, shape (m//2 + 1,)
        κ(q); 0 at order 0 and at the undetectable orders (set to zero by the fit).

    References
    ----------
    Kokuyama et al. (2015) §3; the fit of :func:`self_calibrate` (generalised least squares
    per order, noise shared through head 0).
    """
    s = np.asarray(shifts, dtype=np.int64)
    m = int(pulses_per_rev)
    g, info = _information(s, m)
    n = s.size
    ok = info > _UNDETECTABLE_TOL * n
    ok[0] = False
    total = np.conj(np.sum(g, axis=0))
    if head == 0:
        num = -total / n
    else:
        q = np.arange(m // 2 + 1)
        num = (np.conj(g[head - 1]) - total / n) * np.exp(2j * np.pi * q * s[head] / m)
    out = np.zeros(m // 2 + 1, dtype=np.complex128)
    out[ok] = num[ok] / info[ok]
    return out


def _gls(diff_spec: np.ndarray, shifts: NDArray[np.int64], m: int) -> tuple[np.ndarray, np.ndarray]:
    """Solve D̂_i(q) = a(q)·g_i(q) for a(q) per order, noise shared through head 0.

    The head differences D_i = e_i − e_0 have covariance σ²(I + 11ᵀ); its inverse is
    (I − 11ᵀ/n)/σ², which gives a(q) = [Σ g_i* D_i − (Σ g_i*)(Σ D_i)/n] / [Σ|g_i|² − |Σ g_i|²/n].
    """
    g, info = _information(shifts, m)
    n = shifts.size
    gc = np.conj(g)
    num = (
        np.einsum("iq,...iq->...q", gc, diff_spec)
        - np.sum(gc, axis=0) * np.sum(diff_spec, axis=-2) / n
    )
    ok = info > _UNDETECTABLE_TOL * n
    a = np.zeros((*diff_spec.shape[:-2], g.shape[1]), dtype=complex)
    a[..., ok] = num[..., ok] / info[ok]
    resid = a[..., None, :] * g
    np.subtract(diff_spec, resid, out=resid)  # in place: one array of the spectra's size less
    return a, resid


def _local_rate_deg_s(mean_times: FloatArray, pitch_deg: float) -> FloatArray:
    """Rate at every paired pulse from the head-averaged times over ±RATE_WINDOW pulses."""
    n = mean_times.size
    w = min(RATE_WINDOW, max(1, (n - 1) // 2))
    rate = np.empty(n)
    inner = slice(w, n - w)
    rate[inner] = 2 * w * pitch_deg / (mean_times[2 * w :] - mean_times[: n - 2 * w])
    rate[:w] = rate[w]
    rate[n - w :] = rate[n - w - 1]
    return rate


def _autocorrelation(x: FloatArray, lags: int) -> FloatArray:
    """Σ_i x_i·x_{i+ℓ} for ℓ = 0 … lags − 1, by a zero-padded FFT of a fast length ≥ 2N.

    The spectrum's power is formed in place: the whole-record FFT is the largest array of a
    long capture, and a power of two ≥ 2N was up to 4N long with a product array beside it.
    """
    size = sp_fft.next_fast_len(2 * x.size, real=True)
    f = sp_fft.rfft(x, size, workers=1)
    power = f.real**2
    power += f.imag**2
    del f
    return np.asarray(sp_fft.irfft(power, size, workers=1)[:lags], dtype=np.float64)


def check_period(signal: FloatArray, m: int, *, coarse: bool = True) -> bool:
    """Refuse a pulses-per-revolution that contradicts the period of the deviation.

    ``signal`` is indexed by head-0 pulse (the head-averaged difference ≈ −a(j), or a single
    head's angle error). A scale's deviation repeats once per revolution, so when the signal is
    strongly periodic its correlation at lag m must be about as high as at its best lag. A
    deviation dominated by order k also repeats at m/k: that alone is no fault, so only a lag m
    that is clearly worse than the best is refused. Records too short to reach lag m are not
    judged here (the closure test of :func:`self_calibrate` covers them). ``coarse=False`` keeps
    only the test of the sharp spike the random graduation errors leave at one revolution: for a
    single head, whose angle error also holds the table's (smooth) rate fluctuation.

    Returns True when the data confirm m (a strong correlation or a graduation spike at lag m),
    False when they cannot (a record too short to reach lag m, a deviation too weak).
    """
    x = signal - signal.mean()
    n = x.size
    # lags from m/8 up to what leaves a quarter of the record (or of m) overlapping
    lo, hi = max(2, m // 8), n - max(m // 4, n // 4)
    if not lo <= m <= hi:
        return False
    acf = _autocorrelation(x, hi + 1)
    c2 = np.cumsum(x**2)
    lags = np.arange(lo, hi + 1)
    # normalise by the energy of both overlapping parts
    head_energy = c2[n - 1 - lags]
    tail_energy = c2[-1] - np.concatenate(([0.0], c2))[lags]
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = acf[lags] / np.sqrt(head_energy * tail_energy)
    corr = np.nan_to_num(corr)
    spike_at_m = _check_fine_period(corr, lags, m)
    best = float(corr.max())
    at_m = float(corr[m - lo])
    if not coarse:
        return spike_at_m
    if best < _PERIODIC or at_m >= best - 0.1:
        return spike_at_m or at_m >= _PERIODIC
    # the shortest lag at a local peak (nearly) as high as the best one: a smooth deviation
    # gives broad peaks, so the flank of a peak must not count
    peaks, _ = find_peaks(corr, height=best - 0.02, prominence=0.1)
    first = int(peaks[0]) if peaks.size else int(np.argmax(corr))
    near = slice(max(0, first - m // 20), first + m // 20 + 1)
    period = int(lags[near][np.argmax(corr[near])])
    raise CaptureError(
        f"the scale's deviation repeats every {period} pulses of head_0, not every {m} "
        f"(correlation {best:.2f} against {at_m:.2f}): check --pulses-per-rev."
    )


def _check_fine_period(corr: FloatArray, lags: NDArray[np.int64], m: int) -> bool:
    """The random graduation errors put a sharp spike on the correlation at exactly one
    revolution (and its multiples); refuse an m whose lag has none while another lag has one.
    Returns True when lag m carries such a spike (m confirmed)."""
    idx = np.arange(1, corr.size - 1)
    spike = corr[idx] - 0.5 * (corr[idx - 1] + corr[idx + 1])
    spread = 1.4826 * float(np.median(np.abs(spike - np.median(spike))))
    if spread <= 0:
        return False
    strong = np.flatnonzero(spike > 10 * spread)
    if strong.size == 0:
        return False
    found = int(lags[idx[strong[0]]])  # the shortest lag with a spike: one revolution
    pos = m - int(lags[0]) - 1
    at_m = float(spike[pos]) if 0 <= pos < spike.size else 0.0
    # at m's own lag there must be a spike of the same kind (noise alone reaches ~3 spreads)
    if found != m and at_m < 0.3 * float(spike[strong[0]]):
        raise CaptureError(
            f"the scale's graduation pattern repeats every {found} pulses of head_0, not every "
            f"{m}: check --pulses-per-rev."
        )
    return at_m > 10 * spread


def _data_shifts(
    heads: int, m: int, rotation: str, mean_offsets_arcsec: FloatArray
) -> NDArray[np.int64]:
    """Line shift of each head from the data: the nominal position plus the measured offset.

    The mean angle between head 0's pulse j and head i's paired pulse is s_i·Δθ − h_i, so with h_i
    within half a pitch of its nominal ±i·360/n the line shift is the whole number of pitches in
    (±i·360/n + mean offset). This decides the line even when i·m/n ends in about one half.
    """
    pitch_arcsec = 360.0 / m * 3600.0
    sign = 1.0 if rotation == "forward" else -1.0
    nominal = sign * np.arange(1, heads) * 360.0 / heads * 3600.0
    s = np.rint((nominal + mean_offsets_arcsec) / pitch_arcsec).astype(np.int64) % m
    return np.concatenate(([0], s)).astype(np.int64)


def _parseval_ss(resid: np.ndarray, m: int) -> float:
    """Sum of squares in the sample domain of residual rfft spectra (last axis: orders)."""
    w = np.full(resid.shape[-1], 2.0)
    w[0] = 1.0
    if m % 2 == 0:
        w[-1] = 1.0
    return float(np.sum(w * np.abs(resid) ** 2)) / m


def _one_revolution_closure(diff: FloatArray, m: int, rotation: str) -> float:
    """rms closure residual of the fit on the first m head-0 pulses, taking m as the period."""
    one = diff[:, :m]
    shifts = _data_shifts(one.shape[0] + 1, m, rotation, one.mean(axis=1))
    spec = np.fft.rfft(one - one.mean(axis=1, keepdims=True), axis=-1)
    _, resid = _gls(spec, shifts, m)
    return float(np.sqrt(_parseval_ss(resid, m) / one.size))


def _check_pulses_per_rev_by_closure(diff: FloatArray, m: int, *, near: bool) -> None:
    """Refuse m when another count per revolution explains the head differences far better.

    With three or more heads the model over-determines the deviation, so a wrong m (a mistyped
    count, edges counted twice) leaves a closure residual that a right one does not. Tried: m/4,
    m/3, m/2 (a multiple of the true count repeats with it, so the period tests cannot see it),
    and, when ``near``, also m ± 1…3, 2m, 3m and 4m (records too short for the period tests).
    """
    n_pulses = diff.shape[1]
    factors = (0.25, 1 / 3, 0.5, 2.0, 3.0, 4.0) if near else (0.25, 1 / 3, 0.5)
    candidates = {round(m * f) for f in factors}
    if near:
        candidates |= {m + d for d in (-3, -2, -1, 1, 2, 3)}
    heads = diff.shape[0] + 1
    candidates = {c for c in candidates if heads <= c <= n_pulses}
    if not candidates:
        return

    # judge every count in the sense that suits it best, whatever the user forced
    def closure(c: int) -> float:
        return min(_one_revolution_closure(diff, c, sense) for sense in ("forward", "reverse"))

    own = closure(m)
    scores = {c: closure(c) for c in sorted(candidates)}
    best = min(scores, key=lambda c: scores[c])
    if scores[best] < 0.5 * own:
        raise CaptureError(
            f"the head differences fit {best} pulses per revolution far better than {m} "
            f"(closure residual {scores[best]:.3g} against {own:.3g} arcsec): check "
            "--pulses-per-rev."
        )


def _smooth_spectrum(var: FloatArray, keep: NDArray[np.bool_]) -> FloatArray:
    """Moving average of ``var`` over ±_SPECTRUM_SMOOTH neighbouring kept orders (others 0)."""
    out = np.zeros_like(var)
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        return out
    vals = var[idx]
    c = np.concatenate(([0.0], np.cumsum(vals)))
    pos = np.arange(idx.size)
    lo = np.maximum(pos - _SPECTRUM_SMOOTH, 0)
    hi = np.minimum(pos + _SPECTRUM_SMOOTH + 1, idx.size)
    out[idx] = (c[hi] - c[lo]) / (hi - lo)
    return out


def _deviation_uncertainty(
    per_rev: FloatArray,
    deviation: FloatArray,
    undetect: list[int],
    specs: InstrumentSpecs | None,
) -> tuple[DeviationNoise | None, UncertaintyBudget | None, dict[str, Any]]:
    """Noise model, per-point budget and the budgets of the peak-to-peak and rms.

    With two or more revolutions the curve's noise comes from their spread (Type A); with one,
    only a stated ``encoder.undetectable_harmonics_arcsec`` can be budgeted (no budget without).

    Returns
    -------
    noise : DeviationNoise or None
    point : UncertaintyBudget or None
    summaries : dict
        ``{"deviation_pp_arcsec": Summary, "deviation_rms_arcsec": Summary}`` (empty without any
        input).

    References
    ----------
    JCGM 100:2008 (GUM) §4.2 (Type A: the mean of R revolutions, s²/R), §4.3 (Type B), G.4
    (Welch–Satterthwaite over the orders); JCGM 101:2008 §7 (Monte Carlo of the peak-to-peak).
    """
    revs, m = per_rev.shape
    w = _order_weights(m)
    und = np.zeros(m // 2 + 1, dtype=bool)
    und[np.asarray(undetect, dtype=np.int64)] = True
    und_input, und_note = undetectable_input(specs)
    u_und = und_input.u if und_input is not None else 0.0
    inputs: list[Input] = []
    notes: list[str] = []
    noise: DeviationNoise | None = None
    nu_a = math.inf
    if revs >= 2:
        resid = np.fft.rfft(per_rev - deviation, axis=-1)
        var = np.sum(np.abs(resid) ** 2, axis=0) / ((revs - 1) * revs)  # of the mean's orders
        keep = ~und
        keep[0] = False
        var = np.where(keep, var, 0.0)
        total = float(np.sum(w * var))
        smooth = _smooth_spectrum(var, keep)
        s_total = float(np.sum(w * smooth))
        if s_total > 0:
            smooth *= total / s_total
        # Welch–Satterthwaite over the orders: each order's variance has 2(R − 1) degrees of
        # freedom (R − 1 for the real Nyquist order), the pooled one their effective number
        nu_q = np.where(w == 2.0, 2.0 * (revs - 1), float(revs - 1))
        den = float(np.sum((w * smooth) ** 2 / nu_q))
        nu_a = (float(np.sum(w * smooth)) ** 2 / den) if den > 0 else math.inf
        noise = DeviationNoise(m, smooth if s_total > 0 else var, und, u_und)
        inputs.append(
            Input(
                name=f"repeatability over {revs} revolutions",
                value=0.0,
                u=math.sqrt(total) / m,
                dof=nu_a,
                distribution="normal",
                unit="arcsec",
                source=f"Type A, the spread of {revs} single-revolution curves pooled over the lines",
                description="normal (per order, from the revolutions' spread)",
            )
        )
    elif und_input is None:
        return None, None, {}
    else:
        notes.append(
            "one whole revolution: the curve's own noise cannot be estimated from the data and is "
            "not in this budget (record several revolutions); only the stated specification is."
        )
    if und_input is not None:
        inputs.append(und_input)
        if und_note:
            notes.append(und_note)
    else:
        notes.append(
            "the orders that are multiples of the number of heads are neither in the curve nor in "
            f"its uncertainty; state {UNDETECTABLE_SPEC} to include them."
        )
    if specs is None:
        notes.append(TYPE_A_ONLY_NOTE)
    gum = propagate(
        lambda *x: float(sum(x)),
        [dataclasses.replace(inp, value=0.0) for inp in inputs],  # errors about their estimates
        p=COVERAGE,
        names_out=["deviation_arcsec (every line)"],
        units_out=["arcsec"],
    )
    point = drop_large_dof_notes(gum.budget(0))
    point = dataclasses.replace(
        point,
        rows=tuple(
            dataclasses.replace(row, value=inp.value)
            for row, inp in zip(point.rows, inputs, strict=True)
        ),
        notes=(
            *point.notes,
            "the fit is the same at every Fourier order, so every line has this uncertainty"
            + (
                f" (ν = {nu_a:.4g} from the spread of every detectable order, Welch–Satterthwaite)."
                if revs >= 2
                else "."
            ),
            *notes,
        ),
    )

    # the curve holds its noise (it biases pp and rms) but lacks the undetectable orders
    sources: list[ErrorProcess] = []
    if noise is not None:
        sources.append(CirculantError(inputs[0], "noise", autocov=noise.autocov()))
    if und_input is not None:
        model = noise or DeviationNoise(m, np.zeros(m // 2 + 1), und, u_und)
        sources.append(
            CirculantError(und_input, "absent", autocov=model.autocov(undetectable=True))
        )
        notes.append(
            f"{UNDETECTABLE_SPEC} is taken as a random curve over the undetectable orders with "
            "the stated rms (white across them)."
        )
    summaries = {
        "deviation_pp_arcsec": mc_budget(
            "deviation_pp_arcsec", "arcsec", deviation, sources, statistic="pp", notes=notes
        ),
        "deviation_rms_arcsec": rms_budget(
            "deviation_rms_arcsec", "arcsec", deviation, sources, notes=notes
        ),
    }
    return noise, point, summaries


def self_calibrate(
    heads: Sequence[ArrayLike] | Mapping[str, ArrayLike],
    *,
    pulses_per_rev: int,
    rotation: Literal["auto", "forward", "reverse"] = "auto",
    specs: InstrumentSpecs | None = None,
) -> SelfCalibration:
    """Scale deviation of an n-head encoder by the equal-division-averaged method.

    Parameters
    ----------
    heads : sequence of array_like, or mapping with ``head_0`` … ``head_{n-1}``, s
        Pulse edge times of each head; head 0 is the reference, the heads equally spaced
        (within half a pitch) and numbered in one sense around the scale. Heads may start and
        stop at different times; only the span all of them cover is compared.
    pulses_per_rev : int
        m, pulses per revolution of one head.
    rotation : {"auto", "forward", "reverse"}
        Whether head i lies i·360/n ahead of head 0 in the sense of rotation ("forward") or
        behind ("reverse"); "auto" takes the one whose model explains the head differences
        better (undecidable with 2 heads: forward).
    specs : InstrumentSpecs, optional
        The lab's instrument specifications (Type B inputs). Used:
        ``encoder.undetectable_harmonics_arcsec`` (the rms, arcsec, of the scale's deviation at
        the orders that are multiples of n; a stated mean enters as √(mean² + u²), see
        :func:`undetectable_input`). A timebase error scales the delays and the rate that turns
        them into angles alike, so it does not enter. None: Type A only.

    Returns
    -------
    SelfCalibration
        With the standard uncertainty of every point (the revolutions' spread, Type A) and the
        budgets of the peak-to-peak (Monte Carlo) and rms (closed form) — plain value, noise
        bias, 95 % interval for the true value — when the heads share two or more whole
        revolutions; with one, from ``encoder.undetectable_harmonics_arcsec`` alone when stated.

    Raises
    ------
    CaptureError
        Fewer than 2 heads, bad pulse trains (see :func:`check_pulse_times`), a head that is a
        (time-shifted) copy of head 0 (:func:`~rotacal.encoder.pulses.check_heads_not_copies`:
        copies carry no information about the scale), heads that cannot be paired, less than one
        whole revolution covered by all heads, a pulses_per_rev that does not match the period of
        the data.

    References
    ----------
    Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration
    facility using self-calibratable rotary encoder", §3: s_i(k) = kΔθ + 360i/n + a_i(k),
    m = 360/Δθ, a_i(k) = a(k + m·i/n); Figures 4–5.
    Masuda T., Kajitani M., "High accuracy calibration system for angular encoders", J. Robotics
    and Mechatronics 5 (1993) — the equal-division-averaged method.
    JCGM 100:2008 (GUM) §4.2, G.4; JCGM 101:2008 §7 (the uncertainty of the curve and its
    summaries).
    """
    m = check_pulses_per_rev(pulses_per_rev)
    if specs is not None and not isinstance(specs, InstrumentSpecs):
        raise ConfigError(
            f"specs must be the InstrumentSpecs of load_specs(...), got {type(specs).__name__}."
        )
    if rotation not in ("auto", "forward", "reverse"):
        raise ConfigError(f"rotation must be 'auto', 'forward' or 'reverse', got {rotation!r}.")
    if isinstance(heads, Mapping):
        trains = head_columns(heads)
    else:
        trains = [np.asarray(h, dtype=np.float64) for h in heads]
    n = len(trains)
    if n < 2:
        raise CaptureError(
            f"self-calibration needs at least 2 heads, the capture has {n}; give head_0 … head_{{n-1}}."
        )
    if m < n:
        raise ConfigError(f"pulses_per_rev ({m}) must be at least the number of heads ({n}).")
    names = [f"head_{i}" for i in range(n)]
    trains = [check_pulse_times(t, name) for t, name in zip(trains, names, strict=True)]
    if trains[0].size - 1 < m:
        raise CaptureError(
            f"head_0 has {trains[0].size} pulses, less than one revolution of {m}: record at least "
            "one whole revolution (or check --pulses-per-rev)."
        )
    check_heads_not_copies(trains, names)
    pairing = pair_heads(trains, names)
    revs = pairing.pulses // m
    if revs < 1:
        raise CaptureError(
            f"all heads together cover only {pairing.pulses} pulses of head_0, less than one "
            f"revolution of {m} ({'; '.join(pairing.notes) or 'the heads overlap too little'})."
        )
    pitch = 360.0 / m
    rate = _local_rate_deg_s(pairing.mean_times_s, pitch)
    angle_diff = pairing.delays_s[1:] * rate * 3600.0  # arcsec, shape (n−1, J)
    # the pairing's per-pulse delays and mean times are not needed past here: drop them
    first_paired, pairing_notes = pairing.first, pairing.notes
    del pairing, rate
    period_checked = check_period(angle_diff.mean(axis=0), m)

    used = angle_diff[:, : revs * m].reshape(n - 1, revs, m).transpose(1, 0, 2)  # (R, n−1, m)
    offsets_mean = used.mean(axis=(0, 2))
    spec = np.fft.rfft(used - used.mean(axis=2, keepdims=True), axis=-1)

    notes = list(pairing_notes)
    candidates = ["forward", "reverse"] if rotation == "auto" else [rotation]
    fits = {}
    for sense in candidates:
        shifts = _data_shifts(n, m, sense, offsets_mean)
        a, resid = _gls(spec, shifts, m)
        fits[sense] = (a, _parseval_ss(resid, m), shifts)
    sense = min(fits, key=lambda k: fits[k][1])
    if rotation == "auto" and n == 2:
        sense = "forward"
    if rotation == "auto" and n > 2:
        other = "reverse" if sense == "forward" else "forward"
        if fits[other][1] < 2.0 * fits[sense][1]:
            notes.append(
                "the sense of rotation against the head numbering is unclear from the data (both "
                f"fit about as well); took '{sense}'. Give rotation= (--rotation) if you know it."
            )
    if not period_checked:
        notes.append(
            f"the data cannot confirm {m} pulses per revolution from their own period (a record "
            "under 1.25 revolutions shared by all heads, or a weak deviation); only near and "
            "whole-ratio mistakes are caught."
        )
    if n >= 3:
        _check_pulses_per_rev_by_closure(angle_diff, m, near=not period_checked)
    else:
        notes.append(
            "with two heads every curve fits the head differences exactly: neither the pulses per "
            "revolution nor the fit can be checked from the data."
        )
    a, ss, shifts = fits[sense]
    closure_rms = float(np.sqrt(ss / (revs * (n - 1) * m)))

    per_rev = np.fft.irfft(a, m, axis=-1)  # (R, m), index j' = head-0 pulse first + r·m + j'
    mean_curve = per_rev.mean(axis=0)
    roll = first_paired % m
    deviation = np.roll(mean_curve, roll)
    per_rev = np.roll(per_rev, roll, axis=1)

    undetect = undetectable_orders(n, m, shifts)
    if revs >= 2:
        rep = per_rev - deviation
        rep_rms: float | None = float(np.sqrt(np.mean(rep**2)))
        rep_pp: float | None = float(np.max(rep.max(axis=1) - rep.min(axis=1)))
    else:
        rep_rms = rep_pp = None
        notes.append(
            "one whole revolution only: no repeatability and no uncertainty from the data; "
            "record several revolutions."
        )
    noise, point, summaries = _deviation_uncertainty(per_rev, deviation, undetect, specs)
    budgets = {key: sm.budget for key, sm in summaries.items()}
    # one truth: the JSON values are the budgets' values (the plain summaries of the curve)
    pp = budgets["deviation_pp_arcsec"].value if budgets else float(np.ptp(deviation))
    rms = (
        budgets["deviation_rms_arcsec"].value if budgets else float(np.sqrt(np.mean(deviation**2)))
    )
    amp = np.abs(np.fft.rfft(deviation)) * 2.0 / m
    amp[0] = 0.0
    if m % 2 == 0:
        amp[-1] /= 2.0
    if undetect:
        listed = ", ".join(str(q) for q in undetect[:5])
        more = ", …" if len(undetect) > 5 else ""
        exact = all(q % n == 0 for q in undetect) and m % n == 0
        why = (
            f"are multiples of {n} (the number of heads)"
            if exact
            else "are (nearly) blind to these heads' line shifts"
        )
        note = (
            f"Fourier orders {listed}{more} {why}: they are undetectable by equal-division "
            "averaging and are set to zero; the scale's true deviation may hold them."
        )
    else:
        note = "every Fourier order 1 … m/2 is detectable with these head shifts."
    pitch_arcsec = pitch * 3600.0
    nominal = np.arange(n) * 360.0 / n * 3600.0
    placed = shifts * pitch_arcsec - np.concatenate(([0.0], offsets_mean))
    if sense == "reverse":
        placed = -placed
    head_off = (placed - nominal + pitch_arcsec / 2) % pitch_arcsec - pitch_arcsec / 2
    head_off[0] = 0.0
    offsets_u, offsets_dof = _head_offsets_u(used)
    return SelfCalibration(
        deviation_arcsec=deviation,
        heads=n,
        pulses_per_rev=m,
        deviation_pp_arcsec=pp,
        deviation_rms_arcsec=rms,
        undetectable_harmonics_note=note,
        undetectable_orders=undetect,
        revolutions_used=int(revs),
        repeatability_rms_arcsec=rep_rms,
        repeatability_pp_arcsec=rep_pp,
        deviation_u_arcsec=None if point is None else point.u,
        deviation_dof=None if point is None else point.dof_eff,
        deviation_pp_arcsec_bias=_bias(summaries, "deviation_pp_arcsec"),
        deviation_pp_arcsec_bias_corrected=_bias(summaries, "deviation_pp_arcsec", True),
        deviation_rms_arcsec_bias=_bias(summaries, "deviation_rms_arcsec"),
        deviation_rms_arcsec_bias_corrected=_bias(summaries, "deviation_rms_arcsec", True),
        closure_residual_rms_arcsec=closure_rms,
        head_offsets_arcsec=[float(x) for x in head_off],
        harmonic_amplitudes_arcsec=[float(x) for x in amp[1 : min(m // 2, 100) + 1]],
        rotation=sense,
        head_line_shifts=[int(x) for x in shifts],
        first_pulse_time_s=float(trains[0][0]),
        last_pulse_time_s=float(trains[0][-1]),
        head0_pulses=int(trains[0].size),
        notes=notes,
        head_offsets_arcsec_u=offsets_u,
        head_offsets_dof=offsets_dof,
        _per_revolution_arcsec=per_rev,
        _spectrum_arcsec=amp,
        _noise=noise,
        _point_budget=point,
        _budgets=budgets,
        warnings=tuple(
            selfcal_warnings(
                closure_residual_rms_arcsec=closure_rms,
                repeatability_rms_arcsec=rep_rms,
                heads=n,
            )
        ),
    )


def _head_offsets_u(used: FloatArray) -> tuple[list[float] | None, float | None]:
    """Type A standard uncertainty (arcsec) of each head's placement and its degrees of freedom.

    ``used`` holds the head differences (arcsec) of heads 1 … n−1 against head 0 over R whole
    revolutions, shape (R, n−1, m). Over a whole revolution the scale deviation averages out, so
    each revolution's mean difference is one reading of the placement; u = s/√R with s their
    standard deviation, ν = R − 1 (GUM §4.2.2–4.2.3). Head 0 is the reference: u = 0.
    """
    revs = used.shape[0]
    if revs < 2:
        return None, None
    per_rev = used.mean(axis=2)  # (R, n−1)
    u = per_rev.std(axis=0, ddof=1) / math.sqrt(revs)
    return [0.0, *(float(x) for x in u)], float(revs - 1)


def _bias(summaries: Mapping[str, Any], key: str, corrected: bool = False) -> float | None:
    if key not in summaries:
        return None
    sm = summaries[key]
    return sm.bias_corrected if corrected else sm.bias
