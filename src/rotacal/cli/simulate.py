"""``rotacal simulate`` and ``rotacal demo``: the digital twin."""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.errors import ConfigError

from ._app import cli
from ._common import (
    F,
    _progress,
    _wrote,
)
from ._help import example


@cli.group(
    short_help="Write a synthetic capture with its truth beside it.",
    epilog=example(
        "rotacal simulate encoder --out run.npz",
        "rotacal simulate gyro-rates --out rates.csv --noise-std 0.001",
    ),
)
def simulate() -> None:
    """Write a synthetic capture of a kind, with its truth beside it (FILE.truth.json).

    The digital twin: the table's motion and the sensor that reads it are modelled, and the
    true values of everything an analysis reports go into FILE.truth.json, so that a result can
    be checked against them.
    """


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
        click.option(
            "--seed",
            type=int,
            default=0,
            show_default=True,
            help="Seed of the random noise: the same seed writes the same capture.",
        ),
        click.option(
            "--overwrite", is_flag=True, help="Replace FILE and FILE.truth.json if they exist."
        ),
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
        click.option(
            "--amplitude-deg",
            type=float,
            default=0.5,
            show_default=True,
            help="Amplitude of the table's sinusoidal motion (deg).",
        ),
        click.option(
            "--frequency-hz",
            type=float,
            default=2.0,
            show_default=True,
            help="Frequency of the motion (Hz).",
        ),
        click.option(
            "--harmonic",
            "harmonic_items",
            multiple=True,
            metavar="H:REL[:PHASE]",
            help="Add harmonic H with amplitude REL×fundamental (REL without unit, 0.03 = 3 %) "
            "and phase PHASE (rad). Repeatable.",
        ),
        click.option(
            "--stagnation-s",
            type=float,
            default=0.0,
            show_default=True,
            help="Dwell of the table at each reversal (s).",
        ),
        click.option(
            "--creep-deg",
            type=float,
            default=0.0,
            show_default=True,
            help="Peak creep lag after each reversal (deg).",
        ),
        click.option(
            "--backlash-deg",
            type=float,
            default=0.0,
            show_default=True,
            help="Width of the play (dead band) in the drive (deg).",
        ),
        click.option(
            "--vibration-deg",
            type=float,
            default=0.0,
            show_default=True,
            help="Amplitude of a vibration added to the motion (deg).",
        ),
        click.option(
            "--vibration-hz",
            type=float,
            default=0.0,
            show_default=True,
            help="Frequency of that vibration (Hz).",
        ),
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
            help="Length of the capture (s) [default: about 6 periods of the motion; 40⅛ for "
            "the fibre-optic gyro].",
        ),
        click.option(
            "--fs-hz",
            type=float,
            default=None,
            help="Sample rate (Hz) [default: encoder 50 000, laser triangulation 10 000, "
            "fibre-optic gyro 2000].",
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
    from rotacal.sim.sensors import truth_path

    capture.write(out, overwrite=overwrite)
    _wrote(out)
    _wrote(truth_path(out))


@simulate.command(
    "encoder",
    epilog=example(
        "rotacal simulate encoder --amplitude-deg 0.5 --frequency-hz 2 --harmonic 2:0.03 "
        "--out run.npz"
    ),
)
@_motion_sim_options
@click.option("--lines", type=int, default=None, help="Encoder lines per revolution [36000].")
@click.option("--offset-a", type=float, default=None, help="Offset of a (signal units).")
@click.option("--offset-b", type=float, default=None, help="Offset of b (signal units).")
@click.option(
    "--gain-ratio",
    type=float,
    default=None,
    help="Amplitude of b over that of a (ratio, 1 = matched).",
)
@click.option(
    "--phase-error-deg",
    type=float,
    default=None,
    help="Quadrature error of b: its phase beyond 90° (deg).",
)
@click.option(
    "--adc-bits",
    type=int,
    default=None,
    help="Quantise a and b to this many ADC bits over ±1.25 signal units.",
)
@click.option("--noise", type=float, default=None, help="Signal noise, rms (signal units).")
def simulate_encoder(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Optical shaft encoder (OSE) capture: time_s, a, b.

    The analog quadrature signals a ≈ cos φ, b ≈ sin φ of an encoder on the table, with the
    offsets, gain ratio, quadrature error, noise and ADC quantisation asked for.
    """
    kw["amplitude_b"] = kw.pop("gain_ratio")
    kw["noise_rms"] = kw.pop("noise")
    phase = kw.pop("phase_error_deg")
    kw["phase_error_rad"] = None if phase is None else math.radians(phase)
    _sim_write(_sim_motion("encoder", harmonic_items, kw), out, overwrite)


@simulate.command(
    "lts",
    epilog=example("rotacal simulate lts --amplitude-deg 0.1 --radius-mm 100 --out lts.csv"),
)
@_motion_sim_options
@click.option(
    "--radius-mm",
    type=float,
    default=None,
    help="R: distance of the laser spot from the table axis (mm) [100].",
)
@click.option(
    "--zero-offset-mm", type=float, default=None, help="Reading of the sensor at θ = 0 (mm) [0]."
)
@click.option("--noise", type=float, default=None, help="Displacement noise, rms (mm) [3e-5].")
@click.option(
    "--range-mm", type=float, default=None, help="Sensor range: readings clip at ±R (mm)."
)
def simulate_lts(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Laser triangulation sensor (LTS) capture.

    Columns time_s and displacement_mm: the sensor reads a reflector at radius R on the table: D = R·tan θ + zero offset + noise.
    """
    kw["noise_mm"] = kw.pop("noise")
    _sim_write(_sim_motion("lts", harmonic_items, kw), out, overwrite)


@simulate.command(
    "fog",
    epilog=example("rotacal simulate fog --snr-db 30 --out fog.h5"),
)
@_motion_sim_options
@click.option(
    "--bias-deg-s", type=float, default=None, help="Constant rate bias of the gyro (deg/s) [0]."
)
@click.option(
    "--bias-drift-deg-s2",
    type=float,
    default=None,
    help="Drift of the rate bias (deg/s per s), e.g. a warm-up [0].",
)
@click.option("--noise", type=float, default=None, help="Rate noise, rms per sample (deg/s) [0].")
@click.option(
    "--snr-db",
    type=float,
    default=None,
    help="Set the rate noise by this signal-to-noise ratio (dB) instead of --noise.",
)
@click.option(
    "--range-deg-s", type=float, default=None, help="Gyro range: the output clips at ±R (deg/s)."
)
def simulate_fog(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Fibre-optic gyro (FOG) capture: time_s, rate_deg_s.

    The gyro on the table reads its rate: dθ/dt + bias + drift·t + white noise (deg/s).
    """
    if kw["snr_db"] is not None and kw["noise"] is not None:
        raise ConfigError("give --noise or --snr-db, not both")
    kw["noise_deg_s"] = kw.pop("noise")
    _sim_write(_sim_motion("fog", harmonic_items, kw), out, overwrite)


@simulate.command(
    "pulses",
    epilog=example(
        "rotacal simulate pulses --heads 12 --pulses-per-rev 18000 --rate-deg-s 300 --out heads.h5"
    ),
)
@_sim_common
@click.option(
    "--heads",
    type=int,
    default=12,
    show_default=True,
    help="n: read heads, equally spaced (head 0 the reference).",
)
@click.option(
    "--pulses-per-rev",
    type=int,
    default=18000,
    show_default=True,
    help="m: lines of the scale, pulses per revolution of one head.",
)
@click.option(
    "--rate-deg-s",
    type=float,
    default=300.0,
    show_default=True,
    help="Set rate of the table (deg/s).",
)
@click.option(
    "--revolutions",
    type=float,
    default=3.0,
    show_default=True,
    help="Length of the record in revolutions of the table.",
)
@click.option(
    "--harmonic",
    "harmonic_items",
    multiple=True,
    metavar="ORDER:ARCSEC[:PHASE]",
    help="Scale deviation harmonic of ORDER (1 = eccentricity) with amplitude ARCSEC (arcsec) "
    "and phase PHASE (rad) [default: the twin's set]. Repeatable.",
)
@click.option(
    "--graduation-noise-arcsec",
    type=float,
    default=0.03,
    show_default=True,
    help="Random error of each line of the scale, standard deviation (arcsec).",
)
@click.option(
    "--head-placement-arcsec",
    type=float,
    default=5.0,
    show_default=True,
    help="Placement error of heads 1 … n-1 from i·360/n, standard deviation (arcsec).",
)
@click.option(
    "--rate-bias-percent",
    type=float,
    default=0.0,
    show_default=True,
    help="Mean error of the table's rate against the set rate (%).",
)
@click.option(
    "--rate-fluctuation-percent",
    type=float,
    default=0.01,
    show_default=True,
    help="Fluctuation of the table's rate, rms (% of the rate).",
)
@click.option(
    "--jitter-s",
    type=float,
    default=1e-9,
    show_default=True,
    help="Timing jitter of each pulse edge, standard deviation (s).",
)
@click.option(
    "--start-spread-s",
    type=float,
    default=None,
    help="Heads start late and stop early by up to this (s) [5 % of a revolution].",
)
def simulate_pulses_cmd(
    out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any
) -> None:
    """Multi-head encoder's pulse times.

    Columns head_0 … head_{n-1}: a self-calibratable encoder with n heads on a table turning at a constant rate: each column
    holds the times (s) of the successive pulse edges seen by one head (Kokuyama et al. 2015).
    """
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


@simulate.command(
    "gyro-rates",
    epilog=example("rotacal simulate gyro-rates --scale-factor 0.0125 --bias 2.5 --out rates.csv"),
)
@_sim_common
@click.option(
    "--scale-factor",
    type=float,
    default=None,
    help="S: output per deg/s (output unit per deg/s) [0.0125].",
)
@click.option("--bias", type=float, default=None, help="V0: output at rest (output unit) [2.5].")
@click.option(
    "--noise-std", type=float, default=None, help="Output noise, rms (output unit) [6.25e-4]."
)
@click.option(
    "--samples-per-point", type=int, default=None, help="Samples at each set rate [5000]."
)
@click.option(
    "--quantum", type=float, default=None, help="Output quantisation step (output unit) [none]."
)
@click.option(
    "--asymmetry-ppm", type=float, default=None, help="Scale-factor asymmetry (S+ - S-)/S, ppm [0]."
)
@click.option(
    "--run-scale-factor-std-ppm",
    type=float,
    default=None,
    help="Run-to-run spread of S (ppm): each --seed is one run of the same gyro [0].",
)
@click.option(
    "--temperature-c",
    type=float,
    default=None,
    help="Temperature of this run (deg C): writes a temperature_c column [none].",
)
@click.option(
    "--scale-factor-tc-ppm-per-c", type=float, default=None, help="dS/dT over S (ppm/deg C) [0]."
)
@click.option(
    "--bias-tc-per-c", type=float, default=None, help="dV0/dT (output unit per deg C) [0]."
)
@click.option(
    "--temperature-ref-c", type=float, default=None, help="Where S and V0 hold (deg C) [25]."
)
def simulate_gyro_rates_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Single-axis gyro on a rate table.

    Columns rate_deg_s and output: rows of set rate (deg/s) and gyro output at eleven set rates from -100 to +100 deg/s,
    with a known scale factor, bias and nonlinearity (Kokuyama et al. 2015, §4).
    """
    from rotacal.sim import simulate_gyro_rates

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_rates(**options), out, overwrite)


@simulate.command(
    "gyro-steps",
    epilog=example("rotacal simulate gyro-steps --resolution-deg-s 0.004 --out steps.csv"),
)
@_sim_common
@click.option(
    "--resolution-deg-s", type=float, default=None, help="Stick-slip size r (deg/s) [0.0042]."
)
@click.option(
    "--dead-zone-deg-s", type=float, default=None, help="Dead zone half-width d (deg/s) [0.007]."
)
@click.option(
    "--noise-std", type=float, default=None, help="Output noise, rms (output unit) [2.5e-5]."
)
@click.option("--samples-per-dwell", type=int, default=None, help="Samples at each dwell [2000].")
def simulate_gyro_steps_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """A gyro's small-step test: rate_deg_s, output.

    Small increments around 0 and +-10 deg/s; the gyro has a known threshold max(r, d) and
    resolution r (IEEE Std 528 definitions), for `rotacal gyro resolution`.
    """
    from rotacal.sim import simulate_gyro_steps

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_steps(**options), out, overwrite)


@simulate.command(
    "gyro-log",
    epilog=example("rotacal simulate gyro-log --lag-s 0.3 --out log.npz"),
)
@_sim_common
@click.option("--plateau-s", type=float, default=None, help="Seconds at each set rate [30].")
@click.option(
    "--rate-noise-deg-s", type=float, default=None, help="Table rate noise, rms (deg/s) [0.02]."
)
@click.option("--lag-s", type=float, default=None, help="DUT's first-order lag τ (s) [0.05].")
@click.option(
    "--ringing-hz",
    "natural_frequency_hz",
    type=float,
    default=None,
    help="DUT's ringing frequency (Hz; 0: none) [2].",
)
@click.option("--fs-hz", type=float, default=None, help="Sample rate (Hz) [100].")
def simulate_gyro_log_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Continuous rate-table log of a single-axis gyro.

    Columns time_s, rate_deg_s (the table's measured rate, stepping through eleven plateaus
    from 0 to ±100 deg/s) and output (the DUT lagging and ringing after each step), with the
    plateaus, scale factor, bias and nonlinearity in FILE.truth.json.
    """
    from rotacal.sim import simulate_gyro_log

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_log(**options), out, overwrite)


@simulate.command(
    "gyro-triad",
    epilog=example("rotacal simulate gyro-triad --outlier-fraction 0.01 --out triad.h5"),
)
@_sim_common
@click.option("--noise-std", type=float, default=None, help="Output noise, rms (deg/s) [0.1].")
@click.option("--samples-per-point", type=int, default=None, help="Samples at each rate [500].")
@click.option(
    "--outlier-fraction",
    type=float,
    default=None,
    help="Share of samples that are gross outliers (0…1, without unit) [0].",
)
def simulate_gyro_triad_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Three-axis gyro turned about each axis at several rates.

    Columns wx_deg_s, wy_deg_s, wz_deg_s (reference rate) and ux, uy, uz (raw outputs), with a
    known scale/misalignment matrix and bias (robot-manipulator study 2023).
    """
    from rotacal.sim import simulate_gyro_triad

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_triad(**options), out, overwrite)


