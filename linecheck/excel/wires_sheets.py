"""The sheets of a run of a case with ``[[wires]]`` (docs/wires.md, docs/excel.md "Runs of several
wires"): "Totals" (every tower's totals Fx ... Mz: the peak with its spread, GF_Dy, Cont_R, the
design values, the sum and the largest of the attachments' peaks and the ratios) and "Load trees"
(one block per tower: its attachments, then per load case every wire's coincident load, vertical,
transverse and longitudinal, with the governing total's value and spread), and the case sheet's
"Section" block of such a run (the wires and the towers with their types).

Reads the typed blocks of :mod:`linecheck.io.wires_blocks` only; computes nothing but the kN of
the JSON's N (N m) and, per load case, the wires' sum of each component.  Every number is a
number cell (kN, kN m, m, the ratios as they are, Cont_R the JSON fraction in a % format)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from openpyxl.styles import Font
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.pagebreak import Break
from openpyxl.worksheet.worksheet import Worksheet

from ..core.tower_totals import LOAD_CASES, TOTALS
from ..io.display import flag_text
from ..io.document import STAT_BY_NAME, RunDocument, TowerRecord
from . import template as tpl
from .cells import KN3, PCT, RATIO, Cursor, align, header_text, is_num, kn, link, page_setup, stat_cell, wrap_notes

#: The load-tree components in the order of the CSV (docs/wires.md "The load-tree CSV"): the
#: JSON's reaction name and the column's label.
TREE_COLUMNS = (("Rz", "Vertical"), ("Ry", "Transverse"), ("Rx", "Longitudinal"))

#: The sign convention of every load tree (the CSV's comment line, said for the sheet).
SIGN_NOTE = ("Sign convention (each tower's own frame, as the CSV of linecheck run --load-trees): vertical downward "
             "positive (a wire's weight is positive), transverse positive toward +y (to the left of the line looking "
             "along it), longitudinal positive toward +x (along the tower's heading, the bisector of its spans). "
             "The loads are each wire's force on the tower at its attachment point (y, z of the tower type).")

#: What a load tree is (docs/wires.md "Load trees").
TREE_NOTE = ("A load tree is every wire's load at one instant: in each sample (a realization, or a peak window) the "
             "instant the load case's governing total is reached (max |Fy|, |Fx|, |Mx|, |Mz|; the least Fz), still "
             "air included; the values are the means over the samples and ± their standard deviation. 'all wires': "
             "the sum of the wires' loads (the tower's forces at that instant).")

#: The columns of the "Totals" sheet: header and width [characters].
TOTALS_COLUMNS = (("Case", 14), ("Tower", 6), ("Name", 10), ("Type", 14), ("Total", 6), ("Unit", 6),
                  ("mean M", 9), ("peak Dy", 9), ("±", 8), ("GF_Dy", 7), ("Cont_R\n(%)", 8),
                  ("design peak\nwind", 10), ("design total\n(still air +\nwind)", 11), ("sum of\nattachment\npeaks", 10),
                  ("largest\nattachment\npeak", 10), ("peak /\nsum", 7), ("peak /\nlargest", 7), ("dynamic analysis", 26))

#: The columns of a "Load trees" block: header and width [characters].
TREE_HEADERS = (("Load case", 18), ("Total", 7), ("Value", 10), ("±", 8), ("Unit", 6), ("Attachment", 12),
                ("Vertical\n(kN)", 10), ("±", 8), ("Transverse\n(kN)", 10), ("±", 8), ("Longitudinal\n(kN)", 11),
                ("±", 8))

#: The attachments' table at the head of a tower's block (the same columns as the trees).
ATTACHMENT_HEADERS = ("Attachment", "Kind", "Support", "y (m)", "z (m)", "Clamp\nheight (m)",
                      "peak Dy\nRx (kN)", "peak Dy\nRy (kN)", "peak Dy\nRz (kN)", "Uplift\nmargin (kN)",
                      "Weight\nspan (m)", "")


def wires_docs(docs: Sequence[tuple[RunDocument, str]]) -> list[tuple[RunDocument, str]]:
    """The (document, case sheet name) pairs of runs of several wires."""
    return [(d, n) for d, n in docs if d.has_wires]


def unit(total: str) -> str:
    """The display unit of a total: kN for a force, kN m for a moment."""
    return "kN m" if total.startswith("M") else "kN"


def tower_name(t: TowerRecord) -> str:
    """A tower's name (its index when the document gives none)."""
    return str((t.section or {}).get("name", t.index))


