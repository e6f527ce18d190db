"""``rotacal rate`` on angle or counter readings (columns time_s and angle_deg or count).

:func:`angle_readings` decorates the rate command: it adds the options that read a counter and,
when the capture holds ``angle_deg`` or ``count`` and no ``head_k`` column, reduces the readings
to the crossing times of ``--pulses-per-rev`` virtual marks in one streaming pass
(:mod:`rotacal.table.rate_angle`) and runs the same rate analysis on them; pulse-timestamp
captures go to the command as before.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Sequence
from typing import Any

import click

from rotacal.errors import ConfigError, RotacalError

from ._common import F, _check_outputs, _naming_file, _status
from ._readings import capture_names, reading_chunks, reading_name

_OWN = ("counts_per_rev", "counter_bits", "signed", "allow_gaps")


def _reading(capture: str, columns: Sequence[str], group: str | None) -> str | None:
    """The reading of an angle/count capture, else None (the rate command names what is wrong
    with a file it cannot read)."""
    try:
        names = capture_names(capture, columns, group)
    except RotacalError:
        return None
    return reading_name(names)


def angle_readings(func: F) -> F:
    """The rate command's decorator for angle/count captures (module docstring)."""

    @functools.wraps(func)
    def command(**kw: Any) -> Any:
        own = {k: kw.pop(k) for k in _OWN}
        with _naming_file(kw["capture"]):
            name = _reading(kw["capture"], kw["columns"], kw["group"])
        if name is None:
            if own["counts_per_rev"] is not None or own["counter_bits"] is not None:
                raise ConfigError("--counts-per-rev and --counter-bits need a count column")
            return func(**kw)
        with _naming_file(kw["capture"]):
            return _rate_of_readings(name, own, kw)

    options = [
        click.option(
            "--counts-per-rev",
            type=float,
            default=None,
            help="N of a count column (angle/counter captures: time_s with angle_deg or count, "
            "timed at the crossings of --pulses-per-rev marks).",
        ),
        click.option(
            "--counter-bits",
            type=click.Choice(["8", "16", "24", "32", "64"]),
            default=None,
            help="Register width of a count column [default: inferred from its range].",
        ),
        click.option(
            "--signed/--unsigned", default=None, help="A two's complement count register."
        ),
        click.option(
            "--allow-gaps",
            is_flag=True,
            help="Readings: analyse more than 1 %% missing, duplicated or repeated samples.",
        ),
    ]
    for option in reversed(options):
        command = option(command)
    return command  # type: ignore[return-value]


def _rate_of_readings(name: str, own: dict[str, Any], kw: dict[str, Any]) -> None:
    from rotacal.table.rate_angle import calibrate_rate_from_marks, mark_times_from_chunks

    from .pulses import _finish_rate

    capture = kw["capture"]
    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    if name == "count" and own["counts_per_rev"] is None:
        raise ConfigError(f"{capture} holds a count column: give --counts-per-rev N")
    if name == "angle_deg" and own["counts_per_rev"] is not None:
        raise ConfigError(f"{capture} holds angle_deg, not count: drop --counts-per-rev")
    if kw.get("selfcal_path") is not None or kw.get("head") not in (None, "0", "head_0"):
        raise ConfigError("angle/count readings have one virtual head: drop --selfcal and --head")
    windows_deg = kw.pop("window_deg", None)  # the rate command's --window-deg, where it has one
    settings = _settings(kw)
    chunks = reading_chunks(capture, name, kw["columns"], kw["group"])
    reading: dict[str, Any] = {}
    if name == "count":
        reading = {"counts_per_rev": own["counts_per_rev"], "signed": own["signed"]}
        reading["counter_bits"] = None if own["counter_bits"] is None else int(own["counter_bits"])
    with _status("timing the marks"):
        marks = mark_times_from_chunks(chunks, pulses_per_rev=kw["pulses_per_rev"], **reading)
        result = calibrate_rate_from_marks(marks, allow_gaps=own["allow_gaps"], **settings)
        if windows_deg:
            result = _with_windows(result, marks.times, windows_deg, settings, marks.resolution_deg)
    _finish_rate(result, capture, json_path, report_path)


def _with_windows(
    result: Any,
    times: Any,
    windows_deg: Any,
    settings: dict[str, Any],
    resolution_deg: float | None,
) -> Any:
    """The rate over angle windows (``--window-deg``) of the marks' crossing times, joined to
    ``result`` as the pulse-timestamp path joins them (one virtual head, uncompensated; the
    readout's resolution, deg, at each window's ends)."""
    from rotacal.table.rate_windows import rate_windows_stream
    from rotacal.table.rate_windows_result import with_windows

    windows = rate_windows_stream(
        lambda: iter([times]),
        pulses_per_rev=int(settings["pulses_per_rev"]),
        windows_deg=windows_deg,
        set_rate_deg_s=settings.get("set_rate_deg_s"),
        timing_jitter_s=result.timing_jitter_s,
        timebase_correction=result.timebase_correction,
        specs=settings.get("specs"),
        check=False,  # the rate's analysis checked the same times
        readout_resolution_deg=resolution_deg,
    )
    return with_windows(result, windows)


#: Options of the rate command that have no meaning for readings (one virtual head, in one pass).
_PULSE_ONLY = {"capture", "columns", "group", "selfcal_path", "head", "no_compensation", "chunked"}


def _settings(kw: dict[str, Any]) -> dict[str, Any]:
    """The rate options ``calibrate_rate`` takes by name (``--window-deg`` and later ones too);
    an option given that it does not take is refused rather than dropped."""
    from rotacal.table.rate import calibrate_rate

    accepted = set(inspect.signature(calibrate_rate).parameters) - {
        "heads",
        "selfcal",
        "compensate",
    }
    for key, value in kw.items():
        if key not in accepted and key not in _PULSE_ONLY and value not in (None, False, ()):
            option = "--" + key.replace("_", "-")
            raise ConfigError(f"{option} is not available for angle/count readings (yet)")
    return {k: v for k, v in kw.items() if k in accepted}
