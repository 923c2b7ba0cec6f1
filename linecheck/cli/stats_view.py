"""Console views of the run statistics: design values, intervals, flag states, the
``--until`` option and the "how to read" notes (shared by ``run`` and ``batch``)."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from ..core.errors import CaseError
from ..io.display import STAT_ROWS, ci_text, design_text, flag_text, how_to_read, number_text
from ..io.document import RunDocument

UntilOpt = Annotated[str | None, typer.Option(
    "--until", help="Add realizations until the standard error of GF_Dy and of the peak of every reaction at the "
                    "tower of interest is below this share of its mean, e.g. 1% or 0.01.", show_default=False)]
MaxRealOpt = Annotated[int, typer.Option(
    "--max-realizations", help="With --until: stop after this many realizations.", min=2)]


def parse_until(text: str | None) -> float | None:
    """``"1%"`` -> 0.01, ``"0.01"`` -> 0.01; :class:`CaseError` (exit 2) otherwise."""
    if text is None:
        return None
    s = text.strip()
    try:
        v = float(s[:-1]) / 100.0 if s.endswith("%") else float(s)
    except ValueError:
        v = float("nan")
    if not (0.0 < v < 1.0):
        raise CaseError(f"value '{text}' is not allowed: expected a relative standard error between 0 and 1, "
                        "e.g. 1% or 0.01", key="--until")
    return v


def design_table(doc: RunDocument) -> Table:
    """Design values (Gumbel fractile of the peaks), 95 % intervals and the Cont_R flag at the tower."""
    n, w = doc.realizations, doc.windows or 1
    over = f"{n} realization{'s' if n != 1 else ''}" + (f" x {w} windows of {doc.peak_window:g} s" if w > 1 else "")
    t = Table(title=f"design values at tower {doc.tower_of_interest} (peaks: Gumbel fractile {doc.design_fractile:g}; "
                    f"[ ]: 95 % interval of the mean over {over})", title_justify="left")
    for c in ("reaction", "design peak kN", "design total kN", "GF_Dy", "GF_QS", "Cont_R %", "ppcc",
              "dynamic analysis"):
        t.add_column(c, justify="right" if c != "dynamic analysis" else "left")
    pk, tot = STAT_ROWS["peak_dynamic"], STAT_ROWS["peak_dynamic_total"]
    for r, e in doc.reactions.items():
        g = e["peak_dynamic"].gumbel
        ppcc = None if g is None else g.ppcc
        row = [r, design_text(e["peak_dynamic"], pk), design_text(e["peak_dynamic_total"], tot)]
        for k in ("GF_Dy", "GF_QS", "Cont_R"):
            st = STAT_ROWS[k]
            m = e[k].mean
            row.append("**" if m is None else f"{number_text(m, st)} {ci_text(e[k], st)}".strip())
        state = e.dynamic_analysis
        style = {"recommended": "[bold red]", "inconclusive": "[yellow]"}.get(state, "")
        row += ["" if ppcc is None else f"{ppcc:.3f}", f"{style}{flag_text(state)}{'[/]' if style else ''}"]
        t.add_row(*row)
    return t


def notes(doc: RunDocument) -> list[str]:
    """Lines printed under the tables: the --until outcome and the "how to read" notes."""
    out = []
    u = doc.until
    if u is not None:
        ach_t = "n/a" if u.achieved is None else f"{100 * u.achieved:.2f} %"
        verdict = "reached" if u.reached else f"NOT reached (cap --max-realizations {u.max_realizations})"
        out.append(f"--until {100 * u.target:g} %: {doc.realizations} realizations, standard error {ach_t} "
                   f"({verdict}).")
    out += how_to_read(doc)
    return out
