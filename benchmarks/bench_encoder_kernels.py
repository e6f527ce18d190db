"""Throughput of the encoder chain against bare ``np.unwrap(np.arctan2(b, a))``, one run.

    python benchmarks/bench_encoder_kernels.py [--samples 1e7] [--periods 10,100,1000] [--quick] [--cpu]
        [--stages]

For each number of motion periods in the capture (same sample count), every row is timed best
of ``--repeat`` after a warm-up (Numba's first call compiles or loads its cache there) and printed
as M samples/s and as ratios against two baselines measured in the same run:

- ``unwrap``: bare ``np.unwrap(np.arctan2(b, a))`` on the raw signals (the issue's bar: ≤ 1.0);
- ``limit``: ``arctan2`` plus an integer cycle count over 32 k-sample blocks, nothing else (the
  floor of any demodulation; the issue's bar: within 2×).

Rows: the fused pass (:func:`rotacal.encoder._kernel.phase_pass`: Heydemann correction, arctan2,
cycle count, subinterval transitions, extremes) with its Numba and its NumPy twin; the same with
the harmonic fit's block moments added (``HarmonicFitAccumulator``, the accumulation the fit
needs); ``demodulate`` (checks, Heydemann fit, fused pass, reversals) and the whole
``calibrate_encoder_motion`` (fit, residual, budgets), each with Numba on and off; and the
budgets alone (``motion_budgets`` inside the calibration) on their first call, with the cached
Monte Carlo draws and tables cleared: the fixed cost a command pays (the issue: ≤ 10 ms). One core:
BLAS is held to one thread. Machines here are shared and noisy: the ratios are the figures.

``--stages`` adds, per number of periods, where ``calibrate_encoder_motion`` (Numba by size)
spends its time: each stage timed inside the call (its function wrapped for the run), best of
``--repeat`` calls, and what is left (checks of the settings, plot copies, result assembly).
"""

from __future__ import annotations

import argparse
import math
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from rotacal import _jit, sim  # noqa: E402
from rotacal.encoder import demodulate, fit_quadrature_correction  # noqa: E402
from rotacal.encoder._kernel import BLOCK, phase_pass  # noqa: E402
from rotacal.signal import HarmonicFitAccumulator  # noqa: E402
from rotacal.table import calibrate_encoder_motion  # noqa: E402

LINES = 36000
FS = 200_000.0


def capture(n: int, periods: float) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray]:
    """``periods`` motion periods in n samples at 200 kHz: 0.5° (less above 20 Hz), 1 % 2nd harmonic, 2 % offset,
    2 % gain mismatch, 0.01 rad quadrature error, 0.003 noise."""
    duration = n / FS
    f = periods / duration
    # 0.5° up to 20 Hz, less above: the phase step per sample stays below 0.2 rad
    motion = sim.SineMotion(
        amplitude_deg=0.5 * min(1.0, 20.0 / f), frequency_hz=f, harmonics={2: (0.01, 0.3)}
    )
    cap = sim.simulate_encoder(
        motion,
        fs_hz=FS,
        duration_s=duration,
        offset_a=0.02,
        amplitude_b=0.98,
        phase_error_rad=0.01,
        noise_rms=0.003,
        seed=0,
    )
    return motion, cap.columns["time_s"], cap.columns["a"], cap.columns["b"]


#: The clock of every row: wall time, or with --cpu this process's CPU time (steadier where
#: other work shares the cores; BLAS is held to one thread, so the two agree when idle).
CLOCK = time.perf_counter


def best_of(fn: Callable[[], Any], repeats: int) -> float:
    fn()  # warm-up
    best = float("inf")
    for _ in range(repeats):
        t0 = CLOCK()
        fn()
        best = min(best, CLOCK() - t0)
    return best


