"""3-axis gyro calibration from one continuous log of rotation runs, each averaged over whole revolutions.

The robot-manipulator study (2023) rotates the IMU nonstop about one axis for one minute per set
rate (procedure steps 6–8, Table 2: 6, 18, 30, 60 and 90 °/s), in three orientations, and fills
U with the output of each run (processing step 1). One minute at those rates is exactly 1, 3, 5,
10 and 15 revolutions: the average over a run then spans whole revolutions, which cancels every
term of the output that depends on the DUT's orientation about the rotation axis — the
g-sensitivity to gravity turning in the sensor's frame when the axis is not vertical, the Earth
rate's component across the axis, a once-per-revolution wobble of the table. :func:`split_runs`
cuts a log into its runs; :func:`calibrate_triad_log` averages each run over its whole
revolutions only and fits the triad model to the run means (:func:`rotacal.gyro.calibrate_triad`,
eqs. (4), (5), (7)).

**Runs.** The reference rate ω (``wx_deg_s``, ``wy_deg_s``, ``wz_deg_s``: the set rate of the
robot or table in the DUT's nominal axes, °/s) is constant within a run: a run is a maximal span
of consecutive rows whose ω differs from the previous row's by at most ``rate_tolerance_deg_s``
in every component and whose |ω| exceeds it (rows at rest or in a ramp are no run).
``settle_s`` is dropped from each run's start (the DUT's transient after the step).

**Whole revolutions.** The table angle is the integrated reference rate, θ(t) = |ω|·(t − t₀)
within a run (each row holding its rate until the next row's time). A run spanning the angle
Θ = |ω|·T (T: the rows' span including the last row's interval) holds N = ⌊Θ/360°⌋ whole
revolutions; its mean is taken over the rows with θ < N·360°, the remainder Θ − N·360° is
dropped. A run shorter than one revolution is refused (its mean would keep an orientation-
dependent bias of the order of that term's amplitude).

**What the remainder would bias.** A term a·cos(θ + φ) averages to zero over whole revolutions;
over Θ it leaves a·[sin(Θ + φ) − sin φ]/Θ (Θ in rad), up to 2a/Θ: for one and a quarter
revolutions of a 0.2 °/s/g g-sensitivity, up to 0.05 °/s in that run's mean — a bias of the run
mean, not noise, so the least squares cannot average it away and its residual-based uncertainty
does not show it. ``tests/gyro/test_triad_log.py`` shows it on a twin.

References
----------
Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
March 2023: procedure steps 6–8, Table 2, processing steps 1–5, eqs. (4), (5), (7).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal.columns import RATE_COLUMNS, TRIAD_OUTPUT_COLUMNS
from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.triad import TriadResult, calibrate_triad

__all__ = ["TriadLogResult", "TriadRun", "calibrate_triad_log", "split_runs"]

#: Reference rates closer than this (°/s) are one set rate (a commanded rate is exact).
DEFAULT_RUN_TOLERANCE_DEG_S = 1e-3
#: Rows of the log kept for its figure (evenly strided).
_FIGURE_ROWS = 20_000


@dataclasses.dataclass(frozen=True)
class TriadRun:
    """One rotation run of a log: rows [start, stop) after settling, and the rows averaged.

    ``rate_deg_s`` the reference rate vector (°/s); ``revolutions`` the whole revolutions N
    averaged; ``used_stop`` the end of the averaged rows; ``angle_deg`` the run's whole angle
    Θ (deg) after settling; ``start_s``/``end_s``/``used_end_s`` the times (s) of its first,
    last and last averaged rows.
    """

    start: int
    stop: int
    used_stop: int
    rate_deg_s: tuple[float, float, float]
    revolutions: int
    angle_deg: float
    start_s: float
    end_s: float
    used_end_s: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "start_s": self.start_s,
            "end_s": self.end_s,
            "used_end_s": self.used_end_s,
            "rate_deg_s": list(self.rate_deg_s),
            "revolutions": self.revolutions,
            "angle_deg": self.angle_deg,
            "remainder_deg": self.angle_deg - 360.0 * self.revolutions,
            "samples": self.stop - self.start,
            "samples_used": self.used_stop - self.start,
        }


def _settings(rate_tolerance_deg_s: float, settle_s: float) -> tuple[float, float]:
    out = []
    for name, v in (("rate_tolerance_deg_s", rate_tolerance_deg_s), ("settle_s", settle_s)):
        bad = isinstance(v, bool) or not isinstance(v, (int, float, np.floating))
        if bad or not math.isfinite(v) or v < 0:
            raise ConfigError(f"{name} must be a finite number ≥ 0, got {v!r}")
        out.append(float(v))
    return out[0], out[1]


def split_runs(
    time_s: Any,
    omega_deg_s: Any,
    *,
    rate_tolerance_deg_s: float = DEFAULT_RUN_TOLERANCE_DEG_S,
    settle_s: float = 0.0,
) -> tuple[TriadRun, ...]:
    """The rotation runs of a log and the rows of each that span whole revolutions.

    Parameters
    ----------
    time_s : array (n,)
        Time of each row (s), finite and strictly increasing.
    omega_deg_s : array (n, 3)
        Reference rate of each row in the DUT's nominal axes (°/s), constant within a run.
    rate_tolerance_deg_s : float
        Largest change of a component between rows of one run, and the smallest |ω| of a run
        (°/s).
    settle_s : float
        Time dropped from each run's start (s).

    Returns
    -------
    tuple of TriadRun
        In time order.

    Raises
    ------
    CaptureError
        Time not finite or not increasing, a non-finite rate, no run, or a run shorter than one
        revolution after settling (named by its time and rate).

    References
    ----------
    Robot-manipulator study (2023), procedure steps 6–8 (one minute of nonstop rotation per
    rate) and this module's docstring (whole revolutions).
    """
    tol, settle = _settings(rate_tolerance_deg_s, settle_s)
    t = np.asarray(time_s, dtype=float).reshape(-1)
    w = np.asarray(omega_deg_s, dtype=float)
    if w.ndim != 2 or w.shape != (t.size, 3):
        raise CaptureError(
            f"the reference rates have shape {w.shape} but the log has {t.size} rows of "
            f"time_s: give {', '.join(RATE_COLUMNS)} on every row"
        )
    for name, x in (("time_s", t), *((c, w[:, j]) for j, c in enumerate(RATE_COLUMNS))):
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise CaptureError(
                f"column {name} holds {x[bad[0]]} at row {bad[0]} (0-based, {bad.size} such): a "
                "log of rotation runs needs a finite time and reference rate on every row"
            )
    if t.size < 2:
        raise CaptureError(f"the log has {t.size} rows: too few to hold rotation runs")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise CaptureError(
            f"column time_s does not increase at row {k} (0-based): a log of rotation runs "
            "needs strictly increasing time"
        )
    # the interval each row holds its rate: to the next row (the last row: the median step)
    dt = np.diff(t, append=t[-1] + float(np.median(np.diff(t))))
    moving = np.linalg.norm(w, axis=1) > tol
    # a new span of one rate starts where a component changes by more than tol, or the table
    # starts or stops; the spans in which it moves are the runs
    same = np.all(np.abs(np.diff(w, axis=0)) <= tol, axis=1) & (moving[1:] == moving[:-1])
    starts = np.flatnonzero(np.r_[True, ~same])
    ends = np.r_[starts[1:], t.size]
    runs = []
    for first, stop in zip(starts.tolist(), ends.tolist(), strict=True):
        a0, b = int(first), int(stop)
        if not moving[a0]:
            continue
        a = int(np.searchsorted(t, t[a0] + settle - 1e-12 * max(abs(t[a0]), 1.0)))
        a = min(a, b)
        rate = w[a0]
        speed = float(np.linalg.norm(rate))
        elapsed = np.cumsum(dt[a:b])  # time at the end of each row's interval, from t[a]
        angle = speed * float(elapsed[-1]) if b > a else 0.0
        revs = math.floor(angle / 360.0 * (1 + 1e-12))
        if revs < 1:
            raise CaptureError(
                f"the run at {_vec(rate)} °/s from {t[a0]:.6g} s to {t[b - 1]:.6g} s turns "
                f"{angle:.4g}° after settling {settle:g} s, less than one revolution: whole-"
                "revolution averaging needs each run to last 360°/|ω| "
                f"= {360.0 / speed:.4g} s at least (record it longer, or lower --settle-s)"
            )
        # rows whose interval ends within N revolutions
        n_used = int(np.searchsorted(elapsed * speed, revs * 360.0 * (1 + 1e-12), side="right"))
        runs.append(
            TriadRun(
                start=a,
                stop=b,
                used_stop=a + n_used,
                rate_deg_s=(float(rate[0]), float(rate[1]), float(rate[2])),
                revolutions=revs,
                angle_deg=angle,
                start_s=float(t[a]),
                end_s=float(t[b - 1]),
                used_end_s=float(t[a + n_used - 1]),
            )
        )
    if not runs:
        raise CaptureError(
            "the log holds no rotation run: every row's reference rate is below "
            f"{tol:g} °/s; check the columns {', '.join(RATE_COLUMNS)}"
        )
    return tuple(runs)


def _vec(rate: Any) -> str:
    return "(" + ", ".join(f"{float(x):+.6g}" for x in rate) + ")"


@dataclasses.dataclass(frozen=True)
class TriadLogResult(TriadResult):
    """:class:`~rotacal.gyro.triad.TriadResult` of the run means of a log, plus ``runs`` (one
    dict per run: ``start_s``, ``end_s``, ``used_end_s`` in s; ``rate_deg_s`` the reference
    rate vector, °/s; ``revolutions`` averaged; ``angle_deg`` and ``remainder_deg`` (dropped),
    deg; ``samples`` and ``samples_used``; ``output_mean`` the averaged outputs, output unit),
    ``averaging`` (``"whole revolutions"`` or
    ``"whole runs"``) and ``settle_s``. ``_log`` keeps a strided copy (time, |ω|) for the figure.
    """

    runs: tuple[dict[str, Any], ...] = ()
    averaging: str = "whole revolutions"
    settle_s: float = 0.0
    _log: tuple[np.ndarray, np.ndarray] | None = dataclasses.field(
        default=None, repr=False, compare=False
    )


def calibrate_triad_log(
    time_s: Any,
    omega_deg_s: Any,
    u: Any,
    *,
    whole_revolutions: bool = True,
    rate_tolerance_deg_s: float = DEFAULT_RUN_TOLERANCE_DEG_S,
    settle_s: float = 0.0,
    **options: Any,
) -> TriadLogResult:
    """K and b of a gyro triad from a log of rotation runs, each averaged over whole revolutions.

    Parameters
    ----------
    time_s : array (n,)
        Time (s), strictly increasing.
    omega_deg_s : array (n, 3)
        Reference rate in the DUT's nominal axes (°/s), constant within each run.
    u : array (n, 3)
        Raw outputs ``ux``, ``uy``, ``uz`` (output unit).
    whole_revolutions : bool
        Average each run over its whole revolutions only (True, the method); False: over every
        row of the run (keeps the remainder's orientation-dependent bias; for comparison).
    rate_tolerance_deg_s, settle_s : float
        Of :func:`split_runs` (°/s, s).
    **options
        The keywords of :func:`rotacal.gyro.calibrate_triad` (``reject_k``, ``specs``,
        ``output_unit``, …), applied to the run means. ``reject_k`` defaults to ``math.inf``
        (no rejection): a log holds few runs (30 in the study), whose robust σ (1.4826·MAD of
        about 30 residuals) is itself uncertain by ~20 % and, at the Bonferroni k ≈ 3.1, rejects
        good runs (seen on the twin); give a k to reject anomalous runs.

    Returns
    -------
    TriadLogResult
        The triad result of the run means (one row per run; uncertainties from their residuals
        and the budgets of :func:`~rotacal.gyro.calibrate_triad`), with the runs.

    Raises
    ------
    CaptureError
        As :func:`split_runs` and :func:`~rotacal.gyro.calibrate_triad` (e.g. runs about fewer
        than three axes, too few runs); outputs of another length or not finite in a run.

    References
    ----------
    Robot-manipulator study (2023): processing steps 1–5, eqs. (4), (5), (7); this module's
    docstring (whole revolutions).
    """
    t = np.asarray(time_s, dtype=float).reshape(-1)
    w = np.asarray(omega_deg_s, dtype=float)
    uu = np.asarray(u, dtype=float)
    if uu.shape != (t.size, 3):
        raise CaptureError(
            f"the outputs have shape {uu.shape} but the log has {t.size} rows: give "
            f"{', '.join(TRIAD_OUTPUT_COLUMNS)} on every row"
        )
    runs = split_runs(t, w, rate_tolerance_deg_s=rate_tolerance_deg_s, settle_s=settle_s)
    means = np.empty((len(runs), 3))
    for i, run in enumerate(runs):
        seg = uu[run.start : run.used_stop if whole_revolutions else run.stop]
        if not np.isfinite(seg).all():
            j, c = np.argwhere(~np.isfinite(seg))[0]
            raise CaptureError(
                f"column {TRIAD_OUTPUT_COLUMNS[c]} holds {seg[j, c]} at row {run.start + j} "
                f"(0-based), in the run from {run.start_s:.6g} s: every averaged row needs "
                "finite outputs"
            )
        means[i] = seg.mean(axis=0)
    rates = np.array([r.rate_deg_s for r in runs])
    fit = calibrate_triad(rates, means, **{"reject_k": math.inf, **options})
    stride = max(1, t.size // _FIGURE_ROWS)
    base = {f.name: getattr(fit, f.name) for f in dataclasses.fields(fit) if f.init}
    return TriadLogResult(
        **base,
        runs=tuple(
            {**r.to_dict(), "output_mean": m.tolist()} for r, m in zip(runs, means, strict=True)
        ),
        averaging="whole revolutions" if whole_revolutions else "whole runs",
        settle_s=float(settle_s),
        _log=(t[::stride].copy(), np.linalg.norm(w[::stride], axis=1)),
    )
