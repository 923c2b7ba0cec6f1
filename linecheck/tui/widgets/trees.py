"""The Results tab "Load trees" of a run of a case with ``[[wires]]`` (docs/tui.md "Load trees"):
pick a tower (the list, ↑/↓) and a load case (←/→), see every wire's coincident load (vertical,
transverse, longitudinal, kN) with the governing total's value, and the tower's totals.  The
text comes from :mod:`linecheck.tui.wires_text`; each change posts :class:`TreeShown`."""

from __future__ import annotations

from dataclasses import dataclass

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.widgets import DataTable, OptionList, RadioButton, RadioSet, Static

from ...core.tower_totals import LOAD_CASES
from ...io.document import RunDocument
from ..wires_text import SIGN_NOTE, TOTALS_HEADERS, TREE_HEADERS, totals_rows, tower_label, tree_rows, tree_total_text
from .choice import StepChoice

NO_TREES = "Load trees: the result of a run of a case with [[wires]] (every wire on the tower) shows them here."


class CaseChoice(StepChoice):
    """The load case: max_transverse ... min_vertical; stepped by ←/→ in the tower list (the tab's
    one focusable widget: leaving the tab then never hands the focus to another of its widgets,
    which would bring the tab back)."""

    can_focus = False


class TowerList(OptionList):
    """The towers: ↑/↓ pick one, ←/→ step the load case."""

    BINDINGS = [
        Binding("left", "step_case(-1)", "Prev load case", show=False),
        Binding("right", "step_case(1)", "Next load case", show=False),
    ]

    def action_step_case(self, step: int) -> None:
        self.query_ancestor(LoadTreeView).action_step_case(step)


@dataclass
class TreeShown(Message):
    """The view shows tower ``tower``'s (1-based) load tree ``case``."""

    tower: int
    case: str


class LoadTreeView(Vertical):
    """The towers on the left; the chosen tower's load tree and totals on the right (display
    only: the tower list is the one focusable widget)."""

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.doc: RunDocument | None = None
        self.tower = 1
        self.case = next(iter(LOAD_CASES))

    def compose(self) -> ComposeResult:
        yield Static(NO_TREES, id="trees-title")
        with Horizontal(id="trees-body"):
            with Vertical(id="trees-pick"):
                yield TowerList(id="tree-towers")
                with CaseChoice(id="tree-case"):
                    for c in LOAD_CASES:
                        yield RadioButton(c, value=(c == self.case), id=f"case-{c}")
            with VerticalScroll(id="trees-box", can_focus=False, can_focus_children=False):
                yield Static("", id="tree-total")
                yield DataTable(id="tree-table", cursor_type="row", zebra_stripes=True)
                yield Static("", id="totals-title")
                yield DataTable(id="tree-totals", cursor_type="row", zebra_stripes=True)
                yield Static(Text(SIGN_NOTE, style="dim"), id="trees-notes")

    def on_mount(self) -> None:
        self.query_one("#tree-towers", TowerList).border_title = "tower (↑/↓)"
        self.query_one("#tree-case", CaseChoice).border_title = "load case (←/→)"
        self.query_one("#tree-table", DataTable).add_columns(*TREE_HEADERS)
        self.query_one("#tree-totals", DataTable).add_columns(*TOTALS_HEADERS)

    def show(self, doc: RunDocument | None) -> None:
        """Fill the tower list from ``doc`` and show its tower of interest (a document without
        load trees: the tab's one-line help)."""
        towers = self.query_one("#tree-towers", OptionList)
        towers.clear_options()
        if doc is None or not doc.has_wires:
            self.doc = None
            self.query_one("#trees-title", Static).update(NO_TREES)
            self.query_one("#trees-body").display = False
            return
        self.doc = doc
        self.query_one("#trees-body").display = True
        self.query_one("#trees-title", Static).update(Text(
            f"{doc.case}: load trees of every tower: each wire's load at the instant the load case's total is "
            "reached (kN)", style="bold"))
        towers.add_options([tower_label(doc, t) for t in doc.towers])
        self.select(doc.tower_of_interest, self.case)

    def select(self, tower: int, case: str) -> None:
        """Show tower ``tower``'s (1-based) load tree ``case`` (the list and the choice follow)."""
        if self.doc is None:
            return
        self.tower, self.case = tower, case
        towers = self.query_one("#tree-towers", OptionList)
        if towers.highlighted != tower - 1:
            towers.highlighted = tower - 1
        button = self.query_one(f"#case-{case}", RadioButton)
        if not button.value:
            button.value = True
        self._fill()

    def action_step_case(self, step: int) -> None:
        self.query_one(CaseChoice).step(step)

    @on(OptionList.OptionHighlighted, "#tree-towers")
    def _tower_highlighted(self, event: OptionList.OptionHighlighted) -> None:
        event.stop()
        if self.doc is not None and event.option_index + 1 != self.tower:
            self.tower = event.option_index + 1
            self._fill()

    @on(RadioSet.Changed, "#tree-case")
    def _case_changed(self, event: RadioSet.Changed) -> None:
        event.stop()
        case = str(event.pressed.label)
        if self.doc is not None and case != self.case:
            self.case = case
            self._fill()

    def _fill(self) -> None:
        """The tables of the chosen tower and load case; then :class:`TreeShown`."""
        doc = self.doc
        if doc is None:
            return
        self.query_one("#tree-total", Static).update(Text(tree_total_text(doc, self.tower, self.case)))
        table = self.query_one("#tree-table", DataTable)
        table.clear()
        rows = tree_rows(doc, self.tower, self.case)
        for k, row in enumerate(rows):
            cells = [Text(c, style="italic") for c in row] if k == len(rows) - 1 else list(row)
            table.add_row(*cells, key=row[0])
        self.query_one("#totals-title", Static).update(Text(
            f"totals at tower {tower_label(doc, doc.towers[self.tower - 1])}: forces (kN), moments about the "
            "tower's base (kN m)", style="bold"))
        totals = self.query_one("#tree-totals", DataTable)
        totals.clear()
        for row in totals_rows(doc, self.tower):
            totals.add_row(*row, key=row[0])
        self.post_message(TreeShown(self.tower, self.case))
