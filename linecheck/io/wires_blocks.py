"""The typed blocks of a run result of a case with ``[[wires]]`` (docs/wires.md "The JSON of
`linecheck run --json`"): each attachment's reactions, the tower's totals with the bounds of
their peaks, the load trees, and the wires.

A :class:`~linecheck.io.result_blocks.TowerRecord` of such a run carries ``type``,
``attachments`` (:class:`AttachmentRun`, one per wire in the case's order), ``totals``
(:class:`TotalResult` by the names of :data:`~linecheck.core.tower_totals.TOTALS`) and
``load_trees`` (:class:`LoadTree` by the names of
:data:`~linecheck.core.tower_totals.LOAD_CASES`); the document's ``wires`` block lists
:class:`WireRecord`.  Forces in N, moments in N m, lengths in m; tower frame (x along the
tower's heading, y to its left, z down for the forces; moments about the tower's base with z up,
:mod:`linecheck.core.tower_totals`).  A document read and written again is byte for byte the
same (values kept as read).  No UI imports.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..core.tower_totals import LOAD_CASES, TOTALS
from .result_blocks import BurnInRecord, ReactionResult, StatValue, UpliftRecord, reactions_from_json, reactions_to_json

#: The components of an attachment's reaction in a load tree, in JSON order.
TREE_COMPONENTS = ("Rx", "Ry", "Rz")


@dataclass(frozen=True)
class AttachmentRun:
    """``towers[i].attachments[j]``: wire ``wire``'s attachment on the tower.

    ``y`` [m] to the left of the line's centre and ``z`` [m] above the tower's ground (the
    attachment point), ``support`` ("suspension" or "strain"), ``height`` [m] the wire's
    still-air clamp height, ``reactions``: Rx, Ry, Rz with every statistic of a single-wire
    run's reaction [N] (:class:`~linecheck.io.result_blocks.ReactionResult`), ``uplift`` at a
    suspension attachment (the wire's step-1 uplift, as a single-wire run's tower)."""

    wire: str
    kind: str
    y: float
    z: float
    support: str
    height: float | None
    reactions: dict[str, ReactionResult]
    uplift: UpliftRecord | None = None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {"wire": self.wire, "kind": self.kind, "y": self.y, "z": self.z, "support": self.support,
                             "height": self.height}
        if self.uplift is not None:
            d["uplift"] = self.uplift.to_json()
        d["reactions"] = reactions_to_json(self.reactions)
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> AttachmentRun:
        return cls(d["wire"], d["kind"], d["y"], d["z"], d["support"], d.get("height"),
                   reactions_from_json(d["reactions"]),
                   UpliftRecord.from_json(d["uplift"]) if d.get("uplift") is not None else None)


@dataclass(frozen=True)
class TotalResult:
    """``towers[i].totals[name]``: one total of the tower (``name`` one of
    :data:`~linecheck.core.tower_totals.TOTALS`), from the summed histories.

    ``result``: every statistic of a reaction (:class:`~linecheck.io.result_blocks.ReactionResult`:
    mean_max, r.m.s., peaks with their Gumbel design values, GF_Dy, GF_QS, Cont_M/BG/R, the
    flag) [N or N m]; ``peak_sum``: the sum over the attachments of their own peak_dynamic and
    ``peak_largest`` the largest of them, per sample, summarised like a peak (with a Gumbel fit);
    ``peak_to_sum`` and ``peak_to_largest`` [-]: the mean of the total's peak_dynamic over the
    mean of each (at most 1 and, but for torsion with arms on both sides, at least 1)."""

    result: ReactionResult
    peak_sum: StatValue
    peak_largest: StatValue
    peak_to_sum: float | None
    peak_to_largest: float | None

    def __getitem__(self, name: str) -> StatValue:
        return self.result[name]

    @property
    def dynamic_analysis(self) -> str | None:
        return self.result.dynamic_analysis

    def to_json(self) -> dict[str, Any]:
        return {**self.result.to_json(), "peak_sum": self.peak_sum.to_json(),
                "peak_largest": self.peak_largest.to_json(), "peak_to_sum": self.peak_to_sum,
                "peak_to_largest": self.peak_to_largest}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> TotalResult:
        return cls(ReactionResult.from_json(d), StatValue.from_json(d["peak_sum"]),
                   StatValue.from_json(d["peak_largest"]), d.get("peak_to_sum"), d.get("peak_to_largest"))


def totals_to_json(totals: dict[str, TotalResult]) -> dict[str, Any]:
    return {k: totals[k].to_json() for k in TOTALS}


def totals_from_json(d: dict[str, Any]) -> dict[str, TotalResult]:
    return {k: TotalResult.from_json(d[k]) for k in TOTALS}


@dataclass(frozen=True)
class TreeLoad:
    """One attachment's load in a load tree: wire ``wire``'s reaction on the tower at the instant
    the governing total is reached, averaged over the samples (``load``: Rx, Ry, Rz [N], tower
    frame, z down, still air included) with its sample standard deviation (``std``)."""

    wire: str
    load: dict[str, float | None]
    std: dict[str, float | None]

    def to_json(self) -> dict[str, Any]:
        return {"wire": self.wire, **{c: self.load[c] for c in TREE_COMPONENTS},
                **{f"{c}_std": self.std[c] for c in TREE_COMPONENTS}}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> TreeLoad:
        return cls(d["wire"], {c: d[c] for c in TREE_COMPONENTS}, {c: d[f"{c}_std"] for c in TREE_COMPONENTS})


@dataclass(frozen=True)
class LoadTree:
    """``towers[i].load_trees[case]``: the coincident attachment loads of one load case
    (:data:`~linecheck.core.tower_totals.LOAD_CASES`).

    ``total``: the governing total's name ("Fy" for max_transverse); ``value``: that total at
    its instant, still air included [N or N m], the mean over the samples (realizations x peak
    windows) and ``value_std`` its standard deviation; ``attachments``: every wire's
    :class:`TreeLoad` in the case's wire order.  The loads add up to the value: the forces'
    sum, or their moments' (:func:`~linecheck.core.tower_totals.tower_totals` at the
    attachments' points), in every sample and so in the mean."""

    total: str
    value: float | None
    value_std: float | None
    attachments: tuple[TreeLoad, ...]

    def to_json(self) -> dict[str, Any]:
        return {"total": self.total, "value": self.value, "value_std": self.value_std,
                "attachments": [a.to_json() for a in self.attachments]}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> LoadTree:
        return cls(d["total"], d["value"], d["value_std"], tuple(TreeLoad.from_json(a) for a in d["attachments"]))


def load_trees_to_json(trees: dict[str, LoadTree]) -> dict[str, Any]:
    return {k: trees[k].to_json() for k in LOAD_CASES}


def load_trees_from_json(d: dict[str, Any]) -> dict[str, LoadTree]:
    return {k: LoadTree.from_json(d[k]) for k in LOAD_CASES}


@dataclass(frozen=True)
class WireRecord:
    """``wires[k]``: wire k of the run: ``name``, ``kind``, ``bundle`` (sub-conductors),
    ``field_offset``: ``{"y", "z"}`` [m], its place in the one turbulence field (its attachment's
    y at the tower of interest and its still-air clamp height there: the coherence across the
    line and in height), and ``burn_in``: its record's discarded start (None: a downburst)."""

    name: str
    kind: str
    bundle: int
    field_offset: dict[str, float]
    burn_in: BurnInRecord | None

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "bundle": self.bundle, "field_offset": self.field_offset,
                "burn_in": None if self.burn_in is None else self.burn_in.to_json()}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> WireRecord:
        b = d.get("burn_in")
        return cls(d["name"], d["kind"], d["bundle"], d["field_offset"],
                   None if b is None else BurnInRecord.from_json(b))
