"""``rotacal gyro resolution``: threshold and resolution from a small-step test (IEEE Std 1431/528).

Registered on the ``gyro`` group by one import at the end of :mod:`rotacal.cli.gyro`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _names_capture,
    _publish,
    _read,
    _status,
    _summary_wanted,
)
from ._help import example
from .gyro import gyro


@gyro.command(
    "resolution",
    epilog=example(
        "rotacal gyro resolution steps.csv --scale-factor 0.0125 --report steps.html",
        "rotacal simulate gyro-steps --out steps.csv",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--scale-factor",
    type=float,
    default=None,
    help="Nominal scale factor (output unit per deg/s) the 50 % criterion refers to "
    "[default: fitted to the dwells].",
)
@click.option(
    "--settle-samples",
    type=int,
    default=0,
    show_default=True,
    help="Samples dropped at the start of each dwell (the DUT's response to the step).",
)
@click.option(
    "--rate-tolerance-deg-s",
    type=float,
    default=1e-9,
    show_default=True,
    help="Consecutive set rates closer than this are one dwell; inputs closer are one level.",
)
@click.option(
    "--sample-rate-hz",
    type=float,
    default=None,
    help="Sample rate (Hz), for the output's own resolution at fs/2.",
)
@click.option("--output-unit", default="", help="Unit of the output column (e.g. V).")
@_analysis_options
@_names_capture
def gyro_resolution(
    capture: str,
    scale_factor: float | None,
    settle_samples: int,
    rate_tolerance_deg_s: float,
    sample_rate_hz: float | None,
    output_unit: str,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Threshold and resolution from a small-step test.

    Columns rate_deg_s (the table's set rate, row by row in recorded order) and output: the table
    dwells on rates stepped by small increments around 0 deg/s (threshold) and around operating
    rates (resolution). Each step's output change is compared with what the scale factor
    predicts; the threshold (resolution) is the smallest input (input change) from which every
    step reaches 50 % of it (IEEE Std 528-2001 definitions, IEEE Std 1431-2004 test).
    """
    from rotacal.gyro.threshold import small_step_test

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, ["rate_deg_s", "output"], columns, group)
    with _status("analysing the steps"):
        result = small_step_test(
            cap["rate_deg_s"],
            cap["output"],
            scale_factor=scale_factor,
            settle_samples=settle_samples,
            rate_tolerance_deg_s=rate_tolerance_deg_s,
            sample_rate_hz=sample_rate_hz,
            output_unit=output_unit,
        )
    _publish(
        result,
        json_path,
        report_path,
        capture,
        "Gyro threshold and resolution",
        "IEEE Std 528-2001 / IEEE Std 1431-2004: smallest input (change) giving ≥ 50 % of "
        "the expected output",
        ("gyro_steps", "small_step_section"),
    )
    if _summary_wanted():
        for line in result.summary_lines():
            click.echo(line)
