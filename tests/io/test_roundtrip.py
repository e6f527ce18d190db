"""Round trips, files written by third-party libraries, mapping, ragged and chunked reading."""

from __future__ import annotations

import zipfile

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from rotacal.io import (
    Capture,
    capture_length,
    iter_capture_chunks,
    parse_column_mapping,
    read_capture,
    write_capture,
)

EXTS = ["csv", "npz", "h5", "tdms"]


def _columns(n: int = 257, seed: int = 1) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "time_s": np.arange(n) / 1000.0,
        "a": rng.standard_normal(n) * 10.0 ** rng.integers(-300, 300, n),
        "b": np.concatenate([[5e-324, -0.0, 1.7976931348623157e308, 0.1], rng.random(n - 4)]),
    }


def _bits_equal(x: np.ndarray, y: np.ndarray) -> bool:
    return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


# --- round trips ------------------------------------------------------------------------------


@pytest.mark.parametrize("ext", EXTS)
def test_roundtrip_bit_for_bit(tmp_path, ext):
    cols = _columns()
    meta = {"fs_hz": 1000, "operator": "Jane Doe", "lines": 2048, "gain": 0.5}
    out = write_capture(tmp_path / f"cap.{ext}", cols, metadata=meta)
    cap = read_capture(out)
    assert cap.names == list(cols)
    assert len(cap) == 257
    for k, v in cols.items():
        assert _bits_equal(cap[k], v), k
    assert cap.metadata == meta


@pytest.mark.parametrize("ext", ["npz", "h5", "tdms"])
def test_roundtrip_integer_and_float32_columns(tmp_path, ext):
    cols = {"n": np.arange(-5, 95, dtype=np.int32), "f": np.linspace(0, 1, 100, dtype=np.float32)}
    cap = read_capture(write_capture(tmp_path / f"c.{ext}", cols))
    np.testing.assert_array_equal(cap["n"], np.arange(-5, 95).astype(np.float64))
    assert _bits_equal(cap["f"], cols["f"].astype(np.float64))


@settings(max_examples=25, deadline=None)
@given(
    x=arrays(
        np.float64,
        st.integers(1, 30),
        elements=st.floats(allow_nan=False, allow_infinity=False, width=64),
    )
)
def test_csv_roundtrip_any_finite_float(tmp_path_factory, x):
    path = tmp_path_factory.mktemp("csv") / "x.csv"
    write_capture(path, {"x": x, "y": x[::-1].copy()})
    cap = read_capture(path)
    assert _bits_equal(cap["x"], x)
    assert _bits_equal(cap["y"], x[::-1].copy())


def test_hdf5_group_roundtrip(tmp_path):
    cols = _columns(50)
    path = write_capture(tmp_path / "g.hdf5", cols, group="run1/enc")
    with h5py.File(path) as f:  # independent: the datasets are where the contract says
        np.testing.assert_array_equal(f["run1/enc/a"][...], cols["a"])
    cap = read_capture(path, group="run1/enc")
    assert all(_bits_equal(cap[k], cols[k]) for k in cols)


def test_tdms_default_group_is_capture(tmp_path):
    from nptdms import TdmsFile

    path = write_capture(tmp_path / "t.tdms", {"a": np.arange(3.0)})
    assert [g.name for g in TdmsFile.read(path).groups()] == ["capture"]


def test_npz_and_hdf5_reads_are_memory_mapped_and_read_only(tmp_path):
    cols = _columns(100)
    for ext in ("npz", "h5"):
        cap = read_capture(write_capture(tmp_path / f"m.{ext}", cols))
        arr = cap["a"]
        assert isinstance(arr.base, np.memmap) or isinstance(arr, np.memmap)
        assert not arr.flags.writeable


# --- files written by the third-party libraries themselves ------------------------------------


def test_reads_h5py_file(tmp_path):
    path = tmp_path / "daq.h5"
    t = np.arange(40) * 0.01
    with h5py.File(path, "w") as f:
        f["time_s"] = t
        f.create_dataset("ch1", data=np.cos(t), chunks=(7,), compression="gzip")
        f["ch2"] = np.sin(t).astype(">f8")  # big-endian
        f["counts"] = np.arange(40, dtype=np.uint16)
        f["sub/deep/x"] = np.arange(5.0)
        f.attrs["fs_hz"] = 100.0
    cap = read_capture(path, mapping={"ch1": "a", "ch2": "b"})
    assert sorted(cap.names) == ["a", "b", "counts", "time_s"]  # h5py lists by name here
    np.testing.assert_array_equal(cap["a"], np.cos(t))
    np.testing.assert_array_equal(cap["b"], np.sin(t))
    np.testing.assert_array_equal(cap["counts"], np.arange(40.0))
    assert cap.metadata == {"fs_hz": 100.0}
    assert read_capture(path, group="sub/deep")["x"].tolist() == [0, 1, 2, 3, 4]


