"""Coverage and cost of the five-term IEEE 952 noise fit (rotacal.gyro.noise_fit) on twins.

For each twin — each pure noise type (angle quantization Q, white rate N, flicker B, rate random
walk K, rate ramp R with some N) and mixtures (the default ``rotacal simulate gyro-noise``
record N + B; all five) — ``--seeds`` records of ``--duration-s`` at 100 Hz are drawn,
``gyro_noise`` fitted, and for each term the share of seeds whose 95 % interval holds the twin's
truth is printed (for an absent term: holds 0), with the mean and spread of the estimates.
The band-limited bias stand-in (``bias_model="gauss-markov"``, flat only over 1–1000 s) is run
too: its B is flicker on its band only, so the fit's discrepancy δ grows and N/K pick up what
lies outside the band. CPU seconds per record (draw + Allan deviation + fit) close each line.
No asserts: tests/gyro/test_noise_fit.py asserts ≥ 35/40 on short records.

Run: ``python benchmarks/bench_noise_fit.py [--seeds 40] [--duration-s 3600] [--only NAME]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rotacal.gyro.noise import gyro_noise
from rotacal.sim import simulate_gyro_noise

_KEYS = (
    "quantization_arcsec",
    "arw_deg_rt_h",
    "bias_instability_deg_h",
    "rrw_deg_h_rt_h",
    "rate_ramp_deg_h2",
)
_ZERO = {"arw_deg_rt_h": 0.0, "bias_instability_deg_h": 0.0}
TWINS = {
    "Q": {**_ZERO, "quantization_arcsec": 2.0},
    "N": {**_ZERO, "arw_deg_rt_h": 0.3},
    "B": {**_ZERO, "bias_instability_deg_h": 3.0},
    "K": {**_ZERO, "rrw_deg_h_rt_h": 30.0},
    "R (+N)": {**_ZERO, "arw_deg_rt_h": 0.3, "rate_ramp_deg_h2": 2000.0},
    "N+B (default)": {"arw_deg_rt_h": 0.3, "bias_instability_deg_h": 3.0},
    "all five": {
        "quantization_arcsec": 2.0,
        "arw_deg_rt_h": 0.3,
        "bias_instability_deg_h": 3.0,
        "rrw_deg_h_rt_h": 10.0,
        "rate_ramp_deg_h2": 200.0,
    },
    "B Gauss-Markov 1-1000 s": {
        **_ZERO,
        "bias_instability_deg_h": 3.0,
        "bias_model": "gauss-markov",
    },
}


def run(name: str, seeds: int, duration: float) -> None:
    kw = TWINS[name]
    truth = np.array([float(kw.get(k, 0.0)) for k in _KEYS])
    hits = np.zeros(5)
    values, deltas, widths = [], [], []
    cpu = time.process_time()
    for seed in range(seeds):
        cap = simulate_gyro_noise(duration_s=duration, fs_hz=100.0, seed=seed, **kw)
        r = gyro_noise(cap.columns["rate_deg_s"], fs_hz=100.0)
        nt = r.noise_terms
        iv = np.array([nt[f"{k}_interval"] for k in _KEYS])
        hits += (iv[:, 0] <= truth) & (truth <= iv[:, 1])
        values.append([nt[k] for k in _KEYS])
        widths.append([nt[f"{k}_U"] for k in _KEYS])
        deltas.append(r.fit.discrepancy)
    cpu = (time.process_time() - cpu) / seeds
    v, w = np.array(values), np.array(widths)
    print(f"\n{name}: {seeds} seeds of {duration:g} s, {cpu:.2f} s CPU per record")
    print(f"  {'term':<24}{'truth':>10}{'mean':>12}{'std':>12}{'mean U':>12}{'coverage':>10}")
    for j, key in enumerate(_KEYS):
        print(
            f"  {key:<24}{truth[j]:>10.4g}{v[:, j].mean():>12.4g}{v[:, j].std(ddof=1):>12.3g}"
            f"{w[:, j].mean():>12.3g}{hits[j] / seeds:>10.3f}"
        )
    print(f"  model discrepancy δ: median {np.median(deltas):.3g}, max {np.max(deltas):.3g}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=40)
    parser.add_argument("--duration-s", type=float, default=3600.0)
    parser.add_argument("--only", choices=list(TWINS), default=None)
    args = parser.parse_args()
    for name in [args.only] if args.only else list(TWINS):
        run(name, args.seeds, args.duration_s)


if __name__ == "__main__":
    main()
