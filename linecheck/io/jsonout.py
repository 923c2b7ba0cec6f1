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
        "case": case.name,
        "description": case.description,
        "wind": case.wind.type,
        "units": "SI",
        "tower_of_interest": case.line.tower_of_interest,
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
