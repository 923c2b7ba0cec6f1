"""The "Design values" block of the Summary sheet: per case and reaction (R_x, R_y, R_z)
the Gumbel design peak, the total (still air + wind) design reaction, GF_Dy / GF_QS / Cont_R with
their 95 % intervals (two number cells, low and high), the Cont_R flag state, and a "how to read"
block where GF < 1, a negative Cont_BG or a negative Cont_R occurs.  Names, units and meanings come from the one statistics table
(:data:`linecheck.io.document.STAT_TABLE`)."""

from __future__ import annotations

from typing import Any

from openpyxl.styles import Font
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.worksheet import Worksheet

from ..io.display import flag_text, how_to_read
from ..io.document import STAT_BY_NAME, RunDocument, StatValue
from . import template as tpl
from .cells import KN, REACTIONS, Cursor, align, excel_format, is_num, kn, stat_cell

#: Header and column width (characters) of each column; a 95 % interval is two number cells
#: (low, high) in the statistic's own format, so a spreadsheet can compute with them.
HEADERS = (("Case", 16), ("Reaction", 8), ("still air\n(kN)", 9), ("design peak\nwind (kN)", 10),
           ("design total\n(kN)", 10), ("ppcc", 7),
           ("GF_Dy", 8), ("GF_Dy 95 %\nCI low", 11), ("GF_Dy 95 %\nCI high", 11),
           ("GF_QS", 8), ("GF_QS 95 %\nCI low", 11), ("GF_QS 95 %\nCI high", 11),
           ("Cont_R\n(%)", 8), ("Cont_R 95 %\nCI low (%)", 12), ("Cont_R 95 %\nCI high (%)", 12),
           ("dynamic analysis", 9))  # its text runs on into the empty cells to its right (inside the print area)


def _ci(entry: StatValue) -> tuple[float | None, float | None]:
    """The 95 % interval (low, high) of a statistic as numbers, None where absent or null."""
    ci = entry.ci or (None, None)
    if not (is_num(ci[0]) and is_num(ci[1])):
        return None, None
    return float(ci[0]), float(ci[1])


def write_design_block(ws: Worksheet, docs: list, top: int, left: int = 1) -> int:
    """Write the block from row ``top`` (``docs``: RunDocument or FailedRun); returns the next free row."""
    ok = [d for d in docs if isinstance(d, RunDocument)]
    cur = Cursor(ws, top)
    if not ok:
        return top
    _design_header(cur, ok, top, left)
    row = cur.row + 1
    notes: list[str] = []
    for doc in ok:
        row = _design_rows(cur, doc, row, left)
        for line in how_to_read(doc):
            if line not in notes:
                notes.append(line)
    cur.row = row + 1
    _design_notes(cur, notes, left)
    return cur.row


def _design_header(cur: Cursor, ok: list[RunDocument], top: int, left: int) -> None:
    """The block's title (row ``top``) and column headers (the row below, the cursor left on it)."""
    ws = cur.ws
    p = {d.design_fractile for d in ok}
    ptxt = ", ".join(f"{x:g}" for x in sorted(p))
    cur.put(top, left, f"Design values at the tower of interest (Gumbel fractile {ptxt} of the peak; "
                       "95 % confidence intervals of the mean over the realizations)", "lc_text")
    ws.cell(row=top, column=left).font = Font(name="Calibri", size=11, bold=True)
    cur.row = top + 1
    for k, (label, width) in enumerate(HEADERS):
        cur.put(cur.row, left + k, label, "lc_header")
        dim = ws.column_dimensions[get_column_letter(left + k)]
        dim.width = max(width, dim.width or 0)  # wide enough for its header and numbers in print too
    ws.row_dimensions[cur.row].height = 30


def _design_values(doc: RunDocument, r: str, still: dict) -> list[tuple[Any, str | None]]:
    """The cells (value, number format) of one case and reaction, in the order of :data:`HEADERS`."""
    e = doc.reactions[r]
    pk_def, tot_def = STAT_BY_NAME["peak_dynamic"], STAT_BY_NAME["peak_dynamic_total"]
    pk, tot = e[pk_def.name].gumbel, e[tot_def.name].gumbel
    sa = still.get(r)
    vals: list[tuple[Any, str | None]] = [
        (doc.case, None), (r, None),
        (kn(sa), KN),
        (stat_cell(pk_def, pk.design if pk else None), KN),
        (stat_cell(tot_def, tot.design if tot else None), KN),
        (pk.ppcc if pk and is_num(pk.ppcc) else None, "0.000"),
    ]
    for key in ("GF_Dy", "GF_QS", "Cont_R"):
        st = STAT_BY_NAME[key]
        vals.append((stat_cell(st, e[key].mean), excel_format(st)))
        vals.extend((v, excel_format(st)) for v in _ci(e[key]))
    vals.append((flag_text(e.dynamic_analysis), None))
    return vals


def _design_rows(cur: Cursor, doc: RunDocument, row: int, left: int) -> int:
    """One row per reaction of ``doc`` from ``row``, the flag in its colour; returns the next row."""
    ws = cur.ws
    still = doc.still_air.reactions if doc.still_air is not None else {}
    for r in REACTIONS:
        vals = _design_values(doc, r, still)
        state = doc.reactions[r].dynamic_analysis
        for k, (v, fmt) in enumerate(vals):
            style = "lc_text" if k in (0, 1, len(vals) - 1) else "lc_number"
            cell = cur.put(row, left + k, v, style, fmt)
            if k == 1:
                align(cell, horizontal="center")
        if state is not None:
            ws.cell(row=row, column=left + len(vals) - 1).font = Font(
                name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT if state == "recommended" else "9C5700")
        row += 1
    return row


def _design_notes(cur: Cursor, notes: list[str], left: int) -> None:
    """How the design peak and the flag are defined, then the cases' "how to read" lines."""
    cur.note("Design peak: Gumbel (EV-I) fit of the realization peaks by moments, value at the design fractile "
             "([analysis] design_fractile, default 0.5 = median peak); ppcc: probability-plot correlation of the fit. "
             "Design total: the same for still air + wind.")
    cur.note("dynamic analysis: 'recommended' where the 95 % interval of Cont_R lies above 10 %, 'inconclusive: run "
             "more realizations' where it straddles 10 % (linecheck run --until 1%); none where GF is ** or the "
             "wind-induced peak is below 5 % of the still-air reaction.")
    if notes:
        cur.row += 1
        cur.put(cur.row, left, "How to read", "lc_text")
        cur.ws.cell(row=cur.row, column=left).font = Font(name="Calibri", size=11, bold=True)
        cur.row += 1
        for line in notes:
            cur.note(line)
