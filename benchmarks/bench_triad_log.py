"""`gyro triad --runs` on repeated twins: does the stated uncertainty match the spread, and what
does averaging whole revolutions buy over averaging every row of each run?

For each of ``--repeats`` seeds, a ``gyro-triad-log`` twin (the study's 30 runs, ``--run-s`` each,
so that most runs end inside a revolution; a g-sensitivity G with gravity turning with the table;
a random starting orientation per run) is calibrated twice with
:func:`rotacal.gyro.triad_log.calibrate_triad_log`: over whole revolutions (the method) and over
all rows (``whole_revolutions=False``). It prints, for each, the standard deviation over the
twins and elements of z = (K̂ − K)/u(K̂) and (b̂ − b)/u(b̂) — 1 when the stated uncertainty matches
the spread — and the rms error of K against the truth.

    python benchmarks/bench_triad_log.py                 # 40 twins of 75-s runs at 100 Hz
    python benchmarks/bench_triad_log.py --repeats 10 --fs-hz 20
"""

from __future__ import annotations

import argparse

import numpy as np

from rotacal.gyro.triad_log import calibrate_triad_log
from rotacal.sim import simulate_gyro_triad_log


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=40)
    ap.add_argument("--run-s", type=float, default=75.0)
    ap.add_argument("--fs-hz", type=float, default=100.0)
    args = ap.parse_args()
    z: dict[bool, list] = {True: [], False: []}
    for seed in range(args.repeats):
        cap = simulate_gyro_triad_log(run_s=args.run_s, fs_hz=args.fs_hz, seed=1000 + seed)
        c, truth = cap.columns, cap.truth
        w = np.column_stack([c[k] for k in ("wx_deg_s", "wy_deg_s", "wz_deg_s")])
        u = np.column_stack([c[k] for k in ("ux", "uy", "uz")])
        k, b = np.array(truth["scale_misalignment"]), np.array(truth["bias"])
        for whole in (True, False):
            r = calibrate_triad_log(c["time_s"], w, u, whole_revolutions=whole)
            z[whole].append(
                (
                    ((r.scale_misalignment - k) / r.scale_misalignment_u).ravel(),
                    (r.bias - b) / r.bias_u,
                    (r.scale_misalignment - k).ravel(),
                )
            )
    print(f"{args.repeats} twins, runs of {args.run_s:g} s at {args.fs_hz:g} Hz")
    for whole, label in ((True, "whole revolutions"), (False, "all rows of each run")):
        zk, zb, dk = (np.array([x[i] for x in z[whole]]) for i in range(3))
        print(
            f"  {label:<22} std z(K) {zk.std():.3f}  std z(b) {zb.std():.3f}  "
            f"rms error of K {np.sqrt(np.mean(dk**2)):.3g}"
        )


if __name__ == "__main__":
    main()
