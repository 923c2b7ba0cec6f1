"""Codes: the design codes' conductor wind and angle loads beside linecheck's peaks.

Shows the ``"codes"`` block of the run document (computed by the service); no code value is
computed here.
"""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import DataTable, Static

from ...core.codes import CODES_COMPARED, CODES_PEAK
from ...io.display import kn_text
from ...io.document import CodeCheckRecord, RunDocument

HELP = "No result yet. Run a case (r): the four design codes' conductor wind loads appear here beside its peaks."
PEAK_NOTE = (f"{CODES_COMPARED}.\nlinecheck peak: {CODES_PEAK}; ratio = peak / code load. "
             "Unverified codes are shown, not judged (docs/codes.md).")


def codes_rows(codes: dict[str, CodeCheckRecord], names: dict[int, str] | None = None) -> list[tuple[str, ...]]:
    """Table rows (text, kN) of a typed ``codes`` block; ``names``: tower labels by 1-based index
    (a section's ``towers[].name``), shown as "7 T7"."""
    names = names or {}
    rows = []
    for name, block in codes.items():
        for t in block.towers:
            label = f"{t.index} {names[t.index]}" if t.index in names else str(t.index)
            for r, v in t.reactions.items():
                rows.append((name, "yes" if block.verified else "no", label, r, kn_text(v.wind_load),
                             kn_text(v.angle_load), kn_text(v.code_load), kn_text(v.linecheck_peak),
                             "-" if v.ratio is None else f"{v.ratio:.3f}", v.verdict))
    return rows


class CodesView(Vertical):
    """One row per code, tower and reaction (the code load's wind and angle parts, the code load, the
    peak, ratio, verdict); what is compared and the codes' notes below."""

    def compose(self) -> ComposeResult:
        yield Static(HELP, id="codes-title")
        yield DataTable(id="codes-table", cursor_type="row", zebra_stripes=True)
        yield Static("", id="codes-notes")

    def on_mount(self) -> None:
        t = self.query_one(DataTable)
        t.add_columns("code", "verified", "tower", "reaction", "wind kN", "angle kN", "code load kN", "linecheck peak kN",
                      "ratio", "verdict")

    def show(self, doc: RunDocument | None) -> None:
        title = self.query_one("#codes-title", Static)
        notes = self.query_one("#codes-notes", Static)
        table = self.query_one(DataTable)
        table.clear()
        codes = doc.codes if doc is not None else None
        if not codes:
            title.update(HELP)
            notes.update("")
            return
        title.update(Text(f"{doc.case}: transverse load on Ry (wind + angle), design codes vs linecheck", style="bold"))
        names = {t.index: t.section["name"] for t in doc.towers if t.section and "name" in t.section}
        for row in codes_rows(codes, names):
            table.add_row(*row)
        n = Text(PEAK_NOTE + "\n", style="dim")
        for name, block in codes.items():
            n.append(f"{name} ({block.edition}): {block.note}\n", style="dim")
        notes.update(n)
