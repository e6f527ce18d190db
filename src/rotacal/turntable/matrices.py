"""The small rotation matrices of the chain and the entry-wise kernel of the Monte Carlo.

Rotations about x/y/z (eqs. (17), (19)), the small-angle matrix E = I + skew(e) and its exact
counterpart, and ``_fast_kernel``: the recursion D ← A_kᵀ·D·A_k·E_k with D kept as nine entries,
constant zeros and ones skipped, on arrays or — through ``_Symbol`` — generated once as
straight-line code (``_one_point_kernel``).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, eqs. (17)–(24).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from rotacal.turntable.chain import _PLANE, _LinkPlan

__all__: list[str] = []


def _rotation_matrix(axis: int, phi: np.ndarray) -> np.ndarray:
    """Active rotation about x/y/z by φ (rad), as Ry, Rz of eqs. (17), (19): (..., 3, 3)."""
    c, s = np.cos(phi), np.sin(phi)
    out = np.zeros((*np.shape(phi), 3, 3))
    i, j = _PLANE[axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def _point_rotation(axis: int, phi: np.ndarray) -> np.ndarray:
    """:func:`_rotation_matrix` of one angle (φ of shape (1,), rad): the same entries, shape
    (1, 3, 3), built from Python floats (a few µs less per call)."""
    c, s = float(np.cos(phi)[0]), float(np.sin(phi)[0])
    m = [[0.0] * 3 for _ in range(3)]
    i, j = _PLANE[axis]
    m[axis][axis] = 1.0
    m[i][i] = m[j][j] = c
    m[i][j], m[j][i] = -s, s
    return np.array([m])


def _small_angle_matrix(present: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """E(ex, ey, ez) = I + skew(e) of eqs. (17)–(19), errors about the same axis summed."""
    shape = np.broadcast_shapes(*(v.shape for v, _ in present))
    e = np.zeros((*shape, 3))
    for v, a in present:
        e[..., a] += v
    out = np.zeros((*shape, 3, 3))
    out[..., 0, 0] = out[..., 1, 1] = out[..., 2, 2] = 1.0
    out[..., 0, 1] = -e[..., 2]
    out[..., 0, 2] = e[..., 1]
    out[..., 1, 0] = e[..., 2]
    out[..., 1, 2] = -e[..., 0]
    out[..., 2, 0] = -e[..., 1]
    out[..., 2, 1] = e[..., 0]
    return out


def _exact_matrix(present: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """Product of proper elementary rotations in the listed order (scipy Rotation)."""
    from scipy.spatial.transform import Rotation

    shape = np.broadcast_shapes(*(v.shape for v, _ in present))
    size = int(np.prod(shape)) if shape else 1
    total = None
    for v, a in present:
        rotvec = np.zeros((size, 3))
        rotvec[:, a] = np.broadcast_to(v, shape).reshape(-1)
        r = Rotation.from_rotvec(rotvec)
        total = r if total is None else total * r  # total·r: r applied in the moved frame
    assert total is not None
    return np.asarray(total.as_matrix()).reshape(*shape, 3, 3)


_Entry = Any  # float (an exact constant) or ndarray


def _is_const(x: _Entry, value: float) -> bool:
    return isinstance(x, float) and x == value


def _add(a: _Entry, b: _Entry) -> _Entry:
    if _is_const(a, 0.0):
        return b
    if _is_const(b, 0.0):
        return a
    return a + b


def _sub(a: _Entry, b: _Entry) -> _Entry:
    if _is_const(b, 0.0):
        return a
    if _is_const(a, 0.0):
        return -b
    return a - b


def _mul(a: _Entry, b: _Entry) -> _Entry:
    if _is_const(a, 0.0) or _is_const(b, 0.0):
        return 0.0
    if _is_const(a, 1.0):
        return b
    if _is_const(b, 1.0):
        return a
    return a * b


class _Symbol:
    """An entry of :func:`_fast_kernel` as the name of a local variable of generated code: each
    operation on it appends one assignment to ``lines`` (see :func:`_one_point_kernel`)."""

    __slots__ = ("lines", "name")

    def __init__(self, name: str, lines: list[str]) -> None:
        self.name, self.lines = name, lines

    def _new(self, expression: str) -> _Symbol:
        name = f"t{len(self.lines)}"
        self.lines.append(f"    {name} = {expression}")
        return _Symbol(name, self.lines)

    @staticmethod
    def _text(x: Any) -> str:
        return x.name if isinstance(x, _Symbol) else repr(float(x))

    def __add__(self, other: Any) -> _Symbol:
        return self._new(f"{self.name} + {self._text(other)}")

    def __radd__(self, other: Any) -> _Symbol:
        return self._new(f"{self._text(other)} + {self.name}")

    def __sub__(self, other: Any) -> _Symbol:
        return self._new(f"{self.name} - {self._text(other)}")

    def __rsub__(self, other: Any) -> _Symbol:
        return self._new(f"{self._text(other)} - {self.name}")

    def __mul__(self, other: Any) -> _Symbol:
        return self._new(f"{self.name} * {self._text(other)}")

    def __rmul__(self, other: Any) -> _Symbol:
        return self._new(f"{self._text(other)} * {self.name}")

    def __neg__(self) -> _Symbol:
        return self._new(f"-{self.name}")


@functools.lru_cache(maxsize=32)
def _one_point_kernel(links: tuple[_LinkPlan, ...], angles: tuple[int, ...], n_angular: int) -> Any:
    """:func:`_fast_kernel` for one chain, generated once as a straight-line Python function
    ``f(trig, chi) -> (Δψ, Δθ, Δγ)``: the kernel run on :class:`_Symbol` entries records every
    operation it does (the constant zeros and ones of the chain skipped as the kernel skips
    them), in its order, so that on floats the function computes exactly what the kernel does
    on arrays."""
    lines: list[str] = []
    trig = {k: (_Symbol(f"c{k}", lines), _Symbol(f"s{k}", lines)) for k in angles}
    chi = [_Symbol(f"x{i}", lines) for i in range(n_angular)]
    result = _fast_kernel(links, trig, chi)  # type: ignore[arg-type]
    head = [f"    c{k}, s{k} = trig[{k}]" for k in angles]
    head += [f"    x{i} = chi[{i}]" for i in range(n_angular)]
    values = ", ".join(_Symbol._text(v) for v in result)
    source = "\n".join(["def kernel(trig, chi):", *head, *lines, f"    return ({values})"])
    namespace: dict[str, Any] = {}
    exec(compile(source, "<rotacal.turntable.model one-point kernel>", "exec"), namespace)
    return namespace["kernel"]


def _fast_kernel(
    links: tuple[_LinkPlan, ...], trig: dict[int, tuple[np.ndarray, np.ndarray]], chi: np.ndarray
) -> tuple[_Entry, _Entry, _Entry]:
    """ΔR[0,2], ΔR[1,0], ΔR[2,1] by D ← Aᵀ·D·A·E with D as nine entries (row-major)."""
    d: list[_Entry] | None = None
    # the last link with errors needs only the three entries of eq. (24) when no rotation follows
    last = len(links) - 1
    while last >= 0 and not links[last].rotations:
        last -= 1
    if any(plan.axis >= 0 for plan in links[last + 1 :]):
        last = -1
    for k, plan in enumerate(links):
        if plan.axis >= 0 and d is not None:
            c, s = trig[plan.angle]
            i, j = _PLANE[plan.axis]
            m = list(d)
            for r in range(3):  # M = D·A: columns i, j mix
                di, dj = d[3 * r + i], d[3 * r + j]
                m[3 * r + i] = _add(_mul(di, c), _mul(dj, s))
                m[3 * r + j] = _sub(_mul(dj, c), _mul(di, s))
            d = list(m)
            for col in range(3):  # Aᵀ·M: rows i, j mix
                mi, mj = m[3 * i + col], m[3 * j + col]
                d[3 * i + col] = _add(_mul(mi, c), _mul(mj, s))
                d[3 * j + col] = _sub(_mul(mj, c), _mul(mi, s))
        if not plan.rotations:
            continue
        e: list[_Entry] = [0.0, 0.0, 0.0]
        for idx, a in plan.rotations:
            e[a] = _add(e[a], chi[idx])
        ex, ey, ez = e
        if d is None:
            d = [1.0, _sub(0.0, ez), ey, ez, 1.0, _sub(0.0, ex), _sub(0.0, ey), ex, 1.0]
            continue
        # D·(I + skew(e)): (D·K)[r] = (D[r,1]ez − D[r,2]ey, D[r,2]ex − D[r,0]ez, D[r,0]ey − D[r,1]ex)
        rows = (
            ((0, 2), (1, 0), (2, 1))
            if k == last
            else tuple((r, c) for r in range(3) for c in range(3))
        )
        new = list(d)
        for r, col in rows:
            d0, d1, d2 = d[3 * r], d[3 * r + 1], d[3 * r + 2]
            if col == 0:
                inc = _sub(_mul(d1, ez), _mul(d2, ey))
            elif col == 1:
                inc = _sub(_mul(d2, ex), _mul(d0, ez))
            else:
                inc = _sub(_mul(d0, ey), _mul(d1, ex))
            new[3 * r + col] = _add(d[3 * r + col], inc)
        d = new
    if d is None:
        return 0.0, 0.0, 0.0
    return d[2], d[3], d[7]
