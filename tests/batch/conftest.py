"""Fixtures of the batch tests: a real ``distributed.LocalCluster`` of two worker processes (one
per test process for the huge-capture tests; test_batch.py has its own) and folders of twin
plans."""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from distributed import Client

from rotacal.batch import cluster
from rotacal.batch.testing import write_twin_plans

#: The tests' plans measure the rotation test alone (30 ms), so that a batch costs its overhead.
COMMANDS = ("gyro rotations",)


@pytest.fixture(scope="session")
def dask_client() -> Iterator[Client]:
    """A local cluster of two workers shared by the tests of one huge capture on Dask (one per
    test process: starting a cluster costs 2–3 s). The batch tests, which kill workers, have
    their own (test_batch.py)."""
    with cluster.dask_client(2, None, None) as client:  # as `rotacal batch --workers 2` makes it
        yield client


@pytest.fixture(scope="module")
def twin_source(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Eight twin plans (units 0–7), made once per module."""
    folder = tmp_path_factory.mktemp("twin-plans")
    write_twin_plans(folder, 8, commands=COMMANDS)
    return folder


@pytest.fixture
def plans(twin_source: Path, tmp_path: Path) -> Callable[[int], list[Path]]:
    """``plans(n)``: a fresh copy of the first ``n`` twin plans (with their captures) in this
    test's folder."""

    def copy(n: int) -> list[Path]:
        folder = tmp_path / "plans"
        shutil.copytree(twin_source, folder)
        every = sorted(folder.glob("unit-*.toml"))
        for extra in every[n:]:
            extra.unlink()
        return every[:n]

    return copy
