"""What every front end shows of a line section: the tower table, a one-line summary
and the plan/profile geometry.  Plain Python + numpy, no UI library; the geometry itself comes
from :class:`~linecheck.core.system.LineSystem` (docs/method.md "Line sections"), never
recomputed here.

The CLI (``check``, ``static``), the TUI (case browser, tower table) and the Excel case sheet
("Section" block) all read these helpers, so the three show the same numbers and words.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.case import TOWER_COLUMNS, Line, case_from_dict
from ..core.errors import CaseError
from ..core.system import LineSystem

#: Columns of the tower table shown by the front ends: the case's tower keys, then the derived
#: horizontal length of the span to the next tower.
TABLE_COLUMNS = (*TOWER_COLUMNS, "span")
#: Unit of every column (display; SI).
COLUMN_UNITS = {"name": "", "station": "m", "ground": "m", "height": "m", "support": "", "angle": "deg",
                "insulator_length": "m", "span": "m"}


@dataclass(frozen=True)
class TowerRow:
    """One row of the tower table [m, deg].

    ``insulator_length``: as given in the case (None: the line's default for a suspension tower,
    none at a strain tower); ``insulator_used``: the length in force at a suspension tower (None at a
    strain tower); ``span``: horizontal length of the span to the next tower (None at the last).
    """

    index: int  # 1-based
    name: str
    station: float
    ground: float
    height: float
    support: str
    angle: float
    insulator_length: float | None
    insulator_used: float | None
    span: float | None


def tower_rows(line: Line) -> list[TowerRow]:
    """The tower table of a section-form line (empty for the equal-span form)."""
    if not line.is_section:
        return []
    towers = line.towers
    rows = []
    for k, t in enumerate(towers):
        span = towers[k + 1].station - t.station if k + 1 < len(towers) else None
        used = (t.insulator_length if t.insulator_length is not None else line.insulator_length) \
            if t.support == "suspension" else None
        rows.append(TowerRow(k + 1, t.name, t.station, t.ground, t.height, t.support, t.angle, t.insulator_length,
                             used, span))
    return rows


def _num(v: float) -> str:
    return f"{v:g}"


def section_summary(line: Line) -> str:
    """One line about the section: ``"12 spans, 255-420 m, 2 angle towers"``.

    Equal horizontal spans read ``"3 spans of 300 m"``; the tower counts say "no angle tower"
    on a straight section.  The equal-span (paper) form keeps its own wording:
    :func:`line_summary`.
    """
    spans = np.diff([t.station for t in line.towers])
    n = spans.size
    lo, hi = float(spans.min()), float(spans.max())
    if lo == hi:
        length = f"{n} span{'s' if n > 1 else ''} of {_num(lo)} m"
    else:
        length = f"{n} spans, {_num(lo)}-{_num(hi)} m"
    angles = sum(1 for t in line.towers if t.angle != 0.0)
    turns = {0: "no angle tower", 1: "1 angle tower"}.get(angles, f"{angles} angle towers")
    return f"{length}, {turns}"


def line_summary(line: Line) -> str:
    """One line about the modelled line in either form: a section's :func:`section_summary`,
    else the paper form's ``"6 spans x 300 m, sag 10 m, height 43 m"``."""
    if line.is_section:
        return section_summary(line)
    n = line.spans
    return (f"{n} span{'s' if n > 1 else ''} x {_num(line.span_length)} m, sag {_num(line.sag)} m, "
            f"height {_num(line.height)} m")


@dataclass(frozen=True)
class SectionGeometry:
    """Still-air geometry of a section for the plan and profile views [m].

    Per tower (n_towers,): ``station``, plan ``x``/``y`` of the clamp (first span along +x),
    clamp elevation ``z`` and ``ground`` elevation.  Per FE node (n_nodes,): ``node_station`` and
    ``node_z``, the clipped-in still-air conductor (:attr:`LineSystem.node_xyz0`).
    """

    station: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    ground: np.ndarray
    node_station: np.ndarray
    node_z: np.ndarray


def section_geometry(line: Line) -> SectionGeometry:
    """Plan and profile of a section-form line, from :class:`LineSystem` (clamp points, ground,
    the still-air conductor)."""
    system = LineSystem(line)
    p = system.clamp_points
    return SectionGeometry(station=system.stations.copy(), x=p[:, 0].copy(), y=p[:, 1].copy(), z=p[:, 2].copy(),
                           ground=system.ground.copy(), node_station=system.node_station.copy(),
                           node_z=system.node_xyz0[:, 2].copy())


def _getter(t: Any):
    """Key reader of one ``towers[]`` entry: a JSON dict, a typed document tower (its section
    metadata in ``t.section``, its support in ``t.support``) or any object with attributes."""
    if isinstance(t, dict):
        return t.get
    sec = getattr(t, "section", None)
    if isinstance(sec, dict):
        return lambda k: sec[k] if k in sec else getattr(t, k, None)
    return lambda k: getattr(t, k, None)


def _finite(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def line_from_parameters(parameters: dict | None, towers: Any = ()) -> Line | None:
    """The section-form :class:`Line` of a result document, or None (equal-span form, or the
    towers are not in the document).

    ``parameters``: the document's case parameters (``case_to_dict``); its ``line.towers`` list
    when the case gave the towers inline.  A case that read them from ``towers_file`` keeps only
    the file name there: then ``towers`` (the document's ``towers[]`` entries: JSON dicts, typed
    towers with their ``section`` metadata, or objects) are used when they carry ``station`` and
    ``height`` (and ``name``, ``ground``, ``angle``, ``support``, ``insulator_length``); without
    ``insulator_length`` a suspension tower takes the line's default (:func:`insulators_known`).  The line is validated
    again (the case loader's rules); a document that does not validate gives None.
    """
    if not isinstance(parameters, dict) or not isinstance(parameters.get("line"), dict):
        return None
    line = dict(parameters["line"])
    if "towers" not in line:
        if line.get("towers_file") is None:
            return None
        rows = []
        for t in towers or ():
            get = _getter(t)
            station, height = get("station"), get("height")
            if not (_finite(station) and _finite(height)):
                return None
            row = {"station": float(station), "height": float(height), "support": get("support")}
            for key in ("name", "ground", "angle", "insulator_length"):
                if get(key) is not None:
                    row[key] = get(key)
            rows.append(row)
        if not rows:
            return None
        line["towers"] = rows
    line.pop("towers_file", None)
    try:
        case = case_from_dict({"name": "section", "line": line, "wind": {"type": "synoptic", "v_ref": 10.0}})
    except CaseError:
        return None
    return case.line if case.line.is_section else None


def insulators_known(parameters: dict | None, towers: Any = ()) -> bool:
    """Whether a result document states every suspension tower's insulator length: always with
    the towers in its case parameters; from ``towers[]`` only when each suspension entry carries
    ``insulator_length`` (else :func:`line_from_parameters` fell back to the line's default)."""
    line = (parameters or {}).get("line") if isinstance(parameters, dict) else None
    if isinstance(line, dict) and "towers" in line:
        return True
    for t in towers or ():
        get = _getter(t)
        if get("support") == "suspension" and get("insulator_length") is None:
            return False
    return True
