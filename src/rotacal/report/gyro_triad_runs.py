"""Report section and figure of a log of rotation runs (``gyro triad --runs``): the runs, the
whole revolutions averaged, and each run mean's residual from the fitted model."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.triad_log import TriadLogResult
from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.gyro_scale import _style
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib

__all__ = ["runs_figure", "runs_section"]

_C = {
    "rate": "#1f5f99",
    "used": "#8fd19e",
    "rest": "#e4572e",
    "ch": ("#1f5f99", "#e4572e", "#3a8d3a"),
}


def _residuals(r: TriadLogResult) -> np.ndarray:
    """Each run mean less the fitted model K·ω + b (output unit), runs × outputs."""
    w = np.array([run["rate_deg_s"] for run in r.runs])
    u = np.array([run["output_mean"] for run in r.runs])
    return u - (w @ np.asarray(r.scale_misalignment).T + np.asarray(r.bias))


def runs_figure(r: TriadLogResult) -> Figure:
    """|ω| against time with each run's averaged whole revolutions shaded green and its dropped
    remainder hatched; below, each run mean's residual from the fit per output."""
    assert r._log is not None
    t, speed = r._log
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9.0, 5.6))
    ax1.plot(t, speed, color=_C["rate"], lw=0.8)
    first = [True, True]
    for run in r.runs:
        ax1.axvspan(
            run["start_s"],
            run["used_end_s"],
            color=_C["used"],
            alpha=0.6,
            zorder=0,
            label="whole revolutions averaged" if first[0] else None,
        )
        first[0] = False
        if run["end_s"] > run["used_end_s"]:
            ax1.axvspan(
                run["used_end_s"],
                run["end_s"],
                facecolor="none",
                edgecolor=_C["rest"],
                hatch="///",
                zorder=0,
                label="remainder dropped" if first[1] else None,
            )
            first[1] = False
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("|reference rate| (°/s)")
    res = _residuals(r)
    unit = r.output_unit or "output unit"
    idx = np.arange(1, len(r.runs) + 1)
    for j, name in enumerate(("ux", "uy", "uz")):
        ax2.plot(idx, res[:, j], "o", ms=4, color=_C["ch"][j], label=name)
    ax2.axhline(0.0, color="#444444", lw=0.7)
    ax2.set_xlabel("run")
    ax2.set_ylabel(f"run mean − (K·ω + b) ({unit})")
    for ax in (ax1, ax2):
        _style(ax)
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, 1.18), ncols=2, frameon=False)
    ax2.legend(fontsize=8, ncols=3, frameon=False)
    fig.align_ylabels((ax1, ax2))
    fig.tight_layout()
    kept = "over its whole revolutions" if r.averaging == "whole revolutions" else "over all rows"
    return figure_from_matplotlib(
        fig,
        "The rotation runs and their means",
        f"{len(r.runs)} runs, each averaged {kept} (green; the remainder, hatched, dropped) to "
        f"one row of U ({cite('robot2023')}, processing step 1); below, each run mean's "
        "residual from the fitted u = K·ω + b.",
    )


def runs_section(r: TriadLogResult) -> Section:
    """The runs' table and figure."""
    rows = [
        [
            fixed(run["start_s"], 6),
            fixed(run["end_s"], 6),
            ", ".join(fixed(x, 6) for x in run["rate_deg_s"]),
            str(run["revolutions"]),
            fixed(run["remainder_deg"], 4),
            str(run["samples_used"]),
        ]
        for run in r.runs
    ]
    return Section(
        title="Rotation runs of the log",
        paragraphs=[
            "A run is a span of constant, non-zero reference rate. The table angle is the "
            "integrated reference rate; each run is averaged over its whole revolutions only "
            "(the remainder is dropped), which cancels the terms that depend on the DUT's "
            "orientation about the rotation axis — g-sensitivity with a horizontal axis, the "
            "Earth rate across it, a once-per-revolution wobble — as the one-minute runs of "
            f"{cite('robot2023')} do. "
            + (f"{fixed(r.settle_s, 3)} s are dropped from each run's start." if r.settle_s else "")
        ],
        figures=[runs_figure(r)],
        tables=[
            Table(
                ["start (s)", "end (s)", "rate (°/s)", "revolutions", "remainder (°)", "samples"],
                rows,
                caption="Runs (the samples averaged over whole revolutions)",
            )
        ],
    )