# --------------------------------------------------------------------------- Totals
def write_totals(ws: Worksheet, docs: Sequence[tuple[RunDocument, str]], like: Worksheet | None,
                 trees_sheet: str = "Load trees") -> None:
    """The "Totals" sheet: one row per case, tower and total (docstring of the module);
    ``trees_sheet``: the name of the "Load trees" sheet, for the notes."""
    cur = Cursor(ws, 1)
    cur.put(1, 1, "Tower totals of the runs of several wires: forces (kN) and moments about the tower's base (kN m)",
            "lc_title")
    cur.put(2, 1, "Every wire's reactions summed at each instant of each realization, so the wires' correlation is "
                  "in the totals' peaks; means over the realizations.", "lc_subtitle")
    top = 4
    for k, (label, width) in enumerate(TOTALS_COLUMNS):
        cur.put(top, 1 + k, label, "lc_header")
        ws.column_dimensions[get_column_letter(1 + k)].width = width
    ws.row_dimensions[top].height = 42
    row = top + 1
    for doc, sheet in docs:
        for t in doc.towers:
            for name in TOTALS:
                _totals_row(cur, row, doc, sheet, t, name)
                row += 1
    last = row - 1
    cur.row = last + 2
    fractiles = ", ".join(f"{p:g}" for p in sorted({d.design_fractile for d, _ in docs}))
    cur.note("* tower of interest. Fx along the line (the tower's heading), Fy transverse (to the line's left), Fz "
             "vertical (down) in kN; Mx, My, Mz the moments about the tower's base (x along the line, y to its left, "
             "z up; Mx = -sum(z Ry + y Rz), My = sum z Rx, Mz = -sum y Rx) in kN m.")
    cur.note("mean M: the largest wind-induced mean; peak Dy: max |M + B + R| of the wind-induced total, ± its "
             f"standard deviation over the realizations; design peak: the Gumbel fractile {fractiles} of the peaks, "
             "design total: the same with still air.")
    cur.note("sum of attachment peaks: each attachment's own peak added per sample, as a design adding each wire's "
             "peak would take; largest: the largest attachment's peak; peak / sum and peak / largest: the total's "
             "mean peak over theirs (below 1 for the sum: what the correlation saves).")
    cur.note("dynamic analysis: 'recommended' where the 95 % interval of Cont_R lies above 10 %, 'inconclusive' "
             f"where it straddles it. Each tower's load trees: sheet '{trees_sheet}'.")
    right = len(TOTALS_COLUMNS)
    wrap_notes(ws, last + 1, cur.row, right)
    ws.freeze_panes = ws.cell(row=top + 1, column=6)
    ws.auto_filter.ref = f"A{top}:{get_column_letter(right)}{last}"
    ws.print_title_rows = f"{top}:{top}"
    ws.print_area = f"A1:{get_column_letter(right)}{cur.row - 1}"
    page_setup(ws, like)
    ws.sheet_view.showGridLines = False


def _totals_row(cur: Cursor, row: int, doc: RunDocument, sheet: str, t: TowerRecord, name: str) -> None:
    """One total of one tower: identification, statistics [kN or kN m], bounds and flag."""
    x = (t.totals or {})[name]
    pk, tot, mean = STAT_BY_NAME["peak_dynamic"], STAT_BY_NAME["peak_dynamic_total"], STAT_BY_NAME["mean_max"]
    gf, cont = STAT_BY_NAME["GF_Dy"], STAT_BY_NAME["Cont_R"]
    n = doc.realizations
    peak = x["peak_dynamic"]
    case = cur.put(row, 1, doc.case, "lc_text")
    link(case, sheet)
    cur.put(row, 2, t.index)
    align(cur.ws.cell(row=row, column=2), horizontal="center")
    cur.put(row, 3, tower_name(t) + (" *" if t.index == doc.tower_of_interest else ""), "lc_text")
    cur.put(row, 4, t.type or "", "lc_text")
    cur.put(row, 5, name, "lc_text")
    cur.put(row, 6, unit(name), "lc_text")
    values = (
        (stat_cell(mean, x["mean_max"].mean), KN3),
        (stat_cell(pk, peak.mean), KN3),
        (stat_cell(pk, peak.std) if n > 1 and peak.std is not None else None, KN3),
        (stat_cell(gf, x["GF_Dy"].mean), RATIO),
        (stat_cell(cont, x["Cont_R"].mean), PCT),
        (kn(peak.gumbel.design) if peak.gumbel else None, KN3),
        (kn(x["peak_dynamic_total"].gumbel.design) if x["peak_dynamic_total"].gumbel else None, KN3),
        (stat_cell(tot, x.peak_sum.mean), KN3),
        (stat_cell(tot, x.peak_largest.mean), KN3),
        (x.peak_to_sum if is_num(x.peak_to_sum) else None, "0.000"),
        (x.peak_to_largest if is_num(x.peak_to_largest) else None, "0.000"),
    )
    for k, (v, fmt) in enumerate(values):
        cur.put(row, 7 + k, v, "lc_number", fmt)
    state = x.dynamic_analysis
    c = cur.put(row, 7 + len(values), flag_text(state), "lc_text")
    if state is not None:
        c.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT if state == "recommended" else "9C5700")


