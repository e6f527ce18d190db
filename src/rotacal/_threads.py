"""How many threads the numerical libraries may use (private).

rotacal's hot paths are whole-array NumPy or Numba kernels on one core; where they call BLAS it is
for small matrix products (a fit's block sums, the parabolas of the reversals), on which BLAS
threads only wait for each other — and on a busy machine they spin.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

_F = TypeVar("_F", bound=Callable[..., Any])


def one_blas_thread(analysis: _F) -> _F:
    """Run ``analysis`` with one BLAS thread (threadpoolctl; unchanged where it is missing).

    The motion analyses' matrix products are small (the fit's block sums, 2048 blocks a
    product; the parabolas of the reversals): BLAS threads only wait for each other there, and
    on a busy machine they spin — 35–64 % of the CPU time of the three chunked motion analyses
    at 10⁷ samples on this project's 2-core machine with other work running.
    """

    @functools.wraps(analysis)
    def limited(*args: Any, **kwargs: Any) -> Any:
        with blas_one_thread():
            return analysis(*args, **kwargs)

    return limited  # type: ignore[return-value]


@contextlib.contextmanager
def blas_one_thread() -> Iterator[None]:
    """Within: one BLAS thread (threadpoolctl; unchanged where it is missing). ~1 ms to enter,
    ~0.3 ms inside another such context."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - a dependency; the work runs as it is
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield
