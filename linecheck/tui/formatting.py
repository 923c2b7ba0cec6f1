"""Text of the TUI tables, from the ``run_to_dict`` JSON document (plain Python, no Textual).

The summary shows exactly the values of the JSON document, scaled as the CLI
table does (forces in kN with 3 decimals, Cont_* in % with 1 decimal, ratios
with 3 decimals), ``± std`` over realizations when there are several, and
``**`` where a gust factor is undefined (mean zero by symmetry).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from typing import Any

from ..core.case import SCHEMA, Case, FieldSpec
from ..io.display import (  # noqa: F401  (shared with the CLI)
    STAT_ROWS,
    SUMMARY_STATS,
    Stat,
    ci_text,
    design_text,
    flag_text,
    how_to_read,
    stat_text,
)

REACTIONS = ("Rx", "Ry", "Rz")
CONT_R_FLAG = 0.10  # Cont_R above this: "dynamic analysis recommended" (paper's conclusion)


def summary_rows(doc: dict[str, Any]) -> list[tuple[str, str, str, str, str]]:
    """Rows ``(statistic, unit, Rx, Ry, Rz)`` at the tower of interest."""
    n = int(doc.get("realizations", 1))
    rows = []
    for st in SUMMARY_STATS:
        rows.append((st.label, st.unit, *(stat_text(doc["reactions"][r][st.key], st, n) for r in REACTIONS)))
    return rows + design_rows(doc)


def design_rows(doc: dict[str, Any]) -> list[tuple[str, str, str, str, str]]:
    """Issue 18 rows: Gumbel design peaks (wind-induced and total), 95 % intervals of GF_Dy, GF_QS
    and Cont_R, and the Cont_R flag state, at the tower of interest (empty for an old document)."""
    reactions = doc["reactions"]
    if "dynamic_analysis" not in reactions.get("Ry", {}):
        return []
    p = doc.get("design_fractile", 0.5)
    rows = []
    for key, label in (("peak_dynamic", f"design peak (p = {p:g})"),
                       ("peak_dynamic_total", f"design total (p = {p:g})")):
        st = STAT_ROWS[key]
        rows.append((label, st.unit, *(design_text(reactions[r][key], st) for r in REACTIONS)))
    for key in ("GF_Dy", "GF_QS", "Cont_R"):
        st = STAT_ROWS[key]
        rows.append((f"{st.label} 95 % CI", st.unit, *(ci_text(reactions[r][key], st) for r in REACTIONS)))
    rows.append(("dynamic analysis", "", *(flag_text(reactions[r].get("dynamic_analysis")) for r in REACTIONS)))
    return rows


def summary_title(doc: dict[str, Any]) -> str:
    n = int(doc.get("realizations", 1))
    return (f"{doc['case']}: reactions at tower {doc['tower_of_interest']} ({doc['wind']}, "
            f"V_ref = {doc['v_ref']:g} m/s, {n} realization{'s' if n > 1 else ''}, seed {doc.get('seed')})")


def cont_r_flags(doc: dict[str, Any], state: str = "recommended") -> list[str]:
    """Reactions whose ``"dynamic_analysis"`` flag is ``state`` ("recommended": the 95 % interval
    of Cont_R lies above :data:`CONT_R_FLAG`; "inconclusive": it straddles it; docs/method.md)."""
    return [r for r in REACTIONS if doc["reactions"][r].get("dynamic_analysis") == state]


# --------------------------------------------------------------------------- compare
# Relative differences only from a pinned value of at least this share of the largest pinned
# value of the same unit in the table (the rule that makes a GF "**": a mean below 1 % of the
# largest mean is zero by symmetry, e.g. Rz of a level span, 1e-13 kN).  Below it the relative
# change of a value about zero is meaningless (+2.5e15 %) and Δ is the absolute difference.
REL_FLOOR = 0.01


def _delta(a: float | None, b: float | None, stat: Stat, floor: float = 0.0) -> str:
    """Change from ``a`` to ``b``: relative (%) when ``|a| >= floor`` [SI units of the row], else
    absolute in the row's unit ("+0.012 kN"); in percentage points for Cont_*; empty when
    undefined or when both values show as zero at the table's precision."""
    if a is None or b is None:
        return ""
    if stat.unit == "%":  # contributions: difference in percentage points
        return f"{(b - a) * stat.scale:+.1f} pp"
    shown_zero = 0.5 * 10.0 ** -int(stat.fmt[-3])  # "{:.3f}" -> 0.0005, in display units
    if abs(a * stat.scale) < shown_zero and abs(b * stat.scale) < shown_zero:
        return ""
    if a == 0 or abs(a) < floor:
        unit = "" if stat.unit in ("-", "") else f" {stat.unit}"
        return stat.fmt.replace("{:", "{:+").format((b - a) * stat.scale) + unit
    return f"{(b - a) / abs(a) * 100:+.1f} %"


