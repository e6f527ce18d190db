"""Report sections and figures for the 3-axis gyro calibrations: the six-position least squares
(IEEE A&E Systems Magazine 2023) and rotations through known angles (Ferraris et al. 1995)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.rotations import RotationCalibration
from rotacal.gyro.triad import TriadResult
from rotacal.numbers import element_of, fixed
from rotacal.references import cite
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_details, result_row
from rotacal.report.wording import (
    diagnostics_table,
    paragraph,
    readable_rows,
    readable_tables,
)

__all__ = ["rotations_figures", "rotations_section", "triad_figures", "triad_section"]

_AXES = "xyz"
_AXIS_COLORS = {"x": "#1f5f99", "y": "#d2691e", "z": "#2e8b57", "0": "#777777"}
_MAX_REJECTED_ROWS = 25
_PLOT_ROWS = 60_000


def _style(ax: Any) -> None:
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def _unit_k(unit: str) -> str:
    return f"{unit or 'output units'}/(°/s)"


def _matrix_table(data: Mapping[str, Any], caption: str, out_names: list[str], unit: str) -> Table:
    """K row by row, each element value ± U (k, p said once per row where they are shared)."""
    rows = [
        [out_names[i], *(element_of(data, "scale_misalignment", (i, j)) for j in range(3))]
        for i in range(3)
    ]
    return Table(
        ["output", "ω_x", "ω_y", "ω_z"],
        rows,
        caption=caption,
        note=f"In {_unit_k(unit)}; each element ± its expanded uncertainty U (k, p as stated).",
    )


def _axis_results(
    data: Mapping[str, Any], out_names: list[str], unit: str, with_axes: bool
) -> list[ResultRow]:
    """Bias and, where their uncertainties are known, |K_i| and the misalignment of each gyro."""
    p = data.get("coverage_probability")
    k = data.get("k", {})
    rows = []
    for i, name in enumerate(out_names):
        rows.append(
            result_row(
                f"bias of {name}",
                data["bias"][i],
                unit or "output units",
                U=data["bias_U"][i],
                k=k["bias"][i],
                p=p,
            )
        )
        if not with_axes:
            continue
        rows.append(
            result_row(
                f"scale factor |K| of {name}",
                data["scale_factors"][i],
                _unit_k(unit),
                U=data["scale_factors_U"][i],
                k=k["scale_factors"][i],
                p=p,
            )
        )
        rows.append(
            result_row(
                f"misalignment of {name}",
                data["misalignment_deg"][i],
                "°",
                U=data["misalignment_deg_U"][i],
                k=k["misalignment_deg"][i],
                p=p,
                note="angle of its sensitive axis to the nominal axis",
            )
        )
    return rows


def _axes_diagnostics(scale: np.ndarray, mis: np.ndarray, out_names: list[str], unit: str) -> Table:
    """|K_i| and the misalignment without uncertainty: diagnostics."""
    return diagnostics_table(
        [
            [
                f"{out_names[i]}: scale factor |K|, misalignment",
                f"{fixed(float(scale[i]), 7)} {_unit_k(unit)}, {fixed(float(mis[i]) * 60, 3)} arcmin",
            ]
            for i in range(3)
        ],
        "scale factors and misalignment (no uncertainty propagated)",
    )


# ------------------------------------------------------------------------------ six positions
def _point_axis(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each rate point: the dominant rotation axis ('x', 'y', 'z', or '0' at rest) and its
    signed rate about it (°/s)."""
    j = np.argmax(np.abs(pts), axis=1)
    rate = pts[np.arange(pts.shape[0]), j]
    label = np.array([_AXES[i] for i in j])
    label[np.all(pts == 0, axis=1)] = "0"
    return label, rate


