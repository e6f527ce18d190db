"""Sensor models of the digital twin: shaft encoder, laser triangulation sensor, FOG (Feng et al. 2023).

Each ``simulate_*`` function samples a :class:`~rotacal.sim.motion.SineMotion` at a fixed rate and
returns a :class:`SimCapture` whose columns follow the canonical capture layout of INTERFACE.md and
whose ``truth`` holds the motion's true values plus every sensor setting used. The same ``seed``
always gives the same capture.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import to_jsonable
from rotacal.sim.motion import SineMotion, _finite, _nonneg

__all__ = [
    "SimCapture",
    "default_duration_s",
    "simulate",
    "simulate_encoder",
    "simulate_fog",
    "simulate_lts",
    "truth_path",
]

#: Largest capture the twin makes in one go (samples).
MAX_SAMPLES = 200_000_000


@dataclasses.dataclass(frozen=True)
class SimCapture:
    """A synthetic capture: canonical columns and the true values behind them.

    Attributes
    ----------
    kind : str
        ``"encoder"``, ``"lts"`` or ``"fog"`` (more kinds later).
    columns : dict of str to numpy.ndarray
        Equal-length columns, ``time_s`` first.
    truth : dict
        JSON-able true values (see :meth:`SineMotion.truth`) and the sensor settings under
        ``sensor``.
    """

    kind: str
    columns: dict[str, np.ndarray]
    truth: dict[str, Any]

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def write(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write the capture with ``rotacal.io`` and its truth to ``PATH.truth.json``.

        Both files appear together or neither does (``rotacal.io.outputs.write_outputs``): each is
        written to a temporary file first and named only when both are complete.

        Parameters
        ----------
        path : str or Path
            Capture file; the format follows the suffix (as ``rotacal.io.write_capture`` decides).
        overwrite : bool
            Replace existing files (atomically); otherwise an existing capture or truth file is an
            error.

        Returns
        -------
        Path
            The capture's path.
        """
        from rotacal.io.outputs import Output, write_outputs
        from rotacal.io.write import capture_writer

        path = Path(path)
        truth = json.dumps(to_jsonable(self.truth), indent=2) + "\n"
        write_outputs(
            [Output(path, capture_writer(path, self.columns)), Output(truth_path(path), truth)],
            overwrite=overwrite,
        )
        return path


def truth_path(path: str | Path) -> Path:
    """Where :meth:`SimCapture.write` puts the truth of a capture written to ``path``."""
    path = Path(path)
    return path.with_name(path.name + ".truth.json")


# ---------------------------------------------------------------------- helpers
#: Default FOG record: 40⅛ periods, because its THD is limited by the gyro's noise.
FOG_DEFAULT_PERIODS = 40.125


def default_duration_s(motion: SineMotion) -> float:
    """Default capture length: 6⅛ motion periods (s), so a capture starts and ends mid-stroke."""
    return 6.125 / motion.frequency_hz


def _check_motion(motion: Any) -> SineMotion:
    if not isinstance(motion, SineMotion):
        raise ConfigError(f"motion must be a rotacal.sim.SineMotion, got {type(motion).__name__}.")
    return motion


def _time_axis(
    motion: SineMotion, fs_hz: Any, duration_s: Any, start_s: Any
) -> tuple[np.ndarray, float, float, float]:
    fs = _finite("fs_hz", fs_hz)
    if fs <= 0:
        raise ConfigError(f"fs_hz must be > 0 Hz, got {fs_hz!r}.")
    # A line at or above Nyquist would alias into a different motion than the truth describes.
    lines_hz = [h * motion.frequency_hz for h in (1, *motion.harmonics)]
    if motion.vibration_deg > 0:
        lines_hz.append(motion.vibration_hz)
    if max(lines_hz) >= fs / 2:
        raise ConfigError(
            f"the motion has a line at {max(lines_hz):.6g} Hz, at or above the Nyquist frequency "
            f"{fs / 2:.6g} Hz of fs_hz={fs:.6g}: raise fs_hz or drop that harmonic."
        )
    dur = default_duration_s(motion) if duration_s is None else _finite("duration_s", duration_s)
    if dur <= 0:
        raise ConfigError(f"duration_s must be > 0 s, got {duration_s!r}.")
    t0 = _finite("start_s", start_s)
    n = round(dur * fs)
    if n < 16:
        raise ConfigError(
            f"duration_s={dur:.6g} s at fs_hz={fs:.6g} gives only {n} samples; give at least 16."
        )
    if n > MAX_SAMPLES:
        raise ConfigError(
            f"duration_s={dur:.6g} s at fs_hz={fs:.6g} gives {n} samples, more than the "
            f"{MAX_SAMPLES} the twin makes at once; shorten duration_s or lower fs_hz."
        )
    t = t0 + np.arange(n) / fs
    return t, fs, dur, t0


