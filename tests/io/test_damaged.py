"""Damaged files, one kind at a time: the CaptureError names the file, the part and the damage.

The truth each test checks against comes from outside the reader: zipfile's own CRC test, the
bytes the test itself damaged, what h5py returns for unwritten chunks, the segment sizes npTDMS
writes, the line the test put a bad byte on.
"""

from __future__ import annotations

import io
import struct
import subprocess
import sys
import zipfile

import h5py
import numpy as np
import pytest
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from rotacal.errors import CaptureError, ConfigError
from rotacal.io import (
    capture_length,
    iter_capture_chunks,
    parse_column_mapping,
    read_capture,
    write_capture,
)
from rotacal.io._hdf5_heap import check_global_heaps


def _one_line(exc_info: pytest.ExceptionInfo[BaseException]) -> str:
    text = str(exc_info.value)
    assert "\n" not in text, text
    return text


def _all_entry_points(path, names, *, length: bool = True, **kw) -> list[str]:
    """The message of each of read_capture, iter_capture_chunks and (when ``length``, for damage
    that shows without reading the data) capture_length: all must fail."""
    texts = []
    calls = [
        lambda: read_capture(path, **kw),
        lambda: list(iter_capture_chunks(path, names, chunk_rows=7, **kw)),
    ]
    if length:
        calls.append(lambda: capture_length(path, names[0], **kw))
    for call in calls:
        with pytest.raises(CaptureError) as ei:
            call()
        texts.append(_one_line(ei))
    return texts


def _rezip(members: dict[str, bytes], compression: int) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=compression) as zf:
        for name, raw in members.items():
            zf.writestr(name, raw)
    return buf.getvalue()