def _residual_figure(r: TriadResult) -> Figure:
    p = r._plot
    pts = np.asarray(p["points_deg_s"])
    label, rate = _point_axis(pts)
    count = np.asarray(p["point_rows"], dtype=float)
    ok = count > 0
    before = np.asarray(p["point_before_deg_s"])
    after = np.asarray(p["point_after_deg_s"])
    sem = np.asarray(p["point_after_std_deg_s"]) / np.sqrt(np.maximum(count, 1.0))[:, None]
    # the three rotation axes share the same rates: dodge them sideways to keep all visible
    span = float(np.ptp(rate)) if rate.size else 1.0
    dodge = {"x": -0.012 * span, "y": 0.0, "z": 0.012 * span, "0": 0.0}
    face = "u" if r.nominal_scale == 1 else f"u/{r.nominal_scale:g}"
    fig, axes = plt.subplots(2, 3, figsize=(12.0, 6.4), sharex=True)
    for j in range(3):
        for row, vals in enumerate((before, after)):
            ax = axes[row, j]
            if row == 1:  # ±1σ of single samples after calibration: the noise floor
                ax.axhspan(
                    -r.residual_rms[j],
                    r.residual_rms[j],
                    color="#eef1f4",
                    zorder=0,
                    label="±rms of single samples",
                )
            for a in ("x", "y", "z", "0"):
                sel = ok & (label == a)
                if not sel.any():
                    continue
                name = "at rest" if a == "0" else f"rotation about {a}"
                x = rate[sel] + dodge[a]
                if row == 0:
                    ax.plot(x, vals[sel, j], "o", ms=4.5, color=_AXIS_COLORS[a], label=name)
                else:
                    ax.errorbar(
                        x,
                        vals[sel, j],
                        yerr=sem[sel, j],
                        fmt="o",
                        ms=4.5,
                        lw=1.0,
                        capsize=2,
                        color=_AXIS_COLORS[a],
                        label=name,
                    )
            ax.axhline(0.0, color="#999", lw=0.7)
            if row == 0:
                title = f"axis {_AXES[j]}: {face} − ω, rms {fixed(r.residual_rms_before[j], 3)} °/s"
            else:
                title = f"axis {_AXES[j]}: ω̂ − ω, rms {fixed(r.residual_rms[j], 3)} °/s"
            ax.set_title(title, fontsize=9.5)
            if j == 0:
                ax.set_ylabel(("before" if row == 0 else "after") + " calibration (°/s)")
            if row == 1:
                ax.set_xlabel("rate about the rotation axis (°/s)")
            _style(ax)
    handles, labels = axes[1, 0].get_legend_handles_labels()
    fig.legend(
        handles,
        labels,
        loc="lower center",
        ncols=len(labels),
        frameon=False,
        fontsize=9,
        bbox_to_anchor=(0.5, -0.02),
    )
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return figure_from_matplotlib(
        fig,
        "Residuals before and after calibration",
        "Mean residual of each rate point per axis. Top: raw outputs at face value. Bottom: after "
        f"ω̂ = K⁻¹(u − b) ({cite('robot2023')}, eq. 7), ± the standard error; band: ± single-sample rms.",
    )


def _rejection_figure(r: TriadResult) -> Figure:
    p = r._plot
    res = np.asarray(p["fit_residual"])
    keep = np.asarray(p["keep"])
    names = list(p["columns"])[3:]
    n = res.shape[0]
    step = max(1, n // _PLOT_ROWS)
    idx = np.arange(n)
    fig, axes = plt.subplots(3, 1, figsize=(11.0, 6.6), sharex=True)
    for c, ax in enumerate(axes):
        thr = float(r.reject_k * r.robust_sigma[c])
        kc = keep[:, c]
        ax.plot(idx[kc][::step], res[kc, c][::step], ".", ms=1.5, color="#5a6b7b", alpha=0.5)
        lim = 1.8 * thr if np.isfinite(thr) and thr > 0 else float(np.max(np.abs(res[kc, c])))
        lim = lim if lim > 0 else 1.0
        rej = np.flatnonzero(~kc)
        if rej.size:
            v = res[rej, c]
            inside = np.abs(v) <= 0.95 * lim
            label: str | None = f"rejected ({rej.size})"
            for sel, marker, y in (
                (inside, "x", v),
                (~inside & (v > 0), "^", np.full(rej.size, 0.93 * lim)),
                (~inside & (v < 0), "v", np.full(rej.size, -0.93 * lim)),
            ):
                if sel.any():
                    ax.plot(rej[sel], y[sel], marker, ms=4.5, color="#b22222", label=label)
                    label = None
        if np.isfinite(thr) and thr > 0:
            ax.axhline(thr, color="#b22222", lw=0.8, ls="--", label=f"±k·σ = ±{fixed(thr, 3)}")
            ax.axhline(-thr, color="#b22222", lw=0.8, ls="--")
        ax.set_ylim(-lim, lim)
        ax.set_ylabel(f"{names[c]} residual")
        if ax.get_legend_handles_labels()[0]:  # nothing rejected and no threshold: no legend
            ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=8, frameon=False)
        _style(ax)
    axes[-1].set_xlabel("row of the capture")
    fig.tight_layout()
    k_text = fixed(r.reject_k, 3) if np.isfinite(r.reject_k) else "∞"
    return figure_from_matplotlib(
        fig,
        "Least-squares residuals and rejected measurements",
        f"u − (K·ω + b) per output. Dashed: ±k·σ (k = {k_text}, σ = 1.4826·MAD); red: rejected, "
        "triangles: off the scale (listed in the table and the JSON).",
    )


