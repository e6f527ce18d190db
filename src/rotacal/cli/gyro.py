"""``rotacal gyro``: gyroscope calibrations (Kokuyama et al. 2015; robot-manipulator study 2023; GyroWheel study)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click
import numpy as np

from rotacal.columns import GYRO_MULTIPOSITION
from rotacal.errors import CaptureError, ConfigError
from rotacal.numbers import elements_of, format_plain, quantity_of

from ._app import cli
from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _clipping_option,
    _names_capture,
    _publish,
    _read,
    _sample_progress,
    _status,
    _summary_wanted,
)
from ._dask import dask_options, run_on_dask, split_wanted
from ._ferraris import (
    DEG_S_UNITS,
    echo_matrix,
    gravity_options,
    nominal_scale_option,
    read_sections,
    read_triads,
    sections_option,
)
from ._gyro_log import continuous_log, log_options, log_sections, scale_factor_from_log
from ._gyro_triad_log import check_runs_options, runs_options, runs_sections, triad_from_log
from ._help import example
from ._rate_files import rate_file_options, rate_row_chunks, rate_row_count, read_rate_rows
from ._reading import current_read_options
from ._sf_items import item_lines, scale_factor_items


@cli.group(
    epilog=example(
        "rotacal gyro scale-factor rates.csv --requirement fmvss126",
        "rotacal gyro triad triad.h5 --json k.json",
        "rotacal gyro multiposition mp.csv --axis x --latitude-deg 45.75",
    )
)
def gyro() -> None:
    """Gyroscope calibrations on the table.

    Scale factor after Kokuyama et al. (2015); triad after the robot-manipulator study (IEEE A&E
    Systems Magazine, 2023); multiposition after the GyroWheel study (Int. J. Aerospace Eng.).
    """


#: Logs longer than this stream (``--chunked``): measured, the streamed analysis is already the
#: faster one at 10⁶ rows and holds ~0.3 GB where the in-memory one holds ~1.3 GB at 10⁷ rows
#: (benchmarks/bench_gyro_stream.py); below it, one read of a CSV beats two.
_SCALE_FACTOR_IN_MEMORY_MAX_ROWS = 1_000_000


@gyro.command(
    "scale-factor",
    epilog=example(
        "rotacal gyro scale-factor rates.csv --requirement fmvss126 --report sf.html",
        "rotacal gyro scale-factor daq.csv --column table=rate_deg_s --column gyro=output",
        "rotacal gyro scale-factor p10.dat m10.dat p30.dat m30.dat --rate-from-name "
        "--column col_5=output",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.argument("more_captures", nargs=-1, type=INPUT_FILE)
@rate_file_options
@log_options
@click.option(
    "--full-scale-deg-s",
    type=float,
    default=None,
    help="FS for the nonlinearity in %FS [default: the largest set rate in magnitude].",
)
@click.option(
    "--requirement",
    default=None,
    help="Check against a named requirement (fmvss126) and say pass/fail with the margin.",
)
@click.option(
    "--output-unit",
    default="",
    help="Unit of the output column (e.g. V), for the printed results and the report.",
)
@click.option(
    "--sample-rate-hz",
    type=float,
    default=None,
    help="Sample rate of the output (Hz): the resolution's noise is then stated at fs/2.",
)
@click.option(
    "--bandwidth-hz",
    type=float,
    default=None,
    help="Bandwidth of one reading for the resolution check (Hz, ≤ fs/2; needs "
    "--sample-rate-hz) [default: the recorded samples' own].",
)
@click.option(
    "--chunked/--in-memory",
    default=None,
    help="Stream the captures in chunks (flat memory; two passes over them) or load them whole "
    f"[default: chunked above {_SCALE_FACTOR_IN_MEMORY_MAX_ROWS:.0e} rows].",
)
@dask_options("one capture: NPZ without compression, HDF5 or TDMS")
@_clipping_option
@_analysis_options
@_names_capture
def gyro_scale_factor(
    capture: str,
    more_captures: tuple[str, ...],
    rate_files: dict[str, Any],
    log_opts: dict[str, Any],
    full_scale_deg_s: float | None,
    requirement: str | None,
    output_unit: str,
    sample_rate_hz: float | None,
    bandwidth_hz: float | None,
    chunked: bool | None,
    workers: int | None,
    scheduler: str | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Scale factor, bias and nonlinearity (%FS) of a gyro.

    Columns rate_deg_s (the table's set rate) and output (the gyro's, in its own unit); the
    rows of each set rate are averaged and V(Ω) = S·Ω + V0 is fitted by least squares
    (Kokuyama et al. 2015, §4). FS is the full scale, the largest set rate in magnitude unless given. A test kept as
    one file per set rate takes the rate of each file from its name (--rate-from-name) or from a
    table (--rates). One continuous log with time_s (the table stepping through rates) is cut
    into its plateaus first (--settle-s drops each plateau's start).
    """
    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    captures = [capture, *more_captures]
    options: dict[str, Any] = {
        "full_scale_deg_s": full_scale_deg_s,
        "requirement": requirement,
        "output_unit": output_unit,
        "specs": kw.pop("specs"),
        "sample_rate_hz": sample_rate_hz,
        "bandwidth_hz": bandwidth_hz,
        "allow_clipped": kw.pop("allow_clipped"),
    }
    if continuous_log(captures, rate_files, columns, group, log_opts, (workers, scheduler)):
        result = scale_factor_from_log(capture, columns, group, options, log_opts, chunked)
    elif split_wanted(workers, scheduler, chunked):
        result = _dask_scale_factor(
            captures, rate_files, columns, group, options, (workers, scheduler)
        )
    else:
        result = _scale_factor_here(captures, rate_files, columns, group, options, chunked)
    result = scale_factor_items(  # repeatability over runs, temperature coefficients
        result,
        captures,
        rate_files,
        columns,
        group,
        # each run needs S and its GUM u only: the Monte Carlo of NL at its smallest
        lambda path: _scale_factor_here(
            [path], rate_files, columns, group, {**options, "mc_trials": 2000}, chunked
        ),
    )
    data = _publish(
        result,
        json_path,
        report_path,
        capture,
        "Gyro scale factor and nonlinearity",
        "Kokuyama et al. (2015), §4: V(Ω) = S·Ω + V0 + δ(Ω), NL = max|δ|/FS",
        ("gyro_scale", "scale_factor_section"),
        lambda: log_sections(result),
    )
    if _summary_wanted():
        _print_scale_factor(result, data)


