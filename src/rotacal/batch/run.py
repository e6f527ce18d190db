"""``rotacal batch``: many plans certified as tasks on Dask distributed, resumable, into the records.

The client reads and hashes every plan first: a plan whose ``plan_sha256`` has an issued record is
``skipped`` without running, so a batch that was stopped — by Ctrl-C, a killed worker or a lost
node — is finished by running it again, and nothing is issued twice. The rest run one task per
plan on a local cluster of worker processes (``workers``) or on a running cluster
(``scheduler``); a plan that fails fails alone, with its one-line reason in ``batch.json``.

The records are written by the workers directly — PostgreSQL always, SQLite when the workers
run on this machine (its lock serialises them) — or, for an SQLite file and workers on other
machines, by this process only (see :mod:`rotacal.batch.tasks`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import json
import os
import shutil
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rotacal.errors import ConfigError, RotacalError

from .cluster import dashboard_link, dask_client
from .plans import BatchPlan, find_plans, read_batch_plans
from .tasks import Done, Failed, Measured, certify_task, measure_task, render_task

if TYPE_CHECKING:
    from distributed import Client, Future

    from rotacal.certificate.sign import Signer
    from rotacal.records import Store

__all__ = ["BatchInterruptedError", "BatchResult", "PlanOutcome", "run_batch"]

#: The file that lists every plan of the batch and what became of it (INTERFACE.md "Batches").
BATCH_JSON = "batch.json"
#: Hidden folders in ``--out``: the lock of the batch that writes there, and the staging folders.
LOCK_NAME, STAGING_NAME = ".rotacal-batch.lock", ".rotacal-batch-staging"
#: Where certificate folders found without their record are moved (never deleted).
UNRECORDED_NAME = ".rotacal-unrecorded"


class BatchInterruptedError(RotacalError):
    """The batch was stopped (Ctrl-C) before every plan ended; ``batch.json`` says which did.
    Running the same batch again finishes the rest."""


@dataclasses.dataclass
class PlanOutcome:
    """What became of one plan: ``status`` issued | skipped | failed, the certificate ``number``
    (issued, or the earlier one when skipped), the one-line ``error`` when failed, the task's
    ``seconds`` on its worker and the measurements' ``warnings``."""

    plan: str
    status: str = "pending"
    number: str | None = None
    error: str | None = None
    seconds: float | None = None
    warnings: list[str] = dataclasses.field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {
            "plan": self.plan,
            "status": self.status,
            "number": self.number,
            "error": self.error,
            "seconds": None if self.seconds is None else round(self.seconds, 3),
            "warnings": self.warnings,
        }


@dataclasses.dataclass
class BatchResult:
    """A batch's outcome: one :class:`PlanOutcome` per plan, in the order they were named."""

    outcomes: list[PlanOutcome]
    out: Path
    store: str
    workers: int
    wall_seconds: float
    dashboard: str | None = None
    #: certificate folders of this batch's plans found without their record, moved aside
    set_aside: list[str] = dataclasses.field(default_factory=list)

    def count(self, status: str) -> int:
        return sum(o.status == status for o in self.outcomes)

    @property
    def failed(self) -> int:
        return self.count("failed")

    def to_dict(self) -> dict[str, Any]:
        return {
            "out": str(self.out),
            "store": self.store,
            "workers": self.workers,
            "wall_seconds": round(self.wall_seconds, 3),
            "counts": {s: self.count(s) for s in ("issued", "skipped", "failed")},
            "plans": [o.to_dict() for o in self.outcomes],
            "set_aside": self.set_aside,
        }


