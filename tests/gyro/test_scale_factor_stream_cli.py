"""`rotacal gyro scale-factor --chunked`: the streamed command gives the in-memory JSON (pooled
logs, one file per set rate, the 0 °/s point from runs at rest) and picks itself above a size."""

from __future__ import annotations

import json

import numpy as np
import pytest
from tests.cli.test_gyro_cli import one_line_error, run
from tests.cli.test_rate_files_cli import RATES, _plateau_files
from tests.gyro.test_scale_factor_stream import _same_result

import rotacal.gyro
from rotacal.cli import _rate_files
from rotacal.cli import gyro as gyro_cli


class _AsResult:
    """A JSON result dressed as the object :func:`_same_result` compares."""

    def __init__(self, data: dict) -> None:
        self.data, self.warnings = data, ()

    def to_dict(self) -> dict:
        return json.loads(json.dumps(self.data))


def _json(*args):
    r = run(*args, "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    d.pop("provenance", None)
    return d


@pytest.fixture
def small_chunks(monkeypatch):
    monkeypatch.setattr(_rate_files, "CHUNK_ROWS", 173)


def test_pooled_logs_stream_to_the_same_json(tmp_path, small_chunks):
    rng = np.random.default_rng(3)
    paths = []
    for k, rates in enumerate((np.arange(-100.0, 1.0, 20.0), np.arange(20.0, 101.0, 20.0))):
        rate = np.repeat(rates, 300)
        out = 2.5 + 0.0125 * rate + 4e-8 * rate**3 + rng.normal(0, 6e-4, rate.size)
        path = tmp_path / f"log{k}.npz"
        np.savez(path, time_s=np.arange(rate.size) * 0.01, rate_deg_s=rate, output=out)
        paths.append(str(path))
    args = ("gyro", "scale-factor", *paths, "--requirement", "fmvss126")
    args += ("--sample-rate-hz", "100", "--bandwidth-hz", "10")
    memory, streamed = _json(*args, "--in-memory"), _json(*args, "--chunked")
    assert [p["n"] for p in streamed["points"]] == [300] * 11
    _same_result(_AsResult(memory), _AsResult(streamed))


def test_one_file_per_rate_streams_to_the_same_json(tmp_path, small_chunks):
    paths, s_true, _ = _plateau_files(tmp_path)
    args = ("gyro", "scale-factor", *map(str, paths), "--column", "col_3=output")
    args += ("--rate-from-name",)
    memory, streamed = _json(*args, "--in-memory"), _json(*args, "--chunked")
    assert streamed["scale_factor"] == pytest.approx(s_true, rel=1e-4)
    _same_result(_AsResult(memory), _AsResult(streamed))


def test_the_rest_runs_stream_to_the_same_zero_point(shared_data, small_chunks):
    files = shared_data("xinli_turntable") / "data"
    args = ["gyro", "scale-factor", "--rate-from-name", "--column", "col_5=output"]
    args += [str(files / f"{pre}{r}.dat") for r in RATES for pre in ("p", "m")]
    for f in sorted(files.glob("*turn.dat")):
        args += ["--rest-from", str(f)]
    memory, streamed = _json(*args, "--in-memory"), _json(*args, "--chunked")
    zero = next(p for p in streamed["points"] if p["rate_deg_s"] == 0.0)
    assert zero["n"] == 4345  # as in memory (tests/cli/test_rate_files_cli.py)
    _same_result(_AsResult(memory), _AsResult(streamed))


def test_the_command_streams_by_itself_above_a_size(tmp_path, monkeypatch):
    path = tmp_path / "rates.npz"
    assert run("simulate", "gyro-rates", "--out", str(path)).exit_code == 0
    calls = []
    chunked = rotacal.gyro.calibrate_scale_factor_chunked

    def spy(*a, **kw):
        calls.append(1)
        return chunked(*a, **kw)

    monkeypatch.setattr(rotacal.gyro, "calibrate_scale_factor_chunked", spy)
    _json("gyro", "scale-factor", str(path))
    assert calls == []
    monkeypatch.setattr(gyro_cli, "_SCALE_FACTOR_IN_MEMORY_MAX_ROWS", 1000)
    _json("gyro", "scale-factor", str(path))
    assert calls == [1]


def test_streamed_faults_are_one_line_naming_the_file(tmp_path, small_chunks):
    paths, _, _ = _plateau_files(tmp_path)
    base = ["gyro", "scale-factor", *map(str, paths), "--column", "col_3=output", "--chunked"]
    one_line_error(run(*base), "p10.dat has no column 'rate_deg_s'", "--rate-from-name or --rates")
    one_line_error(run(*base, base[3], "--rate-from-name"), f"{base[3]} is given twice")
    flat = tmp_path / "p0.dat"
    flat.write_text("\n".join(f"{0.1 * i}\t7.0\t0.31" for i in range(50)))
    one_line_error(run(*base, "--rest-from", str(flat)), "--rest-from", "--rate-from-name")
    one_line_error(
        run(*base, "--rate-from-name", "--rest-from", str(flat)), "p0.dat", "never leaves"
    )