def _timebase(value: Any) -> float:
    e = _finite("timebase_relative_error", value)
    if not abs(e) < 0.01:
        raise ConfigError(
            f"timebase_relative_error={value!r} is not a small fraction; give |e| < 0.01 "
            "(e.g. 2e-6 for a clock 2 ppm fast)."
        )
    return e


def _stamped(t: np.ndarray, t0: float, e: float) -> np.ndarray:
    """The DAQ's time stamps of the true sampling instants t for a clock running e fast.

    Every interval since the first sample is stamped (1 + e) long; the first stamp is exact.
    """
    return t if e == 0.0 else t0 + (1.0 + e) * (t - t0)


def _truth(
    motion: SineMotion, kind: str, t: np.ndarray, sensor: dict[str, Any], harmonics: int
) -> dict[str, Any]:
    truth = motion.truth(float(t[0]), float(t[-1]), harmonics=harmonics)
    truth["kind"] = kind
    truth["samples"] = int(t.size)
    truth["sensor"] = to_jsonable(sensor)
    return truth


def _saturate(x: np.ndarray, limit: Any, name: str) -> dict[str, Any]:
    """Clip ``x`` in place to ±limit (a sensor's range); the truth entries it adds (none if None)."""
    if limit is None:
        return {}
    lim = _finite(name, limit)
    if lim <= 0:
        raise ConfigError(f"{name} must be > 0, got {limit!r}.")
    beyond = int(np.count_nonzero(np.abs(x) > lim))
    np.clip(x, -lim, lim, out=x)
    return {name: lim, "clipped_samples": beyond}


