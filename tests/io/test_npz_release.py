"""The pages of a streamed NPZ chunk are dropped after use (flat memory) and read back intact."""

from __future__ import annotations

import numpy as np

from rotacal.io import iter_capture_chunks
from rotacal.io.capture import release_pages


def test_released_rows_read_back_the_same(tmp_path):
    data = np.random.default_rng(1).standard_normal(300_001)
    path = tmp_path / "r.npz"
    np.savez(path, rate_deg_s=data)
    got = [
        c["rate_deg_s"].copy() for c in iter_capture_chunks(path, ["rate_deg_s"], chunk_rows=7_919)
    ]
    np.testing.assert_array_equal(np.concatenate(got), data)
    np.save(tmp_path / "r.npy", data)
    mapped = np.load(tmp_path / "r.npy", mmap_mode="r")
    before = np.array(mapped[1000:200_000])
    release_pages({"x": mapped[:]})  # the whole array: every page dropped, then faulted back in
    np.testing.assert_array_equal(mapped[1000:200_000], before)
