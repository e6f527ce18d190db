"""THD of the sinusoidal-motion calibration with its Monte Carlo evaluation (JCGM 101): bias,
u and a Neyman confidence belt for the true THD (eq. (1) of Feng et al. 2023). Part of
:mod:`rotacal.table.motion_uncertainty`, which re-exports every name.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.table._motion_helpers import _DEG, _P
from rotacal.uncertainty import (
    BudgetRow,
    Input,
    UncertaintyBudget,
    numerical_tolerance,
    propagate,
)

#: Most Monte Carlo draws of the THD (belt and spread; ~30 ms). Each tail probability of the belt
#: is then known to √(α(1−α)/M) ≈ 7·10⁻⁴ (coverage 95 ± 0.1 %); the standard error of U that
#: follows is stated in the budget (typically well under 1 % of U).
THD_TRIALS = 50_000
#: Draws of the first run of the adaptive choice of M (JCGM 101 §7.9): enough when U's Monte Carlo
#: standard error is within the numerical tolerance of its two significant digits.
THD_FIRST_TRIALS = 10_000
_TRIALS_STEP = 10_000
#: Seed of the THD Monte Carlo (the same capture always gives the same budget).
THD_SEED = 4876


def thd_bias_corrected_percent(amplitudes: Any, amplitudes_u: Any) -> float:
    """THD with the noise power removed: ``100·√max(0, Σ_{h≥2}(A_h² − 2u_h²))/A_1`` (%).

    A harmonic fitted in white noise has two components with variance u_h² each, so
    ``E[Â_h²] = A_h² + 2u_h²``; subtracting the expected noise power removes the upward bias of
    eq. (1) near zero (a pure sine gives ~0 instead of ~√(2Σu_h²)/A_1).

    Parameters
    ----------
    amplitudes : array_like — A_1, A_2, … (h = 1 first; any common unit).
    amplitudes_u : array_like — their standard uncertainties (same unit).

    Returns
    -------
    float — bias-corrected THD (%), ≥ 0.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1); JCGM 102:2011 §9 (bias of a magnitude near zero).
    """
    a = np.asarray(amplitudes, dtype=float)
    u = np.asarray(amplitudes_u, dtype=float)
    if a.shape != u.shape or a.ndim != 1 or a.size < 1 or not a[0] > 0:
        raise ConfigError("amplitudes and amplitudes_u must be equal 1-D arrays with A_1 > 0.")
    power = float(np.sum(a[1:] ** 2 - 2.0 * u[1:] ** 2))
    return 100.0 * math.sqrt(max(power, 0.0)) / float(a[0])


@dataclasses.dataclass(frozen=True)
class ThdUncertainty:
    """The THD's evaluation (all in % of the fundamental; see :func:`thd_uncertainty`).

    Attributes
    ----------
    plain : eq. (1) from the fitted amplitudes — the reported ``thd_percent`` and the budget's
        value.
    bias_corrected : :func:`thd_bias_corrected_percent` (noise power removed).
    mc_mean : mean of the plain estimator simulated at the bias-corrected THD.
    bias : ``mc_mean − bias_corrected`` (pp): the noise's upward push at that THD.
    u : standard deviation of the plain estimator there.
    interval : 95 % coverage interval for the TRUE THD (lower end 0 when the measured harmonic
        power is consistent with noise).
    U, k : half the interval's width, and U/u.
    U_mc_error : Monte Carlo standard error of U (pp), from the draws' quantile errors.
    trials : Monte Carlo draws M.
    budget : the UncertaintyBudget (method "Monte Carlo", ``interval`` set).
    """

    plain: float
    bias_corrected: float
    mc_mean: float
    bias: float
    u: float
    U: float
    k: float
    interval: tuple[float, float]
    U_mc_error: float
    trials: int
    budget: UncertaintyBudget


class _ThdDraws:
    """Common random numbers of the THD Monte Carlo, reduced to two numbers per draw.

    With harmonic h's true components (√(w_h·P), 0) in its own frame and noise u_h·(z₁, z₂), the
    measured power ``T = Σ_h |Â_h|² = P + 2√P·X + Y`` with ``X = Σ √w_h·u_h·z_h1`` and
    ``Y = Σ u_h²(z_h1² + z_h2²)`` (Σ w_h = 1): one set of draws serves every true power P, so
    the confidence belt is smooth in P (common random numbers) and each evaluation is O(M).
    """

    def __init__(
        self, a: np.ndarray, u: np.ndarray, weights: np.ndarray, trials: int, seed: int
    ) -> None:
        z1, z_power, za, zb = _thd_normals(trials, a.size - 1, seed)
        uh = u[1:]
        self.x = z1 @ (np.sqrt(weights) * uh)
        self.y = z_power @ (uh * uh)
        self.a1_true = float(a[0])
        self.a1 = np.hypot(a[0] + u[0] * za, u[0] * zb)
        self.trials = trials

    def power(self, thd: float) -> float:
        """True harmonic power P (unit of A squared) of a true THD (%)."""
        return (max(thd, 0.0) * self.a1_true / 100.0) ** 2

    def plain(self, thd: float) -> np.ndarray:
        """The plain estimator of eq. (1) in every draw, at a true THD ``thd`` (%)."""
        p = self.power(thd)
        # 100·√max(P + 2√P·X + Y, 0)/A₁, evaluated in that order, in place (no temporaries)
        t = self.x * (2.0 * math.sqrt(p))
        t += p
        t += self.y
        np.maximum(t, 0.0, out=t)
        np.sqrt(t, out=t)
        t *= 100.0
        t /= self.a1
        return t


def _thd_normals(trials: int, nh: int, seed: int) -> tuple[np.ndarray, ...]:
    """The standard normal draws of :class:`_ThdDraws` (z₁, z₁² + z₂², z_a, z_b), in batches of
    10,000 from one seed each (:func:`_thd_batch`): the adaptive choice of M draws only the
    batches it adds, and every capture with ``nh`` harmonics above the fundamental reads the same
    draws."""
    step = _TRIALS_STEP
    parts = [
        _thd_batch(i, min(step, trials - i * step), nh, seed) for i in range(-(-trials // step))
    ]
    if len(parts) == 1:
        return parts[0]
    return tuple(np.concatenate([part[j] for part in parts]) for j in range(4))


@functools.lru_cache(maxsize=8)
def _thd_batch(index: int, size: int, nh: int, seed: int) -> tuple[np.ndarray, ...]:
    """Batch ``index`` of :func:`_thd_normals`, drawn once and kept, read-only, instead of again
    in every calibration (a tenth of a motion calibration's time)."""
    rng = np.random.default_rng([seed, index])
    z1 = rng.standard_normal((size, nh))
    z2 = rng.standard_normal((size, nh))
    za, zb = rng.standard_normal((2, size))
    drawn = (z1, z1 * z1 + z2 * z2, za, zb)
    for z in drawn:
        z.flags.writeable = False
    return drawn


def _quantile(values: np.ndarray, q: float) -> float:
    """``numpy.quantile(values, q)`` (its default, linear interpolation between the order
    statistics at (n − 1)·q, and its two-sided lerp) to the bit, for a 1-D array without NaN,
    at a fraction of its cost: the belt's root finding asks for ~40 quantiles per budget."""
    q = min(max(q, 0.0), 1.0)
    n = values.size
    at = (n - 1) * q
    if at >= n - 1:
        return float(np.max(values))
    below = math.floor(at)
    # one selection, then the next order statistic as the least value above it: NumPy's
    # partition at two indices costs several times one (the same two values)
    part = np.partition(values, below)
    lo, hi = float(part[below]), float(np.min(part[below + 1 :]))
    gamma = at - below
    diff = hi - lo
    return hi - diff * (1.0 - gamma) if gamma >= 0.5 else lo + diff * gamma


def _bracketed_root(
    f: Callable[[float], float], x0: float, f0: float, x1: float, *, tol: float
) -> float:
    """A root of ``f`` in [x0, x1], where ``f(x0) = f0`` and f(x1) have opposite signs (or
    one is 0), to within ``tol`` (unit of x): the Anderson–Björck variant of false position.

    Each step takes the secant through the two ends that bracket the root; when the same end is
    kept twice its function value is scaled by ``1 − f_new/f_old`` (by ½ when that is not
    positive), which restores superlinear convergence where plain false position stalls; a
    step that would move less than ``tol/2`` moves ``tol/2`` towards the other end (as in
    Brent's method), so the bracket closes once the newest point has converged; and a bisection
    is taken whenever the bracket did not at least halve over two steps, so it shrinks below
    ``tol`` in a bounded number of steps for any continuous ``f``. Returns the end of the final
    bracket with the smaller |f|.

    References
    ----------
    N. Anderson and Å. Björck 1973, BIT 13:253–264 ("A new high order method of regula falsi
    type for computing a root of an equation"); J. A. Ford 1995, "Improved algorithms of
    Illinois-type for the numerical solution of nonlinear equations" (University of Essex).
    """
    f1 = f(x1)
    if f0 == 0.0:
        return x0
    before_last = last = math.inf  # the bracket's width two steps and one step ago
    while f1 != 0.0 and abs(x1 - x0) > tol:
        width = abs(x1 - x0)
        x = x1 - f1 * (x1 - x0) / (f1 - f0)
        if abs(x - x1) < 0.5 * tol:
            # converged from one side: step just past it, so the bracket closes on the root
            x = x1 + math.copysign(0.5 * tol, x0 - x1)
        if not min(x0, x1) < x < max(x0, x1) or width > 0.5 * before_last:
            x = 0.5 * (x0 + x1)  # the secant did not shrink the bracket enough: bisect
        before_last, last = last, width
        fx = f(x)
        if (fx < 0.0) != (f1 < 0.0):
            x0, f0 = x1, f1  # the root lies between the newest two points
        else:
            m = 1.0 - fx / f1
            f0 *= m if m > 0.0 else 0.5  # x0 kept again: the Anderson–Björck scaling
        x1, f1 = x, fx
    return x1 if abs(f1) <= abs(f0) else x0


def _thd_interval(
    draws: _ThdDraws, observed: float, p: float, p_star: float, scale: float
) -> tuple[float, float, float]:
    """Neyman interval [lo, hi] for the true THD and the Monte Carlo standard error of its U.

    Acceptance region of a true THD θ: [Q(θ, α_lo(θ)), Q(θ, 1 − α_hi(θ))], Q the quantile of the
    plain estimator, α_lo + α_hi = 1 − p and ``α_lo(θ) = (1 − p)/2·min(1, P(θ)/P*)``: one-sided
    (α_lo = 0) at a true THD of 0, central from a true power P* on. The split depends on the true
    value only, never on the data, so every θ is covered with probability p (Neyman 1937); the
    interval is {θ : observed ∈ region(θ)}.
    """
    alpha = 1.0 - p

    def a_lo(theta: float) -> float:
        if not p_star > 0:
            return 0.5 * alpha
        return 0.5 * alpha * min(1.0, draws.power(theta) / p_star)

    def lower_edge(theta: float) -> float:
        return _quantile(draws.plain(theta), a_lo(theta))

    def upper_edge(theta: float) -> float:
        return _quantile(draws.plain(theta), 1.0 - (alpha - a_lo(theta)))

    def bracket(edge: Callable[[float], float]) -> float:
        b = observed + 10.0 * scale
        for _ in range(200):
            if edge(b) > observed:
                return b
            b *= 2.0
        raise ConfigError("the THD's confidence belt could not be bracketed; check A_h and u_h.")

    def root(edge: Callable[[float], float]) -> float:
        f0 = edge(0.0) - observed
        if f0 >= 0.0:
            return 0.0
        b = bracket(edge)
        return _bracketed_root(lambda th: edge(th) - observed, 0.0, f0, b, tol=1e-9 * b)

    lo = root(upper_edge)
    hi = root(lower_edge)

    def se(theta: float, edge: Callable[[float], float], q: float) -> float:
        """Standard error of an endpoint: the quantile's √(q(1−q)/M)·dQ/dq over the edge's slope."""
        if not theta > 0:
            return 0.0
        vals = draws.plain(theta)
        d = 0.25 * min(q, 1.0 - q)
        if not d > 0:
            return 0.0
        dq = (_quantile(vals, q + d) - _quantile(vals, q - d)) / (2.0 * d)
        h = 1e-2 * max(theta, scale)
        slope = (edge(theta + h) - edge(max(theta - h, 0.0))) / (theta + h - max(theta - h, 0.0))
        if not slope > 0:
            return 0.0
        return math.sqrt(q * (1.0 - q) / draws.trials) * dq / slope

    se_lo = se(lo, upper_edge, 1.0 - (alpha - a_lo(lo))) if lo > 0 else 0.0
    se_hi = se(hi, lower_edge, a_lo(hi))
    return lo, hi, 0.5 * math.hypot(se_lo, se_hi)


def _power_split(ah: np.ndarray, uh: np.ndarray) -> np.ndarray:
    """Shares w_h of the true harmonic power (Σ w_h = 1) for the Monte Carlo — a nuisance.

    A harmonic counts as detected when |Â_h|² exceeds the χ²₂ quantile of noise alone at
    0.05/(N − 1) (Bonferroni over the harmonics); it gets its excess power Â_h² − 2u_h². The
    power the others may hold (their summed excess, ≥ 0) goes to the noisiest of them: where
    the data cannot say which harmonic holds it, the split that spreads the THD most (largest
    u_h) is taken, so the belt is not made too narrow by a noise-driven split (with unequal u_h,
    as for the FOG). All of it there when nothing is detected.
    """
    n = ah.size
    q = 2.0 * math.log(n / 0.05)  # χ²₂ isf(0.05/n) = −2·ln(0.05/n)
    detected = ah**2 > q * uh**2
    w = np.where(detected, ah**2 - 2.0 * uh**2, 0.0)
    rest = ~detected
    if np.any(rest):
        rem = max(float(np.sum(ah[rest] ** 2 - 2.0 * uh[rest] ** 2)), 0.0)
        noisiest = int(np.flatnonzero(rest)[np.argmax(uh[rest])])
        w[noisiest] += rem
    total = float(w.sum())
    if not total > 0:
        w = np.zeros(n)
        w[int(np.argmax(uh))] = 1.0
        total = 1.0
    return np.asarray(w / total)


def thd_uncertainty(
    amplitudes: Any,
    amplitudes_u: Any,
    *,
    dof: float = math.inf,
    unit: str = _DEG,
    p: float = _P,
    trials: int | None = None,
    seed: int = THD_SEED,
) -> ThdUncertainty:
    """THD (eq. (1)) with its standard uncertainty, bias, bias-corrected value and the 95 %
    coverage interval for the true THD, valid down to a true THD of zero.

    Model. The fitted in-phase and quadrature components of harmonic h are N(A_h, u_h²) each
    (the multi-harmonic fit's white-noise covariance: equal variances, uncorrelated over whole
    periods), so the measured power ``T = Σ_{h≥2} |Â_h|²`` has the mean P + 2Σu_h² and a
    (generalised) noncentral χ² distribution; A_1 likewise. The plain THD ``100·√T/|Â_1|`` is
    biased upward by noise and first-order propagation is meaningless near zero (JCGM 102 §9).

    * ``bias_corrected`` removes the expected noise power (:func:`thd_bias_corrected_percent`).
    * ``u`` and ``bias``: the plain estimator simulated (M draws) at the bias-corrected THD, the
      power split over the harmonics as detected (:func:`_power_split`; the undetected part in
      the noisiest harmonic) — its standard deviation and its mean minus that THD. (Simulating at the plain value instead adds the noise a second time.)
    * ``interval``: a Neyman confidence belt of the plain THD over true values, from the same
      draws: coverage p at every true THD, up to the Monte Carlo error √(α(1−α)/M) of each tail
      and the plug-in of A_1, u_h and the power split. One-sided [0, high] when the measured
      power is consistent with noise, central well above it (see :func:`_thd_interval`). For
      equal u_h the belt is the noncentral χ² one of ``T/u²`` (2(N − 1) degrees of freedom);
      with unequal u_h (the FOG: u_h ∝ 1/h) no closed form exists, hence the simulation.
    * ``U`` = half the interval's width, ``k = U/u``; ``U_mc_error`` its Monte Carlo standard
      error.

    Parameters
    ----------
    amplitudes : array_like — A_1…A_N (unit ``unit``), h = 1 first.
    amplitudes_u : array_like — their standard uncertainties (same unit).
    dof : float — ν of the u_h (N − p of the fit; the first-order rows only).
    unit : str — unit of the amplitudes (budget text).
    p : float — coverage probability.
    trials : int, optional — Monte Carlo draws M. Default: chosen by the precision the budget
        needs (JCGM 101 §7.9): M = 10,000 first; when twice the Monte Carlo standard error of U
        exceeds the numerical tolerance of U's two significant digits, M is raised (in steps of
        10,000) to what that error predicts, at most :data:`THD_TRIALS`.
    seed : int — seed of the draws (the same capture always gives the same budget).

    Returns
    -------
    ThdUncertainty

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1); JCGM 101:2008 §7 (Monte Carlo), §7.9 (its
    numerical accuracy), §8; JCGM 102:2011 §9 (magnitude of a complex quantity near zero);
    J. Neyman (1937), Phil. Trans. R. Soc. A 236:333, §III (confidence belts); G. J. Feldman &
    R. D. Cousins (1998), Phys. Rev. D 57:3873 (intervals near a physical boundary, without
    choosing one- or two-sided from the data).
    """
    a = np.asarray(amplitudes, dtype=float)
    u = np.asarray(amplitudes_u, dtype=float)
    if a.shape != u.shape or a.ndim != 1 or a.size < 1:
        raise ConfigError("amplitudes and amplitudes_u must be 1-D arrays of the same length.")
    if not a[0] > 0 or np.any(a < 0) or np.any(u < 0) or not np.all(np.isfinite(a + u)):
        raise ConfigError("amplitudes must be finite with A_1 > 0, their u finite and ≥ 0.")
    if trials is not None and (
        isinstance(trials, bool) or not isinstance(trials, int) or trials < 1000
    ):
        raise ConfigError(f"trials must be an integer ≥ 1000, got {trials!r}.")
    adaptive = trials is None
    nh = a.size
    tail = 0.5 * (1.0 - p)
    root = math.sqrt(float(a[1:] @ a[1:]))
    plain = 100.0 * root / float(a[0])
    corrected = thd_bias_corrected_percent(a, u)
    uh = u[1:]
    noise_free = nh < 2 or not (float(uh @ uh) > 0 or u[0] > 0)
    if noise_free:
        trials = 0 if trials is None else trials
        lo = hi = plain
        u_thd, mc_mean, u_mc = 0.0, plain, 0.0
    else:
        weights = _power_split(a[1:], uh)
        p_star = 4.0 * math.sqrt(float(np.sum(uh**4)))  # 2 standard deviations of T at P = 0
        scale = max(100.0 * (math.sqrt(2.0 * float(uh @ uh)) + plain * u[0]) / float(a[0]), 1e-300)
        m = THD_FIRST_TRIALS if trials is None else trials
        while True:
            draws = _ThdDraws(a, u, weights, m, seed)
            lo, hi, u_mc = _thd_interval(draws, plain, p, p_star, scale)
            delta = numerical_tolerance(0.5 * (hi - lo), 2)
            if trials is not None or m >= THD_TRIALS or not 2.0 * u_mc > delta > 0:
                break
            # the standard error falls as 1/√M: the M that brings 2·u_mc within δ
            need = m * (2.0 * u_mc / delta) ** 2
            m = min(THD_TRIALS, _TRIALS_STEP * math.ceil(need / _TRIALS_STEP))
        trials = m
        at_corrected = draws.plain(corrected)
        mc_mean = float(np.mean(at_corrected))
        u_thd = float(np.std(at_corrected, ddof=1))
    big_u = 0.5 * (hi - lo)
    if u_thd > 0:
        k = big_u / u_thd
    else:
        from rotacal.uncertainty.quantiles import norm_isf

        k = norm_isf(tail)
    bias = mc_mean - corrected

    # first-order GUM for the rows and the comparison with the interval
    sens = np.empty(nh)
    sens[0] = -plain / a[0]
    sens[1:] = 100.0 * a[1:] / (a[0] * root) if root > 0 else 100.0 / a[0]
    ins = [
        Input(f"A_{h}", float(a[h - 1]), float(u[h - 1]), dof=dof, unit=unit)
        for h in range(1, nh + 1)
    ]

    def thd_model(*x: float) -> float:
        xa = np.asarray(x)
        return 100.0 * math.sqrt(float(xa[1:] @ xa[1:])) / float(xa[0])

    gum = propagate(thd_model, ins, jacobian=lambda *x: sens, p=p, names_out=["thd_percent"])
    u_gum = float(gum.u[0])
    side = "two-sided"
    if lo == 0:
        side = "one-sided: the measured harmonic power is consistent with noise"
    how_many = f"M = {trials}" + (
        " (chosen so that U holds 2 significant digits, §7.9)" if adaptive else ""
    )
    notes = [
        f"Monte Carlo (JCGM 101), {how_many} draws of every harmonic's in-phase and quadrature "
        "components from N(A_h, u_h²) (the fit's white-noise covariance), A_h at the "
        f"bias-corrected THD {corrected:.4g} % (noise power 2Σu_h² subtracted; split over the "
        "harmonics as detected, the undetected part on the noisiest): u is the standard deviation of the plain THD of eq. (1), "
        f"its noise bias {bias:+.3g} pp.",
        f"95 % coverage interval for the true THD [{lo:.4g}, {hi:.4g}] % ({side}): a Neyman "
        "confidence belt of the plain THD over true values from the same draws, one-sided at a "
        "true THD of 0 and central from a true harmonic power of 2 standard deviations of the "
        "noise power on (the split set by the true value, not by the data, so the coverage "
        f"holds near zero too); U is half its width, k = U/u. Monte Carlo standard error of U: "
        f"{u_mc:.2g} pp ({100.0 * u_mc / big_u if big_u > 0 else 0.0:.2g} % of U).",
    ]
    if u_gum > 0 and big_u > 0:
        delta = numerical_tolerance(u_gum, 1)
        y_gum = float(gum.U[0])
        ok = abs(plain - y_gum - lo) <= delta and abs(plain + y_gum - hi) <= delta
        notes.append(
            f"first-order GUM gives u = {u_gum:.3g} %, plain ± U = [{plain - y_gum:.4g}, "
            f"{plain + y_gum:.4g}] %, which "
            + (
                "agrees with the interval at one significant digit of u (JCGM 101 §8)."
                if ok
                else "does not agree with the interval (JCGM 101 §8): first order is not "
                "adequate here (harmonics near the noise push the THD up, as for a magnitude "
                "near zero, JCGM 102)."
            )
            + " The rows show the first-order sensitivities and shares, for orientation."
        )
    notes.append(
        "no instrument specification enters the THD: it is a ratio of amplitudes of one sensor "
        "(scale factors and the timebase cancel)."
    )
    rows = tuple(
        BudgetRow(
            source=f"A_{h} (harmonic {h} of the fit)",
            value=float(a[h - 1]),
            unit=unit,
            distribution="normal, in-phase and quadrature",
            u=float(u[h - 1]),
            sensitivity=float(sens[h - 1]),
            contribution=float(sens[h - 1] * u[h - 1]),
            share=float((sens[h - 1] * u[h - 1]) ** 2 / u_gum**2) if u_gum > 0 else 0.0,
            dof=dof,
            origin="Type A",
        )
        for h in range(1, nh + 1)
    )
    budget = UncertaintyBudget(
        quantity="thd_percent",
        unit="%",
        value=plain,
        u=u_thd,
        dof_eff=math.inf,
        k=float(k),
        p=float(p),
        U=float(big_u),
        rows=rows,
        method="Monte Carlo",
        notes=tuple(notes),
        interval=(float(lo), float(hi)),
    )
    return ThdUncertainty(
        plain=plain,
        bias_corrected=corrected,
        mc_mean=mc_mean,
        bias=bias,
        u=u_thd,
        U=float(big_u),
        k=float(k),
        interval=(float(lo), float(hi)),
        U_mc_error=float(u_mc),
        trials=int(trials),
        budget=budget,
    )
