"""rotacal.io.outputs: every file whole or not at all, never over an input, one winner in a race."""

from __future__ import annotations

import errno
import multiprocessing
import os
import stat
import textwrap
from pathlib import Path

import pytest

from rotacal.errors import ConfigError
from rotacal.io import outputs
from rotacal.io.outputs import (
    InputFile,
    Output,
    check_folder,
    check_outputs,
    write_output,
    write_outputs,
)


def _names(folder: Path) -> list[str]:
    """Every entry of the folder, hidden temporaries included."""
    return sorted(p.name for p in folder.iterdir())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# --------------------------------------------------------------------------------- plain writing
def test_text_bytes_and_writer_are_written_whole_with_the_usual_mode(tmp_path):
    write_output(tmp_path / "t.json", "ünïcode\n")
    write_output(tmp_path / "b.bin", b"\x00\x01\xff")
    write_output(tmp_path / "w.txt", lambda p: p.write_text("by name"))
    assert (tmp_path / "t.json").read_bytes() == "ünïcode\n".encode()
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01\xff"
    assert (tmp_path / "w.txt").read_text() == "by name"
    assert stat.S_IMODE((tmp_path / "t.json").stat().st_mode) == 0o666 & ~_umask()
    assert _names(tmp_path) == ["b.bin", "t.json", "w.txt"]


def test_a_long_name_still_gets_its_temporary(tmp_path):
    name = "x" * 250 + ".json"  # the temporary's prefix is cut to fit NAME_MAX (255)
    write_output(tmp_path / name, "{}")
    assert _names(tmp_path) == [name]


def test_missing_folders_are_made_only_when_asked(tmp_path):
    with pytest.raises(ConfigError, match="does not exist; create it"):
        write_output(tmp_path / "a" / "b.json", "{}")
    assert _names(tmp_path) == []
    write_output(tmp_path / "a" / "b" / "c.json", "{}", make_folders=True)
    assert (tmp_path / "a" / "b" / "c.json").read_text() == "{}"


# ------------------------------------------------------------------------ existing files, inputs
def test_an_existing_file_is_kept_without_overwrite(tmp_path):
    out = tmp_path / "r.json"
    out.write_text("keep me")
    with pytest.raises(ConfigError, match=r"r\.json already exists; choose another name or pass"):
        write_output(out, "new")
    assert out.read_text() == "keep me"
    assert _names(tmp_path) == ["r.json"]


def test_overwrite_replaces_the_file_not_its_bytes(tmp_path):
    """A new file takes the name: a hard link to the old one keeps the old content."""
    out = tmp_path / "r.json"
    out.write_text("old")
    os.link(out, tmp_path / "keep.json")
    inode = out.stat().st_ino
    write_output(out, "new", overwrite=True)
    assert out.read_text() == "new" and out.stat().st_ino != inode
    assert (tmp_path / "keep.json").read_text() == "old"


def test_overwrite_through_a_symlink_replaces_its_target(tmp_path):
    (tmp_path / "real.json").write_text("old")
    (tmp_path / "link.json").symlink_to("real.json")
    write_output(tmp_path / "link.json", "new", overwrite=True)
    assert (tmp_path / "link.json").is_symlink()
    assert (tmp_path / "real.json").read_text() == "new"
    assert _names(tmp_path) == ["link.json", "real.json"]


@pytest.mark.parametrize("way", ["same path", "symlink", "hard link", "via a linked folder"])
def test_an_input_is_never_replaced(tmp_path, way):
    data = tmp_path / "data"
    data.mkdir()
    capture = data / "run.csv"
    capture.write_bytes(b"precious")
    target = {
        "same path": capture,
        "symlink": tmp_path / "link.csv",
        "hard link": tmp_path / "hard.csv",
        "via a linked folder": tmp_path / "dlink" / "run.csv",
    }[way]
    if way == "symlink":
        target.symlink_to(capture)
    elif way == "hard link":
        os.link(capture, target)
    elif way == "via a linked folder":
        (tmp_path / "dlink").symlink_to(data)
    before = _names(tmp_path)
    with pytest.raises(ConfigError) as e:
        write_output(
            target,
            "result",
            label=f"--json {target.name}",
            overwrite=True,
            inputs=[InputFile(capture, "CAPTURE run.csv")],
        )
    assert str(e.value).startswith(
        f"--json {target.name} would overwrite the input CAPTURE run.csv"
    )
    assert "not even with --overwrite" in str(e.value)
    assert capture.read_bytes() == b"precious"
    assert _names(tmp_path) == before and _names(data) == ["run.csv"]