@contextlib.contextmanager
def _exclusive(out: Path) -> Iterator[None]:
    """Hold ``out``'s batch lock: two batches never write into the same folder at once (the
    second is refused), which makes it safe to remove the staging folders a killed run left."""
    with open(out / LOCK_NAME, "a+") as fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise ConfigError(
                f"{out}: another batch is writing into this folder; wait for it, or give "
                "another --out"
            ) from None
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _check_batch_json(out: Path) -> None:
    """A ``batch.json`` already in ``out`` must be a batch's (each run of the same batch
    rewrites it); anything else there is the user's and is never replaced."""
    path = out / BATCH_JSON
    if not path.exists():
        return
    try:
        listed = json.loads(path.read_text(encoding="utf-8"))
        ours = isinstance(listed, dict) and {"counts", "plans"} <= listed.keys()
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        ours = False
    if not ours:
        raise ConfigError(
            f"{path} exists and is not a batch's list of plans; it is never replaced: move it "
            "away, or give another --out"
        )


def _write_json(out: Path, result: BatchResult) -> None:
    """``batch.json``, whole or not at all (written beside, then renamed over the last one)."""
    text = json.dumps(result.to_dict(), indent=2, ensure_ascii=False) + "\n"
    partial = out / f".{BATCH_JSON}.partial"
    partial.write_text(text, encoding="utf-8")
    os.replace(partial, out / BATCH_JSON)


class _Run:
    """The client's side of one batch: submits tasks, and as they end draws numbers, keeps
    records and publishes folders (SQLite), and fills in the outcomes."""

    def __init__(
        self,
        client: Client,
        store: Store,
        out: Path,
        staging: Path,
        entries: Sequence[BatchPlan],
        outcomes: list[PlanOutcome],
        advance: Callable[[str], None],
        direct: bool,
        signer: Signer | None = None,
    ) -> None:
        self.client, self.store, self.out, self.staging = client, store, out, staging
        self.entries, self.outcomes, self.advance = entries, outcomes, advance
        self.direct = direct  # the workers write the records (else this process does)
        self.signer = signer
        self.drawn: dict[int, str] = {}  # numbers drawn for plans not yet kept (SQLite)
        self.task_of: dict[Future, int] = {}  # a running task → its plan's index

    def submit(self, index: int) -> Future:
        path = str(self.entries[index].path)
        future: Future
        if self.direct:
            future = self.client.submit(
                certify_task,
                path,
                str(self.out),
                str(self.staging),
                self.store.url,
                self.signer,
                pure=False,
            )
        else:
            future = self.client.submit(measure_task, path, str(self.staging), pure=False)
        self.task_of[future] = index
        return future

    def finished(self, future: Future, value: object) -> Future | None:
        """Take a finished task's result (``value``, fetched with it by ``as_completed``); the
        plan's next task, if it has one."""
        index = self.task_of.pop(future)
        if isinstance(value, BaseException):  # the task died with its workers, or was cancelled
            reason = " ".join(str(value).split())
            value = Failed(f"its task was lost: {type(value).__name__}: {reason}", 0.0)
        assert isinstance(value, (Measured, Failed, Done))
        if isinstance(value, Measured):  # SQLite: number it here, render it there
            return self._number(index, value)
        if isinstance(value, Failed):
            self._fail(index, value)
        elif value.measured is not None:  # SQLite: rendered there, kept and published here
            self._keep(index, value)
        else:
            self._end(index, "issued", value.number, value.seconds, value.warnings)
        return None

    def _end(
        self,
        index: int,
        status: str,
        number: str | None,
        seconds: float,
        warnings: tuple[str, ...] = (),
        error: str | None = None,
    ) -> None:
        outcome = self.outcomes[index]
        outcome.status, outcome.number, outcome.error = status, number, error
        outcome.seconds, outcome.warnings = seconds, list(warnings)
        self.advance(self.entries[index].path.name)

    def _fail(self, index: int, failure: Failed) -> None:
        self._void(index, failure.error)
        earlier = failure.certified_as
        sha = self.entries[index].sha256
        if earlier is None and sha is not None:  # issued meanwhile by another writer?
            with contextlib.suppress(RotacalError):
                earlier = self.store.issued_with(sha)
        if earlier is not None and (self.out / earlier).is_dir():
            # this batch's own certificate: a worker issued it and was lost before it reported,
            # and Dask ran the plan again, which found it done (not done when the batch started)
            note = "issued by a worker that was lost before it reported (the retry found it)"
            self._end(index, "issued", earlier, failure.seconds, (note,))
        elif earlier is not None:
            self._end(index, "skipped", earlier, failure.seconds)
        else:
            self._end(index, "failed", None, failure.seconds, error=failure.error)

    def _void(self, index: int, reason: str) -> None:
        number = self.drawn.pop(index, None)
        if number is not None:
            with contextlib.suppress(RotacalError):
                self.store.void_number(number, f"not issued: {reason}")

    def _number(self, index: int, measured: Measured) -> Future | None:
        plan = measured.content.plan
        try:
            # issued meanwhile by another writer? the record's unique plan_sha256 refuses it at
            # keep, and _fail then counts the plan as skipped: no query here for each plan
            number = plan.number
            if number == "auto":
                number = self.store.draw_number(plan.issue_date, plan=plan)
                self.drawn[index] = number
            if (self.out / number).exists():
                raise ConfigError(
                    f"{self.out / number} exists: a certificate folder is never replaced; "
                    "move it away, or give another --out"
                )
        except RotacalError as e:
            shutil.rmtree(measured.staging, ignore_errors=True)
            self._fail(index, Failed(f"{plan.path}: {e}", measured.seconds))
            return None
        future = self.client.submit(render_task, measured, number, self.signer, pure=False)
        self.task_of[future] = index
        return future

    def _keep(self, index: int, done: Done) -> None:
        from rotacal.certificate.issue import publish

        assert done.measured is not None
        staging = Path(done.measured.staging)
        try:
            publish(done.measured.content, staging, self.out / done.number, self.store)
        except RotacalError as e:
            shutil.rmtree(staging, ignore_errors=True)
            self._fail(index, Failed(" ".join(str(e).split()), done.seconds))
            return
        self.drawn.pop(index, None)
        self._end(index, "issued", done.number, done.seconds, done.warnings)


