"""What an identification leaves open: which measurement separates the rest, which positions to
measure next, and whether the identified errors keep the allocation's bounds.

- :func:`advice` — for each group of errors the positions cannot separate, whether any position of
  this chain would (a *design* gap: measure at the recommended positions) or none would (a
  *structural* gap of orientation-only data: errors of links with no rotary axis between them
  that turns them apart, such as the GyroWheel study's Δφy1 and Δεy, or Δφz2 and Δαz1 about the
  common z axis; translations such as η, which do not turn the instrument at all, after eq. (25)).
  A structural gap is closed by a measurement of something other than the instrument's
  orientation: the orientation of the frame between the links (a mirror on it and an
  autocollimator), or the position of the instrument for a translation.
- :func:`recommend` — greedy D-optimal design (Fedorov 1972; Atkinson, Donev & Tobias 2007,
  §9, §12): from a (φ1, φ2) grid, add one at a time the position that most increases
  log det(Bᵀ·JᵀJ·B + ρI), J the first-order Jacobian (eq. (26)) of the positions measured so far
  and B an orthonormal basis of what orientation data can separate at all (the row space over the
  whole grid). The small ridge ρ (10⁻⁶ of one position's mean information) lets a singular design
  be ranked: positions that add a separable direction win first.
- :func:`compare_with_bounds` — each separable combination c = Σ aᵢχᵢ against the bound
  Σ|aᵢ|·UBᵢ that the allocation implies for it (if every |χᵢ| ≤ UBᵢ, |c| ≤ Σ|aᵢ|UBᵢ; and the
  orientation error depends on the errors only through these combinations, so Lemma 1's argument,
  eqs. (35)–(38), holds whenever each combination keeps its bound), decided by guarded acceptance
  (ILAC-G8:09/2019 §4.2.2): inside when |c| + U ≤ bound, outside when |c| − U > bound, undecided
  otherwise.

References
----------
Seed 001, eqs. (25)–(26), (34)–(38). Fedorov, V. V., *Theory of Optimal Experiments*, Academic
Press 1972. Atkinson, A. C., Donev, A. N., Tobias, R. D., *Optimum Experimental Designs, with
SAS*, Oxford 2007. ILAC-G8:09/2019 §4.2.2.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.turntable.geometry import Turntable

__all__ = [
    "advice",
    "candidate_grid",
    "compare_with_bounds",
    "first_order_rows",
    "groups_of",
    "recommend",
    "right_singular",
]

_TINY = 1e-9

CRITERION = (
    "greedy D-optimal: each next position maximises log det(Bᵀ·JᵀJ·B + ρI) of the first-order "
    "Jacobian (eq. (26)) over the separable directions B, ρ = 10⁻⁶ of one position's mean "
    "information; ties go to the first grid point"
)


def candidate_grid(step_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """The (φ1, φ2) grid (rad), both axes every ``step_deg`` from 0 (deg, dividing 360)."""
    try:
        step = float(step_deg)
    except (TypeError, ValueError):
        raise ConfigError(f"design step must be a number of degrees, got {step_deg!r}.") from None
    count = 360.0 / step if step > 0 else 0.0
    if not (np.isfinite(count) and 2 <= count <= 360 and abs(count - round(count)) < 1e-9):
        raise ConfigError(
            f"design step {step_deg!r}° must divide 360° into 2 to 360 steps (e.g. 15 or 30)."
        )
    a = np.radians(np.arange(round(count)) * step)
    p1, p2 = np.meshgrid(a, a, indexing="ij")
    return p1.reshape(-1), p2.reshape(-1)


def first_order_rows(table: Turntable, phi1: np.ndarray, phi2: np.ndarray) -> np.ndarray:
    """The first-order Jacobian at χ = 0 (3n, p), rows position-major (ψ, θ, γ per position): the
    generalised eq. (26) (:meth:`Turntable.linear_coefficients`), exact sines and cosines."""
    coefficients = table.linear_coefficients([phi1, phi2])  # (n, 3, p)
    return coefficients.reshape(-1, coefficients.shape[-1])


def right_singular(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Singular values and all p right singular vectors (rows of a (p, p) Vᵀ) of an (m, p)
    matrix, without the (m, m) U of a full SVD when m ≫ p."""
    _, s, vt = np.linalg.svd(m, full_matrices=m.shape[0] < m.shape[1])
    return s, vt


