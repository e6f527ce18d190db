"""The figures of a calibration certificate: one or two per measurement, drawn from the command's
own JSON (``MeasurementResult.results``) and nothing else, as vector SVG at print size.

A figure shows what the certificate's numbers come from — the residuals a scale factor and its
nonlinearity leave, the Allan deviation the noise terms are read from, the self-calibrated scale
deviation, the harmonics a THD sums — so that a reader can see a fit that went wrong. Each is
drawn at the width it is printed (16 cm, 8 pt text), so that no scaling changes its lettering.

The bytes are deterministic: the same JSON gives the same SVG (matplotlib's ``svg.hashsalt``
fixed, no date in the metadata, text as paths so that no font of the machine enters), which keeps
a certificate's folder reproducible.
"""

from __future__ import annotations

import dataclasses
import io
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure as MplFigure
from matplotlib.ticker import FuncFormatter, NullFormatter

from rotacal.glossary import GLOSSARY
from rotacal.numbers import fixed

from .content import MeasurementResult

__all__ = ["FIGURE_STYLE", "draw_figures", "noise_term_lines"]

#: matplotlib settings of every certificate figure: print size lettering, text drawn as paths
#: (no font of the machine in the file), and a fixed salt for the ids SVG elements get, so that
#: the same data give the same bytes.
FIGURE_STYLE: dict[str, Any] = {
    "svg.hashsalt": "rotacal-certificate",
    "svg.fonttype": "path",
    "font.family": "DejaVu Sans",
    "font.size": 8.0,
    "axes.titlesize": 8.0,
    "axes.labelsize": 8.0,
    "xtick.labelsize": 7.5,
    "ytick.labelsize": 7.5,
    "legend.fontsize": 7.5,
    "axes.linewidth": 0.6,
    "lines.linewidth": 1.0,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "axes.unicode_minus": True,
    "path.simplify": True,
}
#: Printed width of a figure (in): the text width of an A4 page with 20 mm margins is 6.7 in.
WIDTH_IN = 6.3
_INK, _ACCENT, _BAND, _GRID = "#1d232b", "#1f5f99", "#b9cde3", "#dfe4ea"
_TERM_COLOURS = ("#b35806", "#1b7837", "#762a83", "#b2182b", "#4d4d4d")


@dataclasses.dataclass(frozen=True)
class _Drawn:
    what: str
    caption: str
    figure: MplFigure


#: Margins around the axes (in): room for tick labels of up to six characters and the axis
#: labels. Fixed rather than found by a layout engine, which would draw every figure twice.
_MARGINS_IN = {"left": 0.72, "right": 0.12, "bottom": 0.46, "top": 0.1}


def _axes(height_in: float = 2.6) -> tuple[MplFigure, Any]:
    fig = MplFigure(figsize=(WIDTH_IN, height_in))
    m = _MARGINS_IN
    ax = fig.add_axes(
        (
            m["left"] / WIDTH_IN,
            m["bottom"] / height_in,
            1.0 - (m["left"] + m["right"]) / WIDTH_IN,
            1.0 - (m["bottom"] + m["top"]) / height_in,
        )
    )
    ax.grid(True, which="major", color=_GRID, linewidth=0.5)
    ax.spines[["top", "right"]].set_visible(False)
    return fig, ax


def _plain_log(axis: Any) -> None:
    """Decades labelled as plain decimals (0.01, 1, 100), minor ticks unlabelled: a reader
    needs no exponent notation, and unlabelled minor ticks spare the layout most of its time."""
    axis.set_major_formatter(FuncFormatter(lambda x, _pos: fixed(x, 3)))
    axis.set_minor_formatter(NullFormatter())


def _floats(values: Any) -> np.ndarray | None:
    """A JSON list as a float array (None for a null), or None when it is not a list."""
    if not isinstance(values, Sequence) or isinstance(values, str) or not values:
        return None
    return np.array([np.nan if v is None else float(v) for v in values], dtype=float)


def _number(results: Mapping[str, Any], key: str) -> float | None:
    value = results.get(key)
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def _name(key: str, fallback: str) -> str:
    term = GLOSSARY.get(key)
    return term.name if term is not None else fallback


# --- gyro scale factor and nonlinearity (Kokuyama et al. 2015, §4) ---------------------------


