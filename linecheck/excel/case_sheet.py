"""One sheet per case: inputs, still-air and step-1 states, statistics, spectral check, charts."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from openpyxl.styles import Font, PatternFill
from openpyxl.utils import get_column_letter
from openpyxl.worksheet.worksheet import Worksheet

from ..core.case import SCHEMA
from . import template as tpl
from ..io.display import flag_state, flag_text
from .cells import (
    FLAG_NOTE,
    KN,
    KN3,
    PCT,
    RATIO,
    REACTIONS,
    SEC,
    STAT_INFO,
    SUMMARY_REACTIONS,
    Cursor,
    align,
    cell_value,
    header_text,
    is_num,
    kn,
    link,
    page_setup,
    wind_label,
)
from .charts import CHART_COL, CHART_ROWS, CHART_W, case_charts


def write_case(ws: Worksheet, doc: dict, threshold: float, chart_points: int, summary: Worksheet,
               project: str, flagged: Sequence[str] = SUMMARY_REACTIONS) -> None:
    """Fill ``ws`` with the sheet of one result document (tables in A-H, charts from J)."""
    widths = {"A": 30, "B": 8, "C": 12, "D": 12, "E": 12, "F": 12, "G": 12, "H": 12, "I": 2}
    for col, w in widths.items():
        ws.column_dimensions[col].width = w
    ws.sheet_view.showGridLines = False
    cur = Cursor(ws, 1)
    toi = int(doc["tower_of_interest"])
    n = int(doc.get("realizations") or 1)
    cur.put(1, 1, f"{doc['case']}: reactions at tower {toi}", "lc_title")
    cur.put(2, 1, doc.get("description") or wind_label(doc), "lc_subtitle")
    back = cur.put(3, 1, "← Summary", "lc_text")
    link(back, summary.title)
    info = [f"wind: {wind_label(doc)}"]
    if is_num(doc.get("v_ref")):
        info.append(f"V_ref = {doc['v_ref']:g} m/s")
    info.append(f"{n} realization{'s' if n > 1 else ''}")
    if doc.get("seed") is not None:
        info.append(f"seed {doc['seed']}")
    if is_num(doc.get("duration")):
        info.append(f"record {doc['duration']:g} s")
    if is_num(doc.get("time_step")):
        info.append(f"dt = {doc['time_step']:g} s")
    cur.put(3, 3, ", ".join(info), "lc_subtitle")
    cur.row = 4
    params = doc.get("parameters")
    if isinstance(params, dict):
        _inputs_table(cur, doc, params)
    _still_air_and_step1(cur, doc)
    _stats_table(cur, doc)
    if isinstance(doc.get("models"), dict):
        _models_table(cur, doc)
    contrib_rows = _contributions_table(cur, doc, threshold, flagged)
    _towers_table(cur, doc)
    if isinstance(doc.get("spectral"), dict):
        _spectral(cur, doc)
    elif doc.get("wind") == "synoptic":
        cur.row += 1
        cur.note("Spectral check: not in this result (run with a linecheck version that adds it to the JSON).")
    cur.row += 1
    cur.note("Reactions are wind-induced (still air excluded) unless marked total; "
             "M: step-1 mean, B: background, R: resonant (steps 2-3).")
    last_table_row = cur.row

    # ---- charts (data outside the print area)
    bottom = 2
    charts = case_charts(ws, doc, chart_points, contrib_rows)
    for k, ch in enumerate(charts):
        ws.add_chart(ch, f"{get_column_letter(CHART_COL)}{2 + k * CHART_ROWS}")
        bottom = 2 + (k + 1) * CHART_ROWS
    ws.freeze_panes = "A4"
    right = get_column_letter(CHART_COL + int(CHART_W / 1.75) + 1)
    ws.print_area = f"A1:{right}{max(last_table_row, bottom)}"
    page_setup(ws, summary)
    ws.oddHeader.left.text = header_text(project)
    ws.oddHeader.right.text = header_text(doc["case"])


def _inputs_table(cur: Cursor, doc: dict, params: dict) -> None:
    cur.section("Inputs (case parameters)")
    cur.header(["Key", "Unit", "Value", "", "Description", "", "", ""])
    for section, specs in SCHEMA.items():
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
                value = table.get(spec.name) or doc.get(spec.name)
            else:
                value = table.get(spec.name)
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
    if is_num(doc.get("g_yp_L")):
        cur.put(cur.row, 1, "g*yp Lx (Eq. 17, derived)", "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        cur.put(cur.row, 3, kn(doc["g_yp_L"]), fmt=KN3)
        cur.put(cur.row, 4, None, "lc_text")
        cur.put(cur.row, 5, "normalising force ½ ρ C_d V_ref² D L_x", "lc_note")
        cur.row += 1


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


def _still_air_and_step1(cur: Cursor, doc: dict) -> None:
    still = doc.get("still_air")
    static = doc.get("static")
    toi = int(doc["tower_of_interest"])
    if isinstance(still, dict):
        cur.section(f"Still-air state (tower {toi})")
        cur.header(["Quantity", "Unit", "Value"])
        for r in REACTIONS:
            cur.put(cur.row, 1, f"{r} still air", "lc_text")
            cur.put(cur.row, 2, "kN", "lc_text")
            cur.put(cur.row, 3, kn((still.get("reactions") or {}).get(r)), fmt=KN3)
            cur.row += 1
        for label, key, unit, conv, fmt in (("sag S", "sag", "m", None, "0.00"),
                                            ("nominal tension T0 = W Lx² / 8S", "tension_nominal", "kN", kn, KN3)):
            cur.put(cur.row, 1, label, "lc_text")
            cur.put(cur.row, 2, unit, "lc_text")
            v = still.get(key)
            cur.put(cur.row, 3, conv(v) if conv else v, fmt=fmt)
            cur.row += 1
    if not isinstance(static, dict):
        return
    times = static.get("time") or []
    series = len(times) > 1
    cur.section(f"Step 1: mean state (tower {toi})" + (", extreme over the event" if series else ""))
    cur.header(["Quantity", "Unit", "Value", "at t (s)" if series else ""])
    rw = static.get("reactions_wind") or {}
    for r in REACTIONS:
        v, k = _argmax_abs(rw.get(r) or [])
        cur.put(cur.row, 1, f"{r} mean, wind-induced M" + (" at max |M|" if series else ""), "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        cur.put(cur.row, 3, kn(v), fmt=KN3)
        if series and k is not None:
            cur.put(cur.row, 4, times[k], fmt=SEC)
        cur.row += 1
    disp = static.get("displacement") or {}
    for key in ("dx", "dy", "dz"):
        v, k = _argmax_abs(disp.get(key) or [])
        if v is None:
            continue
        cur.put(cur.row, 1, f"{key} insulator end" + (" at max |d|" if series else ""), "lc_text")
        cur.put(cur.row, 2, "m", "lc_text")
        cur.put(cur.row, 3, v, fmt="0.000")
        if series and k is not None:
            cur.put(cur.row, 4, times[k], fmt=SEC)
        cur.row += 1
    tension = static.get("tension") or []
    if tension and isinstance(tension[0], list):
        t0 = (still or {}).get("tension_nominal") if isinstance(still, dict) else None
        still_h = (still or {}).get("tension") if isinstance(still, dict) else None
        cur.row += 1
        cur.header(["Span tension H", "Unit", "still air", "mean max", "at t (s)" if series else "", "max / T0"])
        arr = np.asarray([[np.nan if v is None else v for v in row] for row in tension], dtype=float)
        for s in range(arr.shape[1]):
            col = arr[:, s]
            k = int(np.nanargmax(col)) if np.isfinite(col).any() else None
            mark = "  (adjacent)" if s + 1 in (toi - 1, toi) else ""
            cur.put(cur.row, 1, f"span {s + 1}{mark}", "lc_text")
            cur.put(cur.row, 2, "kN", "lc_text")
            if isinstance(still_h, list) and s < len(still_h):
                cur.put(cur.row, 3, kn(still_h[s]), fmt=KN3)
            if k is not None:
                cur.put(cur.row, 4, kn(float(col[k])), fmt=KN3)
                if series:
                    cur.put(cur.row, 5, times[k], fmt=SEC)
                if is_num(t0) and t0 > 0:
                    cur.put(cur.row, 6, float(col[k]) / t0, fmt="0.000")
            cur.row += 1


def _stats_table(cur: Cursor, doc: dict) -> None:
    n = int(doc.get("realizations") or 1)
    cur.section(f"Statistics at tower {doc['tower_of_interest']} (mean" + (f" ± std over {n} realizations)" if n > 1
                                                                         else ", 1 realization)"))
    cur.header(["Statistic", "Unit", "Rx", "±", "Ry", "±", "Rz", "±"])
    for stat, (unit, fmt, kind, _meaning) in STAT_INFO.items():
        cur.put(cur.row, 1, stat, "lc_text")
        cur.put(cur.row, 2, unit, "lc_text")
        for k, r in enumerate(REACTIONS):
            entry = (doc["reactions"].get(r) or {}).get(stat)
            if not isinstance(entry, dict):
                continue
            cur.put(cur.row, 3 + 2 * k, cell_value(entry.get("mean"), kind), fmt=fmt)
            std = cell_value(entry.get("std"), "kN" if kind == "kN" else "x") if n > 1 else None
            cur.put(cur.row, 4 + 2 * k, std, fmt=fmt)
        cur.row += 1
    for stat in ("peak_dynamic", "GF_Dy", "Cont_R", "peak_normalised"):
        cur.note(f"{stat}: {STAT_INFO[stat][3]}")


def _models_table(cur: Cursor, doc: dict) -> None:
    """Downburst model spread (issue 15): each model's realization means and the envelope."""
    stats = ("mean_max", "peak_dynamic", "GF_Dy", "peak_normalised")
    cur.section(f"Downburst model spread at tower {doc['tower_of_interest']} (realization means; "
                f"this sheet's other tables: model {doc.get('model', '?')})")
    cur.header(["Model", "Reaction", *stats, "", ""])
    rows = list(doc["models"].items()) + [("envelope", None)]
    for name, blk in rows:
        for r in ("Rx", "Ry"):
            cur.put(cur.row, 1, name if r == "Rx" else "", "lc_text")
            cur.put(cur.row, 2, r, "lc_text")
            for k, stat in enumerate(stats):
                unit, fmt, kind, _meaning = STAT_INFO[stat]
                if blk is None:
                    e = doc["models_envelope"][r][stat]
                    cur.put(cur.row, 3 + k, cell_value(e.get("value"), kind), fmt=fmt)
                else:
                    cur.put(cur.row, 3 + k, cell_value(((blk.get(r) or {}).get(stat) or {}).get("mean"), kind), fmt=fmt)
            cur.row += 1
    env = doc["models_envelope"]
    cur.note("Envelope governed by: " + "; ".join(
        f"{r} {stat} {env[r][stat]['model']}" for r in ("Rx", "Ry") for stat in stats))


