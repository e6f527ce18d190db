"""``rotacal motion``: sinusoidal-motion calibration (Feng et al. 2023)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import click

from rotacal.columns import MOTION_ENCODER, MOTION_FOG, MOTION_LTS
from rotacal.errors import CaptureError
from rotacal.numbers import format_plain, quantity_of
from rotacal.results import with_warnings

from ._app import cli
from ._common import (
    _IN_MEMORY_MAX_SAMPLES,
    INPUT_FILE,
    F,
    _analysis_options,
    _check_outputs,
    _clipping_option,
    _emit_warnings,
    _names_capture,
    _naming_file,
    _read,
    _sample_progress,
    _status,
    _summary_wanted,
    _write_json,
    _write_report,
)
from ._dask import dask_options, run_on_dask, split_wanted
from ._help import example
from ._reading import current_read_options


@cli.group(
    epilog=example(
        "rotacal motion encoder run.npz --lines 36000 --set-amplitude-deg 0.5 --set-frequency-hz 2",
        "rotacal motion lts lts.csv --radius-mm 100",
        "rotacal motion fog fog.h5 --json fog.json",
    )
)
def motion() -> None:
    """Sinusoidal-motion calibration of a table.

    Amplitude, frequency, angular acceleration, THD (IEEE Std 1057 sine fit) and their errors
    against the set values, from an optical shaft encoder (OSE), a laser triangulation sensor
    (LTS) or a fibre-optic gyro (FOG) on the table (Feng et al. 2023, Sensors 23:4876).
    """


def _motion_common(func: F) -> F:
    options = [
        click.option(
            "--harmonics",
            default=10,
            show_default=True,
            help="N_H: highest harmonic in the fit and the THD.",
        ),
        click.option(
            "--periods",
            type=int,
            default=None,
            help="Whole periods of the motion to analyse [default: all].",
        ),
        click.option(
            "--set-amplitude-deg",
            type=float,
            default=None,
            help="Set amplitude of the table (deg).",
        ),
        click.option(
            "--set-frequency-hz", type=float, default=None, help="Set frequency of the table (Hz)."
        ),
        click.option(
            "--drift",
            is_flag=True,
            help="Fit a linear drift term beside the harmonics, so that a slow drift of the table "
            "does not count as distortion; reports drift_deg_s (deg/s). For the fibre-optic gyro (FOG), "
            "whose rate "
            "offset already holds a steady drift (with the gyro's bias), it fits the rate's own "
            "linear change as well (rate_drift_deg_s2). Without it a drift that matters is named "
            "in the warnings.",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return _clipping_option(_analysis_options(func))


def _finish_motion(
    result: Any, capture_path: str, json_path: str | None, report_path: str | None
) -> None:
    for note in result.notes:
        if "partial" in note:
            click.echo(
                f"rotacal: warning: {note}: amplitude and THD may be biased by the signals' "
                "gain and phase errors; prefer the LTS scheme for motions this small",
                err=True,
            )
    _emit_warnings(result)
    data = result.to_dict()
    _write_json(data, json_path)
    if report_path:
        from rotacal.references import cite
        from rotacal.report.motion import motion_section

        _write_report(
            "Sinusoidal-motion calibration",
            f"The methods of {cite('feng2023')}, with the sine fit of {cite('ieee1057')}",
            [motion_section(result)],
            capture_path,
            report_path,
            warnings=result.warnings,
        )
    if _summary_wanted():
        _print_motion(result, data)


def _print_motion(r: Any, data: dict[str, Any]) -> None:
    click.echo(f"scheme            {r.scheme}")
    click.echo(f"amplitude         {quantity_of(data, 'amplitude_deg', 'deg')}")
    click.echo(f"frequency         {quantity_of(data, 'frequency_hz', 'Hz', digits=9)}")
    click.echo(
        f"ang. acceleration {quantity_of(data, 'angular_acceleration_amplitude_deg_s2', 'deg/s^2')}"
    )
    click.echo(f"THD               {quantity_of(data, 'thd_percent', '%')}  (h = 2..{r.harmonics})")
    click.echo(
        f"periods used      {r.periods_used}  ({r.reversal_times_s.size} reversing moments found)"
    )
    if r.snr_db is not None:
        click.echo(f"SNR               {format_plain(r.snr_db, 'dB', digits=4)}")
    if r.drift_deg_s is not None:
        click.echo(f"drift             {quantity_of(data, 'drift_deg_s', 'deg/s')}")
    if r.rate_drift_deg_s2 is not None:
        click.echo(f"rate drift        {quantity_of(data, 'rate_drift_deg_s2', 'deg/s^2')}")
    for note in r.notes:
        click.echo(f"note              {note}")
    if r.set_amplitude_deg is not None:
        click.echo(f"amplitude error   {quantity_of(data, 'amplitude_error_percent', '%')}")
        click.echo(f"frequency error   {quantity_of(data, 'frequency_error_percent', '%')}")
        click.echo(
            f"ang. accel. error {quantity_of(data, 'angular_acceleration_error_percent', '%')}"
        )
        click.echo(
            f"position error    max {format_plain(r.position_error_max_deg, 'deg', digits=4)}, "
            f"rms {format_plain(r.position_error_rms_deg, 'deg', digits=4)}"
        )


@motion.command(
    "encoder",
    epilog=example(
        "rotacal motion encoder run.npz --lines 36000 --set-amplitude-deg 0.5 "
        "--set-frequency-hz 2 --json result.json --report run.html"
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.option("--lines", type=int, required=True, help="Encoder lines per revolution (e.g. 36000).")
@click.option(
    "--correction-from",
    type=INPUT_FILE,
    default=None,
    help="Fit the Heydemann correction on this capture (time_s, a, b with more motion, same "
    "encoder and electronics) instead of on CAPTURE: for motions shorter than a signal period.",
)
@click.option(
    "--hysteresis",
    "hysteresis_subintervals",
    type=click.IntRange(min=1),
    default=None,
    help="Reversal rule's hysteresis, in 30° subintervals of the signal period: neighbouring "
    "reversal candidates whose levels differ by less are merged (a vibration near a reversal), "
    "an odd cluster counting as one reversal. 1 or 2 merges none: the paper's odd/even rule "
    "alone. [default: 10 % of the largest swing between candidates, at least 2]",
)
@click.option(
    "--chunked/--in-memory",
    default=None,
    help="Stream the capture in chunks (flat memory) or load it whole "
    f"[default: chunked above {_IN_MEMORY_MAX_SAMPLES:.0e} samples].",
)
@dask_options("NPZ without compression, HDF5 or TDMS: for a capture larger than one process's time")
@_motion_common
@_names_capture
def motion_encoder(
    capture: str,
    lines: int,
    correction_from: str | None,
    chunked: bool | None,
    workers: int | None,
    scheduler: str | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Optical shaft encoder (OSE) scheme: columns time_s, a, b.

    a and b are the encoder's analog quadrature signals (a ≈ cos φ, b ≈ sin φ, φ = 2π·lines·θ/360);
    the angle comes from their subintervals and the reversing moments (Feng et al. 2023, eqs. 3–8).
    """
    from rotacal.io import capture_length, parse_column_mapping

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    mapping = parse_column_mapping(columns)
    if correction_from is not None:
        from rotacal.encoder import fit_quadrature_correction

        ref = _read(correction_from, ["a", "b"], columns, group)
        with _naming_file(correction_from, "--correction-from"):
            kw["correction"] = fit_quadrature_correction(
                ref["a"], ref["b"], allow_clipped=kw["allow_clipped"]
            )
        if kw["correction"].method != "heydemann":
            raise CaptureError(
                f"--correction-from {correction_from} covers only part of a signal period too; "
                "record the reference with the table turning through several signal periods"
            )
    n = capture_length(
        capture, "a", mapping=mapping, group=group, read_options=current_read_options()
    )
    split = split_wanted(workers, scheduler, chunked)
    if not split and chunked is None:
        chunked = n > _IN_MEMORY_MAX_SAMPLES
    if split:
        from rotacal.batch.capture_motion import calibrate_encoder_motion_on_dask

        result = _dask_motion(
            capture,
            columns,
            group,
            (workers, scheduler),
            "a",
            8,  # correction points, phase twice, windows, fit, position error
            calibrate_encoder_motion_on_dask,
            {**kw, "lines": lines},
        )
    elif chunked:  # the streaming modules are imported only here (start-up of the in-memory path)
        from rotacal.table import calibrate_encoder_motion_chunked, encoder_chunks_from_file

        source = encoder_chunks_from_file(capture, mapping=mapping, group=group)
        # the chunked calibration reads the capture in up to six passes
        with _sample_progress(6 * n, "calibrating (chunked)") as progress:
            result = calibrate_encoder_motion_chunked(source, lines=lines, progress=progress, **kw)
    else:
        from rotacal._jit import ENCODER_CALL_SAMPLES, single_call
        from rotacal.table import calibrate_encoder_motion

        cap, checks = _read(capture, list(MOTION_ENCODER.required), columns, group, True)
        # one calibration, then the process ends: Numba only where this call repays its load;
        # the capture's values and CRC-32s are checked on a second thread meanwhile, and a fault
        # they find is the one reported
        with checks, _status("demodulating and fitting"), single_call(ENCODER_CALL_SAMPLES):
            result = calibrate_encoder_motion(cap["time_s"], cap["a"], cap["b"], lines=lines, **kw)
    if correction_from is not None:  # a clipped reference analysed with --allow-clipped
        result = with_warnings(
            result, (f"--correction-from {correction_from}: {w}" for w in kw["correction"].warnings)
        )
    _finish_motion(result, capture, json_path, report_path)


