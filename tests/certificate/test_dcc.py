"""The Digital Calibration Certificate: valid against PTB's DCC 3.1.2 schema (checked with
xmlschema on the project's shared copy), and stating exactly what the certificate content states —
every number as printed, with its unit, U, k and p; the administrative data; the conformity."""

from __future__ import annotations

import dataclasses
import io
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest
import xmlschema
from lxml import etree

import rotacal
from rotacal.certificate.content import CertificateContent, Conformity
from rotacal.certificate.dcc import (
    DCC_NAMESPACE,
    SI_NAMESPACE,
    dcc_conformity,
    dcc_xml,
    quantity_id,
    validate_dcc,
)
from rotacal.errors import ConfigError

SHARED_DCC = Path(__file__).parents[3] / "shared" / "standards" / "dcc"
PACKAGED_DCC = Path(rotacal.__file__).parent / "certificate" / "schema"
NS = {"dcc": DCC_NAMESPACE, "si": SI_NAMESPACE}


@pytest.fixture(scope="session")
def schema() -> xmlschema.XMLSchema:
    """The shared copy of the schema, loaded once (it takes most of a second)."""
    return xmlschema.XMLSchema(str(SHARED_DCC / "dcc.xsd"))


@pytest.fixture(scope="session")
def xml(content) -> bytes:
    return dcc_xml(content)


@pytest.fixture(scope="session")
def tree(xml) -> etree._Element:
    return etree.fromstring(xml)


def _errors(schema: xmlschema.XMLSchema, xml: bytes) -> list[str]:
    return [str(e) for e in schema.iter_errors(io.BytesIO(xml))]


def _text(element: etree._Element, path: str) -> str | None:
    return element.findtext(path, namespaces=NS)


def _one(element: etree._Element, xpath: str, **variables: str) -> etree._Element:
    found = element.xpath(xpath, namespaces=NS, **variables)
    assert len(found) == 1, (xpath, variables, len(found))
    return found[0]


def _with_plan(content: CertificateContent, **changes) -> CertificateContent:
    return dataclasses.replace(content, plan=dataclasses.replace(content.plan, **changes))


def _check_numbers(content: CertificateContent, tree: etree._Element) -> None:
    """Each reported quantity is a si:real in its own measurementResult, with the value, unit,
    U, k and p (or the coverage interval) exactly as the content states them."""
    for m in content.measurements:
        result = _one(tree, "//dcc:measurementResult[@id=$id]", id=f"m{m.index}")
        assert _text(result, "dcc:name/dcc:content") == m.name
        reals = result.findall("dcc:results/dcc:result/dcc:data/dcc:quantity/si:real", NS)
        assert len(reals) == len(m.quantities)
        by_key = {_text(r, "si:label"): r for r in reals}
        for q in m.quantities:
            real = by_key[q.key]
            quantity = real.getparent()
            assert _text(quantity, "dcc:name/dcc:content") == q.name
            assert (_text(real, "si:value"), _text(real, "si:unit")) == (q.value, q.dsi_unit)
            if q.interval is None:
                unc = real.find("si:expandedUnc", NS)
                assert unc is not None, q.key
                assert [_text(unc, f"si:{x}") for x in ("uncertainty", "coverageFactor")] == [
                    q.U,
                    q.k,
                ]
                assert _text(unc, "si:coverageProbability") == q.p
            else:
                interval = real.find("si:coverageInterval", NS)
                assert interval is not None, q.key
                assert (_text(interval, "si:intervalMin"), _text(interval, "si:intervalMax")) == (
                    q.interval
                )
                assert _text(interval, "si:coverageProbability") == q.p
                # u = U/k, kept to two significant digits: within 5 % of the ratio
                u = float(_text(interval, "si:standardUnc") or "nan")
                assert u == pytest.approx(float(q.U) / float(q.k), rel=0.05)
                description = " ".join(
                    quantity.xpath("dcc:description/dcc:content/text()", namespaces=NS)
                )
                assert f"U = {q.U}" in description and f"k = {q.k}" in description


def test_certificate_is_valid_against_the_shared_dcc_schema(schema, xml):
    assert _errors(schema, xml) == []


def test_every_command_kind_gives_a_valid_certificate_with_its_numbers(schema, kind_content):
    failures = {}
    for command, content in kind_content.items():
        xml = dcc_xml(content)
        if errors := _errors(schema, xml):
            failures[command] = errors[0]
        _check_numbers(content, etree.fromstring(xml))
    assert failures == {}