def _contributions_table(cur: Cursor, doc: dict, threshold: float,
                         flagged: Sequence[str]) -> tuple[int, int]:
    cur.section("Contributions to the peak (paper Eq. 16, Fig. 12)")
    cur.header(["Reaction", "", "Cont_M", "Cont_BG", "Cont_R", "Note"])
    first = cur.row
    for r in REACTIONS:
        cur.put(cur.row, 1, r, "lc_text")
        cur.put(cur.row, 2, "%", "lc_text")
        for k, stat in enumerate(("Cont_M", "Cont_BG", "Cont_R")):
            v = doc["reactions"][r][stat].get("mean")
            cur.put(cur.row, 3 + k, cell_value(v, "pct"), fmt=PCT)
        state = flag_state(doc, r, threshold) if r in flagged else None  # issue 18: on the 95 % interval
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


def _towers_table(cur: Cursor, doc: dict) -> None:
    towers = doc.get("towers")
    if not isinstance(towers, list) or not towers:
        return
    cur.section("Every tower: dynamic peak and maximum mean reactions (kN)")
    cur.header(["Tower", "", "peak Rx", "peak Ry", "peak Rz", "max|M| Rx", "max|M| Ry", "max|M| Rz"])
    toi = int(doc["tower_of_interest"])
    for t in towers:
        idx = t.get("index")
        mark = " *" if idx == toi else ""
        cur.put(cur.row, 1, f"{idx} {t.get('support', '')}{mark}", "lc_text")
        cur.put(cur.row, 2, "kN", "lc_text")
        block = t.get("reactions") or {}
        for k, r in enumerate(REACTIONS):
            stats = block.get(r) or {}
            cur.put(cur.row, 3 + k, kn((stats.get("peak_dynamic") or {}).get("mean")), fmt=KN)
            cur.put(cur.row, 6 + k, kn((stats.get("mean_max") or {}).get("mean")), fmt=KN)
        cur.row += 1
    cur.note("* tower of interest; peaks are means over the realizations, wind-induced.")


