"""The run result of a case with ``[[wires]]`` as a :class:`~linecheck.io.document.RunDocument`
(:func:`wires_run_document`), and its load trees as the CSV tower-design programs import
(:func:`load_trees_csv`, :func:`write_load_trees`); docs/wires.md.

The document is a run result (docs/results.schema.json): the header of a single-wire run, the
tower of interest's ``reactions`` and every tower's ``reactions`` = the totals' forces (Fx, Fy,
Fz under Rx, Ry, Rz), and the blocks of :mod:`linecheck.io.wires_blocks`: each tower's
``attachments``, ``totals`` and ``load_trees``, and the ``wires``.  No spectral check, design
codes, still-air or step-1 series or time histories (one-wire blocks).  Forces in N, moments in
N m, the CSV in kN.  No UI imports.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.tower_totals import LOAD_CASES, TOTALS
from .atomic import write_text_atomic
from .display import kn
from .document import RunDocument, reactions_of, stat_value, uplift_of
from .result_blocks import BurnInRecord, ReactionResult, TowerRecord
from .result_blocks import finite_or_none as _f
from .result_schema import SCHEMA_VERSION
from .stat_table import STAT_TABLE
from .wires_blocks import AttachmentRun, LoadTree, TotalResult, TreeLoad, WireRecord

if TYPE_CHECKING:  # annotations only: importing the analysis loads the numerical core
    from ..analysis.wires_run import WiresRun

__all__ = ["LOAD_TREE_COLUMNS", "load_trees_csv", "wires_run_document", "write_load_trees"]

#: The load-tree CSV's columns: the tower's name, the load case, the wire, and the wire's force
#: on the tower [kN]: vertical (R_z, downward +), transverse (R_y, +y of the tower frame: to the
#: left of the line), longitudinal (R_x, +x: along the tower's heading).
LOAD_TREE_COLUMNS = ("structure", "load_case", "attachment", "vertical", "transverse", "longitudinal")


def _totals(res: WiresRun, k: int) -> dict[str, TotalResult]:
    """Tower k's (0-based) totals: each one's statistics and the bounds of its peak."""
    forces, moments = res.totals_summary()
    sums, largest = res.bounds_summary()
    out = {}
    for c, name in enumerate(TOTALS):
        summary = forces if c < 3 else moments
        result = ReactionResult({s.name: stat_value(summary.statistics[s.name], k, c % 3) for s in STAT_TABLE},
                                summary.dynamic_analysis[k, c % 3])
        top, big = stat_value(sums, k, c), stat_value(largest, k, c)
        peak = result["peak_dynamic"].mean

        def ratio(b: float | None, peak: float | None = peak) -> float | None:
            return None if peak is None or not b else _f(peak / b)

        out[name] = TotalResult(result, top, big, ratio(top.mean), ratio(big.mean))
    return out


def _load_trees(res: WiresRun, k: int) -> dict[str, LoadTree]:
    """Tower k's (0-based) load trees: the samples' means and standard deviations."""
    trees = res.load_trees
    mean, std = trees.mean()[k], trees.std()[k]  # (n_cases, n_wires, 3)
    value = trees.value[:, k]  # (n_samples, n_cases)
    value_std = value.std(axis=0, ddof=1) if value.shape[0] > 1 else np.zeros(value.shape[1])
    out = {}
    for c, case in enumerate(trees.cases):
        loads = tuple(TreeLoad(wire, {r: _f(mean[c, w, i]) for i, r in enumerate(("Rx", "Ry", "Rz"))},
                               {r: _f(std[c, w, i]) for i, r in enumerate(("Rx", "Ry", "Rz"))})
                      for w, wire in enumerate(res.wires))
        out[case] = LoadTree(LOAD_CASES[case][0], _f(value[:, c].mean()), _f(value_std[c]), loads)
    return out


def _attachments(res: WiresRun, k: int, summaries: list) -> tuple[AttachmentRun, ...]:
    """Tower k's (0-based) attachments: each wire's point, support, clamp height, statistics and uplift."""
    case = res.case
    tower_type = case.tower_type(case.line.towers[k].type)
    out = []
    for w, wire in enumerate(case.wires):
        a = tower_type.attachment(wire.name)
        st = res.static[w]
        out.append(AttachmentRun(wire.name, wire.kind, _f(a.y), _f(a.z), a.support, _f(st.case.line.towers[k].height),
                                 reactions_of(summaries[w], k), uplift_of(st, k)))
    return tuple(out)


def _wires(res: WiresRun) -> tuple[WireRecord, ...]:
    """The ``wires`` block: each wire's place in the field and its burn-in (synoptic)."""
    out = []
    for w, wire in enumerate(res.case.wires):
        b = res.burn_in[w]
        burn = None if res.case.wind.type != "synoptic" else BurnInRecord(
            _f(b.seconds), _f(b.required), _f(b.mode_hz), _f(b.zeta), bool(b.sufficient), b.source)
        out.append(WireRecord(wire.name, wire.kind, int(wire.bundle),
                              {"y": _f(res.offsets[w, 0]), "z": _f(res.offsets[w, 1])}, burn))
    return tuple(out)


