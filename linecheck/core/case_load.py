"""Loading a case: a TOML case file (or a parsed document) validated and built into a :class:`~.case_model.Case`.

:func:`load_case` reads the file safely (:mod:`.case_files`) and parses it; :func:`case_from_dict`
validates every table against :data:`~.case_schema.SCHEMA` (:mod:`.case_validate`), builds the
line (:mod:`.case_geometry`; with ``[[wires]]`` the wires and tower types too, :mod:`.case_wires`),
the wind (with its downburst) and the analysis settings, and cross-checks them.  Every refusal is one :class:`~.errors.CaseError` line naming the file, the
key (and its line), the value and what is allowed.
"""

from __future__ import annotations

import hashlib
import math
import re
import tomllib
from pathlib import Path
from typing import Any

from .case_files import MAX_CASE_BYTES, read_regular_file, read_text_file
from .case_geometry import equal_span_line, section_line
from .case_model import Analysis, Case, Codes, Downburst, Line, TowerType, Wind, Wire
from .case_schema import RING_MODELS
from .case_validate import MAX_NESTING, ErrorContext, check_text, fmt_value, read_section
from .case_wires import WIRE_LINE_KEYS, wires_line
from .errors import CaseError


def case_from_dict(
    data: dict[str, Any],
    *,
    file: str | None = None,
    text: str | None = None,
    default_name: str = "case",
    base_dir: Path | None = None,
) -> Case:
    """Validate a parsed TOML document and build a :class:`Case`.

    Raises :class:`CaseError` naming file, key, line, value and what is allowed.
    """
    ctx = ErrorContext(file, text)
    check_text(data, ctx)
    top = read_section(data, "", ctx)
    for required in ("line", "wind"):
        if required not in data:
            raise ctx.error("", required, f"missing required table [{required}]")
    line_data = dict(data["line"]) if isinstance(data["line"], dict) else data["line"]
    towers_data = line_data.pop("towers", None) if isinstance(line_data, dict) else None
    with_wires = "wires" in data or "tower_types" in data  # docs/case-files.md "Every wire on the tower"
    line_d = read_section(line_data, "line", ctx, optional=WIRE_LINE_KEYS if with_wires else ())
    wind_d = read_section(data["wind"], "wind", ctx)
    an_d = read_section(data.get("analysis", {}), "analysis", ctx)

    wires: tuple[Wire, ...] = ()
    tower_types: tuple[TowerType, ...] = ()
    if with_wires:
        line, wires, tower_types = wires_line(line_data, line_d, towers_data, data.get("wires"), data.get("tower_types"),
                                              ctx, base_dir)
    elif towers_data is not None or line_d["towers_file"] is not None or line_d["tension"] is not None:
        line = section_line(line_d, towers_data, ctx, base_dir)
    else:
        line = equal_span_line(line_d, ctx)
    wind = _build_wind(data["wind"].get("downburst"), wind_d, line, ctx, base_dir)
    analysis = _build_analysis(an_d, ctx)
    codes = Codes(**read_section(data.get("codes", {}), "codes", ctx))
    name = top["name"] or default_name
    return Case(name=name, description=top["description"] or "", line=line, wind=wind, analysis=analysis,
                source=Path(file) if file else None, codes=codes, wires=wires, tower_types=tower_types)


def _build_wind(db_data: Any, wind_d: dict[str, Any], line: Line, ctx: ErrorContext, base_dir: Path | None) -> Wind:
    """The :class:`Wind` from its validated keys ``wind_d`` and the raw ``[wind.downburst]`` table
    ``db_data`` (None when absent), cross-checked against the wind type and the line's spans."""
    if wind_d["type"] == "downburst":
        if db_data is None:
            raise ctx.error("wind", "downburst", "missing table [wind.downburst] for type = \"downburst\"")
        db_d = read_section(db_data, "wind.downburst", ctx)
        db = _build_downburst(db_d, line, ctx, base_dir)
        if wind_d["span_speeds"] is not None:
            raise ctx.error("wind", "span_speeds", "is for synoptic winds only: a downburst's speeds come from its field")
    else:
        if db_data is not None:
            raise ctx.error("wind", "downburst", "table [wind.downburst] given but type = \"synoptic\": remove it or set type = \"downburst\"")
        db = None
        if wind_d["span_speeds"] is not None and len(wind_d["span_speeds"]) != line.spans:
            raise ctx.error("wind", "span_speeds", f"value {fmt_value(wind_d['span_speeds'])} has {len(wind_d['span_speeds'])} entries: expected {line.spans}, one per span")
    return Wind(downburst=db, **wind_d)