def run_batch(
    plans: Sequence[str | os.PathLike[str]],
    *,
    out: str | os.PathLike[str] | None = None,
    db: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Client | None = None,
    advance: Callable[[str], None] | None = None,
    on_start: Callable[[int, str | None], None] | None = None,
    records_from_workers: bool | None = None,
    signer: Signer | None = None,
) -> BatchResult:
    """Certify many plans as tasks on Dask distributed (INTERFACE.md "Batches").

    Parameters
    ----------
    plans : sequence of path
        Plan files, or folders whose ``*.toml`` files are plans.
    out : path, optional
        The folder that gets each certificate's folder (``OUT/<number>/``) and ``batch.json``
        [default: the current folder]; made when missing.
    db : str, optional
        The records store's URL [default: ``ROTACAL_DB``, else the user's SQLite file].
    workers : int, optional
        Worker processes of the local cluster [default: one per core].
    scheduler : str, optional
        The address of a running Dask scheduler (``tcp://host:8786``) instead of a local
        cluster; its workers must see the plans, captures and ``out`` at the same paths.
    client : distributed.Client, optional
        A client to use as it is (tests, notebooks).
    advance : callable, optional
        Called with the plan's file name each time a plan ends (a progress bar).
    on_start : callable, optional
        Called with the number of plans to run and the dashboard's link (or None) once the
        cluster is up; not called when every plan was done already.
    records_from_workers : bool, optional
        Whether the workers write the records store themselves [default: always for
        PostgreSQL; for SQLite when every worker runs on this machine, where SQLite's lock
        serialises them — an SQLite file is not safe to share between machines, so with
        workers elsewhere this process writes it].
    signer : Signer, optional
        Sign every certificate.xml as ``rotacal certify --sign-key`` does
        (:func:`rotacal.certificate.sign.load_signer`, read once here and sent to the workers);
        a plan whose date of issue the signing certificate does not cover fails alone, before
        it runs [default: unsigned].

    Returns
    -------
    BatchResult
        Also written to ``OUT/batch.json``.

    Raises
    ------
    ConfigError, StoreError
        No plans, an unusable ``out``, store or scheduler; nothing has run.
    BatchInterruptedError
        Stopped by Ctrl-C; ``batch.json`` says what ended, and a second run finishes the rest.
    """
    from rotacal.records import open_store

    start = time.perf_counter()
    paths = find_plans(plans)
    target = Path(out if out is not None else os.getcwd()).resolve()
    if target.exists() and not target.is_dir():
        raise ConfigError(f"--out {target}: exists and is not a folder")
    target.mkdir(parents=True, exist_ok=True)
    advance = advance or (lambda label: None)
    store = open_store(db)
    try:
        with _exclusive(target):
            _check_batch_json(target)
            staging = target / STAGING_NAME
            shutil.rmtree(staging, ignore_errors=True)  # what a killed run left
            staging.mkdir()
            try:
                cluster = _Cluster(workers, scheduler, client, records_from_workers)
                result = _run(paths, target, staging, store, cluster, advance, on_start, signer)
            finally:
                shutil.rmtree(staging, ignore_errors=True)
            unfinished = [o for o in result.outcomes if o.status == "pending"]
            for o in unfinished:
                o.status, o.error = "failed", "interrupted; run the batch again to finish it"
            result.wall_seconds = time.perf_counter() - start
            _write_json(target, result)
    finally:
        store.close()
    if unfinished:
        raise BatchInterruptedError(
            f"batch stopped: {result.count('issued')} issued, {result.count('skipped')} "
            f"skipped, {len(unfinished)} not finished ({target / BATCH_JSON}); run the same "
            "batch again to finish it"
        )
    return result


