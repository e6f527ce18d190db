"""``rotacal batch`` on a real ``distributed.LocalCluster``: every plan issued exactly once, through
killed workers, restarts and resumes; failures isolated; SQLite written by the client, PostgreSQL
by the workers directly."""

from __future__ import annotations

import json
import os
import shutil
import signal
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import sqlalchemy as sa
from click.testing import CliRunner
from distributed import Client, Future

from rotacal.batch import BatchInterruptedError, BatchResult, expected_plan_sha256, run_batch
from rotacal.batch.cluster import dask_client as cluster_client
from rotacal.batch.tasks import open_store_urls
from rotacal.cli import cli
from rotacal.errors import ConfigError
from rotacal.plan.read import read_plan
from rotacal.records import models as m
from rotacal.records import open_store

CERTIFICATE_FILES = {"certificate.pdf", "certificate.xml", "results.json"}


@pytest.fixture(scope="module")
def dask_client() -> Iterator[Client]:
    """This module's own local cluster of two workers (as ``rotacal batch --workers 2`` makes
    it): its tests kill workers and cancel work on it."""
    with cluster_client(2, None, None) as client:
        yield client


def _records(url: str) -> dict[str, str]:
    """plan_sha256 → number of every certificate in the store (and that no sha is there twice)."""
    store = open_store(url)
    try:
        with store.begin(read_only=True) as connection:
            rows = connection.execute(sa.select(m.Certificate.plan_sha256, m.Certificate.number))
            pairs = [tuple(r) for r in rows]
    finally:
        store.close()
    shas = [sha for sha, _ in pairs]
    assert len(shas) == len(set(shas)), "a plan was issued twice"
    return dict(pairs)


def _check_issued_once(result: BatchResult, plans: list[Path], url: str) -> None:
    """Every plan has exactly one certificate, whose folder is whole and whose record holds the
    plan_sha256 that the plan and its captures give (computed here from the files alone)."""
    records = _records(url)
    assert len(records) == len(plans)
    out = result.out
    for path in plans:
        sha = expected_plan_sha256(read_plan(path))
        number = records[sha]
        folder = out / number
        assert CERTIFICATE_FILES <= {p.name for p in folder.iterdir()}
        assert json.loads((folder / "results.json").read_text())["plan_sha256"] == sha
    folders = {p.name for p in out.iterdir() if p.is_dir() and not p.name.startswith(".")}
    assert folders == set(records.values()), "a partial or unrecorded folder was left"
    listed = json.loads((out / "batch.json").read_text())
    assert {str(p) for p in plans} <= {p["plan"] for p in listed["plans"]}


def _stores_opened_by_workers(client: Client) -> list[str]:
    """The URLs of the records stores the workers opened themselves."""
    # a function of rotacal's: the workers cannot import the tests' modules
    return [u for urls in client.run(open_store_urls).values() for u in urls]


def _sqlite(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'records.sqlite'}"


