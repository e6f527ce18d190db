"""``rotacal gyro``: gyroscope calibrations (seeds 004, 003, 001)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click
import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._app import cli
from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _clipping_option,
    _emit_warnings,
    _names_capture,
    _read,
    _status,
    _write_json,
    _write_report,
)
from ._reading import current_read_options


@cli.group()
def gyro() -> None:
    """Gyroscope calibrations on the table (seeds 004, 003, 001)."""


@gyro.command("scale-factor")
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--full-scale-deg-s",
    type=float,
    default=None,
    help="FS for the nonlinearity in %FS [default: the largest |set rate|].",
)
@click.option(
    "--requirement",
    default=None,
    help="Check against a named requirement (fmvss126) and say pass/fail with the margin.",
)
@click.option("--output-unit", default="", help="Unit of the output column, for the report.")
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
@_clipping_option
@_analysis_options
@_names_capture
def gyro_scale_factor(
    capture: str,
    full_scale_deg_s: float | None,
    requirement: str | None,
    output_unit: str,
    sample_rate_hz: float | None,
    bandwidth_hz: float | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Scale factor, bias, nonlinearity %FS: capture with rate_deg_s (set rate), output."""
    from rotacal.gyro import calibrate_scale_factor

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, ["rate_deg_s", "output"], columns, group)
    with _status("fitting"):
        result = calibrate_scale_factor(
            cap["rate_deg_s"],
            cap["output"],
            full_scale_deg_s=full_scale_deg_s,
            requirement=requirement,
            output_unit=output_unit,
            specs=kw.pop("specs"),
            sample_rate_hz=sample_rate_hz,
            bandwidth_hz=bandwidth_hz,
            allow_clipped=kw.pop("allow_clipped"),
        )
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path)
    if report_path:
        from rotacal.report.gyro_scale import scale_factor_section

        _write_report(
            "Gyro scale factor and nonlinearity",
            "Kokuyama et al. (seed 004), §4: V(Ω) = S·Ω + V0 + δ(Ω), NL = max|δ|/FS",
            [scale_factor_section(result)],
            capture,
            report_path,
            warnings=result.warnings,
        )
    if json_path is None and report_path is None:
        for line in result.summary_lines():
            click.echo(line)


@gyro.command("triad")
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--reject-k",
    type=float,
    default=None,
    help="Reject residuals beyond k robust sigmas [default: 5 % family-wise for Gaussian noise].",
)
@_clipping_option
@_analysis_options
@_names_capture
def gyro_triad(
    capture: str, reject_k: float | None, columns: Sequence[str], group: str | None, **kw: Any
) -> None:
    """3-axis K and bias with outlier rejection: wx_deg_s, wy_deg_s, wz_deg_s, ux, uy, uz."""
    from rotacal.gyro import RATE_COLUMNS, TRIAD_OUTPUT_COLUMNS, calibrate_triad_columns

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, [*RATE_COLUMNS, *TRIAD_OUTPUT_COLUMNS], columns, group)
    with _status("fitting"):
        result = calibrate_triad_columns(
            cap.columns,
            reject_k=reject_k,
            specs=kw.pop("specs"),
            allow_clipped=kw.pop("allow_clipped"),
        )
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path)
    if report_path:
        from rotacal.report.triad import triad_section

        _write_report(
            "3-axis gyro calibration",
            "Modified six-position method (seed 003): u = K·ω + b by least squares",
            [triad_section(result)],
            capture,
            report_path,
            warnings=result.warnings,
        )
    if json_path is None and report_path is None:
        k = np.asarray(result.scale_misalignment)
        click.echo("K (output per deg/s):")
        for row in k:
            click.echo("   " + "  ".join(f"{x:+.6f}" for x in row))
        click.echo("bias              " + "  ".join(f"{x:+.5g}" for x in result.bias))
        click.echo(f"outliers rejected {result.outliers_rejected}")
        click.echo("residual rms      " + "  ".join(f"{x:.3g}" for x in result.residual_rms))


