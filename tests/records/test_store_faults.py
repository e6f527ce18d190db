"""A store that cannot be used, as ``rotacal certify PLAN --db …`` meets it (ISSUE 16): exit 2,
one line that names the store and says what to do, and nothing written — no certificate folder,
no staging folder, no record, no number drawn, the store's file as it was."""

from __future__ import annotations

import os
import sqlite3
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
import sqlalchemy as sa
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.records import models as m
from rotacal.records import open_store
from rotacal.records.testing import ThrowawayPostgres

from .certify_plans import capture_folder_fixture, write_plans  # noqa: F401  (a fixture)


@pytest.fixture
def plan(tmp_path: Path, capture_folder: Path) -> Path:
    """A plan that certifies (``number = "auto"``) when its store can be used."""
    (path,) = write_plans(tmp_path / "plan", capture_folder, 1)
    return path


def certify_fails(plan: Path, db: str, *phrases: str) -> str:
    """Run ``rotacal certify PLAN --db DB``; check exit 2, one line with ``phrases``, and that
    the plan's folder holds what it held before. Returns the line."""
    before = sorted(p.name for p in plan.parent.iterdir())
    result = CliRunner().invoke(cli, ["certify", str(plan), "--db", db])
    return check_failed(plan, before, result.exit_code, result.stderr, *phrases)


def check_failed(plan: Path, before: list[str], code: int, stderr: str, *phrases: str) -> str:
    assert code == 2, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    (line,) = lines
    assert line.startswith("rotacal: error: records store "), line
    for phrase in phrases:
        assert phrase in line
    assert sorted(p.name for p in plan.parent.iterdir()) == before  # no folder, nothing staged
    return line


def test_the_plan_certifies_when_its_store_can_be_used(plan: Path, tmp_path: Path) -> None:
    # what the faults below are measured against: the same plan, a usable store
    result = CliRunner().invoke(
        cli, ["certify", str(plan), "--db", f"sqlite:///{tmp_path / 'records.sqlite'}"]
    )
    assert result.exit_code == 0, result.stderr
    assert (plan.parent / "RC-2026-0001" / "certificate.pdf").is_file()


@pytest.mark.parametrize(
    ("db", "phrases"),
    [
        ("records.sqlite", ["a file path, not a database URL", "give sqlite:///"]),
        ("mysql://lab:secret@db.example.org/records", ["'mysql' is not supported", "***"]),
        ("postgres://lab@db.example.org/records", ["postgresql+psycopg://"]),
        ("sqlite:///{tmp}/no/such/folder/records.sqlite", ["{tmp}/no/such/folder does not exist"]),
        ("sqlite://", ["needs a file"]),
    ],
)
def test_a_wrong_url_is_refused_before_anything_is_measured(
    plan: Path, tmp_path: Path, db: str, phrases: list[str]
) -> None:
    line = certify_fails(plan, db.format(tmp=tmp_path), *(p.format(tmp=tmp_path) for p in phrases))
    assert "secret" not in line  # a password is never printed
    assert not (tmp_path / "no").exists()


def test_a_postgresql_server_that_is_not_running(plan: Path) -> None:
    import socket

    with socket.socket() as s:  # a port where nothing listens: bound, never listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        certify_fails(
            plan,
            f"postgresql+psycopg://rotacal@127.0.0.1:{port}/records",
            f"no PostgreSQL server answers at 127.0.0.1:{port}",
            "Connection refused",
            "start the server",
        )


def test_a_database_that_the_server_does_not_have(plan: Path, postgres: ThrowawayPostgres) -> None:
    certify_fails(
        plan,
        postgres.url("no_such_records"),
        "has no database 'no_such_records'",
        "createdb no_such_records",
    )
    import psycopg

    with psycopg.connect(
        f"host=127.0.0.1 port={postgres.port} user=rotacal dbname=postgres"
    ) as connection:
        names = connection.execute("SELECT datname FROM pg_database").fetchall()
    assert ("no_such_records",) not in names


def test_a_file_that_is_not_an_sqlite_database(plan: Path, tmp_path: Path) -> None:
    path = tmp_path / "records.sqlite"
    data = b"Lab notes, not a database.\n" * 200
    path.write_bytes(data)
    certify_fails(plan, f"sqlite:///{path}", "is not an SQLite database")
    assert path.read_bytes() == data


def _store_state(url: str) -> tuple[list[str], list[str], list[int]]:
    with open_store(url).read() as session:
        return (
            list(session.execute(sa.select(m.Certificate.number)).scalars()),
            list(session.execute(sa.select(m.VoidedNumber.number)).scalars()),
            list(session.execute(sa.select(m.Counter.last)).scalars()),
        )


def test_a_locked_sqlite_store_is_reported_after_the_timeout(
    plan: Path, tmp_path: Path, issue: Callable[..., object]
) -> None:
    url = f"sqlite:///{tmp_path / 'records.sqlite'}"
    issue(open_store(url), {"scale_factor": ("1.000", "0.002")})  # a store with one record
    state = _store_state(url)
    before = sorted(p.name for p in plan.parent.iterdir())
    holder = sqlite3.connect(tmp_path / "records.sqlite", isolation_level=None)
    try:
        holder.execute("BEGIN EXCLUSIVE")  # another program writing, for longer than we wait
        done = subprocess.run(
            [sys.executable, "-m", "rotacal", "certify", str(plan), "--db", url],
            env={**os.environ, "ROTACAL_DB_TIMEOUT": "1"},
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    check_failed(
        plan, before, done.returncode, done.stderr, "locked by another program (waited 1 s)"
    )
    assert _store_state(url) == state