def _scale_factor(results: Mapping[str, Any]) -> list[_Drawn]:
    rates = _floats(results.get("rates_deg_s"))
    resid = _floats(results.get("residuals_percent_fs"))
    if rates is None or resid is None or len(rates) != len(resid):
        return []
    fig, ax = _axes()
    nl = _number(results, "nonlinearity_percent_fs")
    interval = _floats(results.get("nonlinearity_percent_fs_interval"))
    band_text = ""
    if nl is not None:
        if interval is not None and len(interval) == 2:
            low, high = (max(float(interval[0]), 0.0), float(interval[1]))
            for sign in (1.0, -1.0):
                ax.axhspan(sign * low, sign * high, color=_BAND, lw=0, zorder=0)
            band_text = "; shaded: the coverage interval of ±NL (p = 95 %)"
        for sign in (1.0, -1.0):
            ax.axhline(sign * nl, color=_INK, lw=0.7, ls="--", zorder=1)
    errors = _standard_errors_percent_fs(results)
    ax.errorbar(
        rates,
        resid,
        yerr=errors,
        fmt="o",
        ms=3.5,
        color=_ACCENT,
        ecolor=_ACCENT,
        elinewidth=0.8,
        capsize=2,
        zorder=2,
    )
    ax.axhline(0.0, color=_INK, lw=0.5, zorder=1)
    ax.set_xlabel("rate of the table (°/s)")
    ax.set_ylabel("deviation from the line (% of full scale)")
    fs = _number(results, "full_scale_deg_s")
    caption = (
        "Deviation of each rate point's mean output from the least-squares line, in percent of "
        f"the full-scale output{f' (full scale {fixed(fs)} °/s)' if fs is not None else ''}; "
        + (
            "bars: ±1 standard error of the point mean; "
            if errors is not None
            else "no standard errors in the results; "
        )
        + "dashed: ±NL, the largest deviation"
        + band_text
        + "."
    )
    return [_Drawn("nonlinearity", caption, fig)]


def _standard_errors_percent_fs(results: Mapping[str, Any]) -> np.ndarray | None:
    """The points' standard errors in %FS: 100·SE/(|S|·FS), as the residuals are scaled."""
    points = results.get("points")
    s = _number(results, "scale_factor")
    fs = _number(results, "full_scale_deg_s")
    if not isinstance(points, Sequence) or not points or s is None or fs is None or s == 0:
        return None
    se = _floats([p.get("standard_error") if isinstance(p, Mapping) else None for p in points])
    if se is None or not np.all(np.isfinite(se)):
        return None
    return se * 100.0 / (abs(s) * fs)


# --- Allan deviation and the noise terms (IEEE Std 952-1997, Annex C) ------------------------

_DEVIATIONS = {
    "adev": "overlapping Allan deviation",
    "mdev": "modified Allan deviation",
    "hdev": "Hadamard deviation",
    "tdev": "time deviation",
    "totdev": "total deviation",
}


def _term_values(results: Mapping[str, Any]) -> dict[str, float]:
    """The noise terms of an ``allan`` JSON in the units of :func:`noise_term_lines`: the
    top-level keys, or those of ``noise_terms`` (quantization there in arcsec)."""
    nested = results.get("noise_terms")
    source: Mapping[str, Any] = nested if isinstance(nested, Mapping) else {}
    terms: dict[str, float] = {}
    for key in ("arw_deg_rt_h", "bias_instability_deg_h", "rrw_deg_h_rt_h", "rate_ramp_deg_h2"):
        value = _number(results, key)
        value = value if value is not None else _number(source, key)
        if value is not None:
            terms[key] = value
    q_deg = _number(results, "quantization_deg")
    q_arcsec = _number(source, "quantization_arcsec")
    if q_deg is not None:
        terms["quantization_deg"] = q_deg
    elif q_arcsec is not None:
        terms["quantization_deg"] = q_arcsec / 3600.0
    return terms


