"""JSON documents of results (a public contract: the key names are part of it).

Forces in N, lengths in m, Cont_* as fractions; no UI imports.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.names import REACTIONS
from ..core.tower_totals import TOTALS
from .atomic import write_text_atomic
from .stat_table import SPECTRAL_EXACT

if TYPE_CHECKING:  # annotations only: importing the service loads the numerical core
    from ..service import StaticResult, WiresStatic


def _num(x: Any) -> Any:
    """Plain JSON numbers (NaN/inf become null)."""
    if isinstance(x, np.ndarray):
        return [_num(v) for v in x.tolist()]
    if isinstance(x, (list, tuple)):
        return [_num(v) for v in x]
    if isinstance(x, (np.floating, float)):
        f = float(x)
        return f if math.isfinite(f) else None
    if isinstance(x, (np.integer,)):
        return int(x)
    return x


def _header(case: Any) -> dict[str, Any]:
    """Keys every result document starts with."""
    return {
        "case": case.name,
        "description": case.description,
        "wind": case.wind.type,
        "units": "SI",
        "tower_of_interest": case.line.tower_of_interest,
    }


def with_provenance(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with the top-level ``"provenance"`` block every result document records
    (:func:`linecheck.io.provenance.provenance`: versions, BLAS, compiled kernel pieces)."""
    from .provenance import provenance

    return {**doc, "provenance": provenance().to_json()}


def _static_tower(case: Any, system: Any, m: Any, R: np.ndarray, R0: np.ndarray, j: int, pick: Any) -> dict[str, Any]:
    """Tower ``j`` (0-based) of the step-1 JSON: support, section metadata, reactions [N] in its own
    frame (total, wind-induced, still air), displacements [m] and on a section the global frame."""
    still = m.still_air
    t: dict[str, Any] = {"index": j + 1, "support": case.line.supports[j]}
    if system.is_section:
        tw = case.line.towers[j]
        t.update(name=tw.name, station=_num(system.stations[j]), ground=tw.ground, height=tw.height,
                 angle=tw.angle, heading=_num(np.degrees(system.tower_headings[j])))
    t.update({
        "Rx": pick(R[:, j, 0]),
        "Ry": pick(R[:, j, 1]),
        "Rz": pick(R[:, j, 2]),
        "Rx_wind": pick(R[:, j, 0] - R0[j, 0]),
        "Ry_wind": pick(R[:, j, 1] - R0[j, 1]),
        "Rz_wind": pick(R[:, j, 2] - R0[j, 2]),
        "Rx_still_air": _num(R0[j, 0]),
        "Ry_still_air": _num(R0[j, 1]),
        "Rz_still_air": _num(R0[j, 2]),
        "dx": pick(m.displacement[:, j, 0]),
        "dy": pick(m.displacement[:, j, 1]),
        "dz": pick(m.displacement[:, j, 2]),
    })
    if system.is_section:  # the global frame too (x along the first span, y to its left, z down)
        t["global"] = {"Rx": pick(m.reactions[:, j, 0]), "Ry": pick(m.reactions[:, j, 1]),
                       "Rz": pick(m.reactions[:, j, 2]),
                       "Rx_still_air": _num(still.reactions[j, 0]), "Ry_still_air": _num(still.reactions[j, 1]),
                       "Rz_still_air": _num(still.reactions[j, 2])}
    return t


def _static_uplift(u: Any, j: int, series: bool) -> dict[str, Any]:
    """Suspension tower ``j``'s ``uplift`` in the step-1 JSON (a :class:`~linecheck.core.uplift.Uplift`):
    ``margin`` [N] (R_z, negative: the insulator would be in compression), ``weight_span`` [m],
    ``held`` (the clamp was held at its still-air point) and the same in ``still_air``; a downburst
    lists margin, weight span and held over the step-1 instants."""
    held = [bool(h) for h in u.held[:, j]]
    return {"margin": _num(u.margin[:, j] if series else u.margin[0, j]),
            "weight_span": _num(u.weight_span[:, j] if series else u.weight_span[0, j]),
            "held": held if series else held[0],
            "still_air": {"margin": _num(u.margin_still_air[j]), "weight_span": _num(u.weight_span_still_air[j]),
                          "held": bool(u.held_still_air[j])}}


