"""`rotacal motion encoder` checks the capture's values and CRC-32s on a second thread while it
analyses the columns (rotacal.io.read_capture_deferred): a fault of the file must still be the one
line that reading the file alone (read_capture, the truth here) gives, and nothing is written."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.errors import CaptureError
from rotacal.io import DeferredChecks, read_capture, read_capture_deferred, write_capture

FS = 50_000.0


def _rows(n_periods: float = 4.0) -> dict[str, np.ndarray]:
    t = np.arange(0, n_periods / 2.0, 1.0 / FS)
    phi = 2 * np.pi * 36000 * 0.5 * np.sin(2 * np.pi * 2.0 * t) / 360
    return {"time_s": t, "a": np.cos(phi), "b": np.sin(phi)}


def _read_error(path) -> str:
    with pytest.raises(CaptureError) as ei:
        read_capture(path, columns=["time_s", "a", "b"])
    return str(ei.value)


def _cli_error(path, tmp_path) -> str:
    out = tmp_path / "out.json"
    r = CliRunner().invoke(
        cli, ["motion", "encoder", str(path), "--lines", "36000", "--json", str(out)]
    )
    assert r.exit_code == 2, r.output
    assert not out.exists()  # nothing written from a damaged capture
    err = r.stderr.strip()
    assert "\n" not in err and "Traceback" not in r.output, err
    return err


def _deferred(path) -> DeferredChecks:
    _, checks = read_capture_deferred(path, columns=["time_s", "a", "b"])
    assert checks._thread is not None  # the threaded path is the one under test
    return checks


@pytest.mark.parametrize("column", ["time_s", "a", "b"])
def test_a_nan_row_is_the_fault_reported(tmp_path, column):
    cols = _rows()
    cols[column][1234] = np.nan
    path = write_capture(tmp_path / "n.npz", cols)
    _deferred(path)
    expected = _read_error(path)
    assert "row 1234" in expected and "not a finite number" in expected
    assert _cli_error(path, tmp_path) == f"rotacal: error: {expected}"


def test_a_damaged_member_is_the_fault_reported(tmp_path):
    good = write_capture(tmp_path / "g.npz", _rows())
    data = bytearray(good.read_bytes())
    a = _rows()["a"]
    at = data.index(a[:4].tobytes()) + 8 * 3000 + 3  # a low bit of a mantissa: still finite
    data[at] ^= 0x01
    bad = tmp_path / "bad.npz"
    bad.write_bytes(bytes(data))
    _deferred(bad)
    expected = _read_error(bad)
    assert "CRC-32" in expected and "'a.npy'" in expected
    assert _cli_error(bad, tmp_path) == f"rotacal: error: {expected}"


def test_the_checks_supersede_the_analysis_error(tmp_path):
    cols = _rows(1.0)
    cols["b"][7] = np.inf
    path = write_capture(tmp_path / "i.npz", cols)
    checks = _deferred(path)
    with pytest.raises(CaptureError, match="holds inf at row 7"):
        with checks:
            raise ValueError("what an analysis of the damaged values said")


def test_columns_are_those_of_read_capture(tmp_path):
    path = write_capture(tmp_path / "g.npz", _rows(1.0))
    cap, checks = read_capture_deferred(path)
    with checks:
        pass
    whole = read_capture(path)
    assert list(cap.columns) == list(whole.columns)
    for name, col in whole.columns.items():
        np.testing.assert_array_equal(cap[name], col)


def test_columns_that_need_converting_are_checked_at_once(tmp_path):
    cols = _rows(1.0)
    cols["a"] = np.round(cols["a"] * 1000).astype(np.int32)  # int: converted, checked in place
    cols["b"][5] = np.nan
    path = tmp_path / "c.npz"
    np.savez(path, **cols)
    with pytest.raises(CaptureError) as ei:
        read_capture_deferred(path, columns=["time_s", "a", "b"])
    assert str(ei.value) == _read_error(path)
