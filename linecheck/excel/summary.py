"""The "Summary" (paper Table 5 layout) and "Peaks" (Fig. 13) sheets."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from openpyxl.chart import BarChart, Reference
from openpyxl.formatting.rule import CellIsRule
from openpyxl.styles import Font, PatternFill
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.worksheet import Worksheet

from ..io.display import flag_state
from ..io.document import STAT_BY_NAME, FailedRun, RunDocument, StatDef
from . import template as tpl
from .cells import (
    FLAG_NOTE,
    GF_UNDEFINED,
    SUMMARY_STATS,
    Cursor,
    align,
    excel_format,
    link,
    page_setup,
    stat_cell,
    wind_label,
    wrap_notes,
)
from .charts import chart_title

INCONCLUSIVE_NOTE = "inconclusive: run more realizations"


# --------------------------------------------------------------------------- Summary
@dataclass(frozen=True)
class Column:
    """A Summary column: header, width [characters] and what it holds, by ``name``: an
    identification value (a key of :func:`id_values`), ``"stat"`` (``stat``'s realization
    ``which``, "mean" or "std"), ``"sanity"`` (the time-vs-frequency check) or ``"note"``.
    An identification column is a text or a number, maybe centred, maybe with a number format."""

    header: str
    width: int
    name: str
    stat: StatDef | None = None
    which: str = "mean"
    text: bool = False
    center: bool = False
    fmt: str | None = None


#: The identification columns, left of the statistics (paper Table 5).
ID_COLUMNS: tuple[Column, ...] = (
    Column("Case", 16, "case", text=True),
    Column("Wind", 14, "wind", text=True),
    Column("Spans", 6, "spans", center=True),
    Column("L_x\n(m)", 7, "span_length", fmt="0.#"),
    Column("V_ref\n(m/s)", 7, "v_ref", fmt="0.#"),
    Column("Tower", 6, "tower", center=True),
    Column("n", 5, "realizations", center=True),
    Column("Reaction", 8, "reaction", text=True, center=True),
)


def id_values(doc: RunDocument | FailedRun, reaction: str) -> dict[str, Any]:
    """The identification values of a Summary row by column name (a failed case: its name only)."""
    if isinstance(doc, FailedRun):
        return {"case": doc.case, "wind": ""}
    return {"case": doc.case, "wind": wind_label(doc), "spans": doc.spans, "span_length": doc.span_length,
            "v_ref": doc.v_ref, "tower": doc.tower_of_interest, "realizations": doc.realizations,
            "reaction": reaction}


def summary_columns(docs: list[RunDocument | FailedRun]) -> list[Column]:
    """Every Summary column in order: identification, statistics (each with a ``±`` column when a
    case has several realizations and the statistic varies between them), sanity check, note."""
    with_std = any(d.realizations > 1 for d in docs if isinstance(d, RunDocument))
    cols = list(ID_COLUMNS)
    for name in SUMMARY_STATS:
        stat = STAT_BY_NAME[name]
        cols.append(Column(stat.header(), 9, "stat", stat))
        if with_std and stat.varies:
            cols.append(Column("±", 7, "stat", stat, "std"))
    cols += [Column(SANITY_HEADER, 14, "sanity"), Column("Note", 44, "note")]
    return cols


def _headers(ws: Worksheet, cur: Cursor, cols: list[Column], top: int, left: int) -> None:
    """The header row and the column widths (a width set before, other than the default, may widen one)."""
    for k, col in enumerate(cols):
        cur.put(top, left + k, col.header, "lc_header")
        letter = get_column_letter(left + k)
        current = ws.column_dimensions[letter].width
        ws.column_dimensions[letter].width = max(col.width, current if current and current != 13 else 0)
    ws.row_dimensions[top].height = 30


def _put_id(cur: Cursor, row: int, at: int, col: Column, value: Any, link_to: str | None) -> None:
    cell = cur.put(row, at, value, "lc_text" if col.text else "lc_number")
    if col.fmt is not None:
        cell.number_format = col.fmt
    if col.center:
        align(cell, horizontal="center")
    if col.name == "case" and link_to is not None:
        link(cell, link_to)


def _put_stat(cur: Cursor, row: int, at: int, stat: StatDef, which: str, doc: RunDocument | FailedRun,
              reaction: str) -> None:
    """A statistic's cell (``which``: "mean" or "std" over realizations) [kN, -, or fraction shown
    in %]; empty for a failed case."""
    if isinstance(doc, FailedRun):
        cur.put(row, at, None)
        return
    entry = doc.reactions[reaction][stat.name]
    if which == "std":
        value = stat_cell(stat, entry.std) if doc.realizations > 1 and entry.std is not None else None
    else:
        value = stat_cell(stat, entry.mean)
    cur.put(row, at, value, "lc_number", excel_format(stat, summary=True))


def _put_sanity(cur: Cursor, row: int, at: int, doc: RunDocument | FailedRun) -> bool:
    """The sanity-check cell; whether it is a FLAG (then marked)."""
    check, check_bad = ("", False) if isinstance(doc, FailedRun) else sanity_text(doc)
    cell = cur.put(row, at, check, "lc_text")
    align(cell, horizontal="center", wrap_text=True)
    if check_bad:
        cell.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
        cell.fill = PatternFill("solid", fgColor=tpl.FLAG_FILL)
    return check_bad


def row_note(doc: RunDocument | FailedRun, reaction: str, threshold: float) -> str:
    """The Note of a row: a failed case's error, else the Cont_R flag state (on its 95 % interval)."""
    if isinstance(doc, FailedRun):
        return f"FAILED: {doc.error}"
    state = flag_state(doc, reaction, threshold)
    return FLAG_NOTE if state == "recommended" else INCONCLUSIVE_NOTE if state == "inconclusive" else ""