def _static_spans(system: Any, m: Any, pick: Any) -> list[dict[str, Any]]:
    """The ``spans`` of the step-1 JSON: each span's mean tension H [N] (``pick``: one value, or a
    list over a downburst's instants), in still air and at clipping-in, and on a section its
    length, unstretched length [m] and heading [deg]."""
    spans = []
    for n in range(system.n_spans):
        sp = {
            "index": n + 1,
            "tension": pick(m.tension[:, n]),
            "tension_still_air": _num(m.still_air.tension[n]),
            "tension_nominal": _num(system.tension_nominal),
        }
        if system.is_section:
            sp.update(length=_num(system.span_lengths[n]), unstretched_length=_num(system.unstretched_lengths[n]),
                      heading=_num(np.degrees(system.span_headings[n])))
        spans.append(sp)
    return spans


def static_to_dict(res: StaticResult) -> dict[str, Any]:
    """Step-1 JSON: ``{"case", "units", "tower_of_interest", "towers": [...], "spans": [...],
    "provenance"}``; every suspension tower has ``"uplift"`` (:func:`_static_uplift`).

    Synoptic: one value per key.  Downburst: every value is a list over the
    step-1 instants and ``"time"`` lists them.
    """
    case, m, system = res.case, res.mean, res.system
    series = case.wind.type == "downburst"

    def pick(a: np.ndarray) -> Any:
        return _num(a if series else a[0])

    still = m.still_air
    # every tower's reactions in its own frame (the equal-span form: the global frame)
    R = system.to_tower_frames(m.reactions)
    R0 = system.to_tower_frames(still.reactions)
    towers = [_static_tower(case, system, m, R, R0, j, pick) for j in range(system.n_towers)]
    from ..analysis.uplift import step1_uplift

    u = step1_uplift(res)
    for j in np.flatnonzero(u.suspension):
        towers[j]["uplift"] = _static_uplift(u, int(j), series)
    doc: dict[str, Any] = {
        **_header(case),
        # the equal-span form's L_u; a section: the total (every span's in "spans")
        "unstretched_length": _num(system.unstretched_lengths.sum() if system.is_section else system.unstretched_length),
        "towers": towers,
        "spans": _static_spans(system, m, pick),
    }
    if series:
        doc["time"] = _num(m.time)
    return with_provenance(doc)


#: Keys of a step-1 tower that place the tower: a case with [[wires]] gives them once per tower,
#: and each attachment the rest of a tower's step-1 keys for its wire.
_TOWER_PLACE_KEYS = ("index", "name", "station", "ground", "angle", "heading")


def wires_static_to_dict(res: WiresStatic) -> dict[str, Any]:
    """Step-1 JSON of a case with ``[[wires]]`` (a :class:`~linecheck.service.WiresStatic`;
    docs/wires.md): ``{"case", ..., "wires": [...], "towers": [...], "provenance"}``.

    ``wires[k]``: ``name``, ``kind``, ``bundle``, ``unstretched_length`` [m] and ``spans`` (as
    the single-wire ``spans``).  ``towers[i]``: its place (``index``, ``name``, ``station``,
    ``ground``, ``angle``, ``heading``, ``type``); ``attachments[j]`` = ``{"wire", "kind", "y",
    "z", ...}`` with the single-wire tower's keys for that wire (``support``, ``height`` (its
    clamp), ``Rx``, ``Ry``, ``Rz``, their ``_wind`` and ``_still_air`` parts [N] in the tower
    frame, ``dx``, ``dy``, ``dz`` [m], ``global``, and ``uplift`` at a suspension attachment);
    ``totals``: ``Fx``, ``Fy``, ``Fz`` [N] and ``Mx``, ``My``, ``Mz`` [N m] about the tower's
    base with their ``_wind`` and ``_still_air`` parts (:func:`~linecheck.core.tower_totals.tower_totals`);
    and the single-wire tower's ``Rx``, ``Ry``, ``Rz`` (and their parts) = the totals' forces, so
    a reader of single-wire documents sees the tower's whole load.  Synoptic: one value per key;
    downburst: lists over the step-1 instants, and ``"time"`` lists them."""
    case = res.case
    series = case.wind.type == "downburst"

    def pick(a: np.ndarray) -> Any:
        return _num(a if series else a[0])

    tot, tot0 = res.totals, res.totals_still_air
    uplifts = [res.uplift(w) for w in range(len(res.wires))]
    towers = []
    for j, tw in enumerate(case.line.towers):
        place = res.wires[0].system
        t: dict[str, Any] = {"index": j + 1, "name": tw.name, "station": _num(place.stations[j]), "ground": tw.ground,
                             "angle": tw.angle, "heading": _num(np.degrees(place.tower_headings[j])), "type": tw.type}
        for c, r in enumerate(("Rx", "Ry", "Rz")):  # the totals' forces under the single-wire keys
            t.update({r: pick(tot[:, j, c]), f"{r}_wind": pick(tot[:, j, c] - tot0[j, c]),
                      f"{r}_still_air": _num(tot0[j, c])})
        attachments = []
        for w, (wire, st) in enumerate(zip(case.wires, res.wires)):
            one = _static_tower(st.case, st.system, st.mean, res.reactions[:, :, w], res.still_air[:, w], j, pick)
            a = {"wire": wire.name, "kind": wire.kind, "y": _num(res.y[j, w]), "z": _num(res.z[j, w]),
                 **{k: v for k, v in one.items() if k not in _TOWER_PLACE_KEYS}}
            if uplifts[w].suspension[j]:
                a["uplift"] = _static_uplift(uplifts[w], j, series)
            attachments.append(a)
        t["attachments"] = attachments
        t["totals"] = {**{k: pick(tot[:, j, c]) for c, k in enumerate(TOTALS)},
                       **{f"{k}_wind": pick(tot[:, j, c] - tot0[j, c]) for c, k in enumerate(TOTALS)},
                       **{f"{k}_still_air": _num(tot0[j, c]) for c, k in enumerate(TOTALS)}}
        towers.append(t)
    wires = [{"name": wire.name, "kind": wire.kind, "bundle": wire.bundle,
              "unstretched_length": _num(st.system.unstretched_lengths.sum()),
              "spans": _static_spans(st.system, st.mean, pick)} for wire, st in zip(case.wires, res.wires)]
    doc: dict[str, Any] = {**_header(case), "wires": wires, "towers": towers}
    if series:
        doc["time"] = _num(res.time)
    return with_provenance(doc)