def _npy(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


# --- NPZ --------------------------------------------------------------------------------------


def test_npz_stored_member_with_a_flipped_bit_fails_its_crc(tmp_path):
    good = write_capture(tmp_path / "g.npz", {"t": np.arange(500.0), "a": np.ones(500)})
    data = bytearray(good.read_bytes())
    at = data.index(np.float64(1.0).tobytes() * 4) + 8 * 300  # inside 'a', a finite value stays
    data[at] ^= 0x10
    bad = tmp_path / "bad.npz"
    bad.write_bytes(bytes(data))
    with zipfile.ZipFile(bad) as zf:
        assert zf.testzip() == "a.npy"  # zipfile's own verdict: the member is damaged
    for text in _all_entry_points(bad, ["a"], length=False):
        assert "bad.npz is damaged" in text and "'a.npy'" in text and "CRC-32" in text, text
    assert read_capture(bad, columns=["t"])["t"][499] == 499.0  # the intact member still reads


def test_npz_damage_that_makes_a_nan_is_named_as_damage(tmp_path):
    good = write_capture(tmp_path / "g.npz", {"a": np.ones(64)})
    data = bytearray(good.read_bytes())
    at = data.index(np.float64(1.0).tobytes() * 4) + 8 * 10
    data[at : at + 8] = np.float64(np.nan).tobytes()
    (tmp_path / "n.npz").write_bytes(bytes(data))
    with pytest.raises(CaptureError) as ei:
        read_capture(tmp_path / "n.npz")
    assert "CRC-32" in _one_line(ei) and "holds nan" not in str(ei.value)


def test_npz_absurd_declared_size_is_refused_before_allocating(tmp_path):
    """A header declaring 10**15 values (8 PB) with a correct CRC: no MemoryError, one line."""
    header = _npy(np.zeros(4))
    huge = header.replace(b"(4,)", b"(1000000000000000,)")
    for compression in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        path = tmp_path / f"huge{compression}.npz"
        path.write_bytes(_rezip({"a.npy": huge}, compression))
        for text in _all_entry_points(path, ["a"]):
            assert "huge" in text and "column 'a' declares 1000000000000000 values" in text, text


def test_npz_damaged_array_header_under_a_good_crc(tmp_path):
    header = _npy(np.arange(5.0))
    for bad_header in (header.replace(b"'descr'", b"'descr "), header.replace(b"}", b"(")):
        for compression in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            path = tmp_path / "h.npz"
            path.write_bytes(_rezip({"a.npy": bad_header}, compression))
            for text in _all_entry_points(path, ["a"]):
                assert "h.npz is damaged" in text and "'a.npy'" in text, text
                assert "NumPy array header" in text


def test_npz_compressed_damage_surfaces_mid_stream_as_capture_error(tmp_path):
    x = np.random.default_rng(3).normal(size=4000)
    path = tmp_path / "c.npz"
    np.savez_compressed(path, x=x)
    data = bytearray(path.read_bytes())
    end = data.rindex(b"PK\x01\x02")  # the damage sits late in the deflate stream
    data[end - 40] ^= 0xFF
    path.write_bytes(bytes(data))
    chunks = iter_capture_chunks(path, ["x"], chunk_rows=500)
    first = next(chunks)  # the start of the member decompresses
    np.testing.assert_array_equal(first["x"], x[:500])
    with pytest.raises(CaptureError) as ei:
        list(chunks)
    assert "c.npz is damaged" in _one_line(ei)


def test_npz_duplicate_member_names_are_refused(tmp_path):
    raw = _npy(np.arange(3.0))
    path = tmp_path / "d.npz"
    with zipfile.ZipFile(path, "w") as zf, pytest.warns(UserWarning, match="Duplicate name"):
        zf.writestr("a.npy", raw)
        zf.writestr("a.npy", raw)
    with pytest.raises(CaptureError, match="names column 'a' more than once"):
        read_capture(path)


# --- HDF5 -------------------------------------------------------------------------------------


def _heap_file(tmp_path):
    path = write_capture(tmp_path / "v.h5", {"a": np.arange(10.0)}, metadata={"op": "Jane"})
    data = bytearray(path.read_bytes())
    heap = data.index(b"GCOL\x01")
    return path, data, heap


def test_hdf5_damaged_global_heap_is_refused_without_hanging(tmp_path):
    """A free-space object of size 0 makes HDF5's heap walk stand still (a hang in C code)."""
    path, data, heap = _heap_file(tmp_path)
    pos = heap + 16  # the first object: index, references, reserved, size
    while struct.unpack_from("<H", data, pos)[0] != 0:  # find the free-space object (index 0)
        pos += 16 + (struct.unpack_from("<Q", data, pos + 8)[0] + 7) // 8 * 8
    struct.pack_into("<Q", data, pos + 8, 0)
    bad = tmp_path / "heap.h5"
    bad.write_bytes(bytes(data))
    check_global_heaps(path, "v.h5")  # the intact file passes
    code = (
        "import sys\nfrom rotacal.errors import CaptureError\nfrom rotacal.io import read_capture\n"
        f"try:\n    read_capture({str(bad)!r})\nexcept CaptureError as e:\n    print(e)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert "heap.h5 is damaged" in run.stdout and "global heap" in run.stdout, run


def test_hdf5_unwritten_chunks_would_read_as_fill_values(tmp_path):
    path = tmp_path / "part.h5"
    with h5py.File(path, "w") as f:
        d = f.create_dataset("a", shape=(100,), chunks=(10,), dtype="f8", fillvalue=0.0)
        d[:50] = np.arange(1.0, 51.0)
        f["t"] = np.arange(100.0)
    with h5py.File(path) as f:  # the silent wrong number h5py would hand over
        assert np.all(f["a"][50:] == 0.0)
    for text in _all_entry_points(path, ["a"]):
        assert "part.h5 is damaged" in text and "stores 5 of its 10 chunks" in text, text


def test_hdf5_never_written_dataset(tmp_path):
    path = tmp_path / "empty.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("a", shape=(10,), dtype="f8")
    for text in _all_entry_points(path, ["a"]):
        assert "dataset 'a' has no data stored" in text, text


def test_hdf5_truncated_file(tmp_path):
    good = write_capture(tmp_path / "g.h5", {"a": np.arange(5000.0)})
    bad = tmp_path / "cut.h5"
    bad.write_bytes(good.read_bytes()[:-8000])
    for text in _all_entry_points(bad, ["a"], length=False):
        assert "cut.h5 is damaged or incomplete" in text, text


# --- TDMS -------------------------------------------------------------------------------------


def _two_segments(path):
    """Write two segments; return the size of the first (where the second starts)."""
    with TdmsWriter(str(path)) as w:
        w.write_segment([RootObject(), GroupObject("g"), ChannelObject("g", "x", np.arange(50.0))])
        w.write_segment([ChannelObject("g", "x", np.arange(50.0, 100.0))])
    return path.read_bytes().index(b"TDSm", 1)


def test_tdms_cut_off_names_the_byte_that_keeps_the_complete_segments(tmp_path):
    path = tmp_path / "run.tdms"
    first = _two_segments(path)
    cut = tmp_path / "cut.tdms"
    cut.write_bytes(path.read_bytes()[:-100])
    for text in _all_entry_points(cut, ["x"]):
        assert "cut.tdms ends inside segment 2" in text, text
        assert f"keep its 1 complete segment by cutting the file at byte {first}" in text
    kept = tmp_path / "kept.tdms"
    kept.write_bytes(cut.read_bytes()[:first])  # what the message tells the user to do
    np.testing.assert_array_equal(read_capture(kept)["x"], np.arange(50.0))


def _stderr_of(code: str) -> str:
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run
    return run.stderr


def test_tdms_warnings_of_nptdms_never_reach_the_terminal(tmp_path):
    path = tmp_path / "p.tdms"
    with TdmsWriter(str(path)) as w:
        w.write_segment(
            [
                RootObject(),
                GroupObject("g", properties={"unit": "unXt"}),
                ChannelObject("g", "x", np.arange(5.0)),
            ]
        )
    path.write_bytes(path.read_bytes().replace(b"unXt", b"un\xfft"))
    alone = f"from nptdms import TdmsFile\nTdmsFile.read({str(path)!r})"
    assert "Error decoding string" in _stderr_of(alone)  # npTDMS alone prints a warning
    for text in _all_entry_points(path, ["x"]):
        assert "p.tdms is damaged" in text and "not UTF-8 text" in text, text
    through = (
        "from rotacal.errors import CaptureError\nfrom rotacal.io import read_capture\n"
        f"try:\n    read_capture({str(path)!r})\nexcept CaptureError:\n    pass\n"
    )
    assert _stderr_of(through) == ""  # through rotacal: nothing but rotacal's own words


# --- CSV --------------------------------------------------------------------------------------


def test_csv_not_utf8_far_into_the_file_names_the_line(tmp_path):
    lines = ["time_s,a"] + [f"{i},{i * 0.5}" for i in range(2000)]
    lines[1500] = "1499,\xe9"
    path = tmp_path / "late.csv"
    path.write_bytes("\n".join(lines).encode("latin-1"))
    assert path.read_bytes().index(b"\xe9") > 8192
    for call in (
        lambda: read_capture(path),
        lambda: list(iter_capture_chunks(path, ["a"], chunk_rows=100)),
    ):
        with pytest.raises(CaptureError) as ei:
            call()
        assert "late.csv line 1501 is not UTF-8 text (byte 0xe9" in _one_line(ei)


# --- names given by the caller ----------------------------------------------------------------


def test_names_that_are_not_text_are_config_errors(tmp_path):
    path = write_capture(tmp_path / "c.npz", {"a": np.arange(3.0)})
    for kw in ({"columns": [b"a"]}, {"mapping": {b"a": "x"}}, {"group": b"g"}):
        with pytest.raises(ConfigError, match="is not text"):
            read_capture(path, **kw)
    with pytest.raises(ConfigError, match="is not text"):
        list(iter_capture_chunks(path, [b"a"]))
    with pytest.raises(ConfigError, match="is not text"):
        capture_length(path, b"a")
    with pytest.raises(ConfigError, match="is not text"):
        parse_column_mapping([b"a=x"])


def test_encoder_chunk_source_is_as_safe_as_the_reader(tmp_path):
    from rotacal.table import encoder_chunks_from_file

    path = tmp_path / "enc.npz"
    np.savez_compressed(path, time_s=np.arange(100.0), a=np.ones(100), b=np.zeros(100))
    data = bytearray(path.read_bytes())
    data[data.index(b"a.npy") + 60] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(CaptureError, match=r"enc\.npz is damaged"):
        for _ in encoder_chunks_from_file(path, chunk_rows=10)():
            pass
