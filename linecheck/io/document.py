"""The typed run-result document every front end reads: :class:`RunDocument`, its reader and its
construction from a run.

:class:`RunDocument` is the frozen form of what ``linecheck run --json`` and a batch write, and
the only form the front ends (console tables, batch summary, Excel, TUI) read: ``to_json()``
gives the public JSON layout (docs/results.schema.json, :mod:`linecheck.io.result_schema`),
``from_json()`` reads it back and rejects a document of another schema version with a
:class:`~linecheck.core.errors.CaseError` that says how to regenerate it.  Every block is a typed
field or a typed optional sub-document (None = absent from the JSON;
:mod:`linecheck.io.result_blocks`): still air, step-1 series, case parameters, burn-in, spectral
check, design codes, time histories, the batch source, the downburst model spread and
``--until``; only keys this version does not know are kept verbatim in
:attr:`RunDocument.blocks`.  ``to_json`` writes the keys in the order ``run``/``batch`` always
wrote them, so a document read and written again is byte for byte the same.

The statistics table (:mod:`linecheck.io.stat_table`), the typed blocks and the schema are
importable from here too, the one module a front end needs.  Forces in N, Cont_* as fractions;
no UI imports.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import CaseError
from .provenance import Provenance
from .result_blocks import (
    BatchSource,
    BurnInRecord,
    CodeCheckRecord,
    CodeTower,
    CodeVerdict,
    Davenport,
    EnvelopeEntry,
    FailedRun,
    Gumbel,
    ReactionResult,
    SanityCheckRow,
    Spectral,
    StaticSeries,
    StatValue,
    StillAir,
    TimeHistories,
    TowerRecord,
    Until,
    UpliftRecord,
    json_value,
    models_of,
    reactions_from_json,
    reactions_to_json,
)
from .result_blocks import finite_or_none as _f
from .result_schema import HEADER_FIELDS, SCHEMA_VERSION, json_schema, result_schema
from .schema import check as check_schema
from .stat_table import (
    FLAG_STATES,
    GUMBEL_KEYS,
    REACTIONS,
    SPECTRAL_EXACT,
    STAT_BY_NAME,
    STAT_TABLE,
    SUMMARY_KEYS,
    StatDef,
    stat_def,
)
from .wires_blocks import AttachmentRun, WireRecord, load_trees_from_json, totals_from_json

__all__ = [
    "BLOCK_FIELDS", "FLAG_STATES", "GUMBEL_KEYS", "HEADER_FIELDS", "REACTIONS", "RESULT_FILE", "SCHEMA_VERSION",
    "SECTION_TOWER_KEYS", "SPECTRAL_EXACT", "STAT_BY_NAME", "STAT_TABLE", "SUMMARY_KEYS", "BatchSource",
    "BurnInRecord", "CodeCheckRecord", "CodeTower", "CodeVerdict", "Davenport", "EnvelopeEntry", "FailedRun",
    "Gumbel", "ReactionResult", "RunDocument", "SanityCheckRow", "Spectral", "StatDef", "StatValue",
    "StaticSeries", "StillAir", "TimeHistories", "TowerRecord", "Until", "UpliftRecord", "WireRecord", "document_of",
    "json_schema", "load_document", "models_of", "reactions_of", "read_result_file", "section_tower", "stat_def",
    "stat_value", "tower_from_json", "uplift_of", "uplift_record",
]

#: Optional typed blocks after ``"towers"``, in JSON order (absent from the JSON when None).
BLOCK_FIELDS = ("still_air", "static", "parameters", "burn_in", "damping", "structural_damping", "wires", "spectral",
                "codes", "time_histories", "batch", "model", "models", "models_envelope", "models_failed",
                "provenance")
_BATCH_KEYS = ("case_file", "case_hash", "changes")


SECTION_TOWER_KEYS = ("name", "station", "ground", "height", "angle", "insulator_length", "heading", "global")


def section_tower(res: Any, k: int) -> dict[str, Any] | None:
    """The section metadata of tower k (0-based) of a run (None for the equal-span form)."""
    system = res.system
    if not system.is_section:
        return None
    t = system.line.towers[k]
    m = res.static.mean
    still = m.still_air.reactions[k]
    total = m.reactions[:, k]
    big = int(np.argmax(np.abs(m.reactions_wind[:, k]).max(axis=1))) if m.time.size > 1 else 0
    return {
        "name": t.name, "station": float(system.stations[k]), "ground": t.ground, "height": t.height,
        "angle": t.angle,
        "insulator_length": float(system.insulator_lengths[k]) if t.support == "suspension" else None,
        "heading": float(np.degrees(system.tower_headings[k])),
        "global": {"still_air": {r: _f(still[c]) for c, r in enumerate(REACTIONS)},
                   "mean": {r: _f(total[big, c]) for c, r in enumerate(REACTIONS)}},
    }


def uplift_record(res: Any, k: int) -> UpliftRecord | None:
    """The uplift of tower k (0-based) of a run (:func:`uplift_of` of its step 1)."""
    return uplift_of(res.static, k)


def uplift_of(static: Any, k: int) -> UpliftRecord | None:
    """The uplift at tower k (0-based) of a step-1 result
    (:func:`linecheck.analysis.uplift.step1_uplift`): the smallest margin [N] over the mean
    states, the weight span [m] and instant [s] there, and the still-air values; None at a
    strain tower."""
    from ..analysis.uplift import step1_uplift

    u = step1_uplift(static)
    if not u.suspension[k]:
        return None
    i = int(u.worst_state[k])
    return UpliftRecord(_f(u.margin[i, k]), _f(u.weight_span[i, k]), _f(u.time[i]),
                        {"margin": _f(u.margin_still_air[k]), "weight_span": _f(u.weight_span_still_air[k])})


@dataclass(frozen=True)
class RunDocument:
    """A run result as saved and read by every front end.

    ``reactions``: the tower of interest; ``towers[k]``: tower k+1.  Optional blocks (None =
    absent): ``still_air``, ``static`` (step-1 series), ``parameters`` (the case's TOML
    document), ``burn_in``, ``damping``/``structural_damping``, ``spectral``, ``codes`` (per
    code), ``time_histories``, ``batch`` (written as the top-level keys ``"case_file"``,
    ``"case_hash"``, ``"changes"``), ``model``/``models``/``models_envelope``/``models_failed``
    (downburst model spread), ``until``, ``provenance`` (versions, BLAS and compiled kernel of the
    run, :mod:`linecheck.io.provenance`; absent from results saved before it was recorded).
    A run of a case with ``[[wires]]`` (:mod:`linecheck.io.wires_document`): ``wires`` (each
    wire's :class:`~linecheck.io.wires_blocks.WireRecord`), ``reactions`` and each tower's
    ``reactions`` the totals' forces, and each tower's ``type``, ``attachments``, ``totals`` and
    ``load_trees`` (:class:`~linecheck.io.result_blocks.TowerRecord`); :attr:`has_wires`.
    ``blocks``: keys this version does not know, verbatim.
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
    towers: tuple[TowerRecord, ...]
    until: Until | None = None
    still_air: StillAir | None = None
    static: StaticSeries | None = None
    parameters: dict[str, Any] | None = None
    burn_in: BurnInRecord | None = None
    damping: str | None = None
    structural_damping: float | None = None
    wires: tuple[WireRecord, ...] | None = None
    spectral: Spectral | None = None
    codes: dict[str, CodeCheckRecord] | None = None
    time_histories: TimeHistories | None = None
    batch: BatchSource | None = None
    model: str | None = None
    models: dict[str, dict[str, ReactionResult]] | None = None
    models_envelope: dict[str, dict[str, EnvelopeEntry]] | None = None
    models_failed: dict[str, str] | None = None
    provenance: Provenance | None = None
    blocks: dict[str, Any] = field(default_factory=dict)

    def reaction(self, r: str) -> ReactionResult:
        return self.reactions[r]

    @property
    def has_wires(self) -> bool:
        """A run of a case with ``[[wires]]``: every tower has attachments, totals and load trees."""
        return self.wires is not None

    def to_json(self) -> dict[str, Any]:
        """The public JSON layout (plain dict of JSON values, keys in the documented order)."""
        d: dict[str, Any] = {k: getattr(self, k) for k, _ in HEADER_FIELDS}
        if self.until is not None:
            d["until"] = self.until.to_json()
        d["reactions"] = reactions_to_json(self.reactions)
        d["towers"] = [t.to_json() for t in self.towers]
        for k in BLOCK_FIELDS:
            v = getattr(self, k)
            if v is None:
                continue
            if k == "batch":
                d.update(v.to_json())
            elif k == "models":
                d[k] = {m: reactions_to_json(blk) for m, blk in v.items()}
            else:
                d[k] = json_value(v)
        for k, v in self.blocks.items():
            d[k] = v
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any], *, source: str | None = None) -> RunDocument:
        """Read a saved document; :class:`CaseError` (exit 2) for another schema version or a
        document that is not a run result, saying how to regenerate it."""
        what = "is " if source else "result document is "  # CaseError puts the file name first
        if not isinstance(d, dict) or "reactions" not in d or "case" not in d:
            raise CaseError("is not a linecheck run result (no \"case\"/\"reactions\"): expected the JSON of "
                            "`linecheck run --json` or of a batch", file=source)
        ver = d.get("schema_version", 1)
        if isinstance(ver, int) and not isinstance(ver, bool) and ver != SCHEMA_VERSION:
            raise CaseError(
                f"result schema_version {ver} is not supported (this linecheck reads {SCHEMA_VERSION}): "
                f"regenerate it with `linecheck run CASE.toml --json {source or 'FILE.json'}` "
                "(or re-run the batch)", file=source)
        check_schema(d, result_schema(), source)  # key path, value, what is allowed: before any value is used
        try:
            head = {k: d[k] for k, _ in HEADER_FIELDS}
            reactions = reactions_from_json(d["reactions"])
            towers = tuple(tower_from_json(t) for t in d["towers"])
            until = Until.from_json(d["until"]) if d.get("until") is not None else None

            def opt(key: str, read: Any) -> Any:
                return None if d.get(key) is None else read(d[key])

            opts = dict(
                still_air=opt("still_air", StillAir.from_json), static=opt("static", StaticSeries.from_json),
                parameters=d.get("parameters"), burn_in=opt("burn_in", BurnInRecord.from_json),
                damping=d.get("damping"), structural_damping=d.get("structural_damping"),
                wires=opt("wires", lambda w: tuple(WireRecord.from_json(x) for x in w)),
                spectral=opt("spectral", Spectral.from_json),
                codes=opt("codes", lambda c: {k: CodeCheckRecord.from_json(v) for k, v in c.items()}),
                time_histories=opt("time_histories", TimeHistories.from_json),
                batch=None if "case_file" not in d else BatchSource(d["case_file"], d.get("case_hash"), d.get("changes")),
                model=d.get("model"), models=opt("models", lambda m: {k: reactions_from_json(v) for k, v in m.items()}),
                models_envelope=opt("models_envelope", lambda e: {
                    r: {s: EnvelopeEntry.from_json(x) for s, x in st.items()} for r, st in e.items()}),
                models_failed=d.get("models_failed"),
                provenance=opt("provenance", Provenance.from_json),  # older results: none
            )
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
            raise CaseError(f"{what}incomplete or damaged ({type(exc).__name__}: {exc}): regenerate it with "
                            f"`linecheck run CASE.toml --json {source or 'FILE.json'}`", file=source) from None
        typed = {k for k, _ in HEADER_FIELDS} | {"reactions", "towers", "until"} | set(BLOCK_FIELDS) | set(_BATCH_KEYS)
        blocks = {k: v for k, v in d.items() if k not in typed}
        return cls(**head, reactions=reactions, towers=towers, until=until, **opts, blocks=blocks)