def modes_to_dict(case: Any, res: Any, *, shapes: bool = False) -> dict[str, Any]:
    """JSON of ``linecheck modes`` (a :class:`~linecheck.service.ModesResult`): the still-air and
    mean-state frequencies [Hz] and dominant directions, the damped modes and those paired with
    the mean-state ones by shape, the mode shapes if ``shapes``, and ``"provenance"``."""
    dirs = "xyz"
    ds, dm = res.still_air.dominant_direction(), res.mean.dominant_direction()
    doc: dict[str, Any] = {
        "case": case.name, "units": "SI",
        "still_air": {"frequencies_hz": _num(res.still_air.frequencies_hz), "direction": [dirs[i] for i in ds]},
        "mean": {"frequencies_hz": _num(res.mean.frequencies_hz), "direction": [dirs[i] for i in dm],
                 "time": res.mean_time,
                 "damped_frequencies_hz": _num(res.damped.frequencies_hz),
                 "damping_ratios": _num(res.damped.damping_ratio),
                 "paired_damped": {"frequencies_hz": _num(res.paired_hz), "damping_ratios": _num(res.paired_ratio),
                                   "mac": _num(res.paired_mac)}},
        "damping": case.analysis.damping}
    if shapes:
        doc["still_air"]["shapes"] = _num(res.still_air.shapes)
        doc["mean"]["shapes"] = _num(res.mean.shapes)
    return with_provenance(doc)


def write_json(path: str | Path, doc: Any, *, force: bool = True) -> Path:
    """Write a JSON document (a dict, or a typed document by its ``to_json()``) atomically."""
    if hasattr(doc, "to_json"):
        doc = doc.to_json()
    return write_text_atomic(path, json.dumps(doc, indent=2, allow_nan=False) + "\n", force=force, what="JSON")


