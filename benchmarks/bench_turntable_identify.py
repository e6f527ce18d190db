"""Turntable identification on the twin: accuracy, stated-u coverage and time, per noise level.

For each reading noise (arcsec rms) and position set, ``--seeds`` twins
(``rotacal.sim.simulate_orientation_errors``, proper rotations, the twin's default table) are
identified (``identify_turntable``, the paper's small-angle model) and the separable
combinations compared with the twin's truth: the rms of (value − truth)/u (1 when u is right),
the share of |value − truth| ≤ U (95 % stated), the largest |value − truth| (arcsec) and the CPU
time per identification (best of the seeds, design and advice included). No asserts.

Run: ``python benchmarks/bench_turntable_identify.py [--seeds N]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import time  # noqa: E402

import numpy as np  # noqa: E402

from rotacal.sim import simulate_orientation_errors  # noqa: E402
from rotacal.turntable import identify_turntable  # noqa: E402

COLUMNS = ("phi1_deg", "phi2_deg", "dpsi_arcsec", "dtheta_arcsec", "dgamma_arcsec")
#: (label, simulate_orientation_errors options)
DESIGNS = (
    ("8 × 8 grid", {"outer_steps": 8, "inner_steps": 8}),
    ("φ1 = 0, 12 φ2", {"outer_steps": 1, "inner_steps": 12}),
    ("φ2 fixed, 8 φ1", {"outer_steps": 8, "inner_steps": 1}),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=300)
    seeds = parser.parse_args().seeds
    print(
        f"{'positions':<16} {'noise″':>7} {'rank':>4} {'rms z':>6} {'in U':>6} "
        f"{'max |err|″':>10} {'ms':>6}"
    )
    for label, design in DESIGNS:
        for noise in (0.05, 0.5, 5.0):
            z, inside, worst, best, rank = [], [], 0.0, np.inf, 0
            for seed in range(seeds):
                cap = simulate_orientation_errors(noise_arcsec=noise, seed=seed, **design)
                t0 = time.process_time()
                r = identify_turntable(*(cap.columns[c] for c in COLUMNS))
                best = min(best, time.process_time() - t0)
                rank = r.rank
                truth = cap.truth["errors_arcsec"]
                for c in r.combinations:
                    err = c["value_arcsec"] - sum(
                        a * truth[n] for n, a in c["coefficients"].items()
                    )
                    z.append(err / c["u_arcsec"])
                    inside.append(abs(err) <= c["U_arcsec"])
                    worst = max(worst, abs(err))
            print(
                f"{label:<16} {noise:>7.2f} {rank:>4} {np.sqrt(np.mean(np.square(z))):>6.3f} "
                f"{np.mean(inside) * 100:>5.1f}% {worst:>10.4f} {best * 1e3:>6.1f}"
            )


if __name__ == "__main__":
    main()
