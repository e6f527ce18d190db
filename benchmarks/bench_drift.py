"""Drift against the twin's truth: THD with and without --drift, and the warning's false alarms.

    python benchmarks/bench_drift.py [--seeds 30]

Part 1. Feng et al. Table 1's 0.1° / 5 Hz and 0.5° / 2 Hz motions (harmonics, stagnation, creep;
the demo's sensors; the FOG at 10 dB SNR, 10⁵ samples at 4 kHz) with a table drift of 0.01° and of 1°
over the 6⅛-period encoder/LTS record (the FOG sees the same drift rate over its longer record),
each analysed without and with --drift: THD − true THD (pp), whether the warning came, and
(with --drift) the drift's error in units of its stated u. "fails" is an analysis that ended in
an error. Bars: 0.02 pp (encoder), 0.05 pp (LTS), 0.15 pp (FOG at 10 dB).

Part 2. Drift-free twins over ``--seeds`` random motions per scheme (amplitude, frequency, one
harmonic, stagnation, creep, noise, record length between 1.6 and 7 periods) and the demo's ten
captures: how many carry the unfitted-drift warning (it must be none).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from rotacal import sim
from rotacal.errors import CaptureError
from rotacal.table import calibrate_encoder_motion, calibrate_fog_motion, calibrate_lts_motion

BARS = {"encoder": 0.02, "lts": 0.05, "fog": 0.15}


def analyse(kind: str, columns: dict, drift: bool):
    c = columns
    if kind == "encoder":
        return calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000, drift=drift)
    if kind == "lts":
        return calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0, drift=drift)
    return calibrate_fog_motion(c["time_s"], c["rate_deg_s"], drift=drift)


def part1() -> None:
    print("THD error (pp) on drifting twins; warn = the unfitted-drift warning came")
    print(
        f"{'motion':14s} {'scheme':8s} {'drift':>7s} {'without --drift':>22s} {'with --drift':>30s}"
    )
    for sc in sim.table1_scenarios()[1:4:2]:  # 0.1°/5 Hz and 0.5°/2 Hz
        record = sc["duration_s"]
        for kind in ("encoder", "lts", "fog"):
            opts = dict(sc["sensors"][kind])
            if kind == "fog":  # 10 dB, 10⁵ samples at 4 kHz (as bench_accuracy's FOG)
                opts.pop("noise_deg_s")
                opts.update(snr_db=10.0, fs_hz=4000.0, duration_s=25.0 + 0.125 / sc["frequency_hz"])
            for total in (0.01, 1.0):
                motion = dataclasses.replace(sc["motion"], drift_deg_s=total / record)
                cap = sim.simulate(kind, motion=motion, **opts)
                cells = []
                for drift in (False, True):
                    try:
                        r = analyse(kind, cap.columns, drift)
                    except CaptureError as e:
                        cells.append(f"fails ({str(e)[:18]}…)")
                        continue
                    truth = motion.truth(r.analysis_start_s, r.analysis_stop_s)
                    err = r.thd_percent - truth["thd_percent"]
                    mark = "ok " if abs(err) < BARS[kind] else "BAR"
                    cell = f"{err:+9.4f} {mark} {'warn' if r.warnings else '    '}"
                    if drift:
                        d_true = truth["drift_deg_s"] + (
                            cap.truth["sensor"]["bias_deg_s"] if kind == "fog" else 0.0
                        )
                        cell += f" drift {(r.drift_deg_s - d_true) / r.drift_deg_s_u:+5.1f} u"
                    cells.append(cell)
                print(f"{sc['name']:14s} {kind:8s} {total:6g}° {cells[0]:>22s} {cells[1]:>30s}")


def part2(seeds: int) -> None:
    rng = np.random.default_rng(2023)
    for kind in ("encoder", "lts", "fog"):
        alarms = 0
        for seed in range(seeds):
            amp = float(rng.choice([0.05, 0.1, 0.5, 2.0]))
            f = float(rng.choice([0.5, 2.0, 5.0]))
            motion = sim.SineMotion(
                amplitude_deg=amp,
                frequency_hz=f,
                harmonics={3: (float(rng.uniform(0, 0.05)), float(rng.uniform(0, 6)))},
                stagnation_s=float(rng.choice([0.0, 0.002])) / f,
                creep_deg=float(rng.choice([0.0, 0.002])) * amp,
                phase_rad=float(rng.uniform(0, 6)),
            )
            dur = float(rng.uniform(1.6, 7.0)) / f
            if kind == "encoder":
                fs = 50_000.0 if amp * f < 3 else 200_000.0
                noise = float(rng.choice([0.001, 0.003, 0.01]))
                cap = sim.simulate_encoder(
                    motion, fs_hz=fs, duration_s=dur, noise_rms=noise, adc_bits=16, seed=seed
                )
            elif kind == "lts":
                noise = float(rng.choice([3e-5, 3e-4]))
                cap = sim.simulate_lts(motion, duration_s=dur, noise_mm=noise, seed=seed)
            else:
                snr = float(rng.choice([10.0, 20.0, 40.0]))
                cap = sim.simulate_fog(
                    motion, snr_db=snr, bias_deg_s=0.01, duration_s=6 * dur, seed=seed
                )
            alarms += bool(analyse(kind, cap.columns, False).warnings)
        print(f"drift-free {kind:8s} twins: {alarms} of {seeds} warn")
    alarms = 0
    for sc in sim.table1_scenarios():
        for kind in (sc["paper_sensors"][0], "fog"):
            cap = sim.simulate(kind, motion=sc["motion"], **sc["sensors"][kind])
            alarms += bool(analyse(kind, cap.columns, False).warnings)
    print(f"the demo's 10 captures: {alarms} warn")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=30)
    args = ap.parse_args()
    part1()
    part2(args.seeds)


if __name__ == "__main__":
    main()
