"""The line of a case: its geometry checked and built from the validated ``[line]`` keys.

Two forms (docs/case-files.md): the paper's equal-span form (``spans``, ``span_length``, ``sag``,
``height``, ``supports``; :func:`equal_span_line`) and the section form (``tension`` H0 and one
tower per ``[[line.towers]]`` table or ``towers_file`` CSV row; :func:`section_line`), for which
the display keys of the equal-span form are derived.  Cross-checks raise one-line
:class:`~.errors.CaseError` messages naming the key, or the tower and its key, or the CSV row
and column.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .case_model import Line, Tower
from .case_schema import field_spec
from .case_towers import read_towers_csv
from .case_validate import ErrorContext, array_table_line, fmt_value, read_section
from .errors import CaseError

MAX_TOWERS = 201  # 200 spans (the equal-span form's limit)
#: keys of the equal-span form, derived (not given) in the section form
EQUAL_SPAN_KEYS = ("spans", "span_length", "sag", "height", "supports")

def equal_span_line(line_d: dict[str, Any], ctx: ErrorContext) -> Line:
    """The paper's equal-span form: ``spans``, ``span_length``, ``sag``, ``height`` (and ``supports``)."""
    for key in ("spans", "span_length", "sag", "height"):
        if line_d[key] is None:
            raise ctx.error("line", key, f"missing required key: expected {field_spec('line', key).allowed()} "
                            "(or describe the section with [[line.towers]] or towers_file and tension)")
    n_towers = line_d["spans"] + 1
    if line_d["supports"] is None:
        if line_d["spans"] == 1:
            line_d["supports"] = ("strain", "strain")
        else:
            raise ctx.error("line", "supports", f"missing: give {n_towers} entries, one per tower (\"strain\" or \"suspension\")")
    sup = line_d["supports"]
    if len(sup) != n_towers:
        raise ctx.error("line", "supports", f"value {fmt_value(list(sup))} has {len(sup)} entries: expected {n_towers} (spans + 1), one per tower")
    if sup[0] != "strain" or sup[-1] != "strain":
        raise ctx.error("line", "supports", f"value {fmt_value(list(sup))} is not allowed: the end towers must be \"strain\" (a suspension end leaves the section unrestrained along the line)")
    toi = line_d["tower_of_interest"]
    if toi > n_towers:
        raise ctx.error("line", "tower_of_interest", f"value {toi} is out of range: expected an integer from 1 to {n_towers} (number of towers)")
    if line_d["sag"] >= 0.25 * line_d["span_length"]:
        raise ctx.error("line", "sag", f"value {line_d['sag']!r} is out of range: expected a sag below span_length/4 = {0.25 * line_d['span_length']:g} m (shallow-cable method)")
    # physically meaningful geometry: the lowest conductor point of a parabola whose
    # average elevation is `height` is height - sag/3; requiring sag < height keeps it at least
    # 2/3 sag above ground.  Insulator swing lifts the conductor, so no allowance is added.
    if line_d["sag"] >= line_d["height"]:
        raise ctx.error("line", "sag", f"value {line_d['sag']!r} is not allowed with height = {line_d['height']!r}: "
                        "expected sag < height (the conductor would reach the ground)")
    if "suspension" in sup and line_d["insulator_length"] >= line_d["height"]:
        raise ctx.error("line", "insulator_length", f"value {line_d['insulator_length']!r} is not allowed with "
                        f"height = {line_d['height']!r} and suspension towers: expected insulator_length < height")
    return Line(**line_d)


class _TowerCtx(ErrorContext):
    """Error context of one tower: an inline [[line.towers]] table or a CSV row."""

    def __init__(self, ctx: ErrorContext, k: int, csv_file: str | None, row: int | None) -> None:
        super().__init__(ctx.file, ctx.text)
        self.k, self.csv_file, self.row = k, csv_file, row

    def error(self, section: str, key: str | None, message: str) -> CaseError:
        if self.csv_file is not None:
            where = f"row {self.row}" + (f", column {key}" if key else "")
            return CaseError(message, file=self.csv_file, key=where)
        dotted = f"line.towers[{self.k + 1}]" + (f".{key}" if key else "")
        return CaseError(message, file=self.file, key=dotted, line=array_table_line(self.text, "line.towers", self.k, key))