# --------------------------------------------------------------------------- run results
def decimate_keep_peaks(series: np.ndarray, max_points: int) -> np.ndarray:
    """Indices of the min and max of each of ``max_points/2`` blocks of ``series`` (n, k)."""
    n = series.shape[0]
    if n <= max_points:
        return np.arange(n)
    nb = max(1, max_points // 2)
    edges = np.linspace(0, n, nb + 1).astype(int)
    keep = [0, n - 1]
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        blk = series[a:b]
        keep.extend((a + blk.argmin(axis=0)).tolist())
        keep.extend((a + blk.argmax(axis=0)).tolist())
    return np.unique(np.array(keep))


def case_parameters(case: Any) -> dict[str, Any]:
    """The case's inputs as a TOML-like document (for sheets and re-runs)."""
    from ..core.case import case_to_dict

    return case_to_dict(case)


def run_to_dict(res: Any, *, full_histories: bool = False, max_points: int = 2000) -> dict[str, Any]:
    """JSON document of a run: ``run_document(res, ...).to_json()`` (contract,
    :class:`~linecheck.io.document.RunDocument`; layout in docs/results.schema.json)."""
    return run_document(res, full_histories=full_histories, max_points=max_points).to_json()


def run_document(res: Any, *, full_histories: bool = False, max_points: int = 2000) -> Any:
    """The typed :class:`~linecheck.io.document.RunDocument` of a run, what every front end reads.

    Header, ``reactions`` at the tower of interest and ``towers`` (every statistic
    ``{"mean", "std", "se", "p05", "p50", "p95"}``, peaks with ``"gumbel"``, GF_Dy/GF_QS/Cont_R
    with ``"ci"``, each reaction with ``"dynamic_analysis"``), ``until``, and the typed blocks
    ``still_air``, ``static``, ``parameters``, ``burn_in``, ``damping``, ``spectral`` (synoptic,
    with its sanity check), ``codes``, ``time_histories`` and ``provenance`` (versions, BLAS and
    compiled kernel pieces of this process: :mod:`linecheck.io.provenance`).  Forces in N, Cont_* as
    fractions, GF null where the mean vanishes.  Time histories are those of realization 1 at
    the tower of interest, thinned to about ``max_points`` samples keeping every block's
    extremes unless ``full_histories``.
    """
    from .document import BurnInRecord, SanityCheckRow, StaticSeries, StillAir, TimeHistories, document_of
    from .provenance import provenance

    case = res.case
    j = res.tower_index
    still = res.static.mean.still_air
    m = res.static.mean
    still_r = res.system.to_tower_frames(still.reactions)  # the tower's own frame
    wind_r = res.system.to_tower_frames(m.reactions_wind)
    blocks: dict[str, Any] = {
        "still_air": StillAir({r: _num(still_r[j, c]) for c, r in enumerate(REACTIONS)}, _num(still.tension),
                              _num(res.system.tension_nominal), case.line.sag),
        "static": StaticSeries(_num(m.time), {r: _num(wind_r[:, j, c]) for c, r in enumerate(REACTIONS)},
                               _num(m.tension),
                               {k: _num(m.displacement[:, j, c]) for c, k in enumerate(("dx", "dy", "dz"))}),
        "parameters": case_parameters(case),
        "damping": case.analysis.damping,
        "structural_damping": case.analysis.structural_ratio,
    }
    if res.burn_in is not None:
        b = res.burn_in
        blocks["burn_in"] = BurnInRecord(_num(b.seconds), _num(b.required), _num(b.mode_hz), _num(b.zeta), b.sufficient,
                                   b.source)
    if res.spectral is not None:
        from dataclasses import replace

        from ..service import sanity_check

        blocks["spectral"] = replace(spectral_document(res.spectral), sanity_check=tuple(
            SanityCheckRow(it.reaction, it.quantity, _num(it.time_domain), _num(it.time_domain_std),
                       _num(it.frequency_domain), _num(it.allowed), it.ok)
            for it in sanity_check(res)))
    blocks["codes"] = codes_block(res)
    M = res.mean[:, j, :]
    B = res.background[0]
    R = res.resonant[0]
    total = M + B + R
    idx = np.arange(res.time.size) if full_histories else decimate_keep_peaks(np.concatenate([total, M + B], axis=1), max_points)
    blocks["time_histories"] = TimeHistories(
        int(res.realizations[0]) + 1, bool(idx.size < res.time.size), _num(res.time[idx]),
        {r: {"M": _num(M[idx, c]), "B": _num(B[idx, c]), "R": _num(R[idx, c])} for c, r in enumerate(REACTIONS)})
    blocks["provenance"] = provenance()
    return document_of(res, **blocks)


def codes_to_dict(cr: Any) -> dict[str, Any]:
    """JSON of a :class:`~linecheck.service.CodesResult` (contract):
    ``{"ASCE74": {"edition", "verified", "provision", "inputs", "note", "load_per_length",
    "towers": [{"index", "Ry": {"wind_load", "angle_load", "code_load", "linecheck_peak", "ratio",
    "verdict"}}]}, ...}``, N; ``code_load`` = |``wind_load`` + ``angle_load``| (``CodesResult.compared``),
    the two parts absent where the code has no load."""
    out: dict[str, Any] = {}
    for c in cr.checks:
        out[c.code] = {
            "edition": c.edition,
            "verified": bool(c.verified),
            "provision": c.provision,
            "inputs": {k: _num(v) for k, v in c.inputs.items()},
            "note": c.note,
            "load_per_length": _num(c.load_per_length),
            "towers": [{"index": t.index, **{r: _verdict_dict(v) for r, v in t.reactions.items()}} for t in c.towers],
        }
    return out


def _verdict_dict(v: Any) -> dict[str, Any]:
    """One reaction's check (:class:`~linecheck.analysis.code_check.ReactionCheck`) as JSON, N."""
    parts = {k: _num(x) for k, x in (("wind_load", v.wind_load), ("angle_load", v.angle_load)) if x is not None}
    return {**parts, "code_load": _num(v.code_load), "linecheck_peak": _num(v.linecheck_peak), "ratio": _num(v.ratio),
            "verdict": v.verdict}


def codes_block(res: Any) -> dict[str, Any]:
    """The typed ``codes`` block of a run document (per code a
    :class:`~linecheck.io.document.CodeCheckRecord`): the design codes beside the run's peaks; a code
    outside its validity is reported, not raised (``linecheck codes`` raises instead)."""
    from ..service import codes_analysis

    return codes_document(codes_analysis(res.case, res, strict=False))


def codes_document(cr: Any) -> dict[str, Any]:
    """The typed form of :func:`codes_to_dict`: per code a :class:`~linecheck.io.document.CodeCheckRecord`."""
    from .document import CodeCheckRecord

    return {k: CodeCheckRecord.from_json(v) for k, v in codes_to_dict(cr).items()}


def with_models(doc: Any, model: str, reactions: dict[str, Any], failed: dict[str, str] | None = None) -> Any:
    """``doc`` (a :class:`~linecheck.io.document.RunDocument`) with the downburst model spread of
    the downburst model spread: ``model`` (the run shown), ``models`` (each model's typed reaction blocks at the
    tower of interest), ``models_envelope`` and, when some failed, ``models_failed``."""
    from dataclasses import replace

    from .document import models_of

    return replace(doc, model=model, models=dict(reactions), models_envelope=models_of(reactions),
                   models_failed=failed or None)


def model_reactions(results: dict[str, Any]) -> dict[str, Any]:
    """Each model's typed reaction blocks at the tower of interest, from its RunResult."""
    from .document import reactions_of

    return {name: reactions_of(res.summary(), res.tower_index) for name, res in results.items()}


def spectral_to_dict(sp: Any) -> dict[str, Any]:
    """JSON block of a :class:`~linecheck.service.SpectralResult` (reactions at the tower of interest)."""
    ex = sp.exact
    keys = [k for k, _ in SPECTRAL_EXACT]
    exact = {r: {k: _num(getattr(ex, k)[c]) for k in keys} for c, r in enumerate(REACTIONS)}
    d = sp.davenport
    dav = {
        "reaction": "Ry",
        "applicable": bool(sp.davenport_applicable),
        "note": sp.davenport_note,
        "background_factor": _num(d.background),
        "resonant_factor": _num(d.resonant),
        "peak_factor": _num(d.peak_factor),
        "f1_hz": _num(d.f1),
        "zeta_a": _num(d.zeta_a),
        "GF_Dy": _num(d.GF_Dy) if sp.davenport_applicable else None,
        "GF_QS": _num(d.GF_QS) if sp.davenport_applicable else None,
        "Cont_R": _num(d.Cont_R) if sp.davenport_applicable else None,
        "GF_ASCE74": _num(d.GF_ASCE),
    }
    out = {"duration": _num(ex.duration), "band_hz": _num(list(ex.band)), "n_frequencies": ex.n_frequencies,
           "exact": exact, "davenport": dav,
           "not_applicable": {"Rx": "closed form ignores the longitudinal influence line",
                              "Rz": "closed form ignores the vertical influence line"}}
    w = getattr(sp, "window", None)
    if w is not None:  # a long line's check ran on a window; absent for the whole line
        out["window"] = {"spans": int(w.spans), "first_tower": int(w.first_tower) + 1,
                         "estimated_error": {r: _num(w.estimated_error[c]) for c, r in enumerate(REACTIONS)},
                         "windows": [int(x) for x in w.windows]}
    return out


def spectral_document(sp: Any) -> Any:
    """The typed :class:`~linecheck.io.document.Spectral` block of a SpectralResult (no sanity check)."""
    from .document import Davenport, Spectral

    d = spectral_to_dict(sp)
    return Spectral(d["duration"], d["band_hz"], d["n_frequencies"], d["exact"], Davenport.from_json(d["davenport"]),
                    d["not_applicable"], None, d.get("window"))
