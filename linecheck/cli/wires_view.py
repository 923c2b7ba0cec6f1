"""A case with ``[[wires]]`` on the console: `static` (the tables of every attachment and of the
tower totals, from the step-1 document :func:`linecheck.io.jsonout.wires_static_to_dict`) and
`run` (the totals, the attachments and the load trees at the tower of interest, from the run
document :func:`linecheck.io.wires_document.wires_run_document`)."""

from __future__ import annotations

from typing import Any

from rich.markup import escape
from rich.table import Table

from ..core.names import REACTIONS
from ..core.tower_totals import FORCES, MOMENTS, TOTALS
from ..io.display import STAT_ROWS, TOWER_FRAME, design_text, kn, kn_text, number_text, stat_text
from ..io.document import RunDocument, TowerRecord
from .common import console

MOMENT_CAPTION = ("totals: F the sum of the attachments' reactions (tower frame, z down); M the moment about the "
                  "tower's base, right-hand rule about x (along the line), y (left) and z up: Mx = -sum(z Ry + y Rz), "
                  "My = sum z Rx, Mz = -sum y Rx (a wind toward +y gives Mx < 0); \"wind\" the wind-induced part")


def _at(v: Any, k: int) -> float:
    """Value ``k`` of a step-1 entry (a list over the instants of a downburst)."""
    return float(v[k] if isinstance(v, list) else v)


def tower_instant(t: dict[str, Any]) -> int:
    """The step-1 instant shown for tower ``t`` of the document: its largest wind-induced |Fy|
    (0 for a synoptic case: one state)."""
    fy = t["totals"]["Fy_wind"]
    return max(range(len(fy)), key=lambda i: abs(fy[i])) if isinstance(fy, list) else 0


def _weight_span(a: dict[str, Any], k: int) -> str:
    """An attachment's weight span [m] at instant ``k``, ``!`` when its clamp is held; ``-`` at strain."""
    u = a.get("uplift")
    if u is None:
        return "-"
    held = u["held"][k] if isinstance(u["held"], list) else u["held"]
    return f"{_at(u['weight_span'], k):.1f}{' !' if held else ''}"


def attachments_table(doc: dict[str, Any]) -> Table:
    """Every attachment's step-1 reactions (kN) in its tower's frame, one row per tower and wire."""
    table = Table(title=f"{doc['case']}: step-1 mean reactions at every attachment (kN), each tower in its own frame",
                  title_justify="left")
    for col in ("tower", "name", "type", "wire", "support", "y (m)", "z (m)", "weight span (m)", *REACTIONS,
                *(f"{r} wind" for r in REACTIONS)):
        table.add_column(col, justify="left" if col in ("name", "type", "wire") else "right")
    toi = doc["tower_of_interest"]
    for t in doc["towers"]:
        k = tower_instant(t)
        for n, a in enumerate(t["attachments"]):
            first = n == 0
            table.add_row(f"{t['index']}{' *' if t['index'] == toi else ''}" if first else "",
                          escape(t["name"]) if first else "", escape(t["type"]) if first else "", escape(a["wire"]),
                          a["support"], f"{a['y']:g}", f"{a['z']:g}", _weight_span(a, k),
                          *(f"{kn(_at(a[c], k)):.3f}" for c in (*REACTIONS, *(f"{r}_wind" for r in REACTIONS))),
                          end_section=n == len(t["attachments"]) - 1)
    return table


def totals_table(doc: dict[str, Any]) -> Table:
    """Every tower's totals: forces (kN) and moments about its base (kN m), with their wind parts."""
    table = Table(title=f"{doc['case']}: tower totals, forces (kN) and moments about the tower's base (kN m)",
                  title_justify="left")
    cols = (*FORCES, *MOMENTS, *(f"{c} wind" for c in (*FORCES, *MOMENTS)))
    for col in ("tower", "name", "type", *cols):
        table.add_column(col, justify="left" if col in ("name", "type") else "right")
    toi = doc["tower_of_interest"]
    for t in doc["towers"]:
        k, tot = tower_instant(t), t["totals"]
        table.add_row(f"{t['index']}{' *' if t['index'] == toi else ''}", escape(t["name"]), escape(t["type"]),
                      *(f"{kn(_at(tot[c.replace(' ', '_')], k)):.2f}" for c in cols))
    return table


def uplift_doc(doc: dict[str, Any]) -> dict[str, Any]:
    """The step-1 document with one pseudo-tower per suspension attachment (``"T3, wire G"``),
    for :func:`linecheck.io.display.uplift_static_lines`."""
    towers = [{"index": t["index"], "name": f"{t['name']}, wire {a['wire']}", "uplift": a["uplift"]}
              for t in doc["towers"] for a in t["attachments"] if "uplift" in a]
    return {"time": doc.get("time"), "towers": towers}


