"""Accuracy against the twin's truth over many noise draws, against the bars of the issue.

    python benchmarks/bench_accuracy.py [--draws 20]

For each scheme: the worst and rms error of THD (pp), amplitude and frequency (relative) and
reversal times (ms) over independent noise seeds, on a distorted motion with stagnation and
creep. The FOG runs at 10 dB SNR (set through the twin) with 10⁵ samples of 4 kHz over
50 periods; at 10 dB the THD's scatter goes as ~50/√N pp, so the record length matters.
"""

from __future__ import annotations

import argparse

import numpy as np

from rotacal import sim
from rotacal.table import calibrate_encoder_motion, calibrate_fog_motion, calibrate_lts_motion

MOTION = sim.SineMotion(
    amplitude_deg=0.5,
    frequency_hz=2.0,
    harmonics={2: (0.010, 0.4), 3: (0.012, 1.1), 5: (0.003, 2.0)},
    stagnation_s=0.001,
    creep_deg=0.001,
)
BARS = {"encoder": 0.02, "lts": 0.05, "fog": 0.15}


def run(kind: str, seed: int) -> tuple[float, ...]:
    if kind == "encoder":
        c = sim.simulate_encoder(
            MOTION,
            offset_a=0.02,
            offset_b=-0.01,
            amplitude_b=0.98,
            phase_error_rad=0.01,
            noise_rms=0.004,
            adc_bits=16,
            seed=seed,
        ).columns
        r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
    elif kind == "lts":
        c = sim.simulate_lts(MOTION, radius_mm=100.0, noise_mm=3e-5, seed=seed).columns
        r = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0)
    else:
        c = sim.simulate_fog(
            MOTION, snr_db=10.0, bias_deg_s=0.2, fs_hz=4000.0, duration_s=25.0625, seed=seed
        ).columns
        r = calibrate_fog_motion(c["time_s"], c["rate_deg_s"])
    truth = MOTION.truth(r.analysis_start_s, r.analysis_stop_s)
    t = c["time_s"]
    true_rev = np.asarray(MOTION.truth(t[0], t[-1])["reversal_times_s"])
    rev_err = (
        np.max(np.abs(r.reversal_times_s - true_rev)) * 1e3
        if r.reversal_times_s.size == true_rev.size
        else np.inf
    )
    return (
        r.thd_percent - truth["thd_percent"],
        r.amplitude_deg / truth["amplitude_deg"] - 1,
        r.frequency_hz / truth["frequency_hz"] - 1,
        rev_err,
        (r.amplitude_deg - truth["amplitude_deg"]) / r.amplitude_deg_u,
        (r.thd_percent - truth["thd_percent"]) / r.thd_percent_u,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--draws", type=int, default=20)
    args = ap.parse_args()
    print(
        f"{'scheme':8s} {'THD worst (pp)':>15s} {'bar':>6s} {'THD rms':>9s} {'ampl. worst':>12s} "
        f"{'freq. worst':>12s} {'reversal worst':>15s} {'ampl err/u rms':>15s} {'THD err/u rms':>14s}"
    )
    for kind in ("encoder", "lts", "fog"):
        e = np.array([run(kind, seed) for seed in range(args.draws)])
        print(
            f"{kind:8s} {np.max(np.abs(e[:, 0])):15.4f} {BARS[kind]:6.2f} "
            f"{np.sqrt(np.mean(e[:, 0] ** 2)):9.4f} {np.max(np.abs(e[:, 1])):12.2e} "
            f"{np.max(np.abs(e[:, 2])):12.2e} {np.max(e[:, 3]):12.2f} ms "
            f"{np.sqrt(np.mean(e[:, 4] ** 2)):15.2f} {np.sqrt(np.mean(e[:, 5] ** 2)):14.2f}"
        )
    print(
        "bars: amplitude 2e-4, frequency 1e-5 relative; reversals: a few ms. err/u rms near 1 means"
    )
    print("the reported standard uncertainty (white-noise fit model) explains the scatter.")


if __name__ == "__main__":
    main()