def triad_figures(r: TriadResult) -> list[Figure]:
    """The figures of a six-position triad calibration, in reading order."""
    return [_residual_figure(r), _rejection_figure(r)]


def triad_section(r: TriadResult, title: str | None = None, *, figures: bool = True) -> Section:
    """A report section for a 3-axis calibration (Wang et al. 2023): K and b with U, |K_i| and the
    misalignment with U, residuals, rejections, the budgets folded."""
    out = list(r._plot.get("columns", ("", "", "", "ux", "uy", "uz")))[3:]
    data = r.to_dict()
    unit = r.output_unit
    plan = r.plan
    tables = [
        _matrix_table(data, "Scale/misalignment matrix K in u = K·ω + b", out, unit),
        Table(
            ["axis", "before (°/s)", "after (°/s)", f"fit residual ({unit or 'output units'})"],
            [
                [
                    _AXES[i],
                    fixed(r.residual_rms_before[i], 4),
                    fixed(r.residual_rms[i], 4),
                    fixed(r.fit_residual_rms[i], 4),
                ]
                for i in range(3)
            ],
            caption="Residual rms per axis (diagnostics, not results)",
        ),
        diagnostics_table(
            [
                ["rows / rows kept in all outputs", f"{r.rows} / {r.rows_used}"],
                ["rate points", str(r.points)],
                ["rank of the plan's matrix A", f"{plan.rank} of 4"],
                [
                    "condition number of A (as built / rows scaled)",
                    f"{fixed(plan.condition_number, 4)} / {fixed(plan.condition_number_scaled, 4)}",
                ],
                [
                    "rejection threshold k (robust σ)",
                    fixed(r.reject_k, 3) if np.isfinite(r.reject_k) else "off",
                ],
                ["robust σ per output", ", ".join(fixed(s, 3) for s in r.robust_sigma)],
                ["rows with a rejected output", str(r.outliers_rejected)],
            ],
            "plan and outlier rejection",
        ),
    ]
    if r.rejected:
        shown = r.rejected[:_MAX_REJECTED_ROWS]
        rows = [
            [str(e["row"]), e["column"], fixed(e["residual"], 4), fixed(e["threshold"], 3)]
            for e in shown
        ]
        more = len(r.rejected) - len(shown)
        tables.append(
            Table(
                ["row", "output", "residual", "threshold k·σ"],
                rows,
                caption="Rejected measurements"
                + (f" (first {len(shown)}; {more} more in the JSON)" if more else ""),
            )
        )
    paragraphs = [
        f"Modified six-position method ({cite('robot2023')}): the outputs fill U, the reference "
        "rates with a row of ones fill A (eq. 5), [K | b] solves U = [K | b]·A by least squares "
        "(eq. 4). Anomalous measurements are rejected per output (|r| > k·1.4826·MAD). "
        "Uncertainties: the least-squares covariance (Type A) and, when stated, the table's "
        "set-rate error (Type B); |K_i| and the misalignment propagate the covariance of row i "
        f"(GUM law of propagation; the split K = diag(s)·R of {cite('ferraris1995')}).",
        *(paragraph(n) for n in r.notes),
    ]
    return Section(
        title=title or "3-axis gyro calibration",
        paragraphs=paragraphs,
        tables=tables,
        figures=triad_figures(r) if figures else [],
        anchor="gyro-triad",
        results=readable_rows(_axis_results(data, out, unit, with_axes=True)),
        details=readable_tables(budget_details({**r._budgets, **r.axis_budgets})),
        references=["robot2023", "ferraris1995", "gum"],
    )


# ------------------------------------------------------------------------------------ rotations
def _recording_figure(r: RotationCalibration) -> Figure:
    p = r._plot
    rate = np.asarray(p["rate"])
    n = rate.shape[0]
    t = np.arange(n) / r.fs_hz
    step = max(1, n // _PLOT_ROWS)
    fig, ax = plt.subplots(figsize=(11.0, 3.6))
    for c, a in enumerate(_AXES):
        ax.plot(t[::step], rate[::step, c], lw=0.8, color=_AXIS_COLORS[a], label=f"u{a}")
    first = True
    for _, s, e in p["static"]:
        ax.axvspan(
            s / r.fs_hz,
            e / r.fs_hz,
            color="#e8ecef",
            zorder=0,
            label="static (bias)" if first else None,
        )
        first = False
    for label, s, e in p["rotations"]:
        ax.axvspan(s / r.fs_hz, e / r.fs_hz, color="#f2f5d8", zorder=0)
        ax.annotate(
            f"about {label}",
            (0.5 * (s + e) / r.fs_hz, 1.0),
            xycoords=("data", "axes fraction"),
            ha="center",
            va="bottom",
            fontsize=8,
        )
    ax.set_xlabel("time (s)")
    ax.set_ylabel("raw output")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncols=4, fontsize=8, frameon=False)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Recording and its sections",
        "Raw outputs; grey: static sections (bias and noise); yellow: rotations through the set "
        "angle, integrated to give K.",
    )