def print_wires_static(doc: dict[str, Any], straight: bool) -> None:
    """The console report of ``linecheck static`` on a case with ``[[wires]]``: the attachments'
    and the totals' tables, their captions, uplift lines and each wire's span tensions.
    ``straight``: the line is straight in plan (every tower frame is the global frame)."""
    from ..io.display import UPLIFT_CONSEQUENCE, uplift_static_lines

    console.print(attachments_table(doc))
    console.print(totals_table(doc))
    frames = "" if straight else "; each tower in its own frame (the JSON's \"global\" blocks: x along the first span)"
    console.print(f"[dim]* tower of interest; Rx, Ry, Rz total reactions of each wire (its weight included), "
                  f"\"wind\" their wind-induced part; {escape(TOWER_FRAME)}{escape(frames)}; y to the left of the "
                  f"line's centre, z above the tower's ground; {escape(MOMENT_CAPTION)}.[/]", highlight=False)
    lifted = uplift_static_lines(uplift_doc(doc))
    for line in lifted:
        console.print(f"[bold yellow]{escape(line)}[/]", highlight=False, soft_wrap=True)
    if lifted:
        console.print(f"[yellow]! {escape(UPLIFT_CONSEQUENCE)}.[/]", highlight=False, soft_wrap=True)
    series = "time" in doc
    for w in doc["wires"]:
        tens = ", ".join(f"{kn(max(s['tension']) if series else s['tension']):.2f}" for s in w["spans"])
        console.print(f"wire {escape(w['name'])}: span tensions H (kN{', largest over the event' if series else ''}): "
                      f"{tens}   still air: {kn(w['spans'][0]['tension_still_air']):.2f}   H0 at clipping-in: "
                      f"{kn(w['spans'][0]['tension_nominal']):.2f}", highlight=False)
    if series:
        console.print(f"[dim]{len(doc['time'])} mean states over t = {doc['time'][0]:.0f} to {doc['time'][-1]:.0f} s; "
                      "each tower's rows show the instant of its largest wind-induced Fy.[/]")


# --------------------------------------------------------------------------- run
RUN_LEGEND = ("peak Dy: max |M + B + R| of the wind-induced total (its design value: the Gumbel fractile; "
              "\"design total\" with still air); sum: the attachments' own peaks added, as a design adding each "
              "wire's peak would; largest: the largest attachment's peak; peak/sum: the total's mean peak over the "
              "sum's. The totals' histories are the attachments' summed at every instant, so the wires' "
              "correlation is in their peaks.")


def _toi(doc: RunDocument) -> TowerRecord:
    return doc.towers[doc.tower_of_interest - 1]


def _tower_label(t: TowerRecord) -> str:
    name = (t.section or {}).get("name")
    return f"{t.index}" + (f" ({escape(name)})" if name else "")


def run_totals_table(doc: RunDocument) -> Table:
    """The totals at the tower of interest (kN, kN m): the peak with its spread, GF_Dy, Cont_R,
    the design values, the sum and the largest of the attachments' peaks and the ratio."""
    t, n = _toi(doc), doc.realizations
    table = Table(title=f"{doc.case}: tower totals at tower {_tower_label(t)} from the summed histories, forces (kN) "
                        f"and moments about the tower's base (kN m); {n} realization{'s' if n != 1 else ''}",
                  title_justify="left")
    for col in ("total", "mean M", "peak Dy", "GF_Dy", "Cont_R %", "design peak", "design total", "sum of\npeaks",
                "largest\npeak", "peak/sum"):
        table.add_column(col, justify="right", no_wrap=True)
    pk, tot, mean = STAT_ROWS["peak_dynamic"], STAT_ROWS["peak_dynamic_total"], STAT_ROWS["mean_max"]
    for name in TOTALS:
        x = (t.totals or {})[name]
        ratio = "" if x.peak_to_sum is None else f"{x.peak_to_sum:.3f}"
        table.add_row(name, stat_text(x["mean_max"], mean, 1), escape(stat_text(x["peak_dynamic"], pk, n)),
                      stat_text(x["GF_Dy"], STAT_ROWS["GF_Dy"], 1), stat_text(x["Cont_R"], STAT_ROWS["Cont_R"], 1),
                      design_text(x["peak_dynamic"], pk), design_text(x["peak_dynamic_total"], tot),
                      number_text(x.peak_sum.mean, pk), number_text(x.peak_largest.mean, pk), ratio)
    return table


def run_attachments_table(doc: RunDocument) -> Table:
    """Each attachment at the tower of interest: its point and the peaks of its reactions (kN),
    with Ry's design value, GF_Dy and Cont_R."""
    t, n = _toi(doc), doc.realizations
    table = Table(title=f"attachments at tower {_tower_label(t)}: peak Dy of each wire's reactions (kN)",
                  title_justify="left")
    for col in ("wire", "kind", "y (m)", "z (m)", "support", *REACTIONS, "Ry design", "Ry GF_Dy", "Ry Cont_R %"):
        table.add_column(col, justify="left" if col in ("wire", "kind", "support") else "right", no_wrap=True)
    pk = STAT_ROWS["peak_dynamic"]
    for a in t.attachments or ():
        ry = a.reactions["Ry"]
        table.add_row(escape(a.wire), a.kind, f"{a.y:g}", f"{a.z:g}", a.support,
                      *(escape(stat_text(a.reactions[r]["peak_dynamic"], pk, n)) for r in REACTIONS),
                      design_text(ry["peak_dynamic"], pk), stat_text(ry["GF_Dy"], STAT_ROWS["GF_Dy"], 1),
                      stat_text(ry["Cont_R"], STAT_ROWS["Cont_R"], 1))
    return table


