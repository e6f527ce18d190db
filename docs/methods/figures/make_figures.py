"""Draw the figures of the method pages (docs/methods/figures/*.svg) from a twin capture.

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_figures.py``.
The figures come from rotacal's own simulator and analysis, with the simulator's truth beside the
result, so a change of either shows in them.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.encoder.selfcal import self_calibrate
from rotacal.gyro.noise import gyro_noise
from rotacal.numbers import format_quantity
from rotacal.sim.gyro_noise import simulate_gyro_noise
from rotacal.sim.pulses import simulate_pulses

HERE = Path(__file__).resolve().parent
# fixed SVG ids and no date: the file only changes when the drawing does
matplotlib.rcParams["svg.hashsalt"] = "rotacal-methods"
METADATA = {"Date": None}


def allan_figure() -> None:
    """Allan deviation of a twin gyro (ARW, bias instability, RRW known) with the fitted terms."""
    truth = {"arw_deg_rt_h": 0.3, "bias_instability_deg_h": 3.0, "rrw_deg_h_rt_h": 3.0}
    cap = simulate_gyro_noise(duration_s=4 * 3600.0, fs_hz=20.0, seed=7, **truth)
    cols = cap.columns
    res = gyro_noise(cols["rate_deg_s"], time_s=cols["time_s"])
    tau = np.asarray(res.tau_s)
    adev_h = np.asarray(res.adev_deg_s) * 3600.0  # °/h
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    ax.loglog(tau, adev_h, color="#1f4e79", lw=1.6, label="overlapping Allan deviation")
    t = np.logspace(np.log10(tau[0]), np.log10(tau[-1]), 50)
    lines = res.fit.term_adev(t) * 3600.0  # each fitted term alone, °/h
    for j, (label, colour) in {
        1: ("slope −½: angle random walk N", "#c55a11"),
        2: ("slope 0: bias instability, 0.664·B", "#7f6000"),
        3: ("slope +½: rate random walk K", "#548235"),
    }.items():
        ax.loglog(t, lines[j], "--", color=colour, lw=1, label=label)
    ax.loglog(t, res.fit.total_adev(t) * 3600.0, color="#222", lw=0.8, label="sum of the five")
    ax.set_ylim(adev_h.min() / 3, adev_h.max() * 3)
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel("Allan deviation (°/h)")
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(fontsize=8, loc="upper right")
    d = res.to_dict()

    def stated(key: str, unit: str) -> str:
        return format_quantity(d[key], unit, U=d[f"{key}_U"])

    found = (
        f"five-term fit: N = {stated('arw_deg_rt_h', '°/√h')}, "
        f"B = {stated('bias_instability_deg_h', '°/h')}, "
        f"K = {stated('rrw_deg_h_rt_h', '°/h/√h')} (U at p = 95 %)"
    )
    sim = "the twin's truth: N = 0.3 °/√h, B = 3 °/h, K = 3 °/h/√h"
    ax.set_title(f"{found}\n{sim}", fontsize=7.5)
    fig.tight_layout()
    fig.savefig(HERE / "allan-slopes.svg", metadata=METADATA)
    plt.close(fig)


def selfcal_figure() -> None:
    """A 4-head self-calibration of a scale with a 4th-order error no 4-head set can see."""
    harmonics = [(1, 3.0, 0.3), (2, 1.0, 1.1), (4, 0.8, 0.0), (7, 0.4, 2.0)]
    cap = simulate_pulses(
        heads=4, pulses_per_rev=3600, rate_deg_s=60.0, revolutions=4.0, harmonics=harmonics, seed=3
    )
    res = self_calibrate(cap.columns, pulses_per_rev=3600)
    truth = np.asarray(cap.truth["deviation_arcsec"])
    detectable = np.asarray(cap.truth["deviation_detectable_arcsec"])
    found = np.asarray(res.deviation_arcsec)
    angle = np.arange(truth.size) * 360.0 / truth.size
    every = slice(None, None, 3)  # 1200 of the 3600 lines: the same curves, a third of the file
    angle, truth, detectable, found = angle[every], truth[every], detectable[every], found[every]
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(angle, truth, color="#bfbfbf", lw=2.5, label="the twin's true scale deviation")
    ax.plot(angle, detectable, color="#c55a11", lw=1, ls="--", label="true, without orders 4, 8, …")
    ax.plot(angle, found, color="#1f4e79", lw=0.8, label="self-calibrated, 4 heads")
    ax.set_xlabel("scale position from head 0's first pulse (°)")
    ax.set_ylabel("deviation (arcsec)")
    ax.set_xlim(0, 360)
    ax.set_xticks(range(0, 361, 45))
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(HERE / "selfcal-undetectable.svg", metadata=METADATA)
    plt.close(fig)


if __name__ == "__main__":
    allan_figure()
    selfcal_figure()
