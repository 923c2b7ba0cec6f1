"""The typed run-result document (issue 18) and the one statistics table every front end reads.

:class:`RunDocument` is the frozen form of what ``linecheck run --json`` and a batch write:
``to_json()`` gives the public JSON layout (docs/results.schema.json, generated from this
module by ``tools/make_result_schema.py``), ``from_json()`` reads it back and rejects a
document of another schema version with a :class:`~linecheck.core.errors.CaseError` that
says how to regenerate it.  Blocks this module does not type (still air, step-1 series,
spectral check, time histories, case parameters, and blocks added by other features such as
``"codes"`` or ``"models"``) are kept verbatim in :attr:`RunDocument.blocks`.

Forces in N, Cont_* as fractions; no UI imports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..core.errors import CaseError

#: Version of the run-result JSON layout.  1 (no "schema_version" key): before issue 18,
#: statistics as {"mean", "std"} only.
SCHEMA_VERSION = 2
REACTIONS = ("Rx", "Ry", "Rz")
SUMMARY_KEYS = ("mean", "std", "se", "p05", "p50", "p95")
GUMBEL_KEYS = ("location", "scale", "ppcc", "design")
FLAG_STATES = ("recommended", "inconclusive")


# --------------------------------------------------------------------------- statistics table
@dataclass(frozen=True)
class StatDef:
    """One statistic: JSON key, label, SI unit, kind, display unit, scale to it, format.

    kind: "force" [N], "ratio" [-] or "fraction" [-] (Cont_*, shown in %); ``peak``: has a
    Gumbel fit; ``ci``: has a 95 % interval; ``summary``: shown in the summary tables.
    """

    name: str
    label: str
    unit: str
    kind: str
    display_unit: str
    scale: float
    fmt: str
    peak: bool = False
    ci: bool = False
    summary: bool = True
    meaning: str = ""


def _force(name, label, meaning, peak=False, summary=True):
    return StatDef(name, label, "N", "force", "kN", 1e-3, "{:.3f}", peak=peak, summary=summary, meaning=meaning)


STAT_TABLE: tuple[StatDef, ...] = (
    _force("mean_max", "mean max", "largest wind-induced mean reaction max_t |M|"),
    _force("rms_background", "rms background B", "r.m.s. of the background reaction B"),
    _force("rms_resonant", "rms resonant R", "r.m.s. of the resonant reaction R = F - B"),
    _force("rms_fluctuating", "rms fluctuating B+R", "r.m.s. of B + R", summary=False),
    _force("peak_quasi_static", "peak quasi-static M+B", "max_t |M + B| (wind-induced)", peak=True),
    _force("peak_dynamic", "peak dynamic M+B+R", "max_t |M + B + R| (wind-induced)", peak=True),
    _force("peak_quasi_static_total", "peak quasi-static total", "max_t |still air + M + B|", peak=True,
           summary=False),
    _force("peak_dynamic_total", "peak dynamic total", "max_t |still air + M + B + R|", peak=True, summary=False),
    StatDef("GF_Dy", "GF_Dy", "-", "ratio", "-", 1.0, "{:.3f}", ci=True,
            meaning="dynamic gust factor peak_dynamic / mean_max (Eq. 15)"),
    StatDef("GF_QS", "GF_QS", "-", "ratio", "-", 1.0, "{:.3f}", ci=True,
            meaning="quasi-static gust factor peak_quasi_static / mean_max (Eq. 15)"),
    StatDef("Cont_M", "Cont_M", "-", "fraction", "%", 100.0, "{:.1f}", meaning="mean share mean_max / peak_dynamic (Eq. 16)"),
    StatDef("Cont_BG", "Cont_BG", "-", "fraction", "%", 100.0, "{:.1f}", meaning="background share (peak_QS - mean_max) / peak_dynamic (Eq. 16)"),
    StatDef("Cont_R", "Cont_R", "-", "fraction", "%", 100.0, "{:.1f}", ci=True,
            meaning="resonant share (peak_dynamic - peak_QS) / peak_dynamic (Eq. 16)"),
    StatDef("peak_normalised", "peak / g*_yp L", "-", "ratio", "-", 1.0, "{:.3f}", peak=True,
            meaning="peak_dynamic / (g*_yp L_x) (Eq. 17)"),
    StatDef("peak_normalised_total", "peak total / g*_yp L", "-", "ratio", "-", 1.0, "{:.3f}", peak=True,
            summary=False, meaning="peak_dynamic_total / (g*_yp L_x)"),
)
STAT_BY_NAME = {s.name: s for s in STAT_TABLE}


def stat_def(name: str) -> StatDef:
    """The :class:`StatDef` of statistic ``name``."""
    return STAT_BY_NAME[name]


# --------------------------------------------------------------------------- typed values
def _f(x: Any) -> float | None:
    """A finite float or None (JSON null)."""
    if x is None:
        return None
    v = float(x)
    return v if math.isfinite(v) else None


@dataclass(frozen=True)
class Gumbel:
    """Gumbel fit of a peak: location, scale (unit of the statistic), ppcc [-], design value."""

    location: float | None
    scale: float | None
    ppcc: float | None
    design: float | None

    def to_json(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in GUMBEL_KEYS}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Gumbel:
        return cls(*(_f(d.get(k)) for k in GUMBEL_KEYS))


@dataclass(frozen=True)
class StatValue:
    """One statistic of one reaction over realizations x windows (None where undefined)."""

    mean: float | None
    std: float | None
    se: float | None
    p05: float | None
    p50: float | None
    p95: float | None
    gumbel: Gumbel | None = None
    ci: tuple[float | None, float | None] | None = None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {k: getattr(self, k) for k in SUMMARY_KEYS}
        if self.gumbel is not None:
            d["gumbel"] = self.gumbel.to_json()
        if self.ci is not None:
            d["ci"] = list(self.ci)
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> StatValue:
        g = d.get("gumbel")
        ci = d.get("ci")
        return cls(*(_f(d.get(k)) for k in SUMMARY_KEYS), gumbel=Gumbel.from_json(g) if g is not None else None,
                   ci=(_f(ci[0]), _f(ci[1])) if ci is not None else None)


@dataclass(frozen=True)
class ReactionResult:
    """Every statistic of one reaction component and its Cont_R flag state."""

    stats: dict[str, StatValue]
    dynamic_analysis: str | None

    def __getitem__(self, name: str) -> StatValue:
        return self.stats[name]

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {s.name: self.stats[s.name].to_json() for s in STAT_TABLE}
        d["dynamic_analysis"] = self.dynamic_analysis
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> ReactionResult:
        return cls({s.name: StatValue.from_json(d[s.name]) for s in STAT_TABLE}, d.get("dynamic_analysis"))


def _reactions_json(block: dict[str, ReactionResult]) -> dict[str, Any]:
    return {r: block[r].to_json() for r in REACTIONS}


def _reactions_from(d: dict[str, Any]) -> dict[str, ReactionResult]:
    return {r: ReactionResult.from_json(d[r]) for r in REACTIONS}


@dataclass(frozen=True)
class Until:
    """Adaptive stop (``--until``): target and achieved relative standard error [-]."""

    target: float
    achieved: float | None
    reached: bool
    max_realizations: int

    def to_json(self) -> dict[str, Any]:
        return {"target": self.target, "achieved": self.achieved, "reached": self.reached,
                "max_realizations": self.max_realizations}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Until:
        return cls(float(d["target"]), _f(d.get("achieved")), bool(d.get("reached", False)),
                   int(d.get("max_realizations", 0)))


#: Header fields of :class:`RunDocument`, in JSON order, with their JSON types (for the schema).
HEADER_FIELDS: tuple[tuple[str, str], ...] = (
    ("schema_version", "integer"),
    ("case", "string"),
    ("description", "string"),
    ("wind", "string"),
    ("units", "string"),
    ("tower_of_interest", "integer"),
    ("g_yp_L", "number"),
    ("v_ref", "number"),
    ("span_length", "number"),
    ("spans", "integer"),
    ("realizations", "integer"),
    ("seed", "integer"),
    ("duration", "number"),
    ("time_step", "number"),
    ("peak_window", "number|null"),
    ("windows", "integer"),
    ("design_fractile", "number"),
)


@dataclass(frozen=True)
class RunDocument:
    """A run result as saved and read by every front end (issue 18).

    ``reactions``: the tower of interest; ``towers[k]``: tower k+1 (``support``, ``reactions``);
    ``blocks``: the untyped blocks, kept verbatim and written after the typed keys (extra
    blocks of later features -- ``"codes"``, ``"models"`` -- go here too).
    """

    schema_version: int
    case: str
    description: str
    wind: str
    units: str
    tower_of_interest: int
    g_yp_L: float | None
    v_ref: float
    span_length: float
    spans: int
    realizations: int
    seed: int
    duration: float | None
    time_step: float
    peak_window: float | None
    windows: int
    design_fractile: float
    reactions: dict[str, ReactionResult]
    towers: tuple[dict[str, Any], ...]
    until: Until | None = None
    blocks: dict[str, Any] = field(default_factory=dict)

    def reaction(self, r: str) -> ReactionResult:
        return self.reactions[r]

    def to_json(self) -> dict[str, Any]:
        """The public JSON layout (plain dict of JSON values)."""
        d: dict[str, Any] = {k: getattr(self, k) for k, _ in HEADER_FIELDS}
        if self.until is not None:
            d["until"] = self.until.to_json()
        d["reactions"] = _reactions_json(self.reactions)
        d["towers"] = [{"index": t["index"], "support": t["support"], "reactions": _reactions_json(t["reactions"])}
                       for t in self.towers]
        for k, v in self.blocks.items():
            d[k] = v
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any], *, source: str | None = None) -> RunDocument:
        """Read a saved document; :class:`CaseError` (exit 2) for another schema version or a
        document that is not a run result, saying how to regenerate it."""
        where = source or "result document"
        if not isinstance(d, dict) or "reactions" not in d or "case" not in d:
            raise CaseError("is not a linecheck run result (no \"case\"/\"reactions\"): expected the JSON of "
                            "`linecheck run --json` or of a batch", file=source)
        ver = d.get("schema_version", 1)
        if ver != SCHEMA_VERSION:
            raise CaseError(
                f"result schema_version {ver} is not supported (this linecheck reads {SCHEMA_VERSION}): "
                f"regenerate it with `linecheck run CASE.toml --json {source or 'FILE.json'}` "
                "(or re-run the batch)", file=source)
        try:
            head = {k: d[k] for k, _ in HEADER_FIELDS}
            reactions = _reactions_from(d["reactions"])
            towers = tuple({"index": int(t["index"]), "support": t["support"],
                            "reactions": _reactions_from(t["reactions"])} for t in d["towers"])
            until = Until.from_json(d["until"]) if d.get("until") is not None else None
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise CaseError(f"{where} is incomplete or damaged ({type(exc).__name__}: {exc}): regenerate it with "
                            "`linecheck run CASE.toml --json FILE.json`", file=source) from None
        typed = {k for k, _ in HEADER_FIELDS} | {"reactions", "towers", "until"}
        blocks = {k: v for k, v in d.items() if k not in typed}
        return cls(**head, reactions=reactions, towers=towers, until=until, blocks=blocks)


# --------------------------------------------------------------------------- from a run
def _stat_value(ss: Any, j: int, c: int) -> StatValue:
    sm = ss.summary
    g = ss.gumbel
    gumbel = None if g is None else Gumbel(_f(g.location[j, c]), _f(g.scale[j, c]), _f(g.ppcc[j, c]),
                                           _f(g.design[j, c]))
    ci = None if ss.ci is None else (_f(ss.ci[0][j, c]), _f(ss.ci[1][j, c]))
    return StatValue(_f(sm.mean[j, c]), _f(sm.std[j, c]), _f(sm.se[j, c]), _f(sm.p05[j, c]), _f(sm.p50[j, c]),
                     _f(sm.p95[j, c]), gumbel, ci)


def reactions_of(summary: Any, tower: int) -> dict[str, ReactionResult]:
    """Typed reaction blocks of 0-based ``tower`` from a :class:`~linecheck.core.results.ResultSummary`."""
    return {r: ReactionResult({s.name: _stat_value(summary.statistics[s.name], tower, c) for s in STAT_TABLE},
                              summary.dynamic_analysis[tower, c])
            for c, r in enumerate(REACTIONS)}


def document_of(res: Any, blocks: dict[str, Any]) -> RunDocument:
    """The :class:`RunDocument` of a :class:`~linecheck.service.RunResult` (``blocks``: untyped blocks)."""
    case = res.case
    summary = res.summary()
    j = res.tower_index
    u = res.until
    until = None if u is None else Until(u.target, _f(u.achieved), u.reached, u.max_realizations)
    return RunDocument(
        schema_version=SCHEMA_VERSION, case=case.name, description=case.description, wind=case.wind.type,
        units="SI", tower_of_interest=case.line.tower_of_interest, g_yp_L=_f(case.g_yp_L), v_ref=case.wind.v_ref,
        span_length=case.line.span_length, spans=case.line.spans, realizations=int(res.realizations.size),
        seed=case.analysis.seed, duration=_f(res.time[-1] - res.time[0]), time_step=case.analysis.time_step,
        peak_window=case.analysis.peak_window, windows=int(res.windows),
        design_fractile=case.analysis.design_fractile,
        reactions=reactions_of(summary, j),
        towers=tuple({"index": k + 1, "support": case.line.supports[k], "reactions": reactions_of(summary, k)}
                     for k in range(res.system.n_towers)),
        until=until, blocks=blocks,
    )


# --------------------------------------------------------------------------- JSON Schema
def json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12 subset) of a run-result document, generated from
    :data:`STAT_TABLE` and :data:`HEADER_FIELDS` (``tools/make_result_schema.py`` writes it to
    docs/results.schema.json).  Keywords used: type, properties, required,
    additionalProperties, items, prefixItems, minItems, maxItems, enum, const, $ref, $defs,
    minimum, maximum, description."""
    num_or_null = {"type": ["number", "null"]}

    def stat_schema(s: StatDef) -> dict[str, Any]:
        props: dict[str, Any] = {k: num_or_null for k in SUMMARY_KEYS}
        req = list(SUMMARY_KEYS)
        if s.peak:
            props["gumbel"] = {"$ref": "#/$defs/gumbel"}
            req.append("gumbel")
        if s.ci:
            props["ci"] = {"$ref": "#/$defs/ci"}
            req.append("ci")
        unit = s.unit if s.unit != "-" else "dimensionless"
        return {"type": "object", "description": f"{s.meaning} [{unit}]", "properties": props,
                "required": req, "additionalProperties": False}

    reaction = {
        "type": "object",
        "properties": {**{s.name: {"$ref": f"#/$defs/stat_{s.name}"} for s in STAT_TABLE},
                       "dynamic_analysis": {"enum": [*FLAG_STATES, None]}},
        "required": [*(s.name for s in STAT_TABLE), "dynamic_analysis"],
        "additionalProperties": False,
    }
    reactions = {"type": "object", "properties": {r: {"$ref": "#/$defs/reaction"} for r in REACTIONS},
                 "required": list(REACTIONS), "additionalProperties": False}

    def json_type(t: str) -> dict[str, Any]:
        parts = t.split("|")
        return {"type": parts[0] if len(parts) == 1 else parts}

    header = {k: json_type(t) for k, t in HEADER_FIELDS}
    header["schema_version"] = {"const": SCHEMA_VERSION}
    header["wind"] = {"enum": ["synoptic", "downburst"]}
    header["units"] = {"const": "SI"}
    header["design_fractile"] = {"type": "number", "minimum": 0, "maximum": 1}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://github.com/linecheck/linecheck/docs/results.schema.json",
        "title": "linecheck run result",
        "description": ("Result of `linecheck run --json` and of each case of a batch (schema_version "
                        f"{SCHEMA_VERSION}). Forces in N, Cont_* as fractions; null where undefined. "
                        "Generated by tools/make_result_schema.py from linecheck/io/document.py."),
        "type": "object",
        "properties": {
            **header,
            "until": {"type": "object",
                      "properties": {"target": {"type": "number"}, "achieved": num_or_null,
                                     "reached": {"type": "boolean"}, "max_realizations": {"type": "integer"}},
                      "required": ["target", "achieved"]},
            "reactions": {"$ref": "#/$defs/reactions"},
            "towers": {"type": "array", "items": {
                "type": "object",
                "properties": {"index": {"type": "integer"}, "support": {"enum": ["strain", "suspension"]},
                               "reactions": {"$ref": "#/$defs/reactions"}},
                "required": ["index", "support", "reactions"], "additionalProperties": False}},
            "still_air": {"type": "object"},
            "static": {"type": "object"},
            "parameters": {"type": "object"},
            "burn_in": {"type": "object"},
            "damping": {"type": "string"},
            "structural_damping": {"type": "number"},
            "spectral": {"type": "object"},
            "time_histories": {"type": "object"},
        },
        "required": [k for k, _ in HEADER_FIELDS] + ["reactions", "towers"],
        "additionalProperties": True,
        "$defs": {
            "gumbel": {"type": "object", "description": "method-of-moments Gumbel (EV-I) fit of the peak; "
                       "design = value at non-exceedance probability design_fractile",
                       "properties": {k: num_or_null for k in GUMBEL_KEYS}, "required": list(GUMBEL_KEYS),
                       "additionalProperties": False},
            "ci": {"type": "array", "description": "95 % confidence interval of the mean [low, high]",
                   "prefixItems": [num_or_null, num_or_null], "minItems": 2, "maxItems": 2},
            "reaction": reaction,
            "reactions": reactions,
            **{f"stat_{s.name}": stat_schema(s) for s in STAT_TABLE},
        },
    }
