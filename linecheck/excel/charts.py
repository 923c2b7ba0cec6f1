"""Native Excel charts of a case sheet (paper Figs B1-B12, 7, 12) and their data columns."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from openpyxl.chart import BarChart, Reference, ScatterChart, Series
from openpyxl.chart.text import RichText, Text
from openpyxl.chart.title import Title
from openpyxl.drawing.text import CharacterProperties, Paragraph, ParagraphProperties, RegularTextRun
from openpyxl.worksheet.worksheet import Worksheet

from ..io.display import kn
from .cells import clean_text, is_num, set_value

#: Layout of a case sheet: charts to the right of the tables (columns A-H), data outside the print area.
CHART_COL = 10  # J
DATA_COL = 21   # U
CHART_W, CHART_H, CHART_ROWS = 17.0, 7.4, 15


def chart_indices(columns: list[np.ndarray], max_points: int) -> np.ndarray:
    """Sample indices for charts: first, last and every block's min and max of each column."""
    n = columns[0].size if columns else 0
    if n <= max_points:
        return np.arange(n)
    per_block = 2 * len(columns)
    nb = max(1, max_points // per_block)
    edges = np.linspace(0, n, nb + 1).astype(int)
    keep = [np.array([0, n - 1])]
    stack = np.stack([np.nan_to_num(c, nan=0.0) for c in columns], axis=1)
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        blk = stack[a:b]
        keep.append(a + blk.argmin(axis=0))
        keep.append(a + blk.argmax(axis=0))
    return np.unique(np.concatenate(keep))


def as_array(values: Any) -> np.ndarray:
    """A JSON list (nulls allowed) as a float array (NaN for null)."""
    return np.asarray([np.nan if v is None else v for v in (values or [])], dtype=float)


def _write_column(ws: Worksheet, col: int, row0: int, header: str, values: np.ndarray) -> None:
    set_value(ws.cell(row=row0, column=col), header)
    for i, v in enumerate(values.tolist()):
        ws.cell(row=row0 + 1 + i, column=col, value=v if math.isfinite(v) else None)


def _line_series(ws: Worksheet, xcol: int, ycol: int, row0: int, n: int, color: str, width: int) -> Series:
    x = Reference(ws, min_col=xcol, min_row=row0 + 1, max_row=row0 + n)
    y = Reference(ws, min_col=ycol, min_row=row0, max_row=row0 + n)
    s = Series(y, x, title_from_data=True)
    s.marker.symbol = "none"
    s.smooth = False
    s.graphicalProperties.line.solidFill = color
    s.graphicalProperties.line.width = width
    return s


def chart_title(text: str, size: int = 1100) -> Title:
    """A chart title in a moderate font (openpyxl's default is 18 pt)."""
    cp = CharacterProperties(sz=size, b=True)
    para = Paragraph(pPr=ParagraphProperties(defRPr=cp), r=[RegularTextRun(rPr=cp, t=clean_text(text))])
    return Title(tx=Text(rich=RichText(p=[para])), overlay=False)


def _scatter(title: str, xtitle: str, ytitle: str, yfmt: str = "0") -> ScatterChart:
    ch = ScatterChart()
    ch.title = chart_title(title)
    ch.style = 2
    ch.scatterStyle = "line"
    ch.x_axis.title = xtitle
    ch.y_axis.title = ytitle
    ch.y_axis.number_format = yfmt
    ch.x_axis.number_format = "0"
    ch.x_axis.delete = False
    ch.y_axis.delete = False
    ch.x_axis.majorGridlines = None
    ch.x_axis.tickLblPos = "low"  # time labels below the plot even when the reaction goes negative
    ch.legend.position = "b"
    ch.width, ch.height = CHART_W, CHART_H
    return ch


def case_charts(ws: Worksheet, doc: Any, chart_points: int, contrib_rows: tuple[int, int]) -> list:
    """Charts of a case sheet (histories of Rx and Ry, tension H/T0, contributions); data from column U.

    ``contrib_rows``: first and last row of the sheet's contributions table (reaction in
    column A, Cont_M/Cont_BG/Cont_R in C-E, headers on the row above).
    """
    charts: list = []
    col = DATA_COL
    ws.cell(row=1, column=col, value="Chart data (from the JSON result; time histories thinned keeping "
                                     "each block's extremes unless saved with --full-histories)").style = "lc_note"
    col = _history_charts(ws, doc, chart_points, col, charts)
    col = _tension_chart(ws, doc, col, charts)
    charts.append(_contributions_chart(ws, contrib_rows))
    return charts


def _history_series(doc: Any) -> tuple[np.ndarray, dict[str, dict[str, np.ndarray]]]:
    """The time and, per reaction Rx/Ry with complete components, M, M+B and M+B+R in kN."""
    th = doc.time_histories
    t = as_array(th.time)
    series: dict[str, dict[str, np.ndarray]] = {}
    for r in ("Rx", "Ry"):
        comp = th.series[r]
        m, b, rr = as_array(comp["M"]), as_array(comp["B"]), as_array(comp["R"])
        if m.size == t.size and b.size == t.size and rr.size == t.size:
            series[r] = {"M": kn(m), "M+B": kn(m + b), "M+B+R": kn(m + b + rr)}
    return t, series


def _history_charts(ws: Worksheet, doc: Any, chart_points: int, col: int, charts: list) -> int:
    """Paper Figs B1-B12: M, M+B, M+B+R of Rx and Ry over time; returns the next free data column."""
    th = doc.time_histories
    if th is None or not th.time:
        return col
    t, series = _history_series(doc)
    if not series:
        return col
    full = th.decimated is False
    idx = np.arange(t.size) if full else chart_indices(
        [s[k] for s in series.values() for k in ("M+B+R", "M+B")], chart_points)
    row0 = 3
    _write_column(ws, col, row0, "t (s)", t[idx])
    xcol = col
    col += 1
    real = th.realization
    for r, s in series.items():
        ch = _scatter(f"{r} at tower {doc.tower_of_interest}: M, M+B, M+B+R (realization {real})",
                      "time (s)", f"{r} (kN)", "0.0")
        cols = {}
        for key in ("M", "M+B", "M+B+R"):
            _write_column(ws, col, row0, f"{r} {key} (kN)", s[key][idx])
            cols[key] = col
            col += 1
        for key, color, width in (("M+B+R", "C55A11", 9525), ("M+B", "2E75B6", 9525),
                                  ("M", "000000", 22225)):
            ch.series.append(_line_series(ws, xcol, cols[key], row0, idx.size, color, width))
        if t.size:
            ch.x_axis.scaling.min = float(np.nanmin(t))
            ch.x_axis.scaling.max = float(np.nanmax(t))
        charts.append(ch)
    return col + 1


def _tension_chart(ws: Worksheet, doc: Any, col: int, charts: list) -> int:
    """Fig. 7: running-mean tension / T0 of the spans next to the tower of interest; returns the
    next free data column."""
    static = doc.static
    t0 = doc.still_air.tension_nominal if doc.still_air is not None else None
    if not (static is not None and static.tension and is_num(t0) and t0 > 0):
        return col
    times = as_array(static.time)
    h = np.asarray([[np.nan if v is None else v for v in row] for row in static.tension], dtype=float)
    toi = doc.tower_of_interest
    spans = [s for s in (toi - 1, toi) if 1 <= s <= h.shape[1]]
    if times.size == 1:  # synoptic: constant over the record
        dur = doc.duration if is_num(doc.duration) else 600.0
        times = np.array([0.0, float(dur)])
        h = np.repeat(h, 2, axis=0)
    if not (times.size == h.shape[0] and spans):
        return col
    row0 = 3
    _write_column(ws, col, row0, "t (s)", times)
    xcol = col
    col += 1
    ch = _scatter(f"Running-mean span tension H / T0 (Fig. 7), T0 = {kn(t0):.1f} kN",
                  "time (s)", "H / T0", "0.00")
    for s, color in zip(spans, ("2E75B6", "C55A11")):
        side = "left" if s == toi - 1 else "right"
        _write_column(ws, col, row0, f"span {s} ({side})", h[:, s - 1] / t0)
        ch.series.append(_line_series(ws, xcol, col, row0, times.size, color, 19050))
        col += 1
    ch.x_axis.scaling.min = float(times.min())
    ch.x_axis.scaling.max = float(times.max())
    charts.append(ch)
    return col + 1


def _contributions_chart(ws: Worksheet, contrib_rows: tuple[int, int]) -> BarChart:
    """Fig. 12: contributions, stacked bars from the visible contributions table."""
    first, last = contrib_rows
    bar = BarChart()
    bar.type = "col"
    bar.grouping = "stacked"
    bar.overlap = 100
    bar.title = chart_title("Contributions to the peak reaction (Fig. 12)")
    bar.y_axis.title = "share of peak"
    bar.y_axis.number_format = "0%"
    bar.y_axis.scaling.min = 0.0
    bar.y_axis.scaling.max = 1.0
    bar.x_axis.delete = False
    bar.y_axis.delete = False
    bar.add_data(Reference(ws, min_col=3, max_col=5, min_row=first - 1, max_row=last), titles_from_data=True)
    bar.set_categories(Reference(ws, min_col=1, min_row=first, max_row=last))
    for s, color in zip(bar.series, ("A6A6A6", "2E75B6", "C55A11")):
        s.graphicalProperties.solidFill = color
        s.graphicalProperties.line.solidFill = color
    bar.gapWidth = 80
    bar.legend.position = "b"
    bar.width, bar.height = CHART_W, CHART_H
    return bar


def _marker_series(ws: Worksheet, xcol: int, ycol: int, row0: int, n: int, color: str, symbol: str,
                   line: bool) -> Series:
    s = _line_series(ws, xcol, ycol, row0, n, color, 19050)
    s.marker.symbol = symbol
    s.marker.size = 6
    s.marker.graphicalProperties.solidFill = color
    s.marker.graphicalProperties.line.solidFill = color
    if not line:
        s.graphicalProperties.line.noFill = True
    return s


def section_charts(ws: Worksheet, geom: Any, names: list[str], col: int) -> tuple[list, int]:
    """Plan and profile of a line section from ``geom``
    (:class:`~linecheck.io.section.SectionGeometry`); data written from column ``col``.

    Plan: the still-air clamp points, y against x (first span along +x).  Profile: clamp
    elevation, ground and the still-air conductor (clipped-in catenaries) against station.
    Returns the charts and the next free data column.
    """
    row0 = 3
    n = geom.station.size
    ws.cell(row=row0 - 1, column=col, value="Section geometry (m, still air)").style = "lc_note"
    for k, (header, values) in enumerate((("x (m)", geom.x), ("y (m)", geom.y), ("station (m)", geom.station),
                                          ("clamp z (m)", geom.z), ("ground (m)", geom.ground))):
        _write_column(ws, col + k, row0, header, np.asarray(values, dtype=float))
    set_value(ws.cell(row=row0, column=col + 5), "tower")
    for i, name in enumerate(names):
        set_value(ws.cell(row=row0 + 1 + i, column=col + 5), name)
    _write_column(ws, col + 6, row0, "conductor station (m)", np.asarray(geom.node_station, dtype=float))
    _write_column(ws, col + 7, row0, "conductor z (m)", np.asarray(geom.node_z, dtype=float))

    plan = _scatter("Section plan: clamp points (first span along +x)", "x (m)", "y (m)")
    plan.scatterStyle = "lineMarker"
    plan.series.append(_marker_series(ws, col, col + 1, row0, n, "2E75B6", "circle", line=True))
    plan.legend = None
    profile = _scatter("Section profile: clamps, ground and still-air conductor", "station (m)", "elevation (m)")
    profile.scatterStyle = "lineMarker"
    m = geom.node_station.size
    profile.series.append(_line_series(ws, col + 6, col + 7, row0, m, "C55A11", 12700))
    profile.series.append(_marker_series(ws, col + 2, col + 3, row0, n, "2E75B6", "triangle", line=False))
    profile.series.append(_line_series(ws, col + 2, col + 4, row0, n, "548235", 19050))
    profile.x_axis.scaling.min = float(np.min(geom.station))
    profile.x_axis.scaling.max = float(np.max(geom.station))
    lo = float(min(np.min(geom.ground), np.min(geom.node_z)))
    hi = float(np.max(geom.z))
    pad = 0.05 * (hi - lo) if hi > lo else 1.0
    profile.y_axis.scaling.min = math.floor(lo - pad)
    profile.y_axis.scaling.max = math.ceil(hi + pad)
    return [plan, profile], col + 9
