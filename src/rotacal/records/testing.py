"""A throwaway PostgreSQL server on loopback, for the tests and benchmarks of the records store.

The same suite runs against SQLite and a real PostgreSQL server (DESIGN.md: no mocks of the
database). :class:`ThrowawayPostgres` makes a cluster with ``initdb`` in a temporary folder, starts
it with ``pg_ctl`` on 127.0.0.1 and a free port, and removes it all on :meth:`stop`. PostgreSQL
refuses to run as root, so as root the server runs as the unprivileged ``postgres`` user (Debian's
package makes it). The programs come from PATH or Debian's ``/usr/lib/postgresql/<version>/bin``;
``.ci/run`` installs the package when the machine lacks it.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import tempfile
import uuid
from pathlib import Path

__all__ = ["PostgresUnavailable", "ThrowawayPostgres", "find_postgres_bin"]


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

    def __init__(self) -> None:
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
            f"-c listen_addresses=127.0.0.1 -p {self.port} -k {self.folder} -c fsync=off "
            "-c max_connections=60"
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
