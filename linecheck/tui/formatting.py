"""Text of the TUI tables, from the typed run document (:class:`~linecheck.io.document.RunDocument`;
plain Python, no Textual).

The summary shows exactly the values of the JSON document, scaled as the CLI
table does (forces in kN with 3 decimals, Cont_* in % with 1 decimal, ratios
with 3 decimals), ``± std`` over realizations when there are several, and
``**`` where a gust factor is undefined (mean zero by symmetry).
"""

from __future__ import annotations

import math
import tomllib
from typing import Any

from ..core.case import SCHEMA, Case, FieldSpec
from ..core.names import REACTIONS
from ..io.display import (  # noqa: F401  (shared with the CLI)
    STAT_ROWS,
    SUMMARY_STATS,
    ci_text,
    design_text,
    flag_text,
    how_to_read,
    stat_text,
)
from ..io.document import RunDocument, StatDef
from ..io.stat_table import SPECTRAL_EXACT


def summary_rows(doc: RunDocument) -> list[tuple[str, str, str, str, str]]:
    """Rows ``(statistic, unit, Rx, Ry, Rz)`` at the tower of interest."""
    rows = []
    for st in SUMMARY_STATS:
        rows.append((st.label, st.display_unit,
                     *(stat_text(doc.reactions[r][st.name], st, doc.realizations) for r in REACTIONS)))
    return rows + design_rows(doc)


def design_rows(doc: RunDocument) -> list[tuple[str, str, str, str, str]]:
    """Design-statistics rows: Gumbel design peaks (wind-induced and total), 95 % intervals of GF_Dy, GF_QS
    and Cont_R, and the Cont_R flag state, at the tower of interest."""
    reactions = doc.reactions
    p = doc.design_fractile
    rows = []
    for key, label in (("peak_dynamic", f"design peak (p = {p:g})"),
                       ("peak_dynamic_total", f"design total (p = {p:g})")):
        st = STAT_ROWS[key]
        rows.append((label, st.display_unit, *(design_text(reactions[r][key], st) for r in REACTIONS)))
    for key in ("GF_Dy", "GF_QS", "Cont_R"):
        st = STAT_ROWS[key]
        rows.append((f"{st.label} 95 % CI", st.display_unit, *(ci_text(reactions[r][key], st) for r in REACTIONS)))
    rows.append(("dynamic analysis", "", *(flag_text(reactions[r].dynamic_analysis) for r in REACTIONS)))
    return rows


def summary_title(doc: RunDocument) -> str:
    n = doc.realizations
    return (f"{doc.case}: reactions at tower {doc.tower_of_interest} ({doc.wind}, "
            f"V_ref = {doc.v_ref:g} m/s, {n} realization{'s' if n > 1 else ''}, seed {doc.seed})")


def cont_r_flags(doc: RunDocument, state: str = "recommended") -> list[str]:
    """Reactions whose ``dynamic_analysis`` flag is ``state`` ("recommended": the 95 % interval
    of Cont_R lies above :data:`CONT_R_FLAG`; "inconclusive": it straddles it; docs/method.md)."""
    return [r for r in REACTIONS if doc.reactions[r].dynamic_analysis == state]


# --------------------------------------------------------------------------- compare
# Relative differences only from a pinned value of at least this share of the largest pinned
# value of the same unit in the table (the rule that makes a GF "**": a mean below 1 % of the
# largest mean is zero by symmetry, e.g. Rz of a level span, 1e-13 kN).  Below it the relative
# change of a value about zero is meaningless (+2.5e15 %) and Δ is the absolute difference.
REL_FLOOR = 0.01


def _delta(a: float | None, b: float | None, stat: StatDef, floor: float = 0.0) -> str:
    """Change from ``a`` to ``b``: relative (%) when ``|a| >= floor`` [SI units of the row], else
    absolute in the row's unit ("+0.012 kN"); in percentage points for Cont_*; empty when
    undefined or when both values show as zero at the table's precision."""
    if a is None or b is None:
        return ""
    if stat.kind == "fraction":  # contributions: difference in percentage points
        return f"{(b - a) * stat.scale:+.1f} pp"
    shown_zero = 0.5 * 10.0 ** -int(stat.fmt[-3])  # "{:.3f}" -> 0.0005, in display units
    if abs(a * stat.scale) < shown_zero and abs(b * stat.scale) < shown_zero:
        return ""
    if a == 0 or abs(a) < floor:
        unit = "" if stat.display_unit in ("-", "") else f" {stat.display_unit}"
        return stat.fmt.replace("{:", "{:+").format((b - a) * stat.scale) + unit
    return f"{(b - a) / abs(a) * 100:+.1f} %"


