"""Parameters of the current case with units, and the editor (validation as you type).

Every row comes from :data:`linecheck.core.case.SCHEMA`; a new value is checked by
:func:`linecheck.core.case.with_value`, i.e. the same validation and the same
messages as the CLI's case loader.
"""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import DataTable, Input, Static

from ...core.case import Case, FieldSpec, with_value
from ...core.errors import CaseError
from ..catalog import shown_path
from ..formatting import fields_for, get_value, iter_fields, parse_value, value_text
from ..messages import ParameterChanged, ParameterRejected

COLUMNS = ("", "parameter", "value", "unit", "description")
# the parameter column fits the longest key (wind.downburst.translation_direction)
WIDTHS = (1, max(len(k) for k, _ in iter_fields()), 22, 6, None)


class ParameterEditor(Vertical):
    """Table of every case key; ``enter``/``e`` edits the highlighted one."""

    BINDINGS = [
        Binding("e", "edit", "Edit"),
        Binding("escape", "stop_editing", "Cancel edit"),
    ]

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.case: Case | None = None
        self.original: Case | None = None
        self.editing: str | None = None
        self.pending: Case | None = None  # validated copy for the text being typed
        self.specs: dict[str, FieldSpec] = dict(iter_fields())

    def compose(self) -> ComposeResult:
        yield Static("No case open: pick one in the Cases tab (key 1).", id="params-title")
        table: DataTable = DataTable(id="params-table", cursor_type="row", zebra_stripes=True)
        yield table
        with Vertical(id="edit-bar"):
            yield Static("", id="edit-label")
            yield Input(id="edit-input", placeholder="new value; empty = default")
            yield Static("", id="edit-message")

    def on_mount(self) -> None:
        table = self.query_one(DataTable)
        for c, w in zip(COLUMNS, WIDTHS):
            table.add_column(c, key=c or "mark", width=w)
        self.query_one("#edit-bar").display = False

    # ------------------------------------------------------------------ showing
    def show_case(self, case: Case, original: Case) -> None:
        """Fill the table with ``case``; keys differing from ``original`` are marked."""
        if self.editing is not None:
            self.stop_editing()
        self.case, self.original = case, original
        table = self.query_one(DataTable)
        row = table.cursor_row
        table.clear()
        for key, spec in fields_for(case.wind.type):
            table.add_row(*self._cells(key, spec), key=key)
        if table.row_count:
            table.move_cursor(row=min(max(row, 0), table.row_count - 1))
        self._update_title()

    def _cells(self, key: str, spec: FieldSpec) -> tuple[Any, ...]:
        v = get_value(self.case, key)
        changed = self.original is not None and get_value(self.original, key) != v
        text = value_text(v)
        value = Text(text) if text else Text("(default)" if spec.default is None else "", style="dim")
        if changed:
            value.stylize("bold yellow")
        unit = "" if spec.unit in ("", "-") else spec.unit
        return (Text("*", style="bold yellow") if changed else "", key, value, unit, spec.help)

    def _update_title(self) -> None:
        c = self.case
        if c is None:
            return
        n = len([k for k in self.specs if get_value(c, k) != get_value(self.original, k)])
        src = f"  {shown_path(c.source)}" if c.source else ""
        t = Text(f"{c.name}", style="bold")
        t.append(src, style="dim")
        if n:
            t.append(f"   {n} edited (*) - s saves as a new file", style="yellow")
        else:
            t.append("   enter edits the highlighted parameter", style="dim")
        self.query_one("#params-title", Static).update(t)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "stop_editing":
            return self.editing is not None
        if action == "edit":
            return self.case is not None and self.editing is None
        return True

    # ------------------------------------------------------------------ editing
    def action_edit(self) -> None:
        table = self.query_one(DataTable)
        if self.case is None or not table.row_count:
            return
        key = table.coordinate_to_cell_key(table.cursor_coordinate).row_key.value
        self.start_editing(key)

    @on(DataTable.RowSelected, "#params-table")
    def _row_selected(self, event: DataTable.RowSelected) -> None:
        event.stop()
        if event.row_key.value is not None:
            self.start_editing(event.row_key.value)

    def start_editing(self, key: str) -> None:
        """Open the edit bar on ``key`` (a dotted case key such as ``wind.v_ref``)."""
        if self.case is None or key not in self.specs:
            return
        spec = self.specs[key]
        self.editing = key
        unit = f" [{spec.unit}]" if spec.unit not in ("", "-") else ""
        label = Text(f"{key}{unit}", style="bold")
        label.append(f"  {spec.help} - expected {spec.allowed()}", style="dim")
        self.query_one("#edit-label", Static).update(label)
        bar = self.query_one("#edit-bar")
        bar.display = True
        inp = self.query_one("#edit-input", Input)
        inp.value = value_text(get_value(self.case, key))
        inp.cursor_position = len(inp.value)
        inp.focus()
        self.validate(inp.value)
        self.refresh_bindings()

    def validate(self, text: str) -> str | None:
        """Check ``text`` for the key being edited; show and return the message (None when valid)."""
        if self.editing is None or self.case is None:
            return None
        spec = self.specs[self.editing]
        msg_box = self.query_one("#edit-message", Static)
        inp = self.query_one("#edit-input", Input)
        try:
            self.pending = with_value(self.case, self.editing, parse_value(spec, text))
        except CaseError as err:
            self.pending = None
            inp.add_class("-invalid")
            msg_box.update(Text(str(err), style="bold red"))
            return str(err)
        inp.remove_class("-invalid")
        msg_box.update(Text("valid - enter applies, esc cancels", style="green"))
        return None

    @on(Input.Changed, "#edit-input")
    def _changed(self, event: Input.Changed) -> None:
        event.stop()
        self.validate(event.value)

    @on(Input.Submitted, "#edit-input")
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        key = self.editing
        if key is None:
            return
        message = self.validate(event.value)
        if message is not None or self.pending is None:
            self.post_message(ParameterRejected(key, event.value, message or "invalid"))
            self.app.bell()
            return
        new = self.pending
        value = get_value(new, key)
        self.stop_editing()
        self.case = new
        table = self.query_one(DataTable)
        for k, spec in fields_for(new.wind.type):  # a change can alter derived values (e.g. presets)
            for col, cell in zip(COLUMNS, self._cells(k, spec)):
                table.update_cell(k, col or "mark", cell)
        self._update_title()
        self.post_message(ParameterChanged(new, key, value))

    def action_stop_editing(self) -> None:
        self.stop_editing()

    def stop_editing(self) -> None:
        self.editing = None
        self.pending = None
        self.query_one("#edit-bar").display = False
        self.query_one("#edit-message", Static).update("")
        self.query_one(DataTable).focus()
        self.refresh_bindings()
