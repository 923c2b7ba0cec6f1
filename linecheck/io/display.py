"""Display of result statistics shared by the CLI table, the TUI and the Excel sheets (plain Python).

Forces in kN with 3 decimals, Cont_* in % with 1 decimal, ratios with 3 decimals,
``± std`` over realizations when there are several, ``**`` where a gust factor is
undefined (mean zero by symmetry).  Names, labels, units and formats come from the one
statistics table, :data:`linecheck.io.stat_table.STAT_TABLE`.  Forces are converted to kN here
(:func:`kn`), the one place for the display unit of a force.
"""

from __future__ import annotations

from typing import Any

from .document import STAT_BY_NAME, STAT_TABLE, StatDef, StatValue

#: Forces are computed in N and shown in kN: a force [N] / N_PER_KN is the force [kN].
N_PER_KN = 1e3


def kn(force: Any) -> Any:
    """A force [N] (a number or an array) in [kN]."""
    return force / N_PER_KN


def kn_text(force: float | None, missing: str = "-", fmt: str = "{:.3f}") -> str:
    """A force [N] as text in [kN] (3 decimals unless ``fmt``); ``missing`` when None."""
    return missing if force is None else fmt.format(kn(force))

#: The statistics of the summary tables (console, TUI, Excel Summary), in table order.
SUMMARY_STATS: tuple[StatDef, ...] = tuple(s for s in STAT_TABLE if s.summary)
#: Every statistic by name (label, display unit, scale, format).
STAT_ROWS: dict[str, StatDef] = STAT_BY_NAME

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
HOW_TO_READ_NEGATIVE_CONT_R = (
    "Cont_R < 0: the dynamic peak max|M+B+R| is below the quasi-static one max|M+B| (GF_Dy < GF_QS): the "
    "resonant part R is out of phase with B at the peak, inertia and damping lowering the response. Typical "
    "of heavily damped (aerodynamic damping) or very flexible systems, whose frequencies lie below the "
    "gusts; a small negative mean is also sampling. Design for the dynamic peak, not the quasi-static one.")

#: The frame every tower's reactions are given in (docs/method.md, "Reactions in tower frames"):
#: the console, the TUI, the JSON and the Excel sheets all use it and name it.
TOWER_FRAME = ("tower frame: x along the line bisector (the mean heading of the tower's two spans; an end "
               "tower: its span's), y = x turned +90 deg in plan (transverse, to the line's left), z down")


def tower_frame_caption(heading: float | None = None, straight: bool = True) -> str:
    """The caption naming the frame of a tower's reactions: :data:`TOWER_FRAME`, with the
    tower's ``heading`` [deg] (its x axis from the global x) when given, and on a line that
    is not straight in plan (``straight`` False) the note that the frames differ per tower."""
    text = TOWER_FRAME
    if heading is not None:
        text += f"; heading {heading:.1f} deg from the global x (the first span)"
    if not straight:
        text += "; each tower in its own frame (the JSON's \"global\" block: x along the first span)"
    return text


def doc_frame_caption(doc: Any) -> str:
    """The frame caption of a run document's tower of interest (a RunDocument): its heading
    when the run is on a section (``towers[].heading``)."""
    towers = getattr(doc, "towers", ()) or ()
    k = doc.tower_of_interest - 1
    section = towers[k].section if 0 <= k < len(towers) else None
    heading = section.get("heading") if section else None
    return tower_frame_caption(heading)


def number_text(value: float | None, stat: StatDef) -> str:
    """``value`` (SI) in the statistic's shown unit and format, "" when None."""
    return "" if value is None else stat.fmt.format(value * stat.scale)


def stat_text(entry: StatValue, stat: StatDef, n_real: int, sep: str = " ± ") -> str:
    """``mean`` (``± std`` when ``n_real`` > 1) of one statistic, ``**`` when undefined."""
    if entry.mean is None:
        return "**"
    text = number_text(entry.mean, stat)
    if n_real > 1 and entry.std is not None:
        text += sep + number_text(entry.std, stat)
    return text


def ci_text(entry: StatValue, stat: StatDef) -> str:
    """``[low, high]`` of a statistic's 95 % interval in the shown unit, "" when absent or null."""
    ci = entry.ci
    if ci is None or ci[0] is None or ci[1] is None:
        return ""
    return "[" + number_text(ci[0], stat) + ", " + number_text(ci[1], stat) + "]"


def design_text(entry: StatValue, stat: StatDef) -> str:
    """The Gumbel design value of a peak in the shown unit, "" when absent or null."""
    return "" if entry.gumbel is None else number_text(entry.gumbel.design, stat)


def flag_text(state: str | None) -> str:
    """Words of a ``"dynamic_analysis"`` state."""
    return FLAG_TEXT.get(state, str(state))