@gyro.command("rotations")
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--sections",
    "sections_path",
    type=INPUT_FILE,
    required=True,
    help="JSON of sample ranges: imucal's Ferraris list (x_p … z_a, x_rot, y_rot, z_rot) or "
    "{'rotations': {'x': [start, stop], …}, 'static': {…}} (a twin's truth file works).",
)
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
@_clipping_option
@_analysis_options
@_names_capture
def gyro_rotations(
    capture: str,
    sections_path: str,
    fs_hz: float | None,
    angle_deg: float | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Triad K and bias from rotations through a known angle (Ferraris): ux, uy, uz."""
    from rotacal.gyro import TRIAD_OUTPUT_COLUMNS, calibrate_triad_rotations, ferraris_sections
    from rotacal.gyro.rotations import FERRARIS_ANGLE_DEG
    from rotacal.io import parse_column_mapping, read_capture
    from rotacal.signal import check_sampling

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    try:
        spec = json.loads(Path(sections_path).read_text(encoding="utf-8"))
    except OSError as e:
        raise ConfigError(f"--sections {sections_path}: cannot read it ({e.strerror})") from None
    except json.JSONDecodeError as e:
        raise ConfigError(
            f"--sections {sections_path} is not JSON ({e.msg}, line {e.lineno})"
        ) from None
    if not isinstance(spec, dict):
        raise ConfigError(f"--sections {sections_path} must hold a JSON object of sample ranges")
    if "rotations" in spec:
        rotations, static = spec["rotations"], spec.get("static")
    else:
        rotations, static = ferraris_sections(spec)
    if angle_deg is None:  # a twin's truth file states the angle it turned through
        angle_deg = spec.get("angle_deg", FERRARIS_ANGLE_DEG)
        if isinstance(angle_deg, bool) or not isinstance(angle_deg, (int, float)):
            raise ConfigError(
                f"--sections {sections_path}: angle_deg must be a number of degrees, got "
                f"{angle_deg!r}; fix it or give --angle-deg"
            )
    with _status(f"reading {capture}"):
        cap = read_capture(
            capture,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )
    missing = [c for c in TRIAD_OUTPUT_COLUMNS if c not in cap.columns]
    if missing:
        raise CaptureError(
            f"{Path(capture).name} has no column {missing[0]!r}; map the gyro outputs with "
            "--column gyr_x=ux (and uy, uz)"
        )
    if "time_s" in cap.columns:
        check_sampling(cap["time_s"], "time_s")
        if cap["time_s"].size < 2:
            raise CaptureError(f"{Path(capture).name} holds one sample: too short for rotations")
        step = float(np.median(np.diff(cap["time_s"])))
        fs_hz = 1.0 / step if fs_hz is None else fs_hz
    if fs_hz is None:
        raise ConfigError(f"{Path(capture).name} has no time_s column: give --fs-hz")
    rate = np.column_stack([cap[c] for c in TRIAD_OUTPUT_COLUMNS])
    with _status("integrating the rotations"):
        result = calibrate_triad_rotations(
            rate,
            fs_hz,
            rotations,
            static=static,
            angle_deg=angle_deg,
            specs=kw.pop("specs"),
            allow_clipped=kw.pop("allow_clipped"),
        )
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path)
    if report_path:
        from rotacal.report.triad import rotations_section

        _write_report(
            "Gyro triad from rotations",
            "Rotations through a known angle (Ferraris et al.): Θ = K·Φ by least squares",
            [rotations_section(result)],
            capture,
            report_path,
            warnings=result.warnings,
        )
    if json_path is None and report_path is None:
        click.echo("K (output per deg/s):")
        for row in np.asarray(result.scale_misalignment):
            click.echo("   " + "  ".join(f"{x:+.6f}" for x in row))
        click.echo("bias              " + "  ".join(f"{x:+.5g}" for x in result.bias))


@gyro.command("multiposition")
@click.argument("capture", type=INPUT_FILE)
@click.option("--axis", type=click.Choice(["x", "y"]), required=True, help="Gyro axis.")
@click.option(
    "--latitude-deg",
    type=float,
    default=None,
    help="Latitude of the laboratory (or site.latitude_deg in --specs).",
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
    """Drift coefficients: phi1_deg, phi2_deg, output_deg_h (seed 001, eqs. 1–6)."""
    from rotacal.gyro import calibrate_multiposition

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, ["phi1_deg", "phi2_deg", "output_deg_h"], columns, group)
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
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path)
    if report_path:
        from rotacal.report.multiposition import multiposition_section

        _write_report(
            "Multiposition calibration of drift coefficients",
            "Seed 001, eqs. (1)–(6): Earth rate and gravity at each turntable position",
            [multiposition_section(result)],
            capture,
            report_path,
            warnings=result.warnings,
        )
    if json_path is None and report_path is None:
        for name, value in result.drift_coefficients.items():
            u = result.drift_coefficients_u[name]
            click.echo(f"{name:<5} {value:+.6f} ± {u:.2g}")
