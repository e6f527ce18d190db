"""The compiled Monte Carlo kernel (rotacal.turntable.fast) against the NumPy path, draw by draw.

Truth for both paths is in test_model.py (the printed matrices of eqs. (17)–(24), closed forms of
single-axis tables, scipy rotations), which runs its fast-path tests on both. Here the two paths
are compared to the last bit on chains that exercise every branch of the kernel: the seed table,
a three-axis table, a fixed link at the base (conjugated by every axis), errors after the last
rotary axis, a chain whose only errors come before every axis, and the single-draw path.
"""

from __future__ import annotations

import types

import numpy as np
import pytest

from rotacal.turntable.allocation import monte_carlo_check
from rotacal.turntable.fast import COMPILE_FROM_DRAWS, use_compiled
from rotacal.turntable.model import ErrorSpec, Link, Turntable, seed_table


def _table(name: str, links: list[Link]) -> Turntable:
    errors = []
    for link in links:
        for error, ax in link.rotations:
            kind = (
                "squareness" if link.axis is None else ("position" if ax == link.axis else "wobble")
            )
            errors.append(ErrorSpec(error, kind))
    return Turntable(name, tuple(links), tuple(errors))


CHAINS = {
    "seed": seed_table(),
    "three axes, base tilt": _table(
        "three axes",
        [
            Link(None, None, (("bx", "x"), ("by", "y"))),
            Link("z", "outer", (("po", "z"), ("wx", "x"))),
            Link(None, None, (("sq", "x"),)),
            Link("y", "middle", (("wm", "x"), ("pm", "y"), ("wz", "z"))),
            Link("z", "inner", (("wi", "x"), ("pi", "z"))),
        ],
    ),
    "errors after the last axis": _table(
        "tail",
        [
            Link("x", "a", (("ea", "x"),)),
            Link("y", "b", ()),
            Link(None, None, (("t1", "z"), ("t2", "z"), ("t3", "y"))),
        ],
    ),
    "errors before every axis only": _table(
        "base only",
        [Link(None, None, (("b1", "x"), ("b2", "y"))), Link("z", "a"), Link("x", "b")],
    ),
}


def _both(table: Turntable, angles: np.ndarray, chi: np.ndarray, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("ROTACAL_NUMBA", "1")
    assert use_compiled(angles.shape[0])
    compiled = table.fast_orientation_error(angles, chi)
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    numpy_path = table.fast_orientation_error(angles, chi)
    return compiled, numpy_path


@pytest.mark.parametrize("name", list(CHAINS))
@pytest.mark.parametrize("size", [1e-5, 3e-2])
def test_compiled_kernel_equals_the_numpy_path(
    name: str, size: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    table = CHAINS[name]
    rng = np.random.default_rng(17)
    n = 40_000  # more than two of the NumPy path's chunks
    angles = rng.uniform(-7.0, 7.0, (n, len(table.angle_names)))
    chi = rng.uniform(-size, size, (n, len(table.angular_error_names)))
    chi[::7, 0] = 0.0  # exact zeros: the NumPy path skips nothing for them, the sum is the same
    compiled, numpy_path = _both(table, angles, chi, monkeypatch)
    np.testing.assert_array_equal(compiled, numpy_path)
    # and both equal the matrix chain (rotation_error) to rounding
    ref = table.orientation_error([angles[:, k] for k in range(angles.shape[1])], chi)
    np.testing.assert_allclose(compiled, ref, rtol=0, atol=1e-15)


def test_compiled_kernel_on_two_and_one_rows(monkeypatch: pytest.MonkeyPatch) -> None:
    table = CHAINS["seed"]
    angles = np.array([[0.3, 1.1], [2.0, -0.4]])
    chi = np.full((2, 8), 2e-4) * np.array([1, -1, 2, -2, 3, -3, 4, -4])
    compiled, numpy_path = _both(table, angles, chi, monkeypatch)
    np.testing.assert_array_equal(compiled, numpy_path)
    one = table.fast_orientation_error(angles[1:], chi[1:])  # the straight-line one-point path
    np.testing.assert_array_equal(one, compiled[1:])


def test_numba_can_be_switched_off_and_forced(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    assert not use_compiled(10**9)
    monkeypatch.setenv("ROTACAL_NUMBA", "1")
    assert use_compiled(1)
    monkeypatch.delenv("ROTACAL_NUMBA")
    assert use_compiled(COMPILE_FROM_DRAWS)


@pytest.mark.parametrize("name", list(CHAINS))
def test_fused_kernel_equals_the_numpy_twin_on_every_chain(name: str, monkeypatch) -> None:
    table = CHAINS[name]
    names = table.angular_error_names
    bounds = types.SimpleNamespace(
        upper_bounds_rad={n: 2e-3 * (1 + i) for i, n in enumerate(names)},
        lower_bounds_rad={n: 2e-4 for n in names},
        requirement_rad={"psi": 6e-3, "theta": 6e-3, "gamma": 6e-3},  # some draws outside
    )
    results = []
    for flag, threads in (("0", 1), ("1", 1), ("1", 2)):
        monkeypatch.setenv("ROTACAL_NUMBA", flag)
        res = monte_carlo_check(
            table,
            bounds,
            runs=30_011,
            seed=9,
            chunk=8_000,
            threads=threads,
        )
        results.append({**res.to_dict(), "draws_per_second": 0})
    assert results[0] == results[1] == results[2]
    assert 0 < results[0]["outside"] < 30_011 or name == "errors before every axis only"
