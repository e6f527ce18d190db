"""The Monte Carlo's path through the model: many draws of (angles, χ) to (Δψ, Δθ, Δγ).

:meth:`Turntable.fast_orientation_error <rotacal.turntable.geometry.Turntable>` (defined here, a
method of the table through :class:`_FastPath`) evaluates ΔR = R_dᵀ·R_t (seed 001,
eqs. (17)–(24)) by the recursion D ← A_kᵀ·D·A_k·E_k of :func:`rotacal.turntable.matrices._fast_kernel`.
That kernel runs on whole arrays, one NumPy operation per entry product (about 75 for the seed
table), so every draw's numbers go through memory 75 times. The same recursion also runs in
compiled code (Numba, :mod:`rotacal.turntable._mc_jit`) over blocks of 256 draws: D is nine rows
of the block, kept in the first-level cache, each step a loop without branches over the block;
cos and sin of an angle are taken only where D is no longer the identity (as there). The Monte
Carlo's Philox stream runs in one fused compiled pass there (:func:`compiled_monte_carlo`); the
PCG64 stream's draws from its uniforms and its tallies (maxima, histograms, draws outside the
requirement) are compiled there too (:func:`compiled_draws`, :func:`compiled_tally`).

The operations are those of ``_fast_kernel`` in the same order. Where that kernel skips a
constant (a product with an exact 0 or 1, a sum with an exact 0), the compiled one does the
operation, whose result is the same number (x·1 = x, x + 0 = x, 0·x = ±0 added to y is y for
finite x); only the sign of an exact zero may differ. cos and sin are the C library's, as
NumPy's are on this platform; the tests compare the two paths draw by draw, to the last bit.

Numba compiles the kernels on first use (cached on disk). Loading Numba and the cached kernels
costs a fresh process about 0.3–0.6 s, so they are used from :data:`COMPILE_FROM_DRAWS` draws (or
once loaded); ``ROTACAL_NUMBA=1`` uses them always, ``ROTACAL_NUMBA=0`` never (and without Numba
the NumPy path is used).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, eqs. (17)–(24), Table 3.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal._jit import use_numba
from rotacal.errors import ConfigError
from rotacal.turntable.chain import _FAST_CHUNK, _LinkPlan, _Plan
from rotacal.turntable.matrices import _fast_kernel, _one_point_kernel

__all__ = [
    "COMPILE_FROM_DRAWS",
    "chain_arrays",
    "compiled_draws",
    "compiled_kernel",
    "compiled_monte_carlo",
    "compiled_tally",
    "use_compiled",
]


#: Draws from which the compiled path pays for loading Numba and the kernels in a fresh process
#: (0.3–0.6 s and ~60 MB; the NumPy path runs 1.5–5·10⁶ draws/s, the fused compiled pass
#: 2–4·10⁷ on one core, so the two meet near 2·10⁶ draws on the development machine).
COMPILE_FROM_DRAWS = 2_000_000


def use_compiled(draws: int) -> bool:
    """Whether ``draws`` draws go through the compiled kernels (the numbers are the same).

    :func:`rotacal._jit.use_numba` with :data:`COMPILE_FROM_DRAWS` as its threshold
    (``ROTACAL_NUMBA=0``: never, ``=1``: always), and for any number of draws once the kernels
    are loaded in this process.
    """
    loaded = "rotacal.turntable._mc_jit" in sys.modules
    return use_numba(draws, True if loaded else None, threshold=COMPILE_FROM_DRAWS)


def chain_arrays(links: Sequence[Any]) -> tuple[np.ndarray, ...]:
    """The chain as the integer arrays the compiled kernel reads.

    Parameters
    ----------
    links : sequence of _LinkPlan
        The table's link plans (axis index or −1, angle index or −1, (error index, axis index)
        rotations).

    Returns
    -------
    (axis, angle, rotation_start, rotation_error, rotation_axis, last)
        Per link its axis and angle index; its rotations are rows rotation_start[k] to
        rotation_start[k + 1] of (rotation_error, rotation_axis); ``last`` (a 1-element array) is
        the link after which only the three entries of eq. (24) are needed, or −1.
    """
    axis = np.array([plan.axis for plan in links], dtype=np.int64)
    angle = np.array([plan.angle for plan in links], dtype=np.int64)
    start = np.zeros(len(links) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(plan.rotations) for plan in links])
    pairs = [pair for plan in links for pair in plan.rotations]
    error = np.array([i for i, _ in pairs], dtype=np.int64)
    error_axis = np.array([a for _, a in pairs], dtype=np.int64)
    last = len(links) - 1
    while last >= 0 and not links[last].rotations:
        last -= 1
    if any(plan.axis >= 0 for plan in links[last + 1 :]):
        last = -1
    return axis, angle, start, error, error_axis, np.array([last], dtype=np.int64)


def compiled_kernel() -> Callable[..., None]:
    """The Numba kernel ``kernel(angles, chi, *chain_arrays(links), out)``, compiled on first use.

    ``angles`` (N, n_angles) rad, ``chi`` (N, n_angular) rad, ``out`` (N, 3) receives (Δψ, Δθ, Δγ)
    in rad (seed 001, eqs. (17)–(24)).
    """
    return _compiled_module().orientation_kernel


def compiled_monte_carlo() -> Callable[..., int]:
    """The Monte Carlo's fused chunk kernel ``monte_carlo_chunk`` of
    :mod:`rotacal.turntable._mc_jit` (the draws of the Philox stream, the model and the tallies in
    one pass, over the cores), compiled on first use."""
    return _compiled_module().monte_carlo_chunk


def _compiled_module() -> Any:
    """:mod:`rotacal.turntable._mc_jit`, imported (with Numba) on first use."""
    from rotacal.turntable import _mc_jit

    return _mc_jit


def compiled_draws() -> Callable[..., None]:
    """``draws(u, lower, width, random_signs, chi, angles)``: the Monte Carlo's χ and angles from
    its uniforms, as :func:`rotacal.turntable.allocation.monte_carlo_check` makes them with NumPy
    (the same operations), compiled on first use."""
    return _compiled_module().pcg64_draws


def compiled_tally() -> Callable[..., int]:
    """``tally(d, requirement, bins_per_rad, max_abs, counts) -> outside``: the Monte Carlo's
    running maxima and histograms of one chunk of (Δψ, Δθ, Δγ), as
    :func:`rotacal.turntable.allocation.monte_carlo_check` keeps them with NumPy, compiled on first
    use."""
    return _compiled_module().tally


class _FastPath:
    """:meth:`fast_orientation_error` and its variants of a
    :class:`~rotacal.turntable.geometry.Turntable`."""

    if TYPE_CHECKING:  # provided by Turntable

        @property
        def _p(self) -> _Plan: ...

        @property
        def angle_names(self) -> tuple[str, ...]: ...

        @property
        def angular_error_names(self) -> tuple[str, ...]: ...

    def fast_orientation_error(self, angles: np.ndarray, chi: np.ndarray) -> np.ndarray:
        """(Δψ, Δθ, Δγ) of many draws at once, the Monte Carlo path (seed model, eqs. (17)–(24)).

        The same recursion as :meth:`rotation_error` with ``model="seed"``, written as whole-array
        element-wise products of 3×3 matrices kept as nine arrays, in cache-sized chunks; constant
        zeros and ones of each link are skipped. Orientation only: translations cannot change it.
        Inputs are trusted (finite; checked for shape only).

        Parameters
        ----------
        angles : ndarray, shape (N, n_angles)
            Rotation angles (rad), columns :attr:`angle_names`.
        chi : ndarray, shape (N, n_angular)
            Angular errors (rad), columns :attr:`angular_error_names`.

        Returns
        -------
        ndarray, shape (N, 3)
            (Δψ, Δθ, Δγ) in rad.

        References
        ----------
        Seed 001, eqs. (17)–(24).
        """
        angles = np.asarray(angles, dtype=float)
        chi = np.asarray(chi, dtype=float)
        n_angles, n_ang = len(self._p.angle_names), len(self._p.angular)
        if angles.ndim != 2 or angles.shape[1] != n_angles:
            raise ConfigError(
                f"angles must have shape (N, {n_angles}) (columns {', '.join(self.angle_names)}), "
                f"got {angles.shape}."
            )
        if chi.ndim != 2 or chi.shape[1] != n_ang or chi.shape[0] != angles.shape[0]:
            raise ConfigError(
                f"chi must have shape ({angles.shape[0]}, {n_ang}) (columns "
                f"{', '.join(self.angular_error_names)}), got {chi.shape}."
            )
        n = angles.shape[0]
        needs_angle = self._fast_angles()
        if n == 1:
            # One point (the worst case's local search asks for thousands, one at a time): the
            # kernel written out as straight-line code (:func:`_one_point_kernel`) on Python
            # floats, without NumPy's per-operation overhead on 1-element arrays — the same IEEE
            # operations in the same order; cos and sin still by NumPy.
            trig1 = {
                k: (float(np.cos(angles[:, k])[0]), float(np.sin(angles[:, k])[0]))
                for k in needs_angle
            }
            kernel = _one_point_kernel(self._p.links, needs_angle, n_ang)
            return np.array([kernel(trig1, [float(v) for v in chi[0]])], dtype=float)
        out = np.empty((n, 3))
        if use_compiled(n):
            compiled_kernel()(
                np.ascontiguousarray(angles),
                np.ascontiguousarray(chi),
                *_chain_arrays(self._p.links),
                out,
            )
            return out
        for start in range(0, n, _FAST_CHUNK):
            stop = min(n, start + _FAST_CHUNK)
            a_t = angles[start:stop].T
            trig = {
                k: (np.cos(a_t[k]), np.sin(a_t[k])) for k in needs_angle
            }  # only angles that do not cancel
            out[start:stop] = self.fast_orientation_error_trig(trig, chi[start:stop])
        return out

    def fast_orientation_error_trig(
        self, trig: dict[int, tuple[np.ndarray, np.ndarray]], chi: np.ndarray
    ) -> np.ndarray:
        """(Δψ, Δθ, Δγ) of N draws from the cos and sin of their angles: the NumPy path of
        :meth:`fast_orientation_error` (seed model, eqs. (17)–(24)) after its cos and sin, in
        chunks of 16 384 draws.

        Parameters
        ----------
        trig : dict
            Angle index → (cos, sin), each of shape (N,), for every index of :meth:`_fast_angles`.
        chi : ndarray, shape (N, n_angular)
            Angular errors (rad), columns :attr:`angular_error_names`.

        Returns
        -------
        ndarray, shape (N, 3)
            (Δψ, Δθ, Δγ) in rad.
        """
        n = chi.shape[0]
        out = np.empty((n, 3))
        for start in range(0, n, _FAST_CHUNK):
            stop = min(n, start + _FAST_CHUNK)
            part = {k: (c[start:stop], s[start:stop]) for k, (c, s) in trig.items()}
            c_t = np.ascontiguousarray(chi[start:stop].T)
            out[start:stop, 0], out[start:stop, 1], out[start:stop, 2] = _fast_kernel(
                self._p.links, part, c_t
            )
        return out

    def fast_angle_trig(self, angles: np.ndarray) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """cos and sin of the angles :meth:`fast_orientation_error_at` needs, by angle index.

        Parameters
        ----------
        angles : ndarray, shape (N, n_angles)
            Rotation angles (rad), columns :attr:`angle_names`.

        Returns
        -------
        dict
            Angle index → (cos, sin), each of shape (N,); slices of them serve any run of rows.
        """
        angles = np.asarray(angles, dtype=float)
        return {k: (np.cos(angles[:, k]), np.sin(angles[:, k])) for k in self._fast_angles()}

    def fast_orientation_error_at(
        self, trig: dict[int, tuple[np.ndarray, np.ndarray]], chi: np.ndarray, n: int
    ) -> np.ndarray:
        """(Δψ, Δθ, Δγ) of one error vector at n angle points: :meth:`fast_orientation_error`
        for many angles and the same χ, as a search over the vertices of an error box asks.

        The same operations on the same values (each χ_i a 0-d array that broadcasts, so no entry
        is taken for a constant), hence the same numbers, without gathering a row of χ and the
        angles' cos and sin for every point again.

        Parameters
        ----------
        trig : dict
            Of the n points, from :meth:`fast_angle_trig` (or slices of its arrays).
        chi : ndarray, shape (n_angular,)
            Angular errors (rad), columns :attr:`angular_error_names`.
        n : int
            Number of angle points.

        Returns
        -------
        ndarray, shape (n, 3)
            (Δψ, Δθ, Δγ) in rad.

        References
        ----------
        Seed 001, eqs. (17)–(24).
        """
        entries = [np.asarray(float(v)) for v in np.asarray(chi, dtype=float)]
        out = np.empty((n, 3))
        out[:, 0], out[:, 1], out[:, 2] = _fast_kernel(self._p.links, trig, entries)  # type: ignore[arg-type]
        return out

    def _fast_angles(self) -> tuple[int, ...]:
        """Angles whose rotation conjugates a non-identity D (the others cancel exactly)."""
        needed = []
        seen_error = False
        for plan in self._p.links:
            if plan.axis >= 0 and seen_error:
                needed.append(plan.angle)
            if plan.rotations:
                seen_error = True
        return tuple(needed)


@functools.lru_cache(maxsize=32)
def _chain_arrays(links: tuple[_LinkPlan, ...]) -> tuple[np.ndarray, ...]:
    """:func:`rotacal.turntable.fast.chain_arrays` of a chain, made once per chain."""
    return chain_arrays(links)