def _chunked_option(func: F) -> F:
    """``--chunked/--in-memory``: stream the capture or load it whole (default by its size)."""
    return click.option(
        "--chunked/--in-memory",
        default=None,
        help="Stream the capture in chunks (flat memory) or load it whole "
        f"[default: chunked above {_IN_MEMORY_MAX_SAMPLES:.0e} samples].",
    )(func)


def _streams(
    capture: str, column: str, chunked: bool | None, columns: Sequence[str], group: str | None
) -> bool:
    """Whether to stream ``capture``: as asked, else when ``column`` holds more samples than
    are read whole (``_IN_MEMORY_MAX_SAMPLES``)."""
    if chunked is not None:
        return chunked
    from rotacal.io import capture_length, parse_column_mapping

    n = capture_length(
        capture,
        column,
        mapping=parse_column_mapping(columns),
        group=group,
        read_options=current_read_options(),
    )
    return n > _IN_MEMORY_MAX_SAMPLES


def _stream_calibration(
    capture: str,
    column: str,
    columns: Sequence[str],
    group: str | None,
    passes: int,
    calibrate: Any,
    source_of: Any,
    **kw: Any,
) -> Any:
    """``calibrate(source_of(capture, ...), progress=..., **kw)`` with a progress bar over the
    samples of up to ``passes`` passes."""
    from rotacal.io import capture_length, parse_column_mapping

    mapping = parse_column_mapping(columns)
    n = capture_length(
        capture, column, mapping=mapping, group=group, read_options=current_read_options()
    )
    source = source_of(capture, mapping=mapping, group=group)
    with _sample_progress(passes * n, "calibrating (chunked)") as progress:
        return calibrate(source, progress=progress, **kw)


