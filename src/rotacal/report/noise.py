"""Report section for gyro noise: the Allan deviation with its fitted IEEE 952 slopes."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.noise import GyroNoise
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_tables

__all__ = ["noise_section"]

_LABELS = {
    "quantization": ("quantization Q", "−1", "°", 1.0),
    "angle_random_walk": ("angle random walk N", "−½", "°/√h", 60.0),
    "bias_instability": ("bias instability B", "0", "°/h", 3600.0),
    "rate_random_walk": ("rate random walk K", "+½", "°/h/√h", 3600.0 * 60.0),
    "rate_ramp": ("rate ramp R", "+1", "°/h²", 3600.0**2),
}
_COLORS = {
    "quantization": "#6a3d9a",
    "angle_random_walk": "#d2691e",
    "bias_instability": "#2e8b57",
    "rate_random_walk": "#b22222",
    "rate_ramp": "#555555",
}


def _figure(r: GyroNoise) -> Figure:
    tau = np.asarray(r.tau_s)
    fig, ax = plt.subplots(figsize=(7.8, 4.8))
    ax.fill_between(
        tau,
        r.adev_low_deg_s,
        r.adev_high_deg_s,
        color="#9fb7cf",
        alpha=0.45,
        lw=0,
        label="68 % interval",
    )
    ax.loglog(tau, r.adev_deg_s, color="#1f5f99", lw=1.4, label="overlapping Allan deviation")
    for name, term in r.terms.terms.items():
        label = _LABELS.get(name, (name, "", "", 1.0))[0]
        # draw the line a decade beyond the points it was fitted through
        t0, t1 = np.asarray(term.line_tau_s, dtype=float)[[0, -1]]
        a0 = float(np.asarray(term.line_adev)[0])
        tt = np.array([max(tau[0], t0 / 10), min(tau[-1], t1 * 10)])
        ax.loglog(
            tt,
            a0 * (tt / t0) ** term.slope,
            "--",
            lw=1.1,
            color=_COLORS.get(name, "#333"),
            label=f"{label} (slope {_LABELS.get(name, ('', '?'))[1]})",
        )
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel("σ(τ) (°/s)")
    ax.grid(True, which="both", color="#e3e7eb", linewidth=0.6)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(loc="best", fontsize=8, frameon=False)
    return figure_from_matplotlib(
        fig,
        "Allan deviation and noise terms",
        f"Column {r.column}, {r.samples} samples at {r.fs_hz:.6g} Hz ({r.duration_s / 3600:.3g} h). "
        "Dashed: the IEEE Std 952 lines fitted where each slope dominates.",
    )


def noise_section(r: GyroNoise, title: str = "Gyro noise (IEEE Std 952)") -> Section:
    """Noise-term table with intervals, and the Allan deviation figure."""
    rows = []
    for name, term in r.terms.terms.items():
        label, slope, unit, scale = _LABELS.get(name, (name, "", term.unit, 1.0))
        rows.append(
            [
                label,
                slope,
                f"{term.coefficient * scale:.4g} {unit}",
                f"{term.low * scale:.3g} … {term.high * scale:.3g}",
                f"{term.tau_ref_s:.3g} s",
            ]
        )
    if not rows:
        rows.append(["no term identified", "", "", "", ""])
    table = Table(
        ["term", "slope", "value", "IEEE 952 C.4 interval (±1/√(2(N/m−1)))", "read at τ"],
        rows,
        caption="Noise terms",
    )
    paragraphs = list(r.notes)
    if r._budgets:
        paragraphs.append(
            "Uncertainty budgets: each term's Type A standard uncertainty is the ±1σ χ² interval "
            "of the reading it comes from — the level of the line fitted through correlated "
            "points of the curve (equivalent degrees of freedom for the term's own noise type), "
            "or the one point of the flat minimum for B — rather than IEEE 952 C.4's rule of "
            "thumb in the table above. The slope method's own bias (other terms adding to the "
            "fitted points, the minimum of noisy points) is not in u; each budget's notes give "
            "an upper estimate of the first part."
        )
    return Section(
        title=title,
        paragraphs=paragraphs,
        tables=[table, *budget_tables(r._budgets)],
        figures=[_figure(r)],
    )
