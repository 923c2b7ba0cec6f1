"""The tower table of a section read from a CSV file (``[line] towers_file``).

One header row naming the columns (:data:`~.case_schema.TOWER_COLUMNS`, the keys of a
``[[line.towers]]`` table) and one row per tower, in line order; blank and ``#`` lines are
skipped.  The rows come back as raw dicts (numbers parsed) for the section builder
(:mod:`.case_geometry`) to validate like inline tables.  A file that is not a tower table is
refused without quoting its content; messages name the file, the row and the column.
"""

from __future__ import annotations

import csv
import difflib
import io
import re
from pathlib import Path
from typing import Any

from .case_files import MAX_CASE_BYTES, read_text_file
from .case_schema import SCHEMA, TOWER_COLUMNS, FieldSpec
from .case_validate import CONTROL_CHARS, fmt_value
from .errors import CaseError

# A tower CSV's column names are quoted in a message only when they are short printable tokens
# like these; anything else -- a file that is not a tower table (towers_file = "/etc/shadow") --
# is refused without quoting its content.
_COLUMN_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_ .-]{0,31}")
MAX_QUOTED_CELL = 40  # [characters] a longer cell is described by its length, not quoted
#: the columns a tower table of a case with [[wires]] needs (height and support come from the type)
TYPED_TOWER_COLUMNS = ("station", "type")


def _not_a_tower_table(path: Path) -> CaseError:
    return CaseError(f"not a tower table: expected a comma-separated (CSV) file whose first row names its columns "
                     f"({', '.join(TOWER_COLUMNS)}; required: station, height, support) and one row per tower",
                     file=str(path))


def reads_as_header(header: list[str], columns: tuple[str, ...]) -> bool:
    """Whether a CSV file's first row makes it a table of ``columns`` (a tower table, a field
    file), so that its column names may be quoted in messages: at least two cells, each a short
    printable token (:data:`_COLUMN_TOKEN`), at least one of them one of ``columns`` or close to one."""
    if len(header) < 2 or not all(_COLUMN_TOKEN.fullmatch(h) for h in header):
        return False
    lower = [c.lower() for c in columns]
    return any(h.lower() in lower or difflib.get_close_matches(h.lower(), lower, n=1, cutoff=0.6) for h in header)


def _reads_as_tower_header(header: list[str]) -> bool:
    return reads_as_header(header, TOWER_COLUMNS)


def cell_text(cell: str) -> str:
    """A CSV data cell as a message quotes it: a short printable cell quoted (``"abc"``), anything
    longer or holding a control character described by its length (``of 60 characters``)."""
    return fmt_value(cell) if len(cell) <= MAX_QUOTED_CELL and not CONTROL_CHARS.search(cell) else f"of {len(cell)} characters"



def read_towers_csv(path: Path, typed: bool = False) -> list[tuple[dict[str, Any], int]]:
    """Rows of a tower CSV as raw dicts (numbers parsed) with their 1-based CSV record numbers.
    ``typed``: the towers of a case with ``[[wires]]``, whose required columns are ``station``
    and ``type`` (the type's attachments give each wire's height and support).

    The same text rule as TOML strings (:data:`~.case_validate.CONTROL_CHARS`: no control
    characters, a quoted newline included) holds for every cell; a leading byte-order mark is
    dropped (:func:`~.case_files.read_text_file`).  A file whose first row is not a tower header
    (:func:`_reads_as_tower_header`) is "not a tower table", and no message quotes its content."""
    numbered = _csv_records(path)
    head_row, header = numbered[0]
    header = [h.strip() for h in header]
    _check_tower_header(path, head_row, header, typed)
    specs = {sp.name: sp for sp in SCHEMA["line.towers"]}
    return [(_tower_row(path, header, specs, row_no, r), row_no) for row_no, r in numbered[1:]]


def _csv_records(path: Path) -> list[tuple[int, list[str]]]:
    """The CSV records of a tower table that are neither blank nor ``#`` comments, with their
    1-based record numbers; at least one (the header)."""
    text = read_text_file(path, "a CSV tower table", MAX_CASE_BYTES)
    try:
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error:
        raise _not_a_tower_table(path) from None
    numbered = [(i + 1, r) for i, r in enumerate(rows) if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not numbered:
        raise CaseError(f"is empty: expected a header row with the columns {', '.join(TOWER_COLUMNS)} and one row per tower",
                        file=str(path))
    return numbered


def _check_tower_header(path: Path, head_row: int, header: list[str], typed: bool) -> None:
    """Refuse a header row that is not a tower header, or names an unknown column, repeats a
    column or lacks a required one (``head_row``: its 1-based record number; ``typed``: the
    towers of a case with ``[[wires]]``)."""
    if not _reads_as_tower_header(header):
        raise _not_a_tower_table(path)
    for h in header:
        if h not in TOWER_COLUMNS:
            close = difflib.get_close_matches(h, TOWER_COLUMNS, n=1, cutoff=0.5)
            hint = f'; did you mean "{close[0]}"?' if close else ""
            raise CaseError(f"unknown column {fmt_value(h)}{hint} (allowed: {', '.join(TOWER_COLUMNS)})", file=str(path),
                            key=f"row {head_row}")
    repeated = [h for h in TOWER_COLUMNS if header.count(h) > 1]
    if repeated:
        raise CaseError(f"header repeats column {fmt_value(repeated[0])}: expected each of {', '.join(TOWER_COLUMNS)} at most once",
                        file=str(path), key=f"row {head_row}")
    required = TYPED_TOWER_COLUMNS if typed else tuple(spec.name for spec in SCHEMA["line.towers"] if spec.required)
    for name in required:
        if name not in header:
            raise CaseError(f"missing column {fmt_value(name)}: expected the columns {', '.join(TOWER_COLUMNS)} "
                            f"(required: {', '.join(required)}{' with [[wires]]' if typed else ''})", file=str(path),
                            key=f"row {head_row}")


def _tower_row(path: Path, header: list[str], specs: dict[str, FieldSpec], row_no: int, r: list[str]) -> dict[str, Any]:
    """One data record ``r`` (record number ``row_no``) as a raw tower dict: blank cells left out
    (they take the default), numeric columns parsed to float, the others kept as text."""
    if len(r) > len(header):
        raise CaseError(f"has {len(r)} cells: expected at most {len(header)} (one per header column)",
                        file=str(path), key=f"row {row_no}")
    d: dict[str, Any] = {}
    for col, cell in zip(header, r):
        m = CONTROL_CHARS.search(cell)
        if m:  # the TOML strings' rule (case_validate.check_text): ESC, NUL, a quoted newline ...
            raise CaseError(f"control character U+{ord(m.group()):04X} at position {m.start() + 1} is not "
                            "allowed: expected printable text", file=str(path), key=f"row {row_no}, column {col}")
        cell = cell.strip()
        if cell == "":
            continue
        if specs[col].kind == "float":
            try:
                d[col] = float(cell)
            except ValueError:
                raise CaseError(f"value {cell_text(cell)} is not a number: expected {specs[col].allowed()}",
                                file=str(path), key=f"row {row_no}, column {col}") from None
        else:
            d[col] = cell
    return d
