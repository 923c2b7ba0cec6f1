"""Text of the TUI's "Load trees" tab: a run of a case with ``[[wires]]`` (docs/wires.md), from its
typed document (:class:`~linecheck.io.document.RunDocument` with the blocks of
:mod:`linecheck.io.wires_blocks`).  Plain Python, no Textual.

Forces in kN, moments in kN m, three decimals (the CSV's), ``± std`` over the samples; the load
trees in the CSV's columns and sign convention (vertical downward positive, transverse +y,
longitudinal +x of each tower's frame)."""

from __future__ import annotations

from ..core.tower_totals import LOAD_CASES, TOTALS
from ..io.display import STAT_ROWS, design_text, kn_text, number_text, stat_text
from ..io.document import RunDocument, TowerRecord

#: The load-tree components in the CSV's order: the JSON's reaction name and the column's label.
TREE_COLUMNS = (("Rz", "vertical"), ("Ry", "transverse"), ("Rx", "longitudinal"))

#: The tree table's and the totals table's column labels.
TREE_HEADERS = ("wire", "vertical kN", "±", "transverse kN", "±", "longitudinal kN", "±")
TOTALS_HEADERS = ("total", "peak Dy", "GF_Dy", "Cont_R %", "design peak", "sum of peaks", "peak/sum")

SIGN_NOTE = ("Each wire's force on the tower at its attachment, tower frame: vertical downward positive, transverse "
             "toward +y (the line's left), longitudinal toward +x (the tower's heading); still air included; means "
             "over the samples, ± their standard deviation. 'all wires': their sum, the tower's forces at that "
             "instant. Totals: forces (kN) and moments about the tower's base (kN m, z up) from the summed "
             "histories; sum of peaks: the attachments' own peaks added (peak/sum below 1: what the correlation "
             "saves). The same trees: --load-trees CSV, Excel sheet 'Load trees'.")


def unit(total: str) -> str:
    """kN for a force total, kN m for a moment."""
    return "kN m" if total.startswith("M") else "kN"


def tower_label(doc: RunDocument, t: TowerRecord) -> str:
    """``"2 T2 (S) *"``: index, name, type, ``*`` at the tower of interest."""
    name = (t.section or {}).get("name")
    text = f"{t.index}" + (f" {name}" if name else "") + (f" ({t.type})" if t.type else "")
    return text + (" *" if t.index == doc.tower_of_interest else "")


def wires_title(doc: RunDocument) -> str:
    """The Results title of a run of several wires."""
    n = doc.realizations
    return (f"{doc.case}: tower totals of {len(doc.wires or ())} wires at tower {doc.tower_of_interest} ({doc.wind}, "
            f"V_ref = {doc.v_ref:g} m/s, {n} realization{'s' if n > 1 else ''}, seed {doc.seed})")


def samples_text(doc: RunDocument) -> str:
    """``"2 samples (realizations)"``."""
    n = doc.realizations * (doc.windows or 1)
    what = " (realizations x peak windows)" if (doc.windows or 1) > 1 else " (realizations)"
    return f"{n} sample{'s' if n != 1 else ''}{what}"


def tree_rows(doc: RunDocument, index: int, case: str) -> list[tuple[str, ...]]:
    """Tower ``index``'s (1-based) load tree ``case``: one row per wire (:data:`TREE_HEADERS`, kN),
    then ``all wires``, the components' sums."""
    tree = (doc.towers[index - 1].load_trees or {})[case]
    rows: list[tuple[str, ...]] = []
    sums: dict[str, float | None] = {r: 0.0 for r, _ in TREE_COLUMNS}
    for a in tree.attachments:
        cells = [a.wire]
        for r, _ in TREE_COLUMNS:
            cells += [kn_text(a.load[r]), kn_text(a.std[r])]
            v, s = a.load[r], sums[r]
            sums[r] = None if v is None or s is None else s + v
        rows.append(tuple(cells))
    rows.append(("all wires", *(c for r, _ in TREE_COLUMNS for c in (kn_text(sums[r]), ""))))
    return rows


def tree_total_text(doc: RunDocument, index: int, case: str) -> str:
    """One line: the load case's governing total at tower ``index`` (value ± std, still air included)."""
    t = doc.towers[index - 1]
    tree = (t.load_trees or {})[case]
    total, how = LOAD_CASES[case]
    when = f"the least {total}" if how == "min" else f"the largest |{total}|"
    std = "" if tree.value_std is None else f" ± {kn_text(tree.value_std)}"
    return (f"{case} at tower {tower_label(doc, t)}: every wire's load at the instant of {when}; "
            f"{total} = {kn_text(tree.value)}{std} {unit(total)} (still air included), mean over {samples_text(doc)}")


def totals_rows(doc: RunDocument, index: int) -> list[tuple[str, ...]]:
    """Tower ``index``'s (1-based) totals (:data:`TOTALS_HEADERS`; the total with its unit): the
    wind-induced peak with its spread, GF_Dy, Cont_R, the design peak (Gumbel fractile), the sum
    of the attachments' peaks and peak/sum (the Excel sheet "Totals" has every column)."""
    t, n = doc.towers[index - 1], doc.realizations
    pk = STAT_ROWS["peak_dynamic"]
    rows = []
    for name in TOTALS:
        x = (t.totals or {})[name]
        rows.append((f"{name} {unit(name)}", stat_text(x["peak_dynamic"], pk, n),
                     stat_text(x["GF_Dy"], STAT_ROWS["GF_Dy"], 1), stat_text(x["Cont_R"], STAT_ROWS["Cont_R"], 1),
                     design_text(x["peak_dynamic"], pk), number_text(x.peak_sum.mean, pk),
                     "" if x.peak_to_sum is None else f"{x.peak_to_sum:.3f}"))
    return rows


def wires_summary_note(doc: RunDocument) -> str:
    """The Summary's note of a run of several wires: what its Rx, Ry, Rz are and where the rest is."""
    return (f"A run of {len(doc.wires or ())} wires in one correlated wind: Rx, Ry, Rz are the tower totals' forces "
            f"Fx, Fy, Fz at tower {doc.tower_of_interest} (every wire's reactions summed at each instant), "
            "wind-induced; every tower's totals, moments and load trees: tab Load trees (] steps to it).")
