"""The ``rotacal`` command: thin shells over the public functions.

A user's mistake (bad file, missing column, impossible option) ends with ONE line on stderr and exit
code 2. Unexpected internal errors end with one line and exit code 1; set ROTACAL_DEBUG=1 to see the
traceback.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import CaptureError, ConfigError, RotacalError

F = TypeVar("F", bound=Callable[..., Any])


class _Group(click.Group):
    """Turns every error into one line: exit 2 for the user's, 1 for ours."""

    def main(self, *args: Any, **kwargs: Any) -> Any:
        try:
            # Warnings become one line each; NumPy's floating-point chatter is silenced because
            # the checks name the fault (a NaN, an overflowing value) themselves.
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.showwarning = _one_line_warning
                return super().main(*args, **{**kwargs, "standalone_mode": False})
        except click.exceptions.Exit as e:
            sys.exit(e.exit_code)
        except click.Abort:
            click.echo("rotacal: aborted", err=True)
            sys.exit(130)
        except click.UsageError as e:
            hint = f" (see '{e.ctx.command_path} --help')" if e.ctx else ""
            click.echo(f"rotacal: error: {e.format_message()}{hint}", err=True)
            sys.exit(2)
        except click.ClickException as e:
            click.echo(f"rotacal: error: {e.format_message()}", err=True)
            sys.exit(2)
        except RotacalError as e:
            click.echo(f"rotacal: error: {_one_line(e)}", err=True)
            sys.exit(2)
        except (FileNotFoundError, IsADirectoryError, PermissionError) as e:
            click.echo(f"rotacal: error: {e.strerror}: {e.filename}", err=True)
            sys.exit(2)
        except MemoryError:
            click.echo(
                "rotacal: error: out of memory — analyse a shorter span (--periods)", err=True
            )
            sys.exit(2)
        except Exception as e:  # pragma: no cover - a bug, not a user error
            if os.environ.get("ROTACAL_DEBUG"):
                raise
            click.echo(
                f"rotacal: internal error: {type(e).__name__}: {_one_line(e)} "
                "(a bug: please report it; ROTACAL_DEBUG=1 shows the traceback)",
                err=True,
            )
            sys.exit(1)


def _one_line_warning(message: Any, *args: Any, **kwargs: Any) -> None:
    click.echo(f"rotacal: warning: {' '.join(str(message).split())}", err=True)


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


@contextlib.contextmanager
def _progress(total: int, description: str) -> Iterator[Callable[[str], None]]:
    """A progress bar on a terminal (stderr), silent otherwise. Yields ``advance(label)``."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        disable=not console.is_terminal,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=total)

        def advance(label: str) -> None:
            bar.update(task, advance=1, description=f"{description}: {label}")

        yield advance


#: Above this many samples the encoder capture is streamed in chunks (its memory then stays flat;
#: in memory the pipeline holds ~8 float64 copies of the capture).
_IN_MEMORY_MAX_SAMPLES = 30_000_000


@contextlib.contextmanager
def _sample_progress(total: int, description: str) -> Iterator[Callable[[int], None]]:
    """A progress bar over samples processed, on a terminal (stderr); silent otherwise."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    console = Console(stderr=True)
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f} %"),
        TimeRemainingColumn(),
        console=console,
        disable=not console.is_terminal,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=total)
        yield lambda done: bar.update(task, completed=done)


@contextlib.contextmanager
def _status(message: str) -> Iterator[None]:
    """A spinner with a message on a terminal (stderr) while a long step runs; silent otherwise."""
    from rich.console import Console

    console = Console(stderr=True)
    if not console.is_terminal:
        yield
        return
    with console.status(message):
        yield


def _check_outputs(json_path: str | None, report_path: str | None, overwrite: bool) -> None:
    """Refuse outputs that would replace an existing file (unless --overwrite) or each other."""
    if report_path == "-":
        raise ConfigError("--report needs a file name (the report is HTML, not for stdout)")
    if json_path and report_path and json_path != "-":
        if Path(json_path).resolve() == Path(report_path).resolve():
            raise ConfigError("--json and --report name the same file; give them different names")
    for option, target in (("--json", json_path), ("--report", report_path)):
        if not target or target == "-":
            continue
        if Path(target).is_dir():
            raise ConfigError(f"{option} {target} is a folder; give a file name")
        if not overwrite and Path(target).exists():
            raise ConfigError(f"{option} {target} exists; choose another name or pass --overwrite")


def _write_json(data: Any, target: str | None, protect: Sequence[Path] = ()) -> None:
    if target is None:
        return
    from rotacal.results import to_jsonable

    text = json.dumps(to_jsonable(data), indent=2, allow_nan=False)
    if target == "-":
        click.echo(text)
        return
    path = Path(target)
    _refuse_overwrite(path, protect, "--json")
    if not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + "\n", encoding="utf-8")


def _refuse_overwrite(path: Path, protect: Sequence[Path], option: str) -> None:
    for p in protect:
        if path.exists() and p.exists() and path.resolve() == p.resolve():
            raise ConfigError(
                f"{option} {path} would overwrite the input file {p}; choose another name"
            )


def _load_specs_option(ctx: click.Context, param: click.Parameter, value: str | None) -> Any:
    """``--specs FILE.toml`` → InstrumentSpecs (one line on any fault, before the capture is read)."""
    if value is None:
        return None
    from rotacal.uncertainty.specs import load_specs

    if not Path(value).is_file():
        raise ConfigError(f"--specs {value}: no such file")
    return load_specs(Path(value))


