"""Multi-harmonic least squares from exponential sums (private).

Every quantity of the Gauss–Newton normal equations of the multi-harmonic model is a linear
combination of the sums

    S_p(k) = Σ_i τ_i^p · exp(j·k·ω·τ_i),     p = 0, 1, 2;  k = 0..2H
    Y_p(k) = Σ_i y_i · τ_i^p · exp(j·k·ω·τ_i), p = 0, 1;     k = 0..H

(τ = t − t_ref, ω = 2πf). A column of the Jacobian is written ``Re(τ^p Σ_m c_m e^{jmωτ})``:
the constant (c_0 = 1), cos(hωτ) (c_h = 1), sin(hωτ) (c_h = −j) and ∂model/∂f
(p = 1, c_h = 2πh·(b_h + j·a_h)). With ``Re z·Re w = ½ Re(z·w + z·w̄)`` the inner product of
two columns is ``½ Re(cᵢᵀ·Hankel(S_p)·cⱼ + cᵢᵀ·Toeplitz(S_p)·c̄ⱼ)``. So a sums provider (block
moments or explicit samples) is all the solver needs; its cost does not depend on N.

The frequency is refined by variable projection: at each f the linear parameters are solved
exactly, then one Gauss–Newton step on the full Jacobian ``[Φ, ∂model/∂f]`` updates f (Golub &
Pereyra 1973; Kaufman 1975), with step halving if the residual grows. Its fixed point is the
least-squares minimiser of IEEE Std 1057-2017 §4.1.3 (four-parameter / multi-harmonic fit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from rotacal.errors import CaptureError


class SumsFn(Protocol):
    """``sums(ω, with_derivative, y_derivative=True) → (S, Y)``: S of (3 with the derivative,
    else 1) × (2H+1) complex sums, Y of (2 with both, else 1) × (H+1): the y-sums with τ only
    for a next step's right-hand side, which a step that ends the refinement does not take."""

    def __call__(
        self, omega: float, deriv: bool, y_deriv: bool = True, /
    ) -> tuple[np.ndarray, np.ndarray]: ...


MAX_COND = 1e12
_EPS = float(np.finfo(np.float64).eps)


@dataclass
class NormalFit:
    """Solution of the normal equations at the final frequency."""

    frequency_hz: float
    params: np.ndarray  # [C', a_1..a_H, b_1..b_H(, D)] (C' relative to the centring constant)
    rss: float
    iterations: int
    cov_unit: np.ndarray  # (JᵀJ)⁻¹, parameter order [C', a, b(, D)(, f)]
    # drift_check: the linear refit [C', a, b, D] at the final frequency, its RSS and (ΦᵀΦ)⁻¹
    check: tuple[np.ndarray, float, np.ndarray] | None = None


#: The refinement ends when the step of f falls below this fraction of f's standard uncertainty
#: (or below ``rtol``·f): nothing the fit reports moves by more than 1e-4 of its u then, and the steps that rounding makes
#: (~1e-16·f) lie orders of magnitude below it, so twins of the sums that add in another order
#: take the same steps (a tolerance near rounding would let rounding decide one more step).
STEP_OF_U = 1e-4


def _frequency_u(inv: np.ndarray, rss: float, n: int) -> float:
    """Standard uncertainty of f (Hz) from (JᵀJ)⁻¹ (f last) and the residual: s²·(JᵀJ)⁻¹_ff."""
    dof = n - inv.shape[0]
    var = inv[-1, -1] * max(rss, 0.0) / dof if dof > 0 else 0.0
    return math.sqrt(var) if math.isfinite(var) and var > 0 else 0.0


#: Accepted steps in a row that lower the residual by no more than rounding, after which a
#: refinement that has not met its step tolerance is taken to sit at the minimum.
STALL_STEPS = 3


class StallWatch:
    """Tells a refinement stuck at the minimum within rounding from one that is still moving.

    Gauss–Newton ignores the residual's curvature, so with a large residual (a record holding
    something the model cannot fit, such as a drift fitted without its term) it can overshoot
    and circle the minimum of the residual, its steps never falling below the step tolerance.
    Every step it then takes is accepted only because the residual stays within rounding of
    the lowest: the frequency is at the minimum as well as float64 can tell. A step counts as
    such when it changes the residual by at most 16·``rss_tol`` either way (the residual from the
    normal equations, ``yᵀy − bᵀp``, carries more rounding than the step test's ``rss_tol``).
    Used only where the refinement would otherwise have failed (its results elsewhere unchanged).
    """

    def __init__(self, rss_tol: float) -> None:
        self._tol = 16.0 * rss_tol
        self._flat = 0

    def step(self, rss_before: float, rss_after: float) -> None:
        """Record an accepted step."""
        self._flat = self._flat + 1 if abs(rss_before - rss_after) <= self._tol else 0

    @property
    def at_minimum(self) -> bool:
        """The last STALL_STEPS accepted steps all stayed within rounding of the residual."""
        return self._flat >= STALL_STEPS