@dataclasses.dataclass(frozen=True)
class _Cluster:
    """Where the tasks run (run_batch's arguments) and who writes the records."""

    workers: int | None
    scheduler: str | None
    client: Client | None
    records_from_workers: bool | None

    def direct(self, dask: Client, store: Store) -> bool:
        """Whether the workers write the records: see :func:`run_batch`."""
        if self.records_from_workers is not None:
            return self.records_from_workers
        if store.engine.dialect.name != "sqlite":
            return True
        return all(_on_this_machine(a) for a in dask.scheduler_info().get("workers", {}))


def _on_this_machine(address: str) -> bool:
    """Whether a worker's address (``tcp://host:port``) is on this machine."""
    import socket
    from urllib.parse import urlsplit

    host = urlsplit(address).hostname or ""
    if host in ("localhost", "::1") or host.startswith("127."):
        return True
    try:
        return host in socket.gethostbyname_ex(socket.gethostname())[2]
    except OSError:
        return False


def _run(
    paths: Sequence[Path],
    out: Path,
    staging: Path,
    store: Store,
    cluster: _Cluster,
    advance: Callable[[str], None],
    on_start: Callable[[int, str | None], None] | None,
    signer: Signer | None = None,
) -> BatchResult:
    entries = read_batch_plans(paths)
    outcomes = [PlanOutcome(str(e.path)) for e in entries]
    first_of: dict[str, int] = {}
    twin_of: dict[int, int] = {}  # a plan named twice (same plan_sha256): its first
    todo = []
    for i, (entry, outcome) in enumerate(zip(entries, outcomes, strict=True)):
        if entry.error is None:
            assert entry.plan is not None and entry.sha256 is not None
            try:
                earlier = store.issued_with(entry.sha256)
                if earlier is None:
                    store.check_plan(entry.plan)
                    if signer is not None:  # as certify: refused before anything is measured
                        signer.check_valid_on(entry.plan.issue_date)
            except RotacalError as e:
                entry.error = " ".join(str(e).split())
            else:
                if earlier is not None:
                    outcome.status, outcome.number = "skipped", earlier
                elif entry.sha256 in first_of:
                    twin_of[i] = first_of[entry.sha256]
                    continue
                else:
                    first_of[entry.sha256] = i
                    todo.append(i)
        if entry.error is not None:
            outcome.status, outcome.error = "failed", entry.error
        if outcome.status != "pending":
            advance(entry.path.name)
    result = BatchResult(outcomes, out, store.shown, 0, 0.0)
    if not todo:
        _settle_twins(outcomes, twin_of, advance)
        result.set_aside = _set_aside_unrecorded(out, store, entries, outcomes)
        return result
    from distributed import as_completed

    with dask_client(cluster.workers, cluster.scheduler, cluster.client) as dask:
        result.workers = len(dask.scheduler_info().get("workers", {}))
        local = cluster.scheduler is None and cluster.client is None
        result.dashboard = dashboard_link(dask, local=local)
        if on_start is not None:
            on_start(len(todo), result.dashboard)
        direct = cluster.direct(dask, store)
        run = _Run(dask, store, out, staging, entries, outcomes, advance, direct, signer)
        # results come with their futures (fetched in the background, not one round trip each);
        # a lost or cancelled task comes with its exception
        pending = as_completed([run.submit(i) for i in todo], with_results=True, raise_errors=False)
        try:
            for future, value in pending:
                follow = run.finished(future, value)
                if follow is not None:
                    pending.add(follow)
        except KeyboardInterrupt:
            dask.cancel(list(run.task_of))
            for index in list(run.drawn):
                run._void(index, "the batch was stopped (Ctrl-C)")
    _settle_twins(outcomes, twin_of, advance)
    result.set_aside = _set_aside_unrecorded(out, store, entries, outcomes)
    return result