def _analysis_options(func: F) -> F:
    """Options every analysis command takes."""
    options = [
        click.option(
            "--json", "json_path", metavar="PATH", help="Write the results as JSON ('-' = stdout)."
        ),
        click.option(
            "--report",
            "report_path",
            metavar="PATH.html",
            help="Write a self-contained HTML report.",
        ),
        click.option(
            "--column",
            "columns",
            multiple=True,
            metavar="OLD=NEW",
            help="Map a column of the file onto a canonical name (repeatable).",
        ),
        click.option("--group", default=None, help="HDF5 group or TDMS group holding the columns."),
        click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files."),
        click.option(
            "--specs",
            "specs",
            metavar="FILE.toml",
            callback=_load_specs_option,
            expose_value=True,
            help="Instrument specifications (Type B inputs of the uncertainty budgets; see "
            "'rotacal specs example').",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _read(path: str, needed: list[str], columns: Sequence[str], group: str | None) -> Any:
    from rotacal.io import parse_column_mapping, read_capture

    with _status(f"reading {path}"):
        return read_capture(
            path, columns=needed, mapping=parse_column_mapping(columns), group=group
        )


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rotacal")
def cli() -> None:
    """rotacal — calibration of rotary tables and the gyroscopes tested on them.

    Start with `rotacal demo`, then point an analysis command at your own capture.
    """


# ---------------------------------------------------------------------------------------------- motion
@cli.group()
def motion() -> None:
    """Sinusoidal-motion calibration of a rotary table (Feng et al. 2023)."""


def _motion_common(func: F) -> F:
    options = [
        click.option(
            "--harmonics",
            default=10,
            show_default=True,
            help="N_H: highest harmonic in fit and THD.",
        ),
        click.option(
            "--periods", type=int, default=None, help="Whole periods to analyse [default: all]."
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
    ]
    for option in reversed(options):
        func = option(func)
    return _analysis_options(func)


def _finish_motion(
    result: Any, capture_path: str, json_path: str | None, report_path: str | None
) -> None:
    protect = (Path(capture_path),)
    for note in result.notes:
        if "partial" in note:
            click.echo(
                f"rotacal: warning: {note}: amplitude and THD may be biased by the signals' "
                "gain and phase errors; prefer the LTS scheme for motions this small",
                err=True,
            )
    _write_json(result.to_dict(), json_path, protect)
    if report_path:
        from rotacal.report.html import Report, write_html
        from rotacal.report.motion import motion_section

        report = Report(
            title="Sinusoidal-motion calibration",
            subtitle="Feng et al. (2023), Sensors 23:4876 — IEEE Std 1057 sine fitting",
            sections=[motion_section(result)],
            inputs={"capture": str(capture_path)},
        )
        _refuse_overwrite(Path(report_path), protect, "--report")
        with _status("drawing the report"):
            write_html(report, report_path)
    if json_path is None and report_path is None:
        _print_motion(result)


def _print_motion(r: Any) -> None:
    click.echo(f"scheme            {r.scheme}")
    click.echo(f"amplitude         {r.amplitude_deg:.7g} deg")
    click.echo(f"frequency         {r.frequency_hz:.9g} Hz")
    click.echo(f"ang. acceleration {r.angular_acceleration_amplitude_deg_s2:.6g} deg/s^2")
    click.echo(
        f"THD               {r.thd_percent:.4f} %  (u = {r.thd_percent_u:.2g} %, h = 2..{r.harmonics})"
    )
    click.echo(
        f"periods used      {r.periods_used}  ({r.reversal_times_s.size} reversing moments found)"
    )
    if r.snr_db is not None:
        click.echo(f"SNR               {r.snr_db:.2f} dB")
    for note in r.notes:
        click.echo(f"note              {note}")
    if r.set_amplitude_deg is not None:
        click.echo(f"amplitude error   {r.amplitude_error_percent:+.4f} %")
        click.echo(f"frequency error   {r.frequency_error_percent:+.5f} %")
        click.echo(
            f"position error    max {r.position_error_max_deg:.4g} deg, rms {r.position_error_rms_deg:.4g} deg"
        )


@motion.command("encoder")
@click.argument("capture", type=click.Path(dir_okay=False))
@click.option("--lines", type=int, required=True, help="Encoder lines per revolution (e.g. 36000).")
@click.option(
    "--correction-from",
    type=click.Path(dir_okay=False),
    default=None,
    help="Fit the Heydemann correction on this capture (time_s, a, b with more motion, same "
    "encoder and electronics) instead of on CAPTURE: for motions shorter than a signal period.",
)
@click.option(
    "--chunked/--in-memory",
    default=None,
    help="Stream the capture in chunks (flat memory) or load it whole "
    f"[default: chunked above {_IN_MEMORY_MAX_SAMPLES:.0e} samples].",
)
@_motion_common
def motion_encoder(
    capture: str,
    lines: int,
    correction_from: str | None,
    chunked: bool | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """OSE scheme: capture with columns time_s, a, b (quadrature signals)."""
    from rotacal.io import capture_length, parse_column_mapping
    from rotacal.table import (
        calibrate_encoder_motion,
        calibrate_encoder_motion_chunked,
        encoder_chunks_from_file,
    )

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    mapping = parse_column_mapping(columns)
    if correction_from is not None:
        from rotacal.encoder import fit_quadrature_correction

        ref = _read(correction_from, ["a", "b"], columns, group)
        kw["correction"] = fit_quadrature_correction(ref["a"], ref["b"])
        if kw["correction"].method != "heydemann":
            raise CaptureError(
                f"--correction-from {correction_from} covers only part of a signal period too; "
                "record the reference with the table turning through several signal periods"
            )
    n = capture_length(capture, "a", mapping=mapping, group=group)
    if chunked is None:
        chunked = n > _IN_MEMORY_MAX_SAMPLES
    if chunked:
        source = encoder_chunks_from_file(capture, mapping=mapping, group=group)
        # the chunked calibration reads the capture in up to six passes
        with _sample_progress(6 * n, "calibrating (chunked)") as progress:
            result = calibrate_encoder_motion_chunked(source, lines=lines, progress=progress, **kw)
    else:
        cap = _read(capture, ["time_s", "a", "b"], columns, group)
        with _status("demodulating and fitting"):
            result = calibrate_encoder_motion(cap["time_s"], cap["a"], cap["b"], lines=lines, **kw)
    _finish_motion(result, capture, json_path, report_path)


@motion.command("lts")
@click.argument("capture", type=click.Path(dir_okay=False))
@click.option("--radius-mm", type=float, required=True, help="R: laser spot to table axis (mm).")
@_motion_common
def motion_lts(
    capture: str, radius_mm: float, columns: Sequence[str], group: str | None, **kw: Any
) -> None:
    """LTS scheme: capture with columns time_s, displacement_mm; θ = arctan(D/R)."""
    from rotacal.table import calibrate_lts_motion

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, ["time_s", "displacement_mm"], columns, group)
    with _status("fitting"):
        result = calibrate_lts_motion(
            cap["time_s"], cap["displacement_mm"], radius_mm=radius_mm, **kw
        )
    _finish_motion(result, capture, json_path, report_path)


@motion.command("fog")
@click.argument("capture", type=click.Path(dir_okay=False))
@_motion_common
def motion_fog(capture: str, columns: Sequence[str], group: str | None, **kw: Any) -> None:
    """FOG scheme: capture with columns time_s, rate_deg_s; THD of displacement from the rate fit."""
    from rotacal.table import calibrate_fog_motion

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, ["time_s", "rate_deg_s"], columns, group)
    with _status("fitting"):
        result = calibrate_fog_motion(cap["time_s"], cap["rate_deg_s"], **kw)
    _finish_motion(result, capture, json_path, report_path)


# ------------------------------------------------------------------------------ multi-head encoder
def _read_heads(path: str, columns: Sequence[str], group: str | None) -> Any:
    from rotacal.encoder.pulses import head_columns
    from rotacal.io import parse_column_mapping, read_capture

    with _status(f"reading {path}"):
        cap = read_capture(path, mapping=parse_column_mapping(columns), group=group, ragged=True)
    try:
        return head_columns(cap.columns)
    except CaptureError as e:
        raise CaptureError(f"{Path(path).name}: {e}") from None


def _write_report(
    title: str, subtitle: str, sections: list[Any], capture: str, report_path: str | None
) -> None:
    if not report_path:
        return
    from rotacal.report.html import Report, write_html

    report = Report(title=title, subtitle=subtitle, sections=sections, inputs={"capture": capture})
    _refuse_overwrite(Path(report_path), (Path(capture),), "--report")
    with _status("drawing the report"):
        write_html(report, report_path)


_PULSES_PER_REV = click.option(
    "--pulses-per-rev", type=int, required=True, help="m: pulses per revolution of one head."
)
_SEED004 = "Kokuyama et al., angular velocity standard with a self-calibratable encoder (seed 004)"


@cli.command("selfcal")
@click.argument("capture", type=click.Path(dir_okay=False))
@_PULSES_PER_REV
@click.option(
    "--rotation",
    type=click.Choice(["auto", "forward", "reverse"]),
    default="auto",
    show_default=True,
    help="Whether head i lies i·360/n ahead of head 0 in the sense of rotation (forward).",
)
@_analysis_options
def selfcal_cmd(
    capture: str,
    pulses_per_rev: int,
    rotation: str,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Scale deviation of a multi-head encoder (columns head_0 … head_{n-1}: pulse times, s)."""
    from rotacal.encoder.selfcal import self_calibrate

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    heads = _read_heads(capture, columns, group)
    with _status("self-calibrating"):
        result = self_calibrate(
            heads,
            pulses_per_rev=pulses_per_rev,
            rotation=rotation,  # type: ignore[arg-type]
            specs=kw.pop("specs"),
        )
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.pulses import selfcal_section

        _write_report(
            "Self-calibration of a multi-head encoder",
            _SEED004 + " — equal-division-averaged method",
            [selfcal_section(result)],
            capture,
            report_path,
        )
    if json_path is None and report_path is None:
        click.echo(f"heads x pulses/rev    {result.heads} x {result.pulses_per_rev}")
        click.echo(f"revolutions averaged  {result.revolutions_used}")
        click.echo(f"deviation p-p         {result.deviation_pp_arcsec:.4g} arcsec")
        click.echo(f"deviation rms         {result.deviation_rms_arcsec:.4g} arcsec")
        if result.repeatability_rms_arcsec is not None:
            click.echo(f"repeatability rms     {result.repeatability_rms_arcsec:.3g} arcsec")
        click.echo(f"closure residual rms  {result.closure_residual_rms_arcsec:.3g} arcsec")
        click.echo(f"note                  {result.undetectable_harmonics_note}")
        for note in result.notes:
            click.echo(f"note                  {note}")


@cli.command("rate")
@click.argument("capture", type=click.Path(dir_okay=False))
@_PULSES_PER_REV
@click.option(
    "--selfcal",
    "selfcal_path",
    type=click.Path(dir_okay=False),
    default=None,
    help="A `rotacal selfcal --json` result to compensate with [default: self-calibrate CAPTURE "
    "when it has several heads].",
)
@click.option(
    "--head", default="0", show_default=True, help="Head whose pulses give the rate, or 'all'."
)
@click.option(
    "--average", type=int, default=10, show_default=True, help="Pulse intervals per rate point."
)
@click.option("--set-rate-deg-s", type=float, default=None, help="Commanded rate, for the bias.")
@click.option("--no-compensation", is_flag=True, help="Use the nominal pitch only.")
@_analysis_options
def rate_cmd(
    capture: str,
    pulses_per_rev: int,
    selfcal_path: str | None,
    head: str,
    average: int,
    set_rate_deg_s: float | None,
    no_compensation: bool,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Angular velocity from pulse timing: mean, bias, stability, root Allan variance vs angle."""
    from rotacal.table.rate import calibrate_rate

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    selfcal: Any = None
    if selfcal_path is not None:
        try:
            selfcal = json.loads(Path(selfcal_path).read_text(encoding="utf-8"))
        except OSError as e:
            raise ConfigError(f"--selfcal {selfcal_path}: cannot read it ({e.strerror})") from None
        except json.JSONDecodeError as e:
            raise ConfigError(
                f"--selfcal {selfcal_path} is not JSON ({e.msg}, line {e.lineno})"
            ) from None
        if not isinstance(selfcal, dict):
            raise ConfigError(f"--selfcal {selfcal_path} is not a `rotacal selfcal --json` result")
    heads = _read_heads(capture, columns, group)
    with _status("timing the pulses"):
        result = calibrate_rate(
            heads,
            pulses_per_rev=pulses_per_rev,
            selfcal=selfcal,
            head=head,
            average=average,
            set_rate_deg_s=set_rate_deg_s,
            compensate=not no_compensation,
            specs=kw.pop("specs"),
        )
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.pulses import rate_section, selfcal_section

        sections = [rate_section(result)]
        if result.selfcal is not None:
            sections.append(selfcal_section(result.selfcal))
        _write_report(
            "Angular-velocity stability of a rate table", _SEED004, sections, capture, report_path
        )
    if json_path is None and report_path is None:
        click.echo(f"mean rate          {result.mean_rate_deg_s:.7f} deg/s ({result.head})")
        if result.rate_bias_percent is not None:
            click.echo(
                f"bias               {result.rate_bias_deg_s:+.3g} deg/s "
                f"({result.rate_bias_percent:+.3g} %)"
            )
        click.echo(
            f"rate deviation     rms {result.rate_deviation_rms_percent:.3g} %, "
            f"peak {result.rate_deviation_peak_percent:.3g} %"
            + (" (compensated)" if result.compensated else "")
        )
        for phi, s in zip(result.allan_angle_deg, result.allan_relative, strict=True):
            if (
                abs(math.log10(phi)) < 0.04
                or abs(math.log10(phi / 10)) < 0.04
                or abs(math.log10(phi / 360)) < 0.01
            ):
                click.echo(f"s({phi:.4g} deg)".ljust(19) + f"{100 * s:.3g} %")
        for note in result.notes:
            click.echo(f"note               {note}")


# ------------------------------------------------------------------------------------------------ gyro
@cli.group()
def gyro() -> None:
    """Gyroscope calibrations on the table (seeds 004, 003, 001)."""


@gyro.command("scale-factor")
@click.argument("capture", type=click.Path(dir_okay=False))
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
@_analysis_options
def gyro_scale_factor(
    capture: str,
    full_scale_deg_s: float | None,
    requirement: str | None,
    output_unit: str,
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
        )
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.gyro_scale import scale_factor_section

        _write_report(
            "Gyro scale factor and nonlinearity",
            "Kokuyama et al. (seed 004), §4: V(Ω) = S·Ω + V0 + δ(Ω), NL = max|δ|/FS",
            [scale_factor_section(result)],
            capture,
            report_path,
        )
    if json_path is None and report_path is None:
        for line in result.summary_lines():
            click.echo(line)


@gyro.command("triad")
@click.argument("capture", type=click.Path(dir_okay=False))
@click.option(
    "--reject-k",
    type=float,
    default=None,
    help="Reject residuals beyond k robust sigmas [default: 5 % family-wise for Gaussian noise].",
)
@_analysis_options
def gyro_triad(
    capture: str, reject_k: float | None, columns: Sequence[str], group: str | None, **kw: Any
) -> None:
    """3-axis K and bias with outlier rejection: wx_deg_s, wy_deg_s, wz_deg_s, ux, uy, uz."""
    from rotacal.gyro import RATE_COLUMNS, TRIAD_OUTPUT_COLUMNS, calibrate_triad_columns

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    cap = _read(capture, [*RATE_COLUMNS, *TRIAD_OUTPUT_COLUMNS], columns, group)
    with _status("fitting"):
        result = calibrate_triad_columns(cap.columns, reject_k=reject_k, specs=kw.pop("specs"))
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.triad import triad_section

        _write_report(
            "3-axis gyro calibration",
            "Modified six-position method (seed 003): u = K·ω + b by least squares",
            [triad_section(result)],
            capture,
            report_path,
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
@click.argument("capture", type=click.Path(dir_okay=False))
@click.option(
    "--sections",
    "sections_path",
    type=click.Path(dir_okay=False),
    required=True,
    help="JSON of sample ranges: imucal's Ferraris list (x_p … z_a, x_rot, y_rot, z_rot) or "
    "{'rotations': {'x': [start, stop], …}, 'static': {…}} (a twin's truth file works).",
)
@click.option("--fs-hz", type=float, default=None, help="Sampling rate, when there is no time_s.")
@click.option(
    "--angle-deg", type=float, default=360.0, show_default=True, help="Angle of each rotation."
)
@_analysis_options
def gyro_rotations(
    capture: str,
    sections_path: str,
    fs_hz: float | None,
    angle_deg: float,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Triad K and bias from rotations through a known angle (Ferraris): ux, uy, uz."""
    from rotacal.gyro import TRIAD_OUTPUT_COLUMNS, calibrate_triad_rotations, ferraris_sections
    from rotacal.io import parse_column_mapping, read_capture

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
    with _status(f"reading {capture}"):
        cap = read_capture(capture, mapping=parse_column_mapping(columns), group=group)
    missing = [c for c in TRIAD_OUTPUT_COLUMNS if c not in cap.columns]
    if missing:
        raise CaptureError(
            f"{Path(capture).name} has no column {missing[0]!r}; map the gyro outputs with "
            "--column gyr_x=ux (and uy, uz)"
        )
    if "time_s" in cap.columns:
        step = float(np.median(np.diff(cap["time_s"])))
        fs_hz = 1.0 / step if fs_hz is None else fs_hz
    if fs_hz is None:
        raise ConfigError(f"{Path(capture).name} has no time_s column: give --fs-hz")
    rate = np.column_stack([cap[c] for c in TRIAD_OUTPUT_COLUMNS])
    with _status("integrating the rotations"):
        result = calibrate_triad_rotations(
            rate, fs_hz, rotations, static=static, angle_deg=angle_deg, specs=kw.pop("specs")
        )
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.triad import rotations_section

        _write_report(
            "Gyro triad from rotations",
            "Rotations through a known angle (Ferraris et al.): Θ = K·Φ by least squares",
            [rotations_section(result)],
            capture,
            report_path,
        )
    if json_path is None and report_path is None:
        click.echo("K (output per deg/s):")
        for row in np.asarray(result.scale_misalignment):
            click.echo("   " + "  ".join(f"{x:+.6f}" for x in row))
        click.echo("bias              " + "  ".join(f"{x:+.5g}" for x in result.bias))


@gyro.command("multiposition")
@click.argument("capture", type=click.Path(dir_okay=False))
@click.option("--axis", type=click.Choice(["x", "y"]), required=True, help="Gyro axis.")
@click.option(
    "--latitude-deg",
    type=float,
    default=None,
    help="Latitude of the laboratory (or site.latitude_deg in --specs).",
)
@_analysis_options
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
        )
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.multiposition import multiposition_section

        _write_report(
            "Multiposition calibration of drift coefficients",
            "Seed 001, eqs. (1)–(6): Earth rate and gravity at each turntable position",
            [multiposition_section(result)],
            capture,
            report_path,
        )
    if json_path is None and report_path is None:
        for name, value in result.drift_coefficients.items():
            u = result.drift_coefficients_u[name]
            click.echo(f"{name:<5} {value:+.6f} ± {u:.2g}")


# ------------------------------------------------------------------------------------------- turntable
@cli.group("turntable")
def turntable() -> None:
    """Turntable geometric errors: model, sensitivities, allocation, Monte Carlo (seed 001)."""


_SEED001 = "GyroWheel calibration tests: turntable error analysis and allocation (seed 001)"


@turntable.command("budget")
@click.argument("config", type=click.Path(dir_okay=False))
@click.option(
    "--runs", type=int, default=None, help="Monte Carlo draws (default: config, else 10⁶)."
)
@click.option(
    "--seed", type=int, default=None, help="Seed of the draws (default: config, else 2026)."
)
@click.option(
    "--json", "json_path", metavar="PATH", help="Write the results as JSON ('-' = stdout)."
)
@click.option("--report", "report_path", metavar="PATH.html", help="Write an HTML report.")
@click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files.")
def turntable_budget_cmd(
    config: str,
    runs: int | None,
    seed: int | None,
    json_path: str | None,
    report_path: str | None,
    overwrite: bool,
) -> None:
    """Allocate accuracy to a turntable's error sources and check it (CONFIG.toml: see
    'rotacal turntable example')."""
    from rotacal.turntable import load_turntable, turntable_budget

    _check_outputs(json_path, report_path, overwrite)
    table = load_turntable(Path(config))
    runs_total = (
        runs
        if runs is not None
        else int(table.settings.get("monte_carlo", {}).get("runs", 1_000_000))
    )
    with _sample_progress(runs_total, "Monte Carlo") as advance:
        result = turntable_budget(
            table, runs=runs, seed=seed, progress=lambda done, _t: advance(done)
        )
    _write_json(result.to_dict(), json_path, (Path(config),))
    if report_path:
        from rotacal.report.turntable import turntable_section

        _write_report(
            f"Turntable error budget: {result.table}",
            _SEED001 + " — eqs. (7)–(34)",
            [turntable_section(result)],
            config,
            report_path,
        )
    if json_path is None and report_path is None:
        req = result.requirement_arcmin
        click.echo(
            "requirement (arcmin)  "
            + "  ".join(f"{c} {req[c]:.4g}" for c in ("psi", "theta", "gamma"))
            + f"  ({result.requirement_source})"
        )
        click.echo(f"{'error':<10} {'lower':>9} {'upper':>9}  (arcmin)  set by")
        for name, ub in result.upper_bounds_arcmin.items():
            lb = result.lower_bounds_arcmin.get(name)
            if ub is None:
                click.echo(f"{name:<10} {'':>9} {'—':>9}  no effect on orientation")
                continue
            click.echo(
                f"{name:<10} {lb:>9.4f} {ub:>9.4f}            {result.binding.get(name, '')}"
            )
        mc = result.monte_carlo
        mx = mc["max_abs_arcmin"]
        click.echo(
            f"Monte Carlo {mc['runs']} draws: max |Δ| (arcmin) "
            + "  ".join(f"{c} {mx[c]:.4g}" for c in ("psi", "theta", "gamma"))
            + ("  — all within" if mc["all_within"] else f"  — {mc['outside']} OUTSIDE")
        )


@turntable.command("example")
@click.option("--out", required=True, metavar="FILE.toml", help="Where to write the example.")
@click.option("--overwrite", is_flag=True, help="Replace an existing file.")
def turntable_example(out: str, overwrite: bool) -> None:
    """Write the seed's two-axis table as a commented TOML to start a configuration from."""
    from rotacal.turntable import seed_table_toml

    path = Path(out)
    if path.exists() and not overwrite:
        raise ConfigError(f"{out} exists; choose another name or pass --overwrite")
    path.write_text(seed_table_toml(), encoding="utf-8")
    click.echo(f"wrote {out}")


# ----------------------------------------------------------------------------------------------- specs
@cli.group("specs")
def specs_group() -> None:
    """Instrument specifications: the Type B inputs of the uncertainty budgets (--specs)."""


@specs_group.command("example")
@click.option("--out", required=True, metavar="FILE.toml", help="Where to write the example.")
@click.option("--overwrite", is_flag=True, help="Replace an existing file.")
def specs_example(out: str, overwrite: bool) -> None:
    """Write a commented specifications file with every entry rotacal's budgets use."""
    from rotacal.uncertainty.specs import example_specs_toml

    path = Path(out)
    if path.exists() and not overwrite:
        raise ConfigError(f"{out} exists; choose another name or pass --overwrite")
    path.write_text(example_specs_toml(), encoding="utf-8")
    click.echo(f"wrote {out}")


# ----------------------------------------------------------------------------------------------- allan
@cli.command("allan")
@click.argument("capture", type=click.Path(dir_okay=False))
@click.option("--fs-hz", type=float, default=None, help="Sampling rate, when there is no time_s.")
@click.option(
    "--unit",
    type=click.Choice(["deg/s", "rad/s", "deg/h", "other"]),
    default="deg/s",
    show_default=True,
    help="Unit of the rate column (the named noise terms are in deg).",
)
@click.option(
    "--taus",
    type=click.Choice(["log", "octave", "decade", "all"]),
    default="log",
    show_default=True,
    help="τ grid: 'all' computes every cluster size (O(N log² N)).",
)
@_analysis_options
def allan_cmd(
    capture: str,
    fs_hz: float | None,
    unit: str,
    taus: str,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Overlapping Allan deviation and IEEE 952 noise terms of a rate column.

    --column NAME picks the rate column (default rate_deg_s); --column OLD=NEW maps names as
    everywhere else. A time_s column, when present, gives the sampling rate.
    """
    from rotacal.gyro.noise import gyro_noise
    from rotacal.io import parse_column_mapping, read_capture

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    names = [c for c in columns if "=" not in c]
    mappings = [c for c in columns if "=" in c]
    if len(names) > 1:
        raise ConfigError(f"--column names one rate column; got {', '.join(names)}")
    rate_column = names[0] if names else "rate_deg_s"
    mapping = parse_column_mapping(mappings)
    with _status(f"reading {capture}"):
        cap = read_capture(capture, mapping=mapping, group=group, columns=None)
    if rate_column not in cap.columns:
        raise CaptureError(
            f"{Path(capture).name} has no column {rate_column!r} (it has "
            f"{', '.join(cap.file_columns)}); name the rate column with --column NAME"
        )
    time_s = cap.columns.get("time_s")
    if time_s is None and fs_hz is None:
        raise ConfigError(f"{Path(capture).name} has no time_s column: give --fs-hz")
    with _status("computing the Allan deviation"):
        result = gyro_noise(
            cap[rate_column],
            fs_hz=fs_hz if time_s is None else None,
            time_s=time_s,
            unit=unit,
            taus=taus,
            column=rate_column,
            specs=kw.pop("specs"),
        )
    _write_json(result.to_dict(), json_path, (Path(capture),))
    if report_path:
        from rotacal.report.noise import noise_section

        _write_report(
            "Gyro noise: Allan deviation",
            "IEEE Std 952-1997 Annex C: overlapping Allan deviation and noise terms",
            [noise_section(result)],
            capture,
            report_path,
        )
    if json_path is None and report_path is None:
        for label, value, u in (
            ("angle random walk", result.arw_deg_rt_h, "deg/rt-h"),
            ("bias instability", result.bias_instability_deg_h, "deg/h"),
            ("rate random walk", result.rrw_deg_h_rt_h, "deg/h/rt-h"),
            ("quantization", result.quantization_deg, "deg"),
            ("rate ramp", result.rate_ramp_deg_h2, "deg/h^2"),
        ):
            text = "not seen" if value is None else f"{value:.4g} {u}"
            click.echo(f"{label:<18} {text}")
        for note in result.notes:
            click.echo(f"note               {note}")


# -------------------------------------------------------------------------------------------- simulate
@cli.group()
def simulate() -> None:
    """Write a synthetic capture of a kind, with its truth beside it (FILE.truth.json)."""


def _sim_common(func: F) -> F:
    options = [
        click.option(
            "--out",
            "out",
            required=True,
            type=click.Path(dir_okay=False),
            help="Capture file to write (.csv, .npz, .h5, .tdms).",
        ),
        click.option("--seed", type=int, default=0, show_default=True),
        click.option("--overwrite", is_flag=True, help="Replace FILE if it exists."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _motion_sim_options(func: F) -> F:
    options = [
        click.option("--amplitude-deg", type=float, default=0.5, show_default=True),
        click.option("--frequency-hz", type=float, default=2.0, show_default=True),
        click.option(
            "--harmonic",
            "harmonic_items",
            multiple=True,
            metavar="H:REL[:PHASE]",
            help="Add harmonic H with amplitude REL×fundamental (and phase, rad). Repeatable.",
        ),
        click.option("--stagnation-s", type=float, default=0.0, show_default=True),
        click.option("--creep-deg", type=float, default=0.0, show_default=True),
        click.option("--backlash-deg", type=float, default=0.0, show_default=True),
        click.option("--vibration-deg", type=float, default=0.0, show_default=True),
        click.option("--vibration-hz", type=float, default=0.0, show_default=True),
        click.option(
            "--duration-s",
            type=float,
            default=None,
            help="Length of the capture [default: ~6 periods].",
        ),
        click.option(
            "--fs-hz", type=float, default=None, help="Sample rate [default: per sensor]."
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return _sim_common(func)


def _sim_motion(kind: str, harmonic_items: Sequence[str], kw: dict[str, Any]) -> Any:
    from rotacal import sim

    harmonics: dict[int, tuple[float, float]] = {}
    for item in harmonic_items:
        parts = item.split(":")
        try:
            h, rel = int(parts[0]), float(parts[1])
            phase = float(parts[2]) if len(parts) > 2 else 0.0
        except (ValueError, IndexError):
            raise ConfigError(f"--harmonic {item!r} is not H:REL[:PHASE], e.g. 3:0.02") from None
        if h in harmonics:
            raise ConfigError(f"--harmonic {h} is given twice")
        harmonics[h] = (rel, phase)
    motion_ = sim.SineMotion(
        amplitude_deg=kw.pop("amplitude_deg"),
        frequency_hz=kw.pop("frequency_hz"),
        harmonics=harmonics,
        stagnation_s=kw.pop("stagnation_s"),
        creep_deg=kw.pop("creep_deg"),
        backlash_deg=kw.pop("backlash_deg"),
        vibration_deg=kw.pop("vibration_deg"),
        vibration_hz=kw.pop("vibration_hz"),
    )
    options = {k: v for k, v in kw.items() if v is not None}
    return sim.simulate(kind, motion=motion_, **options)


def _sim_write(capture: Any, out: str, overwrite: bool) -> None:
    path = capture.write(out, overwrite=overwrite)
    click.echo(f"wrote {path} and {path}.truth.json", err=True)


@simulate.command("encoder")
@_motion_sim_options
@click.option("--lines", type=int, default=None, help="Lines per revolution [36000].")
@click.option("--offset-a", type=float, default=None, help="Offset of a (signal units).")
@click.option("--offset-b", type=float, default=None, help="Offset of b (signal units).")
@click.option("--gain-ratio", type=float, default=None, help="Amplitude of b over a.")
@click.option("--phase-error-deg", type=float, default=None, help="Quadrature error (deg).")
@click.option("--adc-bits", type=int, default=None, help="Quantise to this many bits.")
@click.option("--noise", type=float, default=None, help="Signal noise, rms (signal units).")
def simulate_encoder(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Quadrature encoder capture: time_s, a, b."""
    kw["amplitude_b"] = kw.pop("gain_ratio")
    kw["noise_rms"] = kw.pop("noise")
    phase = kw.pop("phase_error_deg")
    kw["phase_error_rad"] = None if phase is None else math.radians(phase)
    _sim_write(_sim_motion("encoder", harmonic_items, kw), out, overwrite)


@simulate.command("lts")
@_motion_sim_options
@click.option("--radius-mm", type=float, default=None, help="R [100 mm].")
@click.option("--zero-offset-mm", type=float, default=None, help="Reading at θ = 0 (mm).")
@click.option("--noise", type=float, default=None, help="Displacement noise, rms (mm).")
def simulate_lts(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Laser triangulation capture: time_s, displacement_mm."""
    kw["noise_mm"] = kw.pop("noise")
    _sim_write(_sim_motion("lts", harmonic_items, kw), out, overwrite)


@simulate.command("fog")
@_motion_sim_options
@click.option("--bias-deg-s", type=float, default=None, help="Constant rate bias.")
@click.option("--noise", type=float, default=None, help="Rate noise, rms (deg/s).")
@click.option("--snr-db", type=float, default=None, help="Noise set by this SNR instead.")
def simulate_fog(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """FOG capture: time_s, rate_deg_s."""
    if kw["snr_db"] is not None and kw["noise"] is not None:
        raise ConfigError("give --noise or --snr-db, not both")
    kw["noise_deg_s"] = kw.pop("noise")
    _sim_write(_sim_motion("fog", harmonic_items, kw), out, overwrite)


@simulate.command("pulses")
@_sim_common
@click.option("--heads", type=int, default=12, show_default=True, help="n read heads.")
@click.option("--pulses-per-rev", type=int, default=18000, show_default=True, help="m lines.")
@click.option("--rate-deg-s", type=float, default=300.0, show_default=True, help="Set rate.")
@click.option("--revolutions", type=float, default=3.0, show_default=True)
@click.option(
    "--harmonic",
    "harmonic_items",
    multiple=True,
    metavar="ORDER:ARCSEC[:PHASE]",
    help="Scale deviation harmonic (order 1 = eccentricity) [default: the twin's set]. Repeatable.",
)
@click.option("--graduation-noise-arcsec", type=float, default=0.03, show_default=True)
@click.option("--head-placement-arcsec", type=float, default=5.0, show_default=True)
@click.option("--rate-bias-percent", type=float, default=0.0, show_default=True)
@click.option("--rate-fluctuation-percent", type=float, default=0.01, show_default=True)
@click.option("--jitter-s", type=float, default=1e-9, show_default=True)
@click.option(
    "--start-spread-s",
    type=float,
    default=None,
    help="Heads start late / stop early by up to this (s) [5 % of a revolution].",
)
def simulate_pulses_cmd(
    out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any
) -> None:
    """Multi-head encoder: pulse times head_0 … head_{n-1} (seed 004)."""
    from rotacal.sim.pulses import simulate_pulses

    if harmonic_items:
        harmonics = []
        for item in harmonic_items:
            parts = item.split(":")
            try:
                order, amp = int(parts[0]), float(parts[1])
                phase = float(parts[2]) if len(parts) > 2 else 0.0
            except (ValueError, IndexError):
                raise ConfigError(
                    f"--harmonic {item!r} is not ORDER:ARCSEC[:PHASE], e.g. 1:3.0"
                ) from None
            harmonics.append((order, amp, phase))
        kw["harmonics"] = tuple(harmonics)
    _sim_write(simulate_pulses(**kw), out, overwrite)


@simulate.command("gyro-rates")
@_sim_common
@click.option("--scale-factor", type=float, default=None, help="S, output per deg/s [0.0125].")
@click.option("--bias", type=float, default=None, help="V0, output at rest [2.5].")
@click.option("--noise-std", type=float, default=None, help="Output noise, rms.")
@click.option("--samples-per-point", type=int, default=None, help="Samples at each set rate.")
@click.option("--quantum", type=float, default=None, help="Output quantisation step.")
def simulate_gyro_rates_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Single-axis gyro on a rate table: rate_deg_s, output (seed 004 §4)."""
    from rotacal.sim import simulate_gyro_rates

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_rates(**options), out, overwrite)


@simulate.command("gyro-triad")
@_sim_common
@click.option("--noise-std", type=float, default=None, help="Output noise, rms (deg/s).")
@click.option("--samples-per-point", type=int, default=None, help="Samples at each rate.")
@click.option("--outlier-fraction", type=float, default=None, help="Share of gross outliers (0…1).")
def simulate_gyro_triad_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """3-axis gyro, rotations about each axis at several rates: wx/wy/wz_deg_s, ux/uy/uz."""
    from rotacal.sim import simulate_gyro_triad

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_triad(**options), out, overwrite)


@simulate.command("gyro-noise")
@_sim_common
@click.option("--duration-s", type=float, default=None, help="Record length [3600 s].")
@click.option("--fs-hz", type=float, default=None, help="Sampling rate [100 Hz].")
@click.option("--arw-deg-rt-h", type=float, default=None, help="Angle random walk [0.3].")
@click.option("--bias-instability-deg-h", type=float, default=None, help="Bias instability [3].")
@click.option("--rrw-deg-h-rt-h", type=float, default=None, help="Rate random walk [0].")
def simulate_gyro_noise_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """A gyro at rest with known IEEE 952 noise terms: time_s, rate_deg_s."""
    from rotacal.sim import simulate_gyro_noise

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_noise(**options), out, overwrite)


@simulate.command("gyro-rotations")
@_sim_common
@click.option("--angle-deg", type=float, default=None, help="Angle of each rotation [360].")
@click.option("--noise-std", type=float, default=None, help="Output noise, rms.")
@click.option("--fs-hz", type=float, default=None, help="Sampling rate [100 Hz].")
def simulate_gyro_rotations_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Ferraris-style recording: rest, 360° about x, y, z: time_s, ux, uy, uz (sections in truth)."""
    from rotacal.sim import simulate_gyro_rotations

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_rotations(**options), out, overwrite)


@simulate.command("multiposition")
@_sim_common
@click.option("--axis", type=click.Choice(["x", "y"]), default="x", show_default=True)
@click.option("--latitude-deg", type=float, default=None, help="Latitude [45.75].")
@click.option("--noise-deg-h", type=float, default=None, help="Output noise, rms (deg/h).")
@click.option("--repeats", type=int, default=None, help="Readings per position.")
def simulate_multiposition_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Gyro torquer output at turntable positions: phi1_deg, phi2_deg, output_deg_h (seed 001)."""
    from rotacal.sim import simulate_multiposition

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_multiposition(**options), out, overwrite)


# ------------------------------------------------------------------------------------------------ demo
@cli.command()
@click.option(
    "--out", "out", default="rotacal-demo", show_default=True, type=click.Path(file_okay=False)
)
def demo(out: str) -> None:
    """Simulate a calibration campaign on the digital twin, analyse it, write DIR/report.html."""
    from rotacal.demo import demo_steps, run_demo

    with _progress(demo_steps(), "demo") as advance:
        report = run_demo(Path(out), progress=advance)
    click.echo(f"wrote {report}")


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the console script."""
    cli.main(args=list(argv) if argv is not None else None, prog_name="rotacal")


__all__ = ["CaptureError", "cli", "main"]