def noise_term_lines(terms: Mapping[str, float], tau_s: np.ndarray) -> dict[str, np.ndarray]:
    """The Allan deviation each noise term alone gives, in °/h, at the averaging times ``tau_s``.

    Parameters
    ----------
    terms : mapping
        Any of ``quantization_deg`` Q (°), ``arw_deg_rt_h`` N (°/√h), ``bias_instability_deg_h``
        B (°/h), ``rrw_deg_h_rt_h`` K (°/h/√h), ``rate_ramp_deg_h2`` R (°/h²).
    tau_s : ndarray
        Averaging times (s).

    Returns
    -------
    dict
        Term key → σ(τ) (°/h): √3·Q/τ, N/√τ, B·√(2 ln 2/π), K·√(τ/3), R·τ/√2 with τ in hours.

    References
    ----------
    IEEE Std 952-1997, Annex C, eqs. (C.5), (C.11), (C.21), (C.25), (C.29) and Table C.1
    (σ² = 3Q²/τ², N²/τ, (2 ln 2/π)·B², K²τ/3, R²τ²/2).
    """
    tau_h = np.asarray(tau_s, dtype=float) / 3600.0
    forms: dict[str, Callable[[float], np.ndarray]] = {
        "quantization_deg": lambda q: math.sqrt(3.0) * q / tau_h,
        "arw_deg_rt_h": lambda n: n / np.sqrt(tau_h),
        "bias_instability_deg_h": lambda b: np.full_like(
            tau_h, b * math.sqrt(2.0 * math.log(2.0) / math.pi)
        ),
        "rrw_deg_h_rt_h": lambda k: k * np.sqrt(tau_h / 3.0),
        "rate_ramp_deg_h2": lambda r: r * tau_h / math.sqrt(2.0),
    }
    return {key: forms[key](value) for key, value in terms.items() if key in forms}


def _allan(results: Mapping[str, Any]) -> list[_Drawn]:
    tau = _floats(results.get("tau_s"))
    name = next((n for n in _DEVIATIONS if f"{n}_deg_s" in results), None)
    if tau is None or name is None:
        return []
    dev = _floats(results.get(f"{name}_deg_s"))
    if dev is None or len(dev) != len(tau):
        return []
    fig, ax = _axes(3.0)
    low = _floats(results.get(f"{name}_low_deg_s"))
    high = _floats(results.get(f"{name}_high_deg_s"))
    band = low is not None and high is not None and len(low) == len(high) == len(tau)
    if low is not None and high is not None and band:
        ax.fill_between(
            tau, low * 3600.0, high * 3600.0, color=_BAND, lw=0, label="68.3 % interval"
        )
    ax.loglog(tau, dev * 3600.0, color=_ACCENT, lw=1.3, label=_DEVIATIONS[name])
    lines_text = ""
    if name == "adev":
        lines = noise_term_lines(_term_values(results), tau)
        ymin, ymax = np.nanmin(dev) * 3600.0, np.nanmax(dev) * 3600.0
        for colour, (key, sigma) in zip(_TERM_COLOURS, lines.items(), strict=False):
            term = GLOSSARY[key]
            ax.loglog(tau, sigma, ls="--", lw=0.9, color=colour, label=f"{term.name} {term.symbol}")
        if lines:
            # the term lines run on beyond the data: keep the axes on the data
            ax.set_ylim(ymin / 2.0, ymax * 2.0)
            lines_text = (
                "; dashed: the Allan deviation each noise term alone gives "
                "(IEEE Std 952-1997, Annex C)"
            )
    _plain_log(ax.xaxis)
    _plain_log(ax.yaxis)
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel(f"{_DEVIATIONS[name]} (°/h)")
    ax.legend(loc="lower left", frameon=False)
    caption = (
        f"The {_DEVIATIONS[name]} of the gyro's rate against the averaging time"
        + ("; shaded: its 68.3 % confidence interval" if band else "")
        + lines_text
        + "."
    )
    return [_Drawn("allan-deviation", caption, fig)]


# --- encoder self-calibration (Kokuyama et al. 2015, equal-division-averaged method) ----------


def _envelope(x: np.ndarray, low: np.ndarray, high: np.ndarray, bins: int = 1200) -> tuple:
    """Per-bin minimum of ``low`` and maximum of ``high``: a band that covers every point but
    has a few thousand vertices however many points there are."""
    if len(x) <= bins:
        return x, low, high
    edges = np.linspace(0, len(x), bins + 1).astype(int)
    starts = edges[:-1]
    return (
        x[starts],
        np.minimum.reduceat(low, starts),
        np.maximum.reduceat(high, starts),
    )


