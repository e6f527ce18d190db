"""Tables built to a turntable allocation that miss the calibration accuracy, per requirement.

On the seed's two-axis table (seed 001, §2.3: a multiposition drift calibration to 0.01 °/h, 8 × 8
positions, latitude 45.75°), for each way of setting the orientation requirement:

1. eq. (16) as printed, 0.027° on each component, stated (the packaged table until issue 12);
2. ``earth-rate-only``: the paper's reading, ωm/(max Earth-rate change) = 0.02694° each;
3. the same on the paper's 45° constraint grid (the paper's reading end to end);
4. the box of eqs. (15)–(16) unscaled (the derivation of ``calibration_deg_h`` until issue 12);
5. ``calibration-check``: the box scaled so that every table within the bounds keeps ωm (default);

it allocates (``allocate``, full-model guard), draws ``--runs`` tables within the bounds (the
budget's calibration check, random signs) and prints the share above ωm per axis, the largest
drawn, the worst table (every sign vertex, full model) and the time. No asserts.

Run: ``python benchmarks/bench_turntable_requirement.py [--runs N]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from rotacal.turntable.allocation import allocate  # noqa: E402
from rotacal.turntable.budget import calibration_check  # noqa: E402
from rotacal.turntable.calibration import orientation_requirement  # noqa: E402
from rotacal.turntable.model import COMPONENTS, seed_table  # noqa: E402
from rotacal.turntable.requirement import (  # noqa: E402
    calibration_worst_case,
    derive_requirement,
)
from rotacal.turntable.seed001 import EQ16_DEG  # noqa: E402

WM = 0.01
LATITUDE = 45.75


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100_000)
    args = ap.parse_args()
    table = seed_table()
    p1, p2 = np.meshgrid(np.arange(0.0, 360.0, 45.0), np.arange(0.0, 360.0, 45.0), indexing="ij")
    plan = {"phi1_deg": p1.ravel(), "phi2_deg": p2.ravel(), "latitude_deg": LATITUDE}

    def stated(req_rad: dict[str, float], step: float | None = None):
        return lambda: allocate(table, req_rad, constraint_step_deg=step)

    def derived(derivation: str, step: float | None = None):
        return lambda: (
            derive_requirement(table, WM, derivation, constraint_step_deg=step, **plan).allocation
        )

    box = orientation_requirement(WM, **plan).limits_rad
    cases = [
        (
            "eq. (16) as printed, 0.027° stated",
            stated(dict.fromkeys(COMPONENTS, math.radians(EQ16_DEG))),
        ),
        ("earth-rate-only (0.02694°), every angle", derived("earth-rate-only")),
        ("earth-rate-only on the paper's 45° grid", derived("earth-rate-only", 45.0)),
        ("box of eqs. (15)–(16), unscaled (old default)", stated(dict(box))),
        ("calibration-check (new default)", derived("calibration-check")),
    ]
    print(
        f"seed 001 table, calibration to {WM} °/h, 8 × 8 positions, latitude {LATITUDE}°, "
        f"{args.runs:,} tables drawn per case (LB ≤ |χ| ≤ UB, random signs)"
    )
    print(
        f"{'requirement':48s} {'above x':>8s} {'above y':>8s} {'max drawn':>10s} "
        f"{'worst table':>12s} {'Iθ (°)':>9s} {'time':>7s}"
    )
    for label, make in cases:
        t0 = time.perf_counter()
        alloc = make()
        elapsed = time.perf_counter() - t0
        draws = calibration_check(
            table,
            alloc.upper_bounds_rad,
            lower_bounds_rad=alloc.lower_bounds_rad,
            runs=args.runs,
            seed=2026,
            latitude_deg=LATITUDE,
        )
        worst = calibration_worst_case(table, alloc.upper_bounds_rad, **plan)["worst_deg_h"]
        top = max(float(np.max(v)) for v in draws.values())
        print(
            f"{label:48s} {np.mean(draws['x'] > WM) * 100:7.2f}% {np.mean(draws['y'] > WM) * 100:7.2f}% "
            f"{top:10.5f} {worst:12.5f} {math.degrees(alloc.requirement_rad['theta']):9.5f} "
            f"{elapsed:6.1f}s"
        )


if __name__ == "__main__":
    main()