def _put_note(cur: Cursor, row: int, at: int, note: str, failed: bool) -> None:
    cell = cur.put(row, at, note, "lc_text")
    align(cell, indent=1)
    if failed:
        cell.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
        align(cell, wrap_text=True)
    elif note:
        cell.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)


def _write_row(cur: Cursor, row: int, left: int, cols: list[Column], doc: RunDocument | FailedRun, reaction: str,
               link_to: str | None, threshold: float) -> int | None:
    """One Summary row (a case and a reaction); the column of a FLAG sanity cell, if any."""
    failed = isinstance(doc, FailedRun)
    ids = id_values(doc, reaction)
    flagged = None
    for k, col in enumerate(cols):
        if col.stat is not None:
            _put_stat(cur, row, left + k, col.stat, col.which, doc, reaction)
        elif col.name == "sanity":
            flagged = k if _put_sanity(cur, row, left + k, doc) else None
        elif col.name == "note":
            _put_note(cur, row, left + k, row_note(doc, reaction, threshold), failed)
        else:
            _put_id(cur, row, left + k, col, ids.get(col.name), None if failed else link_to)
    return flagged


def _flag_cont_r(ws: Worksheet, cols: list[Column], top: int, last: int, left: int, threshold: float) -> None:
    """Colour the Cont_R means above ``threshold`` [-] (conditional format)."""
    at = next(k for k, c in enumerate(cols) if c.stat is not None and c.stat.name == "Cont_R" and c.which == "mean")
    letter = get_column_letter(left + at)
    ws.conditional_formatting.add(
        f"{letter}{top + 1}:{letter}{last}",
        CellIsRule(operator="greaterThan", formula=[repr(float(threshold))],
                   fill=PatternFill("solid", fgColor=tpl.FLAG_FILL, bgColor=tpl.FLAG_FILL),
                   font=Font(bold=True, color=tpl.FLAG_FONT)))


def _summary_notes(cur: Cursor, threshold: float, summary_reactions: Sequence[str]) -> None:
    cur.note(f"Note: '{FLAG_NOTE}' where the 95 % interval of Cont_R lies above {threshold:.0%}, "
             f"'{INCONCLUSIVE_NOTE}' where it straddles {threshold:.0%} (none where GF is ** or the reaction is below "
             "5 % of the still-air load); the colour marks a mean Cont_R above it.")
    cur.note(f"Cont_R above {threshold:.0%}: {FLAG_NOTE} (the resonant share of the peak "
             "that a quasi-static analysis misses; paper Sect. 5).")
    cur.note(f"{GF_UNDEFINED} : GF undefined, the mean reaction is zero by symmetry or below 1 % of the "
             "largest mean reaction of the case; peaks and contributions are still given.")
    cur.note(f"{SANITY_HEADER.replace(chr(10), ' ')}: the time-domain statistics beside the frequency-domain "
             "estimate of a synoptic case (sanity check, case sheet \"Spectral check\"); FLAG: they differ by more "
             "than the sampling error explains, usually a lightly damped mode the record does not reach stationarity "
             "for; — : downburst (no check); not run: run without the check (--no-check).")
    cur.note("Values are those of the JSON results: forces N/1000; Cont_* are the JSON fractions shown in %; "
             "± is the standard deviation over the realizations (n).")
    cur.note("Reactions at the tower of interest, wind-induced (still air excluded): Rx along the line, "
             "Ry transverse (wind), Rz vertical" + ("" if "Rz" in summary_reactions else
                                                    " (Rz on the case sheets: its wind-induced part is small beside "
                                                    "the conductor weight)") + ".")


