"""Validation of a parsed case document against :data:`~.case_schema.SCHEMA`
(and :data:`~.case_schema.WIRE_SCHEMA`).

Checks each table's keys for name, type and range and fills the defaults (:func:`read_section`),
refuses control characters and absurd nesting (:func:`check_text`), and builds the one-line
:class:`~.errors.CaseError` messages that name the file, the key (and its line), the value and
what is allowed (:class:`ErrorContext`, :func:`fmt_value`).  :func:`case_warnings` flags values
the schema allows but that are probably mistyped.
"""

from __future__ import annotations

import datetime
import difflib
import math
import re
from pathlib import Path
from typing import Any

from .case_model import GRAVITY, Case
from .case_schema import FieldSpec, schema_table
from .errors import CaseError

#: tables a table may hold (not keys of :data:`SCHEMA`): the top level's and ``[wind]``'s
SUBTABLES = {"": ("line", "wind", "analysis", "codes"), "wind": ("downburst",)}
#: arrays of tables a table may hold, checked by their own builders (:mod:`.case_wires`)
ARRAY_TABLES = {"": ("tower_types", "wires")}


#: Bulk density of a conductor, W / (g pi D^2 / 4) [kg/m3], outside which ``line.weight`` is
#: probably mistyped: aluminium 2,700 to copper 8,900 with strands' voids (the paper's
#: conductor: 4,805); a weight typed in kg/m gives about 1/9.81 of it (490 for the paper's).
DENSITY_RANGE = (1500.0, 9000.0)

# C0 controls except tab, DEL and the C1 controls: they inject terminal escape sequences and
# openpyxl refuses them (IllegalCharacterError); no case text needs them.
CONTROL_CHARS = re.compile("[\x00-\x08\x0a-\x1f\x7f-\x9f]")
MAX_NESTING = 16  # deepest table/array nesting a case file needs is 3 ([wind.downburst], a list)


def case_warnings(case: Case) -> list[str]:
    """One-line warnings about values the schema allows but that are probably mistyped: the
    weight against the conductor's bulk density (:data:`DENSITY_RANGE`), of ``[line]`` or, with
    ``[[wires]]``, of each wire's sub-conductor.  Names the file (and line when the file is
    readable), key, value and what is expected.  Never prints."""
    if case.has_wires:
        checks = [(f"wires[{k + 1}]", lambda text, k=k: array_table_line(text, "wires", k, "weight"), w.weight, w.diameter)
                  for k, w in enumerate(case.wires)]
    else:
        checks = [("line", lambda text: find_line(text, "line", "weight"), case.line.weight, case.line.diameter)]
    out = []
    for table, line_of, weight, diameter in checks:
        message = _density_warning(case, table, line_of, weight, diameter)
        if message is not None:
            out.append(message)
    return out


def _density_warning(case: Case, table: str, line_of, weight: float, diameter: float) -> str | None:
    """The bulk-density warning of ``table``'s ``weight`` [N/m] and ``diameter`` [m], or None;
    ``line_of(text)``: the weight's file line."""
    density = weight / (GRAVITY * math.pi * diameter**2 / 4.0)
    low, high = DENSITY_RANGE
    if low <= density <= high:
        return None
    text = None
    if case.source is not None:
        try:
            text = Path(case.source).read_text(encoding="utf-8", errors="replace")
        except OSError:
            text = None
    where = ""
    if case.source is not None:
        line_no = line_of(text)
        where = f"{case.source}" + (f":{line_no}" if line_no is not None else "") + ": "
    if density < low:
        hint = (f"a weight in kg/m? In N/m it would be {weight:g} x {GRAVITY:g} = "
                f"{weight * GRAVITY:.4g} N/m")
    else:
        hint = (f"a bundle's weight with one sub-conductor's diameter, or a unit slip? "
                f"{high:,.0f} kg/m3 would be a weight of {high * GRAVITY * math.pi * diameter**2 / 4.0:.4g} N/m")
    return (f"{where}{table}.weight: value {weight:g} N/m with diameter {diameter:g} m gives a "
            f"bulk density W/(g pi D^2/4) of {density:,.0f} kg/m3, outside {low:,.0f}-{high:,.0f} "
            f"(the paper's conductor: 4,805): {hint}")


