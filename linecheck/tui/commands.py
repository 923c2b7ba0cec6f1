"""Command palette (ctrl+p): "case: ...", "run: ...", "export: ..." and "view: ..." commands."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, NamedTuple

from textual.command import DiscoveryHit, Hit, Hits, Provider

if TYPE_CHECKING:
    from .app import LinecheckApp


class Command(NamedTuple):
    name: str
    callback: Callable[[], object]
    help: str
    listed: bool = True  # shown before anything is typed


class LinecheckCommands(Provider):
    """Commands of the current state (cases found, whether a run or a result exists)."""

    def _commands(self) -> list[Command]:
        app: LinecheckApp = self.app  # type: ignore[assignment]
        cmds: list[Command] = []
        if app.case is not None:
            cmds += [
                Command(f"run: {app.case.name} (current case)", app.action_run,
                        "steps 1-3 in the background; c cancels"),
                Command("case: save as new TOML file", app.action_save_as, "write the edited case to a new file"),
                Command("case: revert edits", app.action_revert, "back to the values of the case file"),
            ]
        if app.running:
            cmds.append(Command("run: cancel", app.action_cancel, "stop the running job"))
        if app.output is not None:
            cmds += [
                Command("export: Excel workbook (.xlsx)", app.action_export_excel,
                        "design sheet of the current result"),
                Command("export: JSON result (.json)", app.action_export_json, "the `linecheck run --json` document"),
                Command("run: pin result for compare", app.action_pin, "keep this result; run a variant; see tab 4"),
            ]
        for entry in app.catalog.all_cases():
            cmds.append(Command(f"case: open {entry.name}", partial(app.open_case, entry.path),
                                entry.description or str(entry.path), listed=False))
            cmds.append(Command(f"run: {entry.name}", partial(app.open_case, entry.path, run=True),
                                f"open and run {entry.path}", listed=False))
        cmds += [
            Command("view: cases", partial(app.action_show_tab, "cases"), "tab 1", listed=False),
            Command("view: parameters", partial(app.action_show_tab, "params"), "tab 2", listed=False),
            Command("view: results", partial(app.action_show_tab, "results"), "tab 3", listed=False),
            Command("view: compare", partial(app.action_show_tab, "compare"), "tab 4", listed=False),
            Command("view: load trees", partial(app.show_result_tab, "res-trees"),
                    "tab 3: a run of several wires, every tower's load trees", listed=False),
            Command("view: help", app.action_help, "keys and a typical session"),
        ]
        return cmds

    async def discover(self) -> Hits:
        for cmd in self._commands():
            if cmd.listed:
                yield DiscoveryHit(cmd.name, cmd.callback, help=cmd.help)

    async def search(self, query: str) -> Hits:
        matcher = self.matcher(query)
        for cmd in self._commands():
            score = matcher.match(cmd.name)
            if score > 0:
                yield Hit(score, matcher.highlight(cmd.name), cmd.callback, help=cmd.help)