def _print_setup(ws: Worksheet, top: int, left: int, last: int, right: int, bottom: int) -> None:
    """Filter, frozen panes, print titles and area (the design block and notes included), fit to width."""
    from .design import HEADERS as DESIGN_HEADERS

    ws.auto_filter.ref = f"{get_column_letter(left)}{top}:{get_column_letter(right)}{last}"
    ws.freeze_panes = ws.cell(row=top + 1, column=left + 1)
    ws.print_title_rows = f"{top}:{top}"
    right = max(right, left + len(DESIGN_HEADERS) - 1)  # the print area holds the design block and the notes
    wrap_notes(ws, last + 1, bottom, right)
    ws.print_area = f"A1:{get_column_letter(right)}{bottom}"
    ws.sheet_properties.pageSetUpPr.fitToPage = True
    ws.page_setup.fitToWidth = 1
    ws.page_setup.fitToHeight = 0
    if not ws.page_setup.orientation:
        ws.page_setup.orientation = "landscape"


def write_summary(ws: Worksheet, docs: list[RunDocument | FailedRun], names: list[str | None], threshold: float,
                  top: int, left: int, summary_reactions: Sequence[str], notes: Sequence[str] = ()) -> None:
    """The Table 5 table from (top, left): one row per case and reaction, flags, notes (``notes``
    after the table's own: a run of several wires says what its reactions are), the design
    block (design values, intervals, flag states, how to read them), print setup."""
    from .design import write_design_block

    cols = summary_columns(docs)
    cur = Cursor(ws, top)
    _headers(ws, cur, cols, top, left)
    row = top + 1
    band = PatternFill("solid", fgColor=tpl.BAND_FILL)
    for n_doc, doc in enumerate(docs):
        for r in ("—",) if isinstance(doc, FailedRun) else summary_reactions:
            flagged = _write_row(cur, row, left, cols, doc, r, names[n_doc], threshold)
            if n_doc % 2 == 1:
                for k in range(len(cols)):
                    if k != flagged:
                        ws.cell(row=row, column=left + k).fill = band
            row += 1
    last = row - 1
    if any(isinstance(d, RunDocument) for d in docs):
        _flag_cont_r(ws, cols, top, last, left, threshold)
    cur.row = last + 2
    _summary_notes(cur, threshold, summary_reactions)
    for line in notes:
        cur.note(line)
    cur.row = write_design_block(ws, docs, cur.row + 1, left)
    _print_setup(ws, top, left, last, left + len(cols) - 1, cur.row)


#: Summary column of the time-vs-frequency sanity check of a synoptic case.
SANITY_HEADER = "Time vs\nfreq."


def sanity_text(doc: RunDocument) -> tuple[str, bool]:
    """Summary text of a case's time-vs-frequency sanity check and whether it failed.

    ``"ok"``, ``"FLAG: Rz rms_resonant, ..."`` (the quantities that differ), ``"—"`` for a
    downburst (no check), ``"not run"`` for a synoptic result without a spectral block.
    """
    if doc.wind != "synoptic":
        return "—", False
    checks = doc.spectral.sanity_check if doc.spectral is not None else None
    if not checks:
        return "not run", False
    bad = [f"{it.reaction} {it.quantity}" for it in checks if not it.ok]
    if bad:
        return "FLAG: " + ", ".join(bad), True
    return "ok", False