def tower_from_json(t: dict[str, Any]) -> TowerRecord:
    """A :class:`TowerRecord` from ``towers[i]`` of a saved document (with a run of a case with
    ``[[wires]]``: its type, attachments, totals and load trees)."""
    attachments = t.get("attachments")
    return TowerRecord(
        int(t["index"]), t["support"], reactions_from_json(t["reactions"]),
        {k: t[k] for k in SECTION_TOWER_KEYS if k in t} or None,
        UpliftRecord.from_json(t["uplift"]) if "uplift" in t else None, t.get("type"),
        None if attachments is None else tuple(AttachmentRun.from_json(a) for a in attachments),
        totals_from_json(t["totals"]) if "totals" in t else None,
        load_trees_from_json(t["load_trees"]) if "load_trees" in t else None)


#: What a saved result file is expected to be (messages).
RESULT_FILE = "a JSON result of `linecheck run --json`"


def read_result_file(path: Any) -> Any:
    """The JSON value of a saved result file (``export``, ``batch --resume``): a regular UTF-8
    file of at most ``MAX_RESULT_BYTES``; bad syntax, an integer of thousands of digits or
    arrays nested too deeply to parse are one :class:`CaseError` naming the file, like every
    other unreadable result (:func:`linecheck.io.schema.read_json_file`)."""
    from ..core.case import MAX_RESULT_BYTES
    from .schema import read_json_file

    return read_json_file(path, RESULT_FILE, MAX_RESULT_BYTES)