def rotations_figures(r: RotationCalibration) -> list[Figure]:
    """The figures of a rotation (Ferraris-style) calibration."""
    return [_recording_figure(r)]


def rotations_section(
    r: RotationCalibration,
    title: str | None = None,
    *,
    reference: Mapping[str, Any] | None = None,
    figures: bool = True,
) -> Section:
    """A report section for a calibration from rotations through known angles.

    ``reference``: another program's result for the same recording, shown beside rotacal's:
    ``{"label": "imucal 2.6.0", "scale_misalignment": K (3×3), "bias": b (3)}``.
    """
    out = ["ux", "uy", "uz"]
    data = r.to_dict()
    unit = r.output_unit
    tables = [
        _matrix_table(data, "Scale/misalignment matrix K in u = K·ω + b", out, unit),
        _axes_diagnostics(r.scale_factors, r.misalignment_deg, out, unit),
        Table(
            ["rotation", "samples", "duration (s)", "set angle (°)", "integrated output (u·s)"],
            [
                [
                    f"about {rot['axis']}",
                    str(rot["samples"]),
                    fixed(rot["duration_s"], 6),
                    fixed(rot["angle_deg"]),
                    ", ".join(fixed(v, 5) for v in rot["integrated_output"]),
                ]
                for rot in r.rotations
            ],
            caption="Rotations",
        ),
    ]
    if "g_sensitivity" in data:  # gyro.ferraris: K_ga separated from K
        tables.insert(
            1,
            Table(
                ["output", "a_x", "a_y", "a_z"],
                [
                    [out[i], *(element_of(data, "g_sensitivity", (i, j)) for j in range(3))]
                    for i in range(3)
                ],
                caption="g-sensitivity K_ga in u = K·(ω + Ω_E) + b + K_ga·a",
                note=f"In {unit or 'output units'}/(m/s²); each element ± its expanded U.",
            ),
        )
    if reference is not None:
        kref = np.asarray(reference["scale_misalignment"], dtype=float)
        bref = np.asarray(reference["bias"], dtype=float)
        lab = str(reference.get("label", "reference"))
        rows = [
            [
                out[i],
                ", ".join(fixed(v, 2) for v in r.scale_misalignment[i] - kref[i]),
                ", ".join(fixed(v, 2) for v in r.scale_misalignment_u[i]),
                fixed(r.bias[i] - bref[i], 2),
            ]
            for i in range(3)
        ]
        tables.append(
            Table(
                ["output", "ΔK (row)", "u(K) (row)", "Δb"],
                rows,
                caption=f"rotacal minus {lab}",
            )
        )
    paragraphs = [
        f"{cite('ferraris1995')}: the rate minus the bias (from the static sections) is "
        "integrated over each rotation; the integrated vectors against the set angles give "
        "K = Θ·Φᵀ(Φ·Φᵀ)⁻¹. Uncertainties: white noise of the static sections integrated over "
        "each rotation, the bias subtracted and the offset change during the rotations (spread "
        f"of the static means), {fixed(r.angle_u_deg * 3600, 3)}″ on each realised angle, and the DAQ "
        "timebase when stated; one budget per element of K and b below."
    ]
    if "g_sensitivity" in data:
        paragraphs.append(
            "With the accelerometer (gyro.ferraris): K_ga from the six static positions, less "
            "the vertical Earth rate at the stated latitude; b + K_ga·a is removed sample by "
            "sample before the rotations are integrated, and the Earth's turn is added to each "
            "set angle. The offset's uncertainties come from the positions' noise and the "
            "horizontal Earth rate (heading not recorded), not from the spread of the static "
            "means."
        )
    paragraphs += [paragraph(n) for n in r.notes]
    return Section(
        title=title or "Gyro triad from rotations through known angles",
        paragraphs=paragraphs,
        tables=tables,
        figures=rotations_figures(r) if figures else [],
        anchor="gyro-rotations",
        results=readable_rows(_axis_results(data, out, unit, with_axes=False)),
        details=readable_tables(budget_details(r._budgets)),
        references=["ferraris1995", "gum"],
    )