def test_every_reported_number_is_in_its_si_real(content, tree):
    assert any(q.interval is not None for m in content.measurements for q in m.quantities)
    _check_numbers(content, tree)


def test_the_bytes_are_utf8_xml_with_declaration_and_the_dcc_root(xml, tree):
    assert xml.startswith(
        b'<?xml version="1.0" encoding="UTF-8"?>\n<dcc:digitalCalibrationCertificate'
    )
    assert tree.get("schemaVersion") == "3.1.2"
    assert tree.tag == f"{{{DCC_NAMESPACE}}}digitalCalibrationCertificate"


def test_core_data_name_the_certificate_dates_and_languages(content, tree):
    plan = content.plan
    core = _one(tree, "/dcc:digitalCalibrationCertificate/dcc:administrativeData/dcc:coreData")
    assert _text(core, "dcc:uniqueIdentifier") == content.number
    assert _text(core, "dcc:beginPerformanceDate") == plan.start_date.isoformat()
    assert _text(core, "dcc:endPerformanceDate") == plan.end_date.isoformat()
    assert _text(core, "dcc:mandatoryLangCodeISO639_1") == plan.language
    assert _text(core, "dcc:performanceLocation") == "laboratory"
    assert content.plan_sha256 in core.xpath("dcc:identifications//dcc:value/text()", namespaces=NS)
    issued = _one(tree, "//dcc:statement[@id='statement_issueDate']")
    assert _text(issued, "dcc:date") == plan.issue_date.isoformat()
    software = _one(tree, "//dcc:dccSoftware/dcc:software")
    assert _text(software, "dcc:name/dcc:content") == "rotacal"
    assert _text(software, "dcc:release") == content.software_version


def test_the_item_is_identified_by_its_serial_number(content, tree):
    item = content.plan.item
    element = _one(tree, "//dcc:items/dcc:item")
    serial = _one(element, "dcc:identifications/dcc:identification[dcc:issuer='manufacturer']")
    assert _text(serial, "dcc:value") == item.serial
    assert _text(element, "dcc:model") == item.model
    assert _text(element, "dcc:manufacturer/dcc:name/dcc:content") == item.manufacturer
    assert item.model in (_text(element, "dcc:name/dcc:content") or "")


def test_laboratory_customer_and_persons(content, tree):
    plan = content.plan
    for path, contact in (
        ("//dcc:calibrationLaboratory/dcc:contact", plan.laboratory),
        ("//dcc:administrativeData/dcc:customer", plan.customer),
    ):
        element = _one(tree, path)
        assert _text(element, "dcc:name/dcc:content") == contact.name
        assert _text(element, "dcc:eMail") == contact.email
        assert _text(element, "dcc:location/dcc:further/dcc:content") == contact.address
    persons = [
        (
            _text(p, "dcc:person/dcc:name/dcc:content"),
            _text(p, "dcc:role"),
            _text(p, "dcc:mainSigner"),
        )
        for p in tree.iterfind(".//dcc:respPersons/dcc:respPerson", NS)
    ]
    # each person with the role's sentence; the first who approved is the one main signer
    roles = {"performed": "performed the calibration", "approved": "approved the certificate"}
    approvers = [p for p in plan.persons if p.role == "approved"]
    assert approvers, "the fixture's plan names no one who approved"
    assert persons == [
        (p.name, roles[p.role], "true" if p is approvers[0] else None) for p in plan.persons
    ]


def test_standards_conditions_and_methods_of_each_measurement(content, tree):
    plan = content.plan
    for m in content.measurements:
        result = _one(tree, "//dcc:measurementResult[@id=$id]", id=f"m{m.index}")
        ids = result.xpath(
            ".//dcc:measuringEquipment//dcc:identification/dcc:value/text()", namespaces=NS
        )
        for s in plan.standards:
            assert s.id in ids and s.certificate in ids
        method = _one(result, "dcc:usedMethods/dcc:usedMethod")
        assert _text(method, "dcc:description/dcc:content") == m.method
        cited = method.xpath("dcc:norm/text() | dcc:reference/text()", namespaces=NS)
        assert sorted(cited) == sorted(m.references)  # the standards (dcc:norm) come first
        assert plan.conditions.temperature_c is not None, "the fixture's plan has no temperature"
        temperature = _one(
            result, ".//dcc:influenceCondition[@refType='basic_temperature']//si:real"
        )
        assert float(_text(temperature, "si:value") or "nan") == plan.conditions.temperature_c
        assert _text(temperature, "si:unit") == r"\degreeCelsius"
        if plan.conditions.temperature_u_c is None:
            assert temperature.find("si:expandedUnc", NS) is None
        else:  # a standard uncertainty: k = 1
            assert float(_text(temperature, "si:expandedUnc/si:uncertainty") or "nan") == (
                plan.conditions.temperature_u_c
            )
            assert _text(temperature, "si:expandedUnc/si:coverageFactor") == "1"
        for name, _value in plan.conditions.others:
            assert name in result.xpath(
                ".//dcc:influenceCondition/dcc:name/dcc:content/text()", namespaces=NS
            )