def section_line(line_d: dict[str, Any], towers_data: Any, ctx: ErrorContext, base_dir: Path | None) -> Line:
    """The section form: [[line.towers]] (``towers_data``, as parsed) or towers_file (relative to
    ``base_dir``), and tension H0.  The towers are checked one by one in line order, then every
    span's still-air sag and ground clearance; ``spans``, ``span_length``, ``sag``, ``height`` and
    ``supports`` are derived for display (:func:`derived_line`)."""
    check_section_keys(line_d, towers_data, ctx)
    raw = raw_towers(line_d, towers_data, ctx, base_dir)
    n = len(raw)
    towers: list[Tower] = []
    for k, (d, tctx) in enumerate(raw):
        towers.append(_read_tower(d, tctx, k, n, line_d["insulator_length"], towers[-1] if towers else None))
    check_still_air_spans(towers, line_d["tension"], line_d["weight"], ctx)
    return derived_line(line_d, towers, ctx)


def check_section_keys(line_d: dict[str, Any], towers_data: Any, ctx: ErrorContext, needs_tension: bool = True) -> None:
    """Refuse the equal-span keys, towers both inline and in a file, and (``needs_tension``) a
    missing tension."""
    for key in EQUAL_SPAN_KEYS:
        if line_d[key] is not None:
            raise ctx.error("line", key, f"value {fmt_value(list(line_d[key]) if isinstance(line_d[key], tuple) else line_d[key])} "
                            "is not allowed with a tower table: the towers define the section (remove "
                            f"{key}, or remove [[line.towers]]/towers_file/tension to use the equal-span form)")
    if towers_data is not None and line_d["towers_file"] is not None:
        raise ctx.error("line", "towers_file", f"value {fmt_value(line_d['towers_file'])} is not allowed together with "
                        "[[line.towers]]: give the towers either inline or in the file, not both")
    if needs_tension and line_d["tension"] is None:
        raise ctx.error("line", "tension", f"missing required key for a tower table: expected {field_spec('line', 'tension').allowed()} "
                        "(still-air horizontal tension H0 at clipping-in)")


def raw_towers(line_d: dict[str, Any], towers_data: Any, ctx: ErrorContext, base_dir: Path | None,
               typed: bool = False) -> list[tuple[dict[str, Any], ErrorContext]]:
    """Each tower's raw keys (from the CSV file or the inline tables) with its error context
    (naming ``line.towers[k].key`` or the CSV row and column), 2 to :data:`MAX_TOWERS` of them.
    ``typed``: the towers of a case with ``[[wires]]`` (a CSV needs the ``type`` column, not
    ``height`` and ``support``)."""
    raw = _raw_tower_list(line_d, towers_data, ctx, base_dir, typed)
    n = len(raw)
    if not 2 <= n <= MAX_TOWERS:
        raise ctx.error("line", "towers_file" if line_d["towers_file"] else "towers",
                        f"has {n} towers: expected 2 to {MAX_TOWERS} towers (1 to {MAX_TOWERS - 1} spans)")
    return raw


def _raw_tower_list(line_d: dict[str, Any], towers_data: Any, ctx: ErrorContext, base_dir: Path | None,
                    typed: bool) -> list[tuple[dict[str, Any], ErrorContext]]:
    if line_d["towers_file"] is not None:
        path = Path(line_d["towers_file"])
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.exists():
            raise ctx.error("line", "towers_file", f"value {fmt_value(line_d['towers_file'])}: file {path} does not exist "
                            "(expected a CSV tower table, see docs/case-files.md)")
        return [(d, _TowerCtx(ctx, k, str(path), row_no)) for k, (d, row_no) in enumerate(read_towers_csv(path, typed))]
    if towers_data is None:
        raise ctx.error("line", "towers", "missing: give one [[line.towers]] table per tower or towers_file = \"section.csv\"")
    if not isinstance(towers_data, list) or not all(isinstance(t, dict) for t in towers_data):
        raise ctx.error("line", "towers", f"value {fmt_value(towers_data)} is not allowed: expected [[line.towers]] tables, one per tower")
    return [(d, _TowerCtx(ctx, k, None, None)) for k, d in enumerate(towers_data)]


