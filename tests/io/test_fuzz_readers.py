"""Fuzzing the capture readers: a damaged file ends in CaptureError/ConfigError, nothing else.

Small valid seed files of every format are written by rotacal's own writer and by NumPy, h5py
and npTDMS directly (compressed NPZ, HDF5 groups with attributes and filtered datasets, TDMS with
several groups and segments). Each example damages one seed with one to three mutations (bit
flips, truncation, inserted, deleted or repeated bytes, header fields overwritten with extreme
integers, NPZ array headers damaged under a correct zip CRC, CSV cells replaced by odd text) and
runs it through ``read_capture``, ``iter_capture_chunks`` and ``capture_length``. Any exception
other than CaptureError/ConfigError fails the test, as does any Python warning or log line that
would reach a user's terminal.

The mutation engine here is also driven by ``benchmarks/fuzz_readers.py`` (10⁵ inputs per reader
from a plain seeded ``random.Random``). In this test Hypothesis draws, per example, the seed file
and the seed of the ``random.Random`` that drives the mutations of a batch of files (a batch
keeps Hypothesis's own cost per file small: the whole file runs in well under a minute on one
core); it is derandomized, so every run damages the same files, and a failure names the
example that reproduces it.
"""

from __future__ import annotations

import gc
import io
import logging
import os
import random
import shutil
import struct
import tempfile
import warnings
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from rotacal.errors import CaptureError, ConfigError
from rotacal.io import capture_length, iter_capture_chunks, read_capture, write_capture

#: the readers the benchmark reports on, and the seeds of each
READERS = ("csv", "npz-stored", "npz-compressed", "hdf5", "tdms")
# 1000 damaged files per reader here (each run the same ones); the depth is the benchmark's 10⁵
EXAMPLES_PER_READER = 250
FILES_PER_EXAMPLE = 4
CHUNK_ROWS = 37  # small, so that a column crosses several chunks


@dataclass(frozen=True)
class Seed:
    """A small valid capture and what the fuzzer needs to know to damage and read it."""

    name: str
    reader: str
    ext: str
    data: bytes
    columns: tuple[str, ...]
    group: str | None = None
    ragged: bool = False
    #: (offset, length) spans of header fields worth overwriting
    regions: tuple[tuple[int, int], ...] = ()
    #: NPZ only: member name -> .npy bytes, and the zip compression, to rebuild with a valid CRC
    members: dict[str, bytes] = field(default_factory=dict)
    compression: int = zipfile.ZIP_STORED


# --- seeds ------------------------------------------------------------------------------------


def _signature_regions(data: bytes, signatures: dict[bytes, int]) -> list[tuple[int, int]]:
    """Spans of ``length`` bytes starting at every occurrence of each signature."""
    spans = []
    for sig, length in signatures.items():
        at = data.find(sig)
        while at >= 0:
            spans.append((at, min(length, len(data) - at)))
            at = data.find(sig, at + 1)
    return spans


def _npy_regions(data: bytes) -> list[tuple[int, int]]:
    spans = []
    at = data.find(b"\x93NUMPY")
    while at >= 0:
        end = data.find(b"\n", at)
        spans.append((at, (end if end > at else at + 128) - at + 1))
        at = data.find(b"\x93NUMPY", at + 1)
    return spans