def _expected_status(c: Conformity) -> str:
    """ILAC-G8:09/2019 §4.2.3: an indeterminate result is a conditional pass when the measured
    value itself lies within the limits, a conditional fail when it lies outside."""
    if c.verdict != "indeterminate":
        return c.verdict
    low = float(c.limit_min) if c.limit_min else float("-inf")
    high = float(c.limit_max) if c.limit_max else float("inf")
    return "conditionalPass" if low <= float(c.value) <= high else "conditionalFail"


def test_each_limited_quantity_states_its_conformity_and_limits(content, tree):
    verdicts = {c.verdict for m in content.measurements for c in m.conformity}
    assert verdicts == {"pass", "fail", "indeterminate"}
    for m in content.measurements:
        units = {q.key: q.dsi_unit for q in m.quantities}
        for c in m.conformity:
            qid = quantity_id(m.index, c.key)
            statement = _one(tree, "//dcc:statements/dcc:statement[@refId=$id]", id=qid)
            assert _text(statement, "dcc:conformity") == _expected_status(c)
            assert _text(statement, "dcc:declaration/dcc:content") == c.statement
            meta = _one(
                tree, "//dcc:quantity[@id=$id]/dcc:measurementMetaData/dcc:metaData", id=qid
            )
            assert _text(meta, "dcc:conformity") == _expected_status(c)
            rule = _one(tree, "//dcc:statement[@id=$id]", id=meta.get("refId"))
            assert f"ILAC-G8:09/2019 §4.2.{1 if c.decision_rule == 'simple' else 2}" in (
                _text(rule, "dcc:declaration/dcc:content") or ""
            )
            for limit, side in ((c.limit_min, "Lower"), (c.limit_max, "Upper")):
                found = meta.xpath(
                    f"dcc:data/dcc:quantity[@refType='basic_toleranceLimit{side}']/si:real",
                    namespaces=NS,
                )
                assert [(_text(r, "si:value"), _text(r, "si:unit")) for r in found] == (
                    [(limit, units[c.key])] if limit else []
                )


@pytest.mark.parametrize(
    ("value", "verdict", "status"),
    [
        ("0.9", "pass", "pass"),
        ("1.2", "fail", "fail"),
        ("0.9", "indeterminate", "conditionalPass"),
        ("1.0", "indeterminate", "conditionalPass"),  # on the limit is within it
        ("1.1", "indeterminate", "conditionalFail"),
        ("-1.1", "indeterminate", "conditionalFail"),
    ],
)
def test_conformity_status_follows_ilac_g8_non_binary_statements(value, verdict, status):
    c = Conformity("x", "x", "", value, "0.2", "-1", "1.0", "guarded", verdict, "")
    assert dcc_conformity(c) == status


def test_same_content_gives_the_same_bytes_in_another_process(content, xml, tmp_path):
    """Another interpreter with another hash seed (set and dict order of strings) writes the
    same bytes."""
    pickled = tmp_path / "content.pickle"
    pickled.write_bytes(pickle.dumps(content))
    code = (
        "import pickle, sys; from rotacal.certificate.dcc import dcc_xml; "
        f"sys.stdout.buffer.write(dcc_xml(pickle.loads(open({str(pickled)!r}, 'rb').read())))"
    )
    src = str(Path(rotacal.__file__).parents[1])
    env = {**os.environ, "PYTHONHASHSEED": "12345", "PYTHONPATH": src}
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, env=env, check=True)
    assert run.stdout == xml


def test_markup_characters_and_non_ascii_text_survive(schema, content):
    name = "Gyro <Maker> & \"Sons\" 'Ltd' — Ærø 東京"
    customer = dataclasses.replace(content.plan.customer, name=name, address="Straße 1 & 2 <b>")
    xml = dcc_xml(_with_plan(content, customer=customer))
    assert _errors(schema, xml) == []
    element = _one(etree.fromstring(xml), "//dcc:administrativeData/dcc:customer")
    assert _text(element, "dcc:name/dcc:content") == name
    assert _text(element, "dcc:location/dcc:further/dcc:content") == "Straße 1 & 2 <b>"
    assert "Ærø 東京".encode() in xml  # UTF-8 itself, not character references


