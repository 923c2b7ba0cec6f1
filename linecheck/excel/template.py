"""The design-sheet template: title block addressed by defined names, named styles.

A template holds layout and styles only (openpyxl drops shapes, charts and unknown
extensions when it loads a workbook, so charts are created by the writer).  The
writer finds the title-block cells through workbook *defined names*, never through
fixed addresses, so a re-styled template with moved cells keeps working.

Defined names a template must have (each naming one cell, or a merged range whose
top-left cell is filled): :data:`TITLE_NAMES`.  Optional: ``summary_table`` -- the
top-left cell of the summary table (default: two rows below the last used row of
the sheet "Summary").  Named styles whose name is in :data:`STYLE_NAMES` override the
writer's built-in table styles.

The default template ``templates/design_sheet.xlsx`` is built by
``templates/make_template.py`` from :func:`build_default_template`; when the file is
not available (an installed package) the same workbook is built in memory.
"""

from __future__ import annotations

import datetime as _dt
import zipfile
from pathlib import Path
from typing import Any

from openpyxl import Workbook, load_workbook
from openpyxl.styles import Alignment, Border, Font, NamedStyle, PatternFill, Side
from openpyxl.workbook.defined_name import DefinedName
from openpyxl.worksheet.worksheet import Worksheet

from ..core.errors import CaseError
from .cells import set_value

#: Defined names of the title block (filled from ``title=``; ``date`` defaults to today).
TITLE_NAMES = ("project", "line", "section", "engineer", "checked_by", "date", "revision", "units_note")

#: Labels shown next to the title cells in the default template.
TITLE_LABELS = {
    "project": "Project", "line": "Line", "section": "Section", "engineer": "Engineer",
    "checked_by": "Checked by", "date": "Date", "revision": "Revision", "units_note": "Units",
}

#: Optional defined name: top-left cell of the summary table.
SUMMARY_ANCHOR = "summary_table"

DEFAULT_UNITS_NOTE = ("Forces in kN (JSON results in N); Cont_M, Cont_BG, Cont_R in % of the peak; "
                      "GF and peak/(g*yp Lx) dimensionless; lengths m, speeds m/s, time s.")

#: Path of the committed default template (absent in an installed package).
DEFAULT_TEMPLATE = Path(__file__).resolve().parents[2] / "templates" / "design_sheet.xlsx"

# ------------------------------------------------------------------------- styles
ACCENT = "1F4E79"
HEADER_FILL = "DDEBF7"
BAND_FILL = "F2F2F2"
FLAG_FILL = "F8CBAD"
FLAG_FONT = "9C0006"

_thin = Side(style="thin", color="8EA9DB")
_hair = Side(style="thin", color="D9D9D9")


def _styles() -> list[NamedStyle]:
    return [
        NamedStyle("lc_title", font=Font(name="Calibri", size=14, bold=True, color=ACCENT)),
        NamedStyle("lc_subtitle", font=Font(name="Calibri", size=11, italic=True, color="404040")),
        NamedStyle("lc_section", font=Font(name="Calibri", size=12, bold=True, color=ACCENT),
                   border=Border(bottom=Side(style="medium", color=ACCENT))),
        NamedStyle("lc_label", font=Font(name="Calibri", size=10, bold=True, color="404040"),
                   alignment=Alignment(horizontal="right", vertical="center")),
        NamedStyle("lc_field", font=Font(name="Calibri", size=10),
                   border=Border(bottom=Side(style="thin", color="808080")),
                   alignment=Alignment(horizontal="left", vertical="center")),
        NamedStyle("lc_header", font=Font(name="Calibri", size=10, bold=True, color=ACCENT),
                   fill=PatternFill("solid", fgColor=HEADER_FILL),
                   border=Border(top=_thin, bottom=_thin, left=_thin, right=_thin),
                   alignment=Alignment(horizontal="center", vertical="center", wrap_text=True)),
        NamedStyle("lc_text", font=Font(name="Calibri", size=10), border=Border(bottom=_hair),
                   alignment=Alignment(horizontal="left", vertical="center")),
        NamedStyle("lc_number", font=Font(name="Calibri", size=10), border=Border(bottom=_hair),
                   alignment=Alignment(horizontal="right", vertical="center")),
        NamedStyle("lc_note", font=Font(name="Calibri", size=9, italic=True, color="595959"),
                   alignment=Alignment(horizontal="left", vertical="top")),
    ]


#: Named styles the writer uses; a template may define any of them to restyle the tables.
STYLE_NAMES = tuple(s.name for s in _styles())


def ensure_styles(wb: Workbook) -> None:
    """Add the built-in named styles the workbook (template) does not define itself."""
    have = set(wb.style_names)
    for style in _styles():
        if style.name not in have:
            wb.add_named_style(style)