def test_reads_nptdms_file_with_two_segments(tmp_path):
    path = tmp_path / "daq.tdms"
    with TdmsWriter(str(path)) as w:
        w.write_segment(
            [
                RootObject({"site": "lab 2"}),
                GroupObject("Untitled", {"rate_hz": 10}),
                ChannelObject("Untitled", "t", np.array([0.0, 0.1, 0.2])),
                ChannelObject("Untitled", "ticks", np.array([1, 2, 3], dtype=np.int32)),
            ]
        )
        w.write_segment(
            [
                ChannelObject("Untitled", "t", np.array([0.3, 0.4])),
                ChannelObject("Untitled", "ticks", np.array([4, 5], dtype=np.int32)),
            ]
        )
    cap = read_capture(path, mapping=["t=time_s"])
    np.testing.assert_array_equal(cap["time_s"], [0.0, 0.1, 0.2, 0.3, 0.4])
    np.testing.assert_array_equal(cap["ticks"], [1, 2, 3, 4, 5])
    assert cap.metadata == {"site": "lab 2", "rate_hz": 10}
    assert capture_length(path, "ticks") == 5


@pytest.mark.parametrize("saver", [np.savez, np.savez_compressed])
def test_reads_numpy_savez(tmp_path, saver):
    path = tmp_path / "x.npz"
    saver(path, time_s=np.arange(6) / 4, a=np.arange(6, dtype=np.int64) - 3, b=np.ones(6, "<f4"))
    cap = read_capture(path, columns=["a", "time_s"])
    assert cap.names == ["a", "time_s"]
    assert "b" not in cap
    np.testing.assert_array_equal(cap["a"], [-3, -2, -1, 0, 1, 2])
    np.testing.assert_array_equal(cap["time_s"], np.arange(6) / 4)


def test_reads_hand_written_csv(tmp_path):
    path = tmp_path / "scope.csv"
    text = (
        "\ufeff# exported by scope XYZ\r\n"
        "# fs_hz: 2000\r\n"
        "#   free text: not metadata\r\n"
        "\r\n"
        " time_s , ch1 ,ch2   # s, V, V\r\n"
        "0.0, 1.5 ,-2e-3\r\n"
        "# a comment between data rows\r\n"
        "5e-4,1.25,  7 # inline note\r\n"
        "\r\n"
        "1e-3,1,0.5\r\n"
        "\r\n"
    )
    path.write_bytes(text.encode("utf-8"))
    cap = read_capture(path, mapping={"ch1": "a", "ch2": "b"}, columns=["time_s", "a", "b"])
    np.testing.assert_array_equal(cap["time_s"], [0.0, 5e-4, 1e-3])
    np.testing.assert_array_equal(cap["a"], [1.5, 1.25, 1.0])
    np.testing.assert_array_equal(cap["b"], [-2e-3, 7.0, 0.5])
    assert cap.metadata == {"fs_hz": 2000}  # free text and "key with spaces: ..." are not metadata
    assert capture_length(path, "a", mapping={"ch1": "a"}) == 3


def test_csv_written_by_numpy_savetxt(tmp_path):
    path = tmp_path / "np.txt"
    x = np.random.default_rng(3).standard_normal((20, 2))
    np.savetxt(path, x, delimiter=",", header="u,v", comments="", fmt="%.17g")
    cap = read_capture(path)
    assert _bits_equal(cap["u"], x[:, 0].copy())
    assert _bits_equal(cap["v"], x[:, 1].copy())


# --- mapping ----------------------------------------------------------------------------------


def test_parse_column_mapping():
    assert parse_column_mapping(["ch1=a", " ch2 = b "]) == {"ch1": "a", "ch2": "b"}
    assert parse_column_mapping([]) == {}


def test_mapping_swap_and_list_form(tmp_path):
    path = write_capture(tmp_path / "s.npz", {"a": np.zeros(3), "b": np.ones(3)})
    cap = read_capture(path, mapping=["a=b", "b=a"])
    np.testing.assert_array_equal(cap["a"], np.ones(3))
    np.testing.assert_array_equal(cap["b"], np.zeros(3))


def test_mapping_applies_before_columns_check(tmp_path):
    path = write_capture(tmp_path / "m.csv", {"t": np.arange(3.0), "ch1": np.arange(3.0) * 2})
    cap = read_capture(path, mapping={"ch1": "a", "t": "time_s"}, columns=["a"])
    assert cap.names == ["a"]
    assert cap.file_columns == ["time_s", "a"]
    np.testing.assert_array_equal(cap["a"], [0, 2, 4])


# --- ragged -----------------------------------------------------------------------------------


def test_ragged_csv_hand_written(tmp_path):
    path = tmp_path / "pulses.csv"
    path.write_text("head_0,head_1,head_2\n0.1,0.2,0.3\n1.1,1.2,\n2.1,,\n3.1,,\n\n")
    cap = read_capture(path, ragged=True)
    assert cap["head_0"].tolist() == [0.1, 1.1, 2.1, 3.1]
    assert cap["head_1"].tolist() == [0.2, 1.2]
    assert cap["head_2"].tolist() == [0.3]
    assert len(cap) == 4
    assert capture_length(path, "head_1") == 4  # CSV: the row count (longest column)


