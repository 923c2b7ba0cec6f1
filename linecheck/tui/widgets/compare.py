"""Compare: a pinned result beside the current one, with the differences."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import DataTable, Static

from ..formatting import case_differences, compare_rows, cont_r_flags
from ..runner import RunOutput

HELP = ("Nothing pinned. Run a case, press p to pin its result, edit a parameter (tab 2), "
        "run again (r): both results appear here side by side.")


class CompareView(Vertical):
    """Pinned vs current: changed parameters, then every statistic with its difference."""

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.pinned: RunOutput | None = None
        self.current: RunOutput | None = None

    def compose(self) -> ComposeResult:
        yield Static(HELP, id="compare-title")
        yield Static("", id="compare-params")
        yield DataTable(id="compare-table", cursor_type="row", zebra_stripes=True)

    def on_mount(self) -> None:
        t = self.query_one(DataTable)
        t.add_columns("reaction", "statistic", "unit", "pinned", "current", "Δ (current - pinned)")
        t.display = False

    def show(self, pinned: RunOutput | None, current: RunOutput | None) -> None:
        self.pinned, self.current = pinned, current
        title = self.query_one("#compare-title", Static)
        params = self.query_one("#compare-params", Static)
        table = self.query_one(DataTable)
        table.clear()
        if pinned is None:
            title.update(HELP)
            params.update("")
            table.display = False
            return
        t = Text("pinned  ", style="bold")
        t.append(pinned.label, style="cyan")
        if current is None or current is pinned:
            t.append("\nnow edit the case and run it again (r) to compare", style="dim")
            title.update(t)
            params.update("")
            table.display = False
            return
        t.append("   vs   ", style="dim")
        t.append("current  ", style="bold")
        t.append(current.label, style="cyan")
        title.update(t)
        diffs = case_differences(pinned.case, current.case)
        p = Text("changed parameters: ", style="bold")
        if not diffs:
            p.append("none (same inputs)", style="dim")
        for i, (key, a, b) in enumerate(diffs):
            p.append(("" if i == 0 else ";  ") + f"{key} ")
            p.append(a, style="dim")
            p.append(" -> ")
            p.append(b, style="bold yellow")
        params.update(p)
        table.display = True
        previous = None
        flagged = {"pinned": cont_r_flags(pinned.doc), "current": cont_r_flags(current.doc)}
        for row in compare_rows(pinned.doc, current.doc):
            cells: list = list(row)
            if row[1] == "Cont_R":  # a flagged Cont_R (> 10 %) as in the Results summary
                for col, which in ((3, "pinned"), (4, "current")):
                    if row[0] in flagged[which]:
                        cells[col] = Text(cells[col], style="bold black on yellow")
            if cells[0] == previous:
                cells[0] = ""  # reaction named once per group
            previous = row[0]
            if any(ch in "123456789" for ch in cells[-1]):  # a non-zero change
                cells[-1] = Text(cells[-1], style="bold yellow")
            table.add_row(*cells)
