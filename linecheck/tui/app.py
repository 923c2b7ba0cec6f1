"""The linecheck TUI application: tabs, key bindings, the run worker and the exports.

Heavy work runs in thread workers (``@work(thread=True, ...)``) that call
:mod:`linecheck.tui.runner` (service functions only) and report through typed
messages; cancellation reaches the service as a :class:`threading.Event`.  Every
error ends in a dialog (:class:`~linecheck.tui.screens.error.ErrorScreen`), never a crash.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

from textual import on, work
from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.screen import ModalScreen
from textual.widgets import Footer, Header, TabbedContent, TabPane
from textual.worker import Worker, WorkerState

from ..core.case import Case, load_case
from ..core.errors import Cancelled, LinecheckError
from ..io.document import RunDocument
from . import files, runner
from .catalog import discover
from .commands import LinecheckCommands
from .formatting import case_differences
from .messages import (
    CaseOpened,
    Exported,
    OpenCaseRequested,
    ParameterChanged,
    RunCancelled,
    RunFailed,
    RunFinished,
    RunProgress,
    RunStarted,
)
from .screens.confirm import ConfirmScreen
from .screens.error import ErrorScreen
from .screens.help import HelpScreen
from .screens.prompt import PathPrompt
from .widgets.browser import CaseBrowser
from .widgets.codes import CodesView
from .widgets.compare import CompareView
from .widgets.params import ParameterEditor
from .widgets.results import ResultsView
from .widgets.runpanel import RunPanel

MAIN_TABS = {"cases": "#case-tree", "params": "#params-table", "results": "#summary-table", "compare": "#compare-table",
             "codes": "#codes-table"}
STATE_ACTIONS = {"run", "run_models", "cancel", "save_as", "revert", "pin", "export_excel", "export_json"}


class LinecheckApp(App[None]):
    """``linecheck tui [PATHS...]``: browse, edit, run, look, compare, export."""

    CSS_PATH = "app.tcss"
    TITLE = "linecheck"
    COMMANDS = App.COMMANDS | {LinecheckCommands}
    BINDINGS = [
        Binding("1", "show_tab('cases')", "Cases", show=False),
        Binding("2", "show_tab('params')", "Parameters", show=False),
        Binding("3", "show_tab('results')", "Results", show=False),
        Binding("4", "show_tab('compare')", "Compare", show=False),
        Binding("5", "show_tab('codes')", "Codes", show=False),
        Binding("r", "run", "Run"),
        Binding("m", "run_models", "Model spread"),
        Binding("c", "cancel", "Cancel run"),
        Binding("s", "save_as", "Save as"),
        Binding("p", "pin", "Pin"),
        Binding("x", "export_excel", "Excel"),
        Binding("j", "export_json", "JSON"),
        Binding("left_square_bracket", "result_tab(-1)", "Prev result tab", show=False),
        Binding("right_square_bracket", "result_tab(1)", "Next result tab", show=False),
        Binding("question_mark,f1", "help", "Help"),
        Binding("ctrl+q", "quit", "Quit", priority=True),
    ]

    def __init__(self, paths: list[Path] | None = None, *, extras: bool = True) -> None:
        """``paths``: case folders/files (default ``./cases``); ``extras``: also compute the
        natural frequencies and the wind at p after each run."""
        super().__init__()
        self.paths = [Path(p) for p in paths or []]
        self.catalog = discover(self.paths)
        self.extras = extras
        self.case: Case | None = None
        self.original: Case | None = None
        self.output: runner.RunOutput | None = None
        self.output_original: Case | None = None  # the file's case the output's case was edited from
        self._run_original: Case | None = None
        self.pinned: runner.RunOutput | None = None
        self.running = False
        self._cancel: threading.Event | None = None
        self._quit_warned = -10.0

    def compose(self) -> ComposeResult:
        yield Header()
        with TabbedContent(id="main-tabs"):
            with TabPane("1 Cases", id="cases"):
                yield CaseBrowser(self.catalog)
            with TabPane("2 Parameters", id="params"):
                yield ParameterEditor()
            with TabPane("3 Results", id="results"):
                yield ResultsView()
            with TabPane("4 Compare", id="compare"):
                yield CompareView()
            with TabPane("5 Codes", id="codes"):
                yield CodesView()
        yield RunPanel(id="run-panel")
        yield Footer()

    def on_mount(self) -> None:
        self.sub_title = "no case open"
        if self.catalog.missing:
            self.notify("not found: " + ", ".join(map(str, self.catalog.missing)), severity="warning")
        files = [p for p in self.paths if p.is_file()]
        if len(files) == 1 and len(self.paths) == 1:
            self.open_case(files[0])

    @property
    def edited(self) -> bool:
        """The current case differs from the file it was opened from (unsaved edits)."""
        return self.case is not None and self.original is not None and self.case != self.original

    async def action_quit(self) -> None:
        """Quit; with unsaved edits, only on the second ctrl+q within 5 s."""
        edited = self.edited
        now = time.monotonic()
        if edited and now - self._quit_warned > 5.0:
            self._quit_warned = now
            self.notify("The case has unsaved edits: s saves them, ctrl+q again quits.", severity="warning")
            return
        self.exit()

    def on_unmount(self) -> None:
        if self._cancel is not None:
            self._cancel.set()  # let a running solver thread stop promptly on exit

    # ------------------------------------------------------------------ bindings
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action not in STATE_ACTIONS:
            return True
        if isinstance(self.screen, ModalScreen):
            return False
        if action in ("run", "run_models"):
            return not self.running
        if action == "cancel":
            return self.running
        if action in ("save_as", "revert"):
            return self.case is not None
        return self.output is not None

    def _state_changed(self) -> None:
        self.refresh_bindings()
        if self.case is None:
            self.sub_title = "no case open"
        else:
            edited = self.original is not None and self.case != self.original
            self.sub_title = self.case.name + (" (edited)" if edited else "")

    def action_show_tab(self, tab: str) -> None:
        self.query_one("#main-tabs", TabbedContent).active = tab
        self.query_one(MAIN_TABS[tab]).focus()

    def show_result_tab(self, tab: str) -> None:
        """Tab 3 on its view ``tab`` ("res-trees": the load trees of a run of several wires; a view
        the result does not have: a notification)."""
        results = self.query_one(ResultsView)
        if not results.has_tab(tab):
            self.notify("The load trees are those of a run of a case with [[wires]]: open one and press r.",
                        severity="warning")
            return
        self.query_one("#main-tabs", TabbedContent).active = "results"
        results.active_tab = tab

    def action_result_tab(self, step: int) -> None:
        tabs = self.query_one("#main-tabs", TabbedContent)
        if tabs.active != "results":
            self.action_show_tab("results")
        else:
            self.query_one(ResultsView).cycle_tab(step)

    def action_help(self) -> None:
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen())

    def show_error(self, title: str, message: str) -> None:
        self.push_screen(ErrorScreen(title, message))

    # ------------------------------------------------------------------ cases
    @on(OpenCaseRequested)
    def _open_requested(self, event: OpenCaseRequested) -> None:
        self.open_case(event.path)

    def open_case(self, path: Path, *, run: bool = False, discard: bool = False) -> None:
        """Load and validate ``path``; it becomes the current case (errors go to a dialog).

        With unsaved edits a dialog asks first (unless ``discard``): opening another case
        (browser, palette) never drops them silently.
        """
        if self.edited and not discard and self.case is not None and self.original is not None:
            keys = [k for k, _a, _b in case_differences(self.original, self.case)]
            shown = ", ".join(keys[:4]) + (f" and {len(keys) - 4} more" if len(keys) > 4 else "")

            def answer(yes: bool | None) -> None:
                if yes:
                    self.open_case(path, run=run, discard=True)
                else:
                    self.notify("kept the edited case: s saves it", timeout=3)

            self.push_screen(ConfirmScreen(
                "Unsaved edits",
                f"{self.case.name} has unsaved edits ({shown}).\n"
                f"Opening {Path(path).name} discards them; s (save as) keeps them in a new file.",
                "Discard the edits and open", "Keep editing"), answer)
            return
        try:
            case = load_case(path)
        except LinecheckError as err:
            self.show_error(err.title, str(err))
            return
        self.case = self.original = case
        self.query_one(ParameterEditor).show_case(case, case)
        self.query_one(CaseBrowser).select_path(Path(path))
        self._results_stale()
        self._state_changed()
        if not self.running:  # the last run's status line belongs to the previous case
            self.query_one(RunPanel).status(f"opened {case.name} - r runs it", style="dim")
        self.post_message(CaseOpened(case, Path(path)))
        self.action_show_tab("params")
        if run:
            self.action_run()

    @on(ParameterChanged)
    def _parameter_changed(self, event: ParameterChanged) -> None:
        self.case = event.case
        self._results_stale()
        self._state_changed()
        self.notify(f"{event.key} = {event.value!r}", timeout=2)

    def action_revert(self) -> None:
        if self.original is not None:
            self.case = self.original
            self.query_one(ParameterEditor).show_case(self.case, self.original)
            self._results_stale()
            self._state_changed()

    def _stale_note(self, out: runner.RunOutput) -> str | None:
        """Why ``out`` does not show the current case (None when it does)."""
        if self.case is None or out.case == self.case:
            return None
        if self.original is not None and out.case.source == self.case.source:
            return "case edited since: r runs it again"
        return f"current case is {self.case.name}: r runs it"

    def _results_stale(self) -> None:
        if self.output is not None:
            self.query_one(ResultsView).mark_stale(self._stale_note(self.output))

    def action_save_as(self) -> None:
        case = self.case
        if case is None:
            return
        default = files.save_as_default(case.name)  # the working directory, not cases/paper/

        def done(answer: tuple[Path, bool] | None) -> None:
            if answer is None or self.case is None:
                return
            path, replace = answer
            try:
                files.save_case(files.case_for_saving(self.case, self.original, path), path, replace=replace)
            except LinecheckError as err:
                self.show_error(err.title, str(err))
                return
            except OSError as err:
                self.show_error("Cannot write", f"{path}: {err.strerror or err}")
                return
            self.post_message(Exported("toml", path))
            self.notify(f"saved {path}")
            self.catalog = discover(self.paths)
            self.query_one(CaseBrowser).reload(self.catalog)
            self.open_case(path, discard=True)  # the edits are in the saved file

        self.push_screen(PathPrompt("Save the case as a new TOML file", default, ".toml",
                                    caution=files.in_shipped_folder), done)

    # ------------------------------------------------------------------ run
    def action_run_models(self) -> None:
        """Run the case under every built-in downburst model, same seeds."""
        if self.case is not None and self.case.wind.type != "downburst":
            self.notify("The model spread is for downburst cases.", severity="warning")
            return
        if self.case is not None and self.case.has_wires:
            self.notify("The model spread of several wires is not available yet: r runs the case.", severity="warning")
            return
        self.action_run(models="all")

    def action_run(self, models: str | None = None) -> None:
        if self.running:
            self.notify("A run is in progress: c cancels it.", severity="warning")
            return
        if self.case is None:
            self.notify("Open a case first (tab 1, enter).", severity="warning")
            return
        editor = self.query_one(ParameterEditor)
        if editor.editing is not None:
            editor.stop_editing()
            self.notify("Unapplied edit discarded (enter applies an edit).", severity="warning")
        self._cancel = threading.Event()
        self.running = True
        self._run_original = self.original
        self.query_one(RunPanel).start(self.case)
        self.post_message(RunStarted(self.case))
        self.run_job(self.case, self._cancel, models)
        self.refresh_bindings()

    @work(thread=True, exclusive=True, exit_on_error=False, group="run")
    def run_job(self, case: Case, cancel: threading.Event, models: str | None = None) -> runner.RunOutput:
        def progress(stage: str, done: int, total: int) -> None:
            self.post_message(RunProgress(stage, done, total))

        return runner.execute(case, progress=progress, cancel=cancel, extras=self.extras, models=models)

    def action_cancel(self) -> None:
        if self.running and self._cancel is not None:
            self._cancel.set()
            self.query_one(RunPanel).status("cancelling...")

    @on(RunProgress)
    def _progress(self, event: RunProgress) -> None:
        self.query_one(RunPanel).progress(event.stage, event.done, event.total)

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        worker = event.worker
        if worker.group == "run":
            if event.state == WorkerState.SUCCESS:
                self.post_message(RunFinished(worker.result))
            elif event.state == WorkerState.ERROR:
                err = worker.error
                if isinstance(err, Cancelled):
                    self.post_message(RunCancelled(self.case))
                elif isinstance(err, LinecheckError):
                    self.post_message(RunFailed(err.title, str(err)))
                else:
                    self.post_message(RunFailed("Unexpected error", f"{type(err).__name__}: {err}"))
            elif event.state == WorkerState.CANCELLED:
                self.post_message(RunCancelled(self.case))
        elif worker.group == "export" and event.state == WorkerState.ERROR:
            err = worker.error
            if isinstance(err, LinecheckError):
                self.show_error(err.title, str(err))
            elif isinstance(err, ImportError):
                self.show_error("Excel export unavailable", f"the Excel writer could not be loaded: {err}")
            else:
                self.show_error("Export failed", f"{type(err).__name__}: {err}")
        elif worker.group == "export" and event.state == WorkerState.SUCCESS:
            kind, path = worker.result
            self.post_message(Exported(kind, path))
            self.notify(f"wrote {path}")

    def _run_ended(self) -> None:
        self.running = False
        self._cancel = None
        self.refresh_bindings()

    @on(RunFinished)
    def _finished(self, event: RunFinished) -> None:
        self._run_ended()
        out = event.output
        self.output, self.output_original = out, self._run_original
        views = "Summary, Contributions, Load trees: [ ] steps" if out.has_wires else "[ ] steps through its views"
        self.query_one(RunPanel).finish(f"done: {out.case.name} in {out.seconds:.1f} s - "
                                        f"tab 3 Results ({views}), p pins for compare, x/j export")
        try:
            self.query_one(ResultsView).show(out, self.pinned, stale=self._stale_note(out))
            self.query_one(CompareView).show(self.pinned, out)
            self.query_one(CodesView).show(out.doc)
        except Exception as err:  # a display problem must not end the session
            self.show_error("Cannot show the result", f"{type(err).__name__}: {err}")
        tab = "compare" if self.pinned is not None and self.pinned is not out else "results"
        if self.query_one(ParameterEditor).editing is None and not isinstance(self.screen, ModalScreen):
            self.action_show_tab(tab)
            self.notify(f"run finished in {out.seconds:.1f} s", timeout=3)
        else:  # do not pull the view away from someone typing
            self.notify(f"run finished in {out.seconds:.1f} s: {'4' if tab == 'compare' else '3'} shows it", timeout=5)

    @on(RunCancelled)
    def _cancelled(self, event: RunCancelled) -> None:
        self._run_ended()
        self.query_one(RunPanel).finish("run cancelled - r runs again", style="yellow")
        self.notify("run cancelled", severity="warning", timeout=3)

    @on(RunFailed)
    def _failed(self, event: RunFailed) -> None:
        self._run_ended()
        self.query_one(RunPanel).finish(f"run failed: {event.message}", style="red")
        self.show_error(event.title, event.message)

    # ------------------------------------------------------------------ compare
    def action_pin(self) -> None:
        if self.output is None:
            return
        self.pinned = self.output
        self.query_one(CompareView).show(self.pinned, self.output)
        self.query_one(ResultsView).pinned = self.pinned
        self.notify(f"pinned {self.pinned.label}: edit the case, r runs the variant, 4 compares", timeout=4)

    # ------------------------------------------------------------------ export
    def _export(self, kind: str, title: str, suffix: str) -> None:
        if self.output is None:
            self.notify("Nothing to export yet: run a case first (r).", severity="warning")
            return
        out = self.output
        # an edited case's description is marked with the edits (it describes the file's values)
        doc = files.doc_for_export(out.doc, out.case, self.output_original)
        default = files.free_path(Path(f"{doc.case}{suffix}"))

        def done(answer: tuple[Path, bool] | None) -> None:
            if answer is not None:
                self.export_job(kind, doc, *answer)

        self.push_screen(PathPrompt(title, default, suffix), done)

    def action_export_excel(self) -> None:
        self._export("xlsx", "Export the result to an Excel design sheet", ".xlsx")

    def action_export_json(self) -> None:
        self._export("json", "Export the result as JSON (linecheck run --json)", ".json")

    @work(thread=True, exclusive=True, exit_on_error=False, group="export")
    def export_job(self, kind: str, doc: RunDocument, path: Path, replace: bool) -> tuple[str, Path]:
        return kind, files.export(kind, doc, path, replace=replace)
