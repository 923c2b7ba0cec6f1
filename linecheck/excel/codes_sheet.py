"""The "Codes" sheet: design-code conductor wind loads beside linecheck's peaks.

Reads the typed ``codes`` block of each :class:`~linecheck.io.document.RunDocument`;
it computes nothing itself.
"""

from __future__ import annotations

from openpyxl.worksheet.worksheet import Worksheet

from ..core.codes import CODES_COMPARED, CODES_PEAK
from ..io.document import RunDocument
from .cells import KN3, RATIO, Cursor, kn, page_setup

COLUMNS = (("Case", 18), ("Code", 11), ("Edition", 30), ("Verified", 9), ("Tower", 6), ("Reaction", 9),
           ("Wind load\n(kN)", 11), ("Angle load\n(kN)", 11), ("Code load\n(kN)", 11), ("linecheck peak\n(kN)", 13),
           ("Ratio", 8), ("Verdict", 26), ("Note", 60))


def write_codes(ws: Worksheet, docs: list[RunDocument], like: Worksheet | None = None) -> int:
    """Fill ``ws`` with one row per case, code, tower and reaction; returns the rows written."""
    from openpyxl.utils import get_column_letter

    cur = Cursor(ws, 1)
    cur.put(1, 1, "Design codes: transverse load (conductor wind load + angle load) vs linecheck's peak",
            "lc_section")
    cur.row = 3
    cur.header([c for c, _ in COLUMNS])
    for k, (_, width) in enumerate(COLUMNS):
        ws.column_dimensions[get_column_letter(k + 1)].width = width
    ws.row_dimensions[3].height = 30
    n = 0
    for doc in docs:
        for code, c in (doc.codes or {}).items():
            for t in c.towers:
                for r, v in t.reactions.items():
                    row = cur.row
                    cur.put(row, 1, doc.case, "lc_text")
                    cur.put(row, 2, code, "lc_text")
                    cur.put(row, 3, c.edition, "lc_text")
                    cur.put(row, 4, "yes" if c.verified else "no", "lc_text")
                    cur.put(row, 5, t.index)
                    cur.put(row, 6, r, "lc_text")
                    cur.put(row, 7, kn(v.wind_load), fmt=KN3)
                    cur.put(row, 8, kn(v.angle_load), fmt=KN3)
                    cur.put(row, 9, kn(v.code_load), fmt=KN3)
                    cur.put(row, 10, kn(v.linecheck_peak), fmt=KN3)
                    cur.put(row, 11, v.ratio, fmt=RATIO)
                    cur.put(row, 12, v.verdict, "lc_text")
                    cur.put(row, 13, c.note, "lc_note")
                    cur.row += 1
                    n += 1
    cur.row += 1
    cur.note(f"{CODES_COMPARED}.")
    cur.note(f"linecheck peak: {CODES_PEAK}; "
             "ratio = linecheck peak / code load. Unverified codes are shown, not judged (docs/codes.md).")
    ws.freeze_panes = "A4"
    page_setup(ws, like)
    return n