@simulate.command(
    "gyro-noise",
    epilog=example(
        "rotacal simulate gyro-noise --duration-s 3600 --arw-deg-rt-h 0.3 --out static.npz"
    ),
)
@_sim_common
@click.option("--duration-s", type=float, default=None, help="Record length (s) [3600].")
@click.option("--fs-hz", type=float, default=None, help="Sampling rate (Hz) [100].")
@click.option("--arw-deg-rt-h", type=float, default=None, help="Angle random walk (deg/√h) [0.3].")
@click.option(
    "--bias-instability-deg-h", type=float, default=None, help="Bias instability (deg/h) [3]."
)
@click.option("--rrw-deg-h-rt-h", type=float, default=None, help="Rate random walk (deg/h/√h) [0].")
@click.option(
    "--quantization-arcsec", type=float, default=None, help="Angle quantization Q (arcsec) [0]."
)
@click.option("--rate-ramp-deg-h2", type=float, default=None, help="Rate ramp R (deg/h²) [0].")
@click.option(
    "--bias-model",
    type=click.Choice(["flicker", "gauss-markov"]),
    default=None,
    help="Bias instability as true flicker noise, or Gauss–Markov processes over a band [flicker].",
)
def simulate_gyro_noise_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """A gyro at rest with known noise terms: time_s, rate_deg_s.

    Angle quantization, white rate noise (angle random walk), bias instability (flicker), rate
    random walk and rate ramp as named in IEEE Std 952-1997, for `rotacal allan`.
    """
    from rotacal.sim import simulate_gyro_noise

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_noise(**options), out, overwrite)


