"""The clipping detector (rotacal.signal.clipping) on honest and clipped captures, one run.

    python benchmarks/bench_clipping.py [--seeds 20] [--data ../shared/data]

Prints, per twin configuration, how many captures were called clipped (honest: must be 0;
clipped: must be all) and the decision figure closest to the threshold: for every side of every
column, ``min(c_e/c_next, max(c_e/c_ref, L_e/L_ref))`` — a rail needs it ≥ 8 (see the module's
rule). For clipped twins it also prints the samples the detector finds at the rails against the
samples the twin clipped (beyond its range; the rail level of an ADC also holds a few honest
samples). The figure is the column-only rule's; the call uses what each analysis adds (the
encoder's other channel, rest rows, rate points). Then the same over every real recording of ../shared/data that the
analyses read (each gyro, rate or frequency column): 0 calls allowed.

Honest twins: every kind ``rotacal simulate`` makes that has a column an analysis checks (the
pulse timestamps of ``pulses`` cannot clip), with quantisation from 8 to 16 bits or a coarse
output quantum, noise and none, distortion, stagnation at the reversals, plateaus that repeat; the
motion amplitude is varied with the seed so the table reverses at every phase of the encoder's
signals. Clipped twins: the LTS at 70 % and 95 % of the displacement amplitude, the FOG at 26 %
and 90 % of the rate amplitude (no noise and 10 dB SNR), encoder a or b beyond the ADC's rails
(12 and 16 bits), and a gyro output at its rails in the rate-table, triad, rotation,
multiposition and static (Allan) twins.
"""

from __future__ import annotations

import argparse
import gzip
import math
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from rotacal import sim
from rotacal.signal.clipping import RAIL_RATIO, RailDetector, find_clipping

COLUMNS = {
    "encoder": ("a", "b"),
    "lts": ("displacement_mm",),
    "fog": ("rate_deg_s",),
    "gyro-rates": ("output",),
    "gyro-triad": ("ux", "uy", "uz"),
    "gyro-rotations": ("ux", "uy", "uz"),
    "multiposition": ("output_deg_h",),
    "gyro-noise": ("rate_deg_s",),
}


def _context(cap: Any, column: str) -> dict[str, Any]:
    """What the analysis of this kind tells the detector (see rotacal.signal.find_clipping)."""
    cols = cap.columns
    if cap.kind == "encoder":
        return {"companion": cols["b" if column == "a" else "a"]}
    if cap.kind in ("gyro-rates", "gyro-triad", "multiposition"):
        ref = {
            "gyro-rates": ("rate_deg_s",),
            "gyro-triad": ("wx_deg_s", "wy_deg_s", "wz_deg_s"),
            "multiposition": ("phi1_deg", "phi2_deg"),
        }[cap.kind]
        x = np.column_stack([cols[c] for c in ref])
        _, groups = np.unique(x, axis=0, return_inverse=True)
        rest = None if cap.kind == "multiposition" else ~np.any(x != 0, axis=1)
        return {"groups": groups.ravel(), "rest": rest}
    if cap.kind == "gyro-rotations":
        rest = np.zeros(len(cols[column]), dtype=bool)
        for s, e in cap.truth["static"]:
            rest[s:e] = True
        return {"rest": rest}
    return {}


def _figure(values: np.ndarray, name: str, context: dict[str, Any]) -> tuple[bool, float, float]:
    """(called clipped, closest figure of the column-only rule, share reported)."""
    det = RailDetector(name)
    det.add(values)
    ratios = det._ratios()
    fig = max((min(r[0], max(r[1], r[2])) for r in ratios.values()), default=0.0)
    found = find_clipping(values, name, **context)
    return found is not None, fig, 0.0 if found is None else found.share


def _amp(seed: int, base: float) -> float:
    return base * (1.0 + 0.2 * ((seed * 0.6180339887) % 1.0 - 0.5))


