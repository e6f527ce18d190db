"""Report sections for the multi-head encoder: self-calibration and constant-rate stability (seed 004)."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.encoder.selfcal import SelfCalibration
from rotacal.errors import ConfigError
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.motion import _fmt, _style
from rotacal.report.uncertainty import budget_tables
from rotacal.table.rate import RateResult
from rotacal.uncertainty import UncertaintyBudget

__all__ = ["rate_section", "selfcal_section"]

_MEAN = "#1f5f99"
_REV = "#9aa7b4"
_BAD = "#b22222"
_RAW = "#d2691e"
#: FMVSS 126 accuracy requirement of a gyro (seed 004, Table 1), as a fraction of full scale.
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
        f"{r.deviation_pp_arcsec:.3g} arcsec (the seed's Figure 4). Orders that are multiples of "
        f"{r.heads} are not in this curve.",
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
        "Order 1 is the eccentricity of the scale against the axis. Shaded orders cannot be "
        "measured by equal-division averaging and are zero here by construction.",
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
        f"One revolution's curve minus the mean of all {r.revolutions_used} (the seed's Figure 5), "
        f"and the spread of every revolution; rms {_fmt(r.repeatability_rms_arcsec, 3)} arcsec.",
    )


def selfcal_section(r: SelfCalibration, title: str = "Self-calibration of the encoder") -> Section:
    """Results, head placement and the three figures of a self-calibration."""
    rows = [
        ["heads × pulses per revolution", f"{r.heads} × {r.pulses_per_rev}"],
        ["whole revolutions averaged", str(r.revolutions_used)],
        ["deviation, peak-to-peak", f"{r.deviation_pp_arcsec:.4g} arcsec"],
        ["deviation, rms", f"{r.deviation_rms_arcsec:.4g} arcsec"],
        ["repeatability, rms (revolution − mean)", f"{_fmt(r.repeatability_rms_arcsec, 3)} arcsec"],
        [
            "standard uncertainty of every point of the curve",
            f"{_fmt(r.deviation_u_arcsec, 2)} arcsec"
            + (
                f" (U = {r.point_budget.U:.2g} arcsec, k = {r.point_budget.k:.3g})"
                if r.point_budget is not None
                else ""
            ),
        ],
        *(
            _summary_row(label, r.budgets.get(key), bias, corrected, "arcsec", 4)
            for label, key, bias, corrected in (
                (
                    "peak-to-peak",
                    "deviation_pp_arcsec",
                    r.deviation_pp_arcsec_bias,
                    r.deviation_pp_arcsec_bias_corrected,
                ),
                (
                    "rms",
                    "deviation_rms_arcsec",
                    r.deviation_rms_arcsec_bias,
                    r.deviation_rms_arcsec_bias_corrected,
                ),
            )
        ),
        [
            "closure residual of the head differences (rms)",
            f"{r.closure_residual_rms_arcsec:.3g} arcsec",
        ],
        [
            "sense of rotation",
            f"{r.rotation} (head i lies i·360/n {'ahead' if r.rotation == 'forward' else 'behind'})",
        ],
    ]
    heads = Table(
        ["head", "nominal position (°)", "placement error (arcsec, modulo one pitch)"],
        [
            [f"head_{i}", f"{i * 360 / r.heads:.3f}", f"{off:+.3f}"]
            for i, off in enumerate(r.head_offsets_arcsec)
        ],
        caption="Head placement found from the mean time offsets",
    )
    figures = [_deviation_figure(r), _spectrum_figure(r)]
    rep = _repeatability_figure(r)
    if rep is not None:
        figures.append(rep)
    tables = [Table(["quantity", "value"], rows, caption="Results"), heads]
    if r.point_budget is not None:
        tables.append(_point_table(r.point_budget))
    tables.extend(budget_tables(r.budgets))
    return Section(
        title=title,
        paragraphs=[r.undetectable_harmonics_note, *r.notes],
        tables=tables,
        figures=figures,
    )


def _summary_row(
    label: str,
    b: UncertaintyBudget | None,
    bias: float | None,
    corrected: float | None,
    unit: str,
    digits: int,
) -> list[str]:
    """One results row of a biased, bounded summary: the interval for the true value, the bias."""
    if b is None or b.interval is None:
        return [f"{label}: 95 % interval for the true value", "—"]
    lo, hi = b.interval
    try:  # the limits to the decimal place of U, as ILAC-P14 rounds a value (§5.4)
        big_u = b.rounded()[1]
        dec = len(big_u.split(".")[1]) if "." in big_u else 0
        text = f"{lo:.{dec}f} … {hi:.{dec}f} {unit}"
        fmt = f".{dec}f"
    except ConfigError:  # U = 0
        text, fmt = f"{lo:.{digits}g} … {hi:.{digits}g} {unit}", f".{digits}g"
    if bias is not None and corrected is not None:
        text += f" (noise bias {bias:+.2g} {unit}; bias-corrected {corrected:{fmt}} {unit})"
    else:
        text += " (no noise of known level: not bias-corrected)"
    return [f"{label}: 95 % interval for the true value", text]


def _point_table(b: UncertaintyBudget) -> Table:
    """The budget of one point of the deviation curve (the same at every line)."""
    header, rows = b.table()
    notes = " ".join(b.notes)
    return Table(
        header,
        rows,
        caption=(
            f"Uncertainty budget of each point of the deviation curve ({b.method}): "
            f"u = {b.u:.2g} arcsec, U = {b.U:.2g} arcsec (k = {b.k:.3g}, p ≈ {100 * b.p:g} %) "
            f"at every line. {notes}"
        ),
    )


def _allan_table(r: RateResult) -> Table:
    """s(φ) with its χ² uncertainty, one row per angle."""
    names = {2: "white PM", 1: "flicker PM", 0: "white FM", -1: "flicker FM", -2: "random-walk FM"}
    rows = [
        [
            f"{phi:.4g}",
            f"{100 * s:.3g}",
            f"{100 * u:.2g}",
            f"{100 * lo:.3g} … {100 * hi:.3g}",
            f"{edf:.3g}",
            names.get(a, str(a)),
        ]
        for phi, s, u, (lo, hi), edf, a in zip(
            r.allan_angle_deg,
            r.allan_relative,
            r.allan_relative_u,
            r.allan_relative_interval,
            r.allan_relative_edf,
            r.allan_noise_alpha,
            strict=True,
        )
    ]
    return Table(
        ["φ (°)", "s(φ) (%)", "u (%)", "95 % interval (%)", "edf", "noise type assumed"],
        rows,
        caption=(
            "Relative root Allan variance with its uncertainty: ν·ŝ²/s² ~ χ²(ν), ν the equivalent "
            "degrees of freedom of the overlapping estimator for the noise type the local slope "
            "suggests (Greenhall & Riley 2003); u = ŝ/√(2ν). Sinusoidal fluctuations of the table "
            "are no power-law noise: there the edf is an approximation."
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
            label=f"nominal pitch: rms {r.rate_deviation_rms_percent_uncompensated:.2g} %",
        )
        ax.plot(
            t,
            comp,
            color=_MEAN,
            lw=0.6,
            label=f"compensated: rms {r.rate_deviation_rms_percent:.2g} %",
        )
    else:
        ax.plot(t, comp, color=_MEAN, lw=0.6, label=f"rms {r.rate_deviation_rms_percent:.2g} %")
    ax.axhline(0.0, color="#333", lw=0.6)
    ax.set_xlim(0, t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rate − mean (% of rate)")
    ax.legend(loc="upper right", fontsize=8, frameon=False)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Angular velocity over time",
        f"Time-difference rate of {r.head}, averaged over {r.average} pulse intervals, about the "
        f"mean {r.mean_rate_deg_s:.6f} °/s (the seed's Figure 9)"
        + (
            ", before and after compensation with the self-calibrated deviation."
            if r.compensated
            else "."
        ),
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
        f"s(φ) = σ(φ/ω_m)/ω_m at ω_m = {r.mean_rate_deg_s:.4g} °/s (the seed's Figure 10). "
        "White timing noise gives the φ⁻¹ slope at small angles; at 360° the scale's deviation "
        "cancels.",
    )


def _near(phi: list[float], values: list[float], target: float) -> str:
    if not phi:
        return "—"
    i = int(np.argmin(np.abs(np.log(np.asarray(phi) / target))))
    return f"{100 * values[i]:.3g} % at {phi[i]:.4g}°"


def rate_section(r: RateResult, title: str = "Constant-rate stability") -> Section:
    """Mean rate, bias, stability before/after compensation and s(φ), with figures."""
    rows: list[list[Any]] = [
        ["mean rate (whole revolutions)", f"{r.mean_rate_deg_s:.7f} °/s", ""],
    ]
    if r.set_rate_deg_s is not None:
        rows.append(["set rate", f"{r.set_rate_deg_s:.7g} °/s", ""])
        rows.append(
            ["bias (mean − set)", f"{r.rate_bias_deg_s:+.3g} °/s", f"{r.rate_bias_percent:+.3g} %"]
        )
    rows += [
        [
            "rate deviation, rms",
            f"{r.rate_deviation_rms_percent:.3g} %",
            f"{r.rate_deviation_rms_percent_uncompensated:.3g} % uncompensated",
        ],
        [
            "rate deviation, peak",
            f"{r.rate_deviation_peak_percent:.3g} %",
            f"{r.rate_deviation_peak_percent_uncompensated:.3g} % uncompensated",
        ],
        *(
            [*_summary_row(label, r.budgets.get(key), bias, corrected, "%", 3), ""]
            for label, key, bias, corrected in (
                (
                    "rate deviation, rms",
                    "rate_deviation_rms_percent",
                    r.rate_deviation_rms_percent_bias,
                    r.rate_deviation_rms_percent_bias_corrected,
                ),
                (
                    "rate deviation, peak",
                    "rate_deviation_peak_percent",
                    r.rate_deviation_peak_percent_bias,
                    r.rate_deviation_peak_percent_bias_corrected,
                ),
            )
        ),
        ["s(φ) near 10°", _near(r.allan_angle_deg, r.allan_relative, 10.0), ""],
        ["s(φ) near 360°", _near(r.allan_angle_deg, r.allan_relative, 360.0), ""],
        ["record", f"{r.duration_s:.4g} s, {r.revolutions} whole revolution(s)", r.head],
        [
            "timing noise of the pulses (Type A)",
            "—" if r.timing_jitter_s is None else f"{r.timing_jitter_s:.3g} s",
            "" if r.timing_jitter_dof is None else f"ν = {r.timing_jitter_dof:.3g}",
        ],
    ]
    tables = [Table(["quantity", "value", ""], rows, caption="Results")]
    tables.extend(budget_tables(r.budgets))
    if r.allan_relative_u:
        tables.append(_allan_table(r))
    return Section(
        title=title,
        paragraphs=list(r.notes),
        tables=tables,
        figures=[_rate_figure(r), _allan_figure(r)],
    )
