"""The plans of a batch: which files they are, and which of them were certified already.

A plan's ``plan_sha256`` (:func:`rotacal.certificate.issue.plan_sha256`) is of its own bytes and of
every file its measurements read, so it is known before anything is measured: hashing the captures
(about 1 GB/s) tells a batch that was stopped which plans it issued, without running them again.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rotacal.errors import ConfigError, RotacalError

if TYPE_CHECKING:
    from rotacal.plan.model import Plan

__all__ = ["BatchPlan", "expected_plan_sha256", "find_plans", "read_batch_plans"]


def find_plans(paths: Iterable[str | os.PathLike[str]]) -> list[Path]:
    """The plan files named: each file as given, each folder's ``*.toml`` files (not its
    subfolders'), in name order; every plan once, in the order first named.

    Raises
    ------
    ConfigError
        A path that does not exist, or a folder without plans.
    """
    found: dict[Path, None] = {}
    for given in paths:
        path = Path(given)
        if path.is_dir():
            plans = sorted(p for p in path.glob("*.toml") if p.is_file())
            if not plans:
                raise ConfigError(f"{path}: a folder without plans (*.toml); name the plan files")
            found.update(dict.fromkeys(p.resolve() for p in plans))
        elif path.is_file():
            found[path.resolve()] = None
        else:
            raise ConfigError(f"{path}: no such plan file or folder")
    if not found:
        raise ConfigError("no plans: name plan files (PLAN.toml) or folders of them")
    return list(found)


class _Digests:
    """SHA-256 of files, each hashed once per batch (twin plans often share a capture)."""

    def __init__(self) -> None:
        self._known: dict[tuple[str, int, int], str] = {}

    def __call__(self, path: str) -> str:
        from rotacal.provenance import sha256_file

        st = os.stat(path)
        key = (os.path.realpath(path), st.st_size, st.st_mtime_ns)
        if key not in self._known:
            self._known[key] = sha256_file(path)
        return self._known[key]


def expected_plan_sha256(plan: Plan, digest: _Digests | None = None) -> str:
    """The ``plan_sha256`` a certificate of ``plan`` will carry, from the plan's bytes and the files its measurements read (INTERFACE.md
    "Calibration plans"), without running it.

    Raises
    ------
    ConfigError
        A capture or option file cannot be read.
    """
    from rotacal.certificate.issue import plan_sha256
    from rotacal.plan.run import measurement_inputs

    digest = digest or _Digests()
    digests = []
    for m in plan.measurements:
        for path in measurement_inputs(plan, m):
            try:
                digests.append(digest(path))
            except OSError as e:
                raise ConfigError(f"{plan.path}: {m.key}: {path}: {e.strerror or e}") from None
    return plan_sha256(plan.text, digests)


@dataclasses.dataclass
class BatchPlan:
    """One plan of a batch as the client knows it before it runs: read, checked and hashed —
    or the one line why it cannot run (``error``)."""

    path: Path
    plan: Plan | None = None
    sha256: str | None = None
    error: str | None = None


def read_batch_plans(paths: Sequence[Path]) -> list[BatchPlan]:
    """Read and hash every plan; a plan that cannot be read gets its one-line ``error``."""
    from rotacal.plan.read import read_plan

    digest = _Digests()
    out = []
    for path in paths:
        entry = BatchPlan(path)
        try:
            entry.plan = read_plan(path)
            entry.sha256 = expected_plan_sha256(entry.plan, digest)
        except RotacalError as e:
            entry.error = " ".join(str(e).split())
        out.append(entry)
    return out
