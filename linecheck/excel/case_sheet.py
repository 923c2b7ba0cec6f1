"""One sheet per case: inputs, still-air and step-1 states, statistics, spectral check, charts."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from openpyxl.styles import Font, PatternFill
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.worksheet import Worksheet

from ..core.case import SCHEMA, Line
from ..io.display import flag_state, flag_text
from ..io.display import kn as to_kn
from ..io.document import SPECTRAL_EXACT, STAT_BY_NAME, STAT_TABLE, RunDocument
from ..io.section import (
    COLUMN_UNITS,
    insulators_known,
    line_from_parameters,
    section_geometry,
    section_summary,
    tower_rows,
)
from . import template as tpl
from .cells import (
    FLAG_NOTE,
    KN,
    KN3,
    PCT,
    REACTIONS,
    SEC,
    SUMMARY_REACTIONS,
    Cursor,
    align,
    excel_format,
    header_text,
    is_num,
    kn,
    link,
    page_setup,
    stat_cell,
    wind_label,
)
from .charts import CHART_COL, CHART_ROWS, CHART_W, case_charts, section_charts
from .wires_sheets import totals_note, wires_section


def write_case(ws: Worksheet, doc: RunDocument, threshold: float, chart_points: int, summary: Worksheet,
               project: str, flagged: Sequence[str] = SUMMARY_REACTIONS,
               wire_sheets: tuple[str, str] | None = None) -> None:
    """Fill ``ws`` with the sheet of one result document (tables in A-H, charts from J);
    ``wire_sheets``: the names of the "Totals" and "Load trees" sheets (a run of several wires)."""
    cur = _sheet_head(ws, doc, summary)
    section = None if doc.has_wires else line_from_parameters(doc.parameters, doc.towers)  # None: equal spans
    contrib_rows = _case_tables(cur, doc, section, threshold, flagged, wire_sheets or ("Totals", "Load trees"))
    last_table_row = cur.row
    bottom = _place_charts(ws, doc, chart_points, contrib_rows, section)
    ws.freeze_panes = "A4"
    right = get_column_letter(CHART_COL + int(CHART_W / 1.75) + 1)
    ws.print_area = f"A1:{right}{max(last_table_row, bottom)}"
    page_setup(ws, summary)
    ws.oddHeader.left.text = header_text(project)
    ws.oddHeader.right.text = header_text(doc.case)


def _sheet_head(ws: Worksheet, doc: RunDocument, summary: Worksheet) -> Cursor:
    """Column widths, the title, subtitle, link back to the Summary and the run's settings (rows 1-3);
    returns the cursor on row 4."""
    widths = {"A": 30, "B": 8, "C": 12, "D": 12, "E": 12, "F": 12, "G": 12, "H": 12, "I": 2}
    for col, w in widths.items():
        ws.column_dimensions[col].width = w
    ws.sheet_view.showGridLines = False
    cur = Cursor(ws, 1)
    n = doc.realizations
    what = f"tower totals of {len(doc.wires)} wires" if doc.has_wires else "reactions"
    cur.put(1, 1, f"{doc.case}: {what} at tower {doc.tower_of_interest}", "lc_title")
    cur.put(2, 1, doc.description or wind_label(doc), "lc_subtitle")
    back = cur.put(3, 1, "← Summary", "lc_text")
    link(back, summary.title)
    info = [f"wind: {wind_label(doc)}", f"V_ref = {doc.v_ref:g} m/s", f"{n} realization{'s' if n > 1 else ''}",
            f"seed {doc.seed}"]
    if is_num(doc.duration):
        info.append(f"record {doc.duration:g} s")
    info.append(f"dt = {doc.time_step:g} s")
    cur.put(3, 3, ", ".join(info), "lc_subtitle")
    cur.row = 4
    return cur


def _case_tables(cur: Cursor, doc: RunDocument, section: Line | None, threshold: float,
                 flagged: Sequence[str], wire_sheets: tuple[str, str]) -> tuple[int, int]:
    """The tables of the sheet in order, ending with the notes; returns the contributions table's rows."""
    if doc.has_wires:
        cur.note(totals_note(doc, wire_sheets))
    if doc.parameters is not None:
        _inputs_table(cur, doc, doc.parameters)
    if doc.has_wires:
        wires_section(cur, doc, wire_sheets)
    elif section is not None:
        _section_table(cur, doc, section)
    elif _is_section_doc(doc):
        cur.row += 1
        cur.note("Section: the tower table is not in this result (the case read it from "
                 f"{doc.parameters['line'].get('towers_file')}); see the case file.")
    _still_air_and_step1(cur, doc)
    _stats_table(cur, doc)
    if doc.models is not None:
        _models_table(cur, doc)
    contrib_rows = _contributions_table(cur, doc, threshold, flagged)
    _towers_table(cur, doc, section)
    _uplift_table(cur, doc, section)
    if doc.spectral is not None:
        _spectral(cur, doc, doc.spectral)
    elif doc.has_wires:
        cur.row += 1
        cur.note("Spectral check: none for a run of several wires (the check is of one wire's linear model).")
    elif doc.wind == "synoptic":
        cur.row += 1
        cur.note("Spectral check: not in this result (run without --no-check to add it).")
    cur.row += 1
    cur.note("Reactions are wind-induced (still air excluded) unless marked total; "
             "M: step-1 mean, B: background, R: resonant (steps 2-3).")
    return contrib_rows


