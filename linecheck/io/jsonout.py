"""JSON documents of results (public contract: key names are spelled out in the issues).

Forces in N, lengths in m, Cont_* as fractions; no UI imports.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..service import StaticResult
from .atomic import write_text_atomic


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


def static_to_dict(res: StaticResult) -> dict[str, Any]:
    """Step-1 JSON: ``{"case", "units", "tower_of_interest", "towers": [...], "spans": [...]}``.

    Synoptic: one value per key.  Downburst: every value is a list over the
    step-1 instants and ``"time"`` lists them.
    """
    case, m, system = res.case, res.mean, res.system
    series = case.wind.type == "downburst"

    def pick(a: np.ndarray) -> Any:
        return _num(a if series else a[0])

    still = m.still_air
    towers = []
    for j in range(system.n_towers):
        towers.append({
            "index": j + 1,
            "support": case.line.supports[j],
            "Rx": pick(m.reactions[:, j, 0]),
            "Ry": pick(m.reactions[:, j, 1]),
            "Rz": pick(m.reactions[:, j, 2]),
            "Rx_wind": pick(m.reactions[:, j, 0] - still.reactions[j, 0]),
            "Ry_wind": pick(m.reactions[:, j, 1] - still.reactions[j, 1]),
            "Rz_wind": pick(m.reactions[:, j, 2] - still.reactions[j, 2]),
            "Rx_still_air": _num(still.reactions[j, 0]),
            "Ry_still_air": _num(still.reactions[j, 1]),
            "Rz_still_air": _num(still.reactions[j, 2]),
            "dx": pick(m.displacement[:, j, 0]),
            "dy": pick(m.displacement[:, j, 1]),
            "dz": pick(m.displacement[:, j, 2]),
        })
    spans = []
    for n in range(system.n_spans):
        spans.append({
            "index": n + 1,
            "tension": pick(m.tension[:, n]),
            "tension_still_air": _num(still.tension[n]),
            "tension_nominal": _num(system.tension_nominal),
        })
    doc: dict[str, Any] = {
        **_header(case),
        "unstretched_length": _num(system.unstretched_length),
        "towers": towers,
        "spans": spans,
    }
    if series:
        doc["time"] = _num(m.time)
    return doc


def write_json(path: str | Path, doc: dict[str, Any], *, force: bool = True) -> Path:
    """Write a JSON document atomically."""
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


def run_to_dict(res: Any, *, full_histories: bool = False, max_points: int = 2000,
                extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """JSON document of a run: ``run_document(res, ...).to_json()`` (issue 18 contract,
    :class:`~linecheck.io.document.RunDocument`; layout in docs/results.schema.json)."""
    return run_document(res, full_histories=full_histories, max_points=max_points, extra=extra).to_json()


def run_document(res: Any, *, full_histories: bool = False, max_points: int = 2000,
                 extra: dict[str, Any] | None = None) -> Any:
    """The typed :class:`~linecheck.io.document.RunDocument` of a run.

    Typed: the header (``"schema_version"``, ``"case"``, ..., ``"realizations"``, ``"windows"``),
    ``"reactions"`` at the tower of interest and ``"towers"`` (every statistic
    ``{"mean", "std", "se", "p05", "p50", "p95"}``, peaks with ``"gumbel"``, GF_Dy/GF_QS/Cont_R
    with ``"ci"``, each reaction with ``"dynamic_analysis"``), ``"until"``.  Untyped blocks:
    ``"still_air"``, ``"static"``, ``"parameters"``, ``"burn_in"``, ``"damping"``,
    ``"spectral"``, ``"time_histories"`` and any ``extra`` blocks (e.g. ``"codes"``).
    Forces in N, Cont_* as fractions, GF null where the mean vanishes.  Time histories are
    those of realization 1 at the tower of interest, thinned to about ``max_points`` samples
    keeping every block's extremes unless ``full_histories``.
    """
    from ..core.results import REACTIONS
    from .document import document_of

    case = res.case
    j = res.tower_index
    still = res.static.mean.still_air
    m = res.static.mean
    doc: dict[str, Any] = {
        "still_air": {
            "reactions": {r: _num(still.reactions[j, c]) for c, r in enumerate(REACTIONS)},
            "tension": _num(still.tension),
            "tension_nominal": _num(res.system.tension_nominal),
            "sag": case.line.sag,
        },
        "static": {
            "time": _num(m.time),
            "reactions_wind": {r: _num(m.reactions_wind[:, j, c]) for c, r in enumerate(REACTIONS)},
            "tension": _num(m.tension),
            "displacement": {k: _num(m.displacement[:, j, c]) for c, k in enumerate(("dx", "dy", "dz"))},
        },
        "parameters": case_parameters(case),
    }
    if res.burn_in is not None:
        b = res.burn_in
        doc["burn_in"] = {"seconds": _num(b.seconds), "required": _num(b.required), "mode_hz": _num(b.mode_hz),
                          "zeta": _num(b.zeta), "sufficient": b.sufficient, "source": b.source}
    doc["damping"] = case.analysis.damping
    doc["structural_damping"] = case.analysis.structural_ratio
    if res.spectral is not None:
        from ..service import sanity_check

        doc["spectral"] = spectral_to_dict(res.spectral)
        doc["spectral"]["sanity_check"] = [
            {"reaction": it.reaction, "quantity": it.quantity, "time_domain": _num(it.time_domain),
             "time_domain_std": _num(it.time_domain_std), "frequency_domain": _num(it.frequency_domain),
             "allowed_difference": _num(it.allowed), "ok": it.ok}
            for it in sanity_check(res)
        ]
    doc["codes"] = codes_block(res)
    M = res.mean[:, j, :]
    B = res.background[0]
    R = res.resonant[0]
    total = M + B + R
    idx = np.arange(res.time.size) if full_histories else decimate_keep_peaks(np.concatenate([total, M + B], axis=1), max_points)
    doc["time_histories"] = {
        "realization": int(res.realizations[0]) + 1,
        "decimated": bool(idx.size < res.time.size),
        "time": _num(res.time[idx]),
        **{r: {"M": _num(M[idx, c]), "B": _num(B[idx, c]), "R": _num(R[idx, c])} for c, r in enumerate(REACTIONS)},
    }
    if extra:
        doc.update(extra)
    return document_of(res, doc)


def codes_to_dict(cr: Any) -> dict[str, Any]:
    """JSON of a :class:`~linecheck.service.CodesResult` (issue 19 contract):
    ``{"ASCE74": {"edition", "verified", "provision", "inputs", "note", "load_per_length",
    "towers": [{"index", "Ry": {"code_load", "linecheck_peak", "ratio", "verdict"}}]}, ...}``, N."""
    out: dict[str, Any] = {}
    for c in cr.checks:
        out[c.code] = {
            "edition": c.edition,
            "verified": bool(c.verified),
            "provision": c.provision,
            "inputs": {k: _num(v) for k, v in c.inputs.items()},
            "note": c.note,
            "load_per_length": _num(c.load_per_length),
            "towers": [{"index": t.index, **{r: {"code_load": _num(v.code_load), "linecheck_peak": _num(v.linecheck_peak),
                                                 "ratio": _num(v.ratio), "verdict": v.verdict}
                                             for r, v in t.reactions.items()}} for t in c.towers],
        }
    return out


def codes_block(res: Any) -> dict[str, Any]:
    """The ``"codes"`` block of a run document: the design codes beside the run's peaks; a code
    outside its validity is reported, not raised (``linecheck codes`` raises instead)."""
    from ..service import codes_analysis

    return codes_to_dict(codes_analysis(res.case, res, strict=False))


def reactions_block(res: Any, tower: int | None = None) -> dict[str, Any]:
    """``{"Rx": {stat: {...}, "dynamic_analysis"}, "Ry": .., "Rz": ..}`` of one tower (0-based; default
    the tower of interest) of a RunResult: the same typed block as the document's ``"reactions"``
    (issue 18: mean, std, se, fractiles, Gumbel fits, intervals, the Cont_R flag)."""
    from .document import _reactions_json, reactions_of

    return _reactions_json(reactions_of(res.summary(), res.tower_index if tower is None else tower))


def models_block(results: dict[str, Any]) -> dict[str, Any]:
    """Model spread of issue 15: ``{"models": {name: <same as "reactions">}, "models_envelope":
    {R: {stat: {"value", "model"}}}}`` at the tower of interest.  The envelope takes, per
    reaction and statistic, the realization mean of largest magnitude and names its model."""
    return models_from_reactions({name: reactions_block(res) for name, res in results.items()})


def models_from_reactions(models: dict[str, Any]) -> dict[str, Any]:
    """:func:`models_block` from each model's ``"reactions"`` block (e.g. of saved documents)."""
    from ..core.results import REACTIONS, STATISTICS

    env: dict[str, Any] = {}
    for r in REACTIONS:
        env[r] = {}
        for s in STATISTICS:
            best, who = None, None
            for name, blk in models.items():
                v = blk[r][s]["mean"]
                if v is not None and (best is None or abs(v) > abs(best)):
                    best, who = v, name
            env[r][s] = {"value": best, "model": who}
    return {"models": models, "models_envelope": env}


def spectral_to_dict(sp: Any) -> dict[str, Any]:
    """JSON block of a :class:`~linecheck.service.SpectralResult` (reactions at the tower of interest)."""
    from ..core.results import REACTIONS

    ex = sp.exact
    keys = ("mean", "rms_background", "rms_resonant", "rms_fluctuating", "peak_quasi_static", "peak_dynamic",
            "GF_Dy", "GF_QS", "Cont_R", "nu_background", "nu_fluctuating")
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
    return {"duration": _num(ex.duration), "band_hz": _num(list(ex.band)), "n_frequencies": ex.n_frequencies,
            "exact": exact, "davenport": dav,
            "not_applicable": {"Rx": "closed form ignores the longitudinal influence line",
                               "Rz": "closed form ignores the vertical influence line"}}