def _columns(rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
    t = np.arange(n) / 1000.0
    return {"time_s": t, "a": np.cos(t * 40.0), "b": rng.normal(size=n)}


def _csv_seeds(tmp: Path, rng: np.random.Generator) -> list[Seed]:
    seeds = []
    # past 8 KiB (where a late non-UTF-8 byte once escaped as UnicodeDecodeError)
    path = write_capture(tmp / "w.csv", _columns(rng, 300), metadata={"fs_hz": 1000, "op": "x"})
    data = path.read_bytes()
    head = data.index(b"time_s")
    seeds.append(
        Seed("csv-writer", "csv", ".csv", data, ("time_s", "a", "b"), regions=((0, head + 16),))
    )
    path = write_capture(tmp / "p.csv", {"head_0": np.arange(40.0), "head_1": np.arange(33.0)})
    seeds.append(
        Seed("csv-ragged", "csv", ".csv", path.read_bytes(), ("head_0", "head_1"), ragged=True)
    )
    lines = [
        "\ufeff# made by hand: CRLF, comments, blank lines, integers",
        "# fs_hz: 10",
        "t, x ,y",
    ]
    lines += [f"{i},{i * i},{-i}" if i % 7 else "" for i in range(60)]
    data = "\r\n".join(lines).encode("utf-8")
    seeds.append(Seed("csv-crlf", "csv", ".csv", data, ("t", "x", "y"), regions=((0, 80),)))
    return seeds


def _npz_seed(name: str, reader: str, data: bytes, columns: tuple[str, ...], **kw: object) -> Seed:
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        members = {i.filename: zf.read(i) for i in zf.infolist()}
        compression = zf.infolist()[0].compress_type
    regions = _signature_regions(data, {b"PK\x03\x04": 30, b"PK\x01\x02": 46, b"PK\x05\x06": 22})
    regions += _npy_regions(data)
    return Seed(
        name,
        reader,
        ".npz",
        data,
        columns,
        regions=tuple(regions),
        members=members,
        compression=compression,
        **kw,  # type: ignore[arg-type]
    )


def _npz_seeds(tmp: Path, rng: np.random.Generator) -> list[Seed]:
    cols = _columns(rng, 200)
    path = write_capture(tmp / "w.npz", cols, metadata={"fs_hz": 1000})
    seeds = [_npz_seed("npz-writer", "npz-stored", path.read_bytes(), ("time_s", "a", "b"))]
    buf = io.BytesIO()
    np.savez(buf, t=np.arange(150, dtype=np.int32), x=cols["a"][:150].astype(">f8"))
    seeds.append(_npz_seed("npz-mixed-dtypes", "npz-stored", buf.getvalue(), ("t", "x")))
    buf = io.BytesIO()
    np.savez(buf, head_0=np.arange(50.0), head_1=np.arange(41.0))
    seeds.append(
        _npz_seed("npz-ragged", "npz-stored", buf.getvalue(), ("head_0", "head_1"), ragged=True)
    )
    buf = io.BytesIO()
    np.savez_compressed(buf, time_s=cols["time_s"], a=cols["a"], n=np.arange(200, dtype=np.int16))
    seeds.append(_npz_seed("npz-compressed", "npz-compressed", buf.getvalue(), ("time_s", "a")))
    buf = io.BytesIO()
    np.savez_compressed(buf, x=cols["b"].astype(np.float32), y=np.zeros(200))
    seeds.append(_npz_seed("npz-compressed-f4", "npz-compressed", buf.getvalue(), ("x", "y")))
    return seeds


_HDF5_SIGNATURES = {
    b"\x89HDF\r\n\x1a\n": 96,  # superblock
    b"TREE": 48,
    b"HEAP": 32,
    b"SNOD": 48,
    b"OHDR": 64,
    b"OCHK": 32,
    b"FRHP": 64,
    b"FHDB": 32,
    b"BTHD": 48,
    b"BTLF": 32,
    b"GCOL": 32,
}


def _hdf5_seed(name: str, path: Path, columns: tuple[str, ...], group: str | None = None) -> Seed:
    data = path.read_bytes()
    regions = [*_signature_regions(data, _HDF5_SIGNATURES), (0, min(len(data), 2048))]
    return Seed(name, "hdf5", ".h5", data, columns, group=group, regions=tuple(regions))


def _hdf5_seeds(tmp: Path, rng: np.random.Generator) -> list[Seed]:
    cols = _columns(rng, 200)
    path = write_capture(tmp / "w.h5", cols, metadata={"fs_hz": 1000, "op": "x"})
    seeds = [_hdf5_seed("hdf5-writer", path, ("time_s", "a", "b"))]
    path = tmp / "groups.h5"
    with h5py.File(path, "w") as f:
        f.attrs["site"] = "lab"
        g = f.create_group("raw/enc")
        g.attrs["lines"] = 4096
        g.attrs["gain"] = np.array([1.0, 2.0])
        g["time_s"] = cols["time_s"]
        g.create_dataset("a", data=cols["a"], chunks=(64,), compression="gzip", shuffle=True)
        g.create_dataset("b", data=(cols["b"] * 1000).astype(np.int16), chunks=(50,))
        f["other/x"] = np.arange(10.0)
    seeds.append(_hdf5_seed("hdf5-groups", path, ("time_s", "a", "b"), group="raw/enc"))
    path = tmp / "latest.h5"
    with h5py.File(path, "w", libver="latest") as f:
        f.attrs["note"] = b"bytes attribute"
        f.create_dataset("t", data=cols["time_s"], chunks=(32,), fletcher32=True)
        f.create_dataset("y", data=cols["a"].astype(np.float32), compression="lzf")
    seeds.append(_hdf5_seed("hdf5-latest", path, ("t", "y")))
    return seeds


def _tdms_regions(data: bytes) -> list[tuple[int, int]]:
    spans = []
    for sig in (b"TDSm", b"TDSh"):
        at = data.find(sig)
        while at >= 0 and at + 28 <= len(data):
            raw_offset = struct.unpack_from("<Q", data, at + 20)[0]
            spans.append((at, int(min(28 + raw_offset, len(data) - at))))
            at = data.find(sig, at + 1)
    return spans


def _tdms_seed(name: str, path: Path, columns: tuple[str, ...], group: str | None = None) -> Seed:
    data = path.read_bytes()
    return Seed(
        name, "tdms", ".tdms", data, columns, group=group, regions=tuple(_tdms_regions(data))
    )


def _tdms_seeds(tmp: Path, rng: np.random.Generator) -> list[Seed]:
    cols = _columns(rng, 150)
    path = write_capture(tmp / "w.tdms", cols, metadata={"fs_hz": 1000, "op": "x"})
    seeds = [_tdms_seed("tdms-writer", path, ("time_s", "a", "b"))]
    path = tmp / "groups.tdms"
    with TdmsWriter(str(path)) as w:
        for part in (slice(0, 80), slice(80, 150)):  # two segments, appended data
            w.write_segment(
                [
                    RootObject(properties={"site": "lab"}),
                    GroupObject("enc", properties={"lines": 4096}),
                    GroupObject("fog", properties={"unit": "deg/s"}),
                    ChannelObject("enc", "time_s", cols["time_s"][part]),
                    ChannelObject("enc", "a", cols["a"][part].astype(np.float32)),
                    ChannelObject("fog", "rate", (cols["b"][part] * 100).astype(np.int32)),
                ]
            )
    seeds.append(_tdms_seed("tdms-groups", path, ("time_s", "a"), group="enc"))
    path = tmp / "i16.tdms"
    with TdmsWriter(str(path)) as w:
        w.write_segment([ChannelObject("g", "n", np.arange(120, dtype=np.int16))])
        w.write_segment([ChannelObject("g", "n", np.arange(30, dtype=np.int16))])
    seeds.append(_tdms_seed("tdms-i16", path, ("n",)))
    return seeds


def build_seeds(tmp: Path) -> dict[str, list[Seed]]:
    """Seeds by reader name (see READERS), written to and read back from ``tmp``."""
    tmp.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(20240612)
    every = _csv_seeds(tmp, rng) + _npz_seeds(tmp, rng) + _hdf5_seeds(tmp, rng)
    every += _tdms_seeds(tmp, rng)
    return {r: [s for s in every if s.reader == r] for r in READERS}


# --- mutations --------------------------------------------------------------------------------

_INTERESTING = (
    0, 1, 2, 7, 0x7F, 0x80, 0xFF, 0x100, 0x7FFF, 0x8000, 0xFFFF, 0x10000, 0x7FFFFFFF,
    0x80000000, 0xFFFFFFFF, 2**32, 2**40, 2**62, 2**63 - 1, 2**63, 2**64 - 1,
)  # fmt: skip
_TOKENS = (
    b",", b"\n", b"\r", b"\r\n", b"#", b'"', b" ", b"\t", b"\x00", b"\xff", b"\xc3", b"\xef\xbb\xbf",
    b"nan", b"inf", b"-inf", b"1e999", b"-1e-400", b"0x10", b"1_0", b"--1", b"1e", b".", b"",
    b"\xe2\x80\xa8", b"9" * 400, b"a,b", b",,", b"\n\n", b"# x: {", b"\\",
)  # fmt: skip


def _position(data: bytearray, seed: Seed, rng: random.Random) -> int:
    """A byte position: in a header field half the time when the seed has any."""
    if seed.regions and rng.random() < 0.5:
        off, length = rng.choice(seed.regions)
        return min(off + rng.randrange(max(length, 1)), max(len(data) - 1, 0))
    return rng.randrange(max(len(data), 1))


def _flip(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    for _ in range(rng.randint(1, 8)):
        if data:
            data[_position(data, seed, rng)] ^= 1 << rng.randrange(8)
    return data


def _truncate(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    return data[: rng.randrange(max(len(data), 1))]


def _insert(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    payload = rng.choice(_TOKENS) if rng.random() < 0.5 else rng.randbytes(rng.randint(1, 64))
    at = _position(data, seed, rng)
    return data[:at] + payload + data[at:]


def _delete(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    at = _position(data, seed, rng)
    return data[:at] + data[at + rng.choice((1, 2, 4, 8, rng.randint(1, 512))) :]


def _repeat(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    """Copy a slice of the file to another place (duplicated segments, spliced headers)."""
    lo = _position(data, seed, rng)
    piece = data[lo : lo + rng.randint(1, 256)]
    at = rng.randrange(len(data) + 1)
    return data[:at] + piece + data[at:]


def _overwrite_field(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    """Write an extreme integer (1, 2, 4 or 8 bytes, either byte order) over a header field."""
    if not data:
        return data
    width = rng.choice((1, 2, 4, 8))
    value = rng.choice(_INTERESTING) if rng.random() < 0.8 else rng.getrandbits(64)
    if rng.random() < 0.2:
        value = len(data) + rng.randint(-64, 64)  # near the file size
    raw = (value % (1 << (8 * width))).to_bytes(width, rng.choice(("little", "big")))
    at = _position(data, seed, rng)
    data[at : at + width] = raw
    return data


def _text_cell(data: bytearray, seed: Seed, rng: random.Random) -> bytearray:
    """Replace the text between two separators with an odd token (CSV)."""
    at = _position(data, seed, rng)
    lo = max(data.rfind(b",", 0, at), data.rfind(b"\n", 0, at)) + 1
    hi_candidates = [i for i in (data.find(b",", at), data.find(b"\n", at)) if i >= 0]
    hi = min(hi_candidates) if hi_candidates else len(data)
    return data[:lo] + rng.choice(_TOKENS) + data[hi:]


def _damaged_member(seed: Seed, rng: random.Random) -> bytearray:
    """Rebuild the NPZ with one member's .npy bytes damaged (the zip CRC then matches)."""
    name = rng.choice(sorted(seed.members))
    npy = bytearray(seed.members[name])
    end = npy.find(b"\n") + 1 if rng.random() < 0.7 else len(npy)
    member_seed = Seed("member", seed.reader, ".npy", bytes(npy), (), regions=((0, max(end, 1)),))
    for _ in range(rng.randint(1, 2)):
        npy = rng.choice((_flip, _overwrite_field, _insert, _delete, _text_cell))(
            npy, member_seed, rng
        )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=seed.compression) as zf:
        for member, raw in seed.members.items():
            zf.writestr(member, bytes(npy) if member == name else raw)
    return bytearray(buf.getvalue())


_BYTE_MUTATIONS: tuple[Callable[[bytearray, Seed, random.Random], bytearray], ...] = (
    _flip,
    _truncate,
    _insert,
    _delete,
    _repeat,
    _overwrite_field,
)


def mutate(seed: Seed, rng: random.Random) -> bytes:
    """One damaged copy of ``seed``: one to three mutations drawn from ``rng``."""
    data = bytearray(seed.data)
    if seed.members and rng.random() < 0.3:
        data = _damaged_member(seed, rng)
        if rng.random() < 0.7:
            return bytes(data)
    kinds = _BYTE_MUTATIONS + ((_text_cell,) * 3 if seed.reader == "csv" else ())
    for _ in range(rng.randint(1, 3)):
        data = rng.choice(kinds)(data, seed, rng)
    return bytes(data)


# --- running the readers ----------------------------------------------------------------------


class _LogCatcher(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


def _calls(path: Path, seed: Seed) -> Iterator[tuple[str, Callable[[], object]]]:
    yield "read_capture", lambda: read_capture(path, group=seed.group, ragged=seed.ragged)
    yield (
        "iter_capture_chunks",
        lambda: sum(
            1
            for _ in iter_capture_chunks(
                path, seed.columns, chunk_rows=CHUNK_ROWS, group=seed.group
            )
        ),
    )
    yield "capture_length", lambda: capture_length(path, seed.columns[-1], group=seed.group)


def run_readers(path: Path, seed: Seed) -> list[tuple[str, BaseException | str]]:
    """Run the three entry points on ``path``; return what escaped that a user must not see.

    Each item is (entry point, the untyped exception) or (entry point, text of a warning or log
    record that would be printed).
    """
    escaped: list[tuple[str, BaseException | str]] = []
    catcher = _LogCatcher()
    root = logging.getLogger()
    root.addHandler(catcher)
    try:
        for what, call in _calls(path, seed):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    call()
                except (CaptureError, ConfigError):
                    pass
                except Exception as exc:
                    escaped.append((what, exc))
            escaped += [(what, f"warning: {w.category.__name__}: {w.message}") for w in caught]
            escaped += [(what, f"log: {r.name}: {r.getMessage()}") for r in catcher.records]
            catcher.records.clear()
    finally:
        root.removeHandler(catcher)
    return escaped


def fuzz_dir() -> Path:
    """A scratch folder for the mutated files: in memory (/dev/shm) where there is one."""
    shm = Path("/dev/shm")
    base = shm if shm.is_dir() and os.access(shm, os.W_OK) else None
    return Path(tempfile.mkdtemp(prefix="rotacal-fuzz-", dir=base))


# --- the test ---------------------------------------------------------------------------------


@pytest.fixture(autouse=True)
def _earlier_tests_collected() -> None:
    """Collect what earlier tests on this worker left to the garbage collector first: an unclosed
    file or connection warns when it is collected, and that warning is not the readers'."""
    gc.collect()


@pytest.fixture(scope="module")
def scratch() -> Iterator[Path]:
    path = fuzz_dir()
    yield path
    shutil.rmtree(path, ignore_errors=True)


@pytest.fixture(scope="module")
def seeds(scratch: Path) -> dict[str, list[Seed]]:
    return build_seeds(scratch / "seeds")


def test_seeds_are_valid(seeds: dict[str, list[Seed]], scratch: Path) -> None:
    """Every seed reads cleanly: the damage, not the seed, is what the fuzz test exercises."""
    for reader in READERS:
        assert seeds[reader], reader
        for seed in seeds[reader]:
            path = scratch / f"seed{seed.ext}"
            path.write_bytes(seed.data)
            assert run_readers(path, seed) == [], seed.name
            cap = read_capture(path, group=seed.group, ragged=seed.ragged)
            assert set(seed.columns) <= set(cap.names), seed.name
            n = capture_length(path, seed.columns[-1], group=seed.group)
            padded = seed.ragged and seed.reader == "csv"  # rows of the longest column
            lengths = [len(cap[c]) for c in seed.columns]
            assert n == (max(lengths) if padded else lengths[-1]), seed.name


@pytest.mark.parametrize("reader", READERS)
def test_damaged_files_end_in_typed_errors(
    reader: str, seeds: dict[str, list[Seed]], scratch: Path
) -> None:
    pool = seeds[reader]

    @settings(
        max_examples=EXAMPLES_PER_READER,
        derandomize=True,
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(index=st.integers(0, len(pool) - 1), salt=st.integers(0, 2**32 - 1))
    def check(index: int, salt: int) -> None:
        seed = pool[index]
        rng = random.Random(salt)
        path = scratch / f"fuzz-{reader}{seed.ext}"
        for _ in range(FILES_PER_EXAMPLE):
            path.write_bytes(mutate(seed, rng))
            escaped = run_readers(path, seed)
            assert not escaped, (seed.name, escaped)

    check()
