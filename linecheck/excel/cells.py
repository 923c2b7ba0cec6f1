"""Shared pieces of the workbook: number formats, cell values, styles helpers, sheet names."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

from openpyxl.styles import Alignment, Font
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.hyperlink import Hyperlink
from openpyxl.worksheet.worksheet import Worksheet

from ..core.names import REACTIONS
from ..io.display import kn as to_kn
from ..io.document import StatDef

__all__ = ["REACTIONS"]  # the reaction names, for the sheets
#: Reactions of the Summary and Peaks sheets by default: the paper's Table 5 and Fig. 13 (Rz, the
#: vertical reaction, whose wind-induced part is small beside the conductor weight, is on the case sheets).
SUMMARY_REACTIONS = ("Rx", "Ry")

# number formats
KN = "#,##0.00"
KN3 = "#,##0.000"
RATIO = "0.00"
PCT = "0.00%"
NORM = "0.000"
SEC = "0.0"

#: Summary columns after the identification columns (paper Table 5): names of the one statistics
#: table (:data:`linecheck.io.document.STAT_TABLE`), whose labels, units and formats they use.
SUMMARY_STATS: tuple[str, ...] = ("mean_max", "peak_quasi_static", "peak_dynamic", "GF_Dy", "GF_QS", "Cont_M",
                                  "Cont_BG", "Cont_R", "peak_normalised")


def excel_format(stat: StatDef, *, summary: bool = False) -> str:
    """The Excel number format of a statistic of the one table (forces to 2 decimals in the
    Summary, 3 on the case sheets; Cont_* as %; gust factors 2 decimals; other ratios 3)."""
    if stat.kind == "force":
        return KN if summary else KN3
    if stat.kind == "fraction":
        return PCT
    return RATIO if stat.ci else NORM


def stat_cell(stat: StatDef, v: float | None) -> Any:
    """The cell value of a statistic's SI value: kN for forces, fractions as they are (shown by
    the % format), ``**`` for an undefined gust factor, empty otherwise."""
    if not is_num(v):
        return GF_UNDEFINED if stat.kind == "ratio" and stat.ci else None
    return v * stat.scale if stat.kind == "force" else v


#: Default thinning of the time histories for the charts (points per case).
CHART_POINTS = 1000

FLAG_NOTE = "dynamic analysis recommended"
GF_UNDEFINED = "**"

_RESERVED = {"summary", "peaks"}


#: First characters that make a spreadsheet read a typed text as a formula (OWASP "CSV injection":
#: ``=``, ``+``, ``-``, ``@``, tab, carriage return).
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


#: Characters an .xlsx (XML 1.0 in UTF-8) cannot hold: control characters but tab, line feed and
#: carriage return (openpyxl's ILLEGAL_CHARACTERS_RE), lone surrogates (no UTF-8 form; JSON's
#: "\ud800" reads as one) and the non-characters U+FFFE, U+FFFF.
XML_ILLEGAL_RE = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def clean_text(text: Any) -> str:
    """``text`` as the workbook can hold it: every character of :data:`XML_ILLEGAL_RE` replaced by
    U+FFFD.  Cell texts, sheet names (and with them defined names and chart references), chart
    titles and page headers all go through here: one such character anywhere in the XML makes
    the whole workbook unreadable."""
    return XML_ILLEGAL_RE.sub("\ufffd", str(text))


def set_value(cell, value: Any) -> Any:
    """Put ``value`` into ``cell``; a text is always stored as a text, never as a formula.

    openpyxl turns a ``str`` beginning with ``=`` into a formula and ``"#N/A"`` into an
    error value; every text the writer puts into a cell (case names, descriptions, title
    block, failed files, error messages) goes through here, so a case named
    ``=cmd|' /C calc'!A0`` is an inline string.  A text that starts like a formula also
    gets Excel's quote prefix, so that editing the cell keeps it a text.  Characters that
    XML 1.0 cannot hold (control characters) are replaced by U+FFFD.
    """
    if isinstance(value, str):
        value = clean_text(value)
        cell.value = value
        cell.data_type = "s"
        if value.startswith(FORMULA_START):
            cell.quotePrefix = True
    else:
        cell.value = value
    return cell


def header_text(text: Any) -> str:
    """``text`` for a page header/footer: ``&`` starts a field code there, ``&&`` is a literal ampersand."""
    return clean_text(text).replace("&", "&&")


def is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def kn(v: Any) -> Any:
    """A force [N] as a cell value [kN]; empty (None) unless a finite number."""
    return to_kn(v) if is_num(v) else None


def sheet_name(name: str, taken: set[str]) -> str:
    r"""A valid, unique (case-insensitive) sheet name from a case name: cleaned like cell text
    (:func:`clean_text`; the name reaches the workbook's sheet list, its defined names such as
    the print area, hyperlinks and every chart reference), tabs and line breaks as spaces, the
    characters Excel forbids (``[]:*?/\``) as ``_``, at most 31 characters."""
    base = re.sub(r"[\t\n\r]", " ", clean_text(name))
    base = re.sub(r"[\[\]:*?/\\]", "_", base).strip("' ") or "case"
    base = base[:31]
    cand, k = base, 2
    while cand.lower() in taken or cand.lower() in _RESERVED:
        suffix = f" ({k})"
        cand = base[: 31 - len(suffix)] + suffix
        k += 1
    taken.add(cand.lower())
    return cand


def wind_label(doc: Any) -> str:
    """``"downburst <preset>"`` or the wind type of a RunDocument."""
    db = ((doc.parameters or {}).get("wind") or {}).get("downburst")
    preset = db.get("preset") if isinstance(db, dict) else None
    return f"{doc.wind} {preset}" if preset else doc.wind


def align(cell, **changes: Any) -> None:
    """Change some alignment attributes of a cell, keeping the others."""
    a = cell.alignment
    cell.alignment = Alignment(horizontal=changes.get("horizontal", a.horizontal),
                               vertical=changes.get("vertical", a.vertical),
                               wrap_text=changes.get("wrap_text", a.wrap_text),
                               indent=changes.get("indent", a.indent))


def link(cell, sheet: str) -> None:
    quoted = sheet.replace("'", "''")  # a quote inside a quoted sheet name is doubled
    cell.hyperlink = Hyperlink(ref=cell.coordinate, location=f"'{quoted}'!A1", display=str(cell.value))
    cell.font = Font(name="Calibri", size=10, color="0563C1", underline="single")


def page_setup(ws: Worksheet, like: Worksheet | None, *, landscape: bool = True) -> None:
    ws.page_setup.orientation = "landscape" if landscape else "portrait"
    ws.page_setup.paperSize = (like.page_setup.paperSize if like is not None and like.page_setup.paperSize
                               else ws.PAPERSIZE_A4)
    ws.sheet_properties.pageSetUpPr.fitToPage = True
    ws.page_setup.fitToWidth = 1
    ws.page_setup.fitToHeight = 0
    ws.page_margins.left = ws.page_margins.right = 0.5
    ws.page_margins.top = ws.page_margins.bottom = 0.75
    ws.page_margins.header = ws.page_margins.footer = 0.3
    ws.oddFooter.left.text = "linecheck design sheet"
    ws.oddFooter.right.text = "page &P of &N"


#: Characters of the 9 pt note font per unit of Excel column width (the width unit is one
#: character of the 11 pt default font), rounded down so that an estimate never falls short.
NOTE_CHARS_PER_WIDTH = 1.1
NOTE_LINE_HEIGHT = 12.0  # [pt] one line of the 9 pt note font


def wrap_notes(ws: Worksheet, first_row: int, last_row: int, right: int) -> None:
    """Keep the notes inside columns A..``right`` (the print area): every note of rows
    ``first_row``..``last_row`` (an ``lc_note`` cell in column A, the rest of its row empty) is
    merged across them and wrapped, its row as tall as the lines it needs (Excel does not
    fit a merged row's height itself)."""
    widths = [ws.column_dimensions[get_column_letter(c)].width or 8.43 for c in range(1, right + 1)]
    chars = max(20.0, sum(widths) * NOTE_CHARS_PER_WIDTH)
    for r in range(first_row, last_row + 1):
        cell = ws.cell(row=r, column=1)
        if cell.style != "lc_note" or not isinstance(cell.value, str) or right < 2:
            continue
        if any(ws.cell(row=r, column=c).value not in (None, "") for c in range(2, right + 1)):
            continue
        ws.merge_cells(start_row=r, start_column=1, end_row=r, end_column=right)
        align(cell, wrap_text=True, vertical="top")
        ws.row_dimensions[r].height = NOTE_LINE_HEIGHT * max(1, math.ceil(len(cell.value) / chars))


class Cursor:
    """Writes styled cells down a sheet."""

    def __init__(self, ws: Worksheet, row: int = 1) -> None:
        self.ws = ws
        self.row = row

    def put(self, row: int, col: int, value: Any, style: str = "lc_number", fmt: str | None = None):
        c = self.ws.cell(row=row, column=col)
        c.style = style
        set_value(c, value)
        if fmt is not None and is_num(value):
            c.number_format = fmt
        return c

    def section(self, text: str, width: int = 8) -> None:
        self.row += 1
        for col in range(1, width + 1):
            self.ws.cell(row=self.row, column=col).style = "lc_section"
        set_value(self.ws.cell(row=self.row, column=1), text)
        self.row += 1

    def header(self, labels: Sequence[str], col0: int = 1) -> None:
        for k, label in enumerate(labels):
            self.put(self.row, col0 + k, label, "lc_header")
        self.row += 1

    def note(self, text: str) -> None:
        self.put(self.row, 1, text, "lc_note")
        self.row += 1


