"""``rotacal batch``: many plans certified on Dask distributed, resumable, into the records store."""

from __future__ import annotations

import statistics
from typing import TYPE_CHECKING

import click

from ._app import cli
from ._common import _progress, _wrote
from ._help import example
from ._sign import load_sign_options, sign_options
from ._store import db_option

if TYPE_CHECKING:
    from rotacal.batch import BatchResult


@cli.command(
    "batch",
    epilog=example(
        "rotacal batch plans/ --out certs     # every .toml file of plans/",
        "rotacal batch unit-1.toml unit-2.toml --out certs --workers 2",
        "rotacal batch plans/ --out /shared/certs --scheduler tcp://head:8786",
        "rotacal batch plans/ --out certs --sign-key lab.key --sign-cert lab.pem",
    ),
)
@click.argument("plans", nargs=-1, required=True, metavar="PLAN...")
@click.option(
    "--out",
    metavar="DIR",
    default=None,
    help="The folder for the certificates (DIR/<number>/) and batch.json [default: the current "
    "folder].",
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Worker processes of the local Dask cluster [default: one per core].",
)
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="A running Dask scheduler (tcp://host:8786) instead of a local cluster; its workers must "
    "see the plans, captures and --out at the same paths.",
)
@sign_options
@db_option
def batch_command(
    plans: tuple[str, ...],
    out: str | None,
    workers: int | None,
    scheduler: str | None,
    sign_key: str | None,
    sign_cert: str | None,
    db: str | None,
) -> None:
    """Certify many plans as tasks on Dask distributed.

    PLAN... are plan files or folders of them (their .toml files). A plan whose plan and
    captures were certified already is skipped, so a stopped batch is finished by running it
    again; a plan that fails fails alone, with its reason in DIR/batch.json. Exit code 2 when
    any plan failed. With --sign-key and --sign-cert every certificate issued is signed as
    `rotacal certify` signs it (the key read and checked once, here).
    """
    from rotacal.batch import run_batch
    from rotacal.batch.plans import find_plans

    if workers is not None and scheduler is not None:
        raise click.UsageError("give --workers (a local cluster) or --scheduler, not both")
    signer = load_sign_options(sign_key, sign_cert)  # read and checked once, before the cluster

    def started(count: int, dashboard: str | None) -> None:
        if dashboard:
            click.echo(f"Dask dashboard: {dashboard}", err=True)

    with _progress(len(find_plans(plans)), "certifying") as advance:
        result = run_batch(
            plans,
            out=out,
            db=db,
            workers=workers,
            scheduler=scheduler,
            advance=advance,
            on_start=started,
            signer=signer,
        )
    _wrote(result.out / "batch.json")
    _summary(result)
    if signer is not None and result.count("issued"):
        click.echo(f"signed by {signer.name} (certificate {signer.cert_path})")
    if result.failed:
        raise SystemExit(2)


def _summary(result: BatchResult) -> None:
    """The final table: plans issued / skipped / failed with their times, then each failure."""
    click.echo(f"{'plans':<9}{'count':>7}   median time a plan")
    for status in ("issued", "skipped", "failed"):
        times = [o.seconds for o in result.outcomes if o.status == status and o.seconds]
        median = f"{statistics.median(times):.2f} s" if times else "-"
        click.echo(f"{status:<9}{result.count(status):>7}   {median}")
    where = f"on {result.workers} worker(s)" if result.workers else "(nothing left to run)"
    click.echo(
        f"{len(result.outcomes)} plans in {result.wall_seconds:.1f} s {where}; "
        f"records: {result.store}"
    )
    if result.set_aside:
        click.echo(
            f"moved aside {len(result.set_aside)} certificate folder(s) without a record (a "
            f"worker lost before its record was kept): {result.out / '.rotacal-unrecorded'}",
            err=True,
        )
    for o in result.outcomes:
        if o.status == "failed":
            click.echo(f"failed: {o.error}", err=True)