# --------------------------------------------------------------------------- Load trees
def write_load_trees(ws: Worksheet, docs: Sequence[tuple[RunDocument, str]], like: Worksheet | None,
                     project: str = "") -> None:
    """The "Load trees" sheet: the notes, then one block per case and tower (each tower from a new
    printed page), its attachments and its five load cases."""
    cur = Cursor(ws, 1)
    for k, (_, width) in enumerate(TREE_HEADERS):
        ws.column_dimensions[get_column_letter(1 + k)].width = width
    cur.put(1, 1, "Load trees: every wire's load on the tower at the instant each governing total is reached (kN)",
            "lc_title")
    cur.put(2, 1, "Forces in kN, the governing totals' values in kN or kN m; means over the samples, ± their "
                  "standard deviation.", "lc_subtitle")
    cur.row = 4
    cur.note("Load cases: " + "; ".join(f"{case}, the instant of the {'least ' if how == 'min' else 'largest |'}"
                                        f"{total}{'' if how == 'min' else '|'}"
                                        for case, (total, how) in LOAD_CASES.items()) + ".")
    cur.note(SIGN_NOTE)
    cur.note(TREE_NOTE)
    for doc, _ in docs:
        n = doc.realizations * (doc.windows or 1)
        cur.note(f"{doc.case}: {doc.wind}, V_ref {doc.v_ref:g} m/s, means over {n} sample{'s' if n != 1 else ''}"
                 + (" (realizations x peak windows)" if (doc.windows or 1) > 1 else " (realizations)") + ".")
    notes_end = cur.row - 1
    first = True
    for doc, sheet in docs:
        for t in doc.towers:
            cur.row += 1
            if not first:
                ws.row_breaks.append(Break(id=cur.row - 1))
            first = False
            _tree_block(cur, doc, sheet, t)
    right = len(TREE_HEADERS)
    wrap_notes(ws, 4, notes_end, right)
    ws.print_area = f"A1:{get_column_letter(right)}{cur.row - 1}"
    page_setup(ws, like)
    ws.oddHeader.left.text = header_text(project)
    ws.oddHeader.right.text = "Load trees"
    ws.sheet_view.showGridLines = False


def _tree_block(cur: Cursor, doc: RunDocument, sheet: str, t: TowerRecord) -> None:
    """One tower's block: its title, its attachments and its load trees."""
    toi = " (tower of interest)" if t.index == doc.tower_of_interest else ""
    cur.section(f"{doc.case}: tower {t.index} {tower_name(t)}, type {t.type}{toi}", width=len(TREE_HEADERS))
    link(cur.ws.cell(row=cur.row - 1, column=1), sheet)
    cur.ws.cell(row=cur.row - 1, column=1).font = Font(name="Calibri", size=11, bold=True, color="FFFFFF")
    _attachments(cur, doc, t)
    cur.row += 1
    cur.header([h for h, _ in TREE_HEADERS])
    cur.ws.row_dimensions[cur.row - 1].height = 30
    for case, tree in (t.load_trees or {}).items():
        _tree_rows(cur, case, tree)


def _attachments(cur: Cursor, doc: RunDocument, t: TowerRecord) -> None:
    """The tower's attachments: point, support, clamp height, each reaction's mean peak and the
    uplift margin of a suspension attachment (its smallest over the step-1 mean states)."""
    cur.header(list(ATTACHMENT_HEADERS))
    cur.ws.row_dimensions[cur.row - 1].height = 30
    for a in t.attachments or ():
        cur.put(cur.row, 1, a.wire, "lc_text")
        cur.put(cur.row, 2, a.kind, "lc_text")
        cur.put(cur.row, 3, a.support, "lc_text")
        for k, (v, fmt) in enumerate(((a.y, "0.00"), (a.z, "0.00"), (a.height, "0.00"),
                                      *((kn(a.reactions[r]["peak_dynamic"].mean), KN3) for r in ("Rx", "Ry", "Rz")),
                                      (kn(a.uplift.margin) if a.uplift else None, KN3),
                                      (a.uplift.weight_span if a.uplift else None, "0.0"))):
            cur.put(cur.row, 4 + k, v if is_num(v) else None, "lc_number", fmt)
        cur.row += 1


