"""The typed values and blocks of a run-result document: statistics of a reaction, the Gumbel fit,
the still-air, step-1, burn-in, spectral, design-code, time-history, batch-source and model-spread
blocks, a tower's record with its uplift and a failed run.

Each has ``to_json()`` (the public JSON layout) and, where read back, ``from_json()``; values are
kept exactly as read (a document read and written again is byte for byte the same).  Forces in
N, Cont_* as fractions; no UI imports.  :mod:`linecheck.io.document` assembles them into a
:class:`~linecheck.io.document.RunDocument`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from .stat_table import GUMBEL_KEYS, REACTIONS, STAT_TABLE, SUMMARY_KEYS


# --------------------------------------------------------------------------- typed values
def finite_or_none(x: Any) -> float | None:
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
        return cls(*(finite_or_none(d.get(k)) for k in GUMBEL_KEYS))


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
        return cls(*(finite_or_none(d.get(k)) for k in SUMMARY_KEYS),
                   gumbel=Gumbel.from_json(g) if g is not None else None,
                   ci=(finite_or_none(ci[0]), finite_or_none(ci[1])) if ci is not None else None)


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


def reactions_to_json(block: dict[str, ReactionResult]) -> dict[str, Any]:
    return {r: block[r].to_json() for r in REACTIONS}


def reactions_from_json(d: dict[str, Any]) -> dict[str, ReactionResult]:
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
        return cls(float(d["target"]), finite_or_none(d.get("achieved")), bool(d.get("reached", False)),
                   int(d.get("max_realizations", 0)))


# --------------------------------------------------------------------------- typed blocks
def json_value(v: Any) -> Any:
    """JSON value of a field: sub-documents by their ``to_json``, containers element-wise."""
    if hasattr(v, "to_json"):
        return v.to_json()
    if isinstance(v, dict):
        return {k: json_value(x) for k, x in v.items()}
    if isinstance(v, tuple):
        return [json_value(x) for x in v]
    return v


class _Block:
    """A JSON object whose keys are the dataclass's fields, in order; values are JSON values kept
    exactly as read or written (no float/int coercion: a document read and written again is byte
    for byte the same).  Subclasses with typed members override ``from_json``."""

    def to_json(self) -> dict[str, Any]:
        return {f.name: json_value(getattr(self, f.name)) for f in fields(self)}  # type: ignore[arg-type]

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
class BurnInRecord(_Block):
    """Discarded start of a synoptic record: seconds used, required [s] (None: never), slowest
    significant mode [Hz] and its damping ratio [-], whether enough, where the value came from."""

    seconds: float
    required: float | None
    mode_hz: float | None
    zeta: float | None
    sufficient: bool
    source: str


@dataclass(frozen=True)
class SanityCheckRow(_Block):
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
    sanity_check: tuple[SanityCheckRow, ...] | None = None
    window: dict[str, Any] | None = None  # long lines: spans, first_tower, estimated_error, windows

    def to_json(self) -> dict[str, Any]:
        d = super().to_json()
        if self.sanity_check is None:
            del d["sanity_check"]
        if self.window is None:
            del d["window"]
        return d

    def window_text(self) -> str | None:
        """One line on the window a long line's check ran on, or None (whole line)."""
        w = self.window
        if w is None:
            return None
        err = w["estimated_error"]
        return (f"long line: estimate 1 on the {w['spans']}-span window from tower {w['first_tower']} "
                f"(windows tried: {', '.join(str(x) for x in w['windows'])} spans); estimated error "
                + ", ".join(f"{r} {100 * (err[r] or 0.0):.2f} %" for r in REACTIONS))

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Spectral:
        sc = d.get("sanity_check")
        return cls(d["duration"], d["band_hz"], d["n_frequencies"], d["exact"], Davenport.from_json(d["davenport"]),
                   d["not_applicable"], None if sc is None else tuple(SanityCheckRow.from_json(x) for x in sc),
                   d.get("window"))