def compare_rows(pinned: dict[str, Any], current: dict[str, Any]) -> list[tuple[str, ...]]:
    """Rows ``(reaction, statistic, unit, pinned, current, Δ)``, grouped by reaction.

    Δ is relative (%) for forces and ratios, absolute where the pinned value is below
    :data:`REL_FLOOR` of the largest pinned value of its unit, in percentage points for Cont_*.
    """
    na, nb = int(pinned.get("realizations", 1)), int(current.get("realizations", 1))
    largest: dict[str, float] = {}
    for r in REACTIONS:
        for st in SUMMARY_STATS:
            v = pinned["reactions"][r][st.key].get("mean")
            if v is not None and math.isfinite(v):
                largest[st.unit] = max(largest.get(st.unit, 0.0), abs(v))
    rows = []
    for r in REACTIONS:
        for st in SUMMARY_STATS:
            ea, eb = pinned["reactions"][r][st.key], current["reactions"][r][st.key]
            rows.append((r, st.label, st.unit, stat_text(ea, st, na), stat_text(eb, st, nb),
                         _delta(ea.get("mean"), eb.get("mean"), st, REL_FLOOR * largest.get(st.unit, 0.0))))
    return rows


# --------------------------------------------------------------------------- parameters
def iter_fields() -> list[tuple[str, FieldSpec]]:
    """Every case key as ``(dotted key, spec)`` in schema order."""
    out = []
    for section, specs in SCHEMA.items():
        for spec in specs:
            out.append((f"{section}.{spec.name}" if section else spec.name, spec))
    return out


# keys that mean something for one wind type only (the other type's table hides them)
ONLY_FOR = {"downburst": ("wind.downburst.", "analysis.mean_states"),
            "synoptic": ("wind.span_speeds", "analysis.burn_in")}


def fields_for(wind_type: str) -> list[tuple[str, FieldSpec]]:
    """:func:`iter_fields` without the keys of the other wind type (a synoptic case does not
    list the downburst keys)."""
    hidden = tuple(p for t, prefixes in ONLY_FOR.items() if t != wind_type for p in prefixes)
    return [(k, spec) for k, spec in iter_fields() if not k.startswith(hidden)]


def get_value(case: Case, dotted: str) -> Any:
    """The value of ``dotted`` in ``case`` (``None`` when unset or derived)."""
    *path, key = dotted.split(".")
    obj: Any = case
    for p in path:
        obj = getattr(obj, p, None)
        if obj is None:
            return None
    return getattr(obj, key, None)