@motion.command(
    "lts",
    epilog=example("rotacal motion lts lts.csv --radius-mm 100 --set-amplitude-deg 0.1"),
)
@click.argument("capture", type=INPUT_FILE)
@click.option("--radius-mm", type=float, required=True, help="R: laser spot to table axis (mm).")
@_chunked_option
@dask_options("NPZ without compression, HDF5 or TDMS: for a capture larger than one process's time")
@_motion_common
@_names_capture
def motion_lts(
    capture: str,
    radius_mm: float,
    chunked: bool | None,
    workers: int | None,
    scheduler: str | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Laser triangulation sensor (LTS) scheme: time_s, displacement_mm.

    The angle is θ = arctan(D/R) for the displacement D of a reflector at radius R on the table
    (Feng et al. 2023, eq. 15).
    """
    from rotacal.table import calibrate_lts_motion

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    if split_wanted(workers, scheduler, chunked):
        from rotacal.batch.capture_lts import calibrate_lts_motion_on_dask

        result = _dask_motion(
            capture,
            columns,
            group,
            (workers, scheduler),
            "displacement_mm",
            12,  # range, ~4 rank passes, swings, windows, fit and error (drift: 3 more)
            calibrate_lts_motion_on_dask,
            {**kw, "radius_mm": radius_mm},
        )
    elif _streams(capture, "displacement_mm", chunked, columns, group):
        from rotacal.table import calibrate_lts_motion_chunked, lts_chunks_from_file

        # checks, levels (2 with a drift: its fit), swings, parabolas, fit, position error
        passes = 10 if kw["drift"] else 7
        result = _stream_calibration(
            capture,
            "displacement_mm",
            columns,
            group,
            passes,
            calibrate_lts_motion_chunked,
            lts_chunks_from_file,
            radius_mm=radius_mm,
            **kw,
        )
    else:
        cap = _read(capture, list(MOTION_LTS.required), columns, group)
        with _status("fitting"):
            result = calibrate_lts_motion(
                cap["time_s"], cap["displacement_mm"], radius_mm=radius_mm, **kw
            )
    _finish_motion(result, capture, json_path, report_path)


@motion.command(
    "fog",
    epilog=example(
        "rotacal motion fog fog.h5 --json fog.json",
        "rotacal motion fog daq.csv --column t=time_s --column gyro_z=rate_deg_s",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@_chunked_option
@dask_options("NPZ without compression, HDF5 or TDMS: for a capture larger than one process's time")
@_motion_common
@_names_capture
def motion_fog(
    capture: str,
    chunked: bool | None,
    workers: int | None,
    scheduler: str | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Fibre-optic gyro (FOG) scheme: columns time_s, rate_deg_s.

    The gyro's rate is fitted with the harmonics of the motion; THD and amplitude are those of
    the angular displacement it implies, with the signal-to-noise ratio (Feng et al. 2023, eqs. 9–14).
    """
    from rotacal.table import calibrate_fog_motion

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    if split_wanted(workers, scheduler, chunked):
        from rotacal.batch.capture_fog import calibrate_fog_motion_on_dask

        result = _dask_motion(
            capture,
            columns,
            group,
            (workers, scheduler),
            "rate_deg_s",
            8,  # whole fit, crossings, analysis fit, angle twice, eq. (2)
            calibrate_fog_motion_on_dask,
            kw,
        )
    elif _streams(capture, "rate_deg_s", chunked, columns, group):
        from rotacal.table import calibrate_fog_motion_chunked, fog_chunks_from_file

        # checks, fit of the whole rate, zero crossings, fit, angle, position error
        result = _stream_calibration(
            capture,
            "rate_deg_s",
            columns,
            group,
            6,
            calibrate_fog_motion_chunked,
            fog_chunks_from_file,
            **kw,
        )
    else:
        cap = _read(capture, list(MOTION_FOG.required), columns, group)
        with _status("fitting"):
            result = calibrate_fog_motion(cap["time_s"], cap["rate_deg_s"], **kw)
    _finish_motion(result, capture, json_path, report_path)


def _dask_motion(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    cluster: tuple[int | None, str | None],
    column: str,
    rounds: int,
    calibrate: Callable[..., Any],
    kw: dict[str, Any],
) -> Any:
    """A motion calibration split over a Dask cluster's workers, noted as such: ``calibrate`` is
    one of :mod:`rotacal.batch`'s ``calibrate_*_motion_on_dask``, ``column`` the capture's
    signal, ``rounds`` the most rounds of tasks it makes over each block (for the bar)."""
    from rotacal.batch.capture_motion import CHUNK_ROWS
    from rotacal.io import capture_length, parse_column_mapping

    mapping = parse_column_mapping(columns)
    options = current_read_options()
    reading: dict[str, Any] = {"mapping": mapping, "group": group, "read_options": options}
    n = capture_length(capture, column, **reading)
    return run_on_dask(
        cluster,
        rounds * (-(-n // CHUNK_ROWS)) + 4,  # the rounds over the blocks, checks, first adds
        "calibrating",
        lambda client, progress: calibrate(
            capture, client=client, progress=progress, **reading, **kw
        ),
        capture=capture,
        columns=[column],
        rows=n,
        reading=reading,
    )


from . import motion_angle  # noqa: E402,F401  (registers `motion angle`)