def how_to_read(doc: Any) -> list[str]:
    """The "how to read" notes that apply to ``doc`` (a RunDocument: GF < 1, negative Cont_BG,
    negative Cont_R at the tower of interest)."""
    notes = []
    means = [(k, blk[k].mean) for blk in doc.reactions.values() for k in ("GF_Dy", "GF_QS", "Cont_BG", "Cont_R")
             if k in blk.stats]
    if any(m is not None and m < 1.0 for k, m in means if k in ("GF_Dy", "GF_QS")):
        notes.append(HOW_TO_READ_GF_BELOW_1)
    if any(m is not None and m < 0.0 for k, m in means if k == "Cont_BG"):
        notes.append(HOW_TO_READ_NEGATIVE_CONT_BG)
    if any(m is not None and m < 0.0 for k, m in means if k == "Cont_R"):
        notes.append(HOW_TO_READ_NEGATIVE_CONT_R)
    return notes


def flag_state(doc: Any, reaction: str, threshold: float | None = None) -> str | None:
    """The Cont_R flag state of ``reaction`` at the tower of interest of ``doc`` (a RunDocument):
    its ``dynamic_analysis``, or -- with a ``threshold`` other than 10 % (``export
    --cont-r-threshold``) -- the same three-state rule recomputed at that threshold from the
    interval (docs/method.md)."""
    from ..core.extremes import CONT_R_THRESHOLD, MIN_WIND_SHARE

    block = doc.reactions[reaction]
    if threshold is None or threshold == CONT_R_THRESHOLD:
        return block.dynamic_analysis
    ci = block["Cont_R"].ci
    if ci is None or ci[0] is None or ci[1] is None or block["GF_Dy"].mean is None:
        return None
    sa = doc.still_air.reactions if doc.still_air is not None else {}
    norm = sum(float(v) ** 2 for v in sa.values() if v is not None) ** 0.5
    peak = block["peak_dynamic"].mean
    if peak is None or peak < MIN_WIND_SHARE * norm:
        return None
    if ci[0] > threshold:
        return "recommended"
    return "inconclusive" if ci[1] > threshold else None


# --------------------------------------------------------------------------- uplift
#: What step 1 does at an uplifting suspension tower and what it stops (docs/method.md, "Line sections").
UPLIFT_CONSEQUENCE = ("a suspension insulator there would be in compression: step 1 holds the clamp at its "
                      "still-air point in those states, and run, modes and spectral refuse the case")


def _tower_name(t: Any) -> str:
    """A run document tower's name (a section) or its 1-based index."""
    return str((t.section or {}).get("name") or t.index)


def uplift_run_text(doc: Any) -> str | None:
    """One line on the smallest uplift margin of a run's suspension towers (a RunDocument's
    ``towers[].uplift``), in kN and m; None when no tower records it."""
    rows = [t for t in doc.towers if t.uplift is not None and t.uplift.margin is not None]
    if not rows:
        return None
    t = min(rows, key=lambda r: r.uplift.margin)
    u = t.uplift
    when = f" at t = {u.time:.1f} s" if doc.wind == "downburst" and u.time is not None else ""
    ws = "" if u.weight_span is None else f", weight span {u.weight_span:.1f} m"
    return (f"uplift margin: smallest {kn_text(u.margin)} kN at tower {_tower_name(t)} under the mean wind{when}"
            f"{ws} (still air {kn_text(u.still_air.get('margin'))} kN); every suspension insulator hangs in "
            "tension (every tower: the JSON's towers[].uplift)")


def uplift_static_lines(doc: dict[str, Any]) -> list[str]:
    """One line per suspension tower of a step-1 JSON document (:func:`linecheck.io.jsonout.static_to_dict`)
    whose clamp was held (uplift) in still air or in a mean state: its margins in kN and weight span in m."""
    out = []
    times = doc.get("time")
    for t in doc["towers"]:
        u = t.get("uplift")
        if u is None:
            continue
        held = u["held"] if isinstance(u["held"], list) else [u["held"]]
        margin = u["margin"] if isinstance(u["margin"], list) else [u["margin"]]
        span = u["weight_span"] if isinstance(u["weight_span"], list) else [u["weight_span"]]
        if not (any(held) or u["still_air"]["held"]):
            continue
        k = min(range(len(margin)), key=lambda i: margin[i] if margin[i] is not None else float("inf"))
        when = f" at t = {times[k]:.1f} s" if times else ""
        out.append(f"uplift at tower {t.get('name', t['index'])}: margin {kn_text(u['still_air']['margin'])} kN "
                   f"in still air (weight span {u['still_air']['weight_span']:.1f} m), {kn_text(margin[k])} kN under "
                   f"the mean wind{when} (weight span {span[k]:.1f} m)")
    return out