# --------------------------------------------------------------------------- Peaks
def write_peaks(ws: Worksheet, cases: list[tuple[RunDocument, str]], like: Worksheet,
                reactions: Sequence[str]) -> None:
    """Normalised peaks of every case and their bar chart (Fig. 13)."""
    docs = [d for d, _ in cases]
    cur = Cursor(ws, 1)
    cur.put(1, 1, "Normalised peak reactions peak_dynamic / (g*yp Lx) (paper Fig. 13)", "lc_title")
    cur.put(2, 1, "g*yp = ½ ρ C_d V_ref² D (Eq. 17); reactions at the tower of interest; mean over realizations.",
            "lc_subtitle")
    cur.row = 4
    ncols = _peaks_header(cur, docs, reactions)
    first = cur.row
    _peaks_rows(cur, cases, reactions, any(d.realizations > 1 for d in docs))
    last = cur.row - 1
    ch = _peaks_chart(ws, first, last, len(reactions), len(docs))
    anchor_col = ncols + 2
    ws.column_dimensions[get_column_letter(anchor_col - 1)].width = 3
    ws.add_chart(ch, f"{get_column_letter(anchor_col)}4")
    ws.freeze_panes = f"B{first}"
    ws.print_title_rows = f"{first - 1}:{first - 1}"
    right_col = anchor_col + int(ch.width / 1.7) + 1
    ws.print_area = f"A1:{get_column_letter(right_col)}{max(last, 4 + int(ch.height / 0.53) + 1)}"
    page_setup(ws, like)
    ws.sheet_view.showGridLines = False


def _peaks_header(cur: Cursor, docs: list[RunDocument], reactions: Sequence[str]) -> int:
    """The table's header row and column widths; returns the number of columns."""
    ws = cur.ws
    nr = len(reactions)
    labels = ["Case", "Wind", "Spans", "L_x\n(m)", "V_ref\n(m/s)", *reactions]
    if any(d.realizations > 1 for d in docs):
        labels += [f"± {r}" for r in reactions]
    cur.header(labels)
    ws.row_dimensions[cur.row - 1].height = 30
    widths = [18, 14, 6, 8, 9] + [8] * nr + [7] * nr
    for k, w in enumerate(widths[: len(labels)]):
        ws.column_dimensions[get_column_letter(k + 1)].width = w
    return len(labels)


def _peaks_rows(cur: Cursor, cases: list[tuple[RunDocument, str]], reactions: Sequence[str],
                with_std: bool) -> None:
    """One row per case: its link, wind, line and normalised peaks (± std where several realizations)."""
    norm = STAT_BY_NAME["peak_normalised"]
    nr = len(reactions)
    for doc, name in cases:
        r = cur.row
        cell = cur.put(r, 1, doc.case, "lc_text")
        link(cell, name)
        cur.put(r, 2, wind_label(doc), "lc_text")
        cur.put(r, 3, doc.spans)
        cur.put(r, 4, doc.span_length, fmt="0.#")
        cur.put(r, 5, doc.v_ref, fmt="0.#")
        for k, rn in enumerate(reactions):
            e = doc.reactions[rn][norm.name]
            cur.put(r, 6 + k, stat_cell(norm, e.mean), fmt=excel_format(norm))
            if with_std:
                cur.put(r, 6 + nr + k, stat_cell(norm, e.std) if doc.realizations > 1 else None,
                        fmt=excel_format(norm))
        cur.row += 1


def _peaks_chart(ws: Worksheet, first: int, last: int, nr: int, ndocs: int) -> BarChart:
    """Fig. 13: clustered bars of the table's rows ``first``-``last`` (``nr`` reactions)."""
    ch = BarChart()
    ch.type = "col"
    ch.grouping = "clustered"
    ch.title = chart_title("Normalised peak reactions (Fig. 13)")
    ch.y_axis.title = "peak / (g*yp Lx)"
    ch.y_axis.number_format = "0.0"
    ch.x_axis.delete = False
    ch.y_axis.delete = False
    data = Reference(ws, min_col=6, max_col=5 + nr, min_row=first - 1, max_row=last)
    ch.add_data(data, titles_from_data=True)
    ch.set_categories(Reference(ws, min_col=1, min_row=first, max_row=last))
    for s, color in zip(ch.series, ("2E75B6", "C55A11", "7F7F7F")):
        s.graphicalProperties.solidFill = color
        s.graphicalProperties.line.solidFill = color
    ch.legend.position = "b"
    ch.width = max(16.0, min(34.0, 1.3 * ndocs + 8))
    ch.height = 9.0
    return ch
