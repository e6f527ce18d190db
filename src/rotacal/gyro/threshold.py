"""Threshold and resolution of a gyro from a small-step test (IEEE Std 1431-2004, IEEE Std 528-2001).

The definitions (IEEE Std 528-2001, used by the test procedures of IEEE Std 952-1997 and
1431-2004), in our words:

* **threshold** — the largest, over the directions of input, of the smallest input rate (from
  zero) whose output is at least 50 % of what the nominal scale factor predicts for it;
* **resolution** — for inputs above the threshold, the largest, over the operating rates, of the
  smallest change of input rate whose output change is at least 50 % of what the nominal scale
  factor predicts.

**The test and its log.** The table dwells on a sequence of set rates, written on every row of
``rate_deg_s`` with the DUT's ``output``: around zero it steps 0 → +δ → 0 → −δ → 0 …, around an
operating rate Ω₀ it steps Ω₀ → Ω₀ ± δ → Ω₀ …, for increments δ of several sizes. Consecutive rows
with the same set rate (within ``rate_tolerance_deg_s``) are one dwell; ``settle_samples`` drop
the start of each (the DUT's response). Each change between consecutive dwells is a step with
input change Δ = Ω_after − Ω_before and output change ΔV = V̄_after − V̄_before; its ratio
r = ΔV/(S·Δ) is 1 for a gyro that follows and 0 for one that does not.

* Steps with one end at 0 °/s test the threshold, with input |Ω| of the other end; steps with
  both ends non-zero test the resolution, with input |Δ|. Inputs within the tolerance of each
  other form one level.
* A level is **met** when every step of it reaches r ≥ 50 % (the "largest over directions and
  rates" of the definitions: the worst step decides). The threshold (resolution) lies between
  the largest level not met below the smallest level from which on every larger level is met
  (L₋), and that level (L₊): the value stated is the middle of (L₋, L₊], its standard
  uncertainty the rectangular (L₊ − L₋)/√12 (GUM, JCGM 100:2008 §4.3.7), and
  ``threshold_bracket_deg_s`` gives (L₋, L₊). When the smallest level tested is met, L₋ = 0
  and a warning says the value is a bound (test smaller increments); when the largest is not
  met, no value is stated.
* A step whose ratio lies within 2 u(r) of 50 % (u(r) from the two dwells' standard errors) is a
  decision the noise could turn: a warning names it (dwell longer).

S is the nominal scale factor when given; otherwise the unweighted least-squares line through the
dwells' means (the test's own rates), which a note states. The output's own resolution (quantum
or noise of one reading, :func:`rotacal.gyro.resolution.output_resolution`) is reported beside
it, as what a single reading can show.

References
----------
IEEE Std 528-2001, IEEE Standard for Inertial Sensor Terminology (threshold, resolution).
IEEE Std 1431-2004, specification format guide and test procedure for Coriolis vibratory gyros
(threshold and resolution tests); IEEE Std 952-1997 (the same items for optic gyros).
JCGM 100:2008 (GUM) §4.3.7 (rectangular distribution), §5.1.2.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.resolution import OutputResolution, output_resolution
from rotacal.gyro.scale_factor_points import _group, output_quantum
from rotacal.results import Result
from rotacal.signal._values import check_magnitudes

__all__ = ["CRITERION", "K_RECTANGULAR_95", "SmallStep", "SmallStepResult", "small_step_test"]

#: The fraction of the expected output change a step must reach (IEEE Std 528: 50 %).
CRITERION = 0.5
#: Set rates closer than this (°/s) on consecutive rows are one dwell: well below any increment.
DEFAULT_STEP_TOLERANCE_DEG_S = 1e-9
_NOISE_SIGMAS = 2.0
#: Coverage factor of a rectangular distribution for p = 95 % (√3·0.95; GUM G.2.3 / G.6.6 note).
K_RECTANGULAR_95 = 1.65


@dataclasses.dataclass(frozen=True)
class SmallStep(Result):
    """One change of set rate: ``before_deg_s`` → ``after_deg_s`` (°/s), the output change (output
    units), ``ratio`` = ΔV/(S·Δ) with ``ratio_u``, ``kind`` ``"threshold"`` or ``"resolution"`` and
    ``input_deg_s`` the level it tests (°/s)."""

    before_deg_s: float
    after_deg_s: float
    output_change: float
    ratio: float
    ratio_u: float
    kind: str
    input_deg_s: float


@dataclasses.dataclass(frozen=True)
class SmallStepResult(Result):
    """Threshold and resolution (°/s) from a small-step test, each with ``_u`` and its bracket.

    ``threshold_deg_s``/``resolution_deg_s`` are None when the largest level tested is not met
    (or no step tests it). ``scale_factor`` (output units per °/s) is the one the ratios use,
    ``scale_factor_source`` ``"nominal"`` or ``"fitted"``; ``steps`` every step; ``dwells`` the
    number of dwells; ``output_resolution`` the output's own (quantum or noise of one reading).
    """

    threshold_deg_s: float | None
    threshold_deg_s_u: float | None
    threshold_bracket_deg_s: tuple[float, float] | None
    resolution_deg_s: float | None
    resolution_deg_s_u: float | None
    resolution_bracket_deg_s: tuple[float, float] | None
    criterion: float
    scale_factor: float
    scale_factor_source: str
    dwells: int
    steps: tuple[SmallStep, ...]
    output_resolution: OutputResolution | None
    output_unit: str = ""
    notes: tuple[str, ...] = ()

    def summary_lines(self) -> list[str]:
        """value ± U (rectangular, p = 95 %) and the bracket of each, for the CLI."""
        out = []
        for name in ("threshold", "resolution"):
            v = getattr(self, f"{name}_deg_s")
            if v is None:
                out.append(f"{name:<11} not reached by the increments tested")
                continue
            lo, hi = getattr(self, f"{name}_bracket_deg_s")
            u = getattr(self, f"{name}_deg_s_u")
            out.append(
                f"{name:<11} {v:.4g} ± {K_RECTANGULAR_95 * u:.2g} deg/s (k = "
                f"{K_RECTANGULAR_95:g}, p = 95 %), between {lo:.4g} and {hi:.4g}"
            )
        return out


def _dwells(
    rate: np.ndarray, y: np.ndarray, tol: float, settle: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(set rate, mean, standard error, samples, dwell id per row; −1 for settling rows)."""
    new = np.r_[True, np.abs(np.diff(rate)) > tol]
    starts = np.flatnonzero(new)
    sizes = np.diff(np.r_[starts, rate.size])
    dwell = np.cumsum(new) - 1
    within = np.arange(rate.size) - starts[dwell]
    dwell = np.where(within >= settle, dwell, -1)
    used = dwell >= 0
    n = np.bincount(dwell[used], minlength=starts.size)
    short = np.flatnonzero(n < 2)
    if short.size:
        i = int(short[0])
        raise CaptureError(
            f"the dwell at {rate[starts[i]]:+.6g} °/s from row {int(starts[i])} holds {int(sizes[i])} "
            f"row(s), {int(n[i])} after settling: each dwell needs at least 2 samples after "
            "--settle-samples; dwell longer or settle less."
        )
    d = y[used] - y[starts][dwell[used]]  # less each dwell's first sample, for the digits
    mean_d = np.bincount(dwell[used], weights=d) / n
    dev = d - mean_d[dwell[used]]
    std = np.sqrt(np.bincount(dwell[used], weights=dev * dev) / (n - 1))
    return rate[starts], y[starts] + mean_d, std / np.sqrt(n), n, dwell


