"""Parameters of the current case with units, and the editor (validation as you type).

Every row comes from :data:`linecheck.core.case.SCHEMA`; a new value is checked by
:func:`linecheck.core.case.with_value`, i.e. the same validation and the same
messages as the CLI's case loader.

A section case also shows its tower table (one row per tower, a cell per
[[line.towers]] key and the derived span to the next tower); ``+``/``insert`` adds a tower after
the highlighted one, ``-``/``delete`` removes it; ``enter``/``e`` on a cell edits it:
the whole table goes through :func:`linecheck.core.case.with_values` (``line.towers``, the
case then holds its towers inline), so a bad cell gets the CLI's one-line message.
"""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import DataTable, Input, Static

from ...core.case import Case, FieldSpec, field_spec, with_value, with_values
from ...core.errors import CaseError
from ...io.section import COLUMN_UNITS, section_summary, tower_rows
from ..catalog import shown_path
from ..formatting import (
    TOWER_KEYS,
    case_differences,
    fields_for,
    get_value,
    iter_fields,
    parse_value,
    tower_dicts,
    tower_key,
    value_text,
)
from ..messages import ParameterChanged, ParameterRejected

COLUMNS = ("", "parameter", "value", "unit", "description")
# the parameter column fits the longest key (wind.downburst.translation_direction)
WIDTHS = (1, max(len(k) for k, _ in iter_fields()), 22, 6, None)
TOWER_COLUMNS = ("mark", *TOWER_KEYS, "span")


