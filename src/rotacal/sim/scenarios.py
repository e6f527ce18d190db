"""The five motions of Feng et al. (2023), Table 1, as inputs of the digital twin.

The paper measured a real table; its true motion is unknown. These scenarios are twin INPUTS chosen
to resemble it: the amplitudes and frequencies of Table 1, and a harmonic content scaled so that the
true THD of the simulated motion (harmonics, stagnation and creep together) equals the paper's
combined-scheme value (4.49, 5.42, 2.79, 1.38, 0.21 %). They are not measurements.
"""

from __future__ import annotations

import math
from typing import Any

from rotacal.sim.motion import SineMotion

__all__ = ["FOG_NOISE_DENSITY_DEG_S_RT_HZ", "HARMONIC_SHAPE", "table1_scenarios"]

#: Shape of the harmonic distortion (relative amplitudes with unit root-sum-square, phases in rad):
#: dominated by the 3rd harmonic, as friction-limited reversals give, with some 2nd, 4th, 5th, 7th.
HARMONIC_SHAPE: dict[int, tuple[float, float]] = {
    2: (0.35733, 0.6),
    3: (0.86780, 1.9),
    4: (0.12251, -0.7),
    5: (0.30628, 2.6),
    7: (0.10209, -1.2),
}

#: FOG white-noise density (deg/s/√Hz), chosen so that the 0.1°/5 Hz motion sampled at 2 kHz has
#: an SNR of 7.7 dB, the value Feng et al. (2023, §5) report for that case.
FOG_NOISE_DENSITY_DEG_S_RT_HZ = 0.02946

# (amplitude deg, frequency Hz, paper THD by OSE, by LTS, by FOG, harmonic scale tuned so that the
#  twin's true THD equals the combined-scheme value, sensors the paper used)
_TABLE1: tuple[
    tuple[float, float, float | None, float | None, float, float, tuple[str, ...]], ...
] = (
    (0.025, 10.0, None, 4.49, 7.50, 0.044952, ("lts", "fog")),
    (0.1, 5.0, 5.42, None, 5.31, 0.054274, ("encoder", "fog")),
    (0.25, 3.0, 2.79, None, 2.81, 0.027900, ("encoder", "fog")),
    (0.5, 2.0, 1.38, None, 1.41, 0.013737, ("encoder", "fog")),
    (5.0, 0.5, 0.21, None, 0.21, 0.0017279, ("encoder", "fog")),
)


def table1_scenarios() -> list[dict[str, Any]]:
    """The five sinusoidal motions of Table 1 of Feng et al. (2023), with sensor settings.

    Each scenario is a dict with

    - ``name`` (e.g. ``"0.1deg_5hz"``), ``amplitude_deg``, ``frequency_hz``;
    - ``motion``: a :class:`SineMotion` — the harmonic shape :data:`HARMONIC_SHAPE` scaled so the
      true THD matches the paper's combined-scheme value, a stagnation of 0.2 % of the period at
      each reversal and a creep of 0.2 % of the amplitude (these are twin inputs, not measured);
    - ``target_thd_percent``: that paper value; ``paper_thd_percent``: ``{"ose", "lts", "fog"}`` of
      Table 1 (None where the paper has no value);
    - ``paper_sensors``: the sensors the paper used (LTS for 0.025°, otherwise the encoder; FOG
      always);
    - ``sensors``: keyword options for ``simulate(kind, motion=motion, **options)`` for each of
      ``"encoder"`` (36 000 lines, 50 kHz, small offsets/gain/phase errors, noise, 16-bit ADC),
      ``"lts"`` (R = 100 mm, 0.03 µm noise, 10 kHz) and ``"fog"`` (2 kHz, white noise of
      :data:`FOG_NOISE_DENSITY_DEG_S_RT_HZ`, which gives ≈ 7.7 dB SNR at 0.1°/5 Hz and a low
      SNR at 0.025°/10 Hz, as the paper observed);
    - ``duration_s``: 6⅛ periods for the encoder and LTS (already in their options); the FOG
      records 40⅛ periods, because its THD is limited by noise and a lab records it longer.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §5 and Table 1.
    """
    out = []
    for i, (amp, freq, ose, lts, fog, scale, used) in enumerate(_TABLE1):
        period = 1.0 / freq
        motion = SineMotion(
            amplitude_deg=amp,
            frequency_hz=freq,
            harmonics={h: (r * scale, p) for h, (r, p) in HARMONIC_SHAPE.items()},
            stagnation_s=0.002 * period,
            creep_deg=0.002 * amp,
        )
        duration = 6.125 * period
        # The FOG's THD is noise-limited (seed §5): a lab records it longer than the encoder.
        fog_duration = 40.125 * period
        fog_fs = 2000.0
        sensors = {
            "encoder": {
                "lines": 36000,
                "fs_hz": 50_000.0,
                "duration_s": duration,
                "offset_a": 0.010,
                "offset_b": -0.007,
                "amplitude_a": 1.0,
                "amplitude_b": 0.994,
                "phase_error_rad": 0.004,
                "noise_rms": 0.002,
                "adc_bits": 16,
                "adc_range": (-1.25, 1.25),
                "seed": 1000 + 10 * i,
            },
            "lts": {
                "radius_mm": 100.0,
                "noise_mm": 3e-5,
                "zero_offset_mm": 0.0,
                "fs_hz": 10_000.0,
                "duration_s": duration,
                "seed": 1001 + 10 * i,
            },
            "fog": {
                "noise_deg_s": FOG_NOISE_DENSITY_DEG_S_RT_HZ * math.sqrt(fog_fs / 2.0),
                "bias_deg_s": 0.01,
                "fs_hz": fog_fs,
                "duration_s": fog_duration,
                "seed": 1002 + 10 * i,
            },
        }
        out.append(
            {
                "name": f"{amp:g}deg_{freq:g}hz",
                "amplitude_deg": amp,
                "frequency_hz": freq,
                "motion": motion,
                "target_thd_percent": ose if ose is not None else lts,
                "paper_thd_percent": {"ose": ose, "lts": lts, "fog": fog},
                "paper_sensors": used,
                "sensors": sensors,
                "duration_s": duration,
                "note": (
                    "twin inputs chosen to resemble Feng et al. 2023 Table 1; the harmonic "
                    "content is tuned so the true THD equals the paper's combined-scheme value"
                ),
            }
        )
    return out