def honest(seed: int) -> Iterator[tuple[str, str, dict[str, Any]]]:
    a = _amp(seed, 0.5)
    for opts in (
        {},
        {"noise_rms": 0.003},
        {"adc_bits": 16},
        {"adc_bits": 16, "noise_rms": 0.003},
        {"adc_bits": 12},
        {"adc_bits": 12, "noise_rms": 0.0005},
        {"adc_bits": 10},
        {"adc_bits": 8},
        {"adc_bits": 12, "stagnation_s": 0.05},
        {"stagnation_s": 0.05},
        {"adc_bits": 16, "harmonics": {2: (0.02, 0.3), 3: (0.01, 1.0)}},
    ):
        yield "encoder", str(opts), {"amplitude_deg": a, **opts}
    for bits in (16, 12):  # few lines, slow motion: long dwells where the table reverses
        yield (
            "encoder",
            f"1000 lines, 1 Hz, {bits} bit",
            {
                "lines": 1000,
                "amplitude_deg": _amp(seed, 1.0),
                "frequency_hz": 1.0,
                "fs_hz": 20_000.0,
                "adc_bits": bits,
            },
        )
    yield (
        "encoder",
        "motion below one line, 16 bit",
        {"amplitude_deg": _amp(seed, 0.004), "adc_bits": 16, "noise_rms": 0.0002},
    )
    for opts in ({}, {"noise_mm": 0.0}, {"noise_mm": 3e-4}, {"stagnation_s": 0.05}):
        yield "lts", str(opts), {"amplitude_deg": a, **opts}
    for opts in ({}, {"snr_db": 10.0}, {"snr_db": 7.7}, {"snr_db": 30.0, "bias_deg_s": 0.3}):
        yield "fog", str(opts), {"amplitude_deg": a, **opts}
    for opts in (
        {},
        {"quantum": 1e-3},
        {"quantum": 1e-2},
        {"quantum": 1e-3, "noise_std": 0.0},
        {"samples_per_point": 5},
        {"rates_deg_s": [-100, -50, 0, 50, 100, 50, 0, -50, -100], "quantum": 1e-2},
    ):
        yield "gyro-rates", str(opts), opts
    for opts in ({}, {"quantum": 0.05}, {"quantum": 0.5}, {"outlier_fraction": 0.02}):
        yield "gyro-triad", str(opts), opts
    for opts in ({}, {"quantum": 0.1}, {"quantum": 1.0}):
        yield "gyro-rotations", str(opts), opts
    for opts in ({"axis": "x"}, {"axis": "y"}, {"axis": "x", "noise_deg_h": 0.0}):
        yield "multiposition", str(opts), opts
    for opts in ({}, {"quantum_deg_s": 0.05}, {"quantum_deg_s": 0.2}):
        yield "gyro-noise", str(opts), {"duration_s": 600.0, **opts}


def clipped(seed: int) -> Iterator[tuple[str, str, dict[str, Any]]]:
    a = _amp(seed, 0.5)
    d_amp = 100.0 * math.tan(math.radians(a))  # the LTS twin's R = 100 mm
    for level in (0.7, 0.95):
        yield (
            "lts",
            f"range {level:.0%} of the amplitude",
            {"amplitude_deg": a, "range_mm": level * d_amp},
        )
    rate_amp = 2 * math.pi * 2.0 * a  # the default 2 Hz motion
    for level in (0.26, 0.90):
        for snr in (None, 10.0):
            yield (
                "fog",
                f"range {level:.0%} of the amplitude, SNR {snr}",
                {"amplitude_deg": a, "range_deg_s": level * rate_amp, "snr_db": snr},
            )
    for bits in (16, 12):
        yield (
            "encoder",
            f"a at the rails, {bits} bit",
            {"amplitude_deg": a, "adc_bits": bits, "amplitude_a": 1.3},
        )
        yield (
            "encoder",
            f"b at the rails, {bits} bit",
            {"amplitude_deg": a, "adc_bits": bits, "amplitude_b": 1.3},
        )
    yield "gyro-rates", "rails (1.3, 3.7)", {"saturation": (1.3, 3.7)}
    yield (
        "gyro-rates",
        "rails (1.3, 3.7), quantum 1e-3",
        {"saturation": (1.3, 3.7), "quantum": 1e-3},
    )
    yield "gyro-triad", "output limit 91", {"output_limit": 91.0}
    yield "gyro-triad", "output limit 91, quantum 0.05", {"output_limit": 91.0, "quantum": 0.05}
    yield "gyro-rotations", "output limit 150", {"output_limit": 150.0}
    yield "multiposition", "output limit 120 deg/h", {"axis": "x", "output_limit_deg_h": 120.0}
    yield "gyro-noise", "range 2.5 sigma", {"duration_s": 600.0, "range_deg_s": 0.125}