@dataclass(frozen=True)
class CodeVerdict(_Block):
    """A code's load beside linecheck's peak for one reaction [N], their ratio [-] and the verdict.

    ``code_load`` = |``wind_load`` + ``angle_load``| (:data:`~linecheck.core.codes.CODES_COMPARED`):
    the code's conductor wind load on the tower's transverse axis [N] and its wind-induced angle
    load [N] (+ where it adds to the wind load; 0 on a straight tower).  Both are absent from the
    JSON where the code has no load, and in results saved before they were recorded.
    """

    code_load: float | None
    linecheck_peak: float | None
    ratio: float | None
    verdict: str
    wind_load: float | None = None
    angle_load: float | None = None

    def to_json(self) -> dict[str, Any]:
        parts = {k: v for k, v in (("wind_load", self.wind_load), ("angle_load", self.angle_load)) if v is not None}
        return {**parts, "code_load": self.code_load, "linecheck_peak": self.linecheck_peak, "ratio": self.ratio,
                "verdict": self.verdict}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CodeVerdict:
        return cls(d["code_load"], d["linecheck_peak"], d["ratio"], d["verdict"], d.get("wind_load"),
                   d.get("angle_load"))


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
class CodeCheckRecord(_Block):
    """One design code beside the run: provision, inputs, load per length [N/m], towers."""

    edition: str
    verified: bool
    provision: str
    inputs: dict[str, Any]
    note: str
    load_per_length: float | None
    towers: tuple[CodeTower, ...]

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CodeCheckRecord:
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
class UpliftRecord(_Block):
    """Uplift at a suspension tower (:mod:`linecheck.core.uplift`): ``margin`` [N], the smallest
    vertical force of the conductor on the clamp (R_z, downward positive; negative: the insulator
    would be in compression) over the step-1 mean states, ``weight_span`` [m] there (margin / W),
    ``time`` [s] its instant, and ``still_air``: ``{"margin", "weight_span"}`` in still air."""

    margin: float | None
    weight_span: float | None
    time: float | None
    still_air: dict[str, float | None]


@dataclass(frozen=True)
class TowerRecord:
    """TowerRecord ``index`` (1-based): support type and its typed reaction blocks.

    ``section`` (section form only): the tower's ``name``, ``station``, ``ground``,
    ``height``, ``angle`` [deg], ``insulator_length`` [m] (in force; null at strain towers),
    ``heading`` [deg] (its frame's x axis from the global x: the
    reactions are in that frame) and ``global``: the still-air and step-1 mean reactions in the
    global frame (x along the first span, y to its left, z down).  ``uplift``: a suspension
    tower's :class:`UpliftRecord` (None, no ``"uplift"`` key: a strain tower, or a result saved
    before it was recorded).

    A run of a case with ``[[wires]]`` (:mod:`linecheck.io.wires_blocks`, docs/wires.md): its
    ``section`` holds the tower's place only (``name``, ``station``, ``ground``, ``angle``,
    ``heading``), ``type`` its tower type, ``reactions`` the totals' forces (Fx, Fy, Fz as Rx,
    Ry, Rz: the tower's whole load for a reader of single-wire results), ``attachments`` one
    :class:`~linecheck.io.wires_blocks.AttachmentRun` per wire, ``totals`` a
    :class:`~linecheck.io.wires_blocks.TotalResult` per total (Fx ... Mz) and ``load_trees`` a
    :class:`~linecheck.io.wires_blocks.LoadTree` per load case; None (absent from the JSON)
    for a single-wire run."""

    index: int
    support: str
    reactions: dict[str, ReactionResult]
    section: dict[str, Any] | None = None
    uplift: UpliftRecord | None = None
    type: str | None = None
    attachments: tuple[Any, ...] | None = None
    totals: dict[str, Any] | None = None
    load_trees: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {"index": self.index, "support": self.support}
        if self.section is not None:
            d.update(self.section)
        if self.type is not None:
            d["type"] = self.type
        if self.uplift is not None:
            d["uplift"] = self.uplift.to_json()
        d["reactions"] = reactions_to_json(self.reactions)
        if self.attachments is not None:
            d["attachments"] = [a.to_json() for a in self.attachments]
        if self.totals is not None:
            d["totals"] = {k: v.to_json() for k, v in self.totals.items()}
        if self.load_trees is not None:
            d["load_trees"] = {k: v.to_json() for k, v in self.load_trees.items()}
        return d


@dataclass(frozen=True)
class FailedRun:
    """A case that did not run (batch): its name and the one-line error."""

    case: str
    error: str

    def to_json(self) -> dict[str, Any]:
        return {"case": self.case, "error": self.error}


def models_of(reactions: dict[str, dict[str, ReactionResult]]) -> dict[str, dict[str, EnvelopeEntry]]:
    """Downburst model-spread envelope of each model's reaction blocks at the tower of interest:
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