def _tree_rows(cur: Cursor, case: str, tree: Any) -> None:
    """One load case: the governing total's value and spread on its first row, one row per wire
    (each component's mean and standard deviation [kN]), then the wires' sum."""
    first = cur.row
    cur.put(first, 1, case, "lc_text")
    cur.put(first, 2, tree.total, "lc_text")
    cur.put(first, 3, kn(tree.value), "lc_number", KN3)
    cur.put(first, 4, kn(tree.value_std), "lc_number", KN3)
    cur.put(first, 5, unit(tree.total), "lc_text")
    sums = {r: 0.0 for r, _ in TREE_COLUMNS}
    for a in tree.attachments:
        if cur.row != first:
            for col in range(1, 6):
                cur.put(cur.row, col, None, "lc_text")
        cur.put(cur.row, 6, a.wire, "lc_text")
        for k, (r, _) in enumerate(TREE_COLUMNS):
            v = kn(a.load[r])
            cur.put(cur.row, 7 + 2 * k, v, "lc_number", KN3)
            cur.put(cur.row, 8 + 2 * k, kn(a.std[r]), "lc_number", KN3)
            sums[r] = sums[r] + v if is_num(v) and sums[r] is not None else None
        cur.row += 1
    for col in range(1, 6):
        cur.put(cur.row, col, None, "lc_text")
    c = cur.put(cur.row, 6, "all wires", "lc_text")
    c.font = Font(name="Calibri", size=10, italic=True)
    for k, (r, _) in enumerate(TREE_COLUMNS):
        cell = cur.put(cur.row, 7 + 2 * k, sums[r], "lc_number", KN3)
        cell.font = Font(name="Calibri", size=10, italic=True)
        cur.put(cur.row, 8 + 2 * k, None, "lc_number")
    cur.row += 1


# --------------------------------------------------------------------------- the case sheet's Section block
def wires_section(cur: Cursor, doc: RunDocument, sheets: tuple[str, str] = ("Totals", "Load trees")) -> None:
    """The case sheet's Section block of a run of several wires: every wire (its conductor as the
    case gives it, its place in the one turbulence field, its burn-in) and every tower (place
    and type); ``sheets``: the names of the "Totals" and "Load trees" sheets."""
    params = doc.parameters or {}
    given = {w.get("name"): w for w in params.get("wires") or () if isinstance(w, dict)}
    wires = doc.wires or ()
    cur.section(f"Section: {len(doc.towers)} towers, {len(wires)} wires in one correlated wind")
    cur.header(["Wire", "Kind", "Bundle", "Weight W\n(N/m)", "Diameter D\n(m)", "Tension H0\n(kN)",
                "Field y\n(m)", "Field z\n(m)"])
    cur.ws.row_dimensions[cur.row - 1].height = 30
    for w in wires:
        spec = given.get(w.name, {})
        cur.put(cur.row, 1, w.name, "lc_text")
        cur.put(cur.row, 2, w.kind, "lc_text")
        for k, (v, fmt) in enumerate(((w.bundle, "0"), (spec.get("weight"), "0.00"), (spec.get("diameter"), "0.0000"),
                                      (kn(spec.get("tension")), KN3), ((w.field_offset or {}).get("y"), "0.00"),
                                      ((w.field_offset or {}).get("z"), "0.00"))):
            cur.put(cur.row, 3 + k, v if is_num(v) else None, "lc_number", fmt)
        cur.row += 1
    cur.note("Weight, diameter and tension of one sub-conductor (a bundle acts as bundle x each); field y, z: the "
             "wire's place in the one turbulence field (its attachment at the tower of interest).")
    cur.row += 1
    cur.header(["Tower", "Name", "Type", "station\n(m)", "ground\n(m)", "angle\n(deg)", "heading\n(deg)", ""])
    cur.ws.row_dimensions[cur.row - 1].height = 30
    for t in doc.towers:
        s = t.section or {}
        cur.put(cur.row, 1, t.index)
        cur.put(cur.row, 2, tower_name(t) + (" *" if t.index == doc.tower_of_interest else ""), "lc_text")
        cur.put(cur.row, 3, t.type or "", "lc_text")
        for k, key in enumerate(("station", "ground", "angle", "heading")):
            v = s.get(key)
            cur.put(cur.row, 4 + k, v if is_num(v) else None, "lc_number", "0.0")
        cur.row += 1
    cur.note("* tower of interest. Each tower's attachments (where each wire hangs on its type) and load trees: sheet "
             f"'{sheets[1]}'; its totals: sheet '{sheets[0]}'.")


def totals_note(doc: RunDocument, sheets: tuple[str, str] = ("Totals", "Load trees")) -> str:
    """The note of a run of several wires on its case sheet and on the Summary; ``sheets``: the
    names of the "Totals" and "Load trees" sheets."""
    return (f"{doc.case} is a run of {len(doc.wires or ())} wires in one correlated wind: its Rx, Ry, Rz are the tower "
            "totals' forces Fx, Fy, Fz (every wire's reactions summed at each instant; Eq. 17's g*yp Lx the sum of "
            f"the wires'); the moments, each tower's totals and the load trees are on the sheets '{sheets[0]}' and "
            f"'{sheets[1]}'.")