def _selfcal(results: Mapping[str, Any]) -> list[_Drawn]:
    dev = _floats(results.get("deviation_arcsec"))
    if dev is None:
        return []
    angle = np.arange(len(dev)) * 360.0 / len(dev)
    fig, ax = _axes()
    big_u = _floats(results.get("deviation_arcsec_U"))
    band_text = ""
    if big_u is not None and len(big_u) == len(dev):
        x, lo, hi = _envelope(angle, dev - big_u, dev + big_u)
        ax.fill_between(x, lo, hi, color=_BAND, lw=0, step="post", zorder=1)
        band_text = (
            f"; shaded: ± its expanded uncertainty U (at most {fixed(np.nanmax(big_u), 2)} arcsec"
            + (
                ", narrower than the line"
                if np.nanmax(big_u) < 0.004 * float(np.ptp(dev) or 1.0)
                else ""
            )
            + ")"
        )
    ax.plot(angle, dev, color=_ACCENT, lw=0.6, zorder=2)
    ax.set_xlim(0.0, 360.0)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("angle of the graduation line (°)")
    ax.set_ylabel(f"{_name('deviation_arcsec', 'scale deviation')} (arcsec)")
    heads = results.get("heads")
    caption = (
        "Scale deviation of the encoder's graduation at each line, self-calibrated "
        + (f"with {heads} read heads " if isinstance(heads, int) else "")
        + "by the equal-division-averaged method"
        + band_text
        + "."
    )
    return [_Drawn("scale-deviation", caption, fig)]


# --- sinusoidal motion (Feng et al. 2023, eqs. 1 and 14) -------------------------------------


def _motion(results: Mapping[str, Any]) -> list[_Drawn]:
    amplitudes = _floats(results.get("harmonic_amplitudes_deg"))
    if amplitudes is None or len(amplitudes) < 2 or not amplitudes[0]:
        return []
    orders = np.arange(2, len(amplitudes) + 1)
    relative = 100.0 * amplitudes[1:] / amplitudes[0]
    fig, ax = _axes(2.4)
    ax.bar(orders, relative, width=0.6, color=_ACCENT)
    ax.set_xticks(orders)
    ax.set_xlabel("harmonic order h")
    ax.set_ylabel("harmonic / fundamental (%)")
    ax.set_axisbelow(True)
    scheme = results.get("scheme")
    read_by = {
        "encoder": "the optical shaft encoder",
        "lts": "the laser triangulation sensor",
        "fog": "the fibre-optic gyro",
    }.get(str(scheme), "the reference sensor")
    caption = (
        f"Amplitudes of the harmonics 2…{len(amplitudes)} of the angular displacement measured by "
        f"{read_by}, in percent of the fundamental's, from the multi-harmonic fit; the total "
        "harmonic distortion is their root-sum-square (Feng et al. 2023, eq. 1)."
    )
    return [_Drawn("harmonics", caption, fig)]


# --- gyro triad (robot-manipulator study 2023, eqs. (4)–(7)) ---------------------------------


def _triad(results: Mapping[str, Any]) -> list[_Drawn]:
    before = _floats(results.get("residual_rms_before"))
    after = _floats(results.get("residual_rms"))
    if before is None or after is None or len(before) != len(after):
        return []
    axes = np.arange(len(after))
    fig, ax = _axes(2.4)
    ax.bar(axes - 0.18, before, width=0.34, color=_BAND, edgecolor=_ACCENT, lw=0.6)
    ax.bar(axes + 0.18, after, width=0.34, color=_ACCENT)
    ax.set_xticks(axes, [f"axis {'xyz'[i]}" if i < 3 else f"axis {i}" for i in axes])
    ax.set_ylabel("rate residual, rms (°/s)")
    ax.set_axisbelow(True)
    ax.legend(
        ["outputs at face value", "outputs calibrated with K and b"], frameon=False, loc="best"
    )
    caption = (
        "Root-mean-square difference between the gyro's rate and the table's reference rate, per "
        "axis: of the raw outputs taken at their nominal scale, and of the outputs calibrated "
        "with the scale-and-misalignment matrix K and the bias b of this certificate."
    )
    return [_Drawn("residuals", caption, fig)]


# --- multiposition drift coefficients (seed 001, eqs. 1–6) -----------------------------------


