"""``rotacal gyro frequency-response``: a gyro's dynamic response on a sinusoidal table.

Registered on the ``gyro`` group by the import at the end of :mod:`rotacal.cli.gyro`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.numbers import format_plain, format_quantity

from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _clipping_option,
    _names_capture,
    _naming_file,
    _publish,
    _read,
    _status,
    _summary_wanted,
)
from ._help import example
from .gyro import gyro


@gyro.command(
    "frequency-response",
    epilog=example(
        "rotacal gyro frequency-response f1.csv f2.csv f5.csv f10.csv --lines 3600",
        "rotacal gyro frequency-response f1.h5 f2.h5 f5.h5 --channel-skew-s 0 --report bode.html",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.argument("more_captures", nargs=-1, type=INPUT_FILE)
@click.option(
    "--lines",
    type=int,
    default=None,
    help="Encoder lines per revolution: the reference is the encoder's a and b. Without it the "
    "reference is the angle_deg column.",
)
@click.option(
    "--harmonics",
    type=click.IntRange(1, 50),
    default=5,
    show_default=True,
    help="Harmonics fitted to the angle and to the DUT's rate (lowered below Nyquist).",
)
@click.option(
    "--channel-skew-s",
    type=click.FloatRange(min=0.0),
    default=None,
    help="Bound of the time skew between the reference and DUT channels (s), a Type B input "
    "of the phase (rectangular); 0 for a simultaneous-sampling DAQ. [default: one sample "
    "interval, as a multiplexing DAQ may convert the channels a whole interval apart]",
)
@click.option(
    "--delay", is_flag=True, help="Fit a pure delay τ with the second-order model (delay_s)."
)
@click.option(
    "--max-thd-percent",
    type=click.FloatRange(min=0.0, min_open=True),
    default=10.0,
    show_default=True,
    help="Refuse a DUT rate as not sinusoidal when its THD exceeds the table rate's by more "
    "than this (root-sum-square).",
)
@click.option(
    "--dut-sign",
    type=click.Choice(["1", "-1"]),
    default="1",
    show_default=True,
    help="-1 when the DUT's sensitive axis points against the encoder's positive direction.",
)
@_clipping_option
@_analysis_options
@_names_capture
def gyro_frequency_response(
    capture: str,
    more_captures: tuple[str, ...],
    lines: int | None,
    harmonics: int,
    channel_skew_s: float | None,
    delay: bool,
    max_thd_percent: float,
    dut_sign: str,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Frequency response of a gyro on a sinusoidal table.

    One capture per frequency, with time_s, the DUT's rate_deg_s and the table's angle (a and b
    of its encoder with --lines, or angle_deg). Both are sine-fitted (IEEE Std 1057): amplitude
    ratio and phase of the DUT's rate against the table's rate at each frequency, then the
    second-order model ωn²/(s² + 2ζωn·s + ωn²) fitted across them: natural frequency, damping
    and −3 dB bandwidth, each with its standard uncertainty.
    """
    from rotacal.gyro.frequency_response import calibrate_frequency_response

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    paths = [capture, *more_captures]
    needed = ["time_s", "rate_deg_s", *(["a", "b"] if lines is not None else ["angle_deg"])]
    data = []
    for path in paths:
        with _naming_file(path):
            cap = _read(path, needed, columns, group)
            one = {name: cap[name] for name in needed}
        if dut_sign == "-1":
            one["rate_deg_s"] = -one["rate_deg_s"]
        data.append(one)
    with _status("fitting"):
        result = calibrate_frequency_response(
            data,
            names=[Path(p).name for p in paths],
            lines=lines,
            harmonics=harmonics,
            channel_skew_s=channel_skew_s,
            delay=delay,
            max_thd_percent=max_thd_percent,
            allow_clipped=kw.pop("allow_clipped"),
            specs=kw.pop("specs"),
        )
    _publish(
        result,
        json_path,
        report_path,
        ", ".join(paths) if len(paths) > 1 else capture,
        "Gyro frequency response",
        "IEEE Std 1057 sine fits per frequency; second-order model ωn²/(s² + 2ζωn·s + ωn²)",
        ("frequency_response", "frequency_response_section"),
    )
    if _summary_wanted():
        _print_frequency_response(result)


def _print_frequency_response(r: Any) -> None:
    """Each point's ratio and phase, then the model's parameters, each ± U (k, p)."""
    p, k = r.coverage_probability, r.k
    for i, f in enumerate(r.frequency_hz):
        ratio = format_quantity(
            r.amplitude_ratio[i], U=k["amplitude_ratio"] * r.amplitude_ratio_u[i]
        )
        phase = format_quantity(
            r.phase_deg[i], "deg", U=k["phase_deg"] * r.phase_deg_u[i], k=k["phase_deg"], p=p
        )
        click.echo(f"{format_plain(f, 'Hz'):<12} ratio {ratio:<22} phase {phase}")
    for label, key, unit in (
        ("natural frequency", "natural_frequency_hz", "Hz"),
        ("damping ratio    ", "damping_ratio", ""),
        ("bandwidth −3 dB  ", "bandwidth_hz", "Hz"),
        ("delay            ", "delay_s", "s"),
    ):
        value = getattr(r, key)
        if value is not None:
            u = getattr(r, f"{key}_u")
            text = format_quantity(value, unit, U=k[key] * u, k=k[key], p=p)
            click.echo(f"{label} {text}")