def _scale_factor_here(
    captures: list[str],
    rate_files: dict[str, Any],
    columns: Sequence[str],
    group: str | None,
    options: dict[str, Any],
    chunked: bool | None,
) -> Any:
    """The calibration in this process: streamed in chunks, or in memory."""
    from rotacal.gyro import calibrate_scale_factor, calibrate_scale_factor_chunked

    n = None if chunked is False else rate_row_count(captures, columns, group, rate_files)
    if chunked is None:
        chunked = n is not None and n > _SCALE_FACTOR_IN_MEMORY_MAX_ROWS
    if chunked:
        assert n is not None
        source = rate_row_chunks(captures, columns, group, rate_files)
        # two passes: the set rates alone, then both columns
        with _sample_progress(2 * n, "calibrating (chunked)") as progress:
            return calibrate_scale_factor_chunked(source, progress=progress, **options)
    rate, output = read_rate_rows(captures, columns, group, rate_files)
    with _status("fitting"):
        return calibrate_scale_factor(rate, output, **options)


def _dask_scale_factor(
    captures: list[str],
    rate_files: dict[str, Any],
    columns: Sequence[str],
    group: str | None,
    options: dict[str, Any],
    where: tuple[int | None, str | None],
) -> Any:
    """The calibration of one log split over a Dask cluster's workers
    (:func:`rotacal.batch.capture_scale_factor.calibrate_scale_factor_on_dask`)."""
    from rotacal.batch.capture_scale_factor import CHUNK_ROWS, calibrate_scale_factor_on_dask
    from rotacal.io import capture_length, parse_column_mapping

    if len(captures) > 1 or rate_files["rate_from_name"] or rate_files["rates_path"] is not None:
        raise ConfigError(
            "--workers and --scheduler split one capture holding rate_deg_s and output; analyse "
            "several captures, or one capture per set rate, in this process (drop them)"
        )
    if rate_files["rest_from"]:
        raise ConfigError(
            "--rest-from runs are analysed in this process; drop --workers/--scheduler"
        )
    reading: dict[str, Any] = {
        "mapping": parse_column_mapping(columns),
        "group": group,
        "read_options": current_read_options(),
    }
    n = capture_length(captures[0], "rate_deg_s", **reading)
    return run_on_dask(
        where,
        2 * (-(-n // CHUNK_ROWS)),  # two rounds of blocks
        "calibrating",
        lambda client, progress: calibrate_scale_factor_on_dask(
            captures[0], client=client, **reading, progress=progress, **options
        ),
        capture=captures[0],
        columns=["rate_deg_s", "output"],
        rows=n,
        reading=reading,
    )


def _print_scale_factor(result: Any, data: dict[str, Any]) -> None:
    unit = result.output_unit or "output unit"
    click.echo(f"scale factor S    {quantity_of(data, 'scale_factor', f'{unit}/(deg/s)')}")
    click.echo(f"bias V0           {quantity_of(data, 'bias', unit)}")
    click.echo(
        f"nonlinearity NL   {quantity_of(data, 'nonlinearity_percent_fs', '%FS', digits=4)} "
        f"(FS {result.full_scale_deg_s:g} deg/s, {result.n_points} rate points)"
    )
    corrected = result.nonlinearity_percent_fs_bias_corrected
    if np.isfinite(corrected):
        click.echo(f"NL bias-corrected {format_plain(corrected, '%FS', digits=4)}")
    if result.requirement is not None:
        for line in result.requirement.lines():
            click.echo(line)
    elif result.resolution is not None:
        value = format_plain(result.resolution.resolution_deg_s, "deg/s", digits=3)
        click.echo(f"resolution        {value} ({result.resolution.basis})")
    if result.decision_with_uncertainty is not None:
        click.echo(f"  {result.decision_with_uncertainty.line}")
    for line in item_lines(result):  # the IEEE Std 952/1431 items
        click.echo(line)


@gyro.command(
    "triad",
    epilog=example("rotacal gyro triad triad.h5 --json k.json"),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--reject-k",
    type=float,
    default=None,
    help="Reject residuals beyond k robust sigmas [default: 5 % family-wise for Gaussian noise].",
)
@click.option(
    "--output-unit",
    default="",
    help="Unit of the outputs ux, uy, uz (e.g. V, LSB, deg/s), for the results and the report.",
)
@runs_options
@_clipping_option
@_analysis_options
@_names_capture
def gyro_triad(
    capture: str,
    reject_k: float | None,
    output_unit: str,
    runs_opts: dict[str, Any],
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Three-axis scale/misalignment and bias.

    Columns wx_deg_s, wy_deg_s, wz_deg_s (the reference rate in the gyro's nominal axes) and
    ux, uy, uz (its raw outputs): u = K·ω + b by least squares, with outlier rejection (the
    modified six-position method of the robot-manipulator study, IEEE A&E Systems Magazine 2023).
    With --runs the capture is one log of rotation runs (time_s too): each run is averaged over
    its whole revolutions and K, b are fitted to the run means.
    """
    from rotacal.gyro import RATE_COLUMNS, TRIAD_OUTPUT_COLUMNS, calibrate_triad_columns

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    options = {
        "output_unit": output_unit,
        "specs": kw.pop("specs"),
        "allow_clipped": kw.pop("allow_clipped"),
    }
    if check_runs_options(runs_opts):
        options.update({} if reject_k is None else {"reject_k": reject_k})
        result = triad_from_log(capture, columns, group, runs_opts, options)
    else:
        cap = _read(capture, [*RATE_COLUMNS, *TRIAD_OUTPUT_COLUMNS], columns, group)
        with _status("fitting"):
            result = calibrate_triad_columns(cap.columns, reject_k=reject_k, **options)
    data = _publish(
        result,
        json_path,
        report_path,
        capture,
        "3-axis gyro calibration",
        "Modified six-position method (IEEE A&E Systems Magazine 2023): u = K·ω + b by least squares",
        ("triad", "triad_section"),
        lambda: runs_sections(result),
    )
    if _summary_wanted():
        _print_triad(result, data)
        click.echo(f"outliers rejected {result.outliers_rejected}")
        click.echo(
            "residual rms      "
            + "   ".join(format_plain(x, digits=3) for x in result.residual_rms)
        )


def _print_triad(result: Any, data: dict[str, Any]) -> None:
    """K (3 × 3) and the bias (3), each element with its U: the lines of triad and rotations."""
    unit = result.output_unit or "output unit"
    click.echo(f"K ({unit} per deg/s), rows x, y, z:")
    for row in range(3):
        line = elements_of(data, "scale_misalignment", [(row, col) for col in range(3)])
        click.echo(f"   {line}")
    click.echo(f"bias              {elements_of(data, 'bias', [(i,) for i in range(3)], unit)}")


@gyro.command(
    "rotations",
    epilog=example(
        "rotacal gyro rotations rot.csv --sections rot.csv.truth.json",
        "rotacal gyro rotations session.csv --sections session_list.json --fs-hz 102.4 "
        "--column gyr_x=ux --column gyr_y=uy --column gyr_z=uz "
        "--column acc_x=ax --column acc_y=ay --column acc_z=az --latitude-deg 49.6",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@sections_option
@click.option("--fs-hz", type=float, default=None, help="Sampling rate, when there is no time_s.")
@click.option(
    "--angle-deg",
    type=float,
    default=None,
    help="Set angle of each rotation in degrees, right-hand rule about the DUT's axis: -360 is "
    "one clockwise turn seen from the tip of the +axis (the Ferraris protocol, imucal's "
    "convention; the gyro reads negative), +360 one counter-clockwise turn. "
    "[default: the sections file's angle_deg, else -360]",
)
@gravity_options
@nominal_scale_option
@click.option(
    "--output-unit",
    default="",
    help="Unit of the outputs ux, uy, uz (e.g. V, LSB, deg/s), for the results and the report.",
)
@_clipping_option
@_analysis_options
@_names_capture
def gyro_rotations(
    capture: str,
    sections_path: str,
    fs_hz: float | None,
    angle_deg: float | None,
    latitude_deg: float | None,
    gravity_m_s2: float | None,
    position_u_deg: float,
    nominal_scale: float | None,
    output_unit: str,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Triad from rotations through a known angle (Ferraris).

    Columns ux, uy, uz (and time_s, or --fs-hz): the outputs integrated over each rotation
    give K and the bias of a three-axis gyro. With the accelerometer's ax, ay, az and the six
    static positions, its g-sensitivity K_ga and the Earth rate are separated from K.
    """
    from rotacal.gyro import calibrate_ferraris, calibrate_triad_rotations, ferraris_sections
    from rotacal.gyro.rotations import FERRARIS_ANGLE_DEG
    from rotacal.signal import check_sampling

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    sections, stated_angle = read_sections(sections_path)
    if angle_deg is None:  # a twin's truth file states the angle it turned through
        angle_deg = FERRARIS_ANGLE_DEG if stated_angle is None else stated_angle
    cap, rate, acc = read_triads(capture, columns, group)
    if "time_s" in cap.columns:
        check_sampling(cap["time_s"], "time_s")
        if cap["time_s"].size < 2:
            raise CaptureError(f"{Path(capture).name} holds one sample: too short for rotations")
        step = float(np.median(np.diff(cap["time_s"])))
        fs_hz = 1.0 / step if fs_hz is None else fs_hz
    if fs_hz is None:
        raise ConfigError(f"{Path(capture).name} has no time_s column: give --fs-hz")
    common = {
        "angle_deg": angle_deg,
        "nominal_scale": 1.0
        if nominal_scale is None and output_unit.strip().lower() in DEG_S_UNITS
        else nominal_scale,
        "output_unit": output_unit,
        "specs": kw.pop("specs"),
        "allow_clipped": kw.pop("allow_clipped"),
    }
    with _status("integrating the rotations"):
        if acc is not None and "rotations" not in sections:
            result: Any = calibrate_ferraris(
                rate,
                acc,
                fs_hz,
                sections,
                latitude_deg=latitude_deg,
                gravity_m_s2=gravity_m_s2,
                position_u_deg=position_u_deg,
                **common,
            )
        elif latitude_deg is not None or gravity_m_s2 is not None:
            raise ConfigError(
                "--latitude-deg and --gravity-m-s2 need the accelerometer columns ax, ay, az and "
                "imucal's six static positions (x_p … z_a) in --sections"
            )
        else:
            if "rotations" in sections:
                rotations, static = sections["rotations"], sections.get("static")
            else:
                rotations, static = ferraris_sections(sections)
            result = calibrate_triad_rotations(rate, fs_hz, rotations, static=static, **common)
    data = _publish(
        result,
        json_path,
        report_path,
        capture,
        "Gyro triad from rotations",
        "Rotations through a known angle (Ferraris et al.): Θ = K·Φ by least squares",
        ("triad", "rotations_section"),
    )
    if _summary_wanted():
        _print_triad(result, data)
        if "g_sensitivity" in data:
            echo_matrix(data, "g_sensitivity", "K_ga", f"{output_unit or 'output unit'}/(m/s²)")


@gyro.command(
    "multiposition",
    epilog=example("rotacal gyro multiposition mp.csv --axis x --latitude-deg 45.75"),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--axis",
    type=click.Choice(["x", "y"]),
    required=True,
    help="Input axis of the gyro on the turntable.",
)
@click.option(
    "--latitude-deg",
    type=float,
    default=None,
    help="Latitude of the laboratory (deg) (or site.latitude_deg in --specs).",
)
@_clipping_option
@_analysis_options
@_names_capture
def gyro_multiposition(
    capture: str,
    axis: str,
    latitude_deg: float | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Drift coefficients by multiposition.

    Columns phi1_deg (outer axis), phi2_deg (inner axis) and output_deg_h: the drift
    coefficients by least squares with the Earth rate and gravity at each position
    (GyroWheel study, Int. J. Aerospace Eng., eqs. 1–6).
    """
    from rotacal.gyro import calibrate_multiposition

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, list(GYRO_MULTIPOSITION.required), columns, group)
    with _status("fitting"):
        result = calibrate_multiposition(
            cap["phi1_deg"],
            cap["phi2_deg"],
            cap["output_deg_h"],
            axis=axis,
            latitude_deg=latitude_deg,
            specs=kw.pop("specs"),
            allow_clipped=kw.pop("allow_clipped"),
        )
    data = _publish(
        result,
        json_path,
        report_path,
        capture,
        "Multiposition calibration of drift coefficients",
        "GyroWheel study, eqs. (1)–(6): Earth rate and gravity at each turntable position",
        ("multiposition", "multiposition_section"),
    )
    if _summary_wanted():
        units = data.get("drift_coefficient_units", {})
        for name in result.drift_coefficients:
            coefficient = _drift_coefficient(data, name)
            click.echo(f"{name:<5} {quantity_of(coefficient, name, units.get(name, ''))}")


def _drift_coefficient(data: dict[str, Any], name: str) -> dict[str, Any]:
    """One drift coefficient of a multiposition result in the keys the formatter reads."""
    k = data.get("k", {}).get("drift_coefficients", {})
    return {
        name: data["drift_coefficients"][name],
        f"{name}_U": data.get("drift_coefficients_U", {}).get(name),
        "k": {name: k.get(name)},
        "coverage_probability": data.get("coverage_probability"),
    }


# each registers its subcommand on `gyro` as it is imported: accelerometer, frequency-response,
# resolution
from . import gyro_accel, gyro_frequency, gyro_resolution  # noqa: E402,F401
