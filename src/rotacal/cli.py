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


# -------------------------------------------------------------------------------------------- simulate
_SIM_KINDS = ["encoder", "lts", "fog"]
#: Sensor options of `rotacal simulate` and the kinds they apply to.
_SIM_SENSOR_OPTIONS = {
    "lines": ("encoder",),
    "offset_a": ("encoder",),
    "offset_b": ("encoder",),
    "gain_ratio": ("encoder",),
    "phase_error_deg": ("encoder",),
    "adc_bits": ("encoder",),
    "radius_mm": ("lts",),
    "zero_offset_mm": ("lts",),
    "bias_deg_s": ("fog",),
    "snr_db": ("fog",),
}
_SIM_RENAME = {"gain_ratio": "amplitude_b"}


@cli.command()
@click.argument("kind", type=click.Choice(_SIM_KINDS))
@click.option(
    "--out", "out", required=True, type=click.Path(dir_okay=False), help="Capture file to write."
)
@click.option("--amplitude-deg", type=float, default=0.5, show_default=True)
@click.option("--frequency-hz", type=float, default=2.0, show_default=True)
@click.option(
    "--harmonic",
    "harmonic_items",
    multiple=True,
    metavar="H:REL[:PHASE]",
    help="Add harmonic H with amplitude REL×fundamental (and phase, rad). Repeatable.",
)
@click.option("--stagnation-s", type=float, default=0.0, show_default=True)
@click.option("--creep-deg", type=float, default=0.0, show_default=True)
@click.option("--backlash-deg", type=float, default=0.0, show_default=True)
@click.option("--vibration-deg", type=float, default=0.0, show_default=True)
@click.option("--vibration-hz", type=float, default=0.0, show_default=True)
@click.option(
    "--duration-s", type=float, default=None, help="Length of the capture [default: ~6 periods]."
)
@click.option("--fs-hz", type=float, default=None, help="Sample rate [default: per sensor].")
@click.option("--lines", type=int, default=None, help="encoder: lines per revolution [36000].")
@click.option("--offset-a", type=float, default=None, help="encoder: offset of a (signal units).")
@click.option("--offset-b", type=float, default=None, help="encoder: offset of b (signal units).")
@click.option("--gain-ratio", type=float, default=None, help="encoder: amplitude of b over a.")
@click.option("--phase-error-deg", type=float, default=None, help="encoder: quadrature error.")
@click.option("--adc-bits", type=int, default=None, help="encoder: quantise to this many bits.")
@click.option("--zero-offset-mm", type=float, default=None, help="lts: reading at θ = 0 (mm).")
@click.option("--bias-deg-s", type=float, default=None, help="fog: constant rate bias.")
@click.option(
    "--noise",
    type=float,
    default=None,
    help="Sensor noise (encoder: signal units; lts: mm; fog: deg/s).",
)
@click.option(
    "--snr-db", type=float, default=None, help="fog: noise set by this SNR instead of --noise."
)
@click.option("--radius-mm", type=float, default=None, help="lts: R [100 mm].")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--overwrite", is_flag=True, help="Replace FILE if it exists.")
def simulate(
    kind: str, out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any
) -> None:
    """Write a synthetic capture of KIND with its truth beside it (FILE.truth.json)."""
    from rotacal import sim

    for option, kinds in _SIM_SENSOR_OPTIONS.items():
        if kw[option] is not None and kind not in kinds:
            flag = "--" + option.replace("_", "-")
            raise ConfigError(f"{flag} applies to the {'/'.join(kinds)} kind only, not {kind}")
    if kw["snr_db"] is not None and kw["noise"] is not None:
        raise ConfigError("give --noise or --snr-db, not both")
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
    options: dict[str, Any] = {"duration_s": kw["duration_s"], "seed": kw["seed"]}
    if kw["fs_hz"] is not None:
        options["fs_hz"] = kw["fs_hz"]
    noise_name = {"encoder": "noise_rms", "lts": "noise_mm", "fog": "noise_deg_s"}[kind]
    given = {_SIM_RENAME.get(k, k): v for k, v in kw.items() if k in _SIM_SENSOR_OPTIONS}
    options.update({k: v for k, v in given.items() if v is not None})
    if kw["noise"] is not None:
        options[noise_name] = kw["noise"]
    if "phase_error_deg" in options:
        options["phase_error_rad"] = math.radians(options.pop("phase_error_deg"))
    capture = sim.simulate(kind, motion=motion_, **options)
    path = capture.write(out, overwrite=overwrite)
    click.echo(f"wrote {path} and {path}.truth.json", err=True)


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