def compare_rows(pinned: RunDocument, current: RunDocument) -> list[tuple[str, ...]]:
    """Rows ``(reaction, statistic, unit, pinned, current, Δ)``, grouped by reaction.

    Δ is relative (%) for forces and ratios, absolute where the pinned value is below
    :data:`REL_FLOOR` of the largest pinned value of its unit, in percentage points for Cont_*.
    """
    na, nb = pinned.realizations, current.realizations
    largest: dict[str, float] = {}
    for r in REACTIONS:
        for st in SUMMARY_STATS:
            v = pinned.reactions[r][st.name].mean
            if v is not None and math.isfinite(v):
                largest[st.display_unit] = max(largest.get(st.display_unit, 0.0), abs(v))
    rows = []
    for r in REACTIONS:
        for st in SUMMARY_STATS:
            ea, eb = pinned.reactions[r][st.name], current.reactions[r][st.name]
            rows.append((r, st.label, st.display_unit, stat_text(ea, st, na), stat_text(eb, st, nb),
                         _delta(ea.mean, eb.mean, st, REL_FLOOR * largest.get(st.display_unit, 0.0))))
    return rows


# --------------------------------------------------------------------------- parameters
def iter_fields() -> list[tuple[str, FieldSpec]]:
    """Every case key as ``(dotted key, spec)`` in schema order; the per-tower keys of a section
    ([[line.towers]]) are not keys of the case but cells of its tower table (:func:`tower_differences`)."""
    out = []
    for section, specs in SCHEMA.items():
        if section == "line.towers":
            continue
        for spec in specs:
            out.append((f"{section}.{spec.name}" if section else spec.name, spec))
    return out


# keys that mean something for one wind type only (the other type's table hides them)
ONLY_FOR = {"downburst": ("wind.downburst.", "analysis.mean_states"),
            "synoptic": ("wind.span_speeds", "analysis.burn_in")}


# keys of one form of the line: a section's towers derive the equal-span keys (shown in
# the tower table instead), and an equal-span case has no tower table to go with tension/towers_file
EQUAL_SPAN_KEYS = ("line.spans", "line.span_length", "line.sag", "line.height", "line.supports")
SECTION_KEYS = ("line.tension", "line.towers_file")


def fields_for(wind_type: str, section: bool | None = None) -> list[tuple[str, FieldSpec]]:
    """:func:`iter_fields` without the keys of the other wind type (a synoptic case does not
    list the downburst keys); with ``section`` True, without the equal-span keys the towers
    derive (they are in the tower table); False, without the section form's ``tension`` and
    ``towers_file`` (an equal-span case has no tower table); None, every line key."""
    hidden = tuple(p for t, prefixes in ONLY_FOR.items() if t != wind_type for p in prefixes)
    if section is not None:
        hidden += EQUAL_SPAN_KEYS if section else SECTION_KEYS
    return [(k, spec) for k, spec in iter_fields() if not k.startswith(hidden)]


#: Columns of the TUI tower table: the [[line.towers]] keys (editable) and the derived span.
TOWER_KEYS = ("name", "station", "ground", "height", "support", "angle", "insulator_length")


def tower_dicts(case: Case) -> list[dict[str, Any]]:
    """The towers of a section case as [[line.towers]] tables (keys that are set), for
    :func:`~linecheck.core.case.with_values` (``{"line.towers_file": None, "line.towers": ...}``)."""
    return [{k: getattr(t, k) for k in TOWER_KEYS if getattr(t, k) is not None} for t in case.line.towers or ()]


def tower_key(k: int, column: str) -> str:
    """``line.towers[k+1].column``: the key the case validation names for tower ``k`` (0-based)."""
    return f"line.towers[{k + 1}].{column}"


