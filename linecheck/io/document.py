"""The typed run-result document (issue 18) and the one statistics table every front end reads.

:class:`RunDocument` is the frozen form of what ``linecheck run --json`` and a batch write, and
the only form the front ends (console tables, batch summary, Excel, TUI) read: ``to_json()``
gives the public JSON layout (docs/results.schema.json, generated from this module by
``tools/make_result_schema.py``), ``from_json()`` reads it back and rejects a document of
another schema version with a :class:`~linecheck.core.errors.CaseError` that says how to
regenerate it.  Every block is a typed field or a typed optional sub-document (None = absent
from the JSON): still air, step-1 series, case parameters, burn-in, spectral check, design
codes, time histories, the batch source, the downburst model spread and ``--until``; only keys
this version does not know are kept verbatim in :attr:`RunDocument.blocks`.  ``to_json``
writes the keys in the order ``run``/``batch`` always wrote them, so a document read and
written again is byte for byte the same.

Forces in N, Cont_* as fractions; no UI imports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from ..core.errors import CaseError
from .provenance import Provenance
from .schema import MAX_DEPTH, MAX_INTEGER, MAX_MAGNITUDE
from .schema import check as check_schema

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
    """One statistic: JSON key, label, short label (column headers), SI unit, kind, display unit,
    scale to it, format.

    kind: "force" [N], "ratio" [-] or "fraction" [-] (Cont_*, shown in %); ``peak``: has a
    Gumbel fit; ``ci``: has a 95 % interval (GF_Dy, GF_QS, Cont_R: a null GF is shown ``**``);
    ``summary``: shown in the summary tables; ``varies``: differs between realizations (the
    largest mean does not, so no ``± std`` column).
    """

    name: str
    label: str
    short: str
    unit: str
    kind: str
    display_unit: str
    scale: float
    fmt: str
    peak: bool = False
    ci: bool = False
    summary: bool = True
    meaning: str = ""
    varies: bool = True

    def header(self, unit_format: str = "\n({})") -> str:
        """Column header: the short label and, unless dimensionless, the shown unit."""
        return self.short + ("" if self.display_unit == "-" else unit_format.format(self.display_unit))


def _force(name, label, short, meaning, peak=False, summary=True, varies=True):
    return StatDef(name, label, short, "N", "force", "kN", 1e-3, "{:.3f}", peak=peak, summary=summary, meaning=meaning,
                   varies=varies)


def _ratio(name, label, short, meaning, **kw):
    return StatDef(name, label, short, "-", "ratio", "-", 1.0, "{:.3f}", meaning=meaning, **kw)


def _fraction(name, meaning, **kw):
    return StatDef(name, name, name, "-", "fraction", "%", 100.0, "{:.1f}", meaning=meaning, **kw)


STAT_TABLE: tuple[StatDef, ...] = (
    _force("mean_max", "mean max", "mean M", "largest wind-induced mean reaction max_t |M|", varies=False),
    _force("rms_background", "rms background B", "rms B", "r.m.s. of the background reaction B"),
    _force("rms_resonant", "rms resonant R", "rms R", "r.m.s. of the resonant reaction R = F - B"),
    _force("rms_fluctuating", "rms fluctuating B+R", "rms B+R", "r.m.s. of B + R", summary=False),
    _force("peak_quasi_static", "peak quasi-static M+B", "peak QS", "max_t |M + B| (wind-induced)", peak=True),
    _force("peak_dynamic", "peak dynamic M+B+R", "peak Dy", "max_t |M + B + R| (wind-induced)", peak=True),
    _force("peak_quasi_static_total", "peak quasi-static total", "peak QS total", "max_t |still air + M + B|",
           peak=True, summary=False),
    _force("peak_dynamic_total", "peak dynamic total", "peak Dy total", "max_t |still air + M + B + R|", peak=True,
           summary=False),
    _ratio("GF_Dy", "GF_Dy", "GF_Dy", "dynamic gust factor peak_dynamic / mean_max (Eq. 15)", ci=True),
    _ratio("GF_QS", "GF_QS", "GF_QS", "quasi-static gust factor peak_quasi_static / mean_max (Eq. 15)", ci=True),
    _fraction("Cont_M", "mean share mean_max / peak_dynamic (Eq. 16)"),
    _fraction("Cont_BG", "background share (peak_QS - mean_max) / peak_dynamic (Eq. 16)"),
    _fraction("Cont_R", "resonant share (peak_dynamic - peak_QS) / peak_dynamic (Eq. 16)", ci=True),
    _ratio("peak_normalised", "peak / g*_yp L", "peak / g*yp Lx", "peak_dynamic / (g*_yp L_x) (Eq. 17)", peak=True),
    _ratio("peak_normalised_total", "peak total / g*_yp L", "peak total / g*yp Lx", "peak_dynamic_total / (g*_yp L_x)",
           peak=True, summary=False),
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


# --------------------------------------------------------------------------- typed blocks
def _out(v: Any) -> Any:
    """JSON value of a field: sub-documents by their ``to_json``, containers element-wise."""
    if hasattr(v, "to_json"):
        return v.to_json()
    if isinstance(v, dict):
        return {k: _out(x) for k, x in v.items()}
    if isinstance(v, tuple):
        return [_out(x) for x in v]
    return v


class _Block:
    """A JSON object whose keys are the dataclass's fields, in order; values are JSON values kept
    exactly as read or written (no float/int coercion: a document read and written again is byte
    for byte the same).  Subclasses with typed members override ``from_json``."""

    def to_json(self) -> dict[str, Any]:
        return {f.name: _out(getattr(self, f.name)) for f in fields(self)}  # type: ignore[arg-type]

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Any:
        return cls(**{f.name: d[f.name] for f in fields(cls)})  # type: ignore[arg-type]


@dataclass(frozen=True)
class StillAir(_Block):
    """Still-air state: reactions at the tower of interest [N], span tensions [N], nominal tension [N], sag [m]."""

    reactions: dict[str, float | None]
    tension: list[float | None]
    tension_nominal: float | None
    sag: float


@dataclass(frozen=True)
class StaticSeries(_Block):
    """Step-1 mean state over its instants (one for synoptic): time [s], wind-induced reactions at
    the tower of interest [N] (``{"Rx": [...], ...}``), tensions [N] (instants x spans), tower
    displacements [m] (``{"dx": [...], ...}``)."""

    time: list[float]
    reactions_wind: dict[str, list[float | None]]
    tension: list[list[float | None]]
    displacement: dict[str, list[float | None]]


@dataclass(frozen=True)
class BurnIn(_Block):
    """Discarded start of a synoptic record: seconds used, required [s] (None: never), slowest
    significant mode [Hz] and its damping ratio [-], whether enough, where the value came from."""

    seconds: float
    required: float | None
    mode_hz: float | None
    zeta: float | None
    sufficient: bool
    source: str


@dataclass(frozen=True)
class SanityItem(_Block):
    """One line of the frequency-domain sanity check (forces [N] or ratios [-])."""

    reaction: str
    quantity: str
    time_domain: float | None
    time_domain_std: float | None
    frequency_domain: float | None
    allowed_difference: float | None
    ok: bool


@dataclass(frozen=True)
class Davenport(_Block):
    """Davenport closed form of Ry (GF_* None where not applicable); factors [-], f1 [Hz]."""

    reaction: str
    applicable: bool
    note: str
    background_factor: float | None
    resonant_factor: float | None
    peak_factor: float | None
    f1_hz: float | None
    zeta_a: float | None
    GF_Dy: float | None
    GF_QS: float | None
    Cont_R: float | None
    GF_ASCE74: float | None


@dataclass(frozen=True)
class Spectral(_Block):
    """Frequency-domain check: record duration [s], band [Hz], exact linear random vibration per
    reaction (``exact[R][key]``, N or -), the Davenport closed form, the sanity check, and for a
    long line the window the check ran on (``window``: ``spans``, ``first_tower`` 1-based,
    ``estimated_error`` per reaction [-], ``windows`` tried; absent for the whole line)."""

    duration: float | None
    band_hz: list[float | None]
    n_frequencies: int
    exact: dict[str, dict[str, float | None]]
    davenport: Davenport
    not_applicable: dict[str, str]
    sanity_check: tuple[SanityItem, ...] | None = None
    window: dict[str, Any] | None = None  # long lines (issue 20): spans, first_tower, estimated_error, windows

    def to_json(self) -> dict[str, Any]:
        d = super().to_json()
        if self.sanity_check is None:
            del d["sanity_check"]
        if self.window is None:
            del d["window"]
        return d

    def window_text(self) -> str | None:
        """One line on the window a long line's check ran on (issue 20), or None (whole line)."""
        w = self.window
        if w is None:
            return None
        err = w["estimated_error"]
        return (f"long line: estimate 1 on the {w['spans']}-span window from tower {w['first_tower']} "
                f"(windows tried: {', '.join(str(x) for x in w['windows'])} spans); estimated error "
                + ", ".join(f"{r} {100 * (err[r] or 0.0):.2f} %" for r in ("Rx", "Ry", "Rz")))

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Spectral:
        sc = d.get("sanity_check")
        return cls(d["duration"], d["band_hz"], d["n_frequencies"], d["exact"], Davenport.from_json(d["davenport"]),
                   d["not_applicable"], None if sc is None else tuple(SanityItem.from_json(x) for x in sc),
                   d.get("window"))


