"""Rich progress bars driven by the core's ``progress(stage, done, total)`` callbacks."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from .common import err_console


@contextlib.contextmanager
def progress_bar() -> Iterator:
    """Yield a callback ``cb(stage, done, total)`` that drives one bar per stage.

    Bars are drawn only on a terminal: on a pipe or a file they would leave nothing but an
    empty line on stderr when they close (a successful command writes nothing there)."""
    bars = Progress(
        TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
        console=err_console, transient=True, disable=not err_console.is_terminal,
    )
    tasks: dict[str, int] = {}

    def cb(stage: str, done: int, total: int) -> None:
        if stage not in tasks:
            tasks[stage] = bars.add_task(stage, total=total)
        bars.update(tasks[stage], completed=done, total=total)

    with bars:
        yield cb