def groups_of(null: np.ndarray) -> list[list[int]]:
    """Indices of parameters connected through the null space (its projector's nonzeros)."""
    proj = null @ null.T
    p = proj.shape[0]
    involved = [i for i in range(p) if proj[i, i] > _TINY]
    seen: set[int] = set()
    groups = []
    for i in involved:
        if i in seen:
            continue
        stack, group = [i], []
        seen.add(i)
        while stack:
            j = stack.pop()
            group.append(j)
            for m in involved:
                if m not in seen and abs(proj[j, m]) > _TINY:
                    seen.add(m)
                    stack.append(m)
        groups.append(sorted(group))
    return groups


def _link_of(table: Turntable) -> dict[str, tuple[int, str]]:
    """Error name → (link index, "rotation" | "translation")."""
    out = {}
    for k, link in enumerate(table.links):
        for name, _ in link.rotations:
            out[name] = (k, "rotation")
        for name, _ in link.translations:
            out[name] = (k, "translation")
    return out


def _link_text(table: Turntable, k: int) -> str:
    link = table.links[k]
    if link.axis is None:
        return f"the fixed link {k} (between the axes)"
    return f"the moving part of the {link.axis} axis ({link.angle})"


def _structural_text(table: Turntable, names: Sequence[str]) -> str:
    where = _link_of(table)
    moved = [n for n in names if where[n][1] == "translation"]
    if moved:
        return (
            f"{', '.join(moved)}: a translation does not turn the instrument (GyroWheel study, "
            "after eq. (25)); measure the instrument's position (a displacement sensor or a laser "
            "tracker on a target on the inner frame) at several outer-axis angles."
        )
    links = sorted({where[n][0] for n in names})
    first = [n for n in names if where[n][0] == links[0]]
    rest = [n for n in names if where[n][0] != links[0]]
    return (
        f"{' + '.join(names)}: orientation at the instrument sees only their sum, whatever the "
        f"angles; measure the orientation of {_link_text(table, links[0])} alone (a mirror on it "
        f"read by an autocollimator, the other axes locked, or the axis's own reference encoder "
        f"for a position error) — it sees {', '.join(first)} without {', '.join(rest)}."
    )


def advice(
    table: Turntable, groups: Sequence[Sequence[str]], step_deg: float
) -> list[dict[str, Any]]:
    """For each inseparable group: ``names``, ``structural`` and ``separate_by`` (list of text).

    A group is *structural* when no position of the (φ1, φ2) grid of ``step_deg`` separates any
    of it (its null directions stay null over the whole grid); otherwise more positions separate
    part of it and the structural groups inside it (if any) need another kind of measurement.
    """
    names = table.angular_error_names
    p1, p2 = candidate_grid(step_deg)
    grid = first_order_rows(table, p1, p2)
    sv, vt = right_singular(grid)
    rank = int(np.sum(sv > 1e-9 * sv[0]))
    structural_groups = [[names[i] for i in g] for g in groups_of(vt[rank:].T)]
    out: list[dict[str, Any]] = []
    for group in groups:
        inside = [g for g in structural_groups if set(g) <= set(group)]
        covered = {n for g in inside for n in g}
        texts = []
        structural = covered == set(group)
        if not structural:
            texts.append(
                "positions at further angles separate "
                f"{', '.join(n for n in group if n not in covered) or 'part of it'} from the "
                "rest of this group: measure at next_positions_deg (D-optimal over the grid)."
            )
        texts += [_structural_text(table, g) for g in inside]
        out.append({"names": list(group), "structural": structural, "separate_by": texts})
    for name in table.offset_names:
        out.append(
            {"names": [name], "structural": True, "separate_by": [_structural_text(table, [name])]}
        )
    return out


def _logdet(m: np.ndarray) -> float | None:
    sign, value = np.linalg.slogdet(m)
    return float(value) if sign > 0 and np.linalg.matrix_rank(m) == m.shape[0] else None