def test_two_outputs_cannot_share_a_file(tmp_path):
    (tmp_path / "sub").mkdir()
    other = tmp_path / "sub" / ".." / "a.json"
    with pytest.raises(
        ConfigError, match=r"--json a\.json and --report b\.json name the same file"
    ):
        check_outputs([(tmp_path / "a.json", "--json a.json"), (other, "--report b.json")])
    (tmp_path / "a.json").write_text("old")
    os.link(tmp_path / "a.json", tmp_path / "b.json")
    with pytest.raises(
        ConfigError, match=r"--json a\.json and --report b\.json name the same file"
    ):
        write_outputs(
            [
                Output(tmp_path / "a.json", "1", "--json a.json"),
                Output(tmp_path / "b.json", "2", "--report b.json"),
            ],
            overwrite=True,
        )
    assert (tmp_path / "a.json").read_text() == "old"


# --------------------------------------------------------------------------- paths refused early
def test_a_path_under_a_regular_file_is_refused(tmp_path):
    (tmp_path / "cap.csv").write_text("t\n1\n")
    for make in (False, True):
        with pytest.raises(ConfigError, match=r"cap\.csv is a file, not a folder"):
            check_outputs(
                [(tmp_path / "cap.csv" / "sub" / "o.json", "--json o")], make_folders=make
            )
    with pytest.raises(ConfigError, match="is a file, not a folder"):
        check_folder(tmp_path / "cap.csv" / "demo", label="--out")
    assert _names(tmp_path) == ["cap.csv"]


@pytest.mark.parametrize("overwrite", [False, True])
def test_a_dangling_symlink_is_not_followed(tmp_path, overwrite):
    (tmp_path / "out.json").symlink_to(tmp_path / "elsewhere.json")
    (tmp_path / "gone").symlink_to(tmp_path / "missing")
    for target in (tmp_path / "out.json", tmp_path / "gone" / "out.json"):
        with pytest.raises(ConfigError, match="dangling symbolic link"):
            write_output(target, "x", overwrite=overwrite, make_folders=True)
    with pytest.raises(ConfigError, match="dangling symbolic link"):
        check_folder(tmp_path / "gone" / "demo", label="--out")
    assert _names(tmp_path) == ["gone", "out.json"]  # nothing created at either target


def test_folders_and_devices_are_not_output_files(tmp_path):
    with pytest.raises(ConfigError, match="is a folder; give a file name"):
        write_output(tmp_path, "x", overwrite=True)
    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(ConfigError, match="not a regular file"):
        write_output(tmp_path / "pipe", "x", overwrite=True)
    with pytest.raises(ConfigError, match="not a regular file"):
        write_output("/dev/null", "x", overwrite=True)
    with pytest.raises(ConfigError, match=r"^--json needs a file name$"):
        write_output("", "x", label="--json ")


def test_permission_bits_are_honoured(tmp_path, bound_by_permissions):
    """A folder without write permission, and a write-protected file even with overwrite.

    As root the permission bits do not stop a write; in a child process they bind (it cannot create
    a file there by itself) rotacal gives its one-line refusals.
    """
    folder = tmp_path / "ro"
    folder.mkdir()
    (folder / "signed.json").write_text("signed")
    (tmp_path / "protected.json").write_text("signed")
    os.chmod(tmp_path / "protected.json", 0o444)
    os.chmod(folder, 0o555)
    code = textwrap.dedent(
        f"""
        from pathlib import Path
        from rotacal.errors import ConfigError
        from rotacal.io.outputs import write_output
        for path, overwrite in (({str(folder / "new.json")!r}, False),
                                ({str(folder / "signed.json")!r}, True),
                                ({str(tmp_path / "protected.json")!r}, True)):
            try:
                write_output(path, "x", overwrite=overwrite)
                print("written", path)
            except ConfigError as e:
                print(e)
        """
    )
    try:
        p = bound_by_permissions(["-c", code], unwritable=folder)
    finally:
        os.chmod(folder, 0o755)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert f"no permission to write in folder {folder}" in lines[0], lines
    assert f"no permission to write in folder {folder}" in lines[1]
    assert "protected.json is write-protected" in lines[2]
    assert _names(folder) == ["signed.json"] and (folder / "signed.json").read_text() == "signed"
    assert (tmp_path / "protected.json").read_text() == "signed"


# ----------------------------------------------------------------------------- failures, crashes
@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_a_writer_that_fails_midway_leaves_nothing(tmp_path, error):
    def half_then_fail(path: Path) -> None:
        path.write_text("half a fi")
        raise error

    with pytest.raises(type(error)):
        write_output(tmp_path / "r.json", half_then_fail)
    assert _names(tmp_path) == []


def test_a_system_refusal_mid_write_is_one_line_and_leaves_nothing(tmp_path):
    def disk_full(path: Path) -> None:
        path.write_text("half")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    with pytest.raises(ConfigError, match=r"cannot write --json r\.json: No space left on device"):
        write_output(tmp_path / "r.json", disk_full, label="--json r.json")
    assert _names(tmp_path) == []


