"""Shared test fixtures: where the real recordings of ../shared/data are."""

from __future__ import annotations

import os

# One BLAS thread per process: pytest runs one worker per core (-n auto), and threaded BLAS on
# top of that oversubscribes the cores (small least-squares fits get many times slower). Set
# before NumPy is first imported in this process; the workers inherit it.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402

import pytest  # noqa: E402

#: The project's shared folder of real recordings (never copied into the repository).
SHARED_DATA = Path(
    os.environ.get("ROTACAL_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)


@pytest.fixture(scope="session")
def shared_data() -> Callable[..., Path]:
    """``shared_data("imucal", "example_data")``: the path, or a skip naming what is absent.

    The only skip the test suite allows: real data that this machine does not have.
    """

    def need(*parts: str) -> Path:
        path = SHARED_DATA.joinpath(*parts)
        if not path.exists():
            pytest.skip(f"real data {path} is absent (the shared data folder is not here)")
        return path

    return need