#: Quantities of the spectral block's estimate 1: key -> (unit, format, kind, time-domain statistic).
SPECTRAL_EXACT = {
    "mean": ("kN", KN3, "kN", "mean_max"),
    "rms_background": ("kN", KN3, "kN", "rms_background"),
    "rms_resonant": ("kN", KN3, "kN", "rms_resonant"),
    "rms_fluctuating": ("kN", KN3, "kN", "rms_fluctuating"),
    "peak_quasi_static": ("kN", KN3, "kN", "peak_quasi_static"),
    "peak_dynamic": ("kN", KN3, "kN", "peak_dynamic"),
    "GF_Dy": ("-", RATIO, "gf", "GF_Dy"),
    "GF_QS": ("-", RATIO, "gf", "GF_QS"),
    "Cont_R": ("%", PCT, "pct", "Cont_R"),
    "nu_background": ("Hz", "0.000", "x", None),
    "nu_fluctuating": ("Hz", "0.000", "x", None),
}
SPECTRAL_DAVENPORT = {
    "background_factor": ("-", "0.000", "x"), "resonant_factor": ("-", "0.000", "x"),
    "peak_factor": ("-", "0.00", "x"), "f1_hz": ("Hz", "0.000", "x"), "zeta_a": ("-", "0.000", "x"),
    "GF_Dy": ("-", RATIO, "x"), "GF_QS": ("-", RATIO, "x"), "Cont_R": ("%", PCT, "pct"),
    "GF_ASCE74": ("-", RATIO, "x"),
}


