"""Draw docs/methods/figures/ferraris-earth-rate.svg from a Ferraris twin on the rotating Earth.

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_ferraris_figure.py``.
The twin's truth stands beside rotacal's result, so a change of either shows in the figure.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.ferraris import calibrate_ferraris
from rotacal.sim import simulate_ferraris

HERE = Path(__file__).resolve().parent
matplotlib.rcParams["svg.hashsalt"] = "rotacal-methods"


def main() -> None:
    cap = simulate_ferraris(seed=3, latitude_deg=49.6, noise_std=0.01, acc_noise_std=0.005)
    t = cap.truth
    g = np.column_stack([cap.columns[c] for c in ("ux", "uy", "uz")])
    a = np.column_stack([cap.columns[c] for c in ("ax", "ay", "az")])
    fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
    x = np.arange(9)
    for shift, lat, color, label in (
        (-0.17, None, "#b0b7bf", "no latitude: Earth rate left in, in the uncertainty"),
        (0.17, 49.6, "#1f4e79", "--latitude-deg 49.6: vertical Earth rate removed"),
    ):
        r = calibrate_ferraris(
            g, a, 100.0, t["sections"], latitude_deg=lat, gravity_m_s2=t["gravity_m_s2"]
        )
        err = (r.g_sensitivity - np.asarray(t["g_sensitivity"])).ravel() * 1e4
        big_u = 2.0 * r.g_sensitivity_u.ravel() * 1e4
        ax.errorbar(x + shift, err, yerr=big_u, fmt="o", color=color, ms=4, capsize=2, label=label)
    ax.axhline(0.0, color="#555", lw=0.7)
    ax.set_xticks(x)
    ax.set_xticklabels([f"K_ga,{i}{j}" for i in "xyz" for j in "xyz"], fontsize=8)
    ax.set_ylabel("estimate − truth (10⁻⁴ (°/s)/(m/s²))")
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(fontsize=7.5, frameon=False, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    fig.savefig(HERE / "ferraris-earth-rate.svg", metadata={"Date": None})
    plt.close(fig)


if __name__ == "__main__":
    main()
