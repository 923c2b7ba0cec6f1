"""File-name dialog for "save as" and exports; never replaces a file without being told to."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Checkbox, Input, Static


class TickBox(Checkbox):
    """A checkbox that shows ``X`` only when ticked (Textual's shows it always, only recoloured)."""

    @property
    def _button(self):
        self.BUTTON_INNER = "X" if self.value else " "
        return super()._button


class PathPrompt(ModalScreen[tuple[Path, bool] | None]):
    """Ask for a file name; dismiss with ``(path, replace)`` or ``None`` (esc).

    An existing file is accepted only with "replace it" ticked.  ``caution(path)`` returns a
    warning for paths that need a second enter (e.g. a shipped case folder), or None.
    """

    BINDINGS = [Binding("escape", "cancel", "Cancel")]

    def __init__(self, title: str, default: Path, suffix: str,
                 caution: Callable[[Path], str | None] | None = None) -> None:
        super().__init__()
        self.title_text = title
        self.default = default
        self.suffix = suffix
        self.caution = caution
        self._confirmed: Path | None = None  # the cautioned path entered twice

    def compose(self) -> ComposeResult:
        with Vertical(id="prompt-box", classes="dialog"):
            yield Static(Text(self.title_text, style="bold"), id="prompt-title")
            yield Input(str(self.default), id="prompt-input")
            yield TickBox("replace the file if it exists", id="prompt-replace")
            yield Static("", id="prompt-message")
            yield Static(Text("enter writes, esc cancels", style="dim"))

    def on_mount(self) -> None:
        inp = self.query_one(Input)
        inp.focus()
        inp.cursor_position = len(inp.value)
        self.check(inp.value)

    def check(self, text: str) -> str | None:
        """Problem with ``text`` as an output path (shown; None when fine)."""
        msg = self.query_one("#prompt-message", Static)
        problem = None
        p = Path(text.strip()).expanduser() if text.strip() else None
        if p is None:
            problem = "type a file name"
        elif p.suffix.lower() != self.suffix:
            problem = f"the file name must end with {self.suffix}"
        elif p.is_dir():
            problem = "this is a folder: type a file name"
        elif not (p.parent if str(p.parent) else Path(".")).is_dir():
            problem = f"folder {p.parent} does not exist"
        elif p.exists() and not self.query_one(Checkbox).value:
            problem = "the file exists: choose another name or tick \"replace\" (tab, space)"
        if problem:
            msg.update(Text(problem, style="bold red"))
        else:
            exists = p is not None and p.exists()
            warning = self.caution(p) if self.caution is not None and p is not None else None
            if warning:
                msg.update(Text(warning + ": enter again to write there anyway", style="bold yellow"))
            else:
                msg.update(Text("will replace the existing file" if exists else "new file",
                                style="yellow" if exists else "green"))
        return problem

    @on(Input.Changed)
    def _changed(self, event: Input.Changed) -> None:
        self.check(event.value)

    @on(Checkbox.Changed)
    def _replace_changed(self, event: Checkbox.Changed) -> None:
        self.check(self.query_one(Input).value)

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        if self.check(event.value) is not None:
            self.app.bell()
            return
        path = Path(event.value.strip()).expanduser()
        if self.caution is not None and self.caution(path) and self._confirmed != path:
            self._confirmed = path  # asked (the message says so): a second enter writes
            self.app.bell()
            return
        self.dismiss((path, self.query_one(Checkbox).value))

    def action_cancel(self) -> None:
        self.dismiss(None)