def _spectral(cur: Cursor, doc: dict) -> None:
    """The frequency-domain check of a synoptic run (the JSON's "spectral" block)."""
    sp = doc["spectral"]
    cur.section("Spectral check: frequency domain beside the time domain (synoptic)")
    done = set()
    for key, label, unit in (("duration", "record duration T (peak factor)", "s"),
                             ("n_frequencies", "frequencies in the band", "")):
        if key in sp:
            cur.put(cur.row, 1, label, "lc_text")
            cur.put(cur.row, 2, unit, "lc_text")
            cur.put(cur.row, 3, sp[key], fmt="0.#")
            cur.row += 1
            done.add(key)
    band = sp.get("band_hz")
    if isinstance(band, list) and len(band) == 2:
        cur.put(cur.row, 1, "frequency band", "lc_text")
        cur.put(cur.row, 2, "Hz", "lc_text")
        cur.put(cur.row, 3, band[0], fmt="0.00E+00")
        cur.put(cur.row, 4, band[1], fmt="0.00")
        cur.row += 1
        done.add("band_hz")
    exact = sp.get("exact")
    if isinstance(exact, dict):
        done.add("exact")
        cur.row += 1
        cur.put(cur.row, 1, "Estimate 1: exact linear random vibration (frequency) vs time domain", "lc_label")
        align(cur.ws.cell(row=cur.row, column=1), horizontal="left")
        cur.row += 1
        cur.header(["Quantity", "Unit", "freq. Rx", "freq. Ry", "freq. Rz", "time Rx", "time Ry", "time Rz"])
        for key, (unit, fmt, kind, td) in SPECTRAL_EXACT.items():
            if not any(isinstance(exact.get(r), dict) and key in exact[r] for r in REACTIONS):
                continue
            cur.put(cur.row, 1, key if td is None or td == key else f"{key} (time: {td})", "lc_text")
            cur.put(cur.row, 2, unit, "lc_text")
            for k, r in enumerate(REACTIONS):
                v = (exact.get(r) or {}).get(key)
                cur.put(cur.row, 3 + k, cell_value(v, kind), fmt=fmt)
                if td is not None:
                    tv = ((doc["reactions"].get(r) or {}).get(td) or {}).get("mean")
                    cur.put(cur.row, 6 + k, cell_value(tv, kind), fmt=fmt)
                else:
                    cur.put(cur.row, 6 + k, None)
            cur.row += 1
    dav = sp.get("davenport")
    if isinstance(dav, dict):
        done.add("davenport")
        cur.row += 1
        cur.put(cur.row, 1, f"Estimate 2: closed form (Davenport/Castanheta), {dav.get('reaction', 'Ry')}",
                "lc_label")
        align(cur.ws.cell(row=cur.row, column=1), horizontal="left")
        cur.row += 1
        applicable = dav.get("applicable", True)
        cur.put(cur.row, 1, "applicable", "lc_text")
        cur.put(cur.row, 3, "yes" if applicable else "no", "lc_text")
        cur.put(cur.row, 4, dav.get("note") or "", "lc_note")
        cur.row += 1
        for key, (unit, fmt, kind) in SPECTRAL_DAVENPORT.items():
            if key not in dav:
                continue
            cur.put(cur.row, 1, key, "lc_text")
            cur.put(cur.row, 2, unit, "lc_text")
            v = dav[key]
            cur.put(cur.row, 3, cell_value(v, kind) if is_num(v) else "n/a", "lc_number", fmt)
            cur.row += 1
    na = sp.get("not_applicable")
    if isinstance(na, dict):
        done.add("not_applicable")
        for r, why in na.items():
            cur.note(f"closed form, {r}: not applicable ({why})")
    checks = sp.get("sanity_check")
    if isinstance(checks, list) and checks:
        done.add("sanity_check")
        cur.row += 1
        cur.header(["Sanity check", "Unit", "time", "± std", "frequency", "allowed", "result"])
        for it in checks:
            if not isinstance(it, dict):
                continue
            cur.put(cur.row, 1, f"{it.get('reaction', '')} {it.get('quantity', '')}", "lc_text")
            cur.put(cur.row, 2, "kN", "lc_text")
            for k, key in enumerate(("time_domain", "time_domain_std", "frequency_domain", "allowed_difference")):
                cur.put(cur.row, 3 + k, kn(it.get(key)), fmt=KN3)
            ok = bool(it.get("ok"))
            c = cur.put(cur.row, 7, "ok" if ok else "FLAG", "lc_text")
            align(c, horizontal="center")
            if not ok:
                c.font = Font(name="Calibri", size=10, bold=True, color=tpl.FLAG_FONT)
                c.fill = PatternFill("solid", fgColor=tpl.FLAG_FILL)
            cur.row += 1
        if any(isinstance(it, dict) and not it.get("ok") for it in checks):
            cur.note("FLAG: time and frequency domain differ by more than the sampling error of the realizations "
                     "explains.")
    rest = {k: v for k, v in sp.items() if k not in done}
    if rest:
        cur.row += 1
        cur.note("Other entries of the spectral block (SI units, as in the JSON):")
        _tree(cur, rest, depth=0)


