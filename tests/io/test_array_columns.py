"""Columns of 2-D arrays in NPZ and HDF5 captures: ``data[:,K]``, both spellings of the mapping."""

from __future__ import annotations

import re

import h5py
import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.io import capture_length, iter_capture_chunks, parse_column_mapping, read_capture

N, K = 1000, 4
MATRIX = np.random.default_rng(2).normal(size=(N, K))


def _files(tmp_path):
    np.savez(tmp_path / "m.npz", data=MATRIX, fs_hz=np.float64(100), labels=np.array(list("abcd")))
    np.savez_compressed(tmp_path / "z.npz", data=MATRIX)
    np.save(tmp_path / "f.npy", np.asfortranarray(MATRIX))  # column by column in the file
    np.savez(tmp_path / "f.npz", data=np.asfortranarray(MATRIX))
    with h5py.File(tmp_path / "m.h5", "w") as f:
        f["data"] = MATRIX
        f.create_dataset("chunked", data=MATRIX, chunks=(64, K), compression="gzip")
    return [tmp_path / "m.npz", tmp_path / "z.npz", tmp_path / "f.npz", tmp_path / "m.h5"]


def test_every_column_of_a_2d_array_reads_back(tmp_path):
    for path in _files(tmp_path):
        cap = read_capture(path)
        assert [n for n in cap.names if n.startswith("data")] == [f"data[:,{k}]" for k in range(K)]
        for k in range(K):
            assert cap[f"data[:,{k}]"].tobytes() == MATRIX[:, k].tobytes(), (path.name, k)
            assert capture_length(path, f"data[:,{k}]") == N
        chunks = list(iter_capture_chunks(path, ["data[:,3]", "data[:,0]"], chunk_rows=99))
        assert np.concatenate([c["data[:,3]"] for c in chunks]).tobytes() == MATRIX[:, 3].tobytes()
        assert np.concatenate([c["data[:,0]"] for c in chunks]).tobytes() == MATRIX[:, 0].tobytes()


def test_mapping_both_spellings_and_negative_k(tmp_path):
    path = _files(tmp_path)[0]
    assert parse_column_mapping(["rate_deg_s=data[:,1]"]) == {"data[:,1]": "rate_deg_s"}
    for spelled in ("data[:,1]=rate_deg_s", "rate_deg_s=data[:,1]", "data[:, -3]=rate_deg_s"):
        cap = read_capture(path, mapping=[spelled], columns=["rate_deg_s"])
        assert cap["rate_deg_s"].tobytes() == MATRIX[:, 1].tobytes(), spelled
    with h5py.File(tmp_path / "m.h5") as f:
        assert (
            read_capture(tmp_path / "m.h5", columns=["chunked[:,-1]"])["chunked[:,3]"].tobytes()
            == np.asarray(f["chunked"][:, 3]).tobytes()
        )


def test_stored_npz_columns_stay_memory_mapped(tmp_path):
    path = _files(tmp_path)[0]
    col = read_capture(path, columns=["data[:,2]"])["data[:,2]"]
    base = col
    while getattr(base, "base", None) is not None and not isinstance(base, np.memmap):
        base = base.base
    assert isinstance(base, np.memmap)


def test_faults_name_the_shape(tmp_path):
    path = _files(tmp_path)[0]
    with pytest.raises(CaptureError, match=r"'data' has shape \(1000, 4\): it has no column 4"):
        read_capture(path, columns=["data[:,4]"])
    with pytest.raises(CaptureError, match=r"no column -5 \(columns 0 … 3\)"):
        read_capture(path, mapping=["data[:,-5]=x"], columns=["x"])
    np.savez(tmp_path / "one.npz", x=np.zeros(3))
    with pytest.raises(CaptureError, match=re.escape("'x' is not a 2-D array of numbers")):
        read_capture(tmp_path / "one.npz", columns=["x[:,0]"])
    with pytest.raises(
        CaptureError, match=re.escape("'labels' holds <U1 values, not real numbers")
    ):
        read_capture(path, columns=["labels"])
    with pytest.raises(CaptureError, match="'fs_hz' holds one value, not a column"):
        read_capture(path, columns=["fs_hz"])
    bad = tmp_path / "bad.npz"
    raw = bytearray((tmp_path / "m.npz").read_bytes())
    at = raw.find(MATRIX[500:501, 0].tobytes())
    raw[at] ^= 0xFF
    bad.write_bytes(bytes(raw))
    with pytest.raises(CaptureError, match=r"bad\.npz is damaged.*CRC-32"):
        read_capture(bad, columns=["data[:,1]"])


def test_smac_adis_2d_npz(shared_data):
    path = shared_data("imudata_smac", "npz") / "adis_16405_imu1.npz"
    with np.load(path) as f:
        data = f["data"]
    cap = read_capture(path)
    assert cap.names == [f"data[:,{k}]" for k in range(6)]
    for k in range(6):
        assert cap[f"data[:,{k}]"].tobytes() == data[:, k].tobytes()
    # the README: 10⁶ samples; gyro in °/s on a 0.05 °/s quantum
    assert capture_length(path, "data[:,0]") == 1_000_000
    steps = np.diff(np.unique(cap["data[:,0]"][:10_000]))
    assert np.min(steps) == pytest.approx(0.05, rel=1e-6)
