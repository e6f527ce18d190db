"""The streamed motion analyses run their (small) matrix products on one BLAS thread."""

from __future__ import annotations

import pytest

from rotacal.table import streaming

threadpoolctl = pytest.importorskip("threadpoolctl")


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

    with pytest.raises(_Seen):
        getattr(streaming, name)(chunks, **kwargs)
    assert seen and set(seen) == {1}