def _scalar_text(v: Any) -> Any:
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return v


def _tree(cur: Cursor, data: dict, depth: int) -> None:
    """Write a nested JSON block: tables for dicts of flat dicts, key/value rows otherwise."""
    scalars = {k: v for k, v in data.items() if not isinstance(v, (dict, list))}
    for k, v in scalars.items():
        cur.put(cur.row, 1, ("  " * depth) + str(k), "lc_text")
        cur.put(cur.row, 3, _scalar_text(v), "lc_number" if is_num(v) else "lc_text", "0.000##")
        cur.row += 1
    for k, v in data.items():
        if isinstance(v, list):
            cur.put(cur.row, 1, ("  " * depth) + str(k), "lc_text")
            if len(v) <= 6 and all(not isinstance(x, (dict, list)) for x in v):
                for j, x in enumerate(v):
                    cur.put(cur.row, 3 + j, _scalar_text(x), "lc_number" if is_num(x) else "lc_text", "0.000##")
            else:
                cur.put(cur.row, 3, f"({len(v)} values, see the JSON)", "lc_note")
            cur.row += 1
    for k, v in data.items():
        if not isinstance(v, dict):
            continue
        flat_children = v and all(isinstance(c, dict) and all(not isinstance(x, (dict, list)) for x in c.values())
                                  for c in v.values())
        if flat_children:
            cols: list[str] = []
            for c in v.values():
                for key in c:
                    if key not in cols:
                        cols.append(key)
            rows = list(v)
            transpose = len(cols) > 6 and len(rows) <= 6
            if transpose:
                cols, rows = rows, cols
            if len(cols) <= 6:
                align(cur.put(cur.row, 1, ("  " * depth) + str(k), "lc_label"), horizontal="left")
                cur.row += 1
                cur.header([""] + [""] + [str(c) for c in cols])
                for rk in rows:
                    cur.put(cur.row, 1, ("  " * depth) + str(rk), "lc_text")
                    for j, ck in enumerate(cols):
                        x = (v.get(ck) or {}).get(rk) if transpose else (v.get(rk) or {}).get(ck)
                        cur.put(cur.row, 3 + j, _scalar_text(x) if not is_num(x) else x,
                                "lc_number" if is_num(x) else "lc_text", "0.000##")
                    cur.row += 1
                continue
        align(cur.put(cur.row, 1, ("  " * depth) + str(k), "lc_label"), horizontal="left")
        cur.row += 1
        _tree(cur, v, depth + 1)