def limits(seed: int) -> Iterator[tuple[str, str, dict[str, Any]]]:
    """Clipping near the stated limits: coarse ADCs, mild overdrive (reported, not required)."""
    a = _amp(seed, 0.5)
    for bits in (10, 8):
        for gain in (1.3, 1.27):
            yield (
                "encoder",
                f"a at {gain} of the ±1.25 range, {bits} bit",
                {"amplitude_deg": a, "adc_bits": bits, "amplitude_a": gain},
            )
    d_amp = 100.0 * math.tan(math.radians(a))
    yield "lts", "range 99 % of the amplitude", {"amplitude_deg": a, "range_mm": 0.99 * d_amp}


def _truth_clipped(cap: Any) -> float:
    """Samples the twin clipped (beyond the range), summed over the analysed columns."""
    t = cap.truth
    beyond = t.get("sensor", {}).get("clipped_samples", t.get("clipped_samples"))
    if isinstance(beyond, dict):  # the encoder: per channel
        beyond = sum(beyond.values())
    return math.nan if beyond is None else float(beyond)


def run_twins(label: str, make: Callable, seeds: int, must_clip: bool) -> int:
    print(f"\n{label} twins ({seeds} seeds each)")
    print(
        f"  {'kind':<15}{'configuration':<58}{'called':>7}{'figure':>9}  at the rails / clipped by the twin"
    )
    rows: dict[tuple[str, str], list] = {}
    for seed in range(seeds):
        for kind, name, opts in make(seed):
            cap = sim.simulate(kind, seed=seed, **opts)
            row = rows.setdefault((kind, name), [0, 0, [], []])
            hit_any = False
            found = 0.0
            for col in COLUMNS[kind]:
                values = np.asarray(cap.columns[col])
                hit, fig, share = _figure(values, col, _context(cap, col))
                if must_clip and not hit:
                    continue
                row[2].append(fig)
                hit_any |= hit
                found += share * values.size
            if hit_any:
                row[3].append((found, _truth_clipped(cap)))
            row[0] += hit_any
            row[1] += 1
    wrong = 0
    for (kind, name), (hits, total, figs, shares) in rows.items():
        fig = (min(figs) if must_clip else max(figs)) if figs else 0.0
        wrong += (total - hits) if must_clip else hits
        share = ""
        if shares:
            s = np.array(shares)
            share = f"{s[:, 0].mean():.0f} / {np.nanmean(s[:, 1]):.0f} samples"
        print(f"  {kind:<15}{name[:57]:<58}{hits:>3}/{total:<3}{fig:>9.3g}  {share}")
    return wrong