def test_files_that_belong_together_appear_together_or_not_at_all(tmp_path):
    """Another process takes the second name while the first file is written: neither stays."""
    cap, truth = tmp_path / "x.csv", tmp_path / "x.csv.truth.json"

    def capture_while_someone_takes_the_truth_name(path: Path) -> None:
        path.write_text("t\n1\n")
        truth.write_text("theirs")

    with pytest.raises(ConfigError, match="was created by another process meanwhile"):
        write_outputs(
            [Output(cap, capture_while_someone_takes_the_truth_name), Output(truth, "{}")]
        )
    assert _names(tmp_path) == ["x.csv.truth.json"] and truth.read_text() == "theirs"
    write_outputs([Output(tmp_path / "y.csv", "t\n"), Output(tmp_path / "y.csv.truth.json", "{}")])
    assert _names(tmp_path) == ["x.csv.truth.json", "y.csv", "y.csv.truth.json"]


# ------------------------------------------------------------------------------ concurrent writers
def _race(path: str, me: int, barrier, results) -> None:  # type: ignore[no-untyped-def]
    def content(tmp: Path) -> None:
        tmp.write_text(f"writer {me}\n" * 1000)
        barrier.wait(timeout=60)  # every writer has passed the checks and written its file

    try:
        write_output(path, content, label="--json out.json")
        results.put((me, "ok"))
    except ConfigError as e:
        results.put((me, str(e)))


def _no_hard_links(*args, **kwargs):  # type: ignore[no-untyped-def]
    raise OSError(errno.EPERM, "Operation not permitted (no hard links here)")


@pytest.mark.parametrize("commit", ["hard link", "renameat2", "claim, then rename"])
def test_ten_concurrent_writers_exactly_one_wins(tmp_path, monkeypatch, commit):
    if commit != "hard link":
        monkeypatch.setattr(os, "link", _no_hard_links)  # a file system without hard links
    if commit == "claim, then rename":
        monkeypatch.setattr(outputs, "_rename_noreplace", lambda src, dst: False)
    ctx = multiprocessing.get_context("fork")  # the children inherit the file system's quirks
    barrier, results = ctx.Barrier(10), ctx.Queue()
    out = tmp_path / "out.json"
    procs = [ctx.Process(target=_race, args=(str(out), i, barrier, results)) for i in range(10)]
    for p in procs:
        p.start()
    got = dict(results.get(timeout=120) for _ in procs)
    for p in procs:
        p.join(timeout=60)
    winners = [me for me, r in got.items() if r == "ok"]
    assert len(winners) == 1, got
    for me, r in got.items():
        if me != winners[0]:
            assert r == (
                "--json out.json was created by another process meanwhile; choose another name "
                "or pass --overwrite"
            )
    assert out.read_text() == f"writer {winners[0]}\n" * 1000
    assert _names(tmp_path) == ["out.json"]


def test_without_hard_links_renameat2_keeps_the_creation_exclusive(tmp_path, monkeypatch):
    calls = []
    real = outputs._rename_noreplace

    def spy(src: Path, dst: Path) -> bool:
        calls.append(dst)
        return real(src, dst)

    monkeypatch.setattr(os, "link", _no_hard_links)
    monkeypatch.setattr(outputs, "_rename_noreplace", spy)
    write_output(tmp_path / "a.json", "1")
    with pytest.raises(ConfigError, match="already exists"):
        write_output(tmp_path / "a.json", "2")
    assert calls == [tmp_path / "a.json"] and (tmp_path / "a.json").read_text() == "1"
    # the name taken between the check and the rename: renameat2 refuses, the file is kept
    tmp = tmp_path / ".b.tmp"
    tmp.write_text("mine")
    (tmp_path / "b.json").write_text("theirs")
    with pytest.raises(FileExistsError):
        outputs._link_exclusive(tmp, tmp_path / "b.json")
    assert (tmp_path / "b.json").read_text() == "theirs"


def _replace_repeatedly(path: str, size: int, rounds: int) -> None:
    for i in range(rounds):
        write_output(path, bytes([65 + i % 26]) * size, overwrite=True)


def test_overwrite_is_atomic_for_a_concurrent_reader(tmp_path):
    """Readers see the old file or the whole new one: never a short or mixed one."""
    out, size, rounds = tmp_path / "r.bin", 1 << 20, 40
    write_output(out, b"@" * size)
    ctx = multiprocessing.get_context("fork")
    writer = ctx.Process(target=_replace_repeatedly, args=(str(out), size, rounds))
    writer.start()
    seen = set()
    while writer.is_alive() or not seen:
        data = out.read_bytes()
        assert len(data) == size and data == data[:1] * size, (len(data), set(data))
        seen.add(data[:1])
    writer.join()
    assert writer.exitcode == 0
    assert out.read_bytes() == bytes([65 + (rounds - 1) % 26]) * size
    assert _names(tmp_path) == ["r.bin"]
    assert len(seen) > 1  # the reader did overlap the writer
