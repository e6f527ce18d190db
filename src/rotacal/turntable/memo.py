"""The last results of a deterministic computation in this process, kept by the text of its inputs.

A turntable's allocation and the reproduction of the GyroWheel study's numbers take seconds each
and are often asked again with the same inputs in one process — the requirement's derivation
tries a scale it tried before, a session budgets one table design several times, every budget
of the seed table reproduces the same paper. Callers get copies, so what they change stays
theirs.
"""

from __future__ import annotations

import collections
import copy
import dataclasses
from collections.abc import Callable
from typing import Any, Generic, TypeVar

__all__ = ["LastResults", "memo_key"]

T = TypeVar("T")


class LastResults(Generic[T]):
    """The ``size`` most recently used results, by key (the text of the inputs that decide them)."""

    def __init__(self, size: int) -> None:
        self._size = size
        self._results: collections.OrderedDict[str, T] = collections.OrderedDict()

    def get(self, key: str, compute: Callable[[], T]) -> T:
        """A copy of the result for ``key``: kept from an earlier call, else ``compute()`` now."""
        if key not in self._results:
            self._results[key] = compute()
            while len(self._results) > self._size:
                self._results.popitem(last=False)
        self._results.move_to_end(key)
        return copy.deepcopy(self._results[key])

    def __contains__(self, key: object) -> bool:
        return key in self._results

    def __len__(self) -> int:
        return len(self._results)

    def clear(self) -> None:
        """Forget every kept result."""
        self._results.clear()


def memo_key(table: Any, *inputs: Any) -> str:
    """A table and further inputs as the text a :class:`LastResults` keeps results by: the table as
    it compares (its ``source``, a file name, left out) and the inputs' reprs (give arrays as
    tuples: NumPy shortens the repr of a long one)."""
    return repr((dataclasses.replace(table, source=""), *inputs))