def load_document(d: Any, *, source: str | None = None) -> RunDocument | FailedRun:
    """A front end's input: a :class:`RunDocument` or :class:`FailedRun` as is, a JSON dict
    through :meth:`RunDocument.from_json` (``{"case", "error"}`` -> :class:`FailedRun`)."""
    if isinstance(d, (RunDocument, FailedRun)):
        return d
    if isinstance(d, dict) and "error" in d and "reactions" not in d:
        return FailedRun(str(d.get("case", "?")), str(d["error"]))
    return RunDocument.from_json(d, source=source)


# --------------------------------------------------------------------------- from a run
def stat_value(ss: Any, j: int, c: int) -> StatValue:
    """Column ``c`` of tower ``j`` (0-based) of a :class:`~linecheck.core.results.StatisticSummary`
    as a :class:`StatValue` (with its Gumbel fit and interval when it has them)."""
    sm = ss.summary
    g = ss.gumbel
    gumbel = None if g is None else Gumbel(_f(g.location[j, c]), _f(g.scale[j, c]), _f(g.ppcc[j, c]),
                                           _f(g.design[j, c]))
    ci = None if ss.ci is None else (_f(ss.ci[0][j, c]), _f(ss.ci[1][j, c]))
    return StatValue(_f(sm.mean[j, c]), _f(sm.std[j, c]), _f(sm.se[j, c]), _f(sm.p05[j, c]), _f(sm.p50[j, c]),
                     _f(sm.p95[j, c]), gumbel, ci)


def reactions_of(summary: Any, tower: int) -> dict[str, ReactionResult]:
    """Typed reaction blocks of 0-based ``tower`` from a :class:`~linecheck.core.results.ResultSummary`."""
    return {r: ReactionResult({s.name: stat_value(summary.statistics[s.name], tower, c) for s in STAT_TABLE},
                              summary.dynamic_analysis[tower, c])
            for c, r in enumerate(REACTIONS)}


def document_of(res: Any, **blocks: Any) -> RunDocument:
    """The :class:`RunDocument` of a :class:`~linecheck.service.RunResult` (``blocks``: its
    optional typed blocks, :data:`BLOCK_FIELDS`)."""
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
        towers=tuple(TowerRecord(k + 1, case.line.supports[k], reactions_of(summary, k), section_tower(res, k),
                                 uplift_record(res, k))
                     for k in range(res.system.n_towers)),
        until=until, **blocks,
    )
