"""What a Dask worker does for a batch: the steps of issuing one plan's certificate.

Every task returns what happened as a value and never raises a user's fault, so that the client
can name the plan and the reason in one line and go on with the others. A task that dies with its
worker leaves at most a hidden staging folder, which the batch removes; it never leaves a
certificate folder without its record.

Two ways to keep the records (``rotacal batch`` chooses by the store and where the workers are):

- **The workers** write the store themselves: :func:`certify_task` runs
  :func:`rotacal.certificate.issue.certify` against it. PostgreSQL keeps numbers unique between
  any number of writers; an SQLite file does so for the workers of one machine (its lock
  serialises their transactions).
- **The client** writes it, for an SQLite file and workers on other machines (a file shared
  between machines is not safe): the worker measures the plan and draws its figures
  (:func:`measure_task`), the client draws the number, the worker renders the certificate with
  it (:func:`render_task`), and the client keeps it and publishes its folder in one step.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import shutil
import time
import traceback
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from rotacal.errors import AlreadyCertifiedError, RotacalError

if TYPE_CHECKING:
    from rotacal.certificate.content import CertificateContent
    from rotacal.certificate.sign import Signer
    from rotacal.records import Store

__all__ = [
    "Done",
    "Failed",
    "Measured",
    "certify_task",
    "measure_task",
    "open_store_urls",
    "render_task",
]


@dataclasses.dataclass(frozen=True)
class Measured:
    """A plan measured on a worker, its figures drawn into ``staging``: waiting for its number."""

    content: CertificateContent
    staging: str
    seconds: float


@dataclasses.dataclass(frozen=True)
class Done:
    """A certificate issued by a worker (PostgreSQL), or rendered and waiting to be kept
    (SQLite: ``measured`` then holds it with its number)."""

    number: str
    seconds: float
    warnings: tuple[str, ...] = ()
    measured: Measured | None = None


@dataclasses.dataclass(frozen=True)
class Failed:
    """The plan was not issued: the one-line reason; ``certified_as`` when the same plan and
    captures have a certificate already (the batch counts it as skipped)."""

    error: str
    seconds: float
    certified_as: str | None = None


def _one_line(e: BaseException) -> str:
    """A fault as one line: a user's fault as rotacal says it, anything else with its type."""
    if isinstance(e, RotacalError):
        return " ".join(str(e).split())
    return f"internal error, please report it: {type(e).__name__}: {' '.join(str(e).split())}"


def _failed(e: BaseException, start: float) -> Failed:
    if not isinstance(e, RotacalError):  # a defect of ours: its traceback goes to the worker's log
        traceback.print_exception(e)
    number = e.number if isinstance(e, AlreadyCertifiedError) else None
    return Failed(_one_line(e), time.perf_counter() - start, certified_as=number)


def _warnings(content: CertificateContent) -> tuple[str, ...]:
    return tuple(f"{m.name}: {w}" for m in content.measurements for w in m.warnings)


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """The commands' summaries and warning lines stay out of the worker's log: the warnings are
    in the certificate's content, which the client reports."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        yield


def measure_task(plan_path: str, staging_root: str) -> Measured | Failed:
    """Run a plan's measurements and draw its figures into a new staging folder in
    ``staging_root`` (SQLite batches; the client checks the plan before it submits it)."""
    from rotacal.certificate.issue import measure_into, new_staging
    from rotacal.plan.read import read_plan

    start = time.perf_counter()
    staging = None
    try:
        plan = read_plan(plan_path)
        staging = new_staging(Path(staging_root))
        with _quiet():
            content = measure_into(plan, staging)
        return Measured(content, str(staging), time.perf_counter() - start)
    except Exception as e:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
        return _failed(e, start)


def render_task(measured: Measured, number: str, signer: Signer | None = None) -> Done | Failed:
    """Render a measured plan's certificate (results.json, DCC signed with ``signer``, PDF) under
    ``number`` into its staging folder (SQLite batches; the client keeps and publishes it)."""
    from rotacal.certificate.issue import render_into

    start = time.perf_counter()
    try:
        content = render_into(measured.content, number, Path(measured.staging), signer)
    except Exception as e:
        return _failed(e, start)
    seconds = measured.seconds + time.perf_counter() - start
    done = Measured(content, measured.staging, seconds)
    return Done(number, seconds, _warnings(content), done)


#: The records stores a worker has open, by URL: one connection pool per worker process.
_STORES: dict[str, Store] = {}


def open_store_urls() -> list[str]:
    """The URLs of the records stores this process has opened for its tasks (run it on the
    workers, ``client.run(open_store_urls)``, to see which of them write the records)."""
    return list(_STORES)


def _store(url: str) -> Store:
    from rotacal.records import open_store

    if url not in _STORES:
        _STORES[url] = open_store(url)
    return _STORES[url]


def certify_task(
    plan_path: str, out: str, staging_root: str, db_url: str, signer: Signer | None = None
) -> Done | Failed:
    """Issue a plan's certificate on the worker, keeping it in the records store at ``db_url``
    (workers that write the records): its folder is ``out``/NUMBER, staged in ``staging_root``;
    its DCC signed with ``signer``."""
    from rotacal.certificate.issue import certify

    start = time.perf_counter()
    try:
        with _quiet():
            issued = certify(
                plan_path, registry=_store(db_url), into=out, staging_in=staging_root, signer=signer
            )
    except Exception as e:
        return _failed(e, start)
    return Done(issued.number, time.perf_counter() - start, _warnings(issued.content))