# ------------------------------------------------------------------------- default template
def build_default_template() -> Workbook:
    """The default design-sheet template: sheet "Summary" with the title block (rows 1-6)."""
    wb = Workbook()
    ws = wb.active
    ws.title = "Summary"
    ensure_styles(wb)
    ws["A1"] = "linecheck: conductor reactions on the tower, design sheet"
    ws["A1"].style = "lc_title"
    ws.row_dimensions[1].height = 22
    # (name, row, label column, first and last column of the (merged) field)
    layout = [
        ("project", 2, "A", "B", "G"), ("engineer", 2, "I", "J", "N"),
        ("line", 3, "A", "B", "G"), ("checked_by", 3, "I", "J", "N"),
        ("section", 4, "A", "B", "G"), ("date", 4, "I", "J", "N"),
        ("revision", 5, "A", "B", "G"),
        ("units_note", 6, "A", "B", "T"),
    ]
    for name, row, lab, first, last in layout:
        ws[f"{lab}{row}"] = TITLE_LABELS[name] + ":"
        ws[f"{lab}{row}"].style = "lc_label"
        for col in range(ws[f"{first}{row}"].column, ws[f"{last}{row}"].column + 1):
            ws.cell(row=row, column=col).style = "lc_field"
        if first != last:
            ws.merge_cells(f"{first}{row}:{last}{row}")
        ref = f"Summary!${first}${row}" if first == last else f"Summary!${first}${row}:${last}${row}"
        wb.defined_names[name] = DefinedName(name, attr_text=ref)
    for col, width in (("A", 16), ("I", 9)):
        ws.column_dimensions[col].width = width
    ws["B6"].style = "lc_note"
    wb.defined_names[SUMMARY_ANCHOR] = DefinedName(SUMMARY_ANCHOR, attr_text="Summary!$A$8")
    ws.sheet_view.showGridLines = False
    from .cells import page_setup  # one page layout for the template and the written sheets

    page_setup(ws, None)
    wb.properties.title = "linecheck design sheet"
    wb.properties.creator = "linecheck"
    return wb


# ------------------------------------------------------------------------- loading / filling
def load_template(path: str | Path | None) -> Workbook:
    """Open ``path`` (or the default template) and check its defined names.

    Raises :class:`CaseError` naming the file and what is expected.
    """
    if path is None:
        if DEFAULT_TEMPLATE.is_file():
            return load_template(DEFAULT_TEMPLATE)
        return build_default_template()
    p = Path(path)
    if not p.exists():
        raise CaseError("template file not found (expected an .xlsx workbook)", file=str(p))
    if p.is_dir():
        raise CaseError("template path is a directory, expected an .xlsx workbook", file=str(p))
    if p.suffix.lower() not in (".xlsx", ".xltx", ".xlsm", ".xltm"):
        raise CaseError(f"template must be an Excel workbook (.xlsx or .xltx), got '{p.suffix}'", file=str(p))
    try:
        wb = load_workbook(p)
    except (zipfile.BadZipFile, KeyError, ValueError, OSError) as exc:
        raise CaseError(f"cannot read template ({type(exc).__name__}: {exc}); expected an .xlsx workbook",
                        file=str(p)) from None
    wb.template = False  # an .xltx template becomes a normal workbook
    missing = [n for n in TITLE_NAMES if _destination(wb, n) is None]
    if missing:
        raise CaseError(
            "template lacks the defined name(s) " + ", ".join(missing)
            + " (each must name one cell on a sheet; required: " + ", ".join(TITLE_NAMES) + ")",
            file=str(p))
    return wb


def check_template(path: str | Path | None) -> None:
    """Validate a template before a long run (raises :class:`CaseError`)."""
    if path is not None:
        load_template(path)


def _destination(wb: Workbook, name: str) -> tuple[Worksheet, str] | None:
    """Sheet and top-left cell of defined name ``name`` (workbook or sheet scope)."""
    dn = wb.defined_names.get(name)
    scoped = None
    if dn is None:
        for ws in wb.worksheets:
            if name in ws.defined_names:
                dn, scoped = ws.defined_names[name], ws
                break
    if dn is None:
        return None
    try:
        dests = list(dn.destinations)
    except Exception:
        return None
    if not dests:
        return None
    sheet, ref = dests[0]
    if sheet is None and scoped is not None:
        sheet = scoped.title
    if sheet not in wb.sheetnames:
        return None
    cell = ref.replace("$", "").split(":")[0]
    return wb[sheet], cell


def destination(wb: Workbook, name: str) -> tuple[Worksheet, str] | None:
    """Public form of :func:`_destination`."""
    return _destination(wb, name)


def title_values(title: dict[str, Any] | None) -> dict[str, Any]:
    """Title-block values: defaults (date today, units note) overridden by ``title``."""
    values: dict[str, Any] = {n: "" for n in TITLE_NAMES}
    values["date"] = _dt.date.today()
    values["units_note"] = DEFAULT_UNITS_NOTE
    for key, val in (title or {}).items():
        if key not in TITLE_NAMES:
            raise CaseError(f"unknown title field '{key}': expected one of " + ", ".join(TITLE_NAMES), key="--title")
        values[key] = val
    return values


def fill_title(wb: Workbook, values: dict[str, Any]) -> None:
    """Write the title-block values into the cells their defined names point to."""
    for name in TITLE_NAMES:
        dest = _destination(wb, name)
        if dest is None:
            continue
        ws, cell = dest
        value = values.get(name, "")
        set_value(ws[cell], value)  # user text: stored as a text, never a formula
        if isinstance(value, (_dt.date, _dt.datetime)):
            ws[cell].number_format = "yyyy-mm-dd"
