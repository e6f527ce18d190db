"""``rotacal simulate`` and ``rotacal demo``: the digital twin."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.errors import ConfigError

from ._app import cli
from ._common import (
    F,
    _progress,
)


@cli.group()
def simulate() -> None:
    """Write a synthetic capture of a kind, with its truth beside it (FILE.truth.json)."""


def _sim_common(func: F) -> F:
    @functools.wraps(func)
    def checked(*args: Any, out: str, overwrite: bool, **kw: Any) -> Any:
        _check_sim_outputs(out, overwrite)  # before the simulation, which may take a while
        return func(*args, out=out, overwrite=overwrite, **kw)

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
        checked = option(checked)
    return checked  # type: ignore[return-value]


def _check_sim_outputs(out: str, overwrite: bool) -> None:
    """The pre-flight of ``simulate``: both the capture and its truth file may be written."""
    from rotacal.io.outputs import check_outputs
    from rotacal.io.write import capture_format
    from rotacal.sim.sensors import truth_path

    capture_format(out)
    truth = truth_path(out)
    check_outputs(
        [(out, f"--out {out}"), (truth, f"{truth} (the truth beside --out)")], overwrite=overwrite
    )


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
            "--drift-deg-s",
            type=float,
            default=0.0,
            show_default=True,
            help="Steady drift of the table (deg/s), added to the angle as drift·t; not part of "
            "the true harmonics and THD (truth key drift_deg_s).",
        ),
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
        drift_deg_s=kw.pop("drift_deg_s"),
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
@click.option(
    "--range-mm", type=float, default=None, help="Sensor range: readings clip at ±R (mm)."
)
def simulate_lts(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Laser triangulation capture: time_s, displacement_mm."""
    kw["noise_mm"] = kw.pop("noise")
    _sim_write(_sim_motion("lts", harmonic_items, kw), out, overwrite)


@simulate.command("fog")
@_motion_sim_options
@click.option("--bias-deg-s", type=float, default=None, help="Constant rate bias.")
@click.option(
    "--bias-drift-deg-s2",
    type=float,
    default=None,
    help="Drift of the rate bias (deg/s per s), e.g. a warm-up [0].",
)
@click.option("--noise", type=float, default=None, help="Rate noise, rms (deg/s).")
@click.option("--snr-db", type=float, default=None, help="Noise set by this SNR instead.")
@click.option(
    "--range-deg-s", type=float, default=None, help="Gyro range: the output clips at ±R (deg/s)."
)
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
@click.option(
    "--angle-deg",
    type=float,
    default=None,
    help="Angle of each rotation, right-hand rule [-360: clockwise, the Ferraris protocol].",
)
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
    from rotacal.io.outputs import check_folder

    check_folder(out, label=f"--out {out}")
    with _progress(demo_steps(), "demo") as advance:
        report = run_demo(Path(out), progress=advance)
    click.echo(f"wrote {report}")
