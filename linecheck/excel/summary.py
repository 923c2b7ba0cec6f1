"""The "Summary" (paper Table 5 layout) and "Peaks" (Fig. 13) sheets."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from openpyxl.chart import BarChart, Reference
from openpyxl.formatting.rule import CellIsRule
from openpyxl.styles import Font, PatternFill
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.worksheet import Worksheet

from ..io.display import flag_state
from ..io.document import STAT_BY_NAME, FailedRun, RunDocument
from . import template as tpl
from .cells import (
    FLAG_NOTE,
    GF_UNDEFINED,
    SUMMARY_IDS,
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
def write_summary(ws: Worksheet, docs: list[RunDocument | FailedRun], names: list[str | None], threshold: float,
                  top: int, left: int, summary_reactions: Sequence[str]) -> None:
    """The Table 5 table from (top, left): one row per case and reaction, flags, notes, print setup."""
    with_std = any(d.realizations > 1 for d in docs if isinstance(d, RunDocument))
    cols: list[tuple[str, Any, int]] = []  # (header, (statistic, "mean" | "std"), width)
    for label, width in SUMMARY_IDS:
        cols.append((label, None, width))
    for name in SUMMARY_STATS:
        stat = STAT_BY_NAME[name]
        cols.append((stat.header(), (stat, "mean"), 9))
        if with_std and stat.varies:
            cols.append(("±", (stat, "std"), 7))
    cols.append((SANITY_HEADER, None, 14))
    cols.append(("Note", None, 44))
    cur = Cursor(ws, top)
    for k, (label, _, width) in enumerate(cols):
        cur.put(top, left + k, label, "lc_header")
        letter = get_column_letter(left + k)
        current = ws.column_dimensions[letter].width
        ws.column_dimensions[letter].width = max(width, current if current and current != 13 else 0)
    ws.row_dimensions[top].height = 30
    row = top + 1
    cont_r_col = None
    band = PatternFill("solid", fgColor=tpl.BAND_FILL)
    for n_doc, doc in enumerate(docs):
        failed = isinstance(doc, FailedRun)
        reactions = ("—",) if failed else summary_reactions
        for r in reactions:
            if isinstance(doc, FailedRun):
                idvals = [doc.case, "", None, None, None, None, None, None]
            else:
                idvals = [doc.case, wind_label(doc), doc.spans, doc.span_length, doc.v_ref,
                          doc.tower_of_interest, doc.realizations, r]
            c = 0
            for k, v in enumerate(idvals):
                cell = cur.put(row, left + c, v, "lc_text" if k in (0, 1, 7) else "lc_number")
                if k == 3 or k == 4:
                    cell.number_format = "0.#"
                if k in (2, 5, 6, 7):
                    align(cell, horizontal="center")
                if k == 0 and not failed:
                    link(cell, names[n_doc])
                c += 1
            note = ""
            for _label, spec, _ in cols[len(SUMMARY_IDS):-2]:
                stat, which = spec
                if failed:
                    cur.put(row, left + c, None)
                else:
                    entry = doc.reactions[r][stat.name]
                    if which == "std":
                        value = stat_cell(stat, entry.std) if doc.realizations > 1 and entry.std is not None else None
                    else:
                        value = stat_cell(stat, entry.mean)
                    cur.put(row, left + c, value, "lc_number", excel_format(stat, summary=True))
                    if stat.name == "Cont_R" and which == "mean":
                        cont_r_col = left + c
                        state = flag_state(doc, r, threshold)  # issue 18: on the 95 % interval
                        if state == "recommended":
                            note = FLAG_NOTE
                        elif state == "inconclusive":
                            note = INCONCLUSIVE_NOTE
                c += 1
            check, check_bad = ("", False) if failed else sanity_text(doc)
            ccell = cur.put(row, left + c, check, "lc_text")
            align(ccell, horizontal="center", wrap_text=True)
            if check_bad:
                ccell.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
                ccell.fill = PatternFill("solid", fgColor=tpl.FLAG_FILL)
            c += 1
            if isinstance(doc, FailedRun):
                note = f"FAILED: {doc.error}"
            ncell = cur.put(row, left + c, note, "lc_text")
            align(ncell, indent=1)
            if failed:
                ncell.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
                align(ncell, wrap_text=True)
            elif note:
                ncell.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
            if n_doc % 2 == 1:
                for k in range(len(cols)):
                    if not (k == len(cols) - 2 and check_bad):
                        ws.cell(row=row, column=left + k).fill = band
            row += 1
    last = row - 1
    right = left + len(cols) - 1
    if cont_r_col is not None and last > top:
        letter = get_column_letter(cont_r_col)
        ws.conditional_formatting.add(
            f"{letter}{top + 1}:{letter}{last}",
            CellIsRule(operator="greaterThan", formula=[repr(float(threshold))],
                       fill=PatternFill("solid", fgColor=tpl.FLAG_FILL, bgColor=tpl.FLAG_FILL),
                       font=Font(bold=True, color=tpl.FLAG_FONT)))
    cur.row = last + 2
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
    from .design import HEADERS as DESIGN_HEADERS
    from .design import write_design_block  # issue 18: design values, intervals, flag states, how to read

    cur.row = write_design_block(ws, docs, cur.row + 1, left)
    ws.auto_filter.ref = f"{get_column_letter(left)}{top}:{get_column_letter(right)}{last}"
    ws.freeze_panes = ws.cell(row=top + 1, column=left + 1)
    ws.print_title_rows = f"{top}:{top}"
    right = max(right, left + len(DESIGN_HEADERS) - 1)  # the print area holds the design block and the notes
    wrap_notes(ws, last + 1, cur.row, right)
    ws.print_area = f"A1:{get_column_letter(right)}{cur.row}"
    ws.sheet_properties.pageSetUpPr.fitToPage = True
    ws.page_setup.fitToWidth = 1
    ws.page_setup.fitToHeight = 0
    if not ws.page_setup.orientation:
        ws.page_setup.orientation = "landscape"


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
    with_std = any(d.realizations > 1 for d in docs)
    norm = STAT_BY_NAME["peak_normalised"]
    nr = len(reactions)
    labels = ["Case", "Wind", "Spans", "L_x\n(m)", "V_ref\n(m/s)", *reactions]
    if with_std:
        labels += [f"± {r}" for r in reactions]
    cur.header(labels)
    ws.row_dimensions[cur.row - 1].height = 30
    widths = [18, 14, 6, 8, 9] + [8] * nr + [7] * nr
    for k, w in enumerate(widths[: len(labels)]):
        ws.column_dimensions[get_column_letter(k + 1)].width = w
    first = cur.row
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
    last = cur.row - 1
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
    ch.width = max(16.0, min(34.0, 1.3 * len(docs) + 8))
    ch.height = 9.0
    anchor_col = len(labels) + 2
    ws.column_dimensions[get_column_letter(anchor_col - 1)].width = 3
    ws.add_chart(ch, f"{get_column_letter(anchor_col)}4")
    ws.freeze_panes = f"B{first}"
    ws.print_title_rows = f"{first - 1}:{first - 1}"
    right_col = anchor_col + int(ch.width / 1.7) + 1
    ws.print_area = f"A1:{get_column_letter(right_col)}{max(last, 4 + int(ch.height / 0.53) + 1)}"
    page_setup(ws, like)
    ws.sheet_view.showGridLines = False