def find_line(text: str | None, section: str, key: str | None) -> int | None:
    """1-based line of ``key`` inside ``[section]`` (or of the header when key is None)."""
    if text is None:
        return None
    current = ""
    header = re.compile(r"^\s*\[\s*([A-Za-z0-9_.\-\" ]+?)\s*\]\s*(#.*)?$")
    for n, raw in enumerate(text.splitlines(), start=1):
        m = header.match(raw)
        if m:
            current = m.group(1).replace('"', "").replace(" ", "")
            if key is None and current == section:
                return n
            continue
        if key is not None and current == section and re.match(rf"^\s*\"?{re.escape(key)}\"?\s*=", raw):
            return n
    return None


class ErrorContext:
    """Where a value came from, to build messages that name file, key and line."""

    def __init__(self, file: str | None, text: str | None) -> None:
        self.file = file
        self.text = text

    def error(self, section: str, key: str | None, message: str) -> CaseError:
        dotted = f"{section}.{key}" if section and key else (key or section or None)
        return CaseError(message, file=self.file, key=dotted, line=find_line(self.text, section, key))


def array_table_line(text: str | None, array: str, k: int, key: str | None) -> int | None:
    """1-based file line of ``key`` in the k-th (0-based) ``[[array]]`` table (``array`` dotted,
    e.g. ``"line.towers"``, ``"wires"``), or of its header when key is None."""
    if text is None:
        return None
    header = re.compile(r"^\[\[\s*" + r"\s*\.\s*".join(re.escape(p) for p in array.split(".")) + r"\s*\]\]")
    count = -1
    inside = False
    for n, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if stripped.startswith("["):
            inside = header.match(stripped) is not None
            if inside:
                count += 1
                if count == k and key is None:
                    return n
            continue
        if inside and count == k and key is not None and re.match(rf"^\s*\"?{re.escape(key)}\"?\s*=", raw):
            return n
    return None


class ItemContext(ErrorContext):
    """Error context of the k-th (0-based) table of an array of tables: messages name
    ``array[k+1].key`` (``wires[2].weight``) and the key's line in that table."""

    def __init__(self, ctx: ErrorContext, array: str, k: int) -> None:
        super().__init__(ctx.file, ctx.text)
        self.array, self.k = array, k

    def error(self, section: str, key: str | None, message: str) -> CaseError:
        dotted = f"{self.array}[{self.k + 1}]" + (f".{key}" if key else "")
        return CaseError(message, file=self.file, key=dotted, line=array_table_line(self.text, self.array, self.k, key))


FMT_LIST_ITEMS = 5  # a list in a message shows its first items and its length, never the whole list


def fmt_value(value: Any) -> str:
    """A value as a message shows it: strings quoted, TOML spellings, a long list abbreviated
    (``[1.0, 2.0, 3.0, 4.0, 5.0, ... (10000 items)]``) so that a message stays one short line."""
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        if len(value) > FMT_LIST_ITEMS + 1:
            head = ", ".join(fmt_value(v) for v in value[:FMT_LIST_ITEMS])
            return f"[{head}, ... ({len(value)} items)]"
        return "[" + ", ".join(fmt_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, (datetime.date, datetime.time)):  # a TOML date/time: its TOML text
        return value.isoformat()
    return repr(value)


def _check_number(spec: FieldSpec, v: Any, ctx: ErrorContext, section: str, item: tuple[int, int] | None = None) -> float:
    """``v`` checked against ``spec``'s kind and range.  ``item``: (1-based position, list length)
    of ``v`` in a list; a message then names that item and its value, never the whole list (the
    value is formatted only when it is refused: checking a list is linear in its length)."""
    if _number_ok(spec, v):
        return v
    shown = f"item {item[0]} of {item[1]} (value {fmt_value(v)})" if item is not None else f"value {fmt_value(v)}"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ctx.error(section, spec.name, f"{shown} is not allowed: expected {spec.allowed()}")
    if spec.kind == "int" and not isinstance(v, int):
        raise ctx.error(section, spec.name, f"{shown} is not allowed: expected {spec.allowed()}")
    if not math.isfinite(float(v)):
        raise ctx.error(section, spec.name, f"{shown} is not allowed: expected {spec.allowed()}")
    raise ctx.error(section, spec.name, f"{shown} is out of range: expected {spec.allowed()}")