def test_a_control_character_in_the_plan_is_refused_naming_the_key(content):
    bad = "Gyro\x01Maker"
    changed = _with_plan(
        content,
        data={"customer": {"name": bad}},
        customer=dataclasses.replace(content.plan.customer, name=bad),
    )
    with pytest.raises(ConfigError, match=r"customer\.name holds the control character U\+0001"):
        dcc_xml(changed)


def test_a_control_character_from_a_capture_is_refused(content):
    m = dataclasses.replace(content.measurements[0], warnings=("column 'rate\x07' is odd",))
    changed = dataclasses.replace(content, measurements=(m, *content.measurements[1:]))
    with pytest.raises(ConfigError, match=r"holds the control character U\+0007"):
        dcc_xml(changed)


def test_country_of_the_laboratory_or_zz_when_not_stated(content):
    lab = dataclasses.replace(content.plan.laboratory)
    # Contact.country comes with the plan reader; set it the way the reader will have it
    object.__setattr__(lab, "country", "DE")
    core = etree.fromstring(dcc_xml(_with_plan(content, laboratory=lab)))
    assert _text(core, ".//dcc:coreData/dcc:countryCodeISO3166_1") == "DE"
    assert _text(core, ".//dcc:calibrationLaboratory//dcc:location/dcc:countryCode") == "DE"
    if not getattr(content.plan.laboratory, "country", ""):
        tree = etree.fromstring(dcc_xml(content))
        assert _text(tree, ".//dcc:coreData/dcc:countryCodeISO3166_1") == "ZZ"


def test_a_replaced_certificate_is_named(schema, content):
    xml = dcc_xml(_with_plan(content, supersedes="RC-2025-0007"))
    assert _errors(schema, xml) == []
    statement = _one(etree.fromstring(xml), "//dcc:statement[@id='statement_supersedes']")
    assert "RC-2025-0007" in (_text(statement, "dcc:declaration/dcc:content") or "")


def test_the_packaged_schema_is_the_shared_one():
    for name in ("dcc.xsd", "SI_Format.xsd", "COPYING.LESSER"):
        assert (PACKAGED_DCC / name).read_bytes() == (SHARED_DCC / name).read_bytes(), name


def test_validate_dcc_accepts_the_certificate(xml):
    validate_dcc(xml)


def _spoilt(content: CertificateContent, xml: bytes) -> dict[str, tuple[bytes, bytes, str]]:
    """What to change in the valid certificate → (old, new, what the refusal names)."""
    m = content.measurements[0]
    first, second = (quantity_id(m.index, q.key).encode() for q in m.quantities[:2])
    limited = next(quantity_id(m.index, c.key) for m in content.measurements for c in m.conformity)
    number = f"<dcc:uniqueIdentifier>{content.number}</dcc:uniqueIdentifier>".encode()
    k = xml.split(b"<si:coverageFactor>", 1)[1].split(b"<", 1)[0]
    return {
        "k below 1 (si:kValueType)": (
            b"<si:coverageFactor>" + k + b"<",
            b"<si:coverageFactor>0.96<",
            "coverageFactor",
        ),
        "an unknown conformity status": (b"<dcc:conformity>", b"<dcc:conformity>X", "conformity"),
        "the number removed": (number, b"", "identifications"),
        "a conformity statement about no quantity": (
            f'refId="{limited}"'.encode(),
            b'refId="nothing"',
            "refId 'nothing' names no",
        ),
        "two quantities with one id": (b'id="' + second + b'"', b'id="' + first + b'"', "xs:ID"),
    }


@pytest.mark.parametrize(
    "fault",
    [
        "k below 1 (si:kValueType)",
        "an unknown conformity status",
        "the number removed",
        "a conformity statement about no quantity",
        "two quantities with one id",
    ],
)
def test_validate_dcc_refuses_what_the_schema_refuses(schema, content, xml, fault):
    old, new, names = _spoilt(content, xml)[fault]
    assert old in xml
    bad = xml.replace(old, new, 1)
    assert _errors(schema, bad) != []  # the reference validator refuses it too
    with pytest.raises(ConfigError, match=f"not valid against the PTB DCC 3.1.2 schema: .*{names}"):
        validate_dcc(bad)


def test_validate_dcc_refuses_broken_xml(xml):
    with pytest.raises(ConfigError, match="not well-formed"):
        validate_dcc(xml[: len(xml) // 2])