def _tower(res: WiresRun, k: int, forces: Any, summaries: list) -> TowerRecord:
    """Tower k (0-based) of the document."""
    case, system = res.case, res.static[0].system
    tw = case.line.towers[k]
    place = {"name": tw.name, "station": _f(system.stations[k]), "ground": tw.ground, "angle": tw.angle,
             "heading": _f(np.degrees(system.tower_headings[k]))}
    return TowerRecord(k + 1, case.line.supports[k], reactions_of(forces, k), place, None, tw.type,
                       _attachments(res, k, summaries), _totals(res, k), _load_trees(res, k))


def wires_run_document(res: WiresRun) -> RunDocument:
    """The :class:`~linecheck.io.document.RunDocument` of a
    :class:`~linecheck.analysis.wires_run.WiresRun` (module docstring; docs/wires.md).

    Header as a single-wire run's (``g_yp_L`` the sum of the wires' g*_yp L, Eq. 17's
    normalising force of the total forces; ``windows`` per realization), ``reactions`` the
    totals' forces at the tower of interest, ``towers`` with their place, ``type``, the totals'
    forces as ``reactions``, ``attachments``, ``totals`` and ``load_trees``, and the blocks
    ``parameters``, ``damping``, ``structural_damping``, ``wires`` and ``provenance``."""
    from .jsonout import case_parameters
    from .provenance import provenance

    case = res.case
    forces, _ = res.totals_summary()
    summaries = [res.attachment_summary(w) for w in range(len(res.wires))]
    n_real = int(res.realizations.size)
    towers = tuple(_tower(res, k, forces, summaries) for k in range(len(case.line.towers)))
    return RunDocument(
        schema_version=SCHEMA_VERSION, case=case.name, description=case.description, wind=case.wind.type,
        units="SI", tower_of_interest=case.line.tower_of_interest,
        g_yp_L=_f(sum(st.case.g_yp_L for st in res.static)), v_ref=case.wind.v_ref,
        span_length=case.line.span_length, spans=case.line.spans, realizations=n_real, seed=case.analysis.seed,
        duration=_f(res.time[-1] - res.time[0]), time_step=case.analysis.time_step,
        peak_window=case.analysis.peak_window, windows=int(res.forces.n_samples // max(n_real, 1)),
        design_fractile=case.analysis.design_fractile,
        reactions=reactions_of(forces, case.line.tower_of_interest - 1), towers=towers,
        parameters=case_parameters(case), damping=case.analysis.damping,
        structural_damping=case.analysis.structural_ratio, wires=_wires(res), provenance=provenance())


# --------------------------------------------------------------------------- the load-tree CSV
def load_tree_rows(doc: RunDocument) -> list[tuple[str, str, str, float | None, float | None, float | None]]:
    """The CSV's rows: (structure, load case, attachment, vertical, transverse, longitudinal
    [kN]) for every tower, load case (:data:`~linecheck.core.tower_totals.LOAD_CASES` order) and
    wire (the case's order): the load tree's mean loads R_z, R_y, R_x."""
    rows = []
    for t in doc.towers:
        name = (t.section or {}).get("name", str(t.index))
        for case, tree in (t.load_trees or {}).items():
            for a in tree.attachments:
                rows.append((name, case, a.wire, *(None if a.load[r] is None else float(kn(a.load[r]))
                                                   for r in ("Rz", "Ry", "Rx"))))
    return rows


def load_trees_csv(doc: RunDocument) -> str:
    """The load trees of a run of a case with ``[[wires]]`` as CSV text: one comment line
    (``#``: the case, what the loads are, the unit and the sign convention), the header
    :data:`LOAD_TREE_COLUMNS`, then :func:`load_tree_rows` in kN with three decimals.
    ValueError for a document without load trees."""
    if not doc.has_wires:
        raise ValueError(f"result of case {doc.case!r} has no load trees: not a run of a case with [[wires]]")
    n = doc.realizations * (doc.windows or 1)
    over = f"{n} sample{'s' if n != 1 else ''}" + (" (realizations x peak windows)" if (doc.windows or 1) > 1 else
                                                   " (realizations)")
    buf = io.StringIO()
    buf.write(f"# linecheck load trees, case {doc.case} ({doc.wind}, V_ref {doc.v_ref:g} m/s): each wire's force "
              f"on the tower at its attachment at the instant the load case's total is reached, mean over {over}, "
              "still air included; kN; each tower's own frame: vertical downward positive, transverse positive "
              "toward +y (to the left of the line looking along it), longitudinal positive toward +x (along the "
              "tower's heading)\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(LOAD_TREE_COLUMNS)
    for row in load_tree_rows(doc):
        w.writerow([*row[:3], *("" if v is None else f"{v:.3f}" for v in row[3:])])
    return buf.getvalue()


def write_load_trees(path: str | Path, doc: RunDocument, *, force: bool = True) -> Path:
    """Write :func:`load_trees_csv` of ``doc`` to ``path`` atomically (:mod:`linecheck.io.atomic`)."""
    return write_text_atomic(path, load_trees_csv(doc), force=force, what="CSV")
