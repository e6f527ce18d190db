"""The first-order model of a turntable: eq. (26) for any chain and the sensitivities of eq. (28).

ΔR ≈ I + Σ_k skew(S_kᵀ·e_k), S_k the product of the perfect rotations after link k: the
coefficients ∂(Δψ, Δθ, Δγ)/∂χ_i at χ = 0 and their mean magnitudes over the angles. Methods of
:class:`rotacal.turntable.geometry.Turntable` (this class is one of its bases).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2 eq. (26), §4.1 eq. (28), Figure 8.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from rotacal.turntable.chain import _V_INDEX, _check_sensitivity_grid, _Plan
from rotacal.turntable.matrices import _point_rotation, _rotation_matrix

__all__: list[str] = []


class _FirstOrder:
    """:meth:`linear_coefficients`, :meth:`point_coefficients` and :meth:`sensitivities` of a
    :class:`~rotacal.turntable.geometry.Turntable`."""

    if TYPE_CHECKING:  # provided by Turntable

        @property
        def _p(self) -> _Plan: ...

        @property
        def sensitivity_grid(self) -> tuple[float, bool]: ...

        def _angles(
            self, angles: Sequence[ArrayLike] | Mapping[str, ArrayLike]
        ) -> list[np.ndarray]: ...

        def _batch_shape(
            self,
            phis: list[np.ndarray],
            ang: list[np.ndarray | None],
            off: list[np.ndarray | None],
        ) -> tuple[int, ...]: ...

    def linear_coefficients(
        self, angles: Sequence[ArrayLike] | Mapping[str, ArrayLike]
    ) -> np.ndarray:
        """First-order coefficients ∂(Δψ, Δθ, Δγ)/∂χ_i at χ = 0: the generalised eq. (26).

        ΔR ≈ I + Σ_k skew(S_kᵀ·e_k) with S_k the product of the perfect rotations after link k, so
        an error of link k about its axis a contributes row a of S_k (the same for both models).
        For the GyroWheel study's table this is eq. (26): e.g. ∂Δψ/∂Δφy1 = cos φ2, ∂Δγ/∂Δφy1 = sin φ2.

        Parameters
        ----------
        angles : sequence or mapping of array_like
            Rotation angles (rad), broadcast together.

        Returns
        -------
        ndarray, shape (..., 3, n_angular)
            rad/rad; rows :data:`COMPONENTS`, columns :attr:`angular_error_names`.

        References
        ----------
        Seed 001, eqs. (26)–(28).
        """
        phis = self._angles(angles)
        batch = self._batch_shape(phis, [], [])  # no errors: names the angle at fault
        n = len(self._p.angular)
        out = np.zeros((*batch, 3, n))
        suffix: np.ndarray = np.eye(3)
        for plan in reversed(self._p.links):
            for i, a in plan.rotations:
                row = suffix[..., a, :]  # (..., 3): v = S_kᵀ·unit_a
                for c, vi in enumerate(_V_INDEX):
                    out[..., c, i] = row[..., vi]
            if plan.axis >= 0:
                suffix = _rotation_matrix(plan.axis, phis[plan.angle]) @ suffix
        return out

    def point_coefficients(self, angles: np.ndarray) -> np.ndarray:
        """:meth:`linear_coefficients` at one point, for a search that asks for tens of thousands.

        The same products in the same order (each rotation matrix of shape (1, 3, 3) and the
        suffix multiplied by NumPy, as there, so the same bits), without the checks of the angles
        and with the entries gathered as Python floats — NumPy's per-call cost on 3×3 arrays was
        most of a point's time.

        Parameters
        ----------
        angles : ndarray, shape (n_angles,)
            Rotation angles (rad, finite; trusted: not checked), in :attr:`angle_names` order.

        Returns
        -------
        ndarray, shape (3, n_angular)
            rad/rad; rows :data:`COMPONENTS`, columns :attr:`angular_error_names`.

        References
        ----------
        Seed 001, eqs. (26)–(28).
        """
        out = [[0.0] * len(self._p.angular) for _ in range(3)]
        suffix: np.ndarray = np.eye(3)
        for plan in reversed(self._p.links):
            if plan.rotations:
                rows = suffix.reshape(3, 3).tolist()
                for i, a in plan.rotations:
                    for c, vi in enumerate(_V_INDEX):
                        out[c][i] = rows[a][vi]
            if plan.axis >= 0:
                suffix = _point_rotation(plan.axis, angles[plan.angle : plan.angle + 1]) @ suffix
        return np.array(out)

    def sensitivities(
        self, *, step_deg: float | None = None, endpoint: bool | None = None
    ) -> np.ndarray:
        """Mean |∂(Δψ, Δθ, Δγ)/∂χ_i| at χ = 0 over the rotation angles (GyroWheel study, eq. (28)).

        The seed says only that the sensitivities "vary with the rotation angles" and that their
        average values are given (Figure 8). rotacal averages |coefficient| over a grid of every
        angle of the table: 0, step, … below 360° (``endpoint=False``, the default: the unbiased
        mean over a turn, 2/π = 0.6366 for every |sin| and |cos| term at a 1° step), or 0, step,
        …, 360° (``endpoint=True``). The paper's grid is ``step_deg=45, endpoint=True`` (9 points
        per angle, 0° and 360° both counted): for the GyroWheel study's table it gives exactly Figure 8's
        0.6476 (mean |cos φ2|) and 0.5365 (mean |sin φ2|) — the counted-twice 0°/360° points are
        where |cos| = 1 and |sin| = 0, hence the unequal pair. Without arguments the table's own
        choice is used (:attr:`sensitivity_grid`, its ``[sensitivity]`` settings).

        Figure 8 also prints 0.6481/0.5372 for some of the same terms and small values
        0.0021–0.0059 where the linear model has 0. rotacal finds these consistent with central
        finite-difference partials of the full model (eqs. (17)–(25)) at a non-zero nominal error,
        averaged over the paper's grid: at every error ≈ 3·10⁻³ rad the full model gives
        0.6483/0.5375 and insensitive pairs between 0.0018 and 0.0052 (the paper states no nominal
        error; rotacal takes the partials at χ = 0).

        Parameters
        ----------
        step_deg : float, optional
            Grid step (deg); 360/step must be an integer. Default: the table's
            (:attr:`sensitivity_grid`).
        endpoint : bool, optional
            Include 360° as well as 0°. Default: the table's.

        Returns
        -------
        ndarray, shape (3, n_angular)
            rad/rad; rows :data:`COMPONENTS`, columns :attr:`angular_error_names`.

        Raises
        ------
        ConfigError
            A step that is not > 0 or does not divide 360°; an endpoint that is not a bool.

        References
        ----------
        Seed 001, eq. (28) and Figure 8.
        """
        table_step, table_end = self.sensitivity_grid
        step, end = _check_sensitivity_grid(
            table_step if step_deg is None else step_deg,
            table_end if endpoint is None else endpoint,
        )
        count = round(360.0 / step)
        degrees = np.linspace(0.0, 360.0, count + 1) if end else np.arange(count) * (360.0 / count)
        grid = np.radians(degrees)
        n_angles = len(self._p.angle_names)
        if n_angles == 0:
            return np.abs(self.linear_coefficients([]))
        total = np.zeros((3, len(self._p.angular)))
        rest = np.meshgrid(*([grid] * (n_angles - 1)), indexing="ij") if n_angles > 1 else []
        for first in grid:  # a loop over the outermost angle's grid keeps memory flat
            coef = self.linear_coefficients([np.full(1, first), *(g.ravel() for g in rest)])
            total += np.abs(coef).sum(axis=0)
        return total / grid.size**n_angles
