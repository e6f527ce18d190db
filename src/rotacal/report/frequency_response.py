"""Bode figure and report section of a gyro's frequency response (``rotacal gyro frequency-response``)."""

from __future__ import annotations

from typing import Any

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.frequency_response import FrequencyResponse
from rotacal.numbers import fixed, format_quantity
from rotacal.references import cite
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import result_row
from rotacal.report.wording import diagnostics_table, paragraph

__all__ = ["bode_figure", "bode_matplotlib", "frequency_response_section"]


def _style(ax: Any) -> None:
    ax.grid(True, which="both", color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def bode_matplotlib(r: FrequencyResponse) -> Any:
    """The Bode diagram as a matplotlib figure: magnitude (dB) and phase (deg) against log f.

    Measured points with ±2u error bars (k = 2), the fitted second-order model as a line, and
    the −3 dB bandwidth marked.
    """
    f = np.asarray(r.frequency_hz)
    lo, hi = f.min() / 2.0, max(f.max(), r.bandwidth_hz) * 2.0
    grid = np.geomspace(lo, hi, 400)
    fit = r._fit
    model = fit.response(grid)
    fig, (ax_m, ax_p) = plt.subplots(2, 1, figsize=(7.2, 6.0), sharex=True)
    ax_m.semilogx(
        grid,
        20.0 * np.log10(np.abs(model)),
        color="#1f4e79",
        lw=1.5,
        label="fitted second-order model",
    )
    ax_m.errorbar(
        f,
        r.amplitude_ratio_db,
        yerr=2.0 * np.asarray(r.amplitude_ratio_db_u),
        fmt="o",
        ms=4.5,
        color="#c0392b",
        capsize=3,
        label="measured (±2u)",
    )
    ax_m.axhline(-3.0103, color="#888", lw=0.8, ls="--")
    ax_m.axvline(r.bandwidth_hz, color="#888", lw=0.8, ls=":")
    ax_m.annotate(
        f"−3 dB: {fixed(r.bandwidth_hz, 4)} Hz",
        (r.bandwidth_hz, -3.0103),
        xytext=(6, 6),
        textcoords="offset points",
        fontsize=8,
        color="#444",
    )
    ax_m.set_ylabel("amplitude ratio (dB)")
    ax_m.legend(fontsize=8, frameon=False, loc="lower left")
    _style(ax_m)
    ax_p.semilogx(grid, fit.phase_deg(grid), color="#1f4e79", lw=1.5)
    ax_p.errorbar(
        f,
        r.phase_deg,
        yerr=2.0 * np.asarray(r.phase_deg_u),
        fmt="o",
        ms=4.5,
        color="#c0392b",
        capsize=3,
    )
    ax_p.axvline(r.bandwidth_hz, color="#888", lw=0.8, ls=":")
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("frequency (Hz)")
    _style(ax_p)
    ax_m.set_xlim(lo, hi)
    ax_p.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: f"{x:g}"))
    fig.align_ylabels((ax_m, ax_p))
    fig.tight_layout()
    return fig


def bode_figure(r: FrequencyResponse) -> Figure:
    """The Bode diagram (:func:`bode_matplotlib`) for the HTML report."""
    return figure_from_matplotlib(
        bode_matplotlib(r),
        "Bode diagram",
        "Amplitude ratio and phase of the DUT's rate against the table's rate: points measured "
        "(error bars ±2u), line the second-order model fitted to them; dotted the −3 dB "
        "bandwidth of the model.",
    )


def frequency_response_section(r: FrequencyResponse, *, figures: bool = True) -> Section:
    """The fitted parameters in the summary, a table of the points, the Bode figure."""
    k, p = r.k, r.coverage_probability
    results = [
        result_row(name, getattr(r, key), unit, U=k[key] * getattr(r, f"{key}_u"), k=k[key], p=p)
        for name, key, unit in (
            ("natural frequency fn", "natural_frequency_hz", "Hz"),
            ("damping ratio ζ", "damping_ratio", ""),
            ("−3 dB bandwidth", "bandwidth_hz", "Hz"),
            ("delay τ", "delay_s", "s"),
        )
        if getattr(r, key) is not None
    ]
    rows = [
        [
            name,
            fixed(f, 7),
            format_quantity(ratio, U=k["amplitude_ratio"] * ratio_u),
            format_quantity(ph, "°", U=k["phase_deg"] * ph_u),
            fixed(thd, 3),
        ]
        for name, f, ratio, ratio_u, ph, ph_u, thd in zip(
            r.captures,
            r.frequency_hz,
            r.amplitude_ratio,
            r.amplitude_ratio_u,
            r.phase_deg,
            r.phase_deg_u,
            r.dut_thd_percent,
            strict=True,
        )
    ]
    points = Table(
        ["capture", "frequency (Hz)", "amplitude ratio", "phase", "DUT THD (%)"],
        rows,
        caption="Each capture: the DUT's rate against the table's rate, ± U "
        f"(k = {k['phase_deg']:.2f}, p = {100 * p:g} %)",
    )
    diag = diagnostics_table(
        [
            ["model", r.model],
            ["χ² (Type A weights)", fixed(r.chi_squared, 4)],
            ["degrees of freedom", str(r.degrees_of_freedom)],
            ["correlation of fn and ζ", fixed(r.correlation_natural_frequency_damping, 3)],
            ["channel skew bound", f"{fixed(max(r.channel_skew_s), 3)} s (rectangular)"],
        ],
        "weighted least-squares fit (GUM annex H.3)",
    )
    return Section(
        title="Frequency response",
        paragraphs=[
            "Each capture holds one frequency of the sinusoidal table. The table's angle and the "
            f"DUT's rate are sine-fitted ({cite('ieee1057')}, as {cite('feng2023')} fit the "
            "table's motion); the reference rate is the derivative of the fitted angle. The "
            "second-order model H(s) = ωn²/(s² + 2ζωn·s + ωn²) is fitted across the frequencies "
            "by weighted least squares; the bandwidth is the model's −3 dB (|H| = 1/√2) "
            "frequency.",
            paragraph(
                "The phase's uncertainty holds a Type B input for the time skew between the "
                "reference and DUT channels (rectangular within the bound in the table below), "
                "which is common to every capture and enters the model's parameters as a fully "
                "correlated input."
            ),
        ],
        tables=[points, diag],
        figures=[bode_figure(r)] if figures else [],
        anchor="frequency-response",
        results=results,
        references=["feng2023", "ieee1057", "ieee952", "ieee1431", "gum"],
    )
