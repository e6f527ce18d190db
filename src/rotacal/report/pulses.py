"""Report sections for the multi-head encoder: self-calibration and constant-rate stability.

The method is Kokuyama et al. (2015): the scale deviation by equal-division averaging of the heads,
and the table's rate and its relative root Allan variance from the pulse times.
"""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.encoder.selfcal import SelfCalibration
from rotacal.numbers import coverage, fixed, format_plain, format_quantity
from rotacal.references import cite
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.motion import _style
from rotacal.report.uncertainty import (
    budget_details,
    budget_results,
    budget_table,
    result_row,
    verdict,
    verdict_note,
)
from rotacal.report.wording import diagnostics_table, paragraph, readable_rows, readable_tables
from rotacal.table.rate import RateResult
from rotacal.uncertainty import UncertaintyBudget

__all__ = ["rate_section", "selfcal_section"]

_MEAN = "#1f5f99"
_REV = "#9aa7b4"
_BAD = "#b22222"
_RAW = "#d2691e"
#: FMVSS 126 accuracy requirement of a gyro (Kokuyama et al. 2015, Table 1), a fraction of FS.
_FMVSS126_ACCURACY = 0.05e-2


def _deviation_figure(r: SelfCalibration) -> Figure:
    m = r.pulses_per_rev
    angle = np.arange(m) * 360.0 / m
    fig, ax = plt.subplots(figsize=(9.5, 3.6))
    step = max(1, m // 4000)  # enough points to draw every feature without a huge PNG
    for k, curve in enumerate(r.per_revolution_arcsec):
        ax.plot(
            angle[::step],
            curve[::step],
            color=_REV,
            lw=0.6,
            label="single revolutions" if k == 0 else None,
        )
    ax.plot(
        angle[::step],
        r.deviation_arcsec[::step],
        color=_MEAN,
        lw=1.3,
        label=f"mean of {r.revolutions_used} revolution(s)",
    )
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("angle from head 0's first pulse (°)")
    ax.set_ylabel("deviation (arcsec)")
    ax.legend(loc="upper right", fontsize=8, frameon=False)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Scale deviation",
        f"{r.pulses_per_rev} pulses per revolution, {r.heads} heads; peak-to-peak "
        f"{fixed(r.deviation_pp_arcsec, 3)} arcsec (as {cite('kokuyama2015')}, Figure 4).",
    )


def _spectrum_figure(r: SelfCalibration) -> Figure:
    amp = r.spectrum_arcsec
    top = min(amp.size - 1, max(4 * r.heads + 4, 40))
    orders = np.arange(1, top + 1)
    fig, ax = plt.subplots(figsize=(9.5, 3.3))
    floor = max(float(amp[1:].max()) * 1e-6, 1e-9)
    ax.vlines(orders, floor, np.maximum(amp[1 : top + 1], floor), color=_MEAN, lw=2.2)
    undetect = [q for q in r.undetectable_orders if q <= top]
    for i, q in enumerate(undetect):
        ax.axvspan(
            q - 0.45,
            q + 0.45,
            color=_BAD,
            alpha=0.15,
            lw=0,
            label="undetectable order (multiple of the number of heads)" if i == 0 else None,
        )
    ax.set_yscale("log")
    ax.set_ylim(floor, float(amp[1:].max()) * 3)
    ax.set_xlim(0.3, top + 0.7)
    ax.set_xlabel("Fourier order (per revolution)")
    ax.set_ylabel("amplitude (arcsec)")
    if undetect:
        ax.legend(loc="upper right", fontsize=8, frameon=False)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Harmonic spectrum of the deviation",
        "Order 1 is the scale's eccentricity. Shaded orders cannot be measured by "
        "equal-division averaging (zero by construction).",
    )


