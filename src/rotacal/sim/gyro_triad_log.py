"""Twin of the robot-manipulator study's test as one continuous log: rotation runs with rests between.

For each axis x, y, z of the DUT and each rate r of ``rates_deg_s``, the robot rests for
``rest_s`` and then turns the DUT at +r, rests, turns at −r, each run lasting ``run_s`` (one
minute in the study: procedure steps 6–8, Table 2). The reference columns hold the set rate
(exact steps; 0 at rest). The outputs are

    u = K·ω + b + G·g_s(θ) + n,

K the scale/misalignment matrix and b the bias (as :func:`rotacal.sim.simulate_gyro_triad`), n
white Gaussian noise, and G·g_s(θ) an orientation-dependent term: the g-sensitivity G (output
unit per g) times gravity in the sensor frame, which turns about the rotation axis with the table
angle θ = |ω|·(t − t_start) when the axis is horizontal (the robot's J6 axis in the study's
figure 5): g_s = cos(θ + φ)·e₁ + sin(θ + φ)·e₂ (in g), e₁, e₂ the two DUT axes across the
rotation axis, φ a phase drawn per run. At rest gravity stays where the last run left it (the
rests are not runs).

Over whole revolutions G·g_s averages to zero; over a partial one it leaves a bias
(:mod:`rotacal.gyro.triad_log`). The truth (K, b, G, the runs' rows) is set here, not estimated.

This module imports only numpy, rotacal.errors and rotacal.sim (twin rule).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.gyro_triad import _bias, _matrix
from rotacal.sim.motion import _finite, _nonneg
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["DEFAULT_G_SENSITIVITY", "simulate_gyro_triad_log"]

#: A MEMS triad's g-sensitivity (output unit, here °/s, per g): a few 0.1 °/s/g on the diagonal.
DEFAULT_G_SENSITIVITY = (
    (0.20, 0.05, -0.03),
    (-0.04, 0.15, 0.02),
    (0.03, -0.02, 0.25),
)
_MAX_ROWS = 50_000_000
_RATE_COLUMNS = ("wx_deg_s", "wy_deg_s", "wz_deg_s")
_OUT_COLUMNS = ("ux", "uy", "uz")


def simulate_gyro_triad_log(
    *,
    rates_deg_s: tuple[float, ...] = (6.0, 18.0, 30.0, 60.0, 90.0),
    run_s: float = 60.0,
    rest_s: float = 2.0,
    K: Any = None,
    bias: Any = None,
    g_sensitivity: Any = None,
    noise_std: float = 0.1,
    fs_hz: float = 100.0,
    seed: int = 0,
) -> SimCapture:
    """A log of rotation runs about each axis at each rate in both directions, rests between.

    Parameters
    ----------
    rates_deg_s : tuple of float
        Rate magnitudes (°/s, > 0); the study's Table 2 by default.
    run_s : float
        Duration of each run (s; the study: 60, i.e. whole revolutions at its rates).
    rest_s : float
        Rest before each run (s).
    K, bias : array_like or None
        True scale/misalignment (output unit per °/s) and bias (output unit); None: the
        defaults of :func:`rotacal.sim.simulate_gyro_triad`.
    g_sensitivity : array_like (3, 3), float or None
        G (output unit per g); a float: that times the identity; None:
        :data:`DEFAULT_G_SENSITIVITY`; 0: no orientation-dependent term.
    noise_std : float
        White output noise per sample and channel (output unit, rms).
    fs_hz : float
        Sampling rate (Hz).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        Kind ``"gyro-triad-log"``; columns ``time_s`` (s), ``wx_deg_s``, ``wy_deg_s``,
        ``wz_deg_s`` (°/s), ``ux``, ``uy``, ``uz``. Truth: ``scale_misalignment``, ``bias``,
        ``g_sensitivity``, ``runs`` (each ``start``/``stop`` rows, ``rate_deg_s``, ``phase_deg``,
        ``angle_deg``), the settings.

    References
    ----------
    Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
    March 2023, procedure steps 6–8, Table 2, Fig. 5.
    """
    rates = np.asarray(rates_deg_s, dtype=float).ravel()
    if rates.size == 0 or not np.isfinite(rates).all() or np.any(rates <= 0):
        raise ConfigError(f"rates_deg_s must be positive rates (°/s), got {rates_deg_s!r}.")
    k, b = _matrix(K), _bias(bias)
    if g_sensitivity is None:
        g = np.asarray(DEFAULT_G_SENSITIVITY, dtype=float)
    elif np.ndim(g_sensitivity) == 0:
        g = _finite("g_sensitivity", g_sensitivity) * np.eye(3)
    else:
        g = np.asarray(g_sensitivity, dtype=float)
        if g.shape != (3, 3) or not np.isfinite(g).all():
            raise ConfigError(f"g_sensitivity must be a finite 3×3 matrix, got {g_sensitivity!r}.")
    fs = _finite("fs_hz", fs_hz)
    if fs <= 0:
        raise ConfigError(f"fs_hz must be > 0 Hz, got {fs_hz!r}.")
    n_run, n_rest = round(_finite("run_s", run_s) * fs), round(_nonneg("rest_s", rest_s) * fs)
    if n_run < 2:
        raise ConfigError(f"run_s={run_s!r} s gives fewer than 2 samples at {fs:g} Hz.")
    sigma = _nonneg("noise_std", noise_std)
    mags = np.ravel(np.column_stack([rates, -rates]))  # +r1, −r1, +r2, …
    n = 3 * mags.size * (n_rest + n_run) + n_rest
    if n > _MAX_ROWS:
        raise ConfigError(f"the log would have {n} rows, more than {_MAX_ROWS}; shorten it")
    rng = np.random.default_rng(seed)
    omega = np.zeros((n, 3))
    grav = np.zeros((n, 3))
    grav[:, 0] = 1.0  # at rest about x first: gravity along the first cross axis
    runs = []
    row = n_rest
    for axis in range(3):
        e1, e2 = (axis + 1) % 3, (axis + 2) % 3
        grav[row - n_rest : row, :] = 0.0
        grav[row - n_rest : row, e1] = 1.0
        for m in mags:
            a, stop = row, row + n_run
            phase = float(rng.uniform(0.0, 360.0))
            theta = np.deg2rad(abs(m) * np.arange(n_run) / fs + phase)
            omega[a:stop, axis] = m
            grav[a:stop, :] = 0.0
            grav[a:stop, e1] = np.cos(theta)
            grav[a:stop, e2] = np.sin(theta)
            # the rest after it: where the run left gravity
            grav[stop : stop + n_rest, :] = grav[stop - 1]
            runs.append(
                {
                    "start": a,
                    "stop": stop,
                    "rate_deg_s": omega[a].tolist(),
                    "phase_deg": phase,
                    "angle_deg": abs(m) * n_run / fs,
                }
            )
            row = stop + n_rest
    u = omega @ k.T + b + grav @ g.T
    if sigma > 0:
        u += rng.normal(0.0, sigma, u.shape)
    columns = {"time_s": np.arange(n) / fs}
    columns.update({c: omega[:, j].copy() for j, c in enumerate(_RATE_COLUMNS)})
    columns.update({c: u[:, j].copy() for j, c in enumerate(_OUT_COLUMNS)})
    truth = {
        "kind": "gyro-triad-log",
        "scale_misalignment": k.tolist(),
        "bias": b.tolist(),
        "g_sensitivity": g.tolist(),
        "runs": runs,
        "rows": n,
        "sensor": {
            "rates_deg_s": rates.tolist(),
            "run_s": n_run / fs,
            "rest_s": n_rest / fs,
            "noise_std": sigma,
            "fs_hz": fs,
            "seed": int(seed),
        },
    }
    return SimCapture("gyro-triad-log", columns, truth)


register_kind("gyro-triad-log", simulate_gyro_triad_log)