def real_columns(data: Path) -> Iterator[tuple[str, np.ndarray]]:
    xin = data / "xinli_turntable" / "data"
    for f in sorted(xin.glob("*.dat")):
        arr = np.loadtxt(f)
        for c, axis in ((2, "x"), (3, "y"), (4, "z")):
            yield f"xinli {f.name} gyro {axis}", arr[:, c]
    for f in ("example_data/example_ferraris_session.csv", "tests/ferraris_example.csv"):
        arr = np.genfromtxt(data / "imucal" / f, delimiter=",", names=True)
        for c in ("gyr_x", "gyr_y", "gyr_z"):
            yield f"imucal {f} {c}", arr[c]
    arr = np.genfromtxt(
        data / "imucal/example_data/annotated_session.csv",
        delimiter=",",
        names=True,
        dtype=None,
        encoding="utf-8",
    )
    for c in ("gyr_x", "gyr_y", "gyr_z"):
        yield f"imucal annotated_session.csv {c} (counts)", np.asarray(arr[c], dtype=float)
    arr = np.loadtxt(data / "imu_tk/bin/test_data/xsens_gyro.mat")
    for c in (1, 2, 3):
        yield f"imu_tk xsens_gyro column {c} (counts)", arr[:, c]
    for f in sorted((data / "imudata_smac/npz").glob("*.npz")):
        d = np.load(f)["data"]
        for c in range(min(3, d.shape[1])):
            yield f"imudata_smac {f.name} gyro {c}", d[:, c]
    allan = data / "allantools/tests"
    for f in (
        "ocxo/ocxo_frequency.txt",
        "pink_frequency/pink_frequency.txt",
        "phasedat/PHASE.DAT",
        "Keysight53230A_ti_noise_floor/tic_phase.txt",
        "gradev/y.dat",
        "gradev/x.dat",
        "gps/gps_1pps_phase_data.txt.gz",
        "Cs5071A/5071A_phase.txt.gz",
    ):
        opener = gzip.open if f.endswith(".gz") else open
        with opener(allan / f, "rt") as fh:
            arr = np.loadtxt(fh, comments="#", ndmin=2)
        yield f"allantools {f}", arr[:, -1]


def run_real(data: Path) -> int:
    print(f"\nreal recordings in {data}")
    called = 0
    worst = (0.0, "")
    count = 0
    for name, values in real_columns(data):
        hit, fig, share = _figure(values, name, {})
        count += 1
        called += hit
        worst = max(worst, (fig, name))
        if hit:
            print(f"  CALLED CLIPPED: {name} ({100 * share:.2f} %)")
    print(f"  columns {count}, called clipped {called}, closest figure {worst[0]:.3g} ({worst[1]})")
    return called


def speed() -> None:
    rng = np.random.default_rng(0)
    n = 10_000_000
    x = np.sin(np.linspace(0, 400 * np.pi, n)) + 1e-3 * rng.standard_normal(n)
    xq = np.round(x * 2**15) / 2**15
    for label, y in (("float", x), ("16-bit", xq)):
        t0 = time.perf_counter()
        det = RailDetector("x")
        det.add(y)
        det.result()
        t1 = time.perf_counter()
        np.max(y)
        np.min(y)
        t2 = time.perf_counter()
        print(
            f"  {label:<7} {n / (t1 - t0) / 1e6:6.0f} M samples/s "
            f"({(t1 - t0) / (t2 - t1):.1f}× np.max + np.min)"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--data", type=Path, default=Path(__file__).parents[2] / "shared" / "data")
    args = ap.parse_args()
    print(f"threshold RAIL_RATIO = {RAIL_RATIO:g}")
    fp = run_twins("honest", honest, args.seeds, must_clip=False)
    missed = run_twins("clipped", clipped, args.seeds, must_clip=True)
    run_twins("near the limits (not counted): clipped", limits, args.seeds, must_clip=True)
    real = run_real(args.data) if args.data.is_dir() else 0
    print("\nspeed of the detector on 10⁷ samples (one run)")
    speed()
    print(
        f"\nfalse calls on honest twins {fp}, on real recordings {real}; clipped twins missed {missed}"
    )


if __name__ == "__main__":
    main()