def limit(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """arctan2 and the integer cycle count over cache-sized blocks: the floor of the chain."""
    out = np.empty(a.size)
    last = 0.0
    cycles = 0
    for s in range(0, a.size, BLOCK):
        w = np.arctan2(b[s : s + BLOCK], a[s : s + BLOCK])
        d = np.diff(w, prepend=last if s else w[0])
        c = np.cumsum((d < -np.pi).astype(np.int64) - (d > np.pi)) + cycles
        np.multiply(c, 2 * np.pi, out=out[s : s + w.size])
        out[s : s + w.size] += w
        last, cycles = float(w[-1]), int(c[-1])
    return out


def budgets_cold(t: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Seconds spent in ``motion_budgets`` by one calibration whose caches start empty."""
    import rotacal.table.motion as motion_module
    from rotacal.table import _argmax_table, motion_thd

    spent: list[float] = []
    plain = motion_module.motion_budgets

    def timed(**kwargs: Any) -> Any:
        t0 = CLOCK()
        out = plain(**kwargs)
        spent.append(CLOCK() - t0)
        return out

    motion_thd._thd_batch.cache_clear()
    _argmax_table._interp = None
    motion_module.motion_budgets = timed  # type: ignore[assignment]
    try:
        calibrate_encoder_motion(t, a, b, lines=LINES)
    finally:
        motion_module.motion_budgets = plain
    return spent[0]


#: (label, module, attribute) of each stage of calibrate_encoder_motion, in the order it runs.
STAGES = (
    ("checks: signals a, b and their rails", "rotacal.encoder.quadrature", "_check_pair_and_rails"),
    ("checks: time stamps", "rotacal.encoder.quadrature", "_check_time"),
    ("checks: rails' verdict", "rotacal.encoder.quadrature", "_rails_verdict"),
    ("Heydemann ellipse fit", "rotacal.encoder.quadrature", "_fit"),
    ("fused pass", "rotacal.encoder._kernel", "phase_pass"),
    ("reversals: plan", "rotacal.encoder.quadrature", "plan_reversals"),
    ("reversals: Chp, eqs. (7)-(8)", "rotacal.encoder.quadrature", "_pinned"),
    ("harmonic fit", "rotacal.table.motion", "fit_motion"),
    ("  of which residual sums", "rotacal.signal._blocks", "residual_tau_sums"),
    ("  of which residual sums", "rotacal.signal._blocks", "residual_sums"),
    ("budgets (THD, Monte Carlo)", "rotacal.table.motion", "motion_budgets"),
)


def stage_times(
    t: np.ndarray, a: np.ndarray, b: np.ndarray, repeats: int
) -> list[tuple[str, float]]:
    """Seconds of each stage of one ``calibrate_encoder_motion`` call (best of ``repeats``),
    the whole call, and the rest."""
    import importlib

    spent: dict[str, float] = {}
    best: dict[str, float] = {}
    plain: list[tuple[Any, str, Any]] = []

    def timed(label: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: Any, **kwargs: Any) -> Any:
            t0 = CLOCK()
            try:
                return fn(*args, **kwargs)
            finally:
                spent[label] = spent.get(label, 0.0) + CLOCK() - t0

        return call

    for label, module, name in STAGES:
        mod = importlib.import_module(module)
        plain.append((mod, name, getattr(mod, name)))
        setattr(mod, name, timed(label, getattr(mod, name)))
    try:
        for i in range(repeats + 1):  # the first call warms up
            spent.clear()
            t0 = CLOCK()
            calibrate_encoder_motion(t, a, b, lines=LINES)
            spent["whole call"] = CLOCK() - t0
            if i:
                for key, sec in spent.items():
                    best[key] = min(best.get(key, math.inf), sec)
    finally:
        for mod, name, fn in plain:
            setattr(mod, name, fn)
    # a label named twice (two functions of one stage) is one row: its times add
    rows = [(label, best.get(label, 0.0)) for label in dict.fromkeys(s[0] for s in STAGES)]
    top = sum(sec for label, sec in rows if not label.startswith(" "))
    rows.append(("rest (settings, plot copies, result)", max(0.0, best["whole call"] - top)))
    rows.append(("whole call", best["whole call"]))
    return rows


def run_periods(n: int, periods: float, repeats: int, stages: bool = False) -> None:
    """Time every row on one capture of ``periods`` motion periods and print them."""
    motion, t, a, b = capture(n, periods)
    corr = fit_quadrature_correction(a, b)
    t_unwrap = best_of(lambda: np.unwrap(np.arctan2(b, a)), repeats)
    t_limit = best_of(lambda: limit(a, b), repeats)

    def with_moments(jit: bool) -> None:
        run = phase_pass(a, b, corr, jit=jit)
        acc = HarmonicFitAccumulator(periods * FS / n, harmonics=10)
        acc.add(t, run.phase_rad)

    def numba_off(fn: Callable[[], Any]) -> Callable[[], Any]:
        def call() -> Any:
            os.environ["ROTACAL_NUMBA"] = "0"
            try:
                return fn()
            finally:
                del os.environ["ROTACAL_NUMBA"]

        return call

    rows: list[tuple[str, float]] = [
        ("np.unwrap(np.arctan2(b, a))  [unwrap]", t_unwrap),
        ("arctan2 + cycle count, 32 k blocks  [limit]", t_limit),
    ]
    for jit in (True, False):
        name = "Numba" if jit else "NumPy"
        rows.append(
            (
                f"fused pass ({name})",
                best_of(lambda j=jit: phase_pass(a, b, corr, jit=j), repeats),
            )
        )
        rows.append(
            (
                f"fused pass + fit moments ({name})",
                best_of(lambda j=jit: with_moments(j), repeats),
            )
        )
    demod = lambda: demodulate(t, a, b, LINES)  # noqa: E731
    calib = lambda: calibrate_encoder_motion(t, a, b, lines=LINES)  # noqa: E731
    rows.append(("demodulate (Numba by size)", best_of(demod, repeats)))
    rows.append(("demodulate (NumPy)", best_of(numba_off(demod), repeats)))
    rows.append(("calibrate_encoder_motion (Numba by size)", best_of(calib, repeats)))
    rows.append(("calibrate_encoder_motion (NumPy)", best_of(numba_off(calib), repeats)))
    rows.append(
        ("  of which motion budgets, cold", min(budgets_cold(t, a, b) for _ in range(repeats)))
    )
    for name, sec in rows:
        print(
            f"{periods:7.0f}  {name:<44s} {sec * 1e3:8.1f} {n / sec / 1e6:6.1f} "
            f"{sec / t_unwrap:8.2f} {sec / t_limit:7.2f}"
        )
    if stages:
        for name, sec in stage_times(t, a, b, repeats):
            print(
                f"{periods:7.0f}  stage: {name:<37s} {sec * 1e3:8.1f} {'':6s} {sec / t_unwrap:8.2f}"
            )
    r = calibrate_encoder_motion(t, a, b, lines=LINES)
    truth = motion.truth(r.analysis_start_s, r.analysis_stop_s)
    print(
        f"{periods:7.0f}  truth: amplitude {r.amplitude_deg / truth['amplitude_deg'] - 1:+.1e} "
        f"(rel), THD {r.thd_percent - truth['thd_percent']:+.1e} pp"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=float, default=1e7)
    ap.add_argument("--periods", default="10,100,1000")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="10⁶ samples, 2 repeats")
    ap.add_argument("--cpu", action="store_true", help="time by CPU time, not wall time")
    ap.add_argument(
        "--stages", action="store_true", help="also time each stage of calibrate_encoder_motion"
    )
    args = ap.parse_args()
    global CLOCK
    if args.cpu:
        CLOCK = time.process_time
    n = int(1e6 if args.quick else args.samples)
    repeats = 2 if args.quick else args.repeat
    clock = "CPU" if args.cpu else "wall"
    print(f"samples {n:,}; numba available: {_jit.numba_available()}; best of {repeats} ({clock})")
    print(f"{'periods':>7s}  {'row':<44s} {'ms':>8s} {'M/s':>6s} {'/unwrap':>8s} {'/limit':>7s}")
    for periods in (float(p) for p in args.periods.split(",")):
        run_periods(n, periods, repeats, args.stages)


if __name__ == "__main__":
    main()
