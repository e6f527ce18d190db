"""Draw docs/methods/figures/allan-family.svg: the five deviations of one twin gyro record.

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_family_figure.py``.
A twin record with white rate noise, a flicker floor and a rate ramp (known from the simulator
plus a ramp added here), each deviation with its 68 % interval.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from rotacal.signal.deviations import DEVIATION_NAMES, stability_deviation
from rotacal.sim.gyro_noise import simulate_gyro_noise

HERE = Path(__file__).resolve().parent
matplotlib.rcParams["svg.hashsalt"] = "rotacal-methods"
METADATA = {"Date": None}
COLORS = {"adev": "#1f4e79", "mdev": "#c55a11", "hdev": "#548235", "totdev": "#7030a0"}
#: Rate ramp added to the twin (°/s per s): it dominates the ADEV beyond a few hundred seconds.
RAMP = 2e-7


def main() -> None:
    cap = simulate_gyro_noise(duration_s=4 * 3600.0, fs_hz=20.0, seed=7, arw_deg_rt_h=0.3,
                              bias_instability_deg_h=3.0, rrw_deg_h_rt_h=0.0)  # fmt: skip
    t = cap.columns["time_s"]
    rate = cap.columns["rate_deg_s"] + RAMP * t
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(9.6, 4.0))
    for kind, color in COLORS.items():
        d = stability_deviation(rate, fs=20.0, kind=kind, taus="log")
        ax.fill_between(d.tau_s, d.low * 3600, d.high * 3600, color=color, alpha=0.18, lw=0)
        ax.loglog(d.tau_s, d.deviation * 3600, color=color, lw=1.3, label=DEVIATION_NAMES[kind])
    d = stability_deviation(rate, fs=20.0, kind="tdev", taus="log")
    bx.fill_between(d.tau_s, d.low, d.high, color="#7f6000", alpha=0.2, lw=0)
    bx.loglog(d.tau_s, d.deviation, color="#7f6000", lw=1.3, label="time deviation")
    ax.set_ylabel("deviation (°/h)")
    bx.set_ylabel("time deviation (°)")
    for a in (ax, bx):
        a.set_xlabel("averaging time τ (s)")
        a.grid(True, which="both", lw=0.3, alpha=0.5)
        a.legend(fontsize=8, loc="best")
    ax.set_title(f"twin: N = 0.3 °/√h, B = 3 °/h, rate ramp {RAMP * 3600**2:.2g} °/h²", fontsize=8)
    fig.tight_layout()
    fig.savefig(HERE / "allan-family.svg", metadata=METADATA)
    plt.close(fig)


if __name__ == "__main__":
    main()
