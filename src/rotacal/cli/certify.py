"""``rotacal certify``: a calibration plan in, a certificate out (PDF, PTB DCC, results.json)."""

from __future__ import annotations

from importlib import resources

import click

from ._app import cli
from ._common import _progress, _wrote
from ._help import example
from ._sign import load_sign_options, sign_options
from ._store import db_option, open_db


def example_plan() -> str:
    """The commented example plan (``rotacal certify --example``)."""
    return resources.files("rotacal.plan").joinpath("example.toml").read_text(encoding="utf-8")


@cli.command(
    "certify",
    epilog=example(
        "rotacal certify --example             # a commented plan",
        "rotacal certify plan.toml             # → a folder named by its number",
        "rotacal certify plan.toml --out cert --overwrite",
        "rotacal certify plan.toml --sign-key lab.key --sign-cert lab.pem",
    ),
)
@click.argument("plan", required=False, metavar="PLAN.toml")
@click.option(
    "--out",
    metavar="DIR",
    default=None,
    help="The certificate's folder [default: a folder named after the certificate number, "
    "beside the plan].",
)
@db_option
@click.option(
    "--no-record",
    is_flag=True,
    help="Do not keep the certificate in the records store (the plan must then give its number).",
)
@click.option("--overwrite", is_flag=True, help="Replace an existing certificate folder.")
@click.option("--example", "show_example", is_flag=True, help="Print a commented plan and exit.")
@sign_options
def certify_command(
    plan: str | None,
    out: str | None,
    db: str | None,
    no_record: bool,
    overwrite: bool,
    show_example: bool,
    sign_key: str | None,
    sign_cert: str | None,
) -> None:
    """Run a calibration plan and issue its certificate.

    The plan (TOML) names the laboratory, the customer, the item, the reference standards, the
    conditions and the measurements with their captures, options and acceptance limits. The
    certificate folder gets certificate.pdf (ISO/IEC 17025 §7.8), certificate.xml (PTB Digital
    Calibration Certificate v3.1.2), results.json and the figures — whole, or not at all. The
    certificate is kept in the records store (--db) in the same step, unless --no-record.
    """
    if show_example:
        click.echo(example_plan(), nl=False)
        return
    if plan is None:
        raise click.UsageError("give the plan file (PLAN.toml), or --example to see one")
    from rotacal.certificate.issue import certify, plan_measurement_count

    signer = load_sign_options(sign_key, sign_cert)
    store = None if no_record else open_db(db)
    with _progress(plan_measurement_count(plan), "measuring") as advance:
        issued = certify(
            plan, out=out, overwrite=overwrite, advance=advance, registry=store, signer=signer
        )
    for name in issued.files:
        _wrote(issued.folder / name)
    verdicts = [c.verdict for m in issued.content.measurements for c in m.conformity]
    summary = ", ".join(
        f"{verdicts.count(v)} {v}" for v in ("pass", "fail", "indeterminate") if v in verdicts
    )
    click.echo(
        f"certificate {issued.number}: {len(issued.content.measurements)} measurements"
        + (f"; conformity: {summary}" if summary else "")
        + (f"; signed by {signer.name}" if signer is not None else "")
        + (f"; recorded in {store.shown}" if store is not None else "; not recorded")
    )
