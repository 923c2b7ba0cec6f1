"""Every wire on the tower: a case's ``[[wires]]`` and ``[[tower_types]]`` checked and built, and
each wire's single-wire case.

A case with ``[[wires]]`` (docs/case-files.md "Every wire on the tower") is a section whose towers
(``[[line.towers]]`` or ``towers_file``) each name a ``type``; each wire gives the conductor keys
of ONE sub-conductor, its ``bundle`` and its tension H0; each tower type gives one attachment per
wire (``y``, ``z`` in the tower frame, ``support``, ``insulator_length``).  :func:`wires_line`
checks them and builds the case's ``line``: the first wire's single-wire line.
:func:`wire_case` gives, for any wire, the single-wire :class:`~.case_model.Case` today's analysis
runs:

* a bundle of n sub-conductors acts as one wire (the sum of n identical sub-conductors side by
  side): weight n W, mass n W/g, area n A, EA = n E A, tension n H0 (so the still-air sag
  W L^2 / 8 H0, Irvine 1981 Eq. 2.8, is the sub-conductor's), drag on the projected width
  n D s with the ``shielding`` factor s (1: each sub-conductor loaded as if alone);
* the wire's tower k is its attachment on tower k's type: the support and insulator length as
  given, the still-air clamp z - v above the tower's ground at a suspension attachment (z is
  the insulator's fixed top T_j = C_j + (0, 0, v_j), docs/method.md "Line sections") and z at
  a strain attachment;
* stations, ground elevations and angles are the towers'.  The single-wire geometry runs along
  the line's centre: the attachment's ``y`` is kept on :class:`~.case_model.Attachment` (for
  the tower's moments), not in the wire's plan geometry.

Every refusal is one :class:`~.errors.CaseError` line naming the file, the key
(``wires[2].name``, ``tower_types[1].attachments[3].wire``, ``line.towers[4].type`` or the CSV
row and column), the value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import difflib
import re
from pathlib import Path
from typing import Any

from .case_geometry import (
    EQUAL_SPAN_KEYS,
    check_end_angle,
    check_section_keys,
    check_station,
    check_still_air_spans,
    derived_line,
    raw_towers,
)
from .case_model import Attachment, Case, Line, Tower, TowerType, Wire
from .case_schema import SCHEMA
from .case_validate import ErrorContext, ItemContext, array_table_line, fmt_value, read_section
from .errors import CaseError

#: [line] keys a case with [[wires]] gives per wire instead
WIRE_LINE_KEYS = ("weight", "diameter", "drag_coefficient", "area", "elastic_modulus", "tension")
#: [[line.towers]] keys a case with [[wires]] gives per attachment (in the tower's type) instead
TYPE_TOWER_KEYS = ("height", "support", "insulator_length")


def wires_line(line_data: dict[str, Any], line_d: dict[str, Any], towers_data: Any, wires_data: Any, types_data: Any,
               ctx: ErrorContext, base_dir: Path | None) -> tuple[Line, tuple[Wire, ...], tuple[TowerType, ...]]:
    """The line, wires and tower types of a case with ``[[wires]]``.

    ``line_data``: the raw ``[line]`` table (without ``towers``); ``line_d``: its validated keys
    (the conductor keys left out); ``towers_data``: the raw ``[[line.towers]]`` (None with
    ``towers_file``, read relative to ``base_dir``); ``wires_data``, ``types_data``: the raw
    ``[[wires]]`` and ``[[tower_types]]`` (None when absent).  Every wire's still-air spans are
    checked (sag and ground clearance); the line returned is the first wire's single-wire line,
    its towers carrying their ``type``."""
    for key in WIRE_LINE_KEYS:
        if key in line_data:
            raise ctx.error("line", key, f"value {fmt_value(line_data[key])} is not allowed with [[wires]]: each wire "
                            f"gives its own {key} (remove it from [line])")
    if wires_data is None:
        raise ctx.error("", "wires", "missing: [[tower_types]] attach wires: give one [[wires]] table per wire")
    if types_data is None:
        raise ctx.error("", "tower_types", "missing: [[wires]] need tower types: give one [[tower_types]] table per "
                        "tower type, with one attachment per wire")
    wires = _read_wires(wires_data, ctx)
    types = _read_tower_types(types_data, wires, line_d["insulator_length"], ctx)
    if towers_data is None and line_d["towers_file"] is None:
        raise ctx.error("line", "towers", "missing: a case with [[wires]] is a section: give one [[line.towers]] table "
                        "per tower (each with its type) or towers_file = \"section.csv\"")
    check_section_keys(line_d, towers_data, ctx, needs_tension=False)
    frames = _read_typed_towers(line_d, towers_data, types, ctx, base_dir)
    for k, w in enumerate(wires):
        towers = wire_towers(frames, w.name, types, line_d["insulator_length"])
        check_still_air_spans(towers, w.tension, w.weight, ItemContext(ctx, "wires", k))
    first = wire_towers(frames, wires[0].name, types, line_d["insulator_length"], keep_type=True)
    return _wire_line(line_d, first, wires[0], ctx), wires, types


def wire_case(case: Case, wire_name: str) -> Case:
    """The single-wire case of wire ``wire_name`` of a case with ``[[wires]]``: the line of the
    bundle-equivalent wire (module docstring) on the towers its attachments give, with no wires
    and no tower types (a case today's analysis runs and the loader accepts: ``case_to_dict``
    of it loads to it again).  Name, description, source, wind, analysis and codes are the
    case's, and so is the reference height of V_ref: one wind for every wire.  Without
    ``wind.reference_height`` the case's default is its line's mean clamp height (the first
    wire's); a wire whose own mean clamp height differs gets that height written in, where its
    own default would scale the profile (and a downburst) at its own height.  KeyError when the
    case has no wire ``wire_name`` (or no wires)."""
    wire = case.wire(wire_name)
    frames = [{"name": t.name, "station": t.station, "ground": t.ground, "angle": t.angle, "type": t.type}
              for t in case.line.towers]
    towers = wire_towers(frames, wire.name, case.tower_types, case.line.insulator_length)
    line_d = {spec.name: getattr(case.line, spec.name) for spec in SCHEMA["line"]}
    line_d["towers_file"] = None  # the wire's towers are its own: held inline
    line = _wire_line(line_d, towers, wire, ErrorContext(None, None))
    wind = case.wind
    if wind.reference_height is None and line.height != case.line.height:  # V_ref at the case's z_ref
        wind = dataclasses.replace(wind, reference_height=float(case.line.height))
    return dataclasses.replace(case, line=line, wind=wind, wires=(), tower_types=())


def clamp_height(attachment: Attachment, line_insulator: float) -> float:
    """Still-air clamp height above the tower's ground [m] of a wire on ``attachment``: z - v at
    a suspension attachment (v its insulator length, else ``line_insulator``; the insulator's
    top T_j = C_j + (0, 0, v_j), docs/method.md "Line sections"), z at a strain attachment."""
    if attachment.support != "suspension":
        return attachment.z
    v = attachment.insulator_length if attachment.insulator_length is not None else line_insulator
    return attachment.z - v


def wire_towers(frames: list[dict[str, Any]], wire: str, types: tuple[TowerType, ...], line_insulator: float,
                keep_type: bool = False) -> list[Tower]:
    """The towers of ``wire``'s single-wire line: each tower's ``frames`` entry (name, station,
    ground, angle, type) with the height, support and insulator length of the wire's attachment
    on that type (:func:`clamp_height`).  ``keep_type``: the towers keep their type (the case's
    own line); else None (a single-wire case)."""
    by_name = {t.name: t for t in types}
    towers = []
    for f in frames:
        a = by_name[f["type"]].attachment(wire)
        towers.append(Tower(name=f["name"], station=f["station"], ground=f["ground"],
                            height=clamp_height(a, line_insulator), support=a.support, angle=f["angle"],
                            insulator_length=a.insulator_length, type=f["type"] if keep_type else None))
    return towers


def _wire_line(line_d: dict[str, Any], towers: list[Tower], wire: Wire, ctx: ErrorContext) -> Line:
    """The section line of ``wire`` on ``towers``: ``line_d``'s keys with the bundle-equivalent
    conductor (module docstring), the equal-span keys derived (:func:`derived_line`)."""
    d = dict(line_d)
    d.update(weight=wire.weight_total, diameter=wire.drag_diameter, drag_coefficient=wire.drag_coefficient,
             area=wire.area_total, elastic_modulus=wire.elastic_modulus, tension=wire.tension_total)
    for key in EQUAL_SPAN_KEYS:
        d[key] = None
    return derived_line(d, towers, ctx)


def _tables(data: Any, ctx: ErrorContext, key: str, what: str) -> list[dict[str, Any]]:
    """``data`` as a non-empty list of tables, else a message naming ``key``."""
    if not isinstance(data, list) or not data or not all(isinstance(d, dict) for d in data):
        raise ctx.error("", key, f"value {fmt_value(data)} is not allowed: expected {what}")
    return data


def _name(d: dict[str, Any], ictx: ErrorContext, seen: dict[str, int], array: str) -> str:
    """The validated ``name`` of item ``len(seen)`` of ``array``: non-empty, not used before."""
    name = d["name"]
    if not name.strip():
        raise ictx.error("", "name", f"value {fmt_value(name)} is not allowed: expected a non-empty name")
    if name in seen:
        raise ictx.error("", "name", f"value {fmt_value(name)} is not allowed: {array}[{seen[name] + 1}] has that name; "
                         f"expected unique names in [[{array}]]")
    seen[name] = len(seen)
    return name


def _read_wires(wires_data: Any, ctx: ErrorContext) -> tuple[Wire, ...]:
    """The ``[[wires]]`` tables as :class:`Wire` (names unique; ``bundle_spacing`` and
    ``shielding`` on bundles only)."""
    wires, seen = [], {}
    for k, d in enumerate(_tables(wires_data, ctx, "wires", "[[wires]] tables, one per wire")):
        wctx = ItemContext(ctx, "wires", k)
        wd = read_section(d, "wires", wctx)
        _name(wd, wctx, seen, "wires")
        if wd["bundle"] == 1:
            for key in ("bundle_spacing", "shielding"):
                if key in d:
                    raise wctx.error("", key, f"value {fmt_value(d[key])} is not allowed with bundle = 1: expected it on "
                                     "bundles only (bundle >= 2; remove it)")
        wires.append(Wire(**wd))
    return tuple(wires)


class _AttachmentCtx(ErrorContext):
    """Error context of attachment j of tower type k (both 0-based): messages name
    ``tower_types[k+1].attachments[j+1].key`` and the attachment's line."""

    def __init__(self, ctx: ErrorContext, k: int, j: int) -> None:
        super().__init__(ctx.file, ctx.text)
        self.k, self.j = k, j

    def error(self, section: str, key: str | None, message: str) -> CaseError:
        dotted = f"tower_types[{self.k + 1}].attachments[{self.j + 1}]" + (f".{key}" if key else "")
        return CaseError(message, file=self.file, key=dotted, line=_attachment_line(self.text, self.k, self.j))


def _attachment_line(text: str | None, k: int, j: int) -> int | None:
    """1-based file line of the j-th inline table of ``attachments = [...]`` in the k-th
    ``[[tower_types]]`` table (both 0-based); the ``attachments`` key's line when not found."""
    start = array_table_line(text, "tower_types", k, "attachments")
    if text is None or start is None:
        return start
    depth, count = 0, -1
    for n, raw in enumerate(text.splitlines()[start - 1:], start=start):
        body = re.sub(r'"[^"]*"|#.*', "", raw.split("=", 1)[1] if n == start else raw)  # strings, comments out
        for ch in body:
            if ch == "[":
                depth += 1
            elif ch == "]":
                depth -= 1
                if depth == 0:
                    return start
            elif ch == "{" and depth == 1:
                count += 1
                if count == j:
                    return n
    return start


def _read_tower_types(types_data: Any, wires: tuple[Wire, ...], line_insulator: float,
                      ctx: ErrorContext) -> tuple[TowerType, ...]:
    """The ``[[tower_types]]`` tables as :class:`TowerType`: names unique, one attachment per
    wire (``line_insulator`` [m]: the default insulator length of suspension attachments)."""
    types, seen = [], {}
    for k, d in enumerate(_tables(types_data, ctx, "tower_types", "[[tower_types]] tables, one per tower type")):
        tctx = ItemContext(ctx, "tower_types", k)
        d = dict(d)
        attachments_data = d.pop("attachments", None)
        td = read_section(d, "tower_types", tctx)
        name = _name(td, tctx, seen, "tower_types")
        if not isinstance(attachments_data, list) or not attachments_data \
                or not all(isinstance(a, dict) for a in attachments_data):
            shown = "missing" if attachments_data is None else f"value {fmt_value(attachments_data)} is not allowed"
            raise tctx.error("", "attachments", f"{shown}: expected one attachment per wire, attachments = "
                             "[{ wire = \"A\", y = -5.5, z = 31.0, support = \"suspension\" }, ...]")
        attachments = tuple(_read_attachment(a, _AttachmentCtx(ctx, k, j), wires, line_insulator)
                            for j, a in enumerate(attachments_data))
        _check_one_per_wire(attachments, wires, tctx, k, ctx)
        types.append(TowerType(name=name, attachments=attachments))
    return tuple(types)


def _read_attachment(a: dict[str, Any], actx: ErrorContext, wires: tuple[Wire, ...], line_insulator: float) -> Attachment:
    """One attachment: a known wire, an insulator on suspension attachments only, and the clamp
    z - v higher than the insulator is long (a single-wire tower's rule: height > insulator_length)."""
    ad = read_section(a, "tower_types.attachments", actx)
    names = [w.name for w in wires]
    if ad["wire"] not in names:
        raise actx.error("", "wire", f"value {fmt_value(ad['wire'])} is not allowed: expected one of "
                         f"{', '.join(fmt_value(n) for n in names)} (the [[wires]] names){_hint(ad['wire'], names)}")
    if ad["insulator_length"] is not None and ad["support"] != "suspension":
        raise actx.error("", "insulator_length", f"value {ad['insulator_length']!r} is not allowed on a strain "
                         "attachment: expected it on suspension attachments only (remove it)")
    att = Attachment(**ad)
    if att.support == "suspension":
        v = att.insulator_length if att.insulator_length is not None else line_insulator
        if clamp_height(att, line_insulator) <= v:
            raise actx.error("", "z", f"value {att.z!r} is not allowed with insulator length {v!r}: expected z > 2 x "
                             f"insulator_length = {2.0 * v:g} m (the clamp hangs insulator_length below z and, as a "
                             "tower's height, must be above the insulator's length)")
    return att


def _check_one_per_wire(attachments: tuple[Attachment, ...], wires: tuple[Wire, ...], tctx: ErrorContext, k: int,
                        ctx: ErrorContext) -> None:
    """Tower type k (0-based) attaches every wire exactly once."""
    first: dict[str, int] = {}
    for j, a in enumerate(attachments):
        if a.wire in first:
            raise _AttachmentCtx(ctx, k, j).error("", "wire", f"value {fmt_value(a.wire)} is not allowed: attachment "
                                                  f"{first[a.wire] + 1} of this type carries that wire; expected each wire once per type")
        first[a.wire] = j
    missing = [w.name for w in wires if w.name not in first]
    if missing:
        raise tctx.error("", "attachments", f"has no attachment of wire {fmt_value(missing[0])}: expected one attachment "
                         f"per wire ({', '.join(fmt_value(w.name) for w in wires)})")


def _hint(value: str, names: list[str]) -> str:
    close = difflib.get_close_matches(value, names, n=1)
    return f' (did you mean "{close[0]}"?)' if close else ""


def _read_typed_towers(line_d: dict[str, Any], towers_data: Any, types: tuple[TowerType, ...], ctx: ErrorContext,
                       base_dir: Path | None) -> list[dict[str, Any]]:
    """Each tower of a case with ``[[wires]]`` as ``{name, station, ground, angle, type}``: a
    known type (whose attachments are all strain at an end tower), no height, support or
    insulator_length of its own, and the place checks of a single-wire tower."""
    raw = raw_towers(line_d, towers_data, ctx, base_dir, typed=True)
    n = len(raw)
    by_name = {t.name: t for t in types}
    allowed = ", ".join(fmt_value(t.name) for t in types)
    frames: list[dict[str, Any]] = []
    for k, (d, tctx) in enumerate(raw):
        td = read_section(d, "line.towers", tctx, optional=("height", "support"))
        for key in TYPE_TOWER_KEYS:
            if td[key] is not None:
                raise tctx.error("", key, f"value {fmt_value(td[key])} is not allowed with [[wires]]: the tower's type "
                                 "places each wire (its attachments' z, support and insulator_length; remove it)")
        if td["type"] is None:
            raise tctx.error("", "type", f"missing: expected one of {allowed} (with [[wires]] every tower names its "
                             "[[tower_types]] type)")
        if td["type"] not in by_name:
            raise tctx.error("", "type", f"value {fmt_value(td['type'])} is not allowed: expected one of {allowed} "
                             f"(the [[tower_types]] names){_hint(td['type'], list(by_name))}")
        if k in (0, n - 1):
            for a in by_name[td["type"]].attachments:
                if a.support != "strain":
                    raise tctx.error("", "type", f"value {fmt_value(td['type'])} is not allowed at an end tower: its "
                                     f"attachment of wire {fmt_value(a.wire)} is \"{a.support}\"; expected a type whose "
                                     "attachments are all \"strain\" (a suspension end leaves the section unrestrained "
                                     "along the line)")
        check_end_angle(td, tctx, k, n)
        check_station(td, tctx, frames[-1]["station"] if frames else None)
        frames.append({"name": td["name"] if td["name"] is not None else f"T{k + 1}", "station": td["station"],
                       "ground": td["ground"], "angle": td["angle"], "type": td["type"]})
    return frames
