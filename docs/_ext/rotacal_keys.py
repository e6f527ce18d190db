"""The ``rotacal-keys`` directive: the table of JSON keys, made from the code at build time.

One row per key of :data:`rotacal.glossary.GLOSSARY` — key, plain name, unit, meaning — and the
commands whose JSON holds it. The commands come from the result class each command writes
(:data:`COMMAND_RESULTS`): a key belongs to a command when it is a public field of that class or
of a result nested in it. So the page cannot drift from the glossary or from the result classes;
a key no listed class has (a key a ``to_dict`` adds, or one of a result added later) shows "—".
"""

from __future__ import annotations

import dataclasses
import importlib
import typing
from collections.abc import Iterator
from typing import Any

from docutils import nodes
from sphinx.util.docutils import SphinxDirective

#: The result class whose ``to_dict()`` is each command's JSON, as "module:Class".
COMMAND_RESULTS: dict[str, str] = {
    "motion encoder": "rotacal.table.motion:MotionResult",
    "motion lts": "rotacal.table.motion:MotionResult",
    "motion fog": "rotacal.table.motion:MotionResult",
    "selfcal": "rotacal.encoder.selfcal:SelfCalibration",
    "rate": "rotacal.table.rate:RateResult",
    "gyro scale-factor": "rotacal.gyro.scale_factor:ScaleFactorResult",
    "gyro triad": "rotacal.gyro.triad:TriadResult",
    "gyro rotations": "rotacal.gyro.rotations:RotationCalibration",
    "gyro multiposition": "rotacal.gyro.multiposition:MultipositionResult",
    "allan": "rotacal.gyro.noise:GyroNoise",
    "turntable budget": "rotacal.turntable.budget:TurntableBudget",
    "inspect": "rotacal.inspect.result:InspectResult",
    # the demo's comparison of the encoder and LTS schemes on one motion
    "demo": "rotacal.table.motion:SchemeComparison",
}


def _load(spec: str) -> type:
    module, name = spec.split(":")
    return typing.cast(type, getattr(importlib.import_module(module), name))


def _dataclasses_in(hint: Any) -> Iterator[type]:
    """The dataclasses a type hint names, also inside ``X | None``, ``tuple[X, ...]``, ``dict``."""
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        yield hint
    for arg in typing.get_args(hint):
        yield from _dataclasses_in(arg)


def json_fields(cls: type, seen: set[type] | None = None) -> set[str]:
    """Public field names of a result class and of the results nested in its public fields."""
    seen = set() if seen is None else seen
    if cls in seen:
        return set()
    seen.add(cls)
    hints = typing.get_type_hints(cls)
    names: set[str] = set()
    for field in dataclasses.fields(cls):
        if field.name.startswith("_") or not field.repr:
            continue
        names.add(field.name)
        for nested in _dataclasses_in(hints.get(field.name)):
            names |= json_fields(nested, seen)
    return names


def commands_by_key() -> dict[str, list[str]]:
    """For every field name of a command's result, the commands whose JSON holds it."""
    out: dict[str, list[str]] = {}
    for command, spec in COMMAND_RESULTS.items():
        for name in json_fields(_load(spec)):
            out.setdefault(name, []).append(command)
    return out


def _cell(*children: nodes.Node) -> nodes.entry:
    entry = nodes.entry()
    para = nodes.paragraph()
    para.extend(children)
    entry += para
    return entry


class RotacalKeys(SphinxDirective):
    """Renders the glossary as a table of key, name, unit, meaning and commands."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from rotacal.glossary import GLOSSARY

        producers = commands_by_key()
        headers = ("JSON key", "name", "unit", "meaning", "written by")
        table = nodes.table(classes=["rotacal-keys"])
        group = nodes.tgroup(cols=len(headers))
        table += group
        for width in (18, 16, 6, 40, 20):
            group += nodes.colspec(colwidth=width)
        head_row = nodes.row()
        for title in headers:
            head_row += _cell(nodes.Text(title))
        group += nodes.thead("", head_row)
        body = nodes.tbody()
        for key in sorted(GLOSSARY):
            entry = GLOSSARY[key]
            commands = producers.get(key, [])
            row = nodes.row()
            row += _cell(nodes.literal(text=key))
            row += _cell(nodes.Text(entry.name))
            row += _cell(nodes.Text(entry.unit or "—"))
            row += _cell(nodes.Text(entry.meaning))
            written_by: list[nodes.Node] = []
            for i, command in enumerate(commands):
                if i:
                    written_by.append(nodes.Text(", "))
                written_by.append(nodes.literal(text=command))
            row += _cell(*(written_by or [nodes.Text("—")]))
            body += row
        group += body
        return [table]


def setup(app: Any) -> dict[str, Any]:
    app.add_directive("rotacal-keys", RotacalKeys)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
