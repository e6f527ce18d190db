"""The certificate as a PTB Digital Calibration Certificate (DCC v3.1.2, ``certificate.xml``).

:func:`dcc_xml` writes the same :class:`~rotacal.certificate.content.CertificateContent` the PDF
prints as a DCC (schema ``https://ptb.de/dcc`` v3.1.2 with the D-SI v2.1.0, ``https://ptb.de/si``)
and :func:`validate_dcc` checks it against the schema that rotacal carries (``schema/``).

What goes where (the DCC's elements; the choices the schema leaves open are said here):

- ``administrativeData``: the software (rotacal and its version); the core data (the laboratory's
  country, the languages, the certificate number as ``uniqueIdentifier``, the SHA-256 of the plan
  and its captures as an identification, the dates of calibration, the place); the item (serial
  number as the manufacturer's identification); the laboratory, the persons responsible (the first
  who approved as ``mainSigner``), the customer; statements — the results relate only to the item,
  traceability, the uncertainty, the validity, the date of issue, a replaced certificate, each
  decision rule used, and one conformity statement per limited quantity (``refId`` → the quantity).
- ``measurementResults``: one ``measurementResult`` per measurement, with the method and its
  references, rotacal and the command's options as the software used, the plan's reference
  standards, the conditions, and one ``result`` per reported quantity holding a ``dcc:quantity``
  with a ``si:real``: the value, the D-SI unit and ``si:expandedUnc`` (U, k, p) — or, for a
  biased, bounded quantity whose certificate states the coverage interval instead of ± U,
  ``si:coverageInterval``. A limited quantity carries its conformity and its limits in
  ``measurementMetaData`` (``refType`` ``basic_conformity``, limits ``basic_toleranceLimitLower`` /
  ``…Upper``).

Every number of a result is the decimal text of the content (ILAC-P14 rounded), written as it is, so
that the XML, the PDF and ``results.json`` state the same numbers. The bytes depend on the content
alone (no clock, no hash order): the same content gives the same file.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator, Mapping
from decimal import Decimal
from functools import lru_cache
from importlib import resources
from typing import Any

from lxml import etree

from rotacal.errors import ConfigError
from rotacal.plan.model import Conditions, Contact, Person, Plan, Standard

from .conformity import RULE_TEXT
from .content import CertificateContent, Conformity, MeasurementResult, ReportedQuantity
from .quantities import standard_uncertainty

__all__ = [
    "DCC_NAMESPACE",
    "SCHEMA_VERSION",
    "SI_NAMESPACE",
    "dcc_conformity",
    "dcc_xml",
    "quantity_id",
    "validate_dcc",
]

DCC_NAMESPACE = "https://ptb.de/dcc"
SI_NAMESPACE = "https://ptb.de/si"
SCHEMA_VERSION = "3.1.2"
_XSI = "http://www.w3.org/2001/XMLSchema-instance"
_SCHEMA_LOCATION = f"{DCC_NAMESPACE} https://ptb.de/dcc/v{SCHEMA_VERSION}/dcc.xsd"
_DECLARATION = b'<?xml version="1.0" encoding="UTF-8"?>\n'

#: The language of the sentences rotacal writes itself (the plan's own text is in the plan's).
_OWN_LANGUAGE = "en"
#: ISO 3166-1 has no code for "not stated"; ZZ is in its user-assigned range and is what CLDR
#: uses for an unknown region. The DCC's core data must name a country.
_UNKNOWN_COUNTRY = "ZZ"
#: Characters XML 1.0 cannot carry (§2.2): C0 controls other than tab, LF, CR; surrogates; FFFE/F.
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")

_ROLE_TEXT = {"performed": "performed the calibration", "approved": "approved the certificate"}
#: The clause of ILAC-G8:09/2019 behind each decision rule.
_RULE_CLAUSE = {"simple": "4.2.1", "guarded": "4.2.2"}
#: Citations that name a standard (``dcc:norm``) rather than a publication (``dcc:reference``).
_NORM_PREFIXES = ("IEEE Std", "ISO", "IEC", "JCGM", "ILAC", "EA-", "DIN", "ASTM", "VDI")


def _is_norm(citation: str) -> bool:
    """Whether a references-list entry cites a standard (its designation appears in it)."""
    return any(f" {prefix}" in f" {citation}" for prefix in _NORM_PREFIXES)


def dcc_conformity(conformity: Conformity) -> str:
    """The DCC's conformity status (``dcc:stringConformityStatementStatusType``) of a statement.

    ``pass`` and ``fail`` are the DCC's own. The DCC has no "indeterminate"; it has the non-binary
    statements of ILAC-G8:09/2019 §4.2.3 (guard band w = U): *conditional pass* when the measured
    value lies within the limits but value ± U reaches beyond one, *conditional fail* when the value
    lies outside but value ± U reaches back inside — which is what an indeterminate verdict under
    guarded acceptance is. The value and the limits are compared as the decimals printed.
    """
    if conformity.verdict in ("pass", "fail"):
        return conformity.verdict
    if conformity.verdict != "indeterminate":
        raise ValueError(f"unknown verdict {conformity.verdict!r}")
    value = Decimal(conformity.value)
    within = (not conformity.limit_min or value >= Decimal(conformity.limit_min)) and (
        not conformity.limit_max or value <= Decimal(conformity.limit_max)
    )
    return "conditionalPass" if within else "conditionalFail"


def quantity_id(measurement_index: int, key: str) -> str:
    """The ``id`` of a reported quantity's ``dcc:quantity``: ``m2_scale_misalignment_0_1``.

    An XML ID (an NCName): the measurement's index and the quantity's JSON key with every run of
    other characters than letters, digits, ``.``, ``-`` and ``_`` made one ``_``.
    """
    return f"m{measurement_index}_" + re.sub(r"[^A-Za-z0-9._-]+", "_", key).strip("_")


def dcc_xml(content: CertificateContent) -> bytes:
    """The DCC v3.1.2 of ``content``: UTF-8 XML with its declaration, indented.

    Raises
    ------
    ConfigError
        When a text of the plan holds a character XML cannot carry (a control character): the
        message names the plan's key.

    References
    ----------
    PTB, Digital Calibration Certificate schema v3.1.2 (https://ptb.de/dcc/v3.1.2/); D-SI v2.1.0
    (Hutzschenreuter et al., SmartCom D-SI guide, PTB 2020); ISO/IEC 17025:2017 §7.8;
    ILAC-G8:09/2019 §4.2 (conformity); ILAC-P14:09/2020 §5.4 (the numbers as rounded).
    """
    _check_plan_text(content.plan)
    root = _DccWriter(content).document()
    # the declaration in the double quotes of the DCC's own examples (lxml writes single ones)
    return _DECLARATION + etree.tostring(root, encoding="UTF-8", pretty_print=True)


# --- validation --------------------------------------------------------------------------------


@lru_cache(maxsize=1)
def _schema() -> etree.XMLSchema:
    """The DCC schema that rotacal carries (``schema/dcc.xsd``, importing ``SI_Format.xsd``)."""
    folder = resources.files(__package__) / "schema"
    with resources.as_file(folder) as path:
        return etree.XMLSchema(etree.parse(str(path / "dcc.xsd")))


def validate_dcc(xml: bytes) -> None:
    """Check ``xml`` against the DCC v3.1.2 schema (with libxml2, through lxml).

    Raises
    ------
    ConfigError
        When it is not well-formed or not valid: one line with the first fault (the element and
        the value refused); a certificate that does not validate must not be issued.
    """
    try:
        document = etree.fromstring(xml)
    except etree.XMLSyntaxError as e:
        raise ConfigError(
            f"certificate.xml is not well-formed XML ({e}); nothing was issued"
        ) from None
    schema = _schema()
    if schema.validate(document):
        # libxml2 checks that IDs are unique but not that every IDREF names one (xmlschema does)
        ids = set(document.xpath("//@id"))
        dangling = sorted({r for refs in document.xpath("//@refId") for r in refs.split()} - ids)
        if dangling:
            raise ConfigError(
                f"certificate.xml is not valid against the PTB DCC {SCHEMA_VERSION} schema: "
                f"refId {dangling[0]!r} names no element's id; nothing was issued"
            )
        return
    error = schema.error_log.filter_from_errors()[0]
    # the message names the element and the value it refuses, which is what a person can act on
    raise ConfigError(
        f"certificate.xml is not valid against the PTB DCC {SCHEMA_VERSION} schema: "
        f"{error.message.rstrip('.')}; nothing was issued"
    )


# --- text of the plan --------------------------------------------------------------------------


def _strings(data: Any, key: str = "") -> Iterator[tuple[str, str]]:
    """(dotted key, text) of every string in a parsed TOML plan, keys included."""
    if isinstance(data, Mapping):
        for name, value in data.items():
            where = f"{key}.{name}" if key else str(name)
            yield where, str(name)
            yield from _strings(value, where)
    elif isinstance(data, (list, tuple)):
        for i, value in enumerate(data, start=1):
            yield from _strings(value, f"{key}[{i}]")
    elif isinstance(data, str):
        yield key, data


def _check_plan_text(plan: Plan) -> None:
    for key, text in _strings(plan.data):
        bad = _NOT_XML.search(text)
        if bad:
            raise ConfigError(
                f"{plan.path.name}: {key} holds the control character U+{ord(bad.group()):04X}, "
                "which a certificate (XML) cannot carry: remove it"
            )


def _plain(value: Any) -> str:
    """A plan's value as a reader wrote it: text as it is, numbers and lists as in TOML."""
    if isinstance(value, str):
        return value
    return json.dumps(value, ensure_ascii=False, default=str)  # a TOML date as 2026-11-25


def _decimal(x: float) -> str:
    """A float of the plan as the shortest decimal text that reads back to it (``repr``)."""
    return repr(float(x))


# --- the writer ---------------------------------------------------------------------------------


class _DccWriter:
    """Builds the element tree of one certificate; ``lang`` is the plan's language."""

    def __init__(self, content: CertificateContent) -> None:
        self.content = content
        self.plan = content.plan
        self.lang = self.plan.language
        # two keys that differ only in characters an XML ID cannot hold get _2, _3 … appended
        self.quantity_ids: dict[tuple[int, str], str] = {}
        taken: set[str] = set()
        for m in content.measurements:
            for q in m.quantities:
                wanted = candidate = quantity_id(m.index, q.key)
                n = 1
                while candidate in taken:
                    n += 1
                    candidate = f"{wanted}_{n}"
                taken.add(candidate)
                self.quantity_ids[(m.index, q.key)] = candidate

    # element helpers ------------------------------------------------------------------------

    @staticmethod
    def el(
        parent: etree._Element | None,
        name: str,
        text: str | None = None,
        *,
        ns: str = DCC_NAMESPACE,
        **attributes: str,
    ) -> etree._Element:
        """A child ``name`` (in ``ns``) of ``parent`` with ``text``; ``ref_id`` → ``refId`` etc."""
        tag = f"{{{ns}}}{name}"
        attrib = {_ATTRIBUTE[k]: v for k, v in attributes.items()}
        if parent is None:
            element = etree.Element(tag, attrib, nsmap={"dcc": DCC_NAMESPACE, "si": SI_NAMESPACE})
        else:
            element = etree.SubElement(parent, tag, attrib)
        if text is not None:
            bad = _NOT_XML.search(text)
            if bad:  # text that is not the plan's (a warning quoting a capture's column name)
                raise ConfigError(
                    f"the certificate's text {text[:60]!r} holds the control character "
                    f"U+{ord(bad.group()):04X}, which XML cannot carry: remove it at its source"
                )
            element.text = text
        return element

    def texts(
        self, parent: etree._Element, name: str, *lines: str, lang: str = _OWN_LANGUAGE, **attr: str
    ) -> etree._Element:
        """A ``dcc:textType`` or ``dcc:richContentType``: one ``dcc:content`` per line."""
        element = self.el(parent, name, **attr)
        for line in lines:
            self.el(element, "content", line, lang=lang)
        return element

    def si_real(
        self, parent: etree._Element, value: str, unit: str, label: str = ""
    ) -> etree._Element:
        real = self.el(parent, "real", ns=SI_NAMESPACE)
        if label:
            self.el(real, "label", label, ns=SI_NAMESPACE)
        self.el(real, "value", value, ns=SI_NAMESPACE)
        self.el(real, "unit", unit, ns=SI_NAMESPACE)
        return real

    def expanded(
        self, real: etree._Element, big_u: str, k: str, p: str, distribution: str = ""
    ) -> None:
        unc = self.el(real, "expandedUnc", ns=SI_NAMESPACE)
        self.el(unc, "uncertainty", big_u, ns=SI_NAMESPACE)
        self.el(unc, "coverageFactor", k, ns=SI_NAMESPACE)
        self.el(unc, "coverageProbability", p, ns=SI_NAMESPACE)
        if distribution:
            self.el(unc, "distribution", distribution, ns=SI_NAMESPACE)

    # the document ---------------------------------------------------------------------------

    def document(self) -> etree._Element:
        root = self.el(None, "digitalCalibrationCertificate", schema_version=SCHEMA_VERSION)
        root.set(f"{{{_XSI}}}schemaLocation", _SCHEMA_LOCATION)
        admin = self.el(root, "administrativeData")
        self.software(self.el(admin, "dccSoftware"))
        self.core_data(self.el(admin, "coreData"))
        self.items(self.el(admin, "items"))
        self.contact(self.el(self.el(admin, "calibrationLaboratory"), "contact"), "laboratory")
        persons = self.el(admin, "respPersons")
        main_signer = next((p for p in self.plan.persons if p.role == "approved"), None)
        for person in self.plan.persons:
            self.person(persons, person, person is main_signer)
        self.contact(self.el(admin, "customer"), "customer")
        self.statements(self.el(admin, "statements"))
        results = self.el(root, "measurementResults")
        for m in self.content.measurements:
            self.measurement(results, m)
        return root

    # administrative data --------------------------------------------------------------------

    def software(self, parent: etree._Element, description: str = "") -> None:
        software = self.el(parent, "software")
        self.texts(software, "name", "rotacal")
        self.el(software, "release", self.content.software_version)
        self.el(software, "type", "application")
        if description:
            self.texts(software, "description", description)

    def core_data(self, core: etree._Element) -> None:
        plan = self.plan
        self.el(core, "countryCodeISO3166_1", _country(plan.laboratory) or _UNKNOWN_COUNTRY)
        languages = dict.fromkeys((self.lang, _OWN_LANGUAGE))  # ordered, without repeats
        for lang in languages:
            self.el(core, "usedLangCodeISO639_1", lang)
        self.el(core, "mandatoryLangCodeISO639_1", self.lang)
        self.el(core, "uniqueIdentifier", self.content.number)
        ids = self.el(core, "identifications")
        self.identification(
            ids,
            "calibrationLaboratory",
            self.content.plan_sha256,
            "SHA-256 of the plan file and of every capture it names (plan_sha256 of results.json)",
        )
        self.el(core, "beginPerformanceDate", plan.start_date.isoformat())
        self.el(core, "endPerformanceDate", plan.end_date.isoformat())
        self.el(core, "performanceLocation", "laboratory")

    def identification(self, parent: etree._Element, issuer: str, value: str, name: str) -> None:
        identification = self.el(parent, "identification")
        self.el(identification, "issuer", issuer)
        self.el(identification, "value", value)
        self.texts(identification, "name", name)

    def items(self, items: etree._Element) -> None:
        item = self.plan.item
        element = self.el(items, "item")
        kind = item.kind.replace("-", " ")
        self.texts(element, "name", f"{kind} {item.model}".strip())
        if item.description:
            self.texts(element, "description", item.description, lang=self.lang)
        self.texts(self.el(element, "manufacturer"), "name", item.manufacturer, lang=self.lang)
        self.el(element, "model", item.model)
        ids = self.el(element, "identifications")
        self.identification(ids, "manufacturer", item.serial, "serial number")

    def contact(self, element: etree._Element, which: str) -> None:
        """``dcc:contactType`` of the plan's ``[laboratory]`` or ``[customer]``."""
        contact: Contact = getattr(self.plan, which)
        self.texts(element, "name", contact.name, lang=self.lang)
        self.el(element, "eMail", contact.email)
        if contact.phone:
            self.el(element, "phone", contact.phone)
        location = self.el(element, "location")
        # the plan gives the address as one text: it goes as written, not split into guessed parts
        if contact.address:
            self.texts(location, "further", contact.address, lang=self.lang)
        if _country(contact):
            self.el(location, "countryCode", _country(contact))
        if not contact.address and not _country(contact):
            self.texts(location, "further", "address not stated")

    def person(self, parent: etree._Element, person: Person, main_signer: bool) -> None:
        element = self.el(parent, "respPerson")
        self.texts(self.el(element, "person"), "name", person.name, lang=self.lang)
        if person.title:
            self.texts(element, "description", person.title, lang=self.lang)
        self.el(element, "role", _ROLE_TEXT.get(person.role, person.role))
        if main_signer:
            self.el(element, "mainSigner", "true")

    def statement(
        self,
        parent: etree._Element,
        declaration: str,
        *,
        norm: str = "",
        references: tuple[str, ...] = (),
        traceable: bool = False,
        lang: str = _OWN_LANGUAGE,
        **attributes: str,
    ) -> etree._Element:
        """A ``dcc:statementMetaDataType`` (its children in the schema's order)."""
        element = self.el(parent, "statement", **attributes)
        if traceable:
            self.el(element, "traceable", "true")
        if norm:
            self.el(element, "norm", norm)
        for reference in references:
            self.el(element, "reference", reference)
        self.texts(element, "declaration", declaration, lang=lang)
        return element

    def statements(self, parent: etree._Element) -> None:
        plan = self.plan
        self.statement(
            parent,
            "The results relate only to the item calibrated, as identified in this certificate.",
            norm="ISO/IEC 17025:2017",
            references=("7.8.2.1 l)",),
            id="statement_itemOnly",
        )
        standards = "; ".join(_standard_line(s) for s in plan.standards)
        self.statement(
            parent,
            "The results are traceable to the International System of Units (SI) through the "
            f"reference standards used, each calibrated as stated: {standards}.",
            norm="ISO/IEC 17025:2017",
            references=("6.5",),
            traceable=True,
            id="statement_traceability",
        )
        self.statement(
            parent,
            "The expanded uncertainty U is the standard uncertainty multiplied by the coverage "
            "factor k stated with it, so that value ± U contains the value of the measurand with "
            "the coverage probability p stated (JCGM 100:2008). U is rounded to two significant "
            "digits and the value to the same decimal place (ILAC-P14:09/2020 §5.4). For a biased, "
            "bounded quantity (a distortion, a nonlinearity, a peak-to-peak near zero) the "
            "coverage interval for the true value is stated instead of value ± U (JCGM 101:2008).",
            norm="JCGM 100:2008",
            references=("ILAC-P14:09/2020 5.4",),
            id="statement_uncertainty",
        )
        self.statement(
            parent,
            "The results are valid at the time of calibration. The customer is responsible for "
            "arranging a recalibration in due time.",
            norm="ISO/IEC 17025:2017",
            references=("7.8.4.3",),
            id="statement_validity",
        )
        issued = self.statement(
            parent,
            "Date of issue of this certificate.",
            norm="ISO/IEC 17025:2017",
            references=("7.8.2.1 j)",),
            id="statement_issueDate",
        )
        self.el(issued, "date", plan.issue_date.isoformat())
        if plan.supersedes:
            self.statement(
                parent,
                f"This certificate replaces certificate {plan.supersedes}, which is withdrawn.",
                norm="ISO/IEC 17025:2017",
                references=("7.8.8.3",),
                id="statement_supersedes",
            )
        conformities = [(m, c) for m in self.content.measurements for c in m.conformity]
        for rule in dict.fromkeys(c.decision_rule for _, c in conformities):
            self.statement(
                parent,
                f"Decision rule of the statements of conformity: {RULE_TEXT[rule]}.",
                norm="ILAC-G8:09/2019",
                references=(_RULE_CLAUSE[rule],),
                id=f"decisionRule_{rule}",
                ref_type="basic_conformity",
            )
        for m, c in conformities:
            status = dcc_conformity(c)
            element = self.statement(
                parent,
                c.statement,
                norm="ILAC-G8:09/2019",
                # a conditional status is the non-binary statement of §4.2.3
                references=(_RULE_CLAUSE[c.decision_rule],)
                + (("4.2.3",) if status.startswith("conditional") else ()),
                ref_id=self.quantity_ids[(m.index, c.key)],
                ref_type="basic_conformity",
            )
            self.el(element, "conformity", status)

    # measurement results --------------------------------------------------------------------

    def measurement(self, parent: etree._Element, m: MeasurementResult) -> None:
        element = self.el(
            parent, "measurementResult", id=f"m{m.index}", ref_type=_command_ref(m.command)
        )
        self.texts(element, "name", m.name, lang=self.lang)
        lines = [f"capture {c.path}: SHA-256 {c.sha256}, {c.bytes} bytes" for c in m.captures] + [
            f"warning: {w}" for w in m.warnings
        ]
        if lines:
            self.texts(element, "description", *lines)
        methods = self.el(element, "usedMethods")
        method = self.el(methods, "usedMethod")
        self.texts(method, "name", f"rotacal {m.command}")
        self.texts(method, "description", m.method)
        # the schema wants every dcc:norm before the first dcc:reference
        norms = [c for c in m.references if _is_norm(c)]
        for citation in norms:
            self.el(method, "norm", citation)
        for citation in m.references:
            if citation not in norms:
                self.el(method, "reference", citation)
        self.software(self.el(element, "usedSoftware"), _command_line(m))
        if self.plan.standards:
            equipment = self.el(element, "measuringEquipments")
            for standard in self.plan.standards:
                self.standard(equipment, standard)
        self.conditions(element, self.plan.conditions)
        results = self.el(element, "results")
        by_key = {c.key: c for c in m.conformity}
        for q in m.quantities:
            self.result(results, m, q, by_key.get(q.key))

    def standard(self, parent: etree._Element, standard: Standard) -> None:
        element = self.el(parent, "measuringEquipment")
        self.texts(element, "name", standard.name, lang=self.lang)
        self.texts(element, "description", _standard_line(standard))
        ids = self.el(element, "identifications")
        self.identification(ids, "calibrationLaboratory", standard.id, "reference standard")
        self.identification(ids, "other", standard.certificate, "calibration certificate")

    def conditions(self, parent: etree._Element, conditions: Conditions) -> None:
        """The plan's ``[conditions]``: temperature (its standard uncertainty written as an
        expanded uncertainty with k = 1), relative humidity, and every further key as text."""
        if (
            conditions.temperature_c is None
            and conditions.humidity_percent is None
            and not conditions.others
        ):
            return
        element = self.el(parent, "influenceConditions")
        if conditions.temperature_c is not None:
            condition = self.el(element, "influenceCondition", ref_type="basic_temperature")
            self.texts(condition, "name", "ambient temperature")
            if conditions.temperature_u_c is not None:
                self.texts(
                    condition,
                    "description",
                    "The uncertainty is the standard uncertainty of the plan "
                    "(temperature_u_c), stated as an expanded uncertainty with k = 1 "
                    "(p = 0.683 for a normal distribution).",
                )
            real = self.si_real(
                self.el(self.el(condition, "data"), "quantity"),
                _decimal(conditions.temperature_c),
                r"\degreeCelsius",
            )
            if conditions.temperature_u_c is not None:
                self.expanded(real, _decimal(conditions.temperature_u_c), "1", "0.683", "normal")
        if conditions.humidity_percent is not None:
            condition = self.el(element, "influenceCondition", ref_type="basic_humidityRelative")
            self.texts(condition, "name", "relative humidity")
            self.si_real(
                self.el(self.el(condition, "data"), "quantity"),
                _decimal(conditions.humidity_percent),
                r"\percent",
            )
        for name, value in conditions.others:
            condition = self.el(element, "influenceCondition")
            self.texts(condition, "name", name, lang=self.lang)
            self.texts(self.el(condition, "data"), "text", _plain(value), lang=self.lang)

    def result(
        self,
        parent: etree._Element,
        m: MeasurementResult,
        q: ReportedQuantity,
        conformity: Conformity | None,
    ) -> None:
        result = self.el(parent, "result")
        self.texts(result, "name", q.name)
        quantity = self.el(
            self.el(result, "data"),
            "quantity",
            id=self.quantity_ids[(m.index, q.key)],
            ref_type="basic_measuredValue",
        )
        self.texts(quantity, "name", q.name)
        notes = [f"key in the results: {q.key}"]
        if q.unit:
            notes.append(f"unit as printed: {q.unit}")
        if q.note:
            notes.append(q.note)
        if q.interval is not None:
            notes.append(
                "a biased, bounded quantity: the coverage interval for the true value is stated "
                f"instead of value ± U (U = {q.U} is half its width, k = {q.k}; the standard "
                "uncertainty is U/k to two significant digits)"
            )
        self.texts(quantity, "description", *notes)
        real = self.si_real(quantity, q.value, q.dsi_unit, label=q.key)
        if q.interval is None:
            self.expanded(real, q.U, q.k, q.p)
        else:
            interval = self.el(real, "coverageInterval", ns=SI_NAMESPACE)
            self.el(interval, "standardUnc", standard_uncertainty(q), ns=SI_NAMESPACE)
            self.el(interval, "intervalMin", q.interval[0], ns=SI_NAMESPACE)
            self.el(interval, "intervalMax", q.interval[1], ns=SI_NAMESPACE)
            self.el(interval, "coverageProbability", q.p, ns=SI_NAMESPACE)
        if conformity is not None:
            self.conformity(quantity, q, conformity)

    def conformity(
        self, quantity: etree._Element, q: ReportedQuantity, conformity: Conformity
    ) -> None:
        """The quantity's ``measurementMetaData``: its conformity, the decision rule it follows
        (``refId``) and the limits as quantities in the quantity's unit."""
        meta = self.el(
            self.el(quantity, "measurementMetaData"),
            "metaData",
            ref_id=f"decisionRule_{conformity.decision_rule}",
            ref_type="basic_conformity",
        )
        self.el(meta, "norm", "ILAC-G8:09/2019")
        self.texts(meta, "declaration", conformity.statement)
        self.el(meta, "conformity", dcc_conformity(conformity))
        data = self.el(meta, "data")
        for limit, ref_type, name in (
            (conformity.limit_min, "basic_toleranceLimitLower", "lower limit"),
            (conformity.limit_max, "basic_toleranceLimitUpper", "upper limit"),
        ):
            if limit:
                limit_quantity = self.el(data, "quantity", ref_type=ref_type)
                self.texts(limit_quantity, "name", name)
                self.si_real(limit_quantity, limit, q.dsi_unit)


#: Keyword names of :meth:`_DccWriter.el` → the DCC's attribute names.
_ATTRIBUTE = {
    "id": "id",
    "ref_id": "refId",
    "ref_type": "refType",
    "lang": "lang",
    "schema_version": "schemaVersion",
}


def _country(contact: Contact) -> str:
    # ``Contact.country`` (ISO 3166-1 alpha-2) arrives with the plan reader; until then none
    return str(getattr(contact, "country", "") or "")


def _standard_line(standard: Standard) -> str:
    line = (
        f"{standard.name} ({standard.id}), calibration certificate {standard.certificate}, "
        f"due {standard.due.isoformat()}"
    )
    return f"{line}, traceable through {standard.traceability}" if standard.traceability else line


def _command_ref(command: str) -> str:
    """``rotacal_gyro_scale-factor``: the command as one token of a ``refType`` list."""
    return "rotacal_" + command.replace(" ", "_")


def _command_line(m: MeasurementResult) -> str:
    options = ", ".join(f"{name} = {_plain(value)}" for name, value in m.options.items())
    return f"command: rotacal {m.command}" + (f"; options: {options}" if options else "")