@simulate.command(
    "gyro-rotations",
    epilog=example("rotacal simulate gyro-rotations --out rot.csv"),
)
@_sim_common
@click.option(
    "--angle-deg",
    type=float,
    default=None,
    help="Angle of each rotation (deg), right-hand rule [-360: clockwise, the Ferraris protocol].",
)
@click.option("--noise-std", type=float, default=None, help="Output noise, rms (deg/s) [0.05].")
@click.option("--fs-hz", type=float, default=None, help="Sampling rate (Hz) [100].")
def simulate_gyro_rotations_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Rotations through a known angle about x, y, z (Ferraris).

    Columns time_s, ux, uy, uz: rest, then 360° about each axis; the sample ranges of the
    rotations are in FILE.truth.json, which `rotacal gyro rotations --sections` reads.
    """
    from rotacal.sim import simulate_gyro_rotations

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_rotations(**options), out, overwrite)


@simulate.command(
    "ferraris",
    epilog=example("rotacal simulate ferraris --out session.csv --latitude-deg 49.6"),
)
@_sim_common
@click.option("--latitude-deg", type=float, default=None, help="Latitude (deg) [49.6].")
@click.option("--noise-std", type=float, default=None, help="Gyro noise, rms (deg/s) [0.05].")
@click.option("--quantum", type=float, default=None, help="Gyro output step (deg/s) [none].")
@click.option("--fs-hz", type=float, default=None, help="Sampling rate (Hz) [100].")
def simulate_ferraris_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """A Ferraris session of a 6-DOF IMU on the rotating Earth.

    Columns time_s, ux, uy, uz (gyro, deg/s), ax, ay, az (m/s²): six static positions, then a
    turn of -360° about each axis; the sections (imucal's names) and the true K, b, K_ga, K_a·R_a,
    b_a are in FILE.truth.json, which `rotacal gyro rotations --sections` reads.
    """
    from rotacal.sim import simulate_ferraris

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_ferraris(**options), out, overwrite)


@simulate.command(
    "multiposition",
    epilog=example("rotacal simulate multiposition --axis x --latitude-deg 45.75 --out mp.csv"),
)
@_sim_common
@click.option(
    "--axis",
    type=click.Choice(["x", "y"]),
    default="x",
    show_default=True,
    help="Input axis of the gyro on the turntable.",
)
@click.option(
    "--latitude-deg", type=float, default=None, help="Latitude of the laboratory (deg) [45.75]."
)
@click.option("--noise-deg-h", type=float, default=None, help="Output noise, rms (deg/h) [0.005].")
@click.option("--repeats", type=int, default=None, help="Readings per position [4].")
def simulate_multiposition_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Gyro torquer output at turntable positions.

    Columns phi1_deg (outer axis), phi2_deg (inner axis) and output_deg_h, with known drift
    coefficients under Earth rate and gravity (GyroWheel study, Int. J. Aerospace Eng.).
    """
    from rotacal.sim import simulate_multiposition

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_multiposition(**options), out, overwrite)