def _set_aside_unrecorded(
    out: Path, store: Store, entries: Sequence[BatchPlan], outcomes: Sequence[PlanOutcome]
) -> list[str]:
    """Move aside the certificate folders of this batch's plans that have no record.

    A worker that writes the records publishes a folder inside the record's transaction; killed
    between the two (the commit's fsync takes milliseconds), it leaves a folder whose record was
    rolled back, while Dask runs the plan again under another number. Such a folder is moved to
    ``out/.rotacal-unrecorded/`` (not deleted) and its number voided with the reason. Only folders
    named by their own ``results.json`` number, of a plan of this batch, whose plan has another
    or no record, are touched; the folders of the plans' known numbers are not even read.
    """
    known = {o.number for o in outcomes if o.number}
    shas = {e.sha256 for e in entries if e.sha256}
    moved = []
    for folder in sorted(out.iterdir()):
        if folder.name.startswith(".") or folder.name in known or not folder.is_dir():
            continue
        try:
            results = json.loads((folder / "results.json").read_text(encoding="utf-8"))
            sha, number = results["plan_sha256"], results["certificate_number"]
        except (OSError, ValueError, KeyError, TypeError):
            continue  # not a certificate folder
        if number != folder.name or sha not in shas:
            continue
        try:
            if store.issued_with(sha) == number:
                continue
            store.void_number(number, "its worker was lost while the record was being kept")
        except RotacalError:
            continue
        aside = out / UNRECORDED_NAME
        aside.mkdir(exist_ok=True)
        os.rename(folder, aside / f"{number}-{time.strftime('%Y%m%dT%H%M%S')}")
        moved.append(number)
    return moved


def _settle_twins(
    outcomes: list[PlanOutcome], twin_of: dict[int, int], advance: Callable[[str], None]
) -> None:
    """A plan named twice ran once: the second is skipped with the first's number, or fails
    with it."""
    for i, first in twin_of.items():
        done, twin = outcomes[first], outcomes[i]
        if done.status in ("issued", "skipped"):
            twin.status, twin.number = "skipped", done.number
        elif done.status == "failed":
            twin.status, twin.error = "failed", done.error
        if twin.status != "pending":
            twin.warnings = list(done.warnings)
            advance(Path(twin.plan).name)