@dataclass(frozen=True)
class CodeVerdict(_Block):
    """A code's load beside linecheck's peak for one reaction [N], their ratio [-] and the verdict."""

    code_load: float | None
    linecheck_peak: float | None
    ratio: float | None
    verdict: str


@dataclass(frozen=True)
class CodeTower:
    """A tower (1-based ``index``) of a code check: one :class:`CodeVerdict` per reaction."""

    index: int
    reactions: dict[str, CodeVerdict]

    def to_json(self) -> dict[str, Any]:
        return {"index": self.index, **{r: v.to_json() for r, v in self.reactions.items()}}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CodeTower:
        return cls(d["index"], {r: CodeVerdict.from_json(v) for r, v in d.items() if r != "index"})


@dataclass(frozen=True)
class CodeCheck(_Block):
    """One design code beside the run (issue 19): provision, inputs, load per length [N/m], towers."""

    edition: str
    verified: bool
    provision: str
    inputs: dict[str, Any]
    note: str
    load_per_length: float | None
    towers: tuple[CodeTower, ...]

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CodeCheck:
        return cls(d["edition"], d["verified"], d["provision"], d["inputs"], d["note"], d["load_per_length"],
                   tuple(CodeTower.from_json(t) for t in d["towers"]))


@dataclass(frozen=True)
class TimeHistories:
    """Realization ``realization`` (1-based) at the tower of interest: time [s] and per reaction
    the mean M, background B and resonant R parts [N] (``series[R]["M"]``), maybe thinned."""

    realization: int
    decimated: bool
    time: list[float]
    series: dict[str, dict[str, list[float | None]]]

    def to_json(self) -> dict[str, Any]:
        return {"realization": self.realization, "decimated": self.decimated, "time": self.time, **self.series}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> TimeHistories:
        return cls(d["realization"], d["decimated"], d["time"],
                   {r: d[r] for r in REACTIONS if r in d})


