"""The true angular motion of a sinusoidal rotary table, with its non-ideal behaviour (Feng et al. 2023).

Feng et al. (2023) calibrate a low-frequency angular-acceleration rotary table whose commanded
motion is a sine but whose real motion shows harmonic distortion and "stagnation, backwardness,
and creep" near the reversing moments (§1, §3.1). :class:`SineMotion` is the digital twin of that
motion: an exactly periodic, vectorised θ(t) and its analytic rate, plus the true values (harmonic
amplitudes, THD, angular-acceleration amplitude, reversing moments) computed by methods that share
nothing with rotacal's estimators (FFT over one exact period; dense sign scan and
``scipy.optimize.brentq``).

The model is a chain of four stages, each exactly periodic with the period T = 1/f (the table is
assumed to be in its settled periodic state from t = -∞, so nothing depends on the start time):

1. **Command.** With the phase ``u`` (rad) of the fundamental,
   ``c(u) = offset + A·[sin u + Σ_h r_h·sin(h·u + ψ_h)]`` (deg), ``harmonics = {h: (r_h, ψ_h)}``.
2. **Stagnation** (``stagnation_s``). A time warp: at each reversal phase ``u_j`` of ``c`` (every
   zero of ``dc/du`` with a sign change) the phase stops for ``stagnation_s`` seconds, and between
   dwells it runs faster by ``k = 2π/(2π − n·ω·stagnation_s)`` so the period stays T (n reversals
   per period). Dwells are centred so that their mean time shift is zero: for a pure sine the
   dwells sit symmetrically around the analytic quarter periods. The velocity is continuous (it is
   zero at the dwell edges because ``dc/du = 0`` there); the acceleration jumps.
3. **Backlash** (``backlash_deg`` = b). The standard play (backlash) operator of width b, centred:
   while the command rises the output is ``max(y₀, c − b/2)``, while it falls ``min(y₀, c + b/2)``,
   with ``y₀`` the output at the start of that monotone segment. After a reversal the output stays
   flat until the command has travelled the dead band (b, in the settled state), then follows it;
   the velocity jumps from zero to the command's velocity when the play is taken up.
4. **Creep** (``creep_deg`` = C, ``creep_time_s`` = X, default 0.1·T). When the table leaves a
   reversal (end of the dwell and of the dead band, at time ``t_e`` with new direction ``d``) it
   creeps off slowly: ``−d·C·sin²(π(t − t_e)/X)`` is added to its angle for ``0 ≤ t − t_e ≤ X``
   (a lag behind the new direction of motion, peak C at X/2) and nothing afterwards (smooth,
   compactly supported, C¹ at both ends). While C < ``A·ω²·X²/(2π²)`` (pure sine) the reversal
   stays at ``t_e`` and the table only leaves it slowly; a larger C makes the table overrun: it
   keeps going the old way after ``t_e`` and reverses later (the truth follows that reversal).

Vibration (``vibration_deg``, ``vibration_hz``) is a separate sine added to the angle: it is part of
what the sensors see but not of the periodic motion whose truth is reported.

Drift (``drift_deg_s`` = d) is a slow, steady turn of the table added to the angle, ``d·t`` (t in s
from the time origin t = 0), so the rate carries the constant d. It is not part of the periodic
motion (its harmonics and THD are the truth without it), but it is part of the motion: the
reversing moments are the zeros of the whole vibration-free rate, periodic part plus d (with drift
a maximum and the next minimum are no longer half a period apart, and for |d| above the periodic
rate's peaks there are none). The truth reports d as ``drift_deg_s``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import brentq

from rotacal.errors import ConfigError

__all__ = ["SineMotion"]

TWO_PI = 2.0 * math.pi
#: FFT length over one period for the harmonic truth.
TRUTH_FFT_POINTS = 2**16
#: Points per period of the dense velocity scan for the reversing moments.
SCAN_POINTS = 2**16
_U_SCAN = 8192  # points per 2π of the command's reversal-phase scan
_RTOL = 4.0 * np.finfo(float).eps


def _finite(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}.") from None
    if not math.isfinite(v):
        raise ConfigError(f"{name} must be finite, got {value!r}.")
    return v


def _nonneg(name: str, value: Any) -> float:
    v = _finite(name, value)
    if v < 0:
        raise ConfigError(f"{name} must be ≥ 0, got {value!r}.")
    return v


@dataclasses.dataclass(frozen=True)
class _Model:
    """Per-period constants of the motion model (computed once per SineMotion)."""

    u_rev: np.ndarray  # reversal phases of the command, ascending in [u0, u0 + 2π)
    c_rev: np.ndarray  # command at each reversal (deg)
    direction: np.ndarray  # +1/-1: direction of the command after each reversal
    k: float  # phase speed-up between dwells
    delta: float  # dwell length in phase units (rad)
    seg_s: np.ndarray  # start of each segment (= start of the dwell), relative to seg_s0 (rad)
    seg_s0: float  # absolute phase s of the first dwell start (rad)
    warp_s: np.ndarray  # knots of the warp in relative phase s (rad)
    warp_u: np.ndarray  # warped phase u at the knots (rad)
    y0: np.ndarray  # backlash output at each segment start (deg)
    depart_s: np.ndarray  # relative phase s at which the output leaves each reversal (rad)
    creep_x_s: float  # creep support (s)


@dataclasses.dataclass(frozen=True)
class SineMotion:
    """Sinusoidal rotary-table motion with harmonics, stagnation, backlash, creep and vibration.

    The full model is described in the module docstring of :mod:`rotacal.sim.motion`.

    Parameters
    ----------
    amplitude_deg : float
        Commanded fundamental amplitude A (deg), > 0.
    frequency_hz : float
        Motion frequency f (Hz), > 0.
    harmonics : mapping of int to (float, float)
        ``h → (r_h, ψ_h)``: amplitude relative to the fundamental (-) and phase (rad) of harmonic
        h ≥ 2 in ``A·r_h·sin(h·u + ψ_h)``.
    phase_rad : float
        Phase of the fundamental at t = 0 (rad): ``u = 2πft + phase_rad`` without stagnation.
    offset_deg : float
        Constant angle added to the command (deg).
    stagnation_s : float
        Dwell at each reversal (s).
    creep_deg : float
        Peak creep lag after each reversal (deg).
    backlash_deg : float
        Width of the play (dead band) b (deg).
    vibration_deg, vibration_hz, vibration_phase_rad : float
        Superposed vibration ``vibration_deg·sin(2π·vibration_hz·t + vibration_phase_rad)``.
    creep_time_s : float or None
        Duration X of the creep lag (s); None gives 0.1/f.
    drift_deg_s : float
        Steady drift d of the table (deg/s): ``d·t`` is added to the angle (see the module
        docstring).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §1 and §3.1 (non-ideal motion: stagnation, backwardness,
    creep), eq. (1) (THD).
    """

    amplitude_deg: float
    frequency_hz: float
    harmonics: Mapping[int, tuple[float, float]] = dataclasses.field(default_factory=dict)
    phase_rad: float = 0.0
    offset_deg: float = 0.0
    stagnation_s: float = 0.0
    creep_deg: float = 0.0
    backlash_deg: float = 0.0
    vibration_deg: float = 0.0
    vibration_hz: float = 0.0
    vibration_phase_rad: float = 0.0
    creep_time_s: float | None = None
    drift_deg_s: float = 0.0

    # ------------------------------------------------------------------ validation
    def __post_init__(self) -> None:
        a = _finite("amplitude_deg", self.amplitude_deg)
        if a <= 0:
            raise ConfigError(f"amplitude_deg must be > 0 degrees, got {self.amplitude_deg!r}.")
        f = _finite("frequency_hz", self.frequency_hz)
        if f <= 0:
            raise ConfigError(f"frequency_hz must be > 0 Hz, got {self.frequency_hz!r}.")
        if not isinstance(self.harmonics, Mapping):
            raise ConfigError(
                "harmonics must be a mapping {order: (relative amplitude, phase_rad)}."
            )
        harm: dict[int, tuple[float, float]] = {}
        for h, val in self.harmonics.items():
            is_int = isinstance(h, (int, np.integer)) and not isinstance(h, bool)
            if not (is_int or (isinstance(h, str) and h.strip().isdigit())) or int(h) < 2:
                raise ConfigError(f"harmonic order {h!r} must be an integer ≥ 2.")
            hi = int(h)
            try:
                r, psi = val
            except (TypeError, ValueError):
                raise ConfigError(
                    f"harmonics[{hi}] must be a pair (relative amplitude, phase_rad), got {val!r}."
                ) from None
            harm[hi] = (
                _nonneg(f"harmonics[{hi}] amplitude", r),
                _finite(f"harmonics[{hi}] phase", psi),
            )
        object.__setattr__(self, "harmonics", dict(sorted(harm.items())))
        for name in ("amplitude_deg", "frequency_hz", "phase_rad", "offset_deg", "drift_deg_s"):
            object.__setattr__(self, name, _finite(name, getattr(self, name)))
        for name in (
            "stagnation_s",
            "creep_deg",
            "backlash_deg",
            "vibration_deg",
            "vibration_hz",
        ):
            object.__setattr__(self, name, _nonneg(name, getattr(self, name)))
        object.__setattr__(
            self, "vibration_phase_rad", _finite("vibration_phase_rad", self.vibration_phase_rad)
        )
        if self.vibration_deg > 0 and self.vibration_hz <= 0:
            raise ConfigError("vibration_hz must be > 0 when vibration_deg is set.")
        if self.creep_time_s is not None:
            x = _finite("creep_time_s", self.creep_time_s)
            if x <= 0:
                raise ConfigError(f"creep_time_s must be > 0 s, got {self.creep_time_s!r}.")
            object.__setattr__(self, "creep_time_s", x)
        _ = self._model  # build (and validate) the periodic model now

    # ------------------------------------------------------------------ basic quantities
    @property
    def period_s(self) -> float:
        """Motion period T = 1/f (s)."""
        return 1.0 / self.frequency_hz

    @property
    def omega(self) -> float:
        """Angular frequency ω = 2πf (rad/s)."""
        return TWO_PI * self.frequency_hz

    def to_dict(self) -> dict[str, Any]:
        """The motion's settings as JSON-able values (harmonics keyed by the order as a string)."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name == "harmonics":
                v = {str(h): [float(r), float(p)] for h, (r, p) in v.items()}
            elif v is not None:
                v = float(v)
            out[f.name] = v
        out["creep_time_s_used"] = float(self._model.creep_x_s)
        return out

    # ------------------------------------------------------------------ command c(u)
    def _command(self, u: np.ndarray) -> np.ndarray:
        c = np.sin(u)
        for h, (r, psi) in self.harmonics.items():
            if r:
                c = c + r * np.sin(h * u + psi)
        return self.offset_deg + self.amplitude_deg * c

    def _command_du(self, u: np.ndarray) -> np.ndarray:
        d = np.cos(u)
        for h, (r, psi) in self.harmonics.items():
            if r:
                d = d + r * h * np.cos(h * u + psi)
        return self.amplitude_deg * d

    def _command_scalar(self, u: float) -> float:
        return float(self._command(np.array([u]))[0])

    def _command_du_scalar(self, u: float) -> float:
        return float(self._command_du(np.array([u]))[0])

    # ------------------------------------------------------------------ model constants
    @functools.cached_property
    def _model(self) -> _Model:
        T = self.period_s
        w = self.omega
        # 1. reversal phases of the command: sign changes of dc/du over one period of u.
        # Scan a little more than one period so a root at the wrap is not lost; samples that
        # are exactly zero are skipped so that such a root counts once.
        ug = np.linspace(-0.25, TWO_PI + 0.25, _U_SCAN + 1)
        sg = np.sign(self._command_du(ug))
        nz = np.flatnonzero(sg != 0)
        idx = np.flatnonzero(sg[nz][1:] != sg[nz][:-1])
        roots = [
            brentq(self._command_du_scalar, ug[nz[i]], ug[nz[i + 1]], xtol=1e-15, rtol=_RTOL)
            for i in idx
        ]
        u_all = np.sort(np.mod(np.asarray(roots, dtype=float), TWO_PI))
        if u_all.size:  # drop the duplicates of the overlap (same root seen twice)
            gap = np.diff(np.append(u_all, u_all[0] + TWO_PI))
            u_all = u_all[gap > 1e-9]
        u_rev = u_all
        n = u_rev.size
        if n < 2 or n % 2:
            raise ConfigError(  # pragma: no cover - a periodic non-constant c always has ≥ 2
                "the commanded motion has no clear reversals; check harmonics."
            )
        c_rev = self._command(u_rev)
        mids = 0.5 * (u_rev + np.append(u_rev[1:], u_rev[0] + TWO_PI))
        direction = np.sign(self._command_du(mids)).astype(float)
        # 2. stagnation warp
        delta = w * self.stagnation_s
        if n * self.stagnation_s > 0.5 * T:
            raise ConfigError(
                f"stagnation_s={self.stagnation_s!r} s is too long: the {n} dwells per period must "
                f"take at most half the period ({0.5 * T / n:.6g} s each)."
            )
        k = TWO_PI / (TWO_PI - n * delta)
        du = np.diff(np.append(u_rev, u_rev[0] + TWO_PI))  # phase between reversals
        d_rel = np.concatenate(([0.0], np.cumsum(delta + du[:-1] / k)))  # σ_j − σ_0
        sigma0 = float(np.mean(u_rev - d_rel))
        sigma = sigma0 + d_rel
        seg_s0 = sigma0 - 0.5 * delta
        seg_s = sigma - 0.5 * delta - seg_s0  # = d_rel
        warp_s = np.empty(2 * n + 1)
        warp_u = np.empty(2 * n + 1)
        warp_s[0:-1:2] = seg_s
        warp_s[1::2] = seg_s + delta
        warp_s[-1] = TWO_PI
        warp_u[0:-1:2] = u_rev
        warp_u[1::2] = u_rev
        warp_u[-1] = u_rev[0] + TWO_PI
        # 3. backlash: output at each segment start, settled periodic state from the global max
        b = self.backlash_deg
        pp = float(np.max(c_rev) - np.min(c_rev))
        if b >= 0.5 * pp:
            raise ConfigError(
                f"backlash_deg={b!r} is too large: it must be less than half the peak-to-peak "
                f"commanded motion ({0.5 * pp:.6g} deg)."
            )
        y0 = np.empty(n)
        depart_u = u_rev.copy()
        if b > 0:
            jstar = int(np.argmax(c_rev))
            y = c_rev[jstar] - 0.5 * b
            for m in range(n):
                j = (jstar + m) % n
                y0[j] = y
                c_next = c_rev[(j + 1) % n]
                if direction[j] < 0:
                    y = min(y, c_next + 0.5 * b)
                    target = y0[j] - 0.5 * b
                    moves = c_next < target
                else:
                    y = max(y, c_next - 0.5 * b)
                    target = y0[j] + 0.5 * b
                    moves = c_next > target
                if moves:
                    ua, ub = u_rev[j], u_rev[j] + du[j]
                    depart_u[j] = brentq(
                        lambda uu, tg=target: self._command_scalar(uu) - tg,
                        ua,
                        ub,
                        xtol=1e-15,
                        rtol=_RTOL,
                    )
                else:
                    depart_u[j] = np.nan  # the output never leaves this reversal
        else:
            y0[:] = c_rev
        # departure in relative s: end of dwell + (u − u_j)/k
        depart_s = seg_s + delta + (depart_u - u_rev) / k
        # 4. creep support must end before the next dwell starts
        x = self.creep_time_s if self.creep_time_s is not None else 0.1 * T
        if self.creep_deg > 0:
            nxt = np.append(seg_s[1:], TWO_PI)
            avail = (nxt - depart_s) / w
            avail = avail[np.isfinite(avail)]
            if avail.size and x > float(np.min(avail)) * (1 + 1e-12):
                raise ConfigError(
                    f"creep_time_s={x:.6g} s is too long: the table moves only "
                    f"{float(np.min(avail)):.6g} s between leaving a reversal and the next one."
                )
        return _Model(
            u_rev=u_rev,
            c_rev=c_rev,
            direction=direction,
            k=float(k),
            delta=float(delta),
            seg_s=seg_s,
            seg_s0=float(seg_s0),
            warp_s=warp_s,
            warp_u=warp_u,
            y0=y0,
            depart_s=depart_s,
            creep_x_s=float(x),
        )

    # ------------------------------------------------------------------ evaluation
    def _evaluate(self, t: Any, *, rate: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Vibration-free angle (deg) and, if asked, rate (deg/s) at times t (s)."""
        m = self._model
        t = np.asarray(t, dtype=float)
        w = self.omega
        s = w * t + self.phase_rad
        s_off = s - m.seg_s0
        s_rel = np.mod(s_off, TWO_PI)
        # 2. warp
        if m.delta > 0:
            u = np.interp(s_rel, m.warp_s, m.warp_u)
            knot = np.searchsorted(m.warp_s, s_rel, side="right") - 1
            du_ds = np.where(knot % 2 == 0, 0.0, m.k)
        else:
            u = s
            du_ds = np.ones_like(s)
        c = self._command(u)
        dc = self._command_du(u) * w * du_ds if rate else None
        # 3. backlash
        b = self.backlash_deg
        if b > 0:
            seg = np.searchsorted(m.seg_s, s_rel, side="right") - 1
            y0 = m.y0[seg]
            rising = m.direction[seg] > 0
            y = np.where(rising, np.maximum(y0, c - 0.5 * b), np.minimum(y0, c + 0.5 * b))
            if dc is not None:
                moving = np.where(rising, c - 0.5 * b > y0, c + 0.5 * b < y0)
                dc = np.where(moving, dc, 0.0)
        else:
            y = c
        # 4. creep
        if self.creep_deg > 0:
            x = m.creep_x_s
            for j in range(m.direction.size):
                if not np.isfinite(m.depart_s[j]):
                    continue
                tau = np.mod(s_rel - m.depart_s[j], TWO_PI) / w
                inside = tau < x
                if not np.any(inside):
                    continue
                arg = math.pi * np.where(inside, tau, 0.0) / x
                lag = -m.direction[j] * self.creep_deg
                y = y + np.where(inside, lag * np.sin(arg) ** 2, 0.0)
                if dc is not None:
                    dc = dc + np.where(inside, lag * (math.pi / x) * np.sin(2.0 * arg), 0.0)
        return y, dc

    def _vibration(self, t: np.ndarray) -> np.ndarray:
        return self.vibration_deg * np.sin(
            TWO_PI * self.vibration_hz * t + self.vibration_phase_rad
        )

    def _vibration_rate(self, t: np.ndarray) -> np.ndarray:
        wv = TWO_PI * self.vibration_hz
        return self.vibration_deg * wv * np.cos(wv * t + self.vibration_phase_rad)

    def angle_deg(self, t: Any) -> np.ndarray:
        """True table angle θ(t) (deg) at times ``t`` (s), vibration included.

        Parameters
        ----------
        t : array_like
            Times (s).

        Returns
        -------
        numpy.ndarray
            θ (deg), same shape as ``t``.
        """
        t = np.asarray(t, dtype=float)
        y, _ = self._evaluate(t, rate=False)
        if self.vibration_deg > 0:
            y = y + self._vibration(t)
        if self.drift_deg_s != 0.0:
            y = y + self.drift_deg_s * t
        return y

    def rate_deg_s(self, t: Any) -> np.ndarray:
        """True angular rate dθ/dt (deg/s) at times ``t`` (s), analytic, vibration included.

        At the instants where the model's velocity jumps (the play being taken up after a
        reversal) the value is the one-sided limit of the segment the instant belongs to.
        """
        t = np.asarray(t, dtype=float)
        _, r = self._evaluate(t, rate=True)
        assert r is not None
        if self.vibration_deg > 0:
            r = r + self._vibration_rate(t)
        if self.drift_deg_s != 0.0:
            r = r + self.drift_deg_s
        return r

    def angle_no_vibration_deg(self, t: Any) -> np.ndarray:
        """The periodic part of θ(t) (deg), without vibration and drift: what :meth:`truth`'s
        harmonics and THD describe."""
        return self._evaluate(np.asarray(t, dtype=float), rate=False)[0]

    def rate_no_vibration_deg_s(self, t: Any) -> np.ndarray:
        """The periodic part of dθ/dt (deg/s), without vibration and drift."""
        r = self._evaluate(np.asarray(t, dtype=float), rate=True)[1]
        assert r is not None
        return r

    def _reversal_rate(self, t: Any) -> np.ndarray:
        """The vibration-free rate whose zeros are the reversing moments: periodic part plus drift."""
        r = self.rate_no_vibration_deg_s(t)
        return r + self.drift_deg_s if self.drift_deg_s != 0.0 else r

    # ------------------------------------------------------------------ truth
    def harmonic_truth(self, harmonics: int = 10, *, points: int = TRUTH_FFT_POINTS) -> dict:
        """Exact Fourier amplitudes of the periodic vibration-free motion.

        The motion is sampled at ``points`` instants over exactly one period and transformed with
        ``numpy.fft.rfft``; for a band-limited motion this is exact, for the piecewise-smooth
        stagnation/backlash/creep model the aliasing error is O(points⁻²).

        Returns
        -------
        dict
            ``amplitudes_deg`` (h = 1..N), ``phases_rad`` (sine phase at t = 0, h = 1..N),
            ``mean_deg``.
        """
        n_h = int(harmonics)
        if n_h < 1 or n_h >= points // 2:
            raise ConfigError(
                f"harmonics must be between 1 and {points // 2 - 1}, got {harmonics!r}."
            )
        key = (n_h, int(points))
        if key not in self._harmonic_truths:
            # the periodic motion's own property: computed once per motion and kept (a truth of
            # every capture of it, which would otherwise evaluate and transform 2¹⁶ points)
            t = np.arange(points) * (self.period_s / points)
            spec = np.fft.rfft(self.angle_no_vibration_deg(t))
            amps = 2.0 * np.abs(spec[1 : n_h + 1]) / points
            # θ ⊃ A_h·sin(2πhft + φ_h)  ⇒  X_h = (M/2)·A_h·e^{i(φ_h − π/2)}
            phases = np.mod(np.angle(spec[1 : n_h + 1]) + 0.5 * math.pi + math.pi, TWO_PI)
            self._harmonic_truths[key] = (amps, phases - math.pi, float(spec[0].real / points))
        amps, phases, mean = self._harmonic_truths[key]
        return {"amplitudes_deg": amps.copy(), "phases_rad": phases.copy(), "mean_deg": mean}

    @functools.cached_property
    def _harmonic_truths(self) -> dict[tuple[int, int], tuple[np.ndarray, np.ndarray, float]]:
        """:meth:`harmonic_truth`'s results by (harmonics, points), filled as they are asked."""
        return {}

    @functools.cached_property
    def _period_reversals(self) -> np.ndarray:
        """Reversing moments of the vibration-free motion in [0, T) (s), ascending."""
        T = self.period_s
        t = np.linspace(-0.25 * T, 1.25 * T, int(1.5 * SCAN_POINTS) + 1)
        r = self._reversal_rate(t)
        sg = np.sign(r)
        nz = np.flatnonzero(sg != 0)
        ch = np.flatnonzero(sg[nz][1:] != sg[nz][:-1])
        out = []

        def rate1(x: float) -> float:
            return float(self._reversal_rate(np.array([x]))[0])

        for i in ch:
            ia, ib = nz[i], nz[i + 1]
            ta, tb = float(t[ia]), float(t[ib])
            s_old, s_new = sg[ia], sg[ib]
            t0 = brentq(rate1, ta, tb, xtol=1e-15, rtol=_RTOL)
            eps = 1e-9 * T
            if rate1(t0 - eps) * s_old > 0 and rate1(t0 + eps) * s_new > 0:
                tr = t0  # a simple zero
            else:  # a dwell: velocity exactly zero on [L, R]; take its middle

                def left(x: float, s: float = s_old) -> float:
                    return 1.0 if rate1(x) * s > 0 else -1.0

                def right(x: float, s: float = s_new) -> float:
                    return 1.0 if rate1(x) * s > 0 else -1.0

                lo = brentq(left, ta, tb, xtol=1e-15, rtol=_RTOL)
                hi = brentq(right, ta, tb, xtol=1e-15, rtol=_RTOL)
                tr = 0.5 * (lo + hi)
            if 0.0 <= tr < T:
                out.append(tr)
        res = np.unique(np.asarray(out, dtype=float))
        return res

    def reversal_times_s(self, t_start: float, t_stop: float) -> np.ndarray:
        """Every reversing moment (zero of the vibration-free velocity) in [t_start, t_stop] (s).

        Found once per period by a dense sign scan of the vibration-free rate (periodic part plus
        drift; periodic, so one period serves all)
        (``SCAN_POINTS`` per period) and ``scipy.optimize.brentq``; a dwell (velocity exactly
        zero over an interval, from stagnation or backlash) counts once, at its middle.
        """
        T = self.period_s
        base = self._period_reversals
        k0 = math.floor(t_start / T) - 1
        k1 = math.ceil(t_stop / T) + 1
        ks = np.arange(k0, k1 + 1)
        allr = (base[None, :] + T * ks[:, None]).ravel()
        return allr[(allr >= t_start) & (allr <= t_stop)]

    def truth(self, t_start: float, t_stop: float, harmonics: int = 10) -> dict[str, Any]:
        """True values of the motion over [t_start, t_stop] (s), as JSON-able Python values.

        Parameters
        ----------
        t_start, t_stop : float
            Time span (s) of the capture; used for the reversing moments and ``periods``.
        harmonics : int
            Highest harmonic order N in the THD.

        Returns
        -------
        dict
            ``amplitude_deg`` (fundamental A₁ of the periodic vibration-free motion),
            ``frequency_hz``, ``thd_percent`` (eq. (1), h = 2..N), ``harmonic_amplitudes_deg``
            (h = 1..N), ``harmonic_phases_rad``, ``mean_deg``,
            ``angular_acceleration_amplitude_deg_s2`` = A₁(2πf)², ``reversal_times_s``,
            ``periods`` (span × f), ``t_start_s``, ``t_stop_s``, ``drift_deg_s`` (the drift d,
            deg/s, not in the harmonics), ``motion`` (the settings).

        References
        ----------
        Feng et al. 2023, Sensors 23:4876, eq. (1); IEEE Std 1057-2017 (THD definition).
        """
        t_start = _finite("t_start", t_start)
        t_stop = _finite("t_stop", t_stop)
        if t_stop <= t_start:
            raise ConfigError(f"t_stop ({t_stop}) must be after t_start ({t_start}).")
        ht = self.harmonic_truth(harmonics)
        amps = ht["amplitudes_deg"]
        a1 = float(amps[0])
        thd = 100.0 * math.sqrt(float(np.sum(amps[1:] ** 2))) / a1
        return {
            "amplitude_deg": a1,
            "frequency_hz": float(self.frequency_hz),
            "thd_percent": thd,
            "harmonic_amplitudes_deg": [float(v) for v in amps],
            "harmonic_phases_rad": [float(v) for v in ht["phases_rad"]],
            "mean_deg": ht["mean_deg"],
            "angular_acceleration_amplitude_deg_s2": a1 * self.omega**2,
            "reversal_times_s": [float(v) for v in self.reversal_times_s(t_start, t_stop)],
            "periods": (t_stop - t_start) * self.frequency_hz,
            "t_start_s": t_start,
            "t_stop_s": t_stop,
            "drift_deg_s": float(self.drift_deg_s),
            "harmonics": int(harmonics),
            "motion": self.to_dict(),
        }
