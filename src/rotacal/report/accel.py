"""Report section and figure for the accelerometer triad from six static positions (Ferraris et
al. 1995, eqs. 19–23)."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.accel_triad import AccelTriadCalibration
from rotacal.numbers import element_of, fixed
from rotacal.references import cite
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_details
from rotacal.report.wording import paragraph, readable_tables

__all__ = ["accel_figure", "accel_section"]

_OUT = ("ax", "ay", "az")
_COLORS = ("#1f5f99", "#d2691e", "#2e8b57")


def accel_figure(r: AccelTriadCalibration) -> Figure:
    """The mean raw output of each column in each position, with its bias and the ±g reading
    the calibration predicts."""
    names = [p["name"] for p in r.positions]
    means = np.array([p["mean"] for p in r.positions])  # (6, 3) output unit
    fig, ax = plt.subplots(figsize=(9.0, 3.9), layout="constrained")
    x = np.arange(len(names))
    for c in range(3):
        ax.bar(x + (c - 1) * 0.26, means[:, c], width=0.25, color=_COLORS[c], label=_OUT[c])
        ax.axhline(r.bias[c], color=_COLORS[c], lw=0.8, ls="--")
    ax.set_xticks(x)
    ax.set_xticklabels(names)
    ax.set_xlabel("static position (axis up: _p, down: _a)")
    ax.set_ylabel(f"mean output ({r.output_unit or 'output unit'})")
    ax.grid(True, axis="y", color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(fontsize=8, ncols=3, frameon=False, loc="upper center", bbox_to_anchor=(0.5, -0.2))
    return figure_from_matplotlib(
        fig,
        "Mean output in each static position",
        "Bars: each column's mean in each position; dashed: its bias b_a. The column of the axis "
        f"up reads b_a + K_a·g, down b_a − K_a·g (g = {fixed(r.gravity_m_s2, 7)} m/s²); the "
        "others show the misalignment.",
    )


def accel_section(r: AccelTriadCalibration, title: str | None = None) -> Section:
    """A report section for :func:`~rotacal.gyro.accel_triad.calibrate_accel_triad`."""
    data: dict[str, Any] = r.to_dict()
    unit = r.output_unit or "output unit"
    tables = [
        Table(
            ["output", "a_x", "a_y", "a_z", "K_a", "misalignment (°)", "b_a"],
            [
                [
                    _OUT[i],
                    *(element_of(data, "scale_misalignment", (i, j)) for j in range(3)),
                    element_of(data, "scale_factors", (i,)),
                    fixed(r.misalignment_deg[i], 4),
                    element_of(data, "bias", (i,)),
                ]
                for i in range(3)
            ],
            caption="K_a·R_a, K_a and b_a in u = K_a·R_a·a + b_a",
            note=f"In {unit}/(m/s²) and {unit}; each value ± its expanded uncertainty U.",
        ),
        Table(
            ["position", "samples", "calibrated a (m/s²)", "|a| − g (m/s²)"],
            [
                [
                    p["name"],
                    str(p["samples"]),
                    ", ".join(fixed(v, 6) for v in p["acceleration_m_s2"]),
                    fixed(p["gravity_error_m_s2"], 3),
                ]
                for p in r.positions
            ],
            caption="Static positions",
        ),
    ]
    paragraphs = [
        f"{cite('ferraris1995')}: with each axis up and down, half the sum of the two readings of "
        "that axis is its bias and their difference over 2g a column of K_a·R_a; the row norms "
        "are K_a, the unit rows R_a. Uncertainties: the white noise of each position's mean, "
        "the rounding a quantised output keeps in it, the stated tilt of the positions and u(g)."
    ]
    paragraphs += [paragraph(n) for n in r.notes]
    return Section(
        title=title or "Accelerometer triad from six static positions",
        paragraphs=paragraphs,
        tables=tables,
        figures=[accel_figure(r)],
        anchor="accelerometer-triad",
        details=readable_tables(budget_details(r._budgets)),
        references=["ferraris1995", "gum"],
    )
