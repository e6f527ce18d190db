"""``rotacal motion angle``: sinusoidal-motion calibration from angle or counter readings.

Registered on the ``motion`` group by the import at the end of :mod:`rotacal.cli.motion`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from rotacal.errors import ConfigError

from ._common import INPUT_FILE, _check_outputs, _read, _sample_progress, _status
from ._help import example
from ._readings import reading_chunks, reading_length, require_reading
from .motion import _chunked_option, _finish_motion, _motion_common, _streams, motion

#: The register widths of ``--counter-bits``.
COUNTER_BITS = click.Choice(["8", "16", "24", "32", "64"])


@motion.command(
    "angle",
    epilog=example(
        "rotacal motion angle counts.csv --counts-per-rev 144000 --set-amplitude-deg 0.5 "
        "--set-frequency-hz 2",
        "rotacal motion angle readout.h5 --resolution-deg 0.0001 --json angle.json",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--counts-per-rev",
    type=float,
    default=None,
    help="N: counts per revolution of a count column (after the card's ×4, e.g. 144000).",
)
@click.option(
    "--counter-bits",
    type=COUNTER_BITS,
    default=None,
    help="Width of the counter's register [default: the smallest of 8/16/24/32/64 bits that "
    "holds every reading].",
)
@click.option(
    "--signed/--unsigned",
    default=None,
    help="Whether the register is two's complement [default: signed if a reading is negative].",
)
@click.option(
    "--resolution-deg",
    type=float,
    default=None,
    help="Resolution of an angle_deg readout (deg), a Type B input [default: the readings' "
    "grid step when they lie on one; a count column: one count].",
)
@click.option(
    "--allow-gaps",
    is_flag=True,
    help="Analyse a record with more than 1 %% of its samples missing, duplicated or repeated "
    "(always named in the warnings).",
)
@_chunked_option
@_motion_common
def motion_angle(
    capture: str,
    counts_per_rev: float | None,
    counter_bits: str | None,
    signed: bool | None,
    resolution_deg: float | None,
    chunked: bool | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Angle readout or counter: time_s and angle_deg or count.

    The seed-000 calibration (IEEE 1057 multi-harmonic fit, THD, amplitude, acceleration,
    reversals, set-value errors) on the angle itself; a counter's wrap-around is unwrapped and
    the DAQ's gaps, duplicated times and repeated rows are named (Feng et al. 2023).
    """
    from rotacal.cli._common import _naming_file
    from rotacal.table.motion_angle import calibrate_angle_motion, calibrate_count_motion

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    with _naming_file(capture):
        name = require_reading(capture, columns, group)
        if name == "count" and counts_per_rev is None:
            raise ConfigError(f"{capture} holds a count column: give --counts-per-rev N")
        if name == "count" and resolution_deg is not None:
            raise ConfigError("--resolution-deg is for angle_deg readings; a count's is one count")
        if name == "angle_deg" and (counts_per_rev is not None or counter_bits is not None):
            raise ConfigError(
                f"{capture} holds angle_deg, not count: --counts-per-rev and --counter-bits "
                "apply to counts only"
            )
        bits = None if counter_bits is None else int(counter_bits)
        if _streams(capture, name, chunked, columns, group):
            kw["resolution_deg"] = resolution_deg
            result = _chunked(capture, name, columns, group, counts_per_rev, bits, signed, kw)
            _finish_motion(result, capture, json_path, report_path)
            return
        cap = _read(capture, ["time_s", name], columns, group)
        with _status("fitting"):
            if name == "count":
                assert counts_per_rev is not None
                result = calibrate_count_motion(
                    cap["time_s"],
                    cap["count"],
                    counts_per_rev=counts_per_rev,
                    counter_bits=bits,
                    signed=signed,
                    **kw,
                )
            else:
                result = calibrate_angle_motion(
                    cap["time_s"], cap["angle_deg"], resolution_deg=resolution_deg, **kw
                )
    _finish_motion(result, capture, json_path, report_path)


def _chunked(
    capture: str,
    name: str,
    columns: Sequence[str],
    group: str | None,
    counts_per_rev: float | None,
    bits: int | None,
    signed: bool | None,
    kw: dict[str, Any],
) -> Any:
    """The streamed calibration (:mod:`rotacal.table.motion_angle_stream`) with a progress bar
    over the samples of its passes (about eight; two more with --drift or an inferred register)."""
    from rotacal.table.motion_angle_stream import calibrate_angle_motion_chunked

    n = reading_length(capture, name, columns, group)
    with _sample_progress(10 * n, "calibrating (chunked)") as progress:
        return calibrate_angle_motion_chunked(
            reading_chunks(capture, name, columns, group, progress),
            counts_per_rev=counts_per_rev,
            counter_bits=bits,
            signed=signed,
            **kw,
        )