@pytest.mark.parametrize("ext", EXTS)
def test_ragged_roundtrip(tmp_path, ext):
    heads = {f"head_{i}": np.cumsum(np.full(10 - 2 * i, 0.25)) + i for i in range(3)}
    cap = read_capture(write_capture(tmp_path / f"r.{ext}", heads), ragged=True)
    for k, v in heads.items():
        assert _bits_equal(cap[k], v)


def test_ragged_npz_drops_trailing_nan_padding(tmp_path):
    path = tmp_path / "p.npz"
    np.savez(path, head_0=np.arange(5.0), head_1=np.array([0.5, 1.5, np.nan, np.nan]))
    cap = read_capture(path, ragged=True)
    assert cap["head_1"].tolist() == [0.5, 1.5]
    assert cap["head_0"].tolist() == [0, 1, 2, 3, 4]


# --- chunked reading --------------------------------------------------------------------------


def _chunk_files(tmp_path_factory) -> dict[str, object]:
    root = tmp_path_factory.mktemp("chunks")
    cols = _columns(203, seed=7)
    files: dict[str, object] = {ext: write_capture(root / f"c.{ext}", cols) for ext in EXTS}
    files["npz_compressed"] = root / "cz.npz"
    np.savez_compressed(files["npz_compressed"], **cols)  # type: ignore[arg-type]
    h5 = root / "chunked.h5"
    with h5py.File(h5, "w") as f:
        for k, v in cols.items():
            f.create_dataset(k, data=v, chunks=(16,), compression="gzip")
    files["h5_chunked"] = h5
    csv = root / "gaps.csv"  # blank and comment lines inside the data
    lines = ["# c", "time_s,a,b"]
    for i in range(203):
        lines.append(",".join(repr(float(cols[k][i])) for k in cols))
        if i % 37 == 5:
            lines += ["", "# note"]
    csv.write_text("\n".join(lines) + "\n\n")
    files["csv_gaps"] = csv
    return files


@pytest.fixture(scope="module")
def chunk_files(tmp_path_factory):
    return _chunk_files(tmp_path_factory)


@settings(max_examples=30, deadline=None)
@given(chunk_rows=st.integers(1, 260), kind=st.sampled_from([*EXTS, "npz_compressed"]))
def test_chunks_equal_whole(chunk_files, chunk_rows, kind):
    _check_chunks(chunk_files[kind], chunk_rows)


@settings(max_examples=10, deadline=None)
@given(chunk_rows=st.integers(1, 260), kind=st.sampled_from(["h5_chunked", "csv_gaps"]))
def test_chunks_equal_whole_awkward_layouts(chunk_files, chunk_rows, kind):
    _check_chunks(chunk_files[kind], chunk_rows)


def _check_chunks(path, chunk_rows):
    whole = read_capture(path, columns=["b", "time_s"])
    pieces = list(iter_capture_chunks(path, ["b", "time_s"], chunk_rows=chunk_rows))
    assert all(len(p["b"]) == len(p["time_s"]) <= chunk_rows for p in pieces)
    assert len(pieces) == -(-203 // chunk_rows)
    for k in ("b", "time_s"):
        joined = np.concatenate([p[k] for p in pieces])
        assert _bits_equal(joined, np.asarray(whole[k]))
    assert capture_length(path, "b") == 203


def test_chunks_with_mapping_and_group(tmp_path):
    path = write_capture(tmp_path / "g.tdms", {"ch": np.arange(10.0)}, group="daq")
    pieces = list(iter_capture_chunks(path, ["x"], chunk_rows=4, mapping={"ch": "x"}, group="daq"))
    assert [p["x"].tolist() for p in pieces] == [[0, 1, 2, 3], [4, 5, 6, 7], [8, 9]]


def test_capture_object():
    cap = Capture(columns={"t": np.arange(3.0), "u": np.arange(5.0)}, source="dir/c.csv")
    assert cap.names == ["t", "u"]
    assert len(cap) == 5
    assert "t" in cap and "a" not in cap


@pytest.mark.parametrize("n", [1, 7, 1001])
def test_npz_columns_are_written_aligned_and_read_by_numpy(tmp_path, n):
    """rotacal's NPZ pads each member's local header so the data start on 64 bytes: the
    mapped columns are aligned arrays (NumPy's fast paths); the archive stays what np.savez
    writes, for np.load and zipfile."""
    cols = {name: np.arange(float(n)) * (i + 1) for i, name in enumerate(["time_s", "a", "b_é"])}
    path = write_capture(tmp_path / "c.npz", cols, metadata={"unit": "V"})
    cap = read_capture(path)
    with np.load(path) as raw, zipfile.ZipFile(path) as zf:
        assert zf.testzip() is None
        for name, values in cols.items():
            assert cap[name].ctypes.data % 64 == 0 and cap[name].flags.aligned
            np.testing.assert_array_equal(cap[name], values)
            np.testing.assert_array_equal(raw[name], values)