def test_a_batch_issues_every_plan_once_and_a_second_run_skips_them(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    paths, url, out = plans(5), _sqlite(tmp_path), tmp_path / "certs"
    dask_client.wait_for_workers(2)
    first = run_batch([paths[0].parent], out=out, db=url, client=dask_client)
    assert [o.status for o in first.outcomes] == ["issued"] * 5
    assert url in _stores_opened_by_workers(dask_client)  # workers on this machine write SQLite
    assert len({o.number for o in first.outcomes}) == 5
    _check_issued_once(first, paths, url)

    again = run_batch(paths, out=out, db=url, client=dask_client)
    assert [o.status for o in again.outcomes] == ["skipped"] * 5
    assert [o.number for o in again.outcomes] == [o.number for o in first.outcomes]
    assert again.workers == 0  # nothing ran: the skips come from the hashes alone
    _check_issued_once(again, paths, url)


def test_a_failing_plan_fails_alone_with_its_reason(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    paths, url, out = plans(3), _sqlite(tmp_path), tmp_path / "certs"
    folder = paths[0].parent
    (folder / "broken.toml").write_text("[certificate\n", encoding="utf-8")
    missing = folder / "missing.toml"
    missing.write_text(paths[0].read_text().replace("captures-0000/rotations.npz", "gone.npz"))
    corrupt = folder / "corrupt.toml"
    (folder / "captures-0001" / "bad.npz").write_bytes(b"PK\x03\x04 not a capture")
    corrupt.write_text(paths[1].read_text().replace('rotations.npz"', 'bad.npz"', 1))
    dask_client.wait_for_workers(2)
    result = run_batch([folder], out=out, db=url, client=dask_client)
    by_name = {Path(o.plan).name: o for o in result.outcomes}
    assert {n: o.status for n, o in by_name.items()} == {
        "broken.toml": "failed",
        "corrupt.toml": "failed",
        "missing.toml": "failed",
        "unit-0000.toml": "issued",
        "unit-0001.toml": "issued",
        "unit-0002.toml": "issued",
    }
    for name in ("broken.toml", "corrupt.toml", "missing.toml"):
        error = by_name[name].error
        assert error is not None and "\n" not in error and name in error, error
    assert "bad.npz" in str(by_name["corrupt.toml"].error)
    assert "gone.npz" in str(by_name["missing.toml"].error)
    _check_issued_once(result, paths, url)


def _kill_one_worker(client: Client) -> Callable[[str], None]:
    """An ``advance`` that kills one worker process (SIGKILL) when the first plan has ended."""
    killed: list[int] = []

    def advance(label: str) -> None:
        if not killed:
            pid = next(iter(client.run(os.getpid).values()))
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    return advance


@pytest.mark.parametrize(
    ("engine", "from_workers"),
    [("sqlite", True), ("sqlite", False), ("postgresql", None)],
    ids=["sqlite-workers", "sqlite-client", "postgresql"],
)
def test_a_killed_worker_loses_nothing_and_issues_nothing_twice(
    dask_client: Client,
    plans: Callable[[int], list[Path]],
    tmp_path: Path,
    request: pytest.FixtureRequest,
    engine: str,
    from_workers: bool | None,
) -> None:
    paths, out = plans(8), tmp_path / "certs"
    url = (
        _sqlite(tmp_path)
        if engine == "sqlite"
        else request.getfixturevalue("postgres").new_database()
    )
    dask_client.wait_for_workers(2)
    killer = _kill_one_worker(dask_client)
    result = run_batch(
        paths,
        out=out,
        db=url,
        client=dask_client,
        advance=killer,
        records_from_workers=from_workers,
    )
    # Dask runs a lost worker's task again elsewhere: the batch ends whole
    assert [o.status for o in result.outcomes] == ["issued"] * 8, [o.error for o in result.outcomes]
    _check_issued_once(result, paths, url)
    assert not (out / ".rotacal-batch-staging").exists()
    dask_client.wait_for_workers(2)
    again = run_batch(paths, out=out, db=url, client=dask_client)
    assert again.count("skipped") == 8
    _check_issued_once(again, paths, url)


def test_tasks_lost_to_the_cluster_fail_their_plans_and_a_second_run_finishes_them(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    # what a cluster that drops the batch's tasks does (a restart, a scheduler that lost them):
    # every task of this client cancelled when the first plan has ended
    paths, url, out = plans(8), _sqlite(tmp_path), tmp_path / "certs"
    dropped: list[bool] = []

    def advance(label: str) -> None:
        if not dropped:
            dropped.append(True)
            dask_client.cancel([Future(key, dask_client) for key in list(dask_client.futures)])

    dask_client.wait_for_workers(2)
    first = run_batch(
        paths, out=out, db=url, client=dask_client, advance=advance, records_from_workers=False
    )
    lost = [o for o in first.outcomes if o.status == "failed"]
    assert lost, "the cancel came too late to stop any plan"
    assert all("lost" in str(o.error) for o in lost)
    issued = {o.number for o in first.outcomes if o.status == "issued"}
    second = run_batch(paths, out=out, db=url, client=dask_client)
    assert second.count("failed") == 0
    assert {o.number for o in second.outcomes if o.status == "skipped"} == issued
    _check_issued_once(second, paths, url)


def test_postgresql_is_written_by_the_workers_directly(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path, postgres: object
) -> None:
    paths, out = plans(4), tmp_path / "certs"
    url = postgres.new_database()  # type: ignore[attr-defined]
    dask_client.wait_for_workers(2)
    result = run_batch(paths, out=out, db=url, client=dask_client)
    assert result.count("issued") == 4
    _check_issued_once(result, paths, url)

    assert url in _stores_opened_by_workers(dask_client)


def test_interrupting_the_client_voids_its_drawn_numbers(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    paths, url, out = plans(6), _sqlite(tmp_path), tmp_path / "certs"

    def advance(label: str) -> None:
        raise KeyboardInterrupt

    dask_client.wait_for_workers(2)
    with pytest.raises(BatchInterruptedError, match="run the same batch again"):
        run_batch(
            paths,
            out=out,
            db=url,
            client=dask_client,
            advance=advance,
            records_from_workers=False,
        )
    listed = json.loads((out / "batch.json").read_text())
    assert any(p["status"] == "failed" and "interrupted" in p["error"] for p in listed["plans"])
    dask_client.wait_for_workers(2)
    finished = run_batch(paths, out=out, db=url, client=dask_client)
    assert finished.count("failed") == 0
    _check_issued_once(finished, paths, url)


def test_the_command_reports_a_table_and_exits_2_when_a_plan_failed(
    plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    paths, url, out = plans(2), _sqlite(tmp_path), tmp_path / "certs"
    (paths[0].parent / "broken.toml").write_text("not = [toml\n", encoding="utf-8")
    result = CliRunner().invoke(
        cli, ["batch", str(paths[0].parent), "--out", str(out), "--db", url, "--workers", "1"]
    )
    assert result.exit_code == 2, result.output
    assert "issued         2" in result.stdout and "failed         1" in result.stdout
    assert "failed: " in result.stderr and "broken.toml" in result.stderr
    assert "Traceback" not in result.output
    assert len(_records(url)) == 2


def test_the_command_refuses_workers_with_a_scheduler(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        cli, ["batch", str(tmp_path), "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"]
    )
    assert result.exit_code == 2 and "not both" in result.output


def test_a_running_scheduler_takes_the_batch_and_a_plan_named_twice_runs_once(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    paths, url, out = plans(2), _sqlite(tmp_path), tmp_path / "certs"
    twin = paths[0].parent / "the-same.toml"
    twin.write_bytes(paths[0].read_bytes())  # the same plan and captures under another name
    address = dask_client.scheduler_info()["address"]
    dask_client.wait_for_workers(2)
    result = CliRunner().invoke(
        cli,
        [
            "batch",
            *map(str, paths),
            str(twin),
            "--out",
            str(out),
            "--db",
            url,
            "--scheduler",
            address,
        ],
    )
    assert result.exit_code == 0, result.output
    listed = {
        Path(p["plan"]).name: p for p in json.loads((out / "batch.json").read_text())["plans"]
    }
    assert listed["the-same.toml"]["status"] == "skipped"
    assert listed["the-same.toml"]["number"] == listed["unit-0000.toml"]["number"]
    assert len(_records(url)) == 2


def test_a_batch_json_that_is_not_a_batchs_is_never_replaced(
    plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    paths, url, out = plans(1), _sqlite(tmp_path), tmp_path / "certs"
    out.mkdir()
    (out / "batch.json").write_text('{"mine": true}', encoding="utf-8")
    with pytest.raises(ConfigError, match="is never replaced"):
        run_batch(paths, out=out, db=url, workers=1)
    assert (out / "batch.json").read_text(encoding="utf-8") == '{"mine": true}'
    assert not _records(url)


def test_a_certificate_folder_without_its_record_is_moved_aside_and_its_number_voided(
    dask_client: Client, plans: Callable[[int], list[Path]], tmp_path: Path
) -> None:
    # what a worker killed between publishing a folder and committing its record leaves behind
    paths, url, out = plans(2), _sqlite(tmp_path), tmp_path / "certs"
    dask_client.wait_for_workers(2)
    first = run_batch(paths, out=out, db=url, client=dask_client)
    issued = first.outcomes[0].number
    assert issued is not None
    orphan = out / "RC-2026-0042"
    shutil.copytree(out / issued, orphan)
    results = json.loads((orphan / "results.json").read_text())
    results["certificate_number"] = orphan.name
    (orphan / "results.json").write_text(json.dumps(results))
    (out / "notes").mkdir()  # the user's own folder: never touched
    again = run_batch(paths, out=out, db=url, client=dask_client)
    assert again.set_aside == ["RC-2026-0042"]
    assert not orphan.exists() and (out / "notes").is_dir()
    assert [p.name.split("-20")[0] for p in (out / ".rotacal-unrecorded").iterdir()] == ["RC"]
    assert json.loads((out / "batch.json").read_text())["set_aside"] == ["RC-2026-0042"]
    store = open_store(url)
    try:
        with store.begin(read_only=True) as connection:
            voided = connection.execute(sa.select(m.VoidedNumber.number)).scalars().all()
    finally:
        store.close()
    assert "RC-2026-0042" in voided


def test_a_plan_a_lost_worker_issued_counts_as_issued_with_a_note(tmp_path: Path) -> None:
    """The race the killed-worker test meets now and then: the lost worker kept the record and
    put the folder in place, then died before it reported; Dask ran the plan again, and the
    retry found it done. It is this batch's certificate: issued, with a note; a certificate
    found done that is not in this batch's folder stays skipped."""
    from types import SimpleNamespace

    from rotacal.batch.run import PlanOutcome, _Run
    from rotacal.batch.tasks import Failed

    out = tmp_path / "certs"
    (out / "RC-7").mkdir(parents=True)
    entries = [SimpleNamespace(path=tmp_path / f"p{i}.toml", sha256=None) for i in range(2)]
    outcomes = [PlanOutcome(str(e.path)) for e in entries]
    run = _Run(None, None, out, tmp_path, entries, outcomes, lambda label: None, True)  # type: ignore[arg-type]
    run._fail(0, Failed("already certified", 0.1, certified_as="RC-7"))
    run._fail(1, Failed("already certified", 0.1, certified_as="RC-3"))
    assert (outcomes[0].status, outcomes[0].number) == ("issued", "RC-7")
    assert "lost before it reported" in outcomes[0].warnings[0]
    assert (outcomes[1].status, outcomes[1].number) == ("skipped", "RC-3")


def test_a_signed_batch_gives_certificates_that_verify(
    dask_client: Client,
    plans: Callable[[int], list[Path]],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``--sign-key``/``--sign-cert``: the key (encrypted, its passphrase in
    ROTACAL_SIGN_PASSPHRASE) read and checked once here, before any cluster is reached; each
    certificate signed on the workers, by those that keep the records (certify_task) and by
    those that render for this process (render_task); and each verifies against the signer."""
    from cryptography.hazmat.primitives.asymmetric import ec

    from rotacal.certificate.sign import load_signer

    from ..certificate.test_signing import make_cert, write_pair

    key = ec.generate_private_key(ec.SECP256R1())
    key_path, cert_path = write_pair(tmp_path, "lab", key, make_cert(key), b"s3cret")
    paths, url, out = plans(2), _sqlite(tmp_path), tmp_path / "certs"
    args = ["batch", str(paths[0]), "--out", str(out), "--db", url]
    signing = ["--sign-key", str(key_path), "--sign-cert", str(cert_path)]
    # a wrong passphrase is refused before the (unreachable) scheduler is tried
    monkeypatch.setenv("ROTACAL_SIGN_PASSPHRASE", "wrong")
    refused = CliRunner().invoke(cli, [*args, "--scheduler", "tcp://127.0.0.1:1", *signing])
    assert refused.exit_code == 2 and "passphrase in ROTACAL_SIGN_PASSPHRASE is wrong" in (
        refused.output
    )
    assert not (out / "batch.json").exists()

    monkeypatch.setenv("ROTACAL_SIGN_PASSPHRASE", "s3cret")
    dask_client.wait_for_workers(2)
    address = dask_client.scheduler_info()["address"]
    result = CliRunner().invoke(cli, [*args, "--scheduler", address, *signing])
    assert result.exit_code == 0 and "signed by B. Manager" in result.stdout, result.output
    by_client = run_batch(
        [paths[1]],
        out=out,
        db=url,
        client=dask_client,
        records_from_workers=False,
        signer=load_signer(key_path, cert_path),
    )
    assert by_client.count("issued") == 1
    numbers = set(_records(url).values())
    assert len(numbers) == 2
    for number in numbers:
        verified = CliRunner().invoke(cli, ["verify", str(out / number), "--trust", str(cert_path)])
        assert verified.exit_code == 0 and "VERIFIED — signed by B. Manager" in verified.stdout
