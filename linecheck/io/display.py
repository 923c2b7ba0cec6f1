"""Display of result statistics shared by the CLI table, the TUI and the Excel sheets (plain Python).

Forces in kN with 3 decimals, Cont_* in % with 1 decimal, ratios with 3 decimals,
``± std`` over realizations when there are several, ``**`` where a gust factor is
undefined (mean zero by symmetry).  Names, labels, units and formats come from the one
statistics table, :data:`linecheck.io.document.STAT_TABLE`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .document import STAT_TABLE


@dataclass(frozen=True)
class Stat:
    """One summary row: JSON key, label, shown unit, scale to the shown unit, format."""

    key: str
    label: str
    unit: str
    scale: float
    fmt: str


SUMMARY_STATS: tuple[Stat, ...] = tuple(
    Stat(s.name, s.label, s.display_unit, s.scale, s.fmt) for s in STAT_TABLE if s.summary)
STAT_ROWS: dict[str, Stat] = {s.name: Stat(s.name, s.label, s.display_unit, s.scale, s.fmt) for s in STAT_TABLE}

FLAG_TEXT = {"recommended": "dynamic analysis recommended",
             "inconclusive": "inconclusive: run more realizations",
             None: ""}
HOW_TO_READ_GF_BELOW_1 = (
    "GF < 1: in this realization set the peak of M + B is below the largest mean. B has zero mean, so "
    "the expected GF_QS is >= 1; a mean below 1 is sampling (downbursts: 20-45 % of single draws). Read "
    "the interval, or run more realizations (--until).")
HOW_TO_READ_NEGATIVE_CONT_BG = (
    "Cont_BG < 0: the background lowered the peak below the largest mean (GF_QS < 1) in these "
    "realizations; it is sampling, not a relief the design can count on.")


def stat_text(entry: dict[str, Any], stat: Stat, n_real: int) -> str:
    """``mean`` (``± std`` when ``n_real`` > 1) of one statistic entry, ``**`` when null."""
    m, s = entry.get("mean"), entry.get("std")
    if m is None:
        return "**"
    text = stat.fmt.format(m * stat.scale)
    if n_real > 1 and s is not None:
        text += " ± " + stat.fmt.format(s * stat.scale)
    return text


def ci_text(entry: dict[str, Any], stat: Stat) -> str:
    """``[low, high]`` of a statistic's 95 % interval in the shown unit, "" when absent or null."""
    ci = entry.get("ci")
    if not ci or ci[0] is None or ci[1] is None:
        return ""
    return "[" + stat.fmt.format(ci[0] * stat.scale) + ", " + stat.fmt.format(ci[1] * stat.scale) + "]"


def design_text(entry: dict[str, Any], stat: Stat) -> str:
    """The Gumbel design value of a peak in the shown unit, "" when absent or null."""
    g = entry.get("gumbel") or {}
    d = g.get("design")
    return "" if d is None else stat.fmt.format(d * stat.scale)


def flag_text(state: str | None) -> str:
    """Words of a ``"dynamic_analysis"`` state."""
    return FLAG_TEXT.get(state, str(state))


def how_to_read(doc: dict[str, Any]) -> list[str]:
    """The "how to read" notes that apply to ``doc`` (GF < 1, negative Cont_BG at the tower of interest)."""
    notes = []
    reactions = doc.get("reactions") or {}
    gf_low = any(((reactions.get(r) or {}).get(k) or {}).get("mean") is not None
                 and reactions[r][k]["mean"] < 1.0 for r in reactions for k in ("GF_Dy", "GF_QS"))
    bg_neg = any(((reactions.get(r) or {}).get("Cont_BG") or {}).get("mean") is not None
                 and reactions[r]["Cont_BG"]["mean"] < 0.0 for r in reactions)
    if gf_low:
        notes.append(HOW_TO_READ_GF_BELOW_1)
    if bg_neg:
        notes.append(HOW_TO_READ_NEGATIVE_CONT_BG)
    return notes


def flag_state(doc: dict[str, Any], reaction: str, threshold: float | None = None) -> str | None:
    """The Cont_R flag state of ``reaction`` at the tower of interest: the document's
    ``"dynamic_analysis"``, or -- with a ``threshold`` other than 10 % (``export
    --cont-r-threshold``) -- the same three-state rule recomputed at that threshold from the
    interval (docs/method.md).  None for a document without intervals (schema 1)."""
    from ..core.extremes import CONT_R_THRESHOLD, MIN_WIND_SHARE

    block = (doc.get("reactions") or {}).get(reaction) or {}
    if threshold is None or threshold == CONT_R_THRESHOLD:
        return block.get("dynamic_analysis")
    ci = (block.get("Cont_R") or {}).get("ci")
    if not ci or ci[0] is None or ci[1] is None or (block.get("GF_Dy") or {}).get("mean") is None:
        return None
    sa = (doc.get("still_air") or {}).get("reactions") or {}
    norm = sum(float(v) ** 2 for v in sa.values() if v is not None) ** 0.5
    peak = (block.get("peak_dynamic") or {}).get("mean")
    if peak is None or peak < MIN_WIND_SHARE * norm:
        return None
    if ci[0] > threshold:
        return "recommended"
    return "inconclusive" if ci[1] > threshold else None
