"""`static` of a case with ``[[wires]]``: the console tables of every attachment and of the tower
totals, from the step-1 document (:func:`linecheck.io.jsonout.wires_static_to_dict`)."""

from __future__ import annotations

from typing import Any

from rich.markup import escape
from rich.table import Table

from ..core.names import REACTIONS
from ..io.display import TOWER_FRAME, kn
from .common import console

FORCES = ("Fx", "Fy", "Fz")
MOMENTS = ("Mx", "My", "Mz")

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