def _graduation_table(value: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """(angles_deg, errors_arcsec) of an encoder's reading error, checked; None stays None."""
    if value is None:
        return None
    try:
        ang, err = (np.asarray(v, dtype=float) for v in value)
    except (TypeError, ValueError):
        raise ConfigError(
            "graduation_error_arcsec must be a pair (angles_deg, errors_arcsec) of equal 1-D "
            f"arrays, got {value!r}."
        ) from None
    if ang.ndim != 1 or ang.shape != err.shape or ang.size < 1:
        raise ConfigError(
            "graduation_error_arcsec must be a pair (angles_deg, errors_arcsec) of equal 1-D "
            f"arrays; got shapes {ang.shape} and {err.shape}."
        )
    if not (np.all(np.isfinite(ang)) and np.all(np.isfinite(err))):
        raise ConfigError("graduation_error_arcsec holds a non-finite angle or error.")
    if np.any(np.diff(ang) <= 0):
        raise ConfigError("graduation_error_arcsec: its angles_deg must increase strictly.")
    return ang, err


# ---------------------------------------------------------------------- encoder
def simulate_encoder(
    motion: SineMotion,
    *,
    lines: int = 36000,
    fs_hz: float = 50_000.0,
    duration_s: float | None = None,
    offset_a: float = 0.0,
    offset_b: float = 0.0,
    amplitude_a: float = 1.0,
    amplitude_b: float = 1.0,
    phase_error_rad: float = 0.0,
    noise_rms: float = 0.0,
    adc_bits: int | None = None,
    adc_range: tuple[float, float] = (-1.25, 1.25),
    seed: int = 0,
    start_s: float = 0.0,
    harmonics: int = 10,
    timebase_relative_error: float = 0.0,
    graduation_error_arcsec: tuple[Any, Any] | None = None,
) -> SimCapture:
    """Analog quadrature signals of an optical shaft encoder on the table.

    ``φ = 2π·lines·θ/360`` (θ in deg), ``a = offset_a + amplitude_a·cos φ + n_a``,
    ``b = offset_b + amplitude_b·sin(φ + phase_error_rad) + n_b`` (so θ increases when a leads b:
    b = sin φ peaks a quarter signal period after a = cos φ while φ grows),
    with independent white Gaussian noise of ``noise_rms`` (signal units) on each channel. With
    ``adc_bits`` the signals are clipped to ``adc_range`` and quantised mid-rise to 2**adc_bits
    codes (value = low + (code + ½)·LSB).

    Parameters
    ----------
    motion : SineMotion
        The table motion.
    lines : int
        Encoder lines per revolution (-), 36 000 for the paper's HEIDENHAIN RON 886.
    fs_hz : float
        Sampling rate (Hz). Must keep φ's advance per sample below π/6 (12 subintervals per signal
        period must stay resolvable).
    duration_s : float or None
        Capture length (s); None gives :func:`default_duration_s`.
    offset_a, offset_b, amplitude_a, amplitude_b : float
        Offsets and amplitudes of the two channels (signal units, nominal 0 and 1).
    phase_error_rad : float
        Quadrature phase error of channel b (rad).
    noise_rms : float
        Additive noise per channel (signal units, rms).
    adc_bits : int or None
        ADC resolution (bits); None keeps the analog values without clipping.
    adc_range : (float, float)
        ADC input range (signal units).
    seed : int
        Seed of ``numpy.random.default_rng``.
    start_s : float
        Time of the first sample (s).
    harmonics : int
        Highest harmonic order in the truth.
    timebase_relative_error : float
        Fractional error e of the DAQ clock (-): the samples are taken at the true instants t but
        stamped ``start_s + (1 + e)·(t − start_s)``, so every measured time is (1 + e) long and a
        frequency comes out f/(1 + e). The truth stays in true time. |e| < 0.01.
    graduation_error_arcsec : (angles_deg, errors_arcsec) or None
        The scale's reading error (reading − true, arcsec) as a table over the true angle (deg,
        increasing), linearly interpolated and held constant beyond its ends: the encoder reads
        ``θ + e(θ)/3600``, so its signals carry ``φ`` of that reading. The truth stays the true
        motion. None: a perfect scale.

    Returns
    -------
    SimCapture
        Columns ``time_s`` (s, as the DAQ stamps them), ``a``, ``b`` (signal units).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3 and §5 (OSE with 36 000 lines, 12 subintervals per
    signal period).
    """
    motion = _check_motion(motion)
    tb = _timebase(timebase_relative_error)
    if isinstance(lines, bool) or not float(lines).is_integer() or int(lines) < 1:
        raise ConfigError(f"lines must be a positive integer, got {lines!r}.")
    lines = int(lines)
    t, fs, dur, t0 = _time_axis(motion, fs_hz, duration_s, start_s)
    oa, ob = _finite("offset_a", offset_a), _finite("offset_b", offset_b)
    ga, gb = _finite("amplitude_a", amplitude_a), _finite("amplitude_b", amplitude_b)
    if ga <= 0 or gb <= 0:
        raise ConfigError(f"amplitude_a and amplitude_b must be > 0, got {ga!r} and {gb!r}.")
    pe = _finite("phase_error_rad", phase_error_rad)
    nr = _nonneg("noise_rms", noise_rms)
    lo, hi = (_finite("adc_range[0]", adc_range[0]), _finite("adc_range[1]", adc_range[1]))
    if hi <= lo:
        raise ConfigError(f"adc_range must be (low, high) with low < high, got {adc_range!r}.")
    if adc_bits is not None and (
        isinstance(adc_bits, bool) or not float(adc_bits).is_integer() or not 2 <= adc_bits <= 32
    ):
        raise ConfigError(f"adc_bits must be an integer from 2 to 32 or None, got {adc_bits!r}.")

    theta = motion.angle_deg(t)
    grad = _graduation_table(graduation_error_arcsec)
    if grad is not None:
        theta = theta + np.interp(theta, grad[0], grad[1]) / 3600.0
    phi = (2.0 * math.pi * lines / 360.0) * theta
    step = float(np.max(np.abs(np.diff(phi))))
    if step >= math.pi / 6:
        need = fs * step / (math.pi / 6)
        raise ConfigError(
            f"fs_hz={fs:.6g} is too low for this motion: the encoder phase advances up to "
            f"{step:.3g} rad per sample; raise fs_hz above {need:.6g} Hz so it stays below π/6."
        )
    rng = np.random.default_rng(seed)
    a = oa + ga * np.cos(phi)
    b = ob + gb * np.sin(phi + pe)
    if nr > 0:
        a += rng.normal(0.0, nr, t.size)
        b += rng.normal(0.0, nr, t.size)
    clipped = {"a": 0, "b": 0}
    if adc_bits is not None:
        levels = 2 ** int(adc_bits)
        lsb = (hi - lo) / levels
        for name, x in (("a", a), ("b", b)):
            clipped[name] = int(np.count_nonzero((x < lo) | (x > hi)))
            code = np.clip(np.floor((x - lo) / lsb), 0, levels - 1)
            x[...] = lo + (code + 0.5) * lsb
    sensor = {
        "lines": lines,
        "fs_hz": fs,
        "duration_s": dur,
        "start_s": t0,
        "offset_a": oa,
        "offset_b": ob,
        "amplitude_a": ga,
        "amplitude_b": gb,
        "phase_error_rad": pe,
        "noise_rms": nr,
        "adc_bits": None if adc_bits is None else int(adc_bits),
        "adc_range": [lo, hi],
        "seed": int(seed),
        "max_phase_step_rad": step,
        "clipped_samples": clipped,
        "timebase_relative_error": tb,
        "graduation_error_arcsec": None if grad is None else [grad[0], grad[1]],
    }
    return SimCapture(
        "encoder",
        {"time_s": _stamped(t, t0, tb), "a": a, "b": b},
        _truth(motion, "encoder", t, sensor, harmonics),
    )


# ---------------------------------------------------------------------- LTS
def simulate_lts(
    motion: SineMotion,
    *,
    radius_mm: float = 100.0,
    noise_mm: float = 3e-5,
    zero_offset_mm: float = 0.0,
    fs_hz: float = 10_000.0,
    duration_s: float | None = None,
    seed: int = 0,
    start_s: float = 0.0,
    harmonics: int = 10,
    timebase_relative_error: float = 0.0,
    range_mm: float | None = None,
) -> SimCapture:
    """Laser triangulation sensor reading a reflector at radius R: ``D = R·tan θ + zero + n``.

    Parameters
    ----------
    motion : SineMotion
        The table motion.
    radius_mm : float
        Distance R from the laser spot to the table axis (mm).
    noise_mm : float
        White Gaussian displacement noise (mm rms); 3·10⁻⁵ mm = 0.03 µm.
    zero_offset_mm : float
        Constant displacement offset (mm).
    fs_hz, duration_s, seed, start_s, harmonics, timebase_relative_error
        As in :func:`simulate_encoder`.
    range_mm : float or None
        Measuring range of the sensor (mm, > 0): a reading beyond ±range_mm is reported as
        ±range_mm (a saturated sensor; the truth's ``sensor`` then holds ``range_mm`` and
        ``clipped_samples``, the readings that were beyond it). None: unlimited.

    Returns
    -------
    SimCapture
        Columns ``time_s`` (s), ``displacement_mm`` (mm); θ = arctan(D/R) inverts it.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (15).
    """
    motion = _check_motion(motion)
    r = _finite("radius_mm", radius_mm)
    if r <= 0:
        raise ConfigError(f"radius_mm must be > 0 mm, got {radius_mm!r}.")
    nmm = _nonneg("noise_mm", noise_mm)
    z = _finite("zero_offset_mm", zero_offset_mm)
    tb = _timebase(timebase_relative_error)
    t, fs, dur, t0 = _time_axis(motion, fs_hz, duration_s, start_s)
    theta = motion.angle_deg(t)
    if float(np.max(np.abs(theta))) >= 80.0:
        raise ConfigError("the motion reaches |θ| ≥ 80°, out of reach of a triangulation sensor.")
    d = r * np.tan(np.deg2rad(theta)) + z
    if nmm > 0:
        d += np.random.default_rng(seed).normal(0.0, nmm, t.size)
    clipped = _saturate(d, range_mm, "range_mm")
    sensor = {
        "radius_mm": r,
        "noise_mm": nmm,
        "zero_offset_mm": z,
        "fs_hz": fs,
        "duration_s": dur,
        "start_s": t0,
        "seed": int(seed),
        "timebase_relative_error": tb,
        **clipped,
    }
    return SimCapture(
        "lts",
        {"time_s": _stamped(t, t0, tb), "displacement_mm": d},
        _truth(motion, "lts", t, sensor, harmonics),
    )


# ---------------------------------------------------------------------- FOG
def simulate_fog(
    motion: SineMotion,
    *,
    snr_db: float | None = None,
    noise_deg_s: float = 0.0,
    bias_deg_s: float = 0.0,
    fs_hz: float = 2_000.0,
    duration_s: float | None = None,
    seed: int = 0,
    start_s: float = 0.0,
    harmonics: int = 10,
    scale_factor_error: float = 0.0,
    timebase_relative_error: float = 0.0,
    range_deg_s: float | None = None,
    bias_drift_deg_s2: float = 0.0,
) -> SimCapture:
    """A fibre-optic gyro on the table: ``rate = (1 + s)·dθ/dt + bias + r·(t − t₀) + white noise``
    (deg/s), r the bias's drift and t₀ the first sample's time.

    Parameters
    ----------
    motion : SineMotion
        The table motion.
    snr_db : float or None
        If given, the noise σ (deg/s) is set so that
        ``10·log10(mean((rate_clean − mean)²)/σ²) = snr_db``; excludes ``noise_deg_s``.
    noise_deg_s : float
        White noise σ (deg/s rms per sample) when ``snr_db`` is None.
    bias_deg_s : float
        Constant rate bias (deg/s).
    duration_s : float or None
        Record length (s); default 40⅛ motion periods (the FOG's THD is noise-limited).
    fs_hz, seed, start_s, harmonics, timebase_relative_error
        As in :func:`simulate_encoder`.
    scale_factor_error : float
        Relative error s of the gyro's scale factor (-): the output is (1 + s) times the true
        rate (the noise σ and the SNR are set on the true rate). |s| < 0.5.
    range_deg_s : float or None
        Measuring range of the gyro (deg/s, > 0): an output beyond ±range_deg_s (noise included)
        is reported as ±range_deg_s (a saturated gyro; the truth's ``sensor`` then holds
        ``range_deg_s`` and ``clipped_samples``). None: unlimited.
    bias_drift_deg_s2 : float
        Drift r of the gyro's bias (deg/s per s), e.g. a warm-up: the bias is ``bias_deg_s`` at
        the first sample and changes linearly. A table drift (``SineMotion.drift_deg_s``) adds
        a constant to the rate instead.

    Returns
    -------
    SimCapture
        Columns ``time_s`` (s), ``rate_deg_s`` (deg/s). The truth's ``sensor`` holds the σ used,
        the designed ``snr_db`` and the realised ``snr_db_realised`` (with the drawn noise).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §4 and §5 (FOG scheme; SNR of 7.7 dB).
    """
    motion = _check_motion(motion)
    bias = _finite("bias_deg_s", bias_deg_s)
    bias_drift = _finite("bias_drift_deg_s2", bias_drift_deg_s2)
    sigma = _nonneg("noise_deg_s", noise_deg_s)
    sf = _finite("scale_factor_error", scale_factor_error)
    if not abs(sf) < 0.5:
        raise ConfigError(f"scale_factor_error={scale_factor_error!r} must lie within ±0.5.")
    tb = _timebase(timebase_relative_error)
    if duration_s is None:  # the FOG's THD is noise-limited: record it longer (seed §5)
        duration_s = FOG_DEFAULT_PERIODS / motion.frequency_hz
    t, fs, dur, t0 = _time_axis(motion, fs_hz, duration_s, start_s)
    clean = motion.rate_deg_s(t)
    p_sig = float(np.mean((clean - np.mean(clean)) ** 2))
    if snr_db is not None:
        snr = _finite("snr_db", snr_db)
        if sigma > 0:
            raise ConfigError("give either snr_db or noise_deg_s for the FOG, not both.")
        sigma = math.sqrt(p_sig / 10.0 ** (snr / 10.0))
    rate = (1.0 + sf) * clean + bias
    if bias_drift != 0.0:
        rate += bias_drift * (t - t0)
    snr_real: float | None = None
    if sigma > 0:
        noise = np.random.default_rng(seed).normal(0.0, sigma, t.size)
        rate += noise
        snr_real = 10.0 * math.log10(p_sig / float(np.mean(noise**2)))
    clipped = _saturate(rate, range_deg_s, "range_deg_s")
    sensor = {
        "noise_deg_s": sigma,
        "noise_density_deg_s_rt_hz": sigma / math.sqrt(fs / 2.0),
        "bias_deg_s": bias,
        "bias_drift_deg_s2": bias_drift,
        "snr_db": None if sigma == 0 else 10.0 * math.log10(p_sig / sigma**2),
        "snr_db_requested": None if snr_db is None else float(snr_db),
        "snr_db_realised": snr_real,
        "fs_hz": fs,
        "duration_s": dur,
        "start_s": t0,
        "seed": int(seed),
        "scale_factor_error": sf,
        "timebase_relative_error": tb,
        **clipped,
    }
    return SimCapture(
        "fog",
        {"time_s": _stamped(t, t0, tb), "rate_deg_s": rate},
        _truth(motion, "fog", t, sensor, harmonics),
    )


# ---------------------------------------------------------------------- dispatcher
_KINDS: dict[str, Callable[..., SimCapture]] = {
    "encoder": simulate_encoder,
    "lts": simulate_lts,
    "fog": simulate_fog,
}
_MOTION_FIELDS = tuple(f.name for f in dataclasses.fields(SineMotion))
#: Motion used by :func:`simulate` when neither ``motion`` nor motion settings are given.
DEFAULT_MOTION: dict[str, Any] = {"amplitude_deg": 0.5, "frequency_hz": 2.0}


def register_kind(name: str, func: Callable[..., SimCapture]) -> None:
    """Add a capture kind to :func:`simulate` (for the pulses, gyro and multiposition twins)."""
    _KINDS[name] = func


def known_kinds() -> tuple[str, ...]:
    """Names :func:`simulate` accepts."""
    return tuple(_KINDS)


def simulate(kind: str, **options: Any) -> SimCapture:
    """Make a synthetic capture of ``kind`` (``"encoder"``, ``"lts"``, ``"fog"``, …).

    ``options`` are the keyword arguments of the kind's ``simulate_*`` function. For the table
    motion pass ``motion=SineMotion(...)``, or the :class:`SineMotion` fields themselves
    (``amplitude_deg``, ``frequency_hz``, ``harmonics``, ``stagnation_s``, …; missing ones default
    to a 0.5°, 2 Hz sine).
    """
    func = _KINDS.get(kind)
    if func is None:
        raise ConfigError(
            f"unknown capture kind {kind!r}; known kinds: {', '.join(sorted(_KINDS))}."
        )
    params = inspect.signature(func).parameters
    opts = dict(options)
    if "motion" in params:
        motion_opts = {k: opts.pop(k) for k in list(opts) if k in _MOTION_FIELDS}
        if "motion" in opts:
            if motion_opts:
                raise ConfigError(
                    f"give either motion= or the motion settings ({', '.join(motion_opts)}), "
                    "not both."
                )
        else:
            opts["motion"] = SineMotion(**{**DEFAULT_MOTION, **motion_opts})
    bad = [k for k in opts if k not in params]
    if bad:
        valid = [p for p in params if p != "motion"]
        raise ConfigError(
            f"unknown option {bad[0]!r} for {kind!r} captures; valid options: "
            f"{', '.join(valid + list(_MOTION_FIELDS))}."
        )
    return func(**opts)