# ------------------------------------------------------------------------------------------------ demo
@cli.command(
    short_help="Simulate, analyse and report a whole campaign.",
    epilog=example("rotacal demo", "rotacal demo --out first-look"),
)
@click.option(
    "--out",
    "out",
    default="rotacal-demo",
    show_default=True,
    type=click.Path(file_okay=False),
    help="Folder for report.html and the JSON of every analysis.",
)
@click.option(
    "--overwrite",
    is_flag=True,
    help="Replace the files of an earlier demo in the folder (refused without it).",
)
def demo(out: str, overwrite: bool) -> None:
    """Simulate a calibration campaign on the digital twin, analyse it, write DIR/report.html.

    The twin makes captures of the paper's five motion scenarios, a multi-head encoder, gyros
    and a turntable; each is analysed as the commands do, and DIR gets the report and one JSON
    per analysis.
    """
    from rotacal.demo import demo_files, demo_steps, run_demo
    from rotacal.io.outputs import check_folder, check_outputs

    check_folder(out, label=f"--out {out}")
    # before the campaign (minutes of work): every file it will write may be written
    names = demo_files()
    existing = [name for name in names if os.path.lexists(Path(out) / name)]
    if existing and not overwrite:
        more = f" and {len(existing) - 1} more of its files" if len(existing) > 1 else ""
        raise ConfigError(
            f"--out {out} already holds {existing[0]}{more} (an earlier demo's, or edited); "
            "choose another folder or pass --overwrite to replace them"
        )
    check_outputs(
        [(Path(out) / name, str(Path(out) / name)) for name in names],
        overwrite=overwrite,
        make_folders=True,
    )
    with _progress(demo_steps(), "demo") as advance:
        written = run_demo(Path(out), progress=advance, overwrite=overwrite)
    for path in written:
        _wrote(path)


# each registers its subcommand on `simulate` as it is imported: gyro-sine, orientation,
# position, angle, gyro-triad-log
from . import (  # noqa: E402,F401
    simulate_angle,
    simulate_frequency,
    simulate_orientation,
    simulate_position,
    simulate_triad_log,
)
