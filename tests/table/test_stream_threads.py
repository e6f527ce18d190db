"""The motion analyses, streamed and in memory, run their (small) matrix products on one BLAS
thread."""

from __future__ import annotations

import numpy as np
import pytest
import threadpoolctl

from rotacal.table import motion, streaming


class _Seen(Exception):
    pass


@pytest.mark.parametrize(
    ("name", "kwargs"),
    [
        ("calibrate_encoder_motion_chunked", {"lines": 100}),
        ("calibrate_lts_motion_chunked", {"radius_mm": 100.0}),
        ("calibrate_fog_motion_chunked", {}),
    ],
)
def test_blas_threads_inside_a_streamed_analysis(name, kwargs):
    # truth: threadpoolctl's own report of the BLAS libraries, read while the analysis runs
    seen = []

    def chunks():
        seen.extend(
            i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"
        )
        raise _Seen
        yield  # pragma: no cover - a generator that stops at its first step

    # the tests run with one BLAS thread already (conftest): give BLAS two, so that a missing
    # limit shows
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"), pytest.raises(_Seen):
        getattr(streaming, name)(chunks, **kwargs)
    assert seen and set(seen) == {1}


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]


@pytest.mark.parametrize(
    ("name", "args", "kwargs"),
    [
        ("calibrate_encoder_motion", 3, {"lines": 100}),
        ("calibrate_lts_motion", 2, {"radius_mm": 100.0}),
        ("calibrate_fog_motion", 2, {}),
    ],
)
def test_blas_threads_inside_an_in_memory_analysis(monkeypatch, name, args, kwargs):
    # truth as above, read from inside the analysis (its first check of the settings)
    seen: list[int] = []

    def spy(*a, **k):
        seen.extend(_blas_threads())
        raise _Seen

    monkeypatch.setattr(motion, "_check_settings", spy)
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"), pytest.raises(_Seen):
        getattr(motion, name)(*([np.zeros(10)] * args), **kwargs)
    assert seen and set(seen) == {1}
