"""``rotacal records``: the certificates issued — list, show, an item's history, the audit trail,
export/import, the schema's upgrade and the laboratory's settings."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from rotacal.errors import ConfigError

from ._app import cli
from ._common import _check_outputs, _emit_warnings, _write_json, _wrote
from ._help import example
from ._store import db_option, open_db

_JSON_HELP = "Write the result as JSON ('-' = stdout)."


@cli.group(
    "records",
    epilog=example(
        "rotacal records list                 # newest first",
        "rotacal records show RC-2026-0001",
        "rotacal records history SN-0001 --report history.html",
        "rotacal records audit                # every state change, chain checked",
        "rotacal records export --out backup.jsonl",
        "rotacal records import backup.jsonl --db postgresql+psycopg://lab@server/records",
    ),
)
def records_group() -> None:
    """Issued certificates: list, show, history, audit, backup.

    The records of ISO/IEC 17025 §7.5 and §8.4.

    Every certificate `rotacal certify` issues is kept, unchanged, in the records store: an
    SQLite file in your data folder by default, or a PostgreSQL database shared by the test
    stations (--db URL or ROTACAL_DB). A correction is a new certificate whose plan says
    supersedes = "NUMBER"; both stay.
    """


def _table(rows: list[list[str]], header: list[str]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = [
        "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
        for r in [header, *rows]
    ]
    return "\n".join(lines)


def _conformity_text(tally: dict[str, int]) -> str:
    return ", ".join(f"{n} {v}" for v, n in tally.items()) or "—"


@records_group.command(
    "list",
    epilog=example("rotacal records list --serial SN-0001", "rotacal records list --json -"),
)
@click.option("--serial", default=None, metavar="S", help="Only the certificates of this item.")
@click.option("--json", "json_path", metavar="PATH", help=_JSON_HELP)
@click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")
@db_option
def list_cmd(serial: str | None, json_path: str | None, overwrite: bool, db: str | None) -> None:
    """The certificates issued, newest first."""
    from rotacal.records.query import list_certificates

    _check_outputs(json_path, None, overwrite)
    store = open_db(db)
    rows = list_certificates(store, serial)
    _write_json({"store": store.shown, "certificates": rows}, json_path)
    if json_path == "-":
        return
    if not rows:
        click.echo(f"no certificates{f' of {serial}' if serial else ''} in {store.shown}")
        return
    table = [
        [
            r["number"],
            r["issue_date"],
            f"{r['item']['manufacturer']} {r['item']['model']} {r['item']['serial']}",
            r["customer"],
            _conformity_text(r["conformity"]),
            f"superseded by {r['superseded_by']}" if r["superseded_by"] else "",
        ]
        for r in rows
    ]
    click.echo(_table(table, ["number", "issued", "item", "customer", "conformity", ""]))


@records_group.command(
    "show",
    epilog=example(
        "rotacal records show RC-2026-0001",
        "rotacal records show RC-2026-0001 --files RC-2026-0001-copy",
    ),
)
@click.argument("number")
@click.option("--json", "json_path", metavar="PATH", help=_JSON_HELP)
@click.option(
    "--files",
    "files_dir",
    metavar="DIR",
    default=None,
    help="Write the certificate's files as issued (PDF, XML, results.json, figures) into the new "
    "folder DIR.",
)
@click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")
@db_option
def show_cmd(
    number: str, json_path: str | None, files_dir: str | None, overwrite: bool, db: str | None
) -> None:
    """One certificate's whole record.

    The plan as given, plan_sha256, the captures' SHA-256, results, conformity, the files with
    their SHA-256, who recorded it, and the certificates it supersedes or is superseded by.
    """
    from rotacal.records.query import certificate_record, restore_files

    _check_outputs(json_path, None, overwrite)
    store = open_db(db)
    record = certificate_record(store, number)
    _write_json(record, json_path)
    if files_dir is not None:
        for path in restore_files(store, number, Path(files_dir)):
            _wrote(path)
    if json_path == "-":
        return
    item = record["item"]
    lines = [
        f"certificate {record['number']}: {record['title']}",
        f"  item        {item['kind']} {item['manufacturer']} {item['model']}, "
        f"serial {item['serial']}",
        f"  customer    {record['customer'].get('name', '')}",
        f"  calibrated  {record['start_date']}"
        + (f" to {record['end_date']}" if record["end_date"] != record["start_date"] else ""),
        f"  issued      {record['issue_date']} (recorded {record['recorded_at']} by "
        f"{record['recorded_by']}, rotacal {record['software_version']})",
        f"  plan        {record['plan']['name']}, plan_sha256 {record['plan_sha256']}",
        "  standards   "
        + "; ".join(f"{s['id']} ({s['certificate']}, due {s['due']})" for s in record["standards"]),
    ]
    for c in record["conformity"]:
        lines.append(f"  conformity  {c['measurement']}: {c['quantity']} {c['verdict']}")
    if record["supersedes"]:
        lines.append(f"  supersedes  {record['supersedes']}")
    if record["superseded_by"]:
        lines.append(f"  SUPERSEDED by {record['superseded_by']}")
    if record["approved_by"]:
        lines.append(f"  approved    by {record['approved_by']} at {record['approved_at']}")
    lines.append("  audit trail" + ("" if record["audit_intact"] else " BROKEN"))
    lines += [f"    {_event_text(e)}" for e in record["audit"]]
    lines += [f"    ! {p}" for p in record["audit_problems"]]
    click.echo("\n".join(lines))


def _event_text(e: dict[str, Any]) -> str:
    change = f"{e['from_state'] or '—'} → {e['to_state']}"
    return f"{e['at'][:19]}Z  {change}  by {e['who']}: {e['reason']}"


@records_group.command(
    "audit",
    epilog=example(
        "rotacal records audit                      # the whole store",
        "rotacal records audit RC-2026-0001 --json -",
    ),
)
@click.argument("number", required=False)
@click.option("--json", "json_path", metavar="PATH", help=_JSON_HELP)
@click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")
@db_option
def audit_cmd(number: str | None, json_path: str | None, overwrite: bool, db: str | None) -> None:
    """The audit trail, checked: every state change of each number.

    Drawn (draft), issued (who approved, when), superseded, voided: appended in the transaction
    of the change, never changed. Each number's events are a SHA-256 hash chain; the command
    recomputes it and checks it against the records. Exit 0 when it holds; exit 1 and the first
    broken event of each chain when it does not.
    """
    from rotacal.records.query import audit_trail

    _check_outputs(json_path, None, overwrite)
    store = open_db(db)
    trail = audit_trail(store, number)
    _write_json(trail, json_path)
    events, problems = trail["events"], trail["problems"]
    if json_path != "-":
        for e in events:
            click.echo((f"{e['number']}  " if number is None else "") + _event_text(e))
        numbers = len({e["number"] for e in events})
        where = number or f"{store.shown} ({numbers} numbers)"
        if not problems:
            click.echo(f"audit trail of {where}: intact, {len(events)} events")
    for problem in problems:
        click.echo(f"rotacal: audit trail broken: {problem}", err=True)
    if problems:
        sys.exit(1)


@records_group.command(
    "history",
    epilog=example(
        "rotacal records history SN-0001",
        "rotacal records history SN-0001 --json h.json --report h.html",
    ),
)
@click.argument("serial")
@click.option(
    "--model", default=None, metavar="M", help="The item's model, when several share the serial."
)
@click.option("--json", "json_path", metavar="PATH", help=_JSON_HELP)
@click.option("--report", "report_path", metavar="PATH.html", help="Write an HTML report.")
@click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files.")
@db_option
def history_cmd(
    serial: str,
    model: str | None,
    json_path: str | None,
    report_path: str | None,
    overwrite: bool,
    db: str | None,
) -> None:
    """An item's calibrations, drift and next due date.

    Each reported quantity with its U at each calibration; the drift per year by weighted least
    squares with its uncertainty; next_due: when the predicted value plus its expanded
    uncertainty reaches the acceptance limit, or the laboratory's fixed interval when no drift
    is significant (ILAC-G24).
    """
    from rotacal.records.history import item_history

    _check_outputs(json_path, report_path, overwrite)
    store = open_db(db)
    history = item_history(store, serial, model=model)
    _emit_warnings(history)
    _write_json(history.to_dict(), json_path)
    if report_path:
        from rotacal.report.history import history_report
        from rotacal.report.html import write_html

        from ._common import _declared_inputs, _overwrite_given, _status

        with _status("drawing the report"):
            write_html(
                history_report(history, store.shown),
                report_path,
                overwrite=_overwrite_given(),
                inputs=_declared_inputs(),
                label=f"--report {report_path}",
            )
        _wrote(report_path)
    if json_path == "-":
        return
    data = history.to_dict()
    due = data["next_due"]
    click.echo(f"{serial}: {len(data['calibrations'])} calibrations; next due {due['date']}")
    click.echo(f"  {due['method']}")
    for key, drift in data["drift_per_year"].items():
        if drift.get("value") is None:
            continue
        mark = "significant" if drift.get("significant") else "not significant"
        click.echo(
            f"  drift of {key}: {drift['value']:.3g} {drift.get('unit', '')}, "
            f"u = {drift['u']:.2g} ({mark})"
        )


@records_group.command("export", epilog=example("rotacal records export --out backup.jsonl"))
@click.option(
    "--out", metavar="FILE.jsonl", default=None, help="The export file [default: stdout]."
)
@db_option
def export_cmd(out: str | None, db: str | None) -> None:
    """Every record as JSON lines, for a backup.

    Loss-free: the same store always exports to the same bytes, and `rotacal records import`
    puts every record into another store (SQLite or PostgreSQL) as it was.
    """
    from rotacal.records.exchange import export_lines, export_to

    store = open_db(db)
    if out is None:
        sys.stdout.writelines(export_lines(store))
        return
    if not out.endswith(".jsonl"):
        raise ConfigError(f"--out {out}: the export is JSON lines; give a name ending in .jsonl")
    export_to(store, Path(out))
    _wrote(out)


@records_group.command(
    "import",
    epilog=example(
        "rotacal records import backup.jsonl --db postgresql+psycopg://lab@server/records"
    ),
)
@click.argument("file", metavar="FILE.jsonl")
@db_option
def import_cmd(file: str, db: str | None) -> None:
    """Import an export into the store.

    All of it or nothing: every file is checked against its SHA-256 first. A certificate the
    store holds already is skipped when identical and refused when it differs.
    """
    from rotacal.records.exchange import import_lines

    store = open_db(db)
    with open(file, encoding="utf-8") as lines:
        summary = import_lines(store, lines, file)
    for line in summary["warnings"]:
        click.echo(f"rotacal: warning: {line}", err=True)
    click.echo(
        f"imported {summary['imported']} certificates into {store.shown}"
        + (f" ({summary['unchanged']} were there already)" if summary["unchanged"] else "")
    )


@records_group.command(
    "upgrade",
    epilog=example("rotacal records upgrade", "rotacal records upgrade --db sqlite:///lab.sqlite"),
)
@db_option
def upgrade_cmd(db: str | None) -> None:
    """Migrate an older store's schema to this rotacal's.

    Alembic migrations, in one transaction: a failed upgrade leaves the store as it was. Back the
    store up first (`rotacal records export`).
    """
    from rotacal.records.schema import upgrade

    store = open_db(db, check_schema=False)
    with store.errors():
        before, after = upgrade(store.engine, store.shown)
    if before == after:
        click.echo(f"{store.shown}: schema revision {after}, already this rotacal's")
    else:
        click.echo(f"{store.shown}: schema upgraded from revision {before or 'none'} to {after}")


@records_group.command(
    "settings",
    epilog=example(
        "rotacal records settings",
        'rotacal records settings --number-format "LAB-{year}-{count:05d}"',
    ),
)
@click.option(
    "--number-format",
    default=None,
    metavar="F",
    help='The series of number = "auto", with {year} and {count}, e.g. "LAB-{year}-{count:05d}".',
)
@click.option(
    "--interval-months",
    default=None,
    metavar="N",
    help="The fixed calibration interval, when no drift sets the next due date.",
)
@db_option
def settings_cmd(number_format: str | None, interval_months: str | None, db: str | None) -> None:
    """Show or change the laboratory's settings.

    The number series of number = "auto" and the fixed calibration interval; kept in the store,
    so that every station shares them.
    """
    store = open_db(db)
    changes: dict[str, Any] = {}
    if number_format is not None:
        changes["number_format"] = number_format
    if interval_months is not None:
        changes["interval_months"] = interval_months
    values = store.set_settings(**changes) if changes else store.settings()
    for key, value in values.items():
        click.echo(f"{key} = {value}")