def _number_ok(spec: FieldSpec, v: Any) -> bool:
    """Whether ``v`` is a number of ``spec``'s kind within its range (no message built)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    if spec.kind == "int" and not isinstance(v, int):
        return False
    if not math.isfinite(float(v)):
        return False
    if spec.low is not None and (v <= spec.low if spec.low_open else v < spec.low):
        return False
    return not (spec.high is not None and v > spec.high)


def check_value(spec: FieldSpec, v: Any, ctx: ErrorContext, section: str) -> Any:
    if spec.kind in ("float", "int"):
        out = _check_number(spec, v, ctx, section)
        return float(out) if spec.kind == "float" else int(out)
    if spec.kind == "str":
        if not isinstance(v, str):
            raise ctx.error(section, spec.name, f"value {fmt_value(v)} is not allowed: expected {spec.allowed()}")
        return v
    if spec.kind == "choice":
        if not isinstance(v, str) or v not in spec.choices:
            hint = ""
            if isinstance(v, str):
                close = difflib.get_close_matches(v, spec.choices, n=1)
                hint = f' (did you mean "{close[0]}"?)' if close else ""
            raise ctx.error(section, spec.name, f"value {fmt_value(v)} is not allowed: expected {spec.allowed()}{hint}")
        return v
    if spec.kind == "bool":
        if not isinstance(v, bool):
            raise ctx.error(section, spec.name, f"value {fmt_value(v)} is not allowed: expected {spec.allowed()}")
        return v
    if spec.kind == "float_list":
        if not isinstance(v, list) or not v:
            raise ctx.error(section, spec.name, f"value {fmt_value(v)} is not allowed: expected {spec.allowed()}")
        n = len(v)
        return tuple(float(_check_number(spec, x, ctx, section, item=(i, n))) for i, x in enumerate(v, start=1))
    if spec.kind == "str_list":
        if not isinstance(v, list) or not v:
            raise ctx.error(section, spec.name, f"value {fmt_value(v)} is not allowed: expected a list, each {spec.allowed()}")
        for i, x in enumerate(v, start=1):
            if not isinstance(x, str) or (spec.choices and x not in spec.choices):
                raise ctx.error(section, spec.name, f"item {i} of {len(v)} (value {fmt_value(x)}) is not allowed: "
                                f"expected each {spec.allowed()}")
        return tuple(v)
    raise ValueError(spec.kind)  # pragma: no cover - schema bug


def read_section(data: dict, section: str, ctx: ErrorContext, optional: tuple[str, ...] = ()) -> dict[str, Any]:
    """Validate the keys of one table against :data:`SCHEMA` (or :data:`WIRE_SCHEMA`); fill
    defaults.  ``optional``: required keys this table may leave out here (their default, None,
    is filled; the caller decides)."""
    specs = {s.name: s for s in schema_table(section)}
    subtables = set(SUBTABLES.get(section, ()))
    arrays = set(ARRAY_TABLES.get(section, ()))
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key in subtables:
            if not isinstance(value, dict):
                raise ctx.error(section, key, f"value {fmt_value(value)} is not allowed: expected a table [{(section + '.') if section else ''}{key}]")
            continue
        if key in arrays:
            continue
        if key not in specs:
            candidates = list(specs) + sorted(subtables | arrays)
            close = difflib.get_close_matches(key, candidates, n=1, cutoff=0.5)
            hint = f'; did you mean "{close[0]}"?' if close else ""
            where = f"[{section}]" if section else "the top level"
            allowed = ", ".join(candidates)
            raise ctx.error(section, key, f"unknown key in {where}{hint} (allowed: {allowed})")
        out[key] = check_value(specs[key], value, ctx, section)
    for name, spec in specs.items():
        if name not in out:
            if spec.required and name not in optional:
                raise ctx.error(section, name, f"missing required key: expected {spec.allowed()}")
            out[name] = spec.default
    return out


def check_text(data: dict[str, Any], ctx: ErrorContext) -> None:
    """Reject control characters in every key and string value, and absurd nesting."""
    stack: list[tuple[str, Any, int]] = [("", data, 0)]
    while stack:
        where, value, depth = stack.pop()
        section, _, key = where.rpartition(".")
        if depth > MAX_NESTING:
            raise ctx.error(section, key or None, f"value nested {depth} levels deep is not allowed: expected "
                            f"at most {MAX_NESTING} levels of tables and arrays")
        if isinstance(value, str):
            m = CONTROL_CHARS.search(value)
            if m:
                raise ctx.error(section, key or None, f"control character U+{ord(m.group()):04X} at position "
                                f"{m.start() + 1} is not allowed: expected printable text")
        elif isinstance(value, dict):
            for k, v in value.items():
                m = CONTROL_CHARS.search(k)
                if m:
                    raise ctx.error(where, None, f"a key holds control character U+{ord(m.group()):04X}: "
                                    "expected printable key names")
                stack.append((f"{where}.{k}" if where else k, v, depth + 1))
        elif isinstance(value, list):
            stack.extend((where, v, depth + 1) for v in value)