def _levels(
    inputs: np.ndarray, ratios: np.ndarray, tol: float, what: str
) -> tuple[float | None, float | None, tuple[float, float] | None, list[str]]:
    """The value, u and bracket of one item from its steps' inputs and ratios; warnings."""
    if inputs.size == 0:
        return None, None, None, [f"no step tests the {what}."]
    gid, levels, _ = _group(inputs, tol)
    worst = np.full(levels.size, np.inf)
    np.minimum.at(worst, gid, ratios)
    met = worst >= CRITERION
    if not met[-1]:
        return (
            None,
            None,
            None,
            [
                f"the largest {what} input tested ({levels[-1]:.4g} °/s) did not reach "
                f"{100 * CRITERION:g} % of the expected output: the {what} is above it; test larger "
                "increments."
            ],
        )
    failing = np.flatnonzero(~met)
    k = int(failing[-1]) + 1 if failing.size else 0  # the smallest level from which on all meet
    lo, hi = (float(levels[k - 1]) if k else 0.0), float(levels[k])
    warnings = []
    if k == 0:
        warnings.append(
            f"the smallest {what} input tested ({hi:.4g} °/s) already reached {100 * CRITERION:g} "
            f"%: the {what} is at most that; test smaller increments."
        )
    if failing.size and np.any(met[: failing[-1]]):
        warnings.append(
            f"some {what} inputs below {lo:.4g} °/s met the criterion while {lo:.4g} °/s did not: "
            "the largest failing input decides (IEEE Std 528: the largest of the minima)."
        )
    return 0.5 * (lo + hi), (hi - lo) / math.sqrt(12.0), (lo, hi), warnings


