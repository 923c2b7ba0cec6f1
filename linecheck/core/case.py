"""The case API: one place to import the case model, its schema, loading, editing and writing.

A case is split by job over these modules, re-exported here so that
``from linecheck.core.case import X`` serves every caller:

* :mod:`.case_schema` -- :data:`SCHEMA` and :data:`WIRE_SCHEMA`, every TOML key's type, range,
  default, unit and help;
* :mod:`.case_model` -- the frozen dataclasses (:class:`Case`, :class:`Line`, :class:`Tower`,
  :class:`Wire`, :class:`TowerType`, :class:`Attachment`, :class:`Wind`, :class:`Downburst`,
  :class:`Analysis`, :class:`Codes`), defaults from SCHEMA;
* :mod:`.case_load` -- :func:`load_case`, :func:`case_from_dict`, :func:`case_hash`;
* :mod:`.case_validate` -- key checks, one-line messages, :func:`case_warnings`;
* :mod:`.case_geometry` -- the line's equal-span and section (towers) forms;
* :mod:`.case_wires` -- every wire on the tower: ``[[wires]]``, ``[[tower_types]]``, and each
  wire's single-wire case (:func:`wire_case`);
* :mod:`.case_towers` -- the tower table CSV reader;
* :mod:`.case_files` -- safe reading of user files (regular files only, size caps).

This module itself writes a case back (:func:`case_to_dict`, :func:`case_to_toml`) and edits it
with the loader's validation (:func:`with_value`, :func:`with_values`, :func:`with_options`).
The TOML key layout is a public contract (``docs/case-files.md``).  Units are SI inside (m, s,
N, kg, Pa); angles are degrees in the file and in the dataclasses (converted where used).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from .case_files import MAX_CASE_BYTES, MAX_RESULT_BYTES, read_regular_file, read_text_file
from .case_geometry import EQUAL_SPAN_KEYS, MAX_TOWERS
from .case_load import case_from_dict, case_hash, load_case
from .case_model import GRAVITY, Analysis, Attachment, Case, Codes, Downburst, Line, Tower, TowerType, Wind, Wire
from .case_schema import (
    CODE_TERRAINS,
    DAMPING_MODELS,
    DEFAULT_STRUCTURAL_DAMPING,
    DOWNBURST_MODELS,
    DOWNBURST_PRESETS,
    DRAG_MODELS,
    FFT_LENGTHS,
    RING_MODELS,
    SCHEMA,
    SUPPORT_TYPES,
    TENSION_MODELS,
    TOWER_COLUMNS,
    WIND_TYPES,
    WIRE_KINDS,
    WIRE_SCHEMA,
    FieldSpec,
    field_spec,
    schema_default,
    schema_table,
)
from .case_towers import MAX_QUOTED_CELL, TYPED_TOWER_COLUMNS, cell_text, reads_as_header
from .case_validate import DENSITY_RANGE, FMT_LIST_ITEMS, MAX_NESTING, ErrorContext, case_warnings, check_value
from .case_wires import TYPE_TOWER_KEYS, WIRE_LINE_KEYS, clamp_height, wire_case
from .errors import CaseError

__all__ = [
    "CODE_TERRAINS", "DAMPING_MODELS", "DEFAULT_STRUCTURAL_DAMPING", "DENSITY_RANGE", "DOWNBURST_MODELS",
    "DOWNBURST_PRESETS", "DRAG_MODELS", "FFT_LENGTHS", "FMT_LIST_ITEMS", "GRAVITY", "MAX_CASE_BYTES",
    "MAX_NESTING", "MAX_QUOTED_CELL", "MAX_RESULT_BYTES", "MAX_TOWERS", "RING_MODELS", "SCHEMA",
    "SUPPORT_TYPES", "TENSION_MODELS", "TOWER_COLUMNS", "TYPED_TOWER_COLUMNS", "TYPE_TOWER_KEYS", "WIND_TYPES",
    "WIRE_KINDS", "WIRE_LINE_KEYS", "WIRE_SCHEMA",
    "Analysis", "Attachment", "Case", "CaseError", "Codes", "Downburst", "FieldSpec", "Line", "Tower", "TowerType",
    "Wind", "Wire",
    "case_from_dict", "case_hash", "case_to_dict", "case_to_toml", "case_warnings", "cell_text", "clamp_height",
    "field_spec", "load_case", "read_regular_file", "read_text_file", "reads_as_header", "replace",
    "schema_default", "schema_table", "wire_case", "with_options", "with_value", "with_values",
]

#: [wind] keys written only when not at their default (documents from before them stay unchanged)
_QUIET_DEFAULTS = ("direction", "profile_exponent", "coherence_decay_y", "coherence_decay_z")


def case_to_dict(case: Case) -> dict[str, Any]:
    """The TOML document of a case (only keys that are set), inverse of :func:`case_from_dict`."""
    def pick(obj: Any, section: str) -> dict[str, Any]:
        out = {}
        for spec in schema_table(section):
            v = getattr(obj, spec.name)
            if v is None:
                continue
            out[spec.name] = list(v) if isinstance(v, tuple) else v
        return out

    doc: dict[str, Any] = {"name": case.name}
    if case.description:
        doc["description"] = case.description
    doc["line"] = pick(case.line, "line")
    if case.line.is_section:  # the towers define the section: the derived equal-span keys are not written
        for key in EQUAL_SPAN_KEYS:
            doc["line"].pop(key, None)
        if case.line.towers_file is None:
            drop = TYPE_TOWER_KEYS if case.has_wires else ()  # with wires, the types place them
            doc["line"]["towers"] = [{k: v for k, v in dataclasses.asdict(t).items() if v is not None and k not in drop}
                                     for t in case.line.towers]
    if case.has_wires:
        for key in WIRE_LINE_KEYS:  # the line is the first wire's: its conductor is written per wire
            doc["line"].pop(key, None)
        doc["wires"] = [pick(w, "wires") for w in case.wires]
        for w, table in zip(case.wires, doc["wires"]):
            if w.bundle == 1:  # shielding is a bundle's key (at its default on a single conductor)
                table.pop("shielding")
        doc["tower_types"] = [{"name": t.name, "attachments": [pick(a, "tower_types.attachments") for a in t.attachments]}
                              for t in case.tower_types]
    doc["wind"] = pick(case.wind, "wind")
    for key in _QUIET_DEFAULTS:  # keys added with the section form: not written at their defaults (older documents unchanged)
        if doc["wind"].get(key) == field_spec("wind", key).default:
            doc["wind"].pop(key)
    if case.wind.downburst is not None:
        db = pick(case.wind.downburst, "wind.downburst")
        if db.get("preset"):
            for k in ("jet_diameter", "distance", "angle"):
                db.pop(k, None)
        doc["wind"]["downburst"] = db
    doc["analysis"] = pick(case.analysis, "analysis")
    if case.codes != Codes():
        doc["codes"] = pick(case.codes, "codes")
    return doc


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return str(v)


def case_to_toml(case: Case) -> str:
    """Serialise a case to TOML text with units as comments."""
    doc = case_to_dict(case)
    lines: list[str] = []

    def emit(section: str, table: dict[str, Any]) -> None:
        for spec in schema_table(section):
            if spec.name in table:
                unit = f"  # {spec.unit}" if spec.unit and spec.unit != "-" else ""
                lines.append(f"{spec.name} = {_toml_value(table[spec.name])}{unit}")

    emit("", doc)
    for section in ("line", "wind", "wind.downburst", "analysis", "codes"):
        table = doc.get(section) if "." not in section else doc["wind"].get("downburst")
        if table is None:
            continue
        lines.append("")
        lines.append(f"[{section}]")
        emit(section, table)
        if section == "line":
            for tower in table.get("towers", ()):
                lines.append("")
                lines.append("[[line.towers]]")
                emit("line.towers", tower)
    for wire in doc.get("wires", ()):
        lines += ["", "[[wires]]"]
        emit("wires", wire)
    for tower_type in doc.get("tower_types", ()):
        lines += ["", "[[tower_types]]"]
        emit("tower_types", tower_type)
        lines.append("attachments = [")
        lines += [f"    {_inline_table(a, 'tower_types.attachments')}," for a in tower_type["attachments"]]
        lines.append("]")
    return "\n".join(lines) + "\n"


def _inline_table(table: dict[str, Any], section: str) -> str:
    """A TOML inline table of ``table``'s keys in schema order: ``{ wire = "A", y = -5.5 }``."""
    items = [f"{spec.name} = {_toml_value(table[spec.name])}" for spec in schema_table(section) if spec.name in table]
    return "{ " + ", ".join(items) + " }"