def tower_differences(a: Case, b: Case) -> list[tuple[str, str, str]]:
    """Tower-table cells that differ: ``(line.towers[k].column, value in a, value in b)``; a
    changed number of towers is one row ``("line.towers", "13 towers", "12 towers")``."""
    ta, tb = a.line.towers or (), b.line.towers or ()
    if ta == tb:
        return []
    if len(ta) != len(tb):
        return [("line.towers", f"{len(ta)} towers", f"{len(tb)} towers")]
    out = []
    for k, (x, y) in enumerate(zip(ta, tb)):
        for col in TOWER_KEYS:
            va, vb = getattr(x, col), getattr(y, col)
            if va != vb:
                out.append((tower_key(k, col), value_text(va) or "(default)", value_text(vb) or "(default)"))
    return out


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
    derived = EQUAL_SPAN_KEYS if a.line.is_section or b.line.is_section else ()  # from the towers
    towers = tower_differences(a, b)
    if towers and a.line.is_section and b.line.is_section:
        derived += ("line.towers_file",)  # an edited tower table is held inline: the cells say what changed
    for dotted, _spec in iter_fields():
        if dotted in derived:
            continue
        va, vb = get_value(a, dotted), get_value(b, dotted)
        if va != vb:
            out.append((dotted, value_text(va) or "(default)", value_text(vb) or "(default)"))
    return out + towers


# --------------------------------------------------------------------------- spectral
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


def _scaled(v: Any, st: StatDef) -> str:
    if v is None or isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "**"
    return st.fmt.format(v * st.scale)


def spectral_compare_rows(doc: RunDocument) -> list[tuple[str, ...]]:
    """Rows ``(statistic, unit, Rx time, Rx freq, Ry time, Ry freq, Rz time, Rz freq)``.

    Time domain: mean over realizations (``doc.reactions``); frequency domain: the exact
    random-vibration estimate (``doc.spectral.exact``).  Empty without a spectral block.
    """
    if doc.spectral is None:
        return []
    exact = doc.spectral.exact
    rows = []
    for fkey, tkey in SPECTRAL_EXACT:
        if tkey is None:  # a frequency-domain quantity only
            continue
        st = STAT_ROWS[tkey]
        row = [st.label if fkey != "mean" else "mean", st.display_unit]
        for r in REACTIONS:
            row.append(_scaled(doc.reactions[r][tkey].mean, st))
            row.append(_scaled(exact[r][fkey], st))
        rows.append(tuple(row))
    return rows


def sanity_rows(doc: RunDocument) -> list[tuple[str, ...]]:
    """Rows ``(reaction, quantity, time domain ± std, frequency domain, allowed, verdict)``."""
    if doc.spectral is None:
        return []
    rows = []
    for it in doc.spectral.sanity_check or ():
        st = STAT_ROWS[it.quantity]
        td = _scaled(it.time_domain, st)
        if it.time_domain_std is not None:
            td += " ± " + _scaled(it.time_domain_std, st)
        rows.append((it.reaction, st.label, td, _scaled(it.frequency_domain, st),
                     "± " + _scaled(it.allowed_difference, st)
                     + (f" {st.display_unit}" if st.display_unit != "-" else ""),
                     "ok" if it.ok else "DIFFERS"))
    return rows


def davenport_lines(doc: RunDocument) -> list[str]:
    """The closed-form (Davenport/Castanheta) estimate in a few lines."""
    if doc.spectral is None:
        return []
    d = doc.spectral.davenport
    out = []
    if d.applicable:
        cont_text = "**" if d.Cont_R is None else f"{100 * d.Cont_R:.1f} %"
        out.append(f"closed form (Davenport/Castanheta), {d.reaction}: GF_Dy {number_text(d.GF_Dy)}, "
                   f"GF_QS {number_text(d.GF_QS)}, Cont_R {cont_text}; "
                   f"ASCE 74 wire GRF {number_text(d.GF_ASCE74)}"
                   + (f" - {d.note}" if d.note else ""))
    else:
        out.append(f"closed form (Davenport/Castanheta), {d.reaction}: not shown - {d.note or 'not applicable'}")
    out += [f"closed form not applicable to {k}: {v}" for k, v in doc.spectral.not_applicable.items()]
    window = doc.spectral.window_text()  # a long line's check ran on a window
    if window:
        out.append(window)
    return out


