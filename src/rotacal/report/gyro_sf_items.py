"""The IEEE Std 952/1431 scale-factor items in the scale-factor report: per sign, runs, temperature."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.scale_factor_result import ScaleFactorResult
from rotacal.numbers import fixed
from rotacal.report.gyro_steps import standard_u_row
from rotacal.report.html import Figure, ResultRow, Table, figure_from_matplotlib

__all__ = ["sf_item_figures", "sf_item_rows", "sf_item_tables"]


def sf_item_rows(r: ScaleFactorResult) -> list[ResultRow]:
    """The items as summary rows, each value ± U with U = 2u (k = 2)."""
    unit = f"{r.output_unit or 'output unit'}/(°/s)"
    rows = []
    sg = r.signed
    if sg is not None:
        rows += [
            standard_u_row(
                "scale factor, positive rates S₊",
                sg.scale_factor_positive,
                sg.scale_factor_positive_u,
                unit,
                note="two slopes, one bias",
            ),
            standard_u_row(
                "scale factor, negative rates S₋",
                sg.scale_factor_negative,
                sg.scale_factor_negative_u,
                unit,
                note="two slopes, one bias",
            ),
            standard_u_row(
                "scale-factor asymmetry (S₊ − S₋)/S",
                sg.asymmetry_ppm,
                sg.asymmetry_ppm_u,
                "ppm",
                note="IEEE Std 528 definition",
            ),
        ]
    rep = r.repeatability
    if rep is not None:
        rows.append(
            standard_u_row(
                "scale-factor repeatability (run to run)",
                rep.scale_factor_repeatability_ppm,
                rep.scale_factor_repeatability_ppm_u,
                "ppm",
                note=f"{rep.runs} runs; u from the number of runs",
            )
        )
    t = r.temperature
    if t is not None:
        note = f"{t.temperature_model} model at {t.temperature_ref_c:.3g} °C"
        rows += [
            standard_u_row(
                "scale-factor temperature coefficient",
                t.scale_factor_temperature_coefficient_ppm_per_c,
                t.scale_factor_temperature_coefficient_ppm_per_c_u,
                "ppm/°C",
                note=note,
            ),
            standard_u_row(
                "bias temperature coefficient",
                t.bias_temperature_coefficient_deg_h_per_c,
                t.bias_temperature_coefficient_deg_h_per_c_u,
                "(°/h)/°C",
                note=note,
            ),
        ]
    return rows


def sf_item_tables(r: ScaleFactorResult) -> list[Table]:
    """The runs' scale factors and the temperature fit's diagnostics."""
    tables = []
    rep = r.repeatability
    if rep is not None:
        tables.append(
            Table(
                ["run", "scale factor S", "u(S)"],
                [
                    [str(i + 1), fixed(s, 8), f"{u:.2g}"]
                    for i, (s, u) in enumerate(
                        zip(rep.run_scale_factors, rep.run_scale_factors_u, strict=True)
                    )
                ],
                caption=f"Runs (their own noise alone would give {rep.within_run_ppm:.3g} ppm)",
            )
        )
    t = r.temperature
    if t is not None:
        p = "—" if t.temperature_f_p is None else f"{t.temperature_f_p:.3g}"
        tables.append(
            Table(
                ["quantity", "value"],
                [
                    [
                        "points / temperature span",
                        f"{t.temperature_points} / {t.temperature_span_c:.3g} °C",
                    ],
                    ["model (F-test p of the quadratic terms)", f"{t.temperature_model} ({p})"],
                    ["Birge ratio √(χ²/ν)", f"{t.temperature_birge_ratio:.3g}"],
                ],
                caption="Temperature fit (diagnostics)",
            )
        )
    return tables


def sf_item_figures(r: ScaleFactorResult) -> list[Figure]:
    """Each run's S relative to their mean (ppm) with ± u, against the run (no runs: none)."""
    rep = r.repeatability
    if rep is None:
        return []
    s = np.array(rep.run_scale_factors)
    u = np.array(rep.run_scale_factors_u)
    mean = float(s.mean())
    fig, ax = plt.subplots(figsize=(7.0, 3.4))
    runs = np.arange(1, s.size + 1)
    ax.errorbar(
        runs,
        1e6 * (s / mean - 1),
        yerr=1e6 * u / abs(mean),
        fmt="o",
        capsize=3,
        color="#1f5f99",
        label="run's S (± u)",
    )
    band = rep.scale_factor_repeatability_ppm
    ax.axhspan(-band, band, color="#f2e3c6", zorder=0, label=f"± repeatability {band:.3g} ppm")
    ax.axhline(0, color="#777", lw=0.7)
    ax.set_xticks(runs)
    ax.set_xlabel("run")
    ax.set_ylabel("S / mean S − 1 (ppm)")
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    return [
        figure_from_matplotlib(
            fig,
            "Scale factor of each run",
            "Run-to-run repeatability: the standard deviation of the runs' scale factors over "
            "their mean (IEEE Std 952-1997 / 1431-2004).",
        )
    ]