def _build_analysis(an_d: dict[str, Any], ctx: ErrorContext) -> Analysis:
    """The :class:`Analysis` from its validated keys, the time step checked against the duration
    and the peak window."""
    analysis = Analysis(**an_d)
    if analysis.duration is not None and analysis.time_step * 4 > analysis.duration:
        raise ctx.error("analysis", "time_step", f"value {analysis.time_step!r} is too large for duration {analysis.duration!r}: expected at most duration/4")
    if analysis.peak_window is not None and analysis.peak_window < 4 * analysis.time_step:
        raise ctx.error("analysis", "peak_window", f"value {analysis.peak_window!r} is too short for time_step {analysis.time_step!r}: expected at least 4 time steps")
    return analysis


def _build_downburst(d: dict[str, Any], line: Line, ctx: ErrorContext, base_dir: Path | None) -> Downburst:
    """The :class:`Downburst` from its validated keys ``d`` (completed in place from a ``preset``,
    whose D_j = 2 L_x): the geometry given, the time history and the running-mean model consistent,
    a field file (relative to ``base_dir``) present."""
    sec = "wind.downburst"
    preset = d["preset"]
    if preset is not None:
        dj = 2.0 * line.span_length  # paper Table 2 note: D_j = 2.0 L_x
        r_ratio, theta = (1.6, 30.0) if preset == "Db_x" else (1.2, 0.0)
        for key, val in (("jet_diameter", dj), ("distance", r_ratio * dj), ("angle", theta)):
            if d[key] is not None and not math.isclose(d[key], val, rel_tol=1e-9, abs_tol=1e-9):
                raise ctx.error(sec, key, f"value {d[key]!r} contradicts preset \"{preset}\" (which sets {key} = {val:g}): remove one of them")
            d[key] = val
    for key in ("jet_diameter", "distance", "angle"):
        if d[key] is None:
            raise ctx.error(sec, key, f"missing: give {key} or a preset (\"Db_x\" or \"Db_y\")")
    if d["t1"] is not None and d["t_f"] is not None and d["t_f"] <= d["t1"]:
        raise ctx.error(sec, "t_f", f"value {d['t_f']!r} is not allowed: expected t_f > t1 = {d['t1']!r}")
    model = d["model"] if d["model"] is not None else ("table" if d["field"] is not None else "holmes-oliver")
    if model == "table" and d["field"] is None:
        raise ctx.error(sec, "model", 'value "table" needs a field file: give field = "file.csv" (or .npz), see docs/wind.md')
    if model != "table" and d["field"] is not None:
        raise ctx.error(sec, "field", f'is read by model "table" only, but model = "{model}": remove field or set model = "table"')
    if model not in RING_MODELS and d["jet_velocity"] is not None:
        raise ctx.error(sec, "jet_velocity", f'is a parameter of model "ring-jet" (and "ring-jet-inviscid") only, but model = "{model}": remove it')
    if model in RING_MODELS:
        for key in ("t1", "t_f"):
            if d[key] is not None:
                raise ctx.error(sec, key, f'shapes the "holmes-oliver" time history only; model "{model}" takes its time scale from D_j/V_j (jet_velocity): remove {key}')
    path = None
    if d["field"] is not None:
        path = Path(d["field"])
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.exists():
            raise ctx.error(sec, "field", f"value {fmt_value(d['field'])}: file {path} does not exist (expected a CSV or NPZ running-mean field, see docs/wind.md)")
    return Downburst(field_path=path, **d)


def load_case(path: str | Path) -> Case:
    """Read and validate a TOML case file.

    Raises :class:`CaseError` (one line: file, key, line, value, what is allowed).
    """
    p = Path(path)
    text = read_text_file(p, "a .toml case file")
    try:
        data = tomllib.loads(text)
    except RecursionError:  # tomllib recurses per nesting level (e.g. a = [[[[...]]]])
        raise CaseError(f"arrays or tables nested too deeply: expected at most {MAX_NESTING} levels",
                        file=str(p)) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        if m:
            raise CaseError(f"TOML syntax error at line {m.group(1)}, column {m.group(2)}: {msg}", file=str(p)) from None
        raise CaseError(f"TOML syntax error: {msg}", file=str(p)) from None
    return case_from_dict(data, file=str(p), text=text, default_name=p.stem, base_dir=p.parent)


def case_hash(path: str | Path) -> str:
    """SHA-256 of the case file's bytes (batch --resume)."""
    return hashlib.sha256(read_regular_file(path, "a .toml case file", MAX_CASE_BYTES)).hexdigest()

