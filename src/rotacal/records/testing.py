"""A throwaway PostgreSQL server on loopback, for the tests and benchmarks of the records store.

The same suite runs against SQLite and a real PostgreSQL server (DESIGN.md: no mocks of the
database). :class:`ThrowawayPostgres` makes a cluster with ``initdb`` in a temporary folder, starts
it with ``pg_ctl`` on 127.0.0.1 and a free port, and removes it all on :meth:`stop`. PostgreSQL
refuses to run as root, so as root the server runs as the unprivileged ``postgres`` user (Debian's
package makes it). The programs come from PATH or Debian's ``/usr/lib/postgresql/<version>/bin``;
``.ci/run`` installs the package when the machine lacks it.

:func:`at_once` runs tasks in processes of their own, released together, for the tests and
benchmarks of concurrent writers.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

__all__ = ["Outcome", "PostgresUnavailable", "ThrowawayPostgres", "at_once", "find_postgres_bin"]


class PostgresUnavailable(RuntimeError):
    """No PostgreSQL server programs on this machine (install Debian's ``postgresql``)."""


def find_postgres_bin() -> Path:
    """The folder of ``initdb`` and ``pg_ctl``: from PATH, else the newest Debian version."""
    found = shutil.which("pg_ctl")
    if found and shutil.which("initdb"):
        return Path(found).resolve().parent
    versions = sorted(
        Path("/usr/lib/postgresql").glob("*/bin/pg_ctl"),
        key=lambda p: int(p.parts[-3]) if p.parts[-3].isdigit() else 0,
    )
    if versions:
        return versions[-1].parent
    raise PostgresUnavailable(
        "PostgreSQL's server programs (initdb, pg_ctl) are not on this machine; install them: "
        "apt-get install -y postgresql"
    )


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class ThrowawayPostgres:
    """A PostgreSQL cluster of its own, started on 127.0.0.1 (``trust`` authentication for the
    user ``rotacal``, loopback only), for as long as the object lives.

    ``url(dbname)`` gives an SQLAlchemy URL; :meth:`new_database` makes an empty database.
    """

    def __init__(self, *, durable: bool = False) -> None:
        """Start the server; ``durable`` keeps PostgreSQL's own default of flushing every
        commit to disk (for benchmarks), otherwise commits are not flushed (for tests)."""
        bin_dir = find_postgres_bin()
        self.folder = Path(tempfile.mkdtemp(prefix="rotacal-pg-"))
        self.port = _free_port()
        self._as: list[str] = []
        if os.geteuid() == 0:  # PostgreSQL refuses root: run it as Debian's postgres user
            shutil.chown(self.folder, "postgres")
            self._as = ["runuser", "-u", "postgres", "--"]
        data = self.folder / "data"
        self._run(
            [str(bin_dir / "initdb"), "-D", str(data), "-A", "trust", "-U", "rotacal", "-E",
             "UTF8", "--no-sync", "--no-instructions"]
        )  # fmt: skip
        options = (
            f"-c listen_addresses=127.0.0.1 -p {self.port} -k {self.folder} "
            f"-c fsync={'on' if durable else 'off'} -c max_connections=60"
        )
        self._pg_ctl = [str(bin_dir / "pg_ctl"), "-D", str(data)]
        self._run([*self._pg_ctl, "-o", options, "-l", str(self.folder / "log"), "-w", "start"])

    def _run(self, argv: list[str]) -> None:
        done = subprocess.run([*self._as, *argv], capture_output=True, text=True, check=False)
        if done.returncode != 0:
            raise PostgresUnavailable(
                f"{Path(argv[0]).name} failed ({done.returncode}): "
                + " ".join((done.stderr or done.stdout).split())[:500]
            )

    def url(self, dbname: str = "postgres") -> str:
        return f"postgresql+psycopg://rotacal@127.0.0.1:{self.port}/{dbname}"

    def new_database(self) -> str:
        """An empty store of its own; returns its URL. It is a schema of its own in one
        database (the URL sets ``search_path``): as empty as a new database to rotacal, made
        in milliseconds rather than the second a ``CREATE DATABASE`` takes."""
        import psycopg

        name = "t_" + uuid.uuid4().hex[:12]
        with psycopg.connect(
            f"host=127.0.0.1 port={self.port} user=rotacal dbname=postgres", autocommit=True
        ) as connection:
            connection.execute(f"CREATE SCHEMA {name}")
        return self.url("postgres") + f"?options=-csearch_path%3D{name}"

    def stop(self) -> None:
        """Stop the server and remove its folder."""
        try:
            self._run([*self._pg_ctl, "-m", "immediate", "-w", "stop"])
        finally:
            shutil.rmtree(self.folder, ignore_errors=True)


@dataclasses.dataclass(frozen=True)
class Outcome:
    """How one task of :func:`at_once` ended."""

    #: what the task returned (None when it raised or exited)
    value: Any
    #: the exit code: 0, the code of a ``SystemExit`` (a CLI command), 1 for an exception
    exit_code: int
    #: ``"TypeName: message"`` of an exception other than ``SystemExit``, else ""
    error: str
    #: what the task wrote to its standard output and standard error
    stdout: str
    stderr: str
    #: when the task started after the common barrier, and when it ended (``time.time()``) [s]
    start: float
    end: float


def _run_task(task: Callable[[], Any], barrier: Any, send: Any, out: str, err: str) -> None:
    """In the child: write stdout/stderr to files, wait for the others, run, send the outcome."""
    # whatever the parent left in its buffers goes to these files, not twice into its streams
    for target, path in ((1, out), (2, err)):
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.dup2(fd, target)
        os.close(fd)
    value, code, error, start = None, 0, "", 0.0
    try:
        barrier.wait(timeout=120)  # broken when a sibling never gets there
        start = time.time()
        value = task()
    except SystemExit as e:  # a click command ends this way, with its exit code
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    except BaseException as e:
        code, error = 1, f"{type(e).__name__}: {' '.join(str(e).split())}"
    end = time.time()
    sys.stdout.flush()
    sys.stderr.flush()
    send.send((value, code, error, start, end))
    send.close()


def at_once(tasks: Sequence[Callable[[], Any]], *, timeout_s: float = 600.0) -> list[Outcome]:
    """Run each task in a process of its own, all released together at one barrier, and wait
    for them: concurrent writers of a store, as on several test stations.

    The processes are forked from this one (POSIX), so they start without importing anything
    again; every task must open its own store (a connection must not cross a fork). A task's
    return value must be picklable.

    Parameters
    ----------
    tasks : sequence of callables
        What each process runs (no arguments).
    timeout_s : float
        How long to wait for all of them [s]; a process still running then is killed and its
        outcome says so.
    """
    context = multiprocessing.get_context("fork")
    barrier = context.Barrier(len(tasks))
    with tempfile.TemporaryDirectory(prefix="rotacal-at-once-") as folder:
        started = []
        for i, task in enumerate(tasks):
            receive, send = context.Pipe(duplex=False)
            out, err = f"{folder}/{i}.out", f"{folder}/{i}.err"
            process = context.Process(target=_run_task, args=(task, barrier, send, out, err))
            process.start()
            send.close()
            started.append((process, receive, out, err))
        deadline = time.monotonic() + timeout_s
        outcomes = []
        for process, receive, out, err in started:
            if receive.poll(max(0.0, deadline - time.monotonic())):
                try:
                    value, code, error, start, end = receive.recv()
                except EOFError:  # the process died without a word (a signal)
                    value, code, error, start, end = None, 1, "died", 0.0, 0.0
            else:
                value, code, error, start, end = (
                    None,
                    1,
                    f"still running after {timeout_s:g} s",
                    0.0,
                    0.0,
                )
            process.join(max(0.0, deadline - time.monotonic()) + 1.0)
            if process.is_alive():
                process.kill()
                process.join()
            if process.exitcode and not error and code == 0:
                code, error = process.exitcode, f"exit code {process.exitcode}"
            outcomes.append(
                Outcome(
                    value,
                    code,
                    error,
                    Path(out).read_text(errors="replace"),
                    Path(err).read_text(errors="replace"),
                    start,
                    end,
                )
            )
    return outcomes