def _read_tower(d: dict[str, Any], tctx: ErrorContext, k: int, n: int, line_insulator: float,
                previous: Tower | None) -> Tower:
    """Tower ``k`` (0-based) of ``n`` from its raw keys ``d``, checked against its place in the
    line (end tower or not) and the ``previous`` tower; ``line_insulator`` [m] is the line's
    default insulator length."""
    td = read_section(d, "line.towers", tctx)
    if td["type"] is not None:
        raise tctx.error("", "type", f"value {fmt_value(td['type'])} is not allowed without [[wires]] and [[tower_types]]: "
                         "a tower type places the wires of a case that lists them (remove type, or add the wires)")
    if td["name"] is None:
        td["name"] = f"T{k + 1}"
    end = k in (0, n - 1)
    if end and td["support"] != "strain":
        raise tctx.error("", "support", f"value {fmt_value(td['support'])} is not allowed at an end tower: expected \"strain\" "
                         "(a suspension end leaves the section unrestrained along the line)")
    check_end_angle(td, tctx, k, n)
    if td["insulator_length"] is not None and td["support"] != "suspension":
        raise tctx.error("", "insulator_length", f"value {td['insulator_length']!r} is not allowed at a strain tower: "
                         "expected it on suspension towers only (remove it)")
    v = td["insulator_length"] if td["insulator_length"] is not None else line_insulator
    if td["support"] == "suspension" and v >= td["height"]:
        raise tctx.error("", "height", f"value {td['height']!r} is not allowed with insulator length {v!r}: expected "
                         "height > insulator_length (the insulator's top would be below its clamp's ground)")
    check_station(td, tctx, previous.station if previous is not None else None)
    return Tower(**td)


def check_end_angle(td: dict[str, Any], tctx: ErrorContext, k: int, n: int) -> None:
    """No angle at an end tower (tower ``k``, 0-based, of ``n``; validated keys ``td``)."""
    if k in (0, n - 1) and td["angle"] != 0.0:
        raise tctx.error("", "angle", f"value {td['angle']!r} is not allowed at an end tower: expected 0 (the line "
                         "deviates only at interior towers)")


def check_station(td: dict[str, Any], tctx: ErrorContext, previous_station: float | None) -> None:
    """The tower's station [m] beyond the previous tower's (None: the first tower) by a span of
    10 to 3000 m."""
    if previous_station is None:
        return
    if td["station"] <= previous_station:
        raise tctx.error("", "station", f"value {td['station']!r} is not allowed: expected stations increasing along the "
                         f"line (the previous tower is at {previous_station!r} m)")
    span = td["station"] - previous_station
    if not 10.0 <= span <= 3000.0:
        raise tctx.error("", "station", f"value {td['station']!r} gives a span of {span:g} m: expected spans "
                         "from 10 to 3000 m")


def check_still_air_spans(towers: list[Tower], H0: float, W: float, ctx: ErrorContext) -> None:
    """Every span's still-air parabola under tension ``H0`` [N] and weight ``W`` [N/m]: its sag
    below a quarter of the span and its lowest point above the straight ground line."""
    for i in range(len(towers) - 1):
        a, b = towers[i], towers[i + 1]
        L = b.station - a.station
        sag = W * L**2 / (8.0 * H0)  # parabolic mid-span sag (Irvine 1981 Eq. 2.8)
        if sag >= 0.25 * L:
            raise ctx.error("line", "tension", f"value {H0!r} is too low for span {i + 1} ({a.name}-{b.name}, {L:g} m): its "
                            f"sag W L^2/(8 H0) = {sag:.4g} m exceeds a quarter of the span; expected tension > "
                            f"W L/2 = {0.5 * W * L:.6g} N")
        # lowest clearance above the ground line (parabola between the clamps)
        s = np.linspace(0.0, 1.0, 201)
        clear = a.height + (b.height - a.height) * s - 4.0 * sag * s * (1.0 - s)
        if clear.min() <= 0.0:
            raise ctx.error("line", "tension", f"value {H0!r} lets span {i + 1} ({a.name}-{b.name}) reach the ground "
                            f"(lowest still-air clearance {clear.min():.3g} m): expected a higher tension or taller towers")


def derived_line(line_d: dict[str, Any], towers: list[Tower], ctx: ErrorContext) -> Line:
    """The section's :class:`Line`, with the equal-span form's keys derived for display:
    ``span_length`` is Eq. 17's L_x, the mean of the spans adjacent to the tower of interest."""
    n = len(towers)
    toi = line_d["tower_of_interest"]
    if toi > n:
        raise ctx.error("line", "tower_of_interest", f"value {toi} is out of range: expected an integer from 1 to {n} (number of towers)")
    stations = np.array([t.station for t in towers])
    spans = np.diff(stations)
    j = toi - 1
    adj = [spans[i] for i in (j - 1, j) if 0 <= i < n - 1]
    L_x = float(sum(adj) / len(adj))  # Eq. 17's L_x: mean of the adjacent spans
    W, H0 = line_d["weight"], line_d["tension"]
    d = dict(line_d)
    d.update(spans=n - 1, span_length=L_x, sag=W * L_x**2 / (8.0 * H0),
             height=float(np.mean([t.height for t in towers])),
             supports=tuple(t.support for t in towers), towers=tuple(towers))
    return Line(**d)