def load_tree_table(doc: RunDocument, index: int | None = None) -> Table:
    """Tower ``index``'s (1-based; default the tower of interest) load trees: per load case the
    governing total and every wire's coincident load (kN; vertical down, transverse +y,
    longitudinal +x of the tower frame), the means over the samples."""
    t = doc.towers[(index or doc.tower_of_interest) - 1]
    table = Table(title=f"load trees at tower {_tower_label(t)}: each wire's load at the instant the case's total "
                        "is reached, still air included (kN, mean over the samples)", title_justify="left")
    for col in ("load case", "total", "wire", "vertical", "transverse", "longitudinal"):
        table.add_column(col, justify="left" if col in ("load case", "wire") else "right", no_wrap=True)
    trees = t.load_trees or {}
    for case, tree in trees.items():
        unit = "kN m" if tree.total.startswith("M") else "kN"
        for n, a in enumerate(tree.attachments):
            first = n == 0
            table.add_row(case if first else "", f"{tree.total} {kn_text(tree.value, fmt='{:.2f}')} {unit}" if first
                          else "", escape(a.wire), *(kn_text(a.load[r]) for r in ("Rz", "Ry", "Rx")),
                          end_section=n == len(tree.attachments) - 1)
    return table


def correlation_line(doc: RunDocument) -> str:
    """One line: by how much each total's peak at the tower of interest is below the sum of its
    attachments' peaks (what the correlation saves), with the transverse force and the
    overturning moment in numbers."""
    t = _toi(doc)
    parts = []
    for name in TOTALS:
        x = (t.totals or {})[name]
        if x.peak_to_sum is None:
            parts.append(f"{name} -")
            continue
        text = f"{name} {100.0 * (1.0 - x.peak_to_sum):.1f} %"
        if name in ("Fy", "Mx"):
            unit = "kN" if name == "Fy" else "kN m"
            text += (f" ({kn_text(x['peak_dynamic'].mean, fmt='{:.2f}')} against "
                     f"{kn_text(x.peak_sum.mean, fmt='{:.2f}')} {unit})")
        parts.append(text)
    return (f"correlation at tower {_tower_label(t)}: each total's peak is below the sum of its attachments' peaks "
            f"by {', '.join(parts)}")


def burn_in_lines(doc: RunDocument) -> list[str]:
    """A synoptic run's burn-in per wire in one line, and a note per wire whose record is not
    stationary (what to do)."""
    wires = [w for w in doc.wires or () if w.burn_in is not None]
    if not wires:
        return []
    sources = {w.burn_in.source for w in wires}
    one = len(sources) == 1
    out = [f"[dim]burn-in discarded per wire{f' ({escape(next(iter(sources)))})' if one else ''}: "
           + ", ".join(f"{escape(w.name)} {w.burn_in.seconds:.0f} s" + ("" if one else f" ({escape(w.burn_in.source)})")
                       for w in wires) + "[/]"]
    for w in wires:
        b = w.burn_in
        if not b.sufficient:
            need = "never (undamped)" if b.required is None else f"{b.required:,.0f} s"
            out.append(f"[yellow]note:[/] wire {escape(w.name)}: record not stationary: the {b.mode_hz:.3f} Hz mode "
                       f"(zeta {b.zeta:.2g}) would need a burn-in of {need}, {b.seconds:,.0f} s used; raise "
                       "analysis.duration or analysis.burn_in, or set analysis.structural_damping (docs/method.md, "
                       "Damping).")
    return out


def print_wires_run(doc: RunDocument) -> None:
    """The console report of ``linecheck run`` on a case with ``[[wires]]``: the totals, the
    attachments and the load trees at the tower of interest, what the correlation saves, the
    captions and the burn-in."""
    console.print(run_totals_table(doc))
    console.print(f"[dim]{escape(RUN_LEGEND)} {escape(MOMENT_CAPTION)}.[/]", highlight=False)
    console.print(run_attachments_table(doc))
    console.print(load_tree_table(doc))
    console.print(f"[dim]{escape(TOWER_FRAME)}; y to the left of the line's centre, z above the tower's ground; every "
                  "tower's trees in the JSON (load_trees) and, with --load-trees, the CSV.[/]", highlight=False)
    console.print(escape(correlation_line(doc)), highlight=False, soft_wrap=True)
    for line in burn_in_lines(doc):
        console.print(line, highlight=False, soft_wrap=True)
    console.print("[dim]no frequency-domain check of several wires (the check is of one wire's linear model).[/]",
                  highlight=False)