def _multiposition(results: Mapping[str, Any]) -> list[_Drawn]:
    resid = _floats(results.get("residuals_deg_h"))
    if resid is None:
        return []
    fig, ax = _axes(2.4)
    ax.plot(np.arange(1, len(resid) + 1), resid, "o", ms=2.2, color=_ACCENT)
    ax.axhline(0.0, color=_INK, lw=0.5)
    ax.set_xlabel("measurement row (position)")
    ax.set_ylabel("residual of the drift model (°/h)")
    caption = (
        "Residuals of the gyro's drift rate at each turntable position from the fitted drift "
        "model (Earth rate and gravity at each position)"
        + (
            f"; rms {fixed(results['residual_rms_deg_h'], 2)} °/h"
            if _number(results, "residual_rms_deg_h") is not None
            else ""
        )
        + "."
    )
    return [_Drawn("residuals", caption, fig)]


# --- rate stability over angle (Kokuyama et al. 2015, §5) ------------------------------------


def _rate(results: Mapping[str, Any]) -> list[_Drawn]:
    angle = _floats(results.get("allan_angle_deg"))
    rel = _floats(results.get("allan_relative"))
    if angle is None or rel is None or len(angle) != len(rel):
        return []
    fig, ax = _axes(2.8)
    interval = results.get("allan_relative_interval") or []
    band = (
        isinstance(interval, Sequence)
        and len(interval) == len(rel)
        and all(isinstance(i, Sequence) and len(i) == 2 for i in interval)
    )
    # in parts per million: the decades read 1, 10, 100 instead of powers of ten
    if band:
        bounds = np.array([[np.nan if v is None else float(v) for v in i] for i in interval])
        ax.fill_between(
            angle, bounds[:, 0] * 1e6, bounds[:, 1] * 1e6, color=_BAND, lw=0, label="95 % interval"
        )
    ax.loglog(angle, rel * 1e6, color=_ACCENT, lw=1.2, label="compensated")
    raw = _floats(results.get("allan_relative_uncompensated"))
    if raw is not None and len(raw) == len(angle):
        ax.loglog(angle, raw * 1e6, color=_INK, lw=0.8, ls="--", label="without compensation")
    _plain_log(ax.xaxis)
    _plain_log(ax.yaxis)
    ax.set_xlabel("rotation angle φ (°)")
    ax.set_ylabel("relative root Allan variance s(φ) (10⁻⁶)")
    ax.legend(loc="lower left", frameon=False)
    caption = (
        "Root Allan variance of the table's rate over the rotation angle φ, relative to the mean "
        "rate (Kokuyama et al. 2015, §5)"
        + (
            ", with the encoder's scale deviation compensated and without"
            if raw is not None
            else ""
        )
        + ("; shaded: the 95 % interval" if band else "")
        + "."
    )
    return [_Drawn("rate-stability", caption, fig)]


_DRAWERS: dict[str, Callable[[Mapping[str, Any]], list[_Drawn]]] = {
    "gyro scale-factor": _scale_factor,
    "allan": _allan,
    "selfcal": _selfcal,
    "gyro triad": _triad,
    "gyro multiposition": _multiposition,
    "rate": _rate,
}


def _drawer(command: str) -> Callable[[Mapping[str, Any]], list[_Drawn]] | None:
    if command.startswith("motion "):
        return _motion
    return _DRAWERS.get(command)


def draw_figures(measurement: MeasurementResult) -> list[tuple[str, str, bytes]]:
    """The certificate's figures of one measurement: ``(file name, caption, SVG bytes)`` each.

    Drawn only from ``measurement.results`` (the command's JSON), as vector SVG at the size they
    are printed; file names ``figure-<measurement index>-<n>-<what>.svg``. A command with no
    figure that adds to its numbers (``gyro rotations``: its angles are matched exactly) gets
    none. The same results give the same bytes.
    """
    drawer = _drawer(measurement.command)
    if drawer is None:
        return []
    out = []
    with matplotlib.rc_context(FIGURE_STYLE):  # type: ignore[arg-type]
        for n, drawn in enumerate(drawer(measurement.results), start=1):
            buffer = io.BytesIO()
            drawn.figure.savefig(buffer, format="svg", metadata={"Date": None})
            name = f"figure-{measurement.index}-{n}-{drawn.what}.svg"
            out.append((name, drawn.caption, buffer.getvalue()))
    return out
