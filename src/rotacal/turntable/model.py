"""Geometric error model of a multi-axis turntable by homogeneous transforms (GyroWheel study, §3).

A turntable is a chain of links from the base (frame F0) to the instrument (the last frame). A
link is either a **rotary axis** — turning by its angle φ about its own x, y or z — or a **fixed
link** that carries the orthogonality (squareness) and intersection (offset) errors between two
axes. Each link also carries small error rotations, listed in order, and error translations. The
two-axis table of the GyroWheel study (Tables 2–3) is the chain::

    0T1 = Ry(φ1) · E(Δαx1, Δφy1, Δαz1)          outer axis about y: position error Δφy1, wobbles
    1T2 = E(Δεx, Δεy, 0) · Trans(Δη, 0, 0)      orthogonality Δεx, Δεy and intersection Δη
    2T3 = Rz(φ2) · E(Δαx2, Δαy2, Δφz2)          inner axis about z: position error Δφz2, wobbles
    3T4 = I                                     the gyro sits on the inner frame

with the active rotations Ry, Rz printed in eqs. (17), (19) and the small-angle error matrix
E(ex, ey, ez) = [[1, −ez, ey], [ez, 1, −ex], [−ey, ex, 1]] = I + skew(e). The actual transform is
T_t = Π iT(i+1) (eq. (22)), the ideal one T_d the product of the perfect rotations (eq. (21)); the
orientation error is ΔR = R_dᵀ·R_t (eq. (23)) and its components (eq. (24)), always in the order
:data:`COMPONENTS`:

    Δψ = ΔR[0, 2]  (about the instrument's y),  Δθ = ΔR[1, 0]  (about z),  Δγ = ΔR[2, 1]  (about x),

so that ΔR ≈ I + skew(v) with v = (Δγ, Δψ, Δθ).

Two models of a link's error rotations:

- ``model="seed"`` (default): one small-angle matrix E per link, with every error of the link
  summed about its axis, multiplied exactly as printed in eqs. (17)–(19) (E is not orthogonal);
- ``model="exact"``: each error is a proper rotation (``scipy.spatial.transform.Rotation``),
  applied in the order the link lists them — Table 3's order for the GyroWheel study's table (e.g. φ1 about y, then
  Δφy1 about y, Δαz1 about z, Δαx1 about x). It equals the GyroWheel study's model to first order.

Translations are applied after the link's rotations (eq. (18): E·Trans; Table 3's wording puts the
translation first — the difference is an origin shift of order Δη·Δε and none in orientation).
Translations never change the orientation: "the intersection error has no effect on the
orientation error" (GyroWheel study, after eq. (25)).

ΔR is computed by the recursion D ← A_kᵀ·D·A_k·E_k over the links (A_k the link's perfect
rotation, E_k its error matrix), which equals R_dᵀR_t because A_kᵀA_k = I. It starts from D = I
and skips the conjugation while D is still exactly the identity, so the outer axis of the GyroWheel study's table
table, R_y(φ1), cancels exactly (to the last bit), as it does in eq. (26). The first-order
expansion, ΔR ≈ I + Σ_k skew(S_kᵀ e_k) with S_k the product of the perfect rotations after link k,
gives the generalised eq. (26) (:meth:`Turntable.linear_coefficients`) and the sensitivities of
eq. (28) (:meth:`Turntable.sensitivities`).

Names: the GyroWheel study's error vector χ (eq. (25)) is ``phi_y1, phi_z2, alpha_x1, alpha_z1, alpha_x2,
alpha_y2, eps_x, eps_y`` plus the translation ``eta``. Every error may also be named by its
ISO 230-1 / ISO 230-7 symbol: the one stated in the table (``iso``) or, when unambiguous, a
generated one — a rotary axis about x/y/z has letter A/B/C; its position error is E{L}{L} (EBB),
its wobble about another axis M is E{M}{L} (EAB, ECB), its offsets E{X|Y|Z}{L}; a fixed link's
rotation about M before the axis with letter L is E{M}0{L} (EA0C, EB0C), its translation E{X}0{L}
(EX0C). Aliases are matched case-insensitively; canonical names exactly.

Units: radians for every angle and angular error, metres for translations (the TOML loader,
:mod:`rotacal.turntable.config`, converts from the file's units).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``): GyroWheel calibration tests — error
analysis and turntable error allocation, §3.2, eqs. (17)–(27), Tables 2–3; §4.1, eq. (28), Figure 8.
ISO 230-1:2012 and ISO 230-7:2015 (symbols of the geometric errors of axes of rotation).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from rotacal.turntable.chain import (
    ANGLE_UNITS,
    ARCMIN_PER_RAD,
    AXES,
    COMPONENTS,
    KINDS,
    LENGTH_UNITS,
    SEED_ERROR_NAMES,
    SMALL_ANGLE_LIMIT_RAD,
    ErrorSpec,
    Link,
    generated_aliases,
)
from rotacal.turntable.config import load_turntable, seed_table
from rotacal.turntable.geometry import Turntable

__all__ = [
    "ANGLE_UNITS",
    "ARCMIN_PER_RAD",
    "AXES",
    "COMPONENTS",
    "KINDS",
    "LENGTH_UNITS",
    "SEED_ERROR_NAMES",
    "SMALL_ANGLE_LIMIT_RAD",
    "ErrorSpec",
    "Link",
    "Turntable",
    "generated_aliases",
    "load_turntable",
    "orientation_error",
    "seed_table",
]


# ------------------------------------------------------------------------------ module level
@functools.lru_cache(maxsize=1)
def _seed_cached() -> Turntable:
    return seed_table()


def orientation_error(
    phi1: ArrayLike, phi2: ArrayLike, errors: Mapping[str, ArrayLike]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orientation error (Δψ, Δθ, Δγ) of the GyroWheel study's two-axis table (eqs. (17)–(24)).

    Parameters
    ----------
    phi1, phi2 : array_like
        Outer (about y) and inner (about z) rotation angles (rad); broadcast.
    errors : mapping
        ``phi_y1, phi_z2, alpha_x1, alpha_z1, alpha_x2, alpha_y2, eps_x, eps_y`` (rad) and ``eta``
        (m) — or their ISO symbols — to values; missing names are zero; arrays broadcast with the
        angles (e.g. values of shape (k, 1) and angles of shape (m,) give (k, m)).

    Returns
    -------
    dpsi, dtheta, dgamma : ndarray
        rad, each of the broadcast shape.

    Raises
    ------
    ConfigError
        An unknown name, a value that is not a finite number, an angular error beyond 0.1 rad
        (radians are expected), shapes that do not broadcast: one line naming the error or angle.

    References
    ----------
    Seed 001, eqs. (17)–(24), Tables 2–3.
    """
    out = _seed_cached().orientation_error([phi1, phi2], errors)
    return out[..., 0], out[..., 1], out[..., 2]
