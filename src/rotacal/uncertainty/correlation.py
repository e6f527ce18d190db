"""Correlation matrices of input quantities (GUM §5.2.2): checked, from a matrix or from pairs.

References
----------
JCGM 100:2008 (GUM) §5.2.2, eqs. (13)–(14) (correlation coefficients r(x_i, x_j)).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import ConfigError

if TYPE_CHECKING:
    pass

from rotacal.uncertainty._checked import _number

__all__ = ["PSD_TOLERANCE", "correlation_matrix"]

#: Smallest eigenvalue a correlation matrix may have (round-off of a valid PSD matrix).
PSD_TOLERANCE = 1e-12
#: Tolerance of the checks for symmetry, unit diagonal and |r| ≤ 1.
_R_TOLERANCE = 1e-12


def correlation_matrix(r: Any, n: int, *, names: Sequence[str] | None = None) -> np.ndarray:
    """A validated n×n correlation matrix of the inputs.

    Parameters
    ----------
    r : None, array_like (n, n) or mapping
        ``None`` → uncorrelated (identity). An n×n matrix of correlation coefficients r(x_i, x_k)
        (dimensionless). Or a mapping ``{(a, b): r_ab}`` whose keys are pairs of input names (with
        ``names``) or of indices; unnamed pairs are uncorrelated.
    n : int
        Number of inputs.
    names : sequence of str, optional
        Names of the inputs, for the keys of a mapping and for the error messages.

    Returns
    -------
    numpy.ndarray
        (n, n) float64, symmetric, unit diagonal, |r| ≤ 1, positive semi-definite (smallest
        eigenvalue ≥ −1e-12). A new array.

    Raises
    ------
    ConfigError
        One line naming the offending entry: wrong shape, non-finite, not symmetric, diagonal ≠ 1,
        |r| > 1, or not positive semi-definite.

    References
    ----------
    JCGM 100:2008 (GUM), §5.2.2 (r(x_i, x_j) = u(x_i, x_j)/(u(x_i)·u(x_j)), |r| ≤ 1),
    C.3.6 (correlation coefficient); JCGM 101:2008 §6.4.8 (the covariance matrix is positive
    semi-definite).
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ConfigError(f"the number of inputs must be an integer ≥ 1; got {n!r}.")
    n = int(n)
    labels = [str(s) for s in names] if names is not None else [str(i) for i in range(n)]
    if len(labels) != n:
        raise ConfigError(f"{len(labels)} names were given for {n} inputs; give one per input.")
    if r is None:
        return np.eye(n)
    if isinstance(r, Mapping):
        mat = _from_pairs(r, n, labels)
    else:
        try:
            mat = np.array(r, dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(
                "the correlation matrix is not numeric; give an n×n array of numbers."
            ) from None
        if mat.shape != (n, n):
            raise ConfigError(
                f"the correlation matrix has shape {mat.shape}; give an {n}×{n} matrix "
                f"(one row and column per input: {', '.join(labels)})."
            )
    if not np.all(np.isfinite(mat)):
        i, j = np.argwhere(~np.isfinite(mat))[0]
        raise ConfigError(
            f"correlation r[{labels[i]}, {labels[j]}] = {mat[i, j]!r} is not finite; give a number "
            "in [−1, 1]."
        )
    diag_err = np.abs(np.diag(mat) - 1.0)
    if np.any(diag_err > _R_TOLERANCE):
        i = int(np.argmax(diag_err))
        raise ConfigError(
            f"correlation r[{labels[i]}, {labels[i]}] = {mat[i, i]:g}; the diagonal of a "
            "correlation matrix must be 1."
        )
    asym = np.abs(mat - mat.T)
    if np.any(asym > _R_TOLERANCE):
        i, j = np.unravel_index(int(np.argmax(asym)), asym.shape)
        raise ConfigError(
            f"the correlation matrix is not symmetric: r[{labels[i]}, {labels[j]}] = "
            f"{mat[i, j]:g} but r[{labels[j]}, {labels[i]}] = {mat[j, i]:g}; give the same value."
        )
    excess = np.abs(mat) - 1.0
    if np.any(excess > _R_TOLERANCE):
        i, j = np.unravel_index(int(np.argmax(excess)), excess.shape)
        raise ConfigError(
            f"correlation r[{labels[i]}, {labels[j]}] = {mat[i, j]:g} is outside [−1, 1]."
        )
    mat = 0.5 * (mat + mat.T)
    np.fill_diagonal(mat, 1.0)
    lam_min = float(np.linalg.eigvalsh(mat)[0]) if n > 1 else 1.0
    if lam_min < -PSD_TOLERANCE:
        raise ConfigError(
            f"the correlation matrix of {', '.join(labels)} is not positive semi-definite "
            f"(smallest eigenvalue {lam_min:.3g}); the correlations contradict each other — "
            "derive them from one covariance estimate."
        )
    return mat


def _from_pairs(r: Mapping[Any, Any], n: int, labels: list[str]) -> np.ndarray:
    index = {name: i for i, name in enumerate(labels)}
    mat = np.eye(n)
    given = np.eye(n, dtype=bool)

    def position(key: Any) -> int:
        if isinstance(key, str):
            if key not in index:
                raise ConfigError(
                    f"correlation names unknown input '{key}'; the inputs are {', '.join(labels)}."
                )
            return index[key]
        if isinstance(key, (int, np.integer)) and not isinstance(key, bool) and 0 <= key < n:
            return int(key)
        raise ConfigError(
            f"correlation key {key!r} is neither an input name nor an index 0…{n - 1}."
        )

    for key, val in r.items():
        if not (isinstance(key, tuple) and len(key) == 2):
            raise ConfigError(
                f"correlation key {key!r} must be a pair (a, b) of input names; e.g. "
                "{('V', 'I'): -0.36}."
            )
        a, b = position(key[0]), position(key[1])
        v = _number(val, f"correlation r[{labels[a]}, {labels[b]}]")
        if a == b:
            if v != 1.0:
                raise ConfigError(
                    f"correlation r[{labels[a]}, {labels[a]}] = {v:g}; the correlation of an "
                    "input with itself is 1."
                )
            continue
        if given[a, b] and mat[a, b] != v:
            raise ConfigError(
                f"correlation r[{labels[a]}, {labels[b]}] is given twice ({mat[a, b]:g} and {v:g}); "
                "give it once."
            )
        mat[a, b] = mat[b, a] = v
        given[a, b] = given[b, a] = True
    return mat
