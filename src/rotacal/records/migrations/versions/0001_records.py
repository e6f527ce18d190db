"""The records: items, persons, reference standards, certificates with their inputs, files,
reported values and conformity; the number series and its voided numbers; settings.

Revision ID: 0001
Revises:
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None

DECIMAL = sa.String(64)


def _certificate_part(name: str, *columns: sa.schema.SchemaItem, key: tuple[str, ...]) -> None:
    """A table of one certificate's rows, keyed by the certificate and ``key``."""
    op.create_table(
        name,
        sa.Column("certificate_id", sa.Integer(), nullable=False),
        *columns,
        sa.ForeignKeyConstraint(
            ["certificate_id"], ["certificates.id"], name=op.f(f"fk_{name}_certificate_id")
        ),
        sa.PrimaryKeyConstraint("certificate_id", *key, name=op.f(f"pk_{name}")),
    )


def upgrade() -> None:
    op.create_table(
        "settings",
        sa.Column("key", sa.String(64), nullable=False),
        sa.Column("value", sa.Text(), nullable=False),
        sa.PrimaryKeyConstraint("key", name=op.f("pk_settings")),
    )
    op.create_table(
        "number_counters",
        sa.Column("scope", sa.String(16), nullable=False),
        sa.Column("last", sa.Integer(), nullable=False),
        sa.PrimaryKeyConstraint("scope", name=op.f("pk_number_counters")),
    )
    op.create_table(
        "voided_numbers",
        sa.Column("number", sa.String(128), nullable=False),
        sa.Column("voided_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("reason", sa.Text(), nullable=False),
        sa.PrimaryKeyConstraint("number", name=op.f("pk_voided_numbers")),
    )
    op.create_table(
        "items",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("kind", sa.String(64), nullable=False),
        sa.Column("manufacturer", sa.String(256), nullable=False),
        sa.Column("model", sa.String(256), nullable=False),
        sa.Column("serial", sa.String(256), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_items")),
        sa.UniqueConstraint(
            "kind",
            "manufacturer",
            "model",
            "serial",
            name=op.f("uq_items_kind_manufacturer_model_serial"),
        ),
    )
    op.create_index(op.f("ix_items_serial"), "items", ["serial"])
    op.create_table(
        "persons",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("name", sa.String(256), nullable=False),
        sa.Column("title", sa.String(256), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_persons")),
        sa.UniqueConstraint("name", "title", name=op.f("uq_persons_name_title")),
    )
    op.create_table(
        "standards",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("identifier", sa.String(256), nullable=False),
        sa.Column("name", sa.String(256), nullable=False),
        sa.Column("certificate", sa.String(256), nullable=False),
        sa.Column("due", sa.Date(), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_standards")),
        sa.UniqueConstraint(
            "identifier",
            "name",
            "certificate",
            "due",
            name=op.f("uq_standards_identifier_name_certificate_due"),
        ),
    )
    op.create_index(op.f("ix_standards_identifier"), "standards", ["identifier"])
    op.create_table(
        "certificates",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("number", sa.String(128), nullable=False),
        sa.Column("item_id", sa.Integer(), nullable=False),
        sa.Column("title", sa.Text(), nullable=False),
        sa.Column("laboratory", sa.Text(), nullable=False),
        sa.Column("customer", sa.Text(), nullable=False),
        sa.Column("start_date", sa.Date(), nullable=False),
        sa.Column("end_date", sa.Date(), nullable=False),
        sa.Column("issue_date", sa.Date(), nullable=False),
        sa.Column("plan_name", sa.Text(), nullable=False),
        sa.Column("plan", sa.LargeBinary(), nullable=False),
        sa.Column("plan_sha256", sa.String(64), nullable=False),
        sa.Column("results", sa.Text(), nullable=False),
        sa.Column("software_version", sa.String(64), nullable=False),
        sa.Column("supersedes", sa.String(128), nullable=True),
        sa.Column("recorded_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("recorded_by", sa.String(256), nullable=False),
        sa.ForeignKeyConstraint(["item_id"], ["items.id"], name=op.f("fk_certificates_item_id")),
        sa.ForeignKeyConstraint(
            ["supersedes"], ["certificates.number"], name=op.f("fk_certificates_supersedes")
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_certificates")),
        sa.UniqueConstraint("number", name=op.f("uq_certificates_number")),
        sa.UniqueConstraint("supersedes", name=op.f("uq_certificates_supersedes")),
    )
    op.create_index(op.f("ix_certificates_item_id"), "certificates", ["item_id"])
    op.create_index(op.f("ix_certificates_issue_date"), "certificates", ["issue_date"])
    op.create_index(
        op.f("ix_certificates_plan_sha256"), "certificates", ["plan_sha256"], unique=True
    )
    _certificate_part(
        "certificate_inputs",
        sa.Column("position", sa.Integer(), nullable=False),
        sa.Column("measurement", sa.Integer(), nullable=False),
        sa.Column("path", sa.Text(), nullable=False),
        sa.Column("sha256", sa.String(64), nullable=False),
        sa.Column("size_bytes", sa.BigInteger(), nullable=False),
        key=("position",),
    )
    op.create_index(op.f("ix_certificate_inputs_sha256"), "certificate_inputs", ["sha256"])
    _certificate_part(
        "certificate_files",
        sa.Column("name", sa.String(256), nullable=False),
        sa.Column("sha256", sa.String(64), nullable=False),
        sa.Column("content", sa.LargeBinary(), nullable=False),
        key=("name",),
    )
    _certificate_part(
        "certificate_persons",
        sa.Column("position", sa.Integer(), nullable=False),
        sa.Column("person_id", sa.Integer(), nullable=False),
        sa.Column("role", sa.String(32), nullable=False),
        sa.ForeignKeyConstraint(
            ["person_id"], ["persons.id"], name=op.f("fk_certificate_persons_person_id")
        ),
        key=("position",),
    )
    op.create_index(op.f("ix_certificate_persons_person_id"), "certificate_persons", ["person_id"])
    _certificate_part(
        "certificate_standards",
        sa.Column("position", sa.Integer(), nullable=False),
        sa.Column("standard_id", sa.Integer(), nullable=False),
        sa.ForeignKeyConstraint(
            ["standard_id"], ["standards.id"], name=op.f("fk_certificate_standards_standard_id")
        ),
        key=("position",),
    )
    op.create_index(
        op.f("ix_certificate_standards_standard_id"), "certificate_standards", ["standard_id"]
    )
    _certificate_part(
        "reported_values",
        sa.Column("measurement", sa.Integer(), nullable=False),
        sa.Column("position", sa.Integer(), nullable=False),
        sa.Column("measurement_name", sa.Text(), nullable=False),
        sa.Column("command", sa.String(64), nullable=False),
        sa.Column("quantity", sa.String(128), nullable=False),
        sa.Column("name", sa.Text(), nullable=False),
        sa.Column("unit", sa.String(64), nullable=False),
        sa.Column("value", DECIMAL, nullable=False),
        sa.Column("expanded", DECIMAL, nullable=False),
        sa.Column("coverage_factor", DECIMAL, nullable=False),
        sa.Column("coverage_probability", DECIMAL, nullable=False),
        sa.Column("interval_low", DECIMAL, nullable=True),
        sa.Column("interval_high", DECIMAL, nullable=True),
        sa.Column("limit_min", DECIMAL, nullable=True),
        sa.Column("limit_max", DECIMAL, nullable=True),
        sa.Column("decision_rule", sa.String(16), nullable=True),
        sa.Column("verdict", sa.String(16), nullable=True),
        key=("measurement", "position"),
    )


def downgrade() -> None:
    for table in (
        "reported_values",
        "certificate_standards",
        "certificate_persons",
        "certificate_files",
        "certificate_inputs",
        "certificates",
        "standards",
        "persons",
        "items",
        "voided_numbers",
        "number_counters",
        "settings",
    ):
        op.drop_table(table)
