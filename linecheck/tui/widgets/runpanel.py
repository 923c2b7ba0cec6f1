"""Run status and one progress bar per stage of the run (step 1, wind, steps 2-3, ...)."""

from __future__ import annotations

import time

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.timer import Timer
from textual.widgets import Label, ProgressBar, Static

from ...core.case import Case

# stages that run all realizations at once (the label says so)
ALL_REALIZATIONS = ("wind", "steps 2-3")


def _slug(stage: str) -> str:
    return "stage-" + "".join(ch if ch.isalnum() else "-" for ch in stage)


class RunPanel(Vertical):
    """Status line (with the elapsed time) plus a bar per stage, in the order the stages report."""

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.stages: dict[str, ProgressBar] = {}
        self.realizations = 1
        self._case_name = ""
        self._seed = 0
        self._started = 0.0
        self._timer: Timer | None = None

    def compose(self) -> ComposeResult:
        yield Static(Text("idle - open a case and press r to run it", style="dim"), id="run-status")
        yield Vertical(id="run-bars")

    def start(self, case: Case) -> None:
        """Reset for a run of ``case``."""
        self.realizations = case.analysis.realizations
        self._case_name, self._seed = case.name, case.analysis.seed
        self._started = time.monotonic()
        self.stages.clear()
        self.query_one("#run-bars").remove_children()
        self.remove_class("-finished")
        self.add_class("-running")
        self._tick()
        if self._timer is None:
            self._timer = self.set_interval(1.0, self._tick)
        else:
            self._timer.resume()

    def _tick(self) -> None:
        if not self.has_class("-running"):
            return
        n = self.realizations
        t = Text("running ", style="bold")
        t.append(self._case_name, style="bold cyan")
        t.append(f": {n} realization{'s' if n > 1 else ''}, seed {self._seed}, "
                 f"{time.monotonic() - self._started:.0f} s   ")
        t.append(" c ", style="bold reverse")
        t.append(" cancels")
        self.query_one("#run-status", Static).update(t)

    def progress(self, stage: str, done: int, total: int) -> None:
        """Show ``done`` of ``total`` for ``stage`` (a new stage gets a new bar).

        A one-step stage that has not finished (``0 of 1``) shows an indeterminate bar.
        """
        bar = self.stages.get(stage)
        if bar is None:
            label = stage
            if stage.startswith(ALL_REALIZATIONS):
                n = self.realizations
                label += f" (all {n} realizations)" if n > 1 else " (1 realization)"
            bar = ProgressBar(total=None, show_eta=True, id=_slug(stage))
            row = Horizontal(Label(label, classes="stage-label"), bar, classes="stage-row")
            self.query_one("#run-bars").mount(row)
            self.stages[stage] = bar
        if total <= 1 and done < total:
            bar.update(total=None)
        else:
            bar.update(total=max(total, 1), progress=done)

    def status(self, text: str, style: str = "yellow") -> None:
        """Replace the status line (bars stay; the elapsed-time line stops)."""
        self.remove_class("-running")
        self.query_one("#run-status", Static).update(Text(text, style=style))

    def finish(self, text: str, style: str = "green") -> None:
        """Show ``text`` and fold the bars away."""
        self.remove_class("-running")
        self.add_class("-finished")
        if self._timer is not None:
            self._timer.pause()
        self.query_one("#run-status", Static).update(Text(text, style=style))