def _place_charts(ws: Worksheet, doc: RunDocument, chart_points: int, contrib_rows: tuple[int, int],
                  section: Line | None) -> int:
    """The charts (data outside the print area) in column J, one under the other; returns the row below them."""
    bottom = 2
    charts = case_charts(ws, doc, chart_points, contrib_rows)
    if section is not None:  # plan and profile first: they describe the sheet's line
        geo, _next = section_charts(ws, section_geometry(section), [r.name for r in tower_rows(section)],
                                    ws.max_column + 2)
        charts = geo + charts
    for k, ch in enumerate(charts):
        ws.add_chart(ch, f"{get_column_letter(CHART_COL)}{2 + k * CHART_ROWS}")
        bottom = 2 + (k + 1) * CHART_ROWS
    return bottom


def _inputs_table(cur: Cursor, doc: RunDocument, params: dict) -> None:
    cur.section("Inputs (case parameters)")
    cur.header(["Key", "Unit", "Value", "", "Description", "", "", ""])
    is_section = _is_section_doc(doc)
    for section, specs in SCHEMA.items():
        if section == "line.towers":  # one row per tower: the Section block
            continue
        if section == "":
            table = params
        elif section == "wind.downburst":
            table = (params.get("wind") or {}).get("downburst")
            if table is None:
                continue
        else:
            table = params.get(section) or {}
        if section:
            align(cur.put(cur.row, 1, f"[{section}]", "lc_label"), horizontal="left")
            cur.row += 1
        for spec in specs:
            if section == "" and spec.name in ("name", "description"):
                value = table.get(spec.name) or getattr(doc, spec.name)
            else:
                value = table.get(spec.name)
            if value is None and is_section and section == "line" and spec.name in _EQUAL_SPAN_KEYS:
                value = "(section: see Section)"
            if value is None and doc.has_wires and section == "line" and spec.name in _WIRE_KEYS:
                value = "(per wire: see Section)"
            if value is None:
                preset = (table or {}).get("preset")
                value = "(from preset)" if preset and spec.name in ("jet_diameter", "distance", "angle") else "(default)"
            elif isinstance(value, list):
                value = _list_text(value)
            elif isinstance(value, bool):
                value = "true" if value else "false"
            cur.put(cur.row, 1, spec.name, "lc_text")
            cur.put(cur.row, 2, spec.unit if spec.unit != "-" else "", "lc_text")
            cur.put(cur.row, 3, value, "lc_number" if is_num(value) else "lc_text", _input_format(value))
            cur.put(cur.row, 4, None, "lc_text")
            cur.put(cur.row, 5, spec.help, "lc_note")
            cur.row += 1
    if is_num(doc.g_yp_L):
        cur.put(cur.row, 1, "g*yp Lx (Eq. 17, derived)", "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        cur.put(cur.row, 3, kn(doc.g_yp_L), fmt=KN3)
        cur.put(cur.row, 4, None, "lc_text")
        cur.put(cur.row, 5, "normalising force ½ ρ C_d V_ref² D L_x", "lc_note")
        cur.row += 1


_EQUAL_SPAN_KEYS = ("spans", "span_length", "sag", "height", "supports")
#: The conductor keys of [line] that each wire of a case with [[wires]] gives instead.
_WIRE_KEYS = ("weight", "diameter", "drag_coefficient", "area", "elastic_modulus", "tension")


def _is_section_doc(doc: RunDocument) -> bool:
    """The result is of a section-form case (towers inline or in a towers_file)."""
    line = (doc.parameters or {}).get("line")
    return isinstance(line, dict) and ("towers" in line or line.get("towers_file") is not None)


def _section_table(cur: Cursor, doc: RunDocument, line: Line) -> None:
    """The Section block: one row per tower, as in the case, plus the span to the next."""
    rows = tower_rows(line)
    src = f", towers from {line.towers_file}" if line.towers_file else ""
    cur.section(f"Section: {len(rows)} towers, {section_summary(line)}, H0 = {to_kn(line.tension):g} kN{src}")
    labels = ["Tower", "station", "ground", "height", "support", "angle", "insulator", "span to next"]
    cur.header(labels)
    keys = ("station", "ground", "height", "support", "angle", "insulator_length", "span")
    cur.header([""] + [f"({COLUMN_UNITS[k]})" if COLUMN_UNITS[k] else "" for k in keys])
    toi = doc.tower_of_interest
    known = insulators_known(doc.parameters, doc.towers)
    for r in rows:
        cur.put(cur.row, 1, f"{r.name}{' *' if r.index == toi else ''}", "lc_text")
        ins = r.insulator_used if known or r.support != "suspension" else "?"
        for k, (v, fmt) in enumerate(((r.station, "0.0"), (r.ground, "0.0"), (r.height, "0.0"), (r.support, None),
                                      (r.angle, "0.0"), (ins, "0.00"), (r.span, "0.0"))):
            cur.put(cur.row, 2 + k, v, "lc_number" if is_num(v) else "lc_text", fmt)
        cur.row += 1
    cur.note(f"* tower of interest ({toi}); clamp elevation = ground + height; insulator: length in force at "
             "suspension towers (line default where not given); span: horizontal length to the next tower.")
    if not known:
        cur.note("?: the insulator lengths of the towers are not in this result (see the case's tower table).")
    cur.note("Charts: plan (clamp points, first span along +x) and profile (clamps, ground and the still-air "
             "conductor) to the right.")


def _list_text(values: list) -> str:
    """``["strain", "suspension", "suspension", "strain"]`` -> ``"strain, suspension ×2, strain"``."""
    out: list[str] = []
    k = 0
    while k < len(values):
        j = k
        while j + 1 < len(values) and values[j + 1] == values[k]:
            j += 1
        text = f"{values[k]:g}" if is_num(values[k]) else str(values[k])
        out.append(text if j == k else f"{text} ×{j - k + 1}")
        k = j + 1
    return ", ".join(out)


def _input_format(v: Any) -> str:
    if is_num(v) and v != 0 and (abs(v) >= 1e6 or abs(v) < 1e-3):
        return "0.00E+00"
    return "General"


def _argmax_abs(values: list) -> tuple[Any, int | None]:
    arr = np.asarray([np.nan if v is None else v for v in values], dtype=float)
    if arr.size == 0 or not np.isfinite(arr).any():
        return None, None
    k = int(np.nanargmax(np.abs(arr)))
    return float(arr[k]), k


def _still_air_and_step1(cur: Cursor, doc: RunDocument) -> None:
    if doc.still_air is not None:
        _still_air_table(cur, doc)
    static = doc.static
    if static is None:
        return
    series = len(static.time) > 1
    cur.section(f"Step 1: mean state (tower {doc.tower_of_interest})" +
                (", extreme over the event" if series else ""))
    cur.header(["Quantity", "Unit", "Value", "at t (s)" if series else ""])
    _step1_extremes(cur, static, series)
    tension = static.tension
    if tension and isinstance(tension[0], list):
        _span_tensions(cur, doc, series)


def _still_air_table(cur: Cursor, doc: RunDocument) -> None:
    """Still-air reactions, sag and nominal tension (H0 at clipping-in for a section)."""
    still = doc.still_air
    cur.section(f"Still-air state (tower {doc.tower_of_interest})")
    cur.header(["Quantity", "Unit", "Value"])
    for r in REACTIONS:
        cur.put(cur.row, 1, f"{r} still air", "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        cur.put(cur.row, 3, kn(still.reactions[r]), fmt=KN3)
        cur.row += 1
    rows = (("sag S", still.sag, "m", "0.00"),
            ("nominal tension T0 = W Lx² / 8S", kn(still.tension_nominal), "kN", KN3))
    if _is_section_doc(doc):  # a section: H0 at clipping-in, the parabolic sag of Eq. 17's L_x
        rows = (("sag W Lx² / 8 H0 (span Lx of Eq. 17)", still.sag, "m", "0.00"),
                ("tension H0 at clipping-in", kn(still.tension_nominal), "kN", KN3))
    for label, v, unit, fmt in rows:
        cur.put(cur.row, 1, label, "lc_text")
        cur.put(cur.row, 2, unit, "lc_text")
        cur.put(cur.row, 3, v, fmt=fmt)
        cur.row += 1


def _step1_extremes(cur: Cursor, static: Any, series: bool) -> None:
    """Step 1's wind-induced mean reactions and insulator-end displacements, largest magnitude
    (and its time over a downburst event)."""
    times = static.time
    for r in REACTIONS:
        v, k = _argmax_abs(static.reactions_wind[r])
        cur.put(cur.row, 1, f"{r} mean, wind-induced M" + (" at max |M|" if series else ""), "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        cur.put(cur.row, 3, kn(v), fmt=KN3)
        if series and k is not None:
            cur.put(cur.row, 4, times[k], fmt=SEC)
        cur.row += 1
    for key in ("dx", "dy", "dz"):
        v, k = _argmax_abs(static.displacement[key])
        if v is None:
            continue
        cur.put(cur.row, 1, f"{key} insulator end" + (" at max |d|" if series else ""), "lc_text")
        cur.put(cur.row, 2, "m", "lc_text")
        cur.put(cur.row, 3, v, fmt="0.000")
        if series and k is not None:
            cur.put(cur.row, 4, times[k], fmt=SEC)
        cur.row += 1


def _span_tensions(cur: Cursor, doc: RunDocument, series: bool) -> None:
    """Per span: still-air tension, the largest mean tension (and when), and its ratio to T0."""
    still, static = doc.still_air, doc.static
    times = static.time
    toi = doc.tower_of_interest
    t0 = still.tension_nominal if still is not None else None
    still_h = still.tension if still is not None else None
    cur.row += 1
    cur.header(["Span tension H", "Unit", "still air", "mean max", "at t (s)" if series else "", "max / T0"])
    arr = np.asarray([[np.nan if v is None else v for v in row] for row in static.tension], dtype=float)
    for s in range(arr.shape[1]):
        col = arr[:, s]
        k = int(np.nanargmax(col)) if np.isfinite(col).any() else None
        mark = "  (adjacent)" if s + 1 in (toi - 1, toi) else ""
        cur.put(cur.row, 1, f"span {s + 1}{mark}", "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        if still_h is not None and s < len(still_h):
            cur.put(cur.row, 3, kn(still_h[s]), fmt=KN3)
        if k is not None:
            cur.put(cur.row, 4, kn(float(col[k])), fmt=KN3)
            if series:
                cur.put(cur.row, 5, times[k], fmt=SEC)
            if is_num(t0) and t0 > 0:
                cur.put(cur.row, 6, float(col[k]) / t0, fmt="0.000")
        cur.row += 1


def _stats_table(cur: Cursor, doc: RunDocument) -> None:
    n = doc.realizations
    cur.section(f"Statistics at tower {doc.tower_of_interest} (mean" + (f" ± std over {n} realizations)" if n > 1
                                                                        else ", 1 realization)"))
    cur.header(["Statistic", "Unit", "Rx", "±", "Ry", "±", "Rz", "±"])
    for st in STAT_TABLE:
        fmt = excel_format(st)
        cur.put(cur.row, 1, st.name, "lc_text")
        cur.put(cur.row, 2, st.display_unit, "lc_text")
        for k, r in enumerate(REACTIONS):
            entry = doc.reactions[r][st.name]
            cur.put(cur.row, 3 + 2 * k, stat_cell(st, entry.mean), fmt=fmt)
            std = stat_cell(st, entry.std) if n > 1 and entry.std is not None else None
            cur.put(cur.row, 4 + 2 * k, std, fmt=fmt)
        cur.row += 1
    for stat in ("peak_dynamic", "GF_Dy", "Cont_R", "peak_normalised"):
        cur.note(f"{stat}: {STAT_BY_NAME[stat].meaning}")


def _models_table(cur: Cursor, doc: RunDocument) -> None:
    """Downburst model spread: each model's realization means and the envelope."""
    stats = [STAT_BY_NAME[k] for k in ("mean_max", "peak_dynamic", "GF_Dy", "peak_normalised")]
    cur.section(f"Downburst model spread at tower {doc.tower_of_interest} (realization means; "
                f"this sheet's other tables: model {doc.model or '?'})")
    cur.header(["Model", "Reaction", *(st.name for st in stats), "", ""])
    env = doc.models_envelope or {}
    rows = list((doc.models or {}).items()) + [("envelope", None)]
    for name, blk in rows:
        for r in ("Rx", "Ry"):
            cur.put(cur.row, 1, name if r == "Rx" else "", "lc_text")
            cur.put(cur.row, 2, r, "lc_text")
            for k, st in enumerate(stats):
                v = env[r][st.name].value if blk is None else blk[r][st.name].mean
                cur.put(cur.row, 3 + k, stat_cell(st, v), fmt=excel_format(st))
            cur.row += 1
    cur.note("Envelope governed by: " + "; ".join(
        f"{r} {st.name} {env[r][st.name].model}" for r in ("Rx", "Ry") for st in stats))


def _contributions_table(cur: Cursor, doc: RunDocument, threshold: float,
                         flagged: Sequence[str]) -> tuple[int, int]:
    cur.section("Contributions to the peak (paper Eq. 16, Fig. 12)")
    cur.header(["Reaction", "", "Cont_M", "Cont_BG", "Cont_R", "Note"])
    first = cur.row
    for r in REACTIONS:
        cur.put(cur.row, 1, r, "lc_text")
        cur.put(cur.row, 2, "%", "lc_text")
        for k, stat in enumerate(("Cont_M", "Cont_BG", "Cont_R")):
            cur.put(cur.row, 3 + k, stat_cell(STAT_BY_NAME[stat], doc.reactions[r][stat].mean), fmt=PCT)
        state = flag_state(doc, r, threshold) if r in flagged else None  # on the 95 % interval
        flag = state is not None
        c = cur.put(cur.row, 6, FLAG_NOTE if state == "recommended" else flag_text(state), "lc_text")
        align(c, indent=1)
        if flag:
            c.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
            cur.ws.cell(row=cur.row, column=5).fill = PatternFill("solid", fgColor=tpl.FLAG_FILL)
        cur.row += 1
    last = cur.row - 1
    if any(r not in flagged for r in REACTIONS):
        others = ", ".join(r for r in REACTIONS if r not in flagged)
        cur.note(f"Flag (Cont_R above {threshold:.0%}) on the summary reactions only; {others}: see the "
                 "statistics, a small wind-induced part beside the conductor weight.")
    return first, last


def _towers_table(cur: Cursor, doc: RunDocument, section: Line | None = None) -> None:
    if not doc.towers:
        return
    names = [r.name for r in tower_rows(section)] if section is not None else []
    if doc.has_wires:
        names = [str((t.section or {}).get("name", "")) for t in doc.towers]
    cur.section("Every tower: dynamic peak and maximum mean reactions (kN)")
    cur.header(["Tower", "", "peak Rx", "peak Ry", "peak Rz", "max|M| Rx", "max|M| Ry", "max|M| Rz"])
    for t in doc.towers:
        mark = " *" if t.index == doc.tower_of_interest else ""
        name = f" {names[t.index - 1]}" if 0 < t.index <= len(names) else ""
        cur.put(cur.row, 1, f"{t.index}{name} {t.support}{mark}", "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        for k, r in enumerate(REACTIONS):
            cur.put(cur.row, 3 + k, kn(t.reactions[r]["peak_dynamic"].mean), fmt=KN)
            cur.put(cur.row, 6 + k, kn(t.reactions[r]["mean_max"].mean), fmt=KN)
        cur.row += 1
    cur.note("* tower of interest; peaks are means over the realizations, wind-induced.")


def _uplift_table(cur: Cursor, doc: RunDocument, section: Line | None = None) -> None:
    """Every suspension tower's uplift (``towers[].uplift``): the vertical margin R_z [kN] and the
    weight span R_z / W [m] in still air and at the mean state of the smallest margin."""
    rows = [t for t in doc.towers if t.uplift is not None]
    if not rows:
        return
    names = [r.name for r in tower_rows(section)] if section is not None else []
    series = doc.wind == "downburst"
    cur.section("Suspension towers: uplift margin (vertical force on the clamp) and weight span")
    cur.header(["Tower", "", "margin still air", "weight span still air", "margin mean", "weight span mean",
                "at t (s)" if series else ""])
    cur.header(["", "", "(kN)", "(m)", "(kN)", "(m)", ""])
    for t in rows:
        u = t.uplift
        name = f" {names[t.index - 1]}" if 0 < t.index <= len(names) else ""
        cur.put(cur.row, 1, f"{t.index}{name}{' *' if t.index == doc.tower_of_interest else ''}", "lc_text")
        cur.put(cur.row, 3, kn(u.still_air.get("margin")), fmt=KN3)
        cur.put(cur.row, 4, u.still_air.get("weight_span"), fmt="0.0")
        cur.put(cur.row, 5, kn(u.margin), fmt=KN3)
        cur.put(cur.row, 6, u.weight_span, fmt="0.0")
        if series and u.time is not None:
            cur.put(cur.row, 7, u.time, fmt=SEC)
        cur.row += 1
    cur.note("margin: the conductor's downward vertical force on the clamp, R_z (mean: the smallest over the "
             "step-1 mean states); negative would lift the insulator (uplift: a run refuses such a case, see "
             "linecheck static). Weight span: R_z / W, the length of conductor whose weight the tower carries.")


#: Davenport closed-form factors: key -> (unit, format); its GF_*/Cont_R use the statistics table.
SPECTRAL_DAVENPORT = {
    "background_factor": ("-", "0.000"), "resonant_factor": ("-", "0.000"), "peak_factor": ("-", "0.00"),
    "f1_hz": ("Hz", "0.000"), "zeta_a": ("-", "0.000"), "GF_Dy": None, "GF_QS": None, "Cont_R": None,
    "GF_ASCE74": ("-", "0.00"),
}


def _spectral(cur: Cursor, doc: RunDocument, sp) -> None:
    """The frequency-domain check of a synoptic run: ``sp``, the document's typed ``spectral`` block."""
    cur.section("Spectral check: frequency domain beside the time domain (synoptic)")
    for label, unit, v in (("record duration T (peak factor)", "s", sp.duration),
                           ("frequencies in the band", "", sp.n_frequencies)):
        cur.put(cur.row, 1, label, "lc_text")
        cur.put(cur.row, 2, unit, "lc_text")
        cur.put(cur.row, 3, v, fmt="0.#")
        cur.row += 1
    cur.put(cur.row, 1, "frequency band", "lc_text")
    cur.put(cur.row, 2, "Hz", "lc_text")
    cur.put(cur.row, 3, sp.band_hz[0], fmt="0.00E+00")
    cur.put(cur.row, 4, sp.band_hz[1], fmt="0.00")
    cur.row += 1
    if sp.window is not None:  # a long line: estimate 1 on a window around the tower of interest
        w = sp.window
        cur.put(cur.row, 1, f"window: {w['spans']} spans from tower {w['first_tower']}; estimated error", "lc_text")
        cur.put(cur.row, 2, "-", "lc_text")
        for c, r in enumerate(REACTIONS):
            cur.put(cur.row, 3 + c, w["estimated_error"][r], fmt="0.00%")
        cur.row += 1
    cur.row += 1
    _spectral_exact(cur, doc, sp)
    _spectral_davenport(cur, sp.davenport, sp.not_applicable)
    _sanity_check(cur, sp.sanity_check or ())


def _spectral_exact(cur: Cursor, doc: RunDocument, sp) -> None:
    """Estimate 1, exact linear random vibration, beside the time-domain statistics [kN, -, %, Hz]."""
    cur.put(cur.row, 1, "Estimate 1: exact linear random vibration (frequency) vs time domain", "lc_label")
    align(cur.ws.cell(row=cur.row, column=1), horizontal="left")
    cur.row += 1
    cur.header(["Quantity", "Unit", "freq. Rx", "freq. Ry", "freq. Rz", "time Rx", "time Ry", "time Rz"])
    for key, td in SPECTRAL_EXACT:
        st = STAT_BY_NAME[td] if td is not None else None
        cur.put(cur.row, 1, key if td is None or td == key else f"{key} (time: {td})", "lc_text")
        cur.put(cur.row, 2, "Hz" if st is None else st.display_unit, "lc_text")
        fmt = "0.000" if st is None else excel_format(st)
        for k, r in enumerate(REACTIONS):
            v = sp.exact[r][key]
            cur.put(cur.row, 3 + k, v if st is None else stat_cell(st, v), fmt=fmt)
            cur.put(cur.row, 6 + k, None if st is None else stat_cell(st, doc.reactions[r][td].mean), fmt=fmt)
        cur.row += 1


def _spectral_davenport(cur: Cursor, dav, not_applicable: dict[str, str]) -> None:
    """Estimate 2, the Davenport closed form, and why it does not apply to the other reactions."""
    cur.row += 1
    cur.put(cur.row, 1, f"Estimate 2: closed form (Davenport/Castanheta), {dav.reaction}", "lc_label")
    align(cur.ws.cell(row=cur.row, column=1), horizontal="left")
    cur.row += 1
    cur.put(cur.row, 1, "applicable", "lc_text")
    cur.put(cur.row, 3, "yes" if dav.applicable else "no", "lc_text")
    cur.put(cur.row, 4, dav.note or "", "lc_note")
    cur.row += 1
    for key, spec in SPECTRAL_DAVENPORT.items():
        st = STAT_BY_NAME[key] if spec is None else None
        unit, fmt = (st.display_unit, excel_format(st)) if st is not None else spec
        v = getattr(dav, key)
        cur.put(cur.row, 1, key, "lc_text")
        cur.put(cur.row, 2, unit, "lc_text")
        cur.put(cur.row, 3, v if is_num(v) else "n/a", "lc_number", fmt)
        cur.row += 1
    for r, why in not_applicable.items():
        cur.note(f"closed form, {r}: not applicable ({why})")


def _sanity_check(cur: Cursor, checks) -> None:
    """The time-vs-frequency sanity check rows [kN]; FLAG marked."""
    if checks:
        cur.row += 1
        cur.header(["Sanity check", "Unit", "time", "± std", "frequency", "allowed", "result"])
        for it in checks:
            cur.put(cur.row, 1, f"{it.reaction} {it.quantity}", "lc_text")
            cur.put(cur.row, 2, "kN", "lc_text")
            for k, v in enumerate((it.time_domain, it.time_domain_std, it.frequency_domain, it.allowed_difference)):
                cur.put(cur.row, 3 + k, kn(v), fmt=KN3)
            c = cur.put(cur.row, 7, "ok" if it.ok else "FLAG", "lc_text")
            align(c, horizontal="center")
            if not it.ok:
                c.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
                c.fill = PatternFill("solid", fgColor=tpl.FLAG_FILL)
            cur.row += 1
        if any(not it.ok for it in checks):
            cur.note("FLAG: time and frequency domain differ by more than the sampling error of the realizations "
                     "explains.")
