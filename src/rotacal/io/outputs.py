"""Writing outputs: whole or not at all, never over an input, exactly one winner in a race.

Every file rotacal writes — ``--json``, ``--report``, a capture and its truth from ``rotacal
simulate``, the TOML examples, the files of ``rotacal demo`` — goes through :func:`write_outputs`.

1. :func:`check_outputs` (also the CLI's pre-flight, run before any analysis) refuses a path that
   names an input of the command — the same path once symbolic links are resolved, or the same file
   through a hard link — whether or not ``overwrite`` is given; a folder; something that is not a
   regular file (a device, a pipe); an existing file without ``overwrite`` and a write-protected one
   even with it; a dangling symbolic link anywhere in the path; a path under a regular file; and a
   folder this process may not write in (asked of the kernel with the effective ids, so read-only
   file systems and access control lists count, and root is not refused where it may write).
2. Each file is written to a hidden temporary file in its destination folder
   (``.NAME.<random>.tmp``), flushed to disk, and only then given its name. Without ``overwrite``
   by a hard link (where a file system has none, ``renameat2(RENAME_NOREPLACE)``), which fails if
   the name exists: of several processes writing one name exactly one succeeds, and the others get
   one line saying so. With ``overwrite`` by an atomic rename over the old file. A reader sees the
   old file or the whole new one, never part of one.
3. The files of one call (a capture and its truth) appear together or, without ``overwrite``, not
   at all; every error path (an exception in a writer, Ctrl-C) removes the temporary files. A
   process killed outright (SIGKILL, power loss) may leave a hidden ``.NAME.*.tmp``, never a partial
   NAME.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import os
import stat
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rotacal.errors import ConfigError

__all__ = [
    "InputFile",
    "Output",
    "Writer",
    "check_folder",
    "check_outputs",
    "write_output",
    "write_outputs",
]

#: Fills a temporary file, given its path (for writers that open files by name: HDF5, TDMS).
Writer = Callable[[Path], None]

#: How the messages tell a person to allow replacing a file.
OVERWRITE_HINT = "--overwrite"

#: os.access asks with the effective ids (those that decide an actual write) where it can.
_EFFECTIVE_IDS = os.access in os.supports_effective_ids

#: errno values of os.link that mean "no hard links on this file system", not "you may not".
_NO_HARD_LINKS = {errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EMLINK, errno.ENOSYS}


@dataclass(frozen=True)
class InputFile:
    """A file a command reads, and how messages name it (``CAPTURE run.npz``, ``--selfcal s.json``)."""

    path: str | os.PathLike[str]
    label: str


@dataclass(frozen=True)
class Output:
    """One file to write: where, what (text, bytes, or a :data:`Writer`), and how messages name it."""

    path: str | os.PathLike[str]
    content: str | bytes | Writer
    label: str | None = None


def check_outputs(
    targets: Sequence[tuple[str | os.PathLike[str], str]],
    *,
    overwrite: bool = False,
    inputs: Sequence[InputFile] = (),
    make_folders: bool = False,
    hint: str = OVERWRITE_HINT,
) -> list[Path]:
    """Refuse, with one line, any of ``targets`` ((path, label) pairs) that may not be written.

    See the module's docstring for what is refused. ``make_folders``: missing folders on the way
    will be created (then the nearest existing one must be a folder this process may write in);
    otherwise the folder must exist. ``hint`` is how the messages say "allow replacing".

    Returns
    -------
    list of Path
        The files that will be written: each target with its symbolic links resolved.

    Raises
    ------
    ConfigError
        Naming the target by its label, what is wrong and what to do.
    """
    planned: list[tuple[Path, str]] = []
    for path, label in targets:
        dest = _check_output(path, label, overwrite, inputs, make_folders, hint)
        for other, other_label in planned:
            if _same_file(dest, other):
                raise ConfigError(
                    f"{other_label} and {label} name the same file; give them different names"
                )
        planned.append((dest, label))
    return [dest for dest, _ in planned]


def check_folder(folder: str | os.PathLike[str], *, label: str) -> None:
    """Refuse a folder that cannot be created or written in (for outputs that are a folder).

    Raises
    ------
    ConfigError
        A dangling symbolic link on the way, a regular file where a folder should be, or a folder
        this process may not write in.
    """
    _refuse_dangling_links(Path(folder), label)
    _check_folder(Path(os.path.realpath(folder)), label, make_folders=True)


def write_output(
    path: str | os.PathLike[str],
    content: str | bytes | Writer,
    *,
    label: str | None = None,
    overwrite: bool = False,
    inputs: Sequence[InputFile] = (),
    make_folders: bool = False,
    hint: str = OVERWRITE_HINT,
) -> Path:
    """Write one file exclusively (or, with ``overwrite``, atomically over an old one).

    ``content``: text (written as UTF-8), bytes, or a :data:`Writer` that fills the temporary file
    it is given. The other arguments are those of :func:`write_outputs`.

    Returns
    -------
    Path
        ``path`` as given.
    """
    return write_outputs(
        [Output(path, content, label)],
        overwrite=overwrite,
        inputs=inputs,
        make_folders=make_folders,
        hint=hint,
    )[0]


def write_outputs(
    outputs: Sequence[Output],
    *,
    overwrite: bool = False,
    inputs: Sequence[InputFile] = (),
    make_folders: bool = False,
    hint: str = OVERWRITE_HINT,
) -> list[Path]:
    """Write files that belong together: all of them, or (without ``overwrite``) none.

    Each is checked as :func:`check_outputs` does (again, since the pre-flight: files appear), then
    written to a temporary file beside it; only when every one is complete are they given their
    names, in order. Without ``overwrite`` a name that exists by then (another process created it
    meanwhile) is refused and the files already named by this call are removed again. With
    ``overwrite`` each replaces its old file atomically.

    Returns
    -------
    list of Path
        The paths as given, in order.

    Raises
    ------
    ConfigError
        A target that may not be written, a name taken meanwhile, or the system refusing the write
        (no space left, permission), naming the target by its label.
    """
    labels = [out.label or str(out.path) for out in outputs]
    dests = check_outputs(
        [(out.path, label) for out, label in zip(outputs, labels, strict=True)],
        overwrite=overwrite,
        inputs=inputs,
        make_folders=make_folders,
        hint=hint,
    )
    temporaries: list[Path] = []
    named: list[tuple[Path, tuple[int, int]]] = []
    try:
        for out, dest, label in zip(outputs, dests, labels, strict=True):
            temporaries.append(_write_temporary(dest, out.content, label, make_folders))
        for tmp, dest, label in zip(temporaries, dests, labels, strict=True):
            identity = _identity(tmp)
            _give_name(tmp, dest, label, overwrite, hint)
            named.append((dest, identity))
        for folder in {dest.parent for dest in dests}:
            _sync_folder(folder)
    except BaseException:
        if not overwrite:  # all or none: take back the names this call gave
            for dest, identity in named:
                with contextlib.suppress(OSError):
                    if _identity(dest) == identity:
                        dest.unlink()
        raise
    finally:
        for tmp in temporaries:
            with contextlib.suppress(OSError):
                tmp.unlink()
    return [Path(out.path) for out in outputs]


# ------------------------------------------------------------------------------------ the checks
def _check_output(
    path: str | os.PathLike[str],
    label: str,
    overwrite: bool,
    inputs: Sequence[InputFile],
    make_folders: bool,
    hint: str,
) -> Path:
    if not os.fspath(path):
        raise ConfigError(f"{label.strip() or 'an output'} needs a file name")
    _refuse_dangling_links(Path(path), label)
    dest = Path(os.path.realpath(path))
    for source in inputs:
        if _same_file(dest, Path(source.path)):
            raise ConfigError(
                f"{label} would overwrite the input {source.label}; choose another name (an input "
                f"is never replaced, not even with {hint})"
            )
    try:
        st = os.stat(dest) if os.path.lexists(dest) else None
    except OSError as e:  # a loop of symbolic links, a folder we may not look into
        raise ConfigError(f"cannot write {label}: {e.strerror}") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise ConfigError(f"{label} is a folder; give a file name")
        if not stat.S_ISREG(st.st_mode):
            raise ConfigError(
                f"{label} is not a regular file (a device, pipe or socket); give a file name"
            )
        if not overwrite:
            raise ConfigError(f"{label} already exists; choose another name or pass {hint}")
        if not os.access(dest, os.W_OK, effective_ids=_EFFECTIVE_IDS):
            raise ConfigError(
                f"{label} is write-protected and is not replaced, not even with {hint}; choose "
                "another name or make the file writable"
            )
    _check_folder(dest.parent, label, make_folders)
    return dest


def _refuse_dangling_links(path: Path, label: str) -> None:
    """Refuse a symbolic link that leads nowhere, as the path or as one of its folders."""
    # Path.absolute keeps "..", which the kernel resolves after the links before it.
    for part in (path.absolute(), *path.absolute().parents):
        if os.path.islink(part) and not os.path.exists(part):
            raise ConfigError(
                f"{label}: {part} is a dangling symbolic link (to {os.readlink(part)}); rotacal "
                "does not create a file through it — give the real path"
            )


def _check_folder(folder: Path, label: str, make_folders: bool) -> None:
    """The folder (``folder`` is resolved) exists or can be made, and this process may write in it."""
    existing = folder
    while not os.path.exists(existing):
        existing = existing.parent
    if not os.path.isdir(existing):
        raise ConfigError(
            f"cannot write {label}: {existing} is a file, not a folder; give a path in a folder"
        )
    if existing != folder and not make_folders:
        raise ConfigError(f"cannot write {label}: folder {folder} does not exist; create it")
    if not os.access(existing, os.W_OK | os.X_OK, effective_ids=_EFFECTIVE_IDS):
        raise ConfigError(
            f"cannot write {label}: no permission to write in folder {existing} (or it is on a "
            "read-only file system); choose a folder you can write to"
        )


def _same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` name one file: one resolved path, or one inode (a hard link)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist
        return False


# ----------------------------------------------------------------------------------- the writing
def _write_temporary(dest: Path, content: str | bytes | Writer, label: str, make: bool) -> Path:
    """The content in a complete, flushed temporary file beside ``dest`` (removed on any error)."""
    try:
        if make:
            dest.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=dest.parent, prefix=f".{dest.name[:200]}.", suffix=".tmp")
    except OSError as e:
        raise ConfigError(f"cannot write {label}: {e.strerror or e}") from None
    tmp = Path(name)
    try:
        if callable(content):
            os.close(fd)
            content(tmp)
        else:
            with os.fdopen(fd, "wb") as fh:
                fh.write(content.encode("utf-8") if isinstance(content, str) else content)
        sync = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(sync)  # the data is on disk before the name points at it
        finally:
            os.close(sync)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
    except BaseException as e:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(e, OSError):
            raise ConfigError(f"cannot write {label}: {e.strerror or e}") from None
        raise
    return tmp


def _give_name(tmp: Path, dest: Path, label: str, overwrite: bool, hint: str) -> None:
    """Name the finished file ``dest``: atomically over an old one, or only if the name is free."""
    try:
        if overwrite:
            os.replace(tmp, dest)
        else:
            _link_exclusive(tmp, dest)
    except FileExistsError:
        raise ConfigError(
            f"{label} was created by another process meanwhile; choose another name or pass {hint}"
        ) from None
    except OSError as e:
        raise ConfigError(f"cannot write {label}: {e.strerror or e}") from None


def _link_exclusive(tmp: Path, dest: Path) -> None:
    """Give ``tmp`` the name ``dest`` unless it exists (FileExistsError), even in a race."""
    try:
        os.link(tmp, dest)
        return
    except OSError as e:
        if isinstance(e, FileExistsError) or e.errno not in _NO_HARD_LINKS:
            raise
    if _rename_noreplace(tmp, dest):
        return
    # Last resort (no hard links, no renameat2): claim the name exclusively, then move the whole
    # file over the claim. Exclusive still; a reader may see the empty claim for a moment.
    os.close(os.open(dest, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    try:
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(OSError):
            dest.unlink()
        raise


_AT_FDCWD = -100
_RENAME_NOREPLACE = 1


def _rename_noreplace(src: Path, dst: Path) -> bool:
    """Linux ``renameat2(RENAME_NOREPLACE)``; False where the system or file system lacks it."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = (
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_uint,
    )
    renameat2.restype = ctypes.c_int
    if renameat2(_AT_FDCWD, os.fsencode(src), _AT_FDCWD, os.fsencode(dst), _RENAME_NOREPLACE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOTSUP):
        return False
    raise OSError(err, os.strerror(err), os.fspath(dst))  # EEXIST becomes FileExistsError


def _identity(path: Path) -> tuple[int, int]:
    st = os.lstat(path)
    return st.st_dev, st.st_ino


def _sync_folder(folder: Path) -> None:
    """Flush the folder's entries, so the new names survive a power loss (where supported)."""
    with contextlib.suppress(OSError, AttributeError):
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _umask() -> int:
    """The process umask, read without changing it (Linux); 0o022 elsewhere."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    return 0o022