def with_value(case: Case, dotted_key: str, value: Any) -> Case:
    """A validated copy of ``case`` with one key changed (e.g. ``"wind.v_ref"``).

    The same validation and messages as the file loader (TUI editor, scans).
    """
    return with_values(case, {dotted_key: value})


def with_values(case: Case, changes: dict[str, Any]) -> Case:
    """A validated copy of ``case`` with several keys changed (``None`` removes a key)."""
    if not changes:
        return case
    doc = case_to_dict(case)
    for dotted_key, value in changes.items():
        *path, key = dotted_key.split(".")
        table = doc
        for p in path:
            table = table.setdefault(p, {})
        if value is None:
            table.pop(key, None)
        else:
            table[key] = value
    base = case.source.parent if case.source else None
    return case_from_dict(doc, file=str(case.source) if case.source else None, default_name=case.name, base_dir=base)


def with_options(case: Case, options: dict[str, tuple[str, Any]]) -> Case:
    """A validated copy of ``case`` with command-line overrides, e.g.
    ``{"--realizations": ("analysis.realizations", 20)}``: each value is checked against the
    :data:`SCHEMA` range with a message naming the option, then the case is re-validated."""
    changes: dict[str, Any] = {}
    for option, (dotted, value) in options.items():
        if value is None:
            continue
        section, _, key = dotted.rpartition(".")
        ctx = ErrorContext(None, None)
        try:
            check_value(field_spec(section, key), value, ctx, section)
        except CaseError as err:
            raise CaseError(err.message.split(": ", 1)[1] + f" (overrides {dotted})", key=option) from None
        changes[dotted] = value
    return with_values(case, changes)


def replace(obj: Any, **changes: Any) -> Any:
    """``dataclasses.replace`` re-exported for convenience."""
    return dataclasses.replace(obj, **changes)