class ParameterEditor(Vertical):
    """Table of every case key; ``enter``/``e`` edits the highlighted one."""

    BINDINGS = [
        Binding("e", "edit", "Edit"),
        Binding("escape", "stop_editing", "Cancel edit"),
        Binding("insert,plus", "insert_tower", "Add tower"),
        Binding("delete,minus", "delete_tower", "Remove tower"),
    ]

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.case: Case | None = None
        self.original: Case | None = None
        self.editing: str | None = None
        self.pending: Case | None = None  # validated copy for the text being typed
        self.specs: dict[str, FieldSpec] = dict(iter_fields())
        self.tower_cell: tuple[int, str] | None = None  # (0-based tower, column) being edited

    def compose(self) -> ComposeResult:
        yield Static("No case open: pick one in the Cases tab (key 1).", id="params-title")
        table: DataTable = DataTable(id="params-table", cursor_type="row", zebra_stripes=True)
        yield table
        with Vertical(id="towers-box"):
            yield Static("", id="towers-title")
            yield DataTable(id="towers-table", cursor_type="cell", zebra_stripes=True)
        with Vertical(id="edit-bar"):
            yield Static("", id="edit-label")
            yield Input(id="edit-input", placeholder="new value; empty = default")
            yield Static("", id="edit-message")

    def on_mount(self) -> None:
        table = self.query_one("#params-table", DataTable)
        for c, w in zip(COLUMNS, WIDTHS):
            table.add_column(c, key=c or "mark", width=w)
        towers = self.query_one("#towers-table", DataTable)
        for c in TOWER_COLUMNS:
            unit = COLUMN_UNITS.get(c, "")
            label = "" if c == "mark" else (f"{c} ({unit})" if unit else c)
            towers.add_column(label, key=c)
        self.query_one("#towers-box").display = False
        self.query_one("#edit-bar").display = False

    # ------------------------------------------------------------------ showing
    def show_case(self, case: Case, original: Case) -> None:
        """Fill the table with ``case``; keys differing from ``original`` are marked."""
        if self.editing is not None:
            self.stop_editing()
        self.case, self.original = case, original
        table = self.query_one("#params-table", DataTable)
        row = table.cursor_row
        table.clear()
        for key, spec in fields_for(case.wind.type, case.line.is_section):
            table.add_row(*self._cells(key, spec), key=key)
        if table.row_count:
            table.move_cursor(row=min(max(row, 0), table.row_count - 1))
        self._show_towers()
        self._update_title()

    def _show_towers(self) -> None:
        """Fill the tower table of a section case (hidden for the equal-span form)."""
        box = self.query_one("#towers-box")
        case = self.case
        if case is None or not case.line.is_section:
            box.display = False
            return
        box.display = True
        table = self.query_one("#towers-table", DataTable)
        cursor = table.cursor_coordinate
        table.clear()
        old = self.original.line.towers if self.original is not None and self.original.line.is_section else ()
        for r, t in zip(tower_rows(case.line), case.line.towers):
            before = old[r.index - 1] if r.index - 1 < len(old) else None
            cells: list[Any] = []
            for col in TOWER_KEYS:
                v = getattr(t, col)
                text = Text(value_text(v))
                if v is None:
                    used = r.insulator_used if col == "insulator_length" else None
                    text = Text(f"({value_text(used)})" if used is not None else "", style="dim")
                if before is not None and getattr(before, col) != v or before is None:
                    text.stylize("bold yellow")
                cells.append(text)
            changed = before != t
            mark = Text("*", style="bold yellow") if changed else ""
            span = Text(value_text(r.span) if r.span is not None else "", style="dim")
            toi = r.index == case.line.tower_of_interest
            if toi:
                cells[0].stylize("bold underline")
            label = Text(f"{r.index}" + (" ToI" if toi else ""), style="bold" if toi else "dim")
            table.add_row(mark, *cells, span, key=str(r.index - 1), label=label)
        if table.row_count:
            table.cursor_coordinate = cursor if cursor.row < table.row_count else table.cursor_coordinate
        src = f" (from {case.line.towers_file})" if case.line.towers_file else " (inline)"
        title = Text("towers: ", style="bold")
        title.append(f"{section_summary(case.line)}, H0 {case.line.tension:g} N{src}")
        title.append("   enter edits the highlighted cell; ToI tower of interest, * edited, () line default",
                     style="dim")
        self.query_one("#towers-title", Static).update(title)

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
        n = len(case_differences(self.original, c)) if self.original is not None else 0
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
        towers = self.query_one("#towers-table", DataTable)
        if self.case is not None and towers.has_focus and towers.row_count:
            self._edit_tower_at(towers.cursor_coordinate)
            return
        table = self.query_one("#params-table", DataTable)
        if self.case is None or not table.row_count:
            return
        key = table.coordinate_to_cell_key(table.cursor_coordinate).row_key.value
        self.start_editing(key)

    # ------------------------------------------------------------------ tower rows
    def _tower_cursor(self) -> int | None:
        """0-based tower under the cursor of a focused tower table, else None."""
        towers = self.query_one("#towers-table", DataTable)
        if self.case is None or not self.case.line.is_section or not towers.has_focus or not towers.row_count:
            return None
        return int(towers.cursor_coordinate.row)

    def action_insert_tower(self) -> None:
        """Add a suspension tower midway between the highlighted tower and the next (before the
        last tower when the last is highlighted): station, ground and height interpolated."""
        k = self._tower_cursor()
        if k is None:
            return
        rows = tower_dicts(self.case)
        a = min(k, len(rows) - 2)  # insert between a and a + 1
        lo, hi = rows[a], rows[a + 1]
        new = {"name": f"{lo.get('name', f'T{a + 1}')}a", "support": "suspension"}
        for col in ("station", "ground", "height"):
            new[col] = 0.5 * (float(lo.get(col, 0.0)) + float(hi.get(col, 0.0)))
        rows.insert(a + 1, new)
        toi = self.case.line.tower_of_interest
        self._apply_towers(rows, toi + 1 if a + 1 < toi else toi, f"added {new['name']} at {new['station']:g} m")

    def action_delete_tower(self) -> None:
        """Remove the highlighted tower (the loader's checks apply: e.g. a new end tower must be
        a strain tower without angle)."""
        k = self._tower_cursor()
        if k is None:
            return
        rows = tower_dicts(self.case)
        if len(rows) <= 2:
            self.notify("a section needs at least two towers", severity="warning", timeout=4)
            return
        gone = rows.pop(k)
        toi = self.case.line.tower_of_interest
        if k < toi - 1:
            toi -= 1
        toi = min(toi, len(rows))
        self._apply_towers(rows, toi, f"removed {gone.get('name', f'T{k + 1}')}")

    def _apply_towers(self, rows: list[dict[str, Any]], toi: int, what: str) -> None:
        """Validate a new tower table (CaseError: the CLI's one-line message, nothing changes)."""
        try:
            new = with_values(self.case, {"line.towers_file": None, "line.towers": rows, "line.tower_of_interest": toi})
        except CaseError as err:
            self.post_message(ParameterRejected("line.towers", what, str(err)))
            self.notify(str(err), severity="error", timeout=8)
            self.app.bell()
            return
        self.case = new
        table = self.query_one("#params-table", DataTable)
        for key, spec in fields_for(new.wind.type, new.line.is_section):
            for col, c in zip(COLUMNS, self._cells(key, spec)):
                table.update_cell(key, col or "mark", c)
        self._show_towers()
        self._update_title()
        self.post_message(ParameterChanged(new, "line.towers", what))

    @on(DataTable.RowSelected, "#params-table")
    def _row_selected(self, event: DataTable.RowSelected) -> None:
        event.stop()
        if event.row_key.value is not None:
            self.start_editing(event.row_key.value)

    @on(DataTable.CellSelected, "#towers-table")
    def _cell_selected(self, event: DataTable.CellSelected) -> None:
        event.stop()
        self._edit_tower_at(event.coordinate)

    def _edit_tower_at(self, coordinate) -> None:
        table = self.query_one("#towers-table", DataTable)
        keys = table.coordinate_to_cell_key(coordinate)
        column = keys.column_key.value
        if column not in TOWER_KEYS:
            self.notify("span is derived from the stations: edit a station", timeout=3)
            return
        self.start_tower_edit(int(keys.row_key.value), column)

    def start_tower_edit(self, k: int, column: str) -> None:
        """Open the edit bar on cell ``column`` of tower ``k`` (0-based) of a section case."""
        if self.case is None or not self.case.line.is_section or column not in TOWER_KEYS:
            return
        self.tower_cell = (k, column)
        self._open_bar(tower_key(k, column), field_spec("line.towers", column),
                       getattr(self.case.line.towers[k], column))

    def start_editing(self, key: str) -> None:
        """Open the edit bar on ``key`` (a dotted case key such as ``wind.v_ref``)."""
        if self.case is None or key not in self.specs:
            return
        self.tower_cell = None
        self._open_bar(key, self.specs[key], get_value(self.case, key))

    def _open_bar(self, key: str, spec: FieldSpec, value: Any) -> None:
        self.editing = key
        unit = f" [{spec.unit}]" if spec.unit not in ("", "-") else ""
        label = Text(f"{key}{unit}", style="bold")
        label.append(f"  {spec.help} - expected {spec.allowed()}", style="dim")
        self.query_one("#edit-label", Static).update(label)
        bar = self.query_one("#edit-bar")
        bar.display = True
        inp = self.query_one("#edit-input", Input)
        inp.value = value_text(value)
        inp.cursor_position = len(inp.value)
        inp.focus()
        self.validate(inp.value)
        self.refresh_bindings()

    def validate(self, text: str) -> str | None:
        """Check ``text`` for the key being edited; show and return the message (None when valid)."""
        if self.editing is None or self.case is None:
            return None
        msg_box = self.query_one("#edit-message", Static)
        inp = self.query_one("#edit-input", Input)
        try:
            if self.tower_cell is not None:
                self.pending = self._with_tower_value(text)
            else:
                self.pending = with_value(self.case, self.editing, parse_value(self.specs[self.editing], text))
        except CaseError as err:
            self.pending = None
            inp.add_class("-invalid")
            msg_box.update(Text(str(err), style="bold red"))
            return str(err)
        inp.remove_class("-invalid")
        msg_box.update(Text("valid - enter applies, esc cancels", style="green"))
        return None

    def _with_tower_value(self, text: str) -> Case:
        """The case with the edited tower cell (empty text: the key's default), validated."""
        k, column = self.tower_cell
        rows = tower_dicts(self.case)
        value = parse_value(field_spec("line.towers", column), text)
        if value is None:
            rows[k].pop(column, None)
        else:
            rows[k][column] = value
        return with_values(self.case, {"line.towers_file": None, "line.towers": rows})

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
        cell = self.tower_cell
        value = get_value(new, key) if cell is None else getattr(new.line.towers[cell[0]], cell[1])
        self.stop_editing()
        self.case = new
        table = self.query_one("#params-table", DataTable)
        for k, spec in fields_for(new.wind.type, new.line.is_section):  # an edit can alter derived values
            for col, c in zip(COLUMNS, self._cells(k, spec)):
                table.update_cell(k, col or "mark", c)
        if cell is not None:
            self._show_towers()
            self.query_one("#towers-table", DataTable).focus()
        self._update_title()
        self.post_message(ParameterChanged(new, key, value))

    def action_stop_editing(self) -> None:
        self.stop_editing()

    def stop_editing(self) -> None:
        tower = self.tower_cell is not None
        self.editing = None
        self.pending = None
        self.tower_cell = None
        self.query_one("#edit-bar").display = False
        self.query_one("#edit-message", Static).update("")
        self.query_one("#towers-table" if tower else "#params-table", DataTable).focus()
        self.refresh_bindings()