@dataclass(frozen=True)
class BatchSource:
    """Where a batch result came from: the case file, its hash (resume) and key changes (``--models``)."""

    case_file: str
    case_hash: str | None
    changes: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {"case_file": self.case_file, "case_hash": self.case_hash}
        if self.changes is not None:
            d["changes"] = self.changes
        return d


@dataclass(frozen=True)
class EnvelopeEntry(_Block):
    """Model-spread envelope of one statistic: the realization mean of largest magnitude and its model."""

    value: float | None
    model: str | None


@dataclass(frozen=True)
class Tower:
    """Tower ``index`` (1-based): support type and its typed reaction blocks.

    ``section`` (section form only, issue 17): the tower's ``name``, ``station``, ``ground``,
    ``height``, ``angle`` [deg], ``insulator_length`` [m] (in force; null at strain towers),
    ``heading`` [deg] (its frame's x axis from the global x: the
    reactions are in that frame) and ``global``: the still-air and step-1 mean reactions in the
    global frame (x along the first span, y to its left, z down)."""

    index: int
    support: str
    reactions: dict[str, ReactionResult]
    section: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {"index": self.index, "support": self.support}
        if self.section is not None:
            d.update(self.section)
        d["reactions"] = _reactions_json(self.reactions)
        return d


@dataclass(frozen=True)
class FailedRun:
    """A case that did not run (batch): its name and the one-line error."""

    case: str
    error: str

    def to_json(self) -> dict[str, Any]:
        return {"case": self.case, "error": self.error}


