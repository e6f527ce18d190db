"""rotacal's Ferraris calibration against imucal's published results on imucal's own recordings.

    python benchmarks/bench_ferraris_imucal.py [--data ../shared/data]

For each recording (102.4 Hz in °/s; 204.8 Hz in counts) prints, with imucal's g = 9.81 and no
Earth rate (as imucal computes): the largest |K − K_g·R_g| relative to the smallest K_g, the same
for the rotations without the accelerometer (g-sensitivity left in K, what rotacal did before),
the largest differences of K_ga, K_a, R_a, b_a, and b_g less the static mean of K_ga·a (which
imucal keeps in b_g); then at 49.6° N (the lab's latitude, assumed) the drop of K_ga's diagonal
against K_ii·Ω_E·sin L/g.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np

from rotacal.gyro.ferraris import calibrate_ferraris
from rotacal.gyro.rotation_sections import ferraris_sections, sections_from_labels
from rotacal.gyro.rotations import calibrate_triad_rotations

STATIC = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")


def _load_102(root: Path) -> tuple:
    ex = root / "example_data"
    d = np.loadtxt(ex / "example_ferraris_session.csv", delimiter=",", skiprows=1)
    sec = json.loads((ex / "example_ferraris_session_list.json").read_text())
    sec = {k: (v["start"], v["end"]) for k, v in sec.items()}
    ref = root / "example_ferraris_session_cal_computed_imucal2.6.0.json"
    return d[:, 1:4], d[:, 4:7], sec, 102.4, ref


def _load_204(root: Path) -> tuple:
    with open(root / "example_data" / "annotated_session.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    vals = np.array([r[2:] for r in rows[1:]], dtype=float)  # acc_x … acc_z, gyr_x … gyr_z
    gyr, acc, sec = vals[:, 3:6], vals[:, 0:3], sections_from_labels([r[0] for r in rows[1:]])
    return gyr, acc, sec, 204.8, root / "tests" / "snapshots" / "example_cal.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path(__file__).parents[2] / "shared" / "data")
    root = ap.parse_args().data / "imucal"
    for load in (_load_102, _load_204):
        gyr, acc, sec, fs, ref_path = load(root)
        ref = {k: np.asarray(v, dtype=float) for k, v in json.loads(ref_path.read_text()).items()
               if k[:2] in ("K_", "R_", "b_")}  # fmt: skip
        k_ref = ref["K_g"] @ ref["R_g"]
        scale = float(np.abs(np.diag(ref["K_g"])).min())
        r = calibrate_ferraris(gyr, acc, fs, sec, gravity_m_s2=9.81)
        rotations, static = ferraris_sections(sec)
        plain = calibrate_triad_rotations(gyr, fs, rotations, static=static)
        rows = np.concatenate([np.arange(*sec[k]) for k in STATIC])
        b_imucal = r.bias + (r.accelerometer.calibrate(acc[rows]) @ r.g_sensitivity.T).mean(0)
        a = r.accelerometer
        print(f"{ref_path.name} ({fs} Hz)")
        print(
            f"  K   − K_g·R_g      {np.abs(r.scale_misalignment - k_ref).max() / scale:.3g} (relative)"
        )
        print(
            f"  K without K_ga    {np.abs(plain.scale_misalignment - k_ref).max() / scale:.3g} (relative)"
        )
        print(
            f"  |ΔK| / u(K)       {np.max(np.abs(r.scale_misalignment - k_ref) / r.scale_misalignment_u):.3g}"
        )
        print(f"  K_ga              {np.abs(r.g_sensitivity - ref['K_ga']).max():.3g}")
        print(f"  b_g (imucal's)    {np.abs(b_imucal - ref['b_g']).max():.3g}")
        print(f"  K_a, R_a, b_a     {np.abs(a.scale_factors - np.diag(ref['K_a'])).max():.3g}, "
              f"{np.abs(a.sensitive_axes - ref['R_a']).max():.3g}, {np.abs(a.bias - ref['b_a']).max():.3g}")  # fmt: skip
        lat = calibrate_ferraris(gyr, acc, fs, sec, gravity_m_s2=9.81, latitude_deg=49.6)
        drop = np.diag(ref["K_ga"] - lat.g_sensitivity)
        expect = (
            np.diag(lat.scale_misalignment) * 15.041067 / 3600 * math.sin(math.radians(49.6)) / 9.81
        )
        print(f"  at 49.6° N, K_ga diagonal drop / K_ii·Ω_E·sin L/g: {np.round(drop / expect, 4)}")


if __name__ == "__main__":
    main()
