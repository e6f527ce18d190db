"""Report section and figure of a continuous rate-table log: the log and its plateaus."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from rotacal.gyro.scale_factor_log import LogScaleFactorResult
from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.gyro_scale import _style
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib

__all__ = ["plateaus_figure", "plateaus_section"]

_C = {"rate": "#1f5f99", "out": "#444444", "used": "#8fd19e", "settle": "#e8e8e8", "rej": "#e4572e"}


def plateaus_figure(r: LogScaleFactorResult) -> Figure:
    """Table rate and DUT output against time; each used plateau shaded green (its settling
    grey), each rejected one hatched red."""
    assert r._log is not None
    t, rate, out = r._log
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9.0, 5.6), sharex=True)
    ax1.plot(t, rate, color=_C["rate"], lw=0.7)
    ax2.plot(t, out, color=_C["out"], lw=0.7)
    first = {"used": True, "settle": True, "rej": True}
    for start, end, _rate, used in r._spans:
        for ax in (ax1, ax2):
            if used:
                ax.axvspan(
                    start - r.settle_s,
                    start,
                    color=_C["settle"],
                    zorder=0,
                    label=f"settling dropped ({fixed(r.settle_s, 3)} s)"
                    if ax is ax1 and first["settle"]
                    else None,
                )
                ax.axvspan(
                    start,
                    end,
                    color=_C["used"],
                    alpha=0.6,
                    zorder=0,
                    label="plateau used" if ax is ax1 and first["used"] else None,
                )
            else:
                ax.axvspan(
                    start,
                    end,
                    facecolor="none",
                    edgecolor=_C["rej"],
                    hatch="///",
                    zorder=0,
                    label="plateau rejected" if ax is ax1 and first["rej"] else None,
                )
        key = "used" if used else "rej"
        first[key] = False
        if used:
            first["settle"] = False
    unit = r.output_unit or "output units"
    ax1.set_ylabel("table rate (°/s)")
    ax2.set_ylabel(f"DUT output ({unit})")
    ax2.set_xlabel("time (s)")
    for ax in (ax1, ax2):
        _style(ax)
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, 1.18), ncols=3, frameon=False)
    fig.align_ylabels((ax1, ax2))
    fig.tight_layout()
    return figure_from_matplotlib(
        fig,
        "The log and its plateaus",
        f"{len(r.plateaus)} plateaus used (green; the settling dropped from each, grey), "
        f"{len(r.plateaus_rejected)} rejected (hatched red); each used plateau is one rate point "
        f"of the line ({cite('kokuyama2015')}, §4).",
    )


def plateaus_section(r: LogScaleFactorResult) -> Section:
    """The plateau table, the detection's settings and the figure."""
    rows = [
        [
            fixed(p["start_s"], 6),
            fixed(p["end_s"], 6),
            fixed(p["rate_deg_s"], 6),
            str(p["samples"]),
            fixed(p["rate_std_deg_s"], 3),
            p.get("reason", "used"),
        ]
        for p in sorted((*r.plateaus, *r.plateaus_rejected), key=lambda p: p["start_s"])
    ]
    det: dict[str, Any] = r.plateau_detection
    return Section(
        title="Plateaus of the continuous log",
        paragraphs=[
            "The table's rate steps between plateaus; a change is where the mean of the next "
            f"{fixed(det.get('window_s'), 3)} s differs from that of the last by more than "
            f"{fixed(det.get('threshold_deg_s'), 3)} °/s (6 standard errors of the table rate's "
            f"noise σ = {fixed(det.get('rate_noise_deg_s'), 3)} °/s, plus 0.001 °/s): the "
            "filtered-derivative detector of Basseville & Nikiforov (1993, §2.1). "
            f"{fixed(r.settle_s, 3)} s are dropped from each plateau's start "
            + (
                "(as given)."
                if r.settle_source == "given"
                else "(the DUT's settling, read from its output)."
            )
        ],
        figures=[plateaus_figure(r)],
        tables=[
            Table(
                ["start (s)", "end (s)", "table rate (°/s)", "samples", "rate σ (°/s)", "use"],
                rows,
                caption="Plateaus (times of the rows used, after settling)",
            )
        ],
        references=["kokuyama2015"],
    )
