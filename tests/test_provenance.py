"""The input hashes of the provenance, prefetched or not, against hashlib on the bytes."""

from __future__ import annotations

import hashlib
import os

import pytest

from rotacal.provenance import prefetch_sha256, sha256_file


def test_a_prefetched_hash_is_the_hash_of_the_bytes(tmp_path):
    path = tmp_path / "capture.bin"
    data = os.urandom(3 * (1 << 20) + 17)  # several hash blocks and a partial one
    path.write_bytes(data)
    prefetch_sha256([path, str(path)])  # the same file twice: hashed once
    assert sha256_file(path) == hashlib.sha256(data).hexdigest()
    assert sha256_file(path) == hashlib.sha256(data).hexdigest()  # again, without the prefetch


def test_a_file_changed_after_the_prefetch_is_hashed_again(tmp_path):
    path = tmp_path / "capture.bin"
    path.write_bytes(b"first version")
    prefetch_sha256([path])
    path.write_bytes(b"the second, longer version")
    assert sha256_file(path) == hashlib.sha256(b"the second, longer version").hexdigest()


def test_a_missing_file_is_not_prefetched_and_still_fails_where_it_is_hashed(tmp_path):
    missing = tmp_path / "gone.bin"
    prefetch_sha256([missing, tmp_path])  # neither a file: nothing started, nothing raised
    with pytest.raises(FileNotFoundError):
        sha256_file(missing)