def value_text(value: Any) -> str:
    """Editable text of a value (TOML-like; strings unquoted)."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}" if abs(value) < 1e15 and float(f"{value:g}") == value else repr(value)
    if isinstance(value, (tuple, list)):
        return ", ".join(value_text(v) for v in value)
    return str(value)


def parse_value(spec: FieldSpec, text: str) -> Any:
    """Typed text to a Python value for :func:`~linecheck.core.case.with_value`.

    Numbers and lists are read as TOML values (``20``, ``2e5``, ``[1, 2]`` or ``1, 2``);
    strings need no quotes.  Text that does not parse is passed on as a string so the
    case validation gives its usual message ("value "abc" is not allowed: ...").
    Empty text means "not set" (``None``): the default applies.
    """
    text = text.strip()
    if not text:
        return None
    if spec.kind in ("str", "choice"):
        if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
            return text[1:-1]
        return text
    if spec.kind == "str_list":
        inner = text[1:-1] if text.startswith("[") and text.endswith("]") else text
        items = [i.strip().strip("\"'") for i in inner.split(",")]
        return [i for i in items if i]
    src = text if spec.kind != "float_list" or text.startswith("[") else f"[{text}]"
    try:
        return tomllib.loads(f"v = {src}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def case_differences(a: Case, b: Case) -> list[tuple[str, str, str]]:
    """Keys whose values differ: ``(dotted key, value in a, value in b)``."""
    out = []
    for dotted, _spec in iter_fields():
        va, vb = get_value(a, dotted), get_value(b, dotted)
        if va != vb:
            out.append((dotted, value_text(va) or "(default)", value_text(vb) or "(default)"))
    return out


# --------------------------------------------------------------------------- spectral
def flatten(block: Any, prefix: str = "") -> list[tuple[str, Any]]:
    """Scalar leaves of a nested JSON block as ``(dotted path, value)`` (lists of numbers skipped)."""
    out: list[tuple[str, Any]] = []
    if isinstance(block, dict):
        for k, v in block.items():
            out.extend(flatten(v, f"{prefix}.{k}" if prefix else str(k)))
    elif isinstance(block, list):
        if block and all(isinstance(v, dict) for v in block):
            for i, v in enumerate(block):
                out.extend(flatten(v, f"{prefix}[{i}]"))
    else:
        out.append((prefix, block))
    return out


def number_text(v: Any) -> str:
    if v is None:
        return "**"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    if isinstance(v, int):
        return str(v)
    if not math.isfinite(v):
        return "**"
    return f"{v:.4g}" if abs(v) < 1e4 else f"{v:.6g}"


SPECTRAL_STATS: tuple[tuple[str, str], ...] = (  # (frequency-domain key, time-domain key)
    ("mean", "mean_max"),
    ("rms_background", "rms_background"),
    ("rms_resonant", "rms_resonant"),
    ("rms_fluctuating", "rms_fluctuating"),
    ("peak_quasi_static", "peak_quasi_static"),
    ("peak_dynamic", "peak_dynamic"),
    ("GF_Dy", "GF_Dy"),
    ("GF_QS", "GF_QS"),
    ("Cont_R", "Cont_R"),
)


def stat_of(key: str) -> Stat:
    """Display rule of a statistic name (forces in kN, Cont in %, ratios as they are)."""
    for st in SUMMARY_STATS:
        if st.key == key:
            return st
    if key.startswith(("rms", "peak", "mean")):
        return Stat(key, key.replace("_", " "), "kN", 1e-3, "{:.3f}")
    if key.startswith("Cont"):
        return Stat(key, key, "%", 100.0, "{:.1f}")
    if key.startswith("nu_"):
        return Stat(key, key, "Hz", 1.0, "{:.3f}")
    return Stat(key, key, "-", 1.0, "{:.3f}")


def _scaled(v: Any, st: Stat) -> str:
    if v is None or isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "**"
    return st.fmt.format(v * st.scale)


def spectral_compare_rows(doc: dict[str, Any]) -> list[tuple[str, ...]]:
    """Rows ``(statistic, unit, Rx time, Rx freq, Ry time, Ry freq, Rz time, Rz freq)``.

    Time domain: mean over realizations (``doc["reactions"]``); frequency domain: the
    exact random-vibration estimate (``doc["spectral"]["exact"]``).  Empty when absent.
    """
    exact = (doc.get("spectral") or {}).get("exact")
    if not isinstance(exact, dict):
        return []
    rows = []
    for fkey, tkey in SPECTRAL_STATS:
        st = stat_of(tkey)
        row = [st.label if fkey != "mean" else "mean", st.unit]
        for r in REACTIONS:
            td = doc.get("reactions", {}).get(r, {}).get(tkey, {})
            row.append(_scaled(td.get("mean") if isinstance(td, dict) else None, st))
            row.append(_scaled((exact.get(r) or {}).get(fkey), st))
        rows.append(tuple(row))
    return rows


def sanity_rows(doc: dict[str, Any]) -> list[tuple[str, ...]]:
    """Rows ``(reaction, quantity, time domain ± std, frequency domain, allowed, verdict)``."""
    items = (doc.get("spectral") or {}).get("sanity_check")
    if not isinstance(items, list):
        return []
    rows = []
    for it in items:
        if not isinstance(it, dict):
            continue
        st = stat_of(str(it.get("quantity", "")))
        td = _scaled(it.get("time_domain"), st)
        if it.get("time_domain_std") is not None:
            td += " ± " + _scaled(it.get("time_domain_std"), st)
        rows.append((str(it.get("reaction", "")), st.label, td, _scaled(it.get("frequency_domain"), st),
                     "± " + _scaled(it.get("allowed_difference"), st) + (f" {st.unit}" if st.unit != "-" else ""),
                     "ok" if it.get("ok") else "DIFFERS"))
    return rows


def davenport_lines(doc: dict[str, Any]) -> list[str]:
    """The closed-form (Davenport/Castanheta) estimate in a few lines."""
    sp = doc.get("spectral") or {}
    d = sp.get("davenport")
    out = []
    if isinstance(d, dict):
        r = d.get("reaction", "Ry")
        if d.get("applicable"):
            cont = d.get("Cont_R")
            cont_text = "**" if cont is None else f"{100 * cont:.1f} %"
            out.append(f"closed form (Davenport/Castanheta), {r}: GF_Dy {number_text(d.get('GF_Dy'))}, "
                       f"GF_QS {number_text(d.get('GF_QS'))}, Cont_R {cont_text}; "
                       f"ASCE 74 wire GRF {number_text(d.get('GF_ASCE74'))}"
                       + (f" - {d['note']}" if d.get("note") else ""))
        else:
            out.append(f"closed form (Davenport/Castanheta), {r}: not shown - {d.get('note') or 'not applicable'}")
    na = sp.get("not_applicable")
    if isinstance(na, dict):
        out += [f"closed form not applicable to {k}: {v}" for k, v in na.items()]
    return out


def spectral_rows(doc: dict[str, Any]) -> list[tuple[str, str, str]]:
    """Fallback rows ``(quantity, spectral value, time-domain value)`` of any ``"spectral"`` block.

    Used when the block has neither ``exact`` nor ``sanity_check``: every scalar is listed;
    where its path names a reaction (Rx/Ry/Rz) and a statistic of the time-domain
    document, the time-domain mean is shown beside it.  Values as stored (SI).
    """
    block = doc.get("spectral")
    if not isinstance(block, dict):
        return []
    rows = []
    for path, value in flatten(block):
        parts = path.replace("[", ".").replace("]", "").split(".")
        td = ""
        r = next((p for p in parts if p in REACTIONS), None)
        s = parts[-1]
        if r is not None:
            entry = doc.get("reactions", {}).get(r, {}).get(s)
            if isinstance(entry, dict):
                td = number_text(entry.get("mean"))
        rows.append((path, number_text(value), td))
    return rows