def models_of(reactions: dict[str, dict[str, ReactionResult]]) -> dict[str, dict[str, EnvelopeEntry]]:
    """Model-spread envelope (issue 15) of each model's reaction blocks at the tower of interest:
    per reaction and statistic, the realization mean of largest magnitude and its model."""
    env: dict[str, dict[str, EnvelopeEntry]] = {}
    for r in REACTIONS:
        env[r] = {}
        for s in STAT_TABLE:
            best, who = None, None
            for name, blk in reactions.items():
                v = blk[r][s.name].mean
                if v is not None and (best is None or abs(v) > abs(best)):
                    best, who = v, name
            env[r][s.name] = EnvelopeEntry(best, who)
    return env


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
#: Optional typed blocks after ``"towers"``, in JSON order (absent from the JSON when None).
BLOCK_FIELDS = ("still_air", "static", "parameters", "burn_in", "damping", "structural_damping", "spectral",
                "codes", "time_histories", "batch", "model", "models", "models_envelope", "models_failed",
                "provenance")
_BATCH_KEYS = ("case_file", "case_hash", "changes")


@dataclass(frozen=True)
class RunDocument:
    """A run result as saved and read by every front end (issue 18).

    ``reactions``: the tower of interest; ``towers[k]``: tower k+1.  Optional blocks (None =
    absent): ``still_air``, ``static`` (step-1 series), ``parameters`` (the case's TOML
    document), ``burn_in``, ``damping``/``structural_damping``, ``spectral``, ``codes`` (per
    code), ``time_histories``, ``batch`` (written as the top-level keys ``"case_file"``,
    ``"case_hash"``, ``"changes"``), ``model``/``models``/``models_envelope``/``models_failed``
    (downburst model spread), ``until``, ``provenance`` (versions, BLAS and compiled kernel of the
    run, :mod:`linecheck.io.provenance`; absent from results saved before it was recorded).
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
    towers: tuple[Tower, ...]
    until: Until | None = None
    still_air: StillAir | None = None
    static: StaticSeries | None = None
    parameters: dict[str, Any] | None = None
    burn_in: BurnIn | None = None
    damping: str | None = None
    structural_damping: float | None = None
    spectral: Spectral | None = None
    codes: dict[str, CodeCheck] | None = None
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

    def to_json(self) -> dict[str, Any]:
        """The public JSON layout (plain dict of JSON values, keys in the documented order)."""
        d: dict[str, Any] = {k: getattr(self, k) for k, _ in HEADER_FIELDS}
        if self.until is not None:
            d["until"] = self.until.to_json()
        d["reactions"] = _reactions_json(self.reactions)
        d["towers"] = [t.to_json() for t in self.towers]
        for k in BLOCK_FIELDS:
            v = getattr(self, k)
            if v is None:
                continue
            if k == "batch":
                d.update(v.to_json())
            elif k == "models":
                d[k] = {m: _reactions_json(blk) for m, blk in v.items()}
            else:
                d[k] = _out(v)
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
        check_schema(d, _schema(), source)  # key path, value, what is allowed: before any value is used
        try:
            head = {k: d[k] for k, _ in HEADER_FIELDS}
            reactions = _reactions_from(d["reactions"])
            towers = tuple(Tower(int(t["index"]), t["support"], _reactions_from(t["reactions"]),
                                 {k: t[k] for k in SECTION_TOWER_KEYS if k in t} or None) for t in d["towers"])
            until = Until.from_json(d["until"]) if d.get("until") is not None else None

            def opt(key: str, read: Any) -> Any:
                return None if d.get(key) is None else read(d[key])

            opts = dict(
                still_air=opt("still_air", StillAir.from_json), static=opt("static", StaticSeries.from_json),
                parameters=d.get("parameters"), burn_in=opt("burn_in", BurnIn.from_json),
                damping=d.get("damping"), structural_damping=d.get("structural_damping"),
                spectral=opt("spectral", Spectral.from_json),
                codes=opt("codes", lambda c: {k: CodeCheck.from_json(v) for k, v in c.items()}),
                time_histories=opt("time_histories", TimeHistories.from_json),
                batch=None if "case_file" not in d else BatchSource(d["case_file"], d.get("case_hash"), d.get("changes")),
                model=d.get("model"), models=opt("models", lambda m: {k: _reactions_from(v) for k, v in m.items()}),
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


def _schema() -> dict[str, Any]:
    """:func:`json_schema`, built once (every document read is checked against it)."""
    global _SCHEMA
    if _SCHEMA is None:
        _SCHEMA = json_schema()
    return _SCHEMA


_SCHEMA: dict[str, Any] | None = None


def load_document(d: Any, *, source: str | None = None) -> RunDocument | FailedRun:
    """A front end's input: a :class:`RunDocument` or :class:`FailedRun` as is, a JSON dict
    through :meth:`RunDocument.from_json` (``{"case", "error"}`` -> :class:`FailedRun`)."""
    if isinstance(d, (RunDocument, FailedRun)):
        return d
    if isinstance(d, dict) and "error" in d and "reactions" not in d:
        return FailedRun(str(d.get("case", "?")), str(d["error"]))
    return RunDocument.from_json(d, source=source)


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
        towers=tuple(Tower(k + 1, case.line.supports[k], reactions_of(summary, k), section_tower(res, k))
                     for k in range(res.system.n_towers)),
        until=until, **blocks,
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

    string_or_null = {"type": ["string", "null"]}
    blas = {"type": "object", "description": "a BLAS library loaded by the run's process: library (openblas, mkl, "
            "blis), version, core (the core kernel OpenBLAS selected for the CPU, e.g. Haswell, SkylakeX), "
            "threads, path of the shared library; null where the library does not say",
            "properties": {"library": {"type": "string"}, "version": string_or_null, "core": string_or_null,
                           "threads": {"type": ["integer", "null"]}, "path": string_or_null},
            "required": ["library", "version", "core", "threads", "path"], "additionalProperties": False}
    piece = {"type": "object", "properties": {"name": {"type": "string"}, "on": {"type": "boolean"},
                                              "reason": {"type": "string"}},
             "required": ["name", "on", "reason"], "additionalProperties": False}
    provenance = {
        "type": "object",
        "description": "where the result was computed (as `linecheck info --json`): versions (numba: \"not "
                       "installed\" when absent), the BLAS numpy calls, the BLAS scipy.linalg calls (null when "
                       "numpy's) and the compiled kernel: Numba installed, LINECHECK_KERNEL mode, and per piece "
                       "whether it ran compiled (reason: why not, \"\" when on); absent from older results",
        "properties": {**{k: {"type": "string"} for k in ("linecheck", "python", "numpy", "scipy", "numba")},
                       "blas": {"$ref": "#/$defs/blas"},
                       "scipy_blas": {**blas, "type": ["object", "null"]},
                       "kernel": {"type": "object",
                                  "properties": {"installed": {"type": "boolean"},
                                                 "mode": {"enum": ["auto", "numpy", "numba"]},
                                                 "pieces": {"type": "array", "items": piece}},
                                  "required": ["installed", "mode", "pieces"], "additionalProperties": False}},
        "required": ["linecheck", "python", "numpy", "scipy", "numba", "blas", "kernel"],
        "additionalProperties": True,
    }

    header = {k: json_type(t) for k, t in HEADER_FIELDS}
    header["schema_version"] = {"const": SCHEMA_VERSION}
    header["tower_of_interest"] = {"type": "integer", "minimum": 1}
    header["spans"] = {"type": "integer", "minimum": 1}
    header["realizations"] = {"type": "integer", "minimum": 1, "maximum": 1_000_000_000}
    header["seed"] = {"type": "integer", "minimum": 0, "maximum": MAX_INTEGER}
    header["windows"] = {"type": "integer", "minimum": 1}
    series = {"type": "array", "items": num_or_null}
    histories = {
        "type": "object", "description": "one realization at the tower of interest: time [s] and per reaction "
        "the mean M, background B and resonant R parts [N], maybe thinned (decimated)",
        "properties": {"realization": {"type": "integer", "minimum": 1}, "decimated": {"type": "boolean"},
                       "time": series,
                       **{r: {"type": "object", "properties": {k: series for k in ("M", "B", "R")},
                              "required": ["M", "B", "R"]} for r in REACTIONS}},
        "required": ["realization", "decimated", "time"]}
    header["wind"] = {"enum": ["synoptic", "downburst"]}
    header["units"] = {"const": "SI"}
    header["design_fractile"] = {"type": "number", "minimum": 0, "maximum": 1}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://github.com/linecheck/linecheck/docs/results.schema.json",
        "title": "linecheck run result",
        "description": ("Result of `linecheck run --json` and of each case of a batch (schema_version "
                        f"{SCHEMA_VERSION}). Forces in N, Cont_* as fractions; null where undefined. "
                        f"Everywhere in the document (linecheck checks it on read): numbers finite and of magnitude "
                        f"at most {MAX_MAGNITUDE:g}, integers of magnitude at most {MAX_INTEGER}, arrays and "
                        f"objects nested at most {MAX_DEPTH} levels. "
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
                               "name": {"type": "string"}, "station": {"type": "number"},
                               "ground": {"type": "number"}, "height": {"type": "number"},
                               "angle": {"type": "number"}, "heading": {"type": "number"},
                               "insulator_length": {"type": ["number", "null"]},
                               "global": {"type": "object", "description": "section form: still-air and "
                                          "step-1 mean reactions [N] in the global frame (x along the first span, "
                                          "y to its left, z down); the tower's reactions are in its own frame, "
                                          "x along heading"},
                               "reactions": {"$ref": "#/$defs/reactions"}},
                "required": ["index", "support", "reactions"], "additionalProperties": False}},
            "still_air": {"type": "object"},
            "static": {"type": "object"},
            "parameters": {"type": "object"},
            "burn_in": {"type": "object"},
            "damping": {"type": "string"},
            "structural_damping": {"type": "number"},
            "spectral": {"type": "object"},
            "time_histories": histories,
            "provenance": {"$ref": "#/$defs/provenance"},
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
            "blas": blas,
            "provenance": provenance,
            **{f"stat_{s.name}": stat_schema(s) for s in STAT_TABLE},
        },
    }