def solve_spd(a: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Solve a symmetric positive (semi)definite system with Jacobi scaling and ``eigh``.

    Returns the solution, the inverse matrix and the condition number of the scaled matrix.
    """
    d = np.sqrt(np.diag(a).copy())
    if not np.all(np.isfinite(d)) or np.any(d <= 0):
        return np.full(rhs.shape, np.nan), np.full(a.shape, np.nan), math.inf
    scaled = a / np.outer(d, d)
    w, v = np.linalg.eigh(scaled)
    if not np.all(np.isfinite(w)) or w[0] <= 0:
        return np.full(rhs.shape, np.nan), np.full(a.shape, np.nan), math.inf
    cond = float(w[-1] / w[0])
    inv_scaled = (v / w) @ v.T
    inv = inv_scaled / np.outer(d, d)
    x = inv_scaled @ (rhs / d) / d
    return x, inv, cond


def _hankel_toeplitz(s: np.ndarray, nh: int) -> tuple[np.ndarray, np.ndarray]:
    m = np.arange(nh + 1)
    hank = s[m[:, None] + m[None, :]]
    k = m[:, None] - m[None, :]
    toep = np.where(k >= 0, s[np.abs(k)], np.conj(s[np.abs(k)]))
    return hank, toep


def _column_coefs(nh: int) -> np.ndarray:
    c = np.zeros((2 * nh + 1, nh + 1), dtype=np.complex128)
    c[0, 0] = 1.0
    idx = np.arange(1, nh + 1)
    c[idx, idx] = 1.0
    c[nh + idx, idx] = -1j
    return c


def _inner(ci: np.ndarray, cj: np.ndarray, hank: np.ndarray, toep: np.ndarray) -> np.ndarray:
    return 0.5 * np.real(ci @ hank @ cj.T + ci @ toep @ np.conj(cj).T)


@dataclass
class _Linear:
    f: float
    p: np.ndarray
    rss: float
    gram: np.ndarray
    s: np.ndarray
    y: np.ndarray


def solve_normal(
    sums: SumsFn,
    yy: float,
    n: int,
    f0: float,
    nh: int,
    *,
    refine: bool,
    max_iter: int,
    rtol: float,
    drift: bool = False,
    drift_check: bool = False,
) -> NormalFit:
    """Fit ``C + Σ a_h cos + b_h sin`` (and f when ``refine``) from exponential sums.

    With ``drift`` the model has the column τ = t − t_ref as well (parameter D after the b_h):
    its products with the other columns come from the sums with p = 1 and 2, which the frequency
    derivative uses too (``Re(τ·e^{j·0})``: coefficients c_0 = 1 at p = 1). With ``drift_check``
    (a fit without drift) the same system with τ is solved once more at the final frequency.
    """
    cmat = _column_coefs(nh)
    e0 = np.zeros((1, nh + 1), dtype=np.complex128)
    e0[0, 0] = 1.0
    n_lin = 2 * nh + 1 + (1 if drift else 0)

    def with_drift_column(
        gram: np.ndarray, rhs: np.ndarray, s: np.ndarray, y: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The normal equations with the column τ appended (needs the sums with p = 1, 2)."""
        hank1, toep1 = _hankel_toeplitz(s[1], nh)
        g_pt = _inner(cmat, e0, hank1, toep1)[:, 0]
        m = gram.shape[0]
        out = np.empty((m + 1, m + 1))
        out[:m, :m] = gram
        out[:m, m] = g_pt
        out[m, :m] = g_pt
        out[m, m] = float(np.real(s[2][0]))
        return out, np.append(rhs, float(np.real(y[1][0])))

    def linear(f: float, last: bool = False) -> _Linear:
        # the y-sums with τ serve the drift column and a next step; a last step needs neither
        y_deriv = drift or drift_check or not last
        s, y = sums(2.0 * math.pi * f, refine or drift, y_deriv)
        hank, toep = _hankel_toeplitz(s[0], nh)
        gram = _inner(cmat, cmat, hank, toep)
        rhs = np.real(cmat @ y[0])
        if drift:
            gram, rhs = with_drift_column(gram, rhs, s, y)
        p, _, cond = solve_spd(gram, rhs)
        if not cond < MAX_COND:
            raise CaptureError(
                f"the {n_lin}-parameter sine fit at {f:.6g} Hz is ill-conditioned "
                f"(condition number {cond:.3g}); supply a longer record (≥ ~1.5 periods) or "
                "fewer harmonics."
            )
        rss = yy - float(rhs @ p)
        return _Linear(f, p, rss, gram, s, y)

    def full_system(lin: _Linear) -> tuple[np.ndarray, np.ndarray | None]:
        """JᵀJ and Jᵀr (None without the y-sums with τ: JᵀJ alone, for the covariance)."""
        a = lin.p[1 : nh + 1]
        b = lin.p[nh + 1 : 2 * nh + 1]
        cd = np.zeros(nh + 1, dtype=np.complex128)
        h = np.arange(1, nh + 1)
        cd[1:] = 2.0 * math.pi * h * (b + 1j * a)
        hank1, toep1 = _hankel_toeplitz(lin.s[1], nh)
        hank2, toep2 = _hankel_toeplitz(lin.s[2], nh)
        g_pd = _inner(cmat, cd[None, :], hank1, toep1)[:, 0]
        g_dd = float(_inner(cd[None, :], cd[None, :], hank2, toep2)[0, 0])
        phi_y = np.real(cmat @ lin.y[0])
        if drift:  # the drift column τ (p = 1) against ∂model/∂f (p = 1): sums with p = 2
            g_pd = np.append(g_pd, float(_inner(e0, cd[None, :], hank2, toep2)[0, 0]))
            phi_y = np.append(phi_y, float(np.real(lin.y[1][0])))
        m = lin.gram.shape[0]
        jtj = np.empty((m + 1, m + 1))
        jtj[:-1, :-1] = lin.gram
        jtj[:-1, -1] = g_pd
        jtj[-1, :-1] = g_pd
        jtj[-1, -1] = g_dd
        if lin.y.shape[0] < 2:
            return jtj, None
        dty = float(np.real(cd @ lin.y[1]))
        phi_r = phi_y - lin.gram @ lin.p
        jtr = np.append(phi_r, dty - float(g_pd @ lin.p))
        return jtj, jtr

    lin = linear(f0)
    iterations = 0
    if refine:
        rss_tol = 64.0 * _EPS * max(yy, 0.0) + 1e-300
        stall = StallWatch(rss_tol)
        converged = False
        for _ in range(max_iter):
            iterations += 1
            jtj, jtr = full_system(lin)
            assert jtr is not None  # lin came from a step that did not end the refinement
            step, inv, cond = solve_spd(jtj, jtr)
            df = float(step[-1])
            tol = max(rtol * abs(lin.f), STEP_OF_U * _frequency_u(inv, lin.rss, n))
            if not (math.isfinite(df) and cond < MAX_COND):
                raise CaptureError(
                    f"the frequency refinement at {lin.f:.6g} Hz is ill-conditioned; supply a "
                    "longer record (more periods of the motion)."
                )
            lam = 1.0
            new = None
            for _half in range(40):
                f_try = lin.f + lam * df
                if f_try > 0:
                    # a step this small ends the refinement once taken
                    cand = linear(f_try, last=abs(lam * df) <= tol)
                    if cand.rss <= lin.rss + rss_tol:
                        new = cand
                        break
                lam *= 0.5
            if new is None:  # no step lowers the residual: at the minimum within rounding
                converged = True
                break
            stall.step(lin.rss, new.rss)
            lin = new
            if abs(lam * df) <= tol:
                converged = True
                break
        if not converged and not stall.at_minimum:
            raise CaptureError(
                f"the frequency refinement did not converge in {max_iter} iterations (last "
                f"f = {lin.f:.9g} Hz); check that the record holds one dominant sine, or raise "
                "max_iter."
            )
        jtj, _ = full_system(lin)
        _, cov_unit, _ = solve_spd(jtj, np.zeros(jtj.shape[0]))
    else:
        _, cov_unit, _ = solve_spd(lin.gram, np.zeros(lin.gram.shape[0]))
    check = None
    if drift_check and not drift:
        s_d, y_d = (lin.s, lin.y) if refine else sums(2.0 * math.pi * lin.f, True)
        gram_d, rhs_d = with_drift_column(lin.gram, np.real(cmat @ y_d[0]), s_d, y_d)
        p_d, inv_d, _ = solve_spd(gram_d, rhs_d)
        check = (p_d, yy - float(rhs_d @ p_d), inv_d)
    return NormalFit(lin.f, lin.p, lin.rss, iterations, cov_unit, check)