def recommend(
    table: Turntable,
    phi1: np.ndarray,
    phi2: np.ndarray,
    count: int,
    step_deg: float,
) -> tuple[list[list[float]], dict[str, Any]]:
    """The ``count`` positions (deg) to measure next after the positions (φ1, φ2) (rad) measured,
    greedy D-optimal on the first-order Jacobian (module docstring)."""
    if isinstance(count, bool) or not float(count).is_integer() or not 0 <= int(count) <= 100:
        raise ConfigError(f"next positions must be an integer from 0 to 100, got {count!r}.")
    g1, g2 = candidate_grid(step_deg)
    grid = first_order_rows(table, g1, g2)
    sv, vt = right_singular(grid)
    basis = vt[: int(np.sum(sv > 1e-9 * sv[0]))].T  # (p, r_g)
    r_g = basis.shape[1]
    blocks = (grid @ basis).reshape(g1.size, 3, r_g)
    gains = np.einsum("cij,cik->cjk", blocks, blocks)  # (candidates, r_g, r_g)
    current = first_order_rows(table, phi1, phi2) @ basis
    info = current.T @ current
    ridge = 1e-6 * float(np.trace(gains.mean(axis=0))) / max(r_g, 1)
    before = info.copy()
    chosen: list[list[float]] = []
    for _ in range(int(count)):
        _, scores = np.linalg.slogdet(info + gains + ridge * np.eye(r_g))
        best = int(np.argmax(scores))
        info = info + gains[best]
        chosen.append(
            [round(float(np.degrees(g1[best])), 9), round(float(np.degrees(g2[best])), 9)]
        )
    design = {
        "criterion": CRITERION,
        "grid_step_deg": float(step_deg),
        "candidates": int(g1.size),
        "separable_by_orientation": r_g,
        "separable_now": int(np.linalg.matrix_rank(before)) if r_g else 0,
        "separable_after": int(np.linalg.matrix_rank(info)) if r_g else 0,
        "log_det_now": _logdet(before),
        "log_det_after": _logdet(info),
        "condition_now": _condition(before),
        "condition_after": _condition(info),
    }
    return chosen, design


def _condition(m: np.ndarray) -> float | None:
    s = np.linalg.svd(m, compute_uv=False)
    return float(np.sqrt(s[0] / s[-1])) if s.size and s[-1] > _TINY * s[0] else None


def compare_with_bounds(
    combinations: Sequence[Mapping[str, Any]],
    bounds_arcsec: Mapping[str, float | None],
    k: float,
    source: str,
    table: Turntable,
) -> dict[str, Any]:
    """Each separable combination against the bound the allocation implies (module docstring).

    Returns ``{"source", "rule", "k", "combinations": [...], "verdict"}``; each entry has
    ``name``, ``value_arcsec``, ``U_arcsec``, ``bound_arcsec``, ``decision`` (``inside`` |
    ``outside`` | ``undecided`` | ``no bound``) and ``statement``.
    """
    bounds = {table.resolve(n): v for n, v in bounds_arcsec.items()}
    entries = []
    for combo in combinations:
        coefficients = combo["coefficients"]
        missing = [n for n in coefficients if bounds.get(n) is None]
        value, big_u = combo["value_arcsec"], combo["U_arcsec"]
        entry: dict[str, Any] = {"name": combo["name"], "value_arcsec": value, "U_arcsec": big_u}
        if missing:
            entry.update(
                bound_arcsec=None,
                decision="no bound",
                statement=f"the allocation gives no bound for {', '.join(missing)}.",
            )
            entries.append(entry)
            continue
        bound = float(sum(abs(a) * float(bounds[n] or 0.0) for n, a in coefficients.items()))
        several = len(coefficients) > 1
        if abs(value) + big_u <= bound:
            decision = "inside"
            statement = f"|{value:.3g}| + U {big_u:.2g} ≤ {bound:.3g} arcsec" + (
                ": the allocation's guarantee holds for this sum" if several else ""
            )
        elif abs(value) - big_u > bound:
            decision = "outside"
            statement = f"|{value:.3g}| − U {big_u:.2g} > {bound:.3g} arcsec" + (
                f": at least one of {', '.join(coefficients)} exceeds its bound" if several else ""
            )
        else:
            decision = "undecided"
            statement = (
                f"the bound {bound:.3g} arcsec lies within {value:.3g} ± {big_u:.2g} arcsec: "
                "no statement of conformity; reduce U (more positions, less noise)"
            )
        entry.update(bound_arcsec=bound, decision=decision, statement=statement)
        entries.append(entry)
    decisions = {e["decision"] for e in entries}
    verdict = (
        "outside"
        if "outside" in decisions
        else "undecided"
        if "undecided" in decisions
        else "inside"
        if decisions == {"inside"}
        else "no bound"
    )
    return {
        "source": source,
        "rule": "guarded acceptance (ILAC-G8:09/2019 §4.2.2, w = U) on Σ|aᵢ|·UBᵢ of each "
        "separable combination Σaᵢχᵢ",
        "k": k,
        "combinations": entries,
        "verdict": verdict,
    }