def _repeatability_figure(r: SelfCalibration) -> Figure | None:
    if r.revolutions_used < 2:
        return None
    m = r.pulses_per_rev
    rep = r.repeatability_arcsec
    # the spread over revolutions, binned to ~0.5° so that the band reads as an envelope
    bins = max(1, m // 720)
    usable = (m // bins) * bins
    spread = rep[:, :usable].reshape(rep.shape[0], -1, bins)
    std = np.sqrt(np.mean(spread**2, axis=(0, 2)) * rep.shape[0] / (rep.shape[0] - 1))
    centres = (np.arange(std.size) + 0.5) * bins * 360.0 / m
    angle = np.arange(m) * 360.0 / m
    step = max(1, m // 4000)
    fig, ax = plt.subplots(figsize=(9.5, 3.2))
    ax.fill_between(
        centres,
        -2 * std,
        2 * std,
        color=_REV,
        alpha=0.35,
        lw=0,
        label=f"±2 s.d. over the {r.revolutions_used} revolutions",
    )
    ax.plot(angle[::step], rep[0, ::step], lw=0.6, color=_MEAN, label="revolution 1 − mean")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("angle from head 0's first pulse (°)")
    ax.set_ylabel("revolution − mean (arcsec)")
    ax.legend(loc="upper right", fontsize=8, frameon=False, ncol=2)
    lim = float(np.max(np.abs(rep[0]))) * 1.35
    ax.set_ylim(-lim, lim)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Repeatability",
        f"One revolution minus the mean of all {r.revolutions_used}, and their spread; rms "
        f"{fixed(r.repeatability_rms_arcsec, 3)} arcsec (as {cite('kokuyama2015')}, Figure 5).",
    )


def _point_row(b: UncertaintyBudget) -> ResultRow:
    """The curve's uncertainty as one summary row: the same U at every line of the scale."""
    u_text = format_quantity(0.0, "arcsec", U=b.U, k=b.k, p=b.p).split("±", 1)[-1].strip()
    return ResultRow(
        quantity="scale deviation, each point of the curve",
        value=f"curve in the figure, ± {u_text.split(' (')[0]}",
        coverage=coverage(b.k, b.p).strip("()"),
        note="the same U at every line",
    )


def _head_table(r: SelfCalibration) -> Table:
    """Each head's placement error with its U (Type A over the revolutions)."""
    us = r.head_offsets_arcsec_U
    k = r.head_offsets_k
    rows = []
    for i, off in enumerate(r.head_offsets_arcsec):
        if i == 0:
            placement = "0 (the reference)"
        else:
            placement = format_quantity(off, "arcsec", U=None if us is None else us[i], k=k, p=0.95)
        rows.append([f"head {i}", fixed(i * 360 / r.heads, 6), placement])
    return Table(
        ["head", "nominal position (°)", "placement error, modulo one pitch"],
        rows,
        caption="Head placement found from the mean time offsets",
        note=(
            "U from the spread of the revolutions' mean head differences (Type A, "
            f"ν = {r.revolutions_used - 1})."
            if us is not None
            else "One whole revolution: the placement errors have no uncertainty from the data."
        ),
    )


def _bias_text(bias: float | None, corrected: float | None) -> str:
    if bias is None or corrected is None:
        return "not known (one revolution: the noise is unknown)"
    return f"noise bias {fixed(bias, 2)} arcsec; less that bias {fixed(corrected, 4)} arcsec"


def selfcal_section(r: SelfCalibration, title: str = "Self-calibration of the encoder") -> Section:
    """Results (peak-to-peak and rms with their coverage intervals, the curve's U), head
    placement with U, diagnostics, the three figures, and the budgets folded."""
    results = readable_rows(budget_results(r.budgets))
    if r.point_budget is not None:
        results.append(_point_row(r.point_budget))
    diagnostics = diagnostics_table(
        [
            ["heads × pulses per revolution", f"{r.heads} × {r.pulses_per_rev}"],
            ["whole revolutions averaged", str(r.revolutions_used)],
            [
                "repeatability, rms (revolution − mean)",
                format_plain(r.repeatability_rms_arcsec, "arcsec", digits=3),
            ],
            [
                "peak-to-peak",
                _bias_text(r.deviation_pp_arcsec_bias, r.deviation_pp_arcsec_bias_corrected),
            ],
            ["rms", _bias_text(r.deviation_rms_arcsec_bias, r.deviation_rms_arcsec_bias_corrected)],
            [
                "closure residual of the head differences, rms",
                format_plain(r.closure_residual_rms_arcsec, "arcsec", digits=3),
            ],
            [
                "sense of rotation",
                f"{r.rotation} (head i lies i·360/n {'ahead' if r.rotation == 'forward' else 'behind'})",
            ],
        ]
    )
    figures = [_deviation_figure(r), _spectrum_figure(r)]
    rep = _repeatability_figure(r)
    if rep is not None:
        figures.append(rep)
    details = []
    if r.point_budget is not None:
        details.append(_point_table(r.point_budget))
    details.extend(budget_details(r.budgets))
    return Section(
        title=title,
        paragraphs=[
            f"Equal-division averaging of {r.heads} read heads ({cite('kokuyama2015')}, §3). "
            + r.undetectable_harmonics_note[:1].upper()
            + r.undetectable_harmonics_note[1:],
            *(paragraph(n) for n in r.notes),
        ],
        tables=[_head_table(r), diagnostics],
        figures=figures,
        results=results,
        details=readable_tables(details),
        references=["kokuyama2015", "gum", "gum_s1"],
        anchor="selfcal",
    )


def _point_table(b: UncertaintyBudget) -> Table:
    """The budget of one point of the deviation curve (the same at every line)."""
    table = budget_table(b)
    table.caption = "Uncertainty budget of each point of the deviation curve"
    table.note = (
        f"Every line: {format_quantity(0.0, 'arcsec', U=b.U, k=b.k, p=b.p).split('±', 1)[-1].strip()}"
        f" ({b.method}). {' '.join(b.notes)}"
    )
    return table


def _allan_table(r: RateResult) -> Table:
    """s(φ) with its 95 % interval, one row per angle."""
    names = {2: "white PM", 1: "flicker PM", 0: "white FM", -1: "flicker FM", -2: "random-walk FM"}
    rows = [
        [
            fixed(phi, 4),
            format_quantity(
                100 * s_, "%", U=100 * (hi - lo) / 2, p=0.95, interval=(100 * lo, 100 * hi)
            ),
            fixed(edf, 3),
            names.get(a, str(a)),
        ]
        for phi, s_, (lo, hi), edf, a in zip(
            r.allan_angle_deg,
            r.allan_relative,
            r.allan_relative_interval,
            r.allan_relative_edf,
            r.allan_noise_alpha,
            strict=True,
        )
    ]
    return Table(
        ["φ (°)", "s(φ)", "equivalent degrees of freedom", "noise type assumed"],
        rows,
        caption="Relative root Allan variance with its 95 % interval",
        note=(
            "ν·ŝ²/s² follows χ²(ν), ν the equivalent degrees of freedom of the overlapping "
            f"estimator for the noise type the local slope suggests ({cite('greenhall2003')}). "
            "Sinusoidal fluctuations of the table are no power-law noise: there ν is an "
            "approximation."
        ),
    )


def _rate_figure(r: RateResult) -> Figure:
    t = r.time_s - r.time_s[0]
    raw = 100.0 * (r.rate_uncompensated_deg_s - r.mean_rate_deg_s) / r.mean_rate_deg_s
    comp = 100.0 * (r.rate_deg_s - r.mean_rate_deg_s) / r.mean_rate_deg_s
    fig, ax = plt.subplots(figsize=(9.5, 3.6))
    if r.compensated:
        ax.plot(
            t,
            raw,
            color=_RAW,
            lw=0.5,
            alpha=0.7,
            label=f"nominal pitch: rms {fixed(r.rate_deviation_rms_percent_uncompensated, 2)} %",
        )
        ax.plot(
            t,
            comp,
            color=_MEAN,
            lw=0.6,
            label=f"compensated: rms {fixed(r.rate_deviation_rms_percent, 2)} %",
        )
    else:
        ax.plot(
            t, comp, color=_MEAN, lw=0.6, label=f"rms {fixed(r.rate_deviation_rms_percent, 2)} %"
        )
    ax.axhline(0.0, color="#333", lw=0.6)
    ax.set_xlim(0, t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rate − mean (% of rate)")
    ax.legend(loc="upper right", fontsize=8, frameon=False)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Angular velocity over time",
        f"Rate of {r.head.replace('_', ' ')} over {r.average} pulse intervals about its mean "
        f"{fixed(r.mean_rate_deg_s, 7)} °/s"
        + (", before and after compensation" if r.compensated else "")
        + f" (as {cite('kokuyama2015')}, Figure 9).",
    )


def _allan_figure(r: RateResult) -> Figure:
    phi = np.asarray(r.allan_angle_deg)
    fig, ax = plt.subplots(figsize=(7.5, 4.4))
    if r.compensated:
        ax.loglog(
            phi, r.allan_relative_uncompensated, "o-", ms=3, color=_RAW, lw=1, label="nominal pitch"
        )
    ax.loglog(
        phi,
        r.allan_relative,
        "o-",
        ms=3,
        color=_MEAN,
        lw=1.2,
        label="compensated" if r.compensated else "s(φ)",
    )
    ax.axhline(
        _FMVSS126_ACCURACY, color=_BAD, ls="--", lw=0.9, label="0.05 % (FMVSS 126 gyro accuracy)"
    )
    ax.set_xlabel("rotation angle φ (°)")
    ax.set_ylabel("relative root Allan variance s(φ)")
    ax.legend(loc="lower left", fontsize=8, frameon=False)
    ax.grid(True, which="both", color="#e3e7eb", linewidth=0.6)
    ax.spines[["top", "right"]].set_visible(False)
    rate = abs(r.mean_rate_deg_s)

    def to_tau(x: Any) -> Any:
        return np.asarray(x) / rate

    def to_phi(x: Any) -> Any:
        return np.asarray(x) * rate

    secax = ax.secondary_xaxis("top", functions=(to_tau, to_phi))
    secax.set_xlabel("τ = φ/ω_m (s)")
    return figure_from_matplotlib(
        fig,
        "Relative root Allan variance versus rotation angle",
        f"s(φ) = σ(φ/ω_m)/ω_m at ω_m = {fixed(r.mean_rate_deg_s, 4)} °/s (as "
        f"{cite('kokuyama2015')}, Figure 10); at 360° the scale's deviation cancels.",
    )


def _nearest(phi: list[float], target: float) -> int | None:
    if not phi:
        return None
    return int(np.argmin(np.abs(np.log(np.asarray(phi) / target))))


def _stability_row(r: RateResult) -> ResultRow | None:
    """s(φ) at the angle nearest 360° against FMVSS 126's gyro accuracy (0.05 %).

    Kokuyama et al. (2015) judge the standard by its stability against the accuracy FMVSS 126 asks
    of a gyro: the verdict is a pass when the whole 95 % interval is below it, a fail when it is wholly above,
    inconclusive otherwise (:func:`~rotacal.report.uncertainty.verdict`, ILAC-G8).
    """
    i = _nearest(r.allan_angle_deg, 360.0)
    if i is None:
        return None
    value = 100 * r.allan_relative[i]
    interval = r.allan_relative_interval[i] if r.allan_relative_interval else None
    if interval is None:
        return result_row(
            f"relative root Allan variance at φ = {fixed(r.allan_angle_deg[i], 4)}°",
            value,
            "%",
            note="no interval: the record is too short for one",
        )
    lo, hi = (100 * x for x in interval)
    limit = 100 * _FMVSS126_ACCURACY
    passed = verdict((lo, hi), limit)
    return result_row(
        f"relative root Allan variance at φ = {fixed(r.allan_angle_deg[i], 4)}°",
        value,
        "%",
        U=(hi - lo) / 2,
        p=0.95,
        interval=(lo, hi),
        limit=f"< {fixed(limit)} % ({cite('fmvss126')} gyro accuracy)",
        passed=passed,
        note=verdict_note(passed),
    )


def rate_section(r: RateResult, title: str = "Constant-rate stability") -> Section:
    """Mean rate, bias and the rate's fluctuation with their U, s(φ) with its interval, figures."""
    results = readable_rows(
        budget_results(r.budgets, names={"rate_bias_percent": "rate bias, relative"})
    )
    stability = _stability_row(r)
    if stability is not None:
        results.append(stability)
    rows = []
    if r.set_rate_deg_s is not None:
        rows.append(["set rate", format_plain(r.set_rate_deg_s, "°/s", digits=7)])
    rows += [
        [
            "rate fluctuation, rms, with the nominal pitch",
            format_plain(r.rate_deviation_rms_percent_uncompensated, "%", digits=3),
        ],
        [
            "rate fluctuation, largest, with the nominal pitch",
            format_plain(r.rate_deviation_peak_percent_uncompensated, "%", digits=3),
        ],
        [
            "rate fluctuation, rms: noise bias",
            format_plain(r.rate_deviation_rms_percent_bias, "%", digits=2),
        ],
        [
            "rate fluctuation, largest: noise bias",
            format_plain(r.rate_deviation_peak_percent_bias, "%", digits=2),
        ],
        [
            "record",
            f"{fixed(r.duration_s, 4)} s, {r.revolutions} whole revolution(s), {r.head.replace('_', ' ')}",
        ],
        [
            "timing noise of the pulses (Type A)",
            format_quantity(r.timing_jitter_s, "s", si_prefix=True, digits=3)
            + ("" if r.timing_jitter_dof is None else f", ν = {fixed(r.timing_jitter_dof, 3)}"),
        ],
    ]
    tables = [diagnostics_table(rows)]
    if r.allan_relative_interval:
        tables.append(_allan_table(r))
    return Section(
        title=title,
        paragraphs=[
            f"Rate from the pulse times of one head ({cite('kokuyama2015')}, §4–5)"
            + (", compensated with the self-calibrated scale deviation." if r.compensated else "."),
            *(paragraph(n) for n in r.notes),
        ],
        tables=tables,
        # a capture streamed from its file keeps no record-long rate series to plot
        figures=[*([_rate_figure(r)] if r.time_s.size else []), _allan_figure(r)],
        results=results,
        details=readable_tables(budget_details(r.budgets)),
        references=["kokuyama2015", "fmvss126", "greenhall2003", "gum"],
        anchor="rate",
    )