def small_step_test(
    rate_deg_s: np.ndarray,
    output: np.ndarray,
    *,
    scale_factor: float | None = None,
    settle_samples: int = 0,
    rate_tolerance_deg_s: float = DEFAULT_STEP_TOLERANCE_DEG_S,
    sample_rate_hz: float | None = None,
    output_unit: str = "",
) -> SmallStepResult:
    """Threshold and resolution of a gyro from a log of small rate steps (see the module).

    Parameters
    ----------
    rate_deg_s : array
        The table's set rate on each row (°/s), in recorded order.
    output : array
        The DUT's output on each row (output units).
    scale_factor : float or None
        Nominal S (output units per °/s, nonzero); None fits it to the dwells.
    settle_samples : int
        Samples dropped at the start of each dwell (≥ 0).
    rate_tolerance_deg_s : float
        Consecutive set rates closer than this (°/s, > 0) are one dwell; inputs closer than this
        are one level.
    sample_rate_hz : float or None
        fs (Hz), for the output's own resolution at fs/2.
    output_unit : str
        Name of the output unit.

    Returns
    -------
    SmallStepResult
    """
    if isinstance(settle_samples, bool) or not isinstance(settle_samples, (int, np.integer)):
        raise ConfigError(f"settle_samples must be an integer ≥ 0, got {settle_samples!r}.")
    if settle_samples < 0:
        raise ConfigError(f"settle_samples must be ≥ 0, got {settle_samples}.")
    tol = float(rate_tolerance_deg_s)
    if not math.isfinite(tol) or tol <= 0:
        raise ConfigError(f"rate_tolerance_deg_s must be > 0 °/s, got {rate_tolerance_deg_s!r}.")
    rate = np.asarray(rate_deg_s, dtype=float).reshape(-1)
    y = np.asarray(output, dtype=float).reshape(-1)
    if rate.size != y.size or rate.size == 0:
        raise CaptureError(
            f"columns rate_deg_s ({rate.size} rows) and output ({y.size}) must hold the same, "
            "non-zero number of rows."
        )
    if not (np.all(np.isfinite(rate)) and np.all(np.isfinite(y))):
        raise CaptureError("rate_deg_s and output must be finite on every row (no NaN or inf).")
    check_magnitudes("rate_deg_s", rate, what="a set rate")
    check_magnitudes("output", y, what="a gyro output")
    set_rate, mean, se, _, dwell = _dwells(rate, y, tol, int(settle_samples))
    if set_rate.size < 2:
        raise CaptureError(
            "the log holds one set rate: a small-step test needs the table to step between rates."
        )
    notes = []
    if scale_factor is None:
        if np.unique(set_rate).size < 2:
            raise CaptureError("the log needs two set rates at least to fit a scale factor.")
        s = float(np.polyfit(set_rate, mean, 1)[0])
        source = "fitted"
        notes.append(
            f"S = {s:.8g} fitted to the {set_rate.size} dwells' means (no nominal scale factor "
            "given, --scale-factor)."
        )
    else:
        s, source = float(scale_factor), "nominal"
        if not math.isfinite(s) or s == 0:
            raise ConfigError(
                f"scale_factor must be a finite non-zero number, got {scale_factor!r}."
            )
    before, after = set_rate[:-1], set_rate[1:]
    change = after - before
    dv = np.diff(mean)
    ratio = dv / (s * change)
    ratio_u = np.hypot(se[:-1], se[1:]) / np.abs(s * change)
    at_zero = (np.abs(before) <= tol) | (np.abs(after) <= tol)
    kind = np.where(at_zero, "threshold", "resolution")
    inputs = np.where(at_zero, np.maximum(np.abs(before), np.abs(after)), np.abs(change))
    thr = _levels(inputs[at_zero], ratio[at_zero], tol, "threshold")
    res = _levels(inputs[~at_zero], ratio[~at_zero], tol, "resolution")
    warnings = [*thr[3], *res[3]]
    close = np.flatnonzero(np.abs(ratio - CRITERION) < _NOISE_SIGMAS * ratio_u)
    if close.size:
        i = int(close[0])
        warnings.append(
            f"{close.size} step(s) lie within {_NOISE_SIGMAS:g} u of the {100 * CRITERION:g} % "
            f"criterion (the first {before[i]:+.6g} → {after[i]:+.6g} °/s, ratio {ratio[i]:.2f} ± "
            f"{ratio_u[i]:.2f}): the noise could turn those decisions; dwell longer."
        )
    used = dwell >= 0
    own = output_resolution(
        y[used],
        dwell[used],
        s,
        quantum=output_quantum(y[used], dwell[used]),
        sample_rate_hz=sample_rate_hz,
        output_unit=output_unit,
    )
    steps = tuple(
        SmallStep(
            float(before[i]),
            float(after[i]),
            float(dv[i]),
            float(ratio[i]),
            float(ratio_u[i]),
            str(kind[i]),
            float(inputs[i]),
        )
        for i in range(change.size)
    )
    return SmallStepResult(
        threshold_deg_s=thr[0],
        threshold_deg_s_u=thr[1],
        threshold_bracket_deg_s=thr[2],
        resolution_deg_s=res[0],
        resolution_deg_s_u=res[1],
        resolution_bracket_deg_s=res[2],
        criterion=CRITERION,
        scale_factor=s,
        scale_factor_source=source,
        dwells=int(set_rate.size),
        steps=steps,
        output_resolution=own,
        output_unit=output_unit,
        notes=tuple(notes),
        warnings=tuple(warnings),
    )
